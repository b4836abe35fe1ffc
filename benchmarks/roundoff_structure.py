"""Benchmark (not a test): does round-off change the paper diagram's structure (issue 13 item 4)?

The whole paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) as the reference, then with
m, k, b, K_hertz x (1 + 1e-13), x (1 - 1e-13), A x (1 + 1e-13) and dt_scale 1 - 1e-9 (101
steps a period: a 1 % step change, more than round-off). For each perturbation prints the
lines of the round-off test's ``structure_differences`` and the unmatched bifurcations (of
either diagram, with no partner of their kind and order within the sum of their stated
errors), counted per stretch of the diagram (the causes: docs/continuation_report.md,
"Events within a grazing point's resolution").

    python benchmarks/roundoff_structure.py            (all four; ~5 diagrams, minutes of CPU)
    python benchmarks/roundoff_structure.py 0 3        (the reference and perturbations 0, 3)
    python benchmarks/roundoff_structure.py --reference REF.pkl 1
        (the reference diagram read from REF.pkl if it exists, else computed and written there:
        perturbations run in separate processes share it)
"""
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402

# the stretches the remaining differences lie in (Hz): which cause each belongs to
STRETCHES = (("6.64-6.66 (order-1 grazing estimate)", 6.64, 6.66),
             ("9.0-9.7 (corner with two far sides)", 9.0, 9.7),
             ("66.5-66.6 (order 2, chattering end)", 66.5, 66.6),
             ("67.49-67.66 (order 2, chattering end)", 67.49, 67.66),
             ("110.7-112.3 (order 3)", 110.7, 112.3))


def _stretch(f):
    for name, lo, hi in STRETCHES:
        if lo <= f <= hi:
            return name
    return "elsewhere"


def _declared(frc, order):
    """The stretches of this order frc declares unresolved (none on a diagram without
    FrequencyResponse.unresolved)."""
    return [s[1:3] for s in frc.unresolved(order)] if hasattr(frc, "unresolved") else []


def unmatched(a, b, rel=1e-7):
    """Bifurcations of a and of b with no partner of their kind and order in the other within
    the sum of their stated errors (numbers.bifurcation_error) plus rel of f, except inside a
    stretch of their order that both diagrams declare unresolved (as structure_differences):
    a list of (which diagram, kind, order, frequency, stated error)."""
    from nlbeam.app.scenes.numbers import bifurcation_error
    out = []
    keys = sorted({(x.kind, x.order) for x in a.bifurcations + b.bifurcations})
    both = {}
    for o in {k[1] for k in keys}:
        both[o] = [(max(p, q), min(r, t)) for p, r in _declared(a, o) for q, t in _declared(b, o)
                   if max(p, q) <= min(r, t)]

    def compared(x):
        return not any(lo <= x.frequency <= hi for lo, hi in both[x.order])
    for key in keys:
        xa = [(x.frequency, bifurcation_error(x, a)) for x in a.bifurcations
              if (x.kind, x.order) == key and compared(x)]
        xb = [(x.frequency, bifurcation_error(x, b)) for x in b.bifurcations
              if (x.kind, x.order) == key and compared(x)]
        used = set()
        for fa, ea in sorted(xa):
            best = None
            for j, (fb, eb) in enumerate(xb):
                d = abs(fa - fb)
                if j not in used and d <= ea + eb + rel * fa and (best is None or d < best[0]):
                    best = (d, j)
            if best is None:
                out.append(("ref", *key, fa, ea))
            else:
                used.add(best[1])
        out += [("perturbed", *key, fb, eb) for j, (fb, eb) in enumerate(xb) if j not in used]
    return out


def _scaled(s):
    p = nlbeam.BeamImpact.paper()
    return p.replace(m=p.m * s, k=p.k * s, b=p.b * s, K_hertz=p.K_hertz * s)


PERTURBATIONS = (("m, k, b, K_hertz x (1 + 1e-13)", lambda: (_scaled(1 + 1e-13), A, 1.0)),
                 ("m, k, b, K_hertz x (1 - 1e-13)", lambda: (_scaled(1 - 1e-13), A, 1.0)),
                 ("A x (1 + 1e-13)", lambda: (nlbeam.BeamImpact.paper(), A * (1 + 1e-13), 1.0)),
                 ("dt_scale 1 - 1e-9", lambda: (nlbeam.BeamImpact.paper(), A, 1 - 1e-9)))
A = 1e-4


def diagram(model, amplitude, dt_scale):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return C.frequency_response(model, amplitude, (5.0, 150.0), orders=(1, 2, 3),
                                    dt_scale=dt_scale)


def summary(frc):
    n_graz = sum(b.kind == "grazing" for b in frc.bifurcations)
    return (f"{sum(len(b.values) for b in frc.branches)} points, {len(frc.branches)} branches, "
            f"{len(frc.bifurcations)} bifurcations ({n_graz} grazing)")


def reference(path=None):
    """The reference diagram (read from / written to the pickle ``path`` if given)."""
    import pickle
    if path and os.path.exists(path):
        with open(path, "rb") as fh:
            ref = pickle.load(fh)
        print(f"reference (read from {path}): {summary(ref)}", flush=True)
        return ref
    t = time.process_time()
    ref = diagram(nlbeam.BeamImpact.paper(), A, 1.0)
    print(f"reference: {summary(ref)}, {time.process_time() - t:.1f} s CPU", flush=True)
    if path:
        with open(path, "wb") as fh:
            pickle.dump(ref, fh)
    return ref


def main(which, ref_path=None):
    sys.path.append(os.path.join(ROOT, "tests", "continuation"))
    from test_continuation_roundoff import structure_differences
    ref = reference(ref_path)
    for i in which:
        name, make = PERTURBATIONS[i]
        t = time.process_time()
        frc = diagram(*make())
        print(f"\n== {name}: {summary(frc)}, {time.process_time() - t:.1f} s CPU")
        for name_, d in (("reference", ref), ("perturbed", frc)):
            st = d.unresolved() if hasattr(d, "unresolved") else []
            print(f"{name_} declares unresolved: " + (", ".join(
                f"order {o}: {lo:.6g}-{hi:.6g}" for o, lo, hi, _ in st) or "nothing"))
        lines = structure_differences(ref, frc)
        print(f"structure_differences: {len(lines)} lines")
        for s in lines:
            print("   ", s[:300])
        um = unmatched(ref, frc)
        print(f"unmatched bifurcations: {len(um)}")
        per = {}
        for u in um:
            per.setdefault(_stretch(u[3]), []).append(u)
        for k in sorted(per):
            print(f"  {k}: {len(per[k])}: " + ", ".join(
                f"{w[0][:3]} {w[1]}/{w[2]} {w[3]:.7g}+-{w[4]:.1e}" for w in per[k]))
        sys.stdout.flush()


if __name__ == "__main__":
    args = sys.argv[1:]
    ref_path = None
    if "--reference" in args:
        k = args.index("--reference")
        ref_path = args[k + 1]
        del args[k:k + 2]
    main([int(a) for a in args] or range(len(PERTURBATIONS)), ref_path)
