"""A corner just behind a smooth fold (issue 13 item 4): the near strand turns at its smooth
fold, runs back to the corner and crosses there; a step from before the fold must not be
taken as a crossing onto the far strand (the paper model at 9.1681 Hz: a step from 9.168480 Hz,
above the 8-impact strand's fold 9.168092, onto a 7-impact orbit at 9.152085 Hz was accepted or
not as round-off decided). Exact piecewise-smooth problems on the tracer's protocol."""
import numpy as np
import pytest

from continuation.pathfollow import Tracer
from helpers import ScalarToyProblem


class FoldThenCorner(ScalarToyProblem):
    """R = (r(u1, p), -u2); side 0 (u1 < 0): r = k (u1 - uf)^2 - p, side 1 (u1 >= 0):
    r = k uf^2 - p + g u1 (continuous across u1 = 0). Multipliers: eigenvalues of
    I + dR/du / 10 (prod(mu - 1) has the sign of det(dR/du)). For uf < 0 the branch, coming
    down side 0, turns at the smooth fold p = 0 (u1 = uf), runs back up to the corner
    u1 = 0, p_c = k uf^2, and turns there (g < 0: a non-smooth fold) down side 1,
    u1 = (p_c - p) / |g|. For uf > 0 side 0 reaches the corner before its fold and the branch
    passes it straight."""

    def __init__(self, k, uf, g=-1.0):
        super().__init__()
        self.k, self.uf, self.g = k, uf, g

    def scalar(self, u, p):
        if self.side(u) == 0:
            return self.k * (u[0] - self.uf) ** 2 - p, 2.0 * self.k * (u[0] - self.uf)
        return self.k * self.uf ** 2 - p + self.g * u[0], self.g



def _trace(k, uf):
    prob = FoldThenCorner(k, uf)
    u0 = np.array([uf - np.sqrt(0.5 / k), 0.0])  # side 0 at p = 0.5, before the fold
    assert prob.on_branch(u0, 0.5) < 1e-14
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    pts, loc, reason = tr.trace(prob, u0, 0.5, direction=-1)
    assert reason == "left the parameter range" and pts[-1].p < -1.0
    assert max(prob.on_branch(q.u, q.p) for q in pts) < 1e-9
    sides = [q.n_impacts for q in pts]
    n0 = sides.index(1)
    assert sides == [0] * n0 + [1] * (len(pts) - n0)  # each side once: no retrace
    return prob, pts, loc


# (k, uf): before corners.fold_ahead, each of these crossings was accepted from before the
# smooth fold (no point between the fold and the corner; for (20, -1e-3) the corner's fold
# put at 1.85e-5 +- 1.0e-6, p_c = 2e-5)
BEHIND = [(1.0, -5e-4), (1.0, -1e-3), (1.0, -2e-3), (5.0, -1e-3), (20.0, -5e-4),
          (20.0, -1e-3)]


@pytest.mark.parametrize("k, uf", BEHIND)
def test_no_crossing_is_accepted_behind_a_smooth_fold(k, uf):
    prob, pts, loc = _trace(k, uf)
    p_c = k * uf ** 2
    # the corner is crossed from the stretch between the smooth fold and the corner
    back = [q for q in pts if q.n_impacts == 0 and q.u[0] > uf]
    assert back and all(0.0 <= q.p <= p_c + 1e-12 for q in back)
    folds = [L for L in loc if L.kind == "fold"]  # in the order met along the branch
    assert len(folds) == 2
    smooth, corner = folds
    assert abs(smooth.point.p) <= smooth.tolerance + 1e-9
    # the corner's (non-smooth) fold: at p_c, within its stated error
    assert abs(corner.point.p - p_c) <= corner.tolerance + 1e-9
    assert [L.kind for L in loc].count("grazing") == 1


@pytest.mark.parametrize("k, uf", [(1.0, 1e-3), (20.0, 1e-3), (20.0, 3e-3)])
def test_corner_before_the_fold_is_still_passed_straight(k, uf):
    """The same corner with the fold beyond it (uf > 0: a real multiplier near +1 at the
    corner, the fold never reached): one grazing point, no fold, no turn."""
    prob, pts, loc = _trace(k, uf)
    assert [L.kind for L in loc] == ["grazing"]
    dp = np.diff([q.p for q in pts])
    assert np.all(dp < 0)
    assert abs(loc[0].point.p - k * uf ** 2) < 1e-4


class StrandBehind(ScalarToyProblem):
    """R = (r(u1, p), -u2) with three pieces: u1 < -0.015 (0 impacts): r = u1 + p (strand A,
    p falling as u1 rises, ending at u1 = -0.015 where r jumps); -0.015 <= u1 < 0 (0 impacts):
    r = p - 0.021 - u1 / 10 (strand B, p = 0.0195 .. 0.021); u1 >= 0 (1 impact):
    r = u1 + p - 0.021. B and the 1-impact strand meet at a corner (u1 = 0, p = 0.021,
    a non-smooth fold: dr/du1 changes sign); A meets neither."""

    r_p = 1.0

    def scalar(self, u, p):
        if u[0] < -0.015:
            return u[0] + p, 1.0
        if u[0] < 0.0:
            return p - 0.021 - 0.1 * u[0], -0.1
        return u[0] + p - 0.021, 1.0



def _check(z_a, t_a, z_b):
    from continuation.corners import check_crossing
    prob = StrandBehind()
    tr = Tracer(p_min=-1.0, p_max=1.0)
    ev_a, ev_b = (prob.evaluate(z[:2], z[2]) for z in (z_a, z_b))
    assert max(abs(ev_a.R).max(), abs(ev_b.R).max()) < 1e-15
    t_a = t_a / np.linalg.norm(t_a)
    a, b = tr._point(prob, z_a, ev_a, t_a), tr._point(prob, z_b, ev_b, t_a)
    return check_crossing(tr, prob, a, z_a, t_a, b, z_b, strict=False)


def test_a_bisection_point_behind_a_in_the_parameter_rejects_the_crossing():
    """a on strand A at p = 0.02 travelling down, b on the 1-impact strand at p = 0.015: the
    chord's bisection finds strand B (0 impacts, p = 0.0204 .. 0.021: behind a) and closes in
    on B's corner with the 1-impact strand at p = 0.021 (before this check it was accepted as
    a crossing, joined, without a turn: the paper model's 9.168480 -> 9.152085 Hz step, whose
    bisection's near end lay at 9.1732 Hz, behind a). No crossing: A does not reach it."""
    z_a = np.array([-0.02, 0.0, 0.02])
    assert _check(z_a, np.array([1.0, 0.0, -1.0]), np.array([0.006, 0.0, 0.015])) is None


def test_the_corner_of_the_strand_behind_is_crossed_from_that_strand():
    """The same corner approached along B itself (p rising to 0.021): a crossing, joined,
    turning back (the sign of dr/du1 changes there), bracketed at p = 0.021."""
    z_a = np.array([-0.01, 0.0, 0.02])
    cr = _check(z_a, np.array([1.0, 0.0, 0.1]), np.array([0.003, 0.0, 0.018]))
    assert cr is not None and cr.connected and cr.turn
    assert abs(cr.lo.p - 0.021) < 1e-4 and abs(cr.hi.p - 0.021) < 1e-4
