"""Benchmark (not a test): why the tracer's step correctors fail on the paper diagram.

Runs frequency_response(paper, 1e-4, (5, 150), orders=(1, 2, 3), accuracy='off') with the
tracers' debug output captured and classifies every step attempt: accepted (with its
corrector iterations), rejected for the angle, for a change of the impact count on a step
longer than grazing_ds, at the corner check, or because the corrector failed; of the failed
correctors, those whose iterates saw two impact counts (the iteration straddles a grazing
corner, where the map is not smooth) and those whose first residual exceeds 1e-2 (a step too
long for the predictor), and where they lie in frequency. (The iterates of correctors run
between two step attempts, by bifurcation location or corner checks, count with the next
attempt: the split is approximate.)

    python benchmarks/corrector_failures.py
"""
import collections
import contextlib
import io
import os
import re
import sys
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import numpy as np  # noqa: E402

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402
from continuation import pathfollow  # noqa: E402

STEP = re.compile(r"ds (\S+) ok (\S+) iters (\d+) angle (\S+) p (\S+)")
EDGES = [5, 10, 12, 20, 60, 70, 100, 120, 150]


def main():
    warnings.simplefilter("ignore")
    init = pathfollow.Tracer.__init__

    def debug_init(self, *a, **kw):
        init(self, *a, **kw)
        self.debug = True

    pathfollow.Tracer.__init__ = debug_init
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        frc = C.frequency_response(nlbeam.BeamImpact.paper(), 1e-4, (5.0, 150.0),
                                   orders=(1, 2, 3), accuracy="off")
    pathfollow.Tracer.__init__ = init
    lines = buf.getvalue().splitlines()
    kinds, iters, failed = collections.Counter(), collections.Counter(), []
    for i, line in enumerate(lines):
        m = STEP.match(line)
        if not m:
            continue
        ds, ok, it, angle, p = float(m[1]), m[2] == "True", int(m[3]), float(m[4]), float(m[5])
        if ok:
            kinds["accepted"] += 1
            iters[it] += 1
            continue
        if angle == np.inf:
            kinds["corrector failed"] += 1
            hist, j = [], i - 1  # this attempt's iterates: the 'it' lines just before
            while j >= 0 and lines[j].strip().startswith("it "):
                hist.append(lines[j].split())
                j -= 1
            failed.append((p, ds, hist[::-1]))
        elif np.isnan(angle):
            kinds["impact count changed on a step > grazing_ds"] += 1
        elif angle > 0.2:
            kinds["angle > max_angle"] += 1
        else:
            kinds["corner check failed or avoided"] += 1
    print(f"{frc.n_points} points; step attempts: {dict(kinds)}")
    print("corrector iterations of accepted steps:", dict(sorted(iters.items())))
    two = sum(1 for _, _, h in failed if len({x[-1] for x in h}) > 1)
    big = sum(1 for _, _, h in failed if h and float(h[0][3]) > 1e-2)
    ds = np.array([d for _, d, _ in failed])
    print(f"failed correctors: {len(failed)}; iterates with two impact counts {two}; first "
          f"residual > 1e-2 {big}; ds quartiles {np.percentile(ds, [25, 50, 75])}")
    hist = np.histogram([p for p, _, _ in failed], EDGES)[0]
    print("by frequency: " + ", ".join(f"{a}-{b} Hz {n}" for a, b, n in
                                       zip(EDGES[:-1], EDGES[1:], hist)))


if __name__ == "__main__":
    main()
