"""A grazing corner passed straight with a smooth fold just beyond it (issue 13, 'through every
non-smooth point'): one step must not pass both. The paper model at A = 0.2 mm: a step from
14.538474 Hz (unstable strand) to 14.537021 Hz (stable strand) went down to the grazing point
14.528206, across the corner, down to the smooth fold 14.528099 and back up, so 9e-3 Hz of two
strands had no stored point and the branch turned at 14.537 Hz, where no fold lies. The
bracket's far end lay 1e-4 Hz from the fold, with a real multiplier within fold_margin of +1,
so ``corners.smooth_fold_beside`` skipped that side. Exact piecewise-smooth problems on the
tracer's protocol, and the paper model's stretch (slow)."""
import warnings

import numpy as np
import pytest

from continuation.pathfollow import Tracer
from continuation.turns import turn_indices
from helpers import ScalarToyProblem


class CornerThenFold(ScalarToyProblem):
    """R = (r(u1, p), -u2); side 0 (u1 < 0): r = -p + g u1 (g < 0: p falls as u1 rises);
    side 1 (u1 >= 0): r = k (u1 - uf)^2 - k uf^2 - p (continuous across u1 = 0). The branch
    comes down side 0 to the corner (u1 = 0, p = 0) and passes it straight (p still falls on
    side 1 while u1 < uf), turns at the smooth fold p_f = -k uf^2 (u1 = uf) and runs back up
    side 1. Multipliers: eigenvalues of I + dR/du / 10, so prod(mu - 1) has the sign of
    -dr/du1: the same on side 0 and on side 1 before the fold (no multiplier passes +1 at the
    corner), the other one beyond the fold; at the corner the real multiplier is
    1 - k uf / 5, within fold_margin 0.05 of +1 for k uf < 0.25."""

    def __init__(self, k, uf, g):
        super().__init__()
        self.k, self.uf, self.g = k, uf, g

    def scalar(self, u, p):
        if self.side(u) == 0:
            return self.g * u[0] - p, self.g
        d = u[0] - self.uf
        return self.k * (d * d - self.uf ** 2) - p, 2.0 * self.k * d


def _trace(k, uf, g, p0=0.5):
    prob = CornerThenFold(k, uf, g)
    u0 = np.array([p0 / g, 0.0])  # side 0
    assert prob.on_branch(u0, p0) < 1e-14
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (none expected; asserted on below by the outcome)
        pts, loc, reason = tr.trace(prob, u0, p0, direction=-1)
    assert reason == "left the parameter range" and pts[-1].p > 1.0
    assert max(prob.on_branch(q.u, q.p) for q in pts) < 1e-9
    return prob, pts, loc


# (k, uf, g): on main before this test, one step went from side 0 (before the corner) to side 1
# beyond the fold, its bracket's far end next to the fold (e.g. (1, 1e-3, -10): from p =
# 8.67e-4 to 1.0e-3, the fold at -1e-6: the branch's lowest point 8.67e-4)
PASSED_BOTH = [(1.0, 1e-3, -1.0), (1.0, 1e-3, -10.0), (1.0, 3e-3, -1.0), (1.0, 3e-3, -10.0),
               (10.0, 1e-3, -1.0), (10.0, 1e-3, -10.0), (10.0, 3e-3, -1.0),
               (100.0, 1e-3, -1.0)]


@pytest.mark.parametrize("k, uf, g", PASSED_BOTH)
def test_no_step_passes_a_corner_and_the_fold_beyond_it(k, uf, g):
    prob, pts, loc = _trace(k, uf, g)
    p_f = -k * uf ** 2
    sides = [q.n_impacts for q in pts]
    n0 = sides.index(1)
    assert sides == [0] * n0 + [1] * (len(pts) - n0)  # each side once: no retrace
    # the step across the corner ends before the fold (or at it: within 5 % of the
    # corner-fold distance |p_f|), not on the strand beyond it
    q = pts[n0]
    assert q.u[0] < uf or abs(q.p - p_f) <= 0.05 * abs(p_f)
    # one turn in p, at the located fold: the fold lies on a step next to the turning point
    p = np.array([q.p for q in pts])
    turns = turn_indices(p, noise=0.0)
    assert len(turns) == 1
    folds = [L for L in loc if L.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].point.p - p_f) <= folds[0].tolerance + 1e-9
    assert turns[0][0] in (folds[0].index, folds[0].index + 1)
    assert [L.kind for L in loc].count("grazing") == 1


