"""Benchmark (not a test): the paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) with the shooting
problems' kept flows off and on (continuation._flowcache), alternating in one process (JIT
warm): CPU time, flows (with variational equations), hits, and whether every array of the two
diagrams is the same bit for bit.

    python benchmarks/flow_cache.py [--rounds 2] [--workers 1]
"""
import argparse
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import nlbeam  # noqa: E402
from nlbeam.integrate import FlowMap  # noqa: E402

import continuation as C  # noqa: E402
from continuation import _flowcache  # noqa: E402
from parallel_diagram import differences  # noqa: E402  (benchmarks/ is on sys.path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, 1e-4, 44.0)  # JIT warm-up
    count = {"flows": 0, "var": 0}
    call = FlowMap.__call__

    def counted(self, *a, **kw):
        count["flows"] += 1
        count["var"] += bool(kw.get("monodromy", False))
        return call(self, *a, **kw)

    FlowMap.__call__ = counted
    out = {}
    for _ in range(args.rounds):
        for on in (False, True):
            _flowcache.enabled = on
            _flowcache.clear()
            _flowcache.hits.update(plain=0, var=0)
            count.update(flows=0, var=0)
            t, c = time.perf_counter(), time.process_time()
            frc = C.frequency_response(model, 1e-4, (5.0, 150.0), orders=(1, 2, 3),
                                       workers=args.workers)
            cpu, wall = time.process_time() - c, time.perf_counter() - t
            print(f"kept flows {'on ' if on else 'off'}: {cpu:.2f} s CPU, {wall:.1f} s wall, "
                  f"{frc.n_points} points, {len(frc.branches)} branches, "
                  f"{len(frc.bifurcations)} bifurcations "
                  f"({sum(b.kind == 'grazing' for b in frc.bifurcations)} grazing), "
                  f"{count['flows']} flows ({count['var']} with variational equations), "
                  f"hits {_flowcache.hits}", flush=True)
            out[on] = frc
    FlowMap.__call__ = call
    d = differences(out[False], out[True])
    print(f"fields differing bit for bit between off and on: {len(d)} {d[:5]}")


if __name__ == "__main__":
    main()
