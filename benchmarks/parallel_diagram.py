"""Benchmark (not a test): the paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) serial, on
local processes (workers=2) and, if dask is installed, on a LocalCluster of 2 one-thread
worker processes; wall time of each and whether every array equals the serial one bit for bit.

    python benchmarks/parallel_diagram.py [--workers 2] [--no-dask] [--accuracy off]

Wall time is the measure here (the work is spread over processes); on a shared machine run
it when the load is steady and compare within one run.
"""
import argparse
import dataclasses
import os
import sys
import time
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402


def differences(a, b):
    """Names of the fields (branch i / bifurcation i) whose values are not bit-identical."""
    def eq(x, y):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            return (x is not None and y is not None and x.shape == y.shape
                    and np.array_equal(x, y, equal_nan=True))
        if isinstance(x, float) and x != x:
            return isinstance(y, float) and y != y
        return x == y
    if len(a.branches) != len(b.branches) or len(a.bifurcations) != len(b.bifurcations):
        return ["number of branches or bifurcations"]
    out = []
    for name, xs, ys in (("branch", a.branches, b.branches),
                         ("bifurcation", a.bifurcations, b.bifurcations)):
        for i, (x, y) in enumerate(zip(xs, ys)):
            out += [f"{name} {i}: {f.name}" for f in dataclasses.fields(x)
                    if f.name != "refined" and not eq(getattr(x, f.name), getattr(y, f.name))]
    return out


def run(label, **kw):
    model = nlbeam.BeamImpact.paper()
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = C.frequency_response(model, 1e-4, (5.0, 150.0), orders=(1, 2, 3), **kw)
    wall = time.perf_counter() - t
    print(f"{label:28s} {wall:7.1f} s wall, {frc.n_points} points, {len(frc.branches)} "
          f"branches, {len(frc.bifurcations)} bifurcations", flush=True)
    return frc, wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--accuracy", default=None)
    a = ap.parse_args()
    kw = {} if a.accuracy is None else {"accuracy": a.accuracy}
    C.periodic_solution(nlbeam.BeamImpact.paper(), 1e-4, 44.0)  # JIT warm-up (disk cache)
    print(f"nlbeam from {os.path.dirname(nlbeam.__file__)}; {os.cpu_count()} CPUs; load "
          f"{os.getloadavg()[0]:.1f}")
    ref, w0 = run("serial", **kw)
    frc, w1 = run(f"workers={a.workers}", workers=a.workers, **kw)
    d = differences(ref, frc)
    print(f"  speed-up {w0 / w1:.2f}x; arrays differing from serial: {len(d)} {d[:5]}")
    if a.no_dask:
        return
    try:
        from distributed import LocalCluster
    except ImportError:
        print("dask not installed: LocalCluster skipped (pip install 'nlbeam[distributed]')")
        return
    with LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        frc, w2 = run(f"LocalCluster({a.workers} x 1 thread)",
                      scheduler=cluster.scheduler_address, **kw)
    d = differences(ref, frc)
    print(f"  speed-up {w0 / w2:.2f}x; arrays differing from serial: {len(d)} {d[:5]}")


if __name__ == "__main__":
    main()
