"""Benchmark (not a test): CPU time of the frequency-response diagram of the paper model alone
(A = 0.1 mm, 5-150 Hz, orders 1-3, default settings; JIT cache warm), with the number of flows
(calls of nlbeam.flow, with and without variational equations) and a per-branch summary.

    python benchmarks/continuation_timing.py [--json out.json] [--profile]

To compare two versions side by side, run each from its own tree in the same minute (CPU time,
time.process_time, is the fair measure on a shared machine), e.g.
    PYTHONPATH=/path/to/old python /path/to/old/benchmarks/continuation_timing.py
    python benchmarks/continuation_timing.py
"""
import json
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence


import nlbeam  # noqa: E402

import continuation as C  # noqa: E402
from continuation_diagram import harmonic_coverage  # noqa: E402  (benchmarks/ is on sys.path)

A = 1e-4


def main():
    warnings.simplefilter("ignore", RuntimeWarning)
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    counts = {"flows": 0, "flows_var": 0}
    flow = nlbeam.flow

    def counted(*a, **kw):
        counts["flows"] += 1
        counts["flows_var"] += bool(kw.get("monodromy", False))
        return flow(*a, **kw)

    nlbeam.flow = counted
    from nlbeam.integrate import FlowMap  # the shooting problems' flows
    fm_call = FlowMap.__call__

    def fm_counted(self, *a, **kw):
        counts["flows"] += 1
        counts["flows_var"] += bool(kw.get("monodromy", False))
        return fm_call(self, *a, **kw)

    FlowMap.__call__ = fm_counted
    prof = None
    if "--profile" in sys.argv:
        import cProfile
        prof = cProfile.Profile()
        prof.enable()
    t, c = time.perf_counter(), time.process_time()
    frc = C.frequency_response(model, A, (5.0, 150.0), orders=(1, 2, 3))
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    if prof is not None:
        prof.disable()
        import pstats
        pstats.Stats(prof).sort_stats("cumulative").print_stats(45)
    nlbeam.flow = flow
    FlowMap.__call__ = fm_call
    kinds = {}
    for b in frc.bifurcations:
        kinds[b.kind] = kinds.get(b.kind, 0) + 1
    print(f"continuation from {os.path.dirname(C.__file__)}")
    print(f"diagram: {wall:.1f} s wall, {cpu:.1f} s CPU, {frc.n_points} points, "
          f"{len(frc.branches)} branches, {len(frc.bifurcations)} bifurcations {kinds}, "
          f"{counts['flows']} flows ({counts['flows_var']} with variational equations)")
    for i, b in enumerate(frc.branches):
        print(f"  branch {i}: order {b.order} ({b.origin}), {len(b.values)} points, "
              f"{b.frequency.min():.4f}-{b.frequency.max():.4f} Hz")
    print(harmonic_coverage(frc))
    for bf in frc.bifurcations:
        if bf.kind != "grazing" and bf.order == 1:
            print(f"  {bf.kind:16s} order 1 at {bf.frequency:.10f} Hz (bracket {bf.tolerance:.1e})")
    if "--json" in sys.argv:
        out = sys.argv[sys.argv.index("--json") + 1]
        with open(out, "w") as fh:
            json.dump({"cpu": cpu, "wall": wall, "points": frc.n_points, "flows": counts,
                       "branches": [dict(order=b.order, origin=b.origin, n=len(b.values),
                                         fmin=float(b.frequency.min()),
                                         fmax=float(b.frequency.max()))
                                    for b in frc.branches],
                       "bifurcations": [dict(kind=b.kind, order=b.order, branch=b.branch,
                                             f=b.frequency, tol=b.tolerance)
                                        for b in frc.bifurcations]}, fh, indent=1)
    return frc


if __name__ == "__main__":
    main()
