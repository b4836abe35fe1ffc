"""Where a branch reverses in its parameter: the check that a diagram traces no stretch twice
(a branch may turn back only at a fold it reports)."""
from __future__ import annotations

import numpy as np


def turns(values, noise=1e-6):
    """The parameter values (floats) where the sequence ``values`` reverses: extrema from which
    it moves back by more than ``noise`` (relative to the extremum; where contacts nearly stick
    the fixed-step map has noise, and the points wiggle in the parameter at the 1e-7 level)."""
    values = list(map(float, values))
    out = []
    if not values:
        return out
    ext, sgn = values[0], 0.0
    for v in values[1:]:
        if sgn == 0.0:
            if abs(v - ext) > noise * abs(ext):
                sgn = np.sign(v - ext)
                ext = v
        elif (v - ext) * sgn > 0:
            ext = v
        elif abs(v - ext) > noise * abs(ext):
            out.append(ext)
            sgn, ext = -sgn, v
    return out
