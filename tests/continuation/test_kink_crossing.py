"""A kink of the map that keeps the number of impacts per period (issue 15, the 4-mode beam's
5.9 Hz branch at 6.3572-6.3595 Hz: the predictor's residual falls only linearly with the step,
the first Newton step multiplies it, and the tracer crept into the kink by halved steps until
the step underflowed). Exact piecewise-linear problem: the branch and its kink in closed form.

    R(u, p) = (u0 - p,  u1 - M max(u0 - P_K, 0))

so the branch is u = (p, M max(p - P_K, 0)), with a kink at p = P_K where it turns from the
direction (1, 0, 1) to (1, M, 1) (scaled: u, p), the same 5 impacts per period throughout.
The Jacobian the problem reports (as the variational equations report the exact flow's
derivative, not the fixed-step map's) misses the kink for states within LAYER beyond it: there
it is the near side's. Beyond the layer it is exact again, so the far side is smooth and
traceable; the kink itself can only be crossed from the far side."""
import warnings

import numpy as np

from continuation.pathfollow import Tracer
from continuation.shooting import Evaluation
from helpers import ToyProblem

P_K = 1.0       # the kink
M = 200.0       # the far side's slope
LAYER = 5e-5    # beyond the kink, u0 - P_K < LAYER: the reported Jacobian is the near side's
MU = np.diag([0.5, 0.3])  # multipliers (no bifurcation anywhere)


class KinkAhead(ToyProblem):

    def evaluate(self, u, p, jac=True, jac_p=True):
        u = np.asarray(u, float)
        d = u[0] - P_K
        R = np.array([u[0] - p, u[1] - M * max(d, 0.0)])
        Ju = np.eye(2)
        if d > LAYER:  # (the reported derivative; within the layer the near side's)
            Ju[1, 0] = -M
        return Evaluation(R, Ju if jac else None, self.jacobian_p(u, p) if jac_p else None,
                          [MU] if jac else [], abs(u[1]), 5)

    def jacobian_p(self, u, p, ev=None):
        return np.array([-1.0, 0.0])


def _trace(**kw):
    prob = KinkAhead()
    opts = dict(p_min=0.5, p_max=1.05, ds=0.02, ds_max=0.05)
    opts.update(kw)
    tr = Tracer(**opts)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pts, located, reason = tr.trace(prob, np.array([0.9, 0.0]), 0.9, direction=1)
    return pts, located, reason


def test_the_branch_is_followed_across_the_kink():
    """From p = 0.9 up: the branch reaches p_max on the exact far side (u1 = M (p - P_K)),
    every point on the exact branch, none inside the layer (a crossing from beyond it, not a
    creep into it), no bifurcation reported."""
    pts, located, reason = _trace()
    assert reason == "left the parameter range", reason
    ps = np.array([q.p for q in pts])
    assert ps[-1] > 1.05
    assert not np.any((ps > P_K) & (ps < P_K + LAYER))
    assert [q.how for q in pts].count("jump") == 1
    for q in pts:
        assert abs(q.u[0] - q.p) < 1e-9
        assert abs(q.u[1] - M * max(q.p - P_K, 0.0)) < 1e-6 * max(1.0, abs(q.u[1]))
    assert not [L for L in located if L.kind != "grazing"]


def test_signal_needs_a_linear_residual_and_a_growing_newton_step():
    """kinks.signal: a residual linear in the step whose first Newton step grows it is a kink;
    quadratic (a smooth branch, a step too long) or shrinking is not."""
    from continuation import kinks
    lin = [(4e-6, 4e-5, 4e-3), (2e-6, 2e-5, 2e-3)]
    quad = [(4e-6, 4e-5, 4e-3), (2e-6, 1e-5, 1e-3)]
    shrink = [(4e-6, 4e-5, 4e-6), (2e-6, 2e-5, 2e-6)]
    assert kinks.signal(lin, 1e-7) is not None
    assert kinks.signal(quad, 1e-7) is None
    assert kinks.signal(shrink, 1e-7) is None
    assert kinks.signal(lin[:1], 1e-7) is None
    assert abs(kinks.residual_order(quad) - 2.0) < 1e-12


def test_without_the_crossing_the_tracer_creeps_into_the_kink():
    """The construction (kink_steps=(): the tracer as before): the steps halve into the kink
    and the branch ends there, short of it, without a point beyond."""
    pts, _, reason = _trace(kink_steps=())
    assert reason == "step underflow", reason
    assert P_K - 1e-5 < pts[-1].p < P_K
