"""Benchmark (not a test): how complete and how accurate the periodic diagram is on systems
other than the one it was first built on (issue 13's robustness study).

For each case: the range covered per order (and what no branch of that order covers),
branches, bifurcations (grazing apart), branch ends where the tracer gave up, the stated error
of the fold / period-doubling frequencies against their measured error (the same diagram at
accuracy='high', matched by kind, order and nearest frequency), and CPU time.

    python benchmarks/robustness.py [--quick] [case ...]

Cases: paper-0.05, paper-0.1, paper-0.2, paper-0.5 (BeamImpact.paper(), A in mm, 5-150 Hz,
orders 1-3), duffing-stop (cubic spring and a one-sided stop, force 2 N, 0.3-3 Hz, orders 1-2),
two-dof (2-DOF with a stop on the second mass, A = 0.1 mm, 10-60 Hz, orders 1-2), modal-2 and
modal-4 (ModalBeam.paper(n_modes=2, 4), A = 0.1 mm, 5-150 Hz, orders 1-2). --quick skips the
accuracy='high' reference (measured errors then not shown).
"""
import argparse
import time
import warnings

import numpy as np

import nlbeam

import continuation as C
from continuation.turns import unexplained_turns

GAVE_UP = ("stuck at a corner", "step underflow", "no progress", "max_points",
           "could not move the segment boundaries")


def paper(a_mm):
    return lambda: (nlbeam.BeamImpact.paper(), a_mm * 1e-3, (5.0, 150.0), (1, 2, 3))


def duffing_stop():
    m = nlbeam.System([[1.0]], [[0.2513]], [[39.48]], elements=(
        nlbeam.CubicSpring(0, k3=10.0),
        nlbeam.PiecewiseLinearStop(0, k=789.6, gap=0.5, on_base=False)),
        excitation_kind="force", y_load=[1.0])
    return m, 2.0, (0.3, 3.0), (1, 2)


def two_dof():
    K = np.array([[1200.0, -400.0], [-400.0, 400.0]])
    m = nlbeam.System(np.diag([0.04, 0.02]), 1e-4 * K, K, elements=(
        nlbeam.Contact(dof=1, law="lankarani-nikravesh", K=1e8, e=0.7, gap=1e-4),),
        excitation_kind="base")
    return m, 1e-4, (10.0, 60.0), (1, 2)


def modal(n):
    return lambda: (nlbeam.ModalBeam.paper(n_modes=n), 1e-4, (5.0, 150.0), (1, 2))


CASES = {"paper-0.05": paper(0.05), "paper-0.1": paper(0.1), "paper-0.2": paper(0.2),
         "paper-0.5": paper(0.5), "duffing-stop": duffing_stop, "two-dof": two_dof,
         "modal-2": modal(2), "modal-4": modal(4)}


