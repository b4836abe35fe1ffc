"""Benchmark (not a test): the paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) at accuracy
'off', default (6 significant digits) and 'high' (8): CPU time, the fold / period-doubling
frequencies against continuation.refine_bifurcations (extended system at dt/4..dt/32,
Richardson; ~200 s CPU, computed first on the diagram without estimates), and the
multipliers of sampled branch points against converged values.

    python benchmarks/continuation_accuracy.py [off default high 7 ...] [--reference FILE]
        [--multipliers] [--every 15]
    python benchmarks/continuation_accuracy.py --levels 67.5837 66.4312 ...

--reference FILE: the refined values are read from FILE (.npz) when it exists, else computed
and written there (the diagram at accuracy='off' decides them: reuse a file only for code
that traces the same diagram). --multipliers: for each accuracy level after the first that
is not 'off', every ``--every``-th point of every branch (126 points at 15) is solved again
from its stored orbit (its own shooting problem and steps per period) at dt / 16 with 512
steps per contact (level 4: the converged reference of tests/continuation/test_accuracy.py)
and the reported multipliers are compared with it (true error: largest |mu - mu_ref| /
max(1, |mu_ref|)) and with their stated error.

--levels F ...: the folds / PDs of the diagram without estimates within 2e-3 Hz of each F,
located at levels 0-4 (digits 12, so that no level is skipped): how their values converge.

Printed per accuracy level: a summary line, then every fold / PD below 6 true significant
digits, above its stated error, or not confirmed (error NaN), with its frequency, order,
kind, stated error, the values per level (``Bifurcation.levels``) and why (the pattern of
the successive changes, or the failure). Folds / PDs reported at a grazing point
(Bifurcation.smooth False: a multiplier jumps there) are counted apart: refine_bifurcations
does not refine them.
"""
import argparse
import os
import time
import warnings

import numpy as np

import nlbeam

import continuation as C
from continuation._newton import ConvergenceError
from continuation.accuracy import _branch_problem, at_level, match_multipliers
from continuation.shooting import Integrator

A = 1e-4
F_RANGE = (5.0, 150.0)
ORDERS = (1, 2, 3)
FINE_LEVEL = 4  # the reference: level 4 of the default, dt / 16 and 512 steps per contact