@pytest.mark.parametrize("k, uf, g", [(1.0, 3e-2, -1.0), (100.0, 1e-2, -1.0)])
def test_a_fold_well_beyond_the_corner_is_still_reached_with_points_between(k, uf, g):
    """The same corner with the fold far enough beyond it that the bracket's far end tells
    (its multiplier more than fold_margin from +1): unchanged, points between the corner and
    the fold."""
    prob, pts, loc = _trace(k, uf, g)
    between = [q for q in pts if q.n_impacts == 1 and q.u[0] < uf]
    assert between
    assert len([L for L in loc if L.kind == "fold"]) == 1


@pytest.mark.slow
def test_paper_model_reaches_the_fold_beside_the_corner_at_14_528_hz():
    """The paper model at A = 0.2 mm from the stable strand at 14.5545 Hz (branch 1 of the
    diagram at accuracy='off'), 14.50-14.60 Hz: on main before this test the branch turned at
    14.537021 Hz (a jump to 14.538474 Hz on the unstable strand past the grazing point and the
    fold 14.528099), with no point below 14.537 Hz. Now both strands are traced down to the
    fold: the branch's lowest point lies within 1e-3 Hz of it, on the step next to it."""
    import nlbeam
    import continuation as C

    paper = nlbeam.BeamImpact.paper()
    guess = np.array([0.00013883874163522558, 0.005685710244263807])  # branch 1's state0
    sol = C.periodic_solution(paper, 2e-4, 14.554482905571742, guess=guess)
    assert abs(sol.xmax - 2.7357e-4) < 1e-7  # the stable strand (the other orbit: 3.02e-4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # (the coverage warning: 14.50-14.528 Hz)
        frc = C.continue_parameter(sol, "frequency", (14.50, 14.60), model=paper,
                                   accuracy="off")
    assert not any("no fold or period doubling" in str(w.message) for w in caught)
    f = np.asarray(frc.branches[0].frequency)
    folds = [b for b in frc.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].frequency - 14.528099) < 1e-5
    k = int(np.argmin(f))
    assert f[k] - folds[0].frequency < 1e-3  # base: 14.537021 (9e-3 Hz above the fold)
    turns = turn_indices(f)
    assert [t for t, _ in turns] == [k]
    # stored points on both strands between the fold and 14.537 Hz
    n = frc.branches[0].stable
    low = (f < 14.537) & (f > folds[0].frequency)
    assert np.any(low & n) and np.any(low & ~n)


def test_a_turn_without_a_fold_beside_it_is_named_in_a_warning():
    """continuation.turns.unexplained_turns and the diagram's warning: the paper model's
    branch of the 14.537 Hz gap (points 14.5385 -> 14.5370 -> 14.5385 Hz, the fold located at
    14.528099, 9e-3 Hz beyond the turn) is named; the same branch with a point at the fold, or
    a fold whose bracket reaches the turn, is not."""
    from types import SimpleNamespace

    import continuation as C
    from continuation.diagram import _warn_turns
    from continuation.turns import unexplained_turns

    gap = [14.5706, 14.538474, 14.537021, 14.538474, 14.539928]
    fold = [(14.528099, 1e-12)]
    assert unexplained_turns(gap, fold) == [14.537021]
    assert unexplained_turns([14.5706, 14.538474, 14.5283, 14.538474], fold) == []
    assert unexplained_turns(gap, [(14.528099, 0.009)]) == []  # the bracket reaches it
    assert unexplained_turns(gap, []) == [14.537021]
    assert unexplained_turns(gap[:3], fold) == []  # no turn
    br = SimpleNamespace(values=np.array(gap), order=1)
    bf = SimpleNamespace(kind="fold", branch=0, value=14.528099, tolerance=1e-12)
    with pytest.warns(C.ContinuationWarning, match=r"branch 0 \(order 1\) at 14\.537021 Hz"):
        _warn_turns([br], [bf], "frequency", "Hz")
    other = SimpleNamespace(kind="fold", branch=1, value=14.537021, tolerance=1e-12)
    with pytest.warns(C.ContinuationWarning, match="no fold or period doubling"):
        _warn_turns([br], [other], "frequency", "Hz")  # a fold of another branch: no excuse
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_turns([br], [SimpleNamespace(kind="period-doubling", branch=3, value=14.537021,
                                           tolerance=0.0)], "frequency", "Hz")
