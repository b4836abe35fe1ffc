"""A corner just behind a smooth fold (issue 13 item 4): the near strand turns at its smooth
fold, runs back to the corner and crosses there; a step from before the fold must not be
taken as a crossing onto the far strand (the paper model at 9.1681 Hz: a step from 9.168480 Hz,
above the 8-impact strand's fold 9.168092, onto a 7-impact orbit at 9.152085 Hz was accepted or
not as round-off decided). Exact piecewise-smooth problems on the tracer's protocol."""
import numpy as np
import pytest

from continuation.pathfollow import Problem, Tracer
from continuation.shooting import Evaluation


class FoldThenCorner(Problem):
    """R = (r(u1, p), -u2); side 0 (u1 < 0): r = k (u1 - uf)^2 - p, side 1 (u1 >= 0):
    r = k uf^2 - p + g u1 (continuous across u1 = 0). Multipliers: eigenvalues of
    I + dR/du / 10 (prod(mu - 1) has the sign of det(dR/du)). For uf < 0 the branch, coming
    down side 0, turns at the smooth fold p = 0 (u1 = uf), runs back up to the corner
    u1 = 0, p_c = k uf^2, and turns there (g < 0: a non-smooth fold) down side 1,
    u1 = (p_c - p) / |g|. For uf > 0 side 0 reaches the corner before its fold and the branch
    passes it straight."""

    def __init__(self, k, uf, g=-1.0):
        self.k, self.uf, self.g = k, uf, g
        self.scale_u = np.ones(2)
        self.scale_p = 1.0

    def side(self, u):
        return int(u[0] >= 0.0)

    def evaluate(self, u, p, jac=True, jac_p=True):
        s = self.side(u)
        if s == 0:
            r, dr = self.k * (u[0] - self.uf) ** 2 - p, 2.0 * self.k * (u[0] - self.uf)
        else:
            r, dr = self.k * self.uf ** 2 - p + self.g * u[0], self.g
        J = np.array([[dr, 0.0], [0.0, -1.0]])
        return Evaluation(np.array([r, -u[1]]), J if jac else None,
                          np.array([-1.0, 0.0]) if jac_p else None,
                          [np.eye(2) + 0.1 * J] if jac else [], abs(u[0]), s)

    def jacobian_p(self, u, p, ev=None):
        return np.array([-1.0, 0.0])

    def multipliers(self, Ms):
        mu = np.linalg.eigvals(Ms[0])
        return mu[np.argsort(-np.abs(mu), kind="stable")]

    def adapt(self, u, p):
        return None

    def on_branch(self, u, p):
        return float(np.max(np.abs(self.evaluate(u, p, jac=False, jac_p=False).R)))


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