def diagram(model, amplitude, f_range, orders, accuracy=None):
    """(FrequencyResponse, CPU s, the ContinuationWarning texts)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t = time.process_time()
        frc = C.frequency_response(model, amplitude, f_range, orders=orders, accuracy=accuracy)
        cpu = time.process_time() - t
    texts = [str(w.message) for w in caught if issubclass(w.category, C.ContinuationWarning)]
    return frc, cpu, texts


def coverage(frc, order):
    """Fraction of the range that branches of this order cover, and the uncovered parts."""
    lo, hi = min(frc.p_range), max(frc.p_range)
    gaps = frc.uncovered(order)
    return 1.0 - sum(b - a for a, b in gaps) / (hi - lo), gaps


def smooth_folds_and_pds(frc):
    return [b for b in frc.bifurcations
            if b.kind in ("fold", "period-doubling") and b.smooth]


def measured_errors(frc, ref):
    """(stated, measured) error pairs (Hz) of the smooth folds / period doublings of ``frc``
    matched in ``ref`` (same kind and order, nearest frequency, within 1e-3 relative)."""
    pairs = []
    cands = smooth_folds_and_pds(ref)
    for b in smooth_folds_and_pds(frc):
        near = [r for r in cands if r.kind == b.kind and r.order == b.order]
        if not near:
            continue
        r = min(near, key=lambda r: abs(r.frequency - b.frequency))
        d = abs(r.frequency - b.frequency)
        if d < 1e-3 * b.frequency:
            pairs.append((b.error, d + (r.error if np.isfinite(r.error) else 0.0), b.frequency))
    return pairs


def report(name, make, quick):
    model, amplitude, f_range, orders = make()
    try:   # JIT warm-up (a failed solve compiles the kernels too)
        C.periodic_solution(model, amplitude, float(np.mean(f_range)))
    except C.ConvergenceError:
        pass
    frc, cpu, texts = diagram(model, amplitude, f_range, orders)
    print(f"## {name}: amplitude {amplitude:g}, {f_range[0]:g}-{f_range[1]:g} Hz, "
          f"orders {orders}: {cpu:.1f} s CPU, {frc.n_points} points")
    for n in orders:
        frac, gaps = coverage(frc, n)
        nb = sum(b.order == n for b in frc.branches)
        print(f"  order {n}: {nb} branches, covers {100 * frac:.1f} % of the range"
              + (f"; uncovered {', '.join(f'{a:.4g}-{b:.4g}' for a, b in gaps)}" if gaps else ""))
    kinds = {}
    for b in frc.bifurcations:
        kinds[b.kind] = kinds.get(b.kind, 0) + 1
    print("  bifurcations: " + (", ".join(f"{k} {v}" for k, v in sorted(kinds.items())) or "none"))
    ends = [(i, e) for i, b in enumerate(frc.branches) for e in b.ends if e in GAVE_UP]
    print(f"  branch ends where the tracer gave up: {len(ends)}"
          + (" (" + ", ".join(f"branch {i}: {e}" for i, e in ends) + ")" if ends else ""))
    retraced = [i for i in range(len(frc.branches)) if _turns_without_fold(frc, i)]
    print(f"  branches that turn back in frequency away from a fold or period doubling: "
          f"{len(retraced)}" + (f" (branches {retraced})" if retraced else ""))
    print(f"  ContinuationWarnings: {len(texts)}"
          + "".join(f"\n    - {t[:200]}" for t in texts))
    if quick:
        return
    ref, cpu_ref, _ = diagram(model, amplitude, f_range, orders, accuracy="high")
    pairs = measured_errors(frc, ref)
    if not pairs:
        print(f"  reference at accuracy='high' ({cpu_ref:.1f} s CPU): no fold / PD to compare")
        return
    stated = np.array([p[0] for p in pairs])
    meas = np.array([p[1] for p in pairs])
    f = np.array([p[2] for p in pairs])
    ok = np.isfinite(stated)
    under = int(np.sum(ok & (meas > stated)))
    print(f"  folds / PDs matched in the accuracy='high' diagram ({cpu_ref:.1f} s CPU): "
          f"{len(pairs)}; stated digits {_digits(stated[ok], f[ok])}; measured digits "
          f"{_digits(meas, f)}; measured error above the stated one at {under}; no estimate "
          f"at {int(np.sum(~ok))}")


def _digits(err, f):
    if err.size == 0:
        return "-"
    d = -np.log10(np.maximum(err, 1e-16 * f) / f)
    return f"{d.min():.1f}-{d.max():.1f} (median {np.median(d):.1f})"


def _turns_without_fold(frc, i, noise=1e-6, near=1e-4):
    """How many times branch i turns back in frequency where no fold of that branch (smooth,
    or at a grazing corner) and no period doubling (a switched branch passes through the
    period doubling it starts or ends at, where it turns) explains it: a retrace, or a step
    that passed a grazing point and a fold together, when > 0 (``turns.unexplained_turns``:
    the diagram warns of the same turns). A fold counts with its tracer bracket
    (``tolerance``) at its reported frequency and at its level-0 value (the diagram's own
    step)."""
    marks = []
    for b in frc.bifurcations:
        if (b.kind == "fold" and b.branch == i) or b.kind == "period-doubling":
            tol = float(b.tolerance) if np.isfinite(b.tolerance) else 0.0
            marks.append((b.frequency, tol))
            if b.levels is not None and len(b.levels) and frc.parameter == "frequency":
                marks.append((float(b.levels[0]), tol))  # where the diagram's branch turns
    return len(unexplained_turns(frc.branches[i].frequency, marks, noise, near))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", nargs="*", help=", ".join(CASES) + " (default: all)")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    bad = [c for c in a.cases if c not in CASES]
    if bad:
        ap.error(f"unknown case(s) {', '.join(bad)}; the cases are {', '.join(CASES)}")
    for name in a.cases or list(CASES):
        report(name, CASES[name], a.quick)


if __name__ == "__main__":
    main()