def reference(model, path=None):
    """One record per fold / PD of the diagram without estimates: (kind, order, branch,
    diagram frequency, refine_bifurcations' value or NaN where it failed, its tolerance);
    read from / written to ``path`` (.npz) if given. The diagrams at every accuracy have the
    same bifurcations (the estimates run after the trace), so a bifurcation is matched to
    its own refined value by kind, order, branch and the nearest diagram frequency."""
    keys = ("kind", "order", "branch", "diagram", "value", "tolerance")
    if path and os.path.exists(path):
        z = np.load(path)
        if all(k in z for k in keys):
            return list(zip(*(z[k].tolist() for k in keys)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = C.frequency_response(model, A, F_RANGE, orders=ORDERS, accuracy="off")
        C.refine_bifurcations(frc, model)
    ref = []
    for b in frc.bifurcations:
        if b.kind not in ("fold", "period-doubling") or not b.smooth:
            continue
        r = getattr(b, "refined", None)
        ref.append((b.kind, b.order, b.branch, b.frequency,
                    r.value if r is not None else np.nan,
                    r.tolerance if r is not None else np.nan))
    if path:
        np.savez(path, **{k: np.array([r[i] for r in ref]) for i, k in enumerate(keys)})
    return ref


def why(bf):
    """A short account of a bifurcation's levels: the successive changes and their ratios."""
    lv = np.asarray(bf.levels if bf.levels is not None else [], float)
    if lv.size < 2:
        return f"{lv.size} level(s): not located again at a finer step"
    d = np.diff(lv)
    r = [f"{d[i - 1] / d[i]:.3g}" if d[i] else "inf" for i in range(1, len(d))]
    return (f"{lv.size} levels, changes " + " ".join(f"{x:.1e}" for x in d)
            + (", ratios " + " ".join(r) if r else ""))


def frequency_digits(frc, ref, acc):
    """Compare the diagram's folds / PDs with the refined values; print the summary and the
    list of poor points. Returns (true digits, stated digits) arrays."""
    true_d, stated_d, under, nan, at_grazing, no_ref, listed = [], [], 0, 0, 0, 0, []
    for bf in frc.bifurcations:
        if bf.kind not in ("fold", "period-doubling"):
            continue
        if not bf.smooth:  # reported at a grazing point: refine skips those
            at_grazing += 1
            continue
        if np.isfinite(bf.error):
            stated_d.append(-np.log10(bf.error / bf.frequency))
        elif acc != "off":
            nan += 1
            listed.append((bf, np.nan, "not confirmed (error NaN): " + why(bf)))
            continue
        cands = [r for r in ref if r[:3] == (bf.kind, bf.order, bf.branch)]
        if not cands:
            continue
        _, _, _, f0, v, tol = min(cands, key=lambda r: abs(r[3] - bf.frequency))
        if abs(f0 - bf.frequency) > 1e-3 * bf.frequency:
            continue  # not the same point
        if not np.isfinite(v):
            no_ref += 1
            if acc != "off":
                listed.append((bf, np.nan, "refine_bifurcations failed here: not compared; "
                               + why(bf)))
            continue
        e = abs(v - bf.frequency)
        digits = -np.log10(max(e, tol) / bf.frequency)
        true_d.append(digits)
        bad = bool(np.isfinite(bf.error) and e > bf.error + tol)
        under += bad
        if acc != "off" and (digits < 6.0 or bad):
            listed.append((bf, digits, ("TRUE > STATED; " if bad else "") + why(bf)
                           + f"; refined {v:.10g}"))
    st = np.array(stated_d)
    print(f"  folds/PDs matched {len(true_d)}: true digits {min(true_d):.1f}-{max(true_d):.1f} "
          f"median {np.median(true_d):.1f} (< 6: {int(np.sum(np.array(true_d) < 6))}, < 8: "
          f"{int(np.sum(np.array(true_d) < 8))}); stated digits "
          + (f"{st.min():.1f}-{st.max():.1f} median {np.median(st):.1f} (>= 6: "
             f"{int(np.sum(st >= 6))}, >= 8: {int(np.sum(st >= 8))})" if st.size else "-")
          + f"; not confirmed (error NaN) {nan}; true error > stated {under}; no refined "
          f"value {no_ref}; "
          f"{at_grazing} more at grazing points (not compared)")
    for bf, digits, text in sorted(listed, key=lambda x: x[0].frequency):
        print(f"    {bf.kind:15s} order {bf.order} {bf.frequency:.10g} Hz +- {bf.error:.1e}: "
              f"true digits {digits:.1f}; {text}")
    return np.array(true_d), st


def multiplier_errors(model, frc, every):
    """True and stated multiplier errors at every ``every``-th point of each branch."""
    rows = []
    for bi, b in enumerate(frc.branches):
        if b.multipliers is None:
            continue
        for i in range(0, len(b.values), every):
            f = float(b.frequency[i])
            try:
                prob, u, p = _branch_problem(model, b, i, Integrator())
                fine = at_level(prob, FINE_LEVEL)
                _, ev, _, _ = fine.solve(u, p, tol=1e-10, max_iter=12)
                ref = fine.multipliers(ev.Ms)
            except (ConvergenceError, nlbeam.IntegrationError, ValueError):
                rows.append((f, b.order, bi, np.nan, float(b.multipliers_error[i])))
                continue
            mu = match_multipliers(ref, b.multipliers[i])
            true = float(np.max(np.abs(mu - ref) / np.maximum(1.0, np.abs(ref))))
            rows.append((f, b.order, bi, true, float(b.multipliers_error[i])))
    r = np.array([x[3:] for x in rows])
    ok = np.isfinite(r[:, 0])
    t, s = r[ok, 0], r[ok, 1]
    print(f"  multipliers at every {every}th point: {ok.sum()} compared ({(~ok).sum()} whose "
          f"reference solve failed); true error median {np.median(t):.1e}, above 1e-5 "
          f"{int(np.sum(t > 1e-5))}, above stated {int(np.sum(t > s))} (largest true / stated "
          f"{np.max(t / s):.2g}); stated median {np.median(s):.1e}, above 1e-5 "
          f"{int(np.sum(s > 1e-5))}")
    for f, order, bi, true, stated in rows:
        if np.isfinite(true) and (true > 1e-5 or true > stated):
            print(f"    {f:.7g} Hz order {order} branch {bi + 1}: true {true:.1e} stated "
                  f"{stated:.1e}" + ("  TRUE > STATED" if true > stated else ""))


def show_levels(model, freqs):
    """The levels 0-4 of the folds / PDs near ``freqs`` (Hz) on the diagram without estimates."""
    from continuation.accuracy import bifurcation_levels

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = C.frequency_response(model, A, F_RANGE, orders=ORDERS, accuracy="off")
        for bf in frc.bifurcations:
            if (bf.kind not in ("fold", "period-doubling") or not bf.smooth
                    or not any(abs(bf.frequency - f) < 2e-3 for f in freqs)):
                continue
            lv = bifurcation_levels(model, A, bf, Integrator(), digits=12.0, max_levels=4)
            print(f"{bf.kind} order {bf.order} branch {bf.branch + 1} {bf.frequency:.10g} Hz: "
                  "levels " + " ".join(f"{v:.10g}" for v in lv.values)
                  + f" -> {lv.value:.10g} +- {lv.error:.1e} {lv.failed}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("levels", nargs="*", default=["off", "default", "high"])
    ap.add_argument("--reference", default=None, help="cache of the refined values (.npz)")
    ap.add_argument("--multipliers", action="store_true")
    ap.add_argument("--every", type=int, default=15)
    ap.add_argument("--levels", dest="locate", type=float, nargs="+", default=None)
    args = ap.parse_args(argv)
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    if args.locate:
        return show_levels(model, args.locate)
    t = time.process_time()
    ref = reference(model, args.reference)
    print(f"reference: {sum(np.isfinite(r[4]) for r in ref)} of {len(ref)} folds / PDs "
          f"refined ({time.process_time() - t:.0f} s CPU)")
    mult_done = False
    for acc in args.levels:
        a = acc if acc in ("off", "default", "high") else float(acc)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t = time.process_time()
            frc = C.frequency_response(model, A, F_RANGE, orders=ORDERS, accuracy=a)
            cpu = time.process_time() - t
        print(f"accuracy={acc}: {cpu:.1f} s CPU, {frc.n_points} points, "
              f"{len(frc.branches)} branches, {len(frc.bifurcations)} bifurcations")
        frequency_digits(frc, ref, acc)
        for w in caught:
            if "accuracy below" in str(w.message):
                print("   warning:", str(w.message)[:300], "...")
        if args.multipliers and acc != "off" and not mult_done:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                multiplier_errors(model, frc, args.every)
            mult_done = True


if __name__ == "__main__":
    main()
