"""A grazing point's estimate at a finer step does not depend on which widths the search tries
(issue 13 item 4). Next to a smooth fold the change of the number of impacts can lie in a
narrow stretch between the fold and the corner; beyond the fold the fixed-parameter solves
fail. The search widens p0 +- width * 4^k: where a solve fails, the stretch between the last
width and this one is scanned like one where the count changed (the paper model at 9.3342 Hz,
step halved: the change lies at 9.333757 Hz between the level's fold and corner, 1.5e-4 Hz
wide; the widths from a diagram bracket of 4.69e-6 Hz stepped over it into the failures, those
from 9.47e-6 Hz did not: the reference and a run with parameters x (1 + 1e-13) estimated
9.334206 +- 9.3e-5 and 9.333757 +- 2.3e-4). Exact stand-ins for the shooting problem."""
from types import SimpleNamespace

import numpy as np
import pytest

from continuation.accuracy import _grazing_bisect
from continuation.shooting import ConvergenceError


class Folded:
    """Orbits with ``counts[i]`` impacts per period between breaks[i - 1] and breaks[i]; a
    count None: no orbit there (the solve fails, as past a fold)."""

    def __init__(self, breaks, counts):
        self.breaks, self.counts = list(breaks), list(counts)

    def solve(self, u, p, tol=1e-10, max_iter=12):
        n = self.counts[int(np.searchsorted(self.breaks, p, side="right"))]
        if n is None:
            raise ConvergenceError(f"no orbit at {p}")
        return np.asarray(u, dtype=float), SimpleNamespace(n_impacts=n), 0.0, 1


# a window of 7 impacts at [1 - a, 1 - b] below p0 = 1 (6 impacts), no orbit below it, and
# the upper strand's 7 impacts again from 1.009 up (windows wider than the scan's step, an eighth
# of the stretch between two widths: a narrower one is a cluster this search does not resolve)
@pytest.mark.parametrize("width", [4.69e-6, 9.47e-6, 1e-5, 2.3e-5, 6e-5])
@pytest.mark.parametrize("a, b", [(9e-4, 7.5e-4), (4.6e-4, 3.6e-4), (2.2e-3, 2.0e-3)])
def test_the_change_next_to_a_fold_is_found_whatever_the_width(width, a, b):
    prob = Folded([1 - a, 1 - b, 1.009], [None, 7, 6, 7])
    p, u, half, pair = _grazing_bisect(prob, np.zeros(2), 1.0, width, 1e-9, expect=(7, 6))
    assert abs(p - (1 - b)) <= 2e-9 and pair == (7, 6)


def test_failures_alone_are_no_change():
    """Nothing but failed solves below and the same count above: no grazing point."""
    prob = Folded([1 - 5e-4], [None, 6])
    with pytest.raises(ConvergenceError, match="no change"):
        _grazing_bisect(prob, np.zeros(2), 1.0, 1e-5, 1e-9)


def test_the_diagrams_own_bracket_still_ignores_failures():
    """At level 0 (widen=False) nothing beyond the diagram's bracket is searched: a failure
    next to it is no reason to scan."""
    prob = Folded([1 - 5e-6, 1 + 3e-5], [None, 6, 7])
    with pytest.raises(ConvergenceError, match="no change"):
        _grazing_bisect(prob, np.zeros(2), 1.0, 1e-5, 1e-9, widen=False)
