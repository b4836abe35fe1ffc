"""Where a branch reverses in its parameter: the check that a diagram traces no stretch twice
(a branch may turn back only at a fold it reports)."""
from __future__ import annotations

import numpy as np


def turn_indices(values, noise=1e-6):
    """Where the sequence ``values`` reverses: (index k of the extremum, +1 at a maximum, -1 at
    a minimum) for each extremum from which it moves back by more than ``noise`` (relative to
    the extremum; where contacts nearly stick the fixed-step map has noise, and the points
    wiggle in the parameter at the 1e-7 level)."""
    values = np.asarray(values, dtype=float)
    out, k, sgn = [], None, 0.0
    for j, v in enumerate(values):
        if k is None:
            k = j
        elif sgn == 0.0:
            if abs(v - values[k]) > noise * abs(values[k]):
                sgn, k = np.sign(v - values[k]), j
        elif (v - values[k]) * sgn > 0:
            k = j
        elif abs(v - values[k]) > noise * abs(values[k]):
            out.append((k, int(sgn)))
            sgn, k = -sgn, j
    return out


def turns(values, noise=1e-6):
    """The parameter values (floats) where the sequence ``values`` reverses (see
    ``turn_indices``)."""
    values = np.asarray(values, dtype=float)
    return [float(values[k]) for k, _ in turn_indices(values, noise)]
