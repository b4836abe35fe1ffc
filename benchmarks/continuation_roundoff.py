"""Benchmark (not a test): does round-off decide the paper diagram (issue 13 item 4)?

The whole paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) as computed, and under four
perturbations: m, k, b, K_hertz x (1 +- 1e-13) (the same dynamics), the amplitude x (1 + 1e-13),
dt_scale 1 - 1e-9 (101 instead of 100 steps a period: not round-off, a 1 % step change). For
each it prints the lines of ``structure_differences`` (tests/continuation/
test_continuation_roundoff.py: branch counts and covered ranges per order, bifurcations per
kind and order within their stated errors) and the unmatched bifurcations (of either diagram,
no partner of their kind and order within the sum of the stated errors, the errors the tables
print, plus 1e-7 of f), and each diagram's points, branches, bifurcations and CPU time.

    python benchmarks/continuation_roundoff.py [OUTDIR] [--only ref,p+,p-,a+,dt]

OUTDIR (default /tmp/continuation_roundoff) keeps each diagram as an .h5 file; a diagram whose
file exists there is loaded, not recomputed (delete the directory to recompute).
"""
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence
sys.path.append(os.path.join(ROOT, "tests", "continuation"))

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402
from nlbeam.app.scenes.numbers import bifurcation_error  # noqa: E402
from test_continuation_roundoff import structure_differences  # noqa: E402

RUNS = {"ref": "reference", "p+": "parameters x (1 + 1e-13)", "p-": "parameters x (1 - 1e-13)",
        "a+": "amplitude x (1 + 1e-13)", "dt": "dt_scale 1 - 1e-9"}


def _scaled(s):
    p = nlbeam.BeamImpact.paper()
    return p.replace(m=p.m * s, k=p.k * s, b=p.b * s, K_hertz=p.K_hertz * s)


def diagram(tag):
    model, amplitude, dt_scale = nlbeam.BeamImpact.paper(), 1e-4, 1.0
    if tag in ("p+", "p-"):
        model = _scaled(1 + (1e-13 if tag == "p+" else -1e-13))
    elif tag == "a+":
        amplitude *= 1 + 1e-13
    elif tag == "dt":
        dt_scale = 1 - 1e-9
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return C.frequency_response(model, amplitude, (5.0, 150.0), orders=(1, 2, 3),
                                    dt_scale=dt_scale)


def unmatched(a, b):
    """Bifurcations of a or b with no partner of their kind and order in the other diagram
    within the sum of their stated errors plus 1e-7 of f (nearest partner first)."""
    out = []
    for key in sorted({(x.kind, x.order) for x in a.bifurcations + b.bifurcations}):
        xa = sorted((x for x in a.bifurcations if (x.kind, x.order) == key),
                    key=lambda x: x.frequency)
        xb = sorted((x for x in b.bifurcations if (x.kind, x.order) == key),
                    key=lambda x: x.frequency)
        used = set()
        for x in xa:
            ex = bifurcation_error(x, a)
            best = None
            for j, y in enumerate(xb):
                d = abs(x.frequency - y.frequency)
                if (j not in used and d <= ex + bifurcation_error(y, b) + 1e-7 * x.frequency
                        and (best is None or d < best[0])):
                    best = (d, j)
            if best is None:
                out.append(("reference", key, x.frequency))
            else:
                used.add(best[1])
        out += [("perturbed", key, y.frequency) for j, y in enumerate(xb) if j not in used]
    return out


def main(outdir, only):
    os.makedirs(outdir, exist_ok=True)
    print(f"nlbeam from {os.path.dirname(nlbeam.__file__)}")
    C.periodic_solution(nlbeam.BeamImpact.paper(), 1e-4, 44.0)  # JIT warm-up
    frcs = {}
    for tag in only:
        path = os.path.join(outdir, f"{tag}.h5")
        if os.path.exists(path):
            frcs[tag] = C.load(path)
            print(f"{RUNS[tag]}: loaded {path}")
            continue
        c = time.process_time()
        frcs[tag] = frc = diagram(tag)
        cpu = time.process_time() - c
        frc.save(path)
        print(f"{RUNS[tag]}: {cpu:.1f} s CPU, {frc.n_points} points, {len(frc.branches)} "
              f"branches, {len(frc.bifurcations)} bifurcations "
              f"({sum(b.kind == 'grazing' for b in frc.bifurcations)} grazing)", flush=True)
    if "ref" not in frcs:
        return
    ref = frcs["ref"]
    for tag in only:
        if tag == "ref":
            continue
        d = structure_differences(ref, frcs[tag])
        u = unmatched(ref, frcs[tag])
        print(f"{RUNS[tag]}: {len(d)} structure lines, {len(u)} unmatched bifurcations")
        for line in d:
            print("   ", line[:300])
        print("    unmatched:", ", ".join(f"{s} {k[0]} order {k[1]} {f:.6f}"
                                         for s, k, f in u) or "none")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--only")]
    only = list(RUNS)
    for i, a in enumerate(sys.argv[1:]):
        if a.startswith("--only"):
            only = (a.split("=", 1)[1] if "=" in a else sys.argv[i + 2]).split(",")
            if not a.count("=") and sys.argv[i + 2] in args:
                args.remove(sys.argv[i + 2])
    main(args[0] if args else "/tmp/continuation_roundoff", only)
