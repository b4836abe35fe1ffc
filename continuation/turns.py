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


def unexplained_turns(values, marks, noise=1e-6, near=1e-4):
    """The parameter values where the sequence ``values`` (a branch's parameter, point by
    point) turns back (``turn_indices``) with no mark (value, tolerance) of a located fold or
    period doubling next to it. The polyline turns at a point k and the fold lies on a step
    next to it, so beyond it: at a maximum v_k the mark must lie in [v_k - near |v_k|, v_k + h
    + near |v_k|], at a minimum in [v_k - h - near |v_k|, v_k + near |v_k|], h the longer of
    the two steps at k (a turning point below a maximum, or above a minimum, is not the one the
    branch turned at); a mark counts with its tolerance (at a corner the turning point lies
    between the bracket's ends, which are not branch points). An unexplained turn is a stretch
    the branch does not hold: a step that passed a grazing point and a fold together, or a
    retrace."""
    v = np.asarray(values, dtype=float)
    out = []
    for k, sgn in turn_indices(v, noise):
        h = max(abs(v[k] - v[max(k - 1, 0)]), abs(v[min(k + 1, len(v) - 1)] - v[k]))
        e = near * abs(v[k])
        lo, hi = (v[k] - e, v[k] + h + e) if sgn > 0 else (v[k] - h - e, v[k] + e)
        if not any(m - t <= hi and m + t >= lo for m, t in marks):
            out.append(float(v[k]))
    return out
