"""The corrector's variational equations only where needed (Tracer.lazy_var), side by side in
one process (not a test).

    python benchmarks/lazy_corrector.py paper [ref new lazy]   (the paper diagram, A = 0.1 mm,
        5-150 Hz, orders 1-3: CPU, points, branches, ends, bifurcations per kind, and the
        largest frequency difference per kind where the counts agree)
    python benchmarks/lazy_corrector.py branch                 (the 4-mode beam's order-1
        branch through 12.1 Hz traced down into its jump, eager / lazy alternating: CPU,
        flows, flows with the variational equations, points, end)

ref: lazy_var=False (every corrector iterate with the variational equations), new: None (the
default: lazy for more than one DOF), lazy: True. Units: s, Hz.
"""
import os
import sys
import time
import warnings

import numpy as np

import continuation as C
import nlbeam
from continuation.pathfollow import Tracer

LAZY = {"ref": False, "new": None, "lazy": True}


def paper(modes):
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, 1e-4, 44.0)  # JIT warm-up
    out = {}
    for mode in modes:
        Tracer.__init__.__kwdefaults__["lazy_var"] = LAZY[mode]
        c = time.process_time()
        frc = C.frequency_response(model, 1e-4, (5.0, 150.0), orders=(1, 2, 3))
        cpu = time.process_time() - c
        kinds = {}
        for b in frc.bifurcations:
            kinds[b.kind] = kinds.get(b.kind, 0) + 1
        print(f"{mode}: {cpu:.1f} s CPU, {frc.n_points} points, {len(frc.branches)} branches, "
              f"{len(frc.bifurcations)} bifurcations {kinds}", flush=True)
        for i, b in enumerate(frc.branches):
            print(f"  {mode} branch {i}: order {b.order} {b.origin}, {len(b.values)} points, "
                  f"{b.frequency.min():.4f}-{b.frequency.max():.4f} Hz, ends {b.ends}")
        out[mode] = [(b.kind, b.frequency) for b in frc.bifurcations]
    Tracer.__init__.__kwdefaults__["lazy_var"] = None
    for m1, m2 in zip(modes, modes[1:]):
        for kind in ("fold", "period-doubling", "grazing", "neimark-sacker"):
            fa = np.sort([f for k, f in out[m1] if k == kind])
            fb = np.sort([f for k, f in out[m2] if k == kind])
            same = len(fa) == len(fb)
            print(f"{m1} / {m2} {kind}: {len(fa)} / {len(fb)}"
                  + (f", max |df| {np.max(np.abs(fa - fb)):.2e} Hz" if same and len(fa) else ""))


def branch():
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                    "tests", "continuation"))
    from test_modal_branch_ends import _trace_down

    for lazy in (False, True, False, True):
        c = time.process_time()
        tr, prob, pts, reason, caught = _trace_down(lazy_var=lazy)
        print(f"lazy_var={lazy}: {time.process_time() - c:.2f} s CPU, flows {tr.n_evaluations} "
              f"({tr.n_variational} with the variational equations), points {len(pts)}, "
              f"{reason} at {pts[-1].p:.6f} Hz, lowest {min(q.p for q in pts):.6f} Hz",
              flush=True)


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    if sys.argv[1:2] == ["branch"]:
        branch()
    else:
        paper(sys.argv[2:] or ["ref", "new"])
