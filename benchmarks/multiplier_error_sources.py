"""Benchmark (not a test): where the Floquet multipliers' error at the defaults comes from.

Paper model, A = 0.1 mm, order-1 orbits: the error of the multipliers (largest over the
orbit's, absolute) against dt / 8 with 256 steps per contact, at nlbeam's 32 steps per contact
(continuation's default), with dt halved there, and with 48 (the measured candidate default,
docs/continuation_report.md), 64, 96, 128 steps per contact; and the CPU time of one
evaluation of the shooting residual with its monodromy relative to the one at 32.

    python benchmarks/multiplier_error_sources.py [f1 f2 ...]   (Hz; default 10.5 12 20 40 60)
"""
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import numpy as np  # noqa: E402

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402
from continuation.accuracy import match_multipliers  # noqa: E402
from continuation.shooting import Integrator, _problem_from_state  # noqa: E402

A = 1e-4
REFERENCE = Integrator(dt_scale=1 / 8, steps_per_contact=256)
BASE = Integrator(steps_per_contact=32)
VARIANTS = [("32 per contact", BASE),
            ("dt / 2", Integrator(dt_scale=0.5, steps_per_contact=32))] + [
    (f"{n} per contact", Integrator(steps_per_contact=n)) for n in (48, 64, 96, 128)]


def cost(model, f, integ, sol):
    """CPU seconds of one evaluation with monodromy of the orbit sol at integ."""
    prob, u = _problem_from_state(model, A, f, 1, sol.state0, 1, integ)
    prob.evaluate(u, f, jac=True, jac_p=False)
    t, n = time.process_time(), 0
    while time.process_time() - t < 0.3:
        prob.evaluate(u, f, jac=True, jac_p=False)
        n += 1
    return (time.process_time() - t) / n


def main(freqs):
    warnings.simplefilter("ignore", RuntimeWarning)
    model = nlbeam.BeamImpact.paper()
    for f in freqs:
        s0 = C.periodic_solution(model, A, f, integrator=BASE, error=False)
        ref = C.periodic_solution(model, A, f, guess=s0, integrator=REFERENCE,
                                  error=False).multipliers
        c0 = cost(model, f, BASE, s0)
        cells = []
        for name, integ in VARIANTS:
            s = C.periodic_solution(model, A, f, guess=s0, integrator=integ, error=False)
            err = np.max(np.abs(s.multipliers - match_multipliers(s.multipliers, ref)))
            cells.append(f"{name} {err:.1e} (x{cost(model, f, integ, s) / c0:.2f})")
        print(f"{f:6.2f} Hz: " + ", ".join(cells), flush=True)


if __name__ == "__main__":
    main([float(a) for a in sys.argv[1:]] or [10.5, 12.0, 20.0, 40.0, 60.0])
