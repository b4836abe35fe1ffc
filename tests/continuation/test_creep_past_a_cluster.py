"""A creep towards a corner (``continuation.corners.far_side``: a fixed-parameter solve ahead of
the last branch point that keeps its number of impacts) must not jump over a cluster of
events: a period doubling, then a stretch with another number of impacts, then the first number
again with jumped multipliers. The 3-mode beam at 27.605 Hz (issue 13 item 6 with the dt caps)
crept 1e-3 relative ahead over the period doubling at 27.62695 Hz, two grazing points and two
folds, and listed one Neimark-Sacker point with a 0.028 Hz bracket instead."""
import numpy as np

from continuation.corners import far_side, mu_distance
from continuation.pathfollow import Tracer
from continuation.shooting import Evaluation
from helpers import ToyProblem

P0 = 0.5                       # the last branch point
P_PD = 0.50007                 # a multiplier passes -1 (smooth period doubling)
WINDOW = (0.5001, 0.5002)      # 6 impacts per period inside, 5 outside
# far_side's distances, relative to P0: 5e-6, 5e-5 (before the period doubling) and 5e-4
# (beyond the window; the chord's midpoint, 0.50025, lies beyond it too, so that the midpoint
# check alone does not see the window)
JUMPS = (1e-5, 1e-4, 1e-3)


class ClusterAhead(ToyProblem):
    """R(u, p) = u - (p, 0): the branch u = (p, 0). Multipliers -1 - (p - P_PD) / 2 and 0.3
    below the window (the period doubling at P_PD), 0.6 and 0.2 inside it, a complex pair
    1.05 e^(+-2i) beyond it."""

    @staticmethod
    def monodromy(p):
        if p < WINDOW[0]:
            return np.diag([-1.0 - 0.5 * (p - P_PD), 0.3])
        if p < WINDOW[1]:
            return np.diag([0.6, 0.2])
        c, s = np.cos(2.0), np.sin(2.0)
        return 1.05 * np.array([[c, -s], [s, c]])

    def evaluate(self, u, p, jac=True, jac_p=True):
        R = np.asarray(u, float) - np.array([p, 0.0])
        n = 6 if WINDOW[0] <= p < WINDOW[1] else 5
        return Evaluation(R, np.eye(2) if jac else None,
                          np.array([-1.0, 0.0]) if jac_p else None,
                          [self.monodromy(p)] if jac else [], abs(u[0]), n)

    def jacobian_p(self, u, p, ev=None):
        return np.array([-1.0, 0.0])



def _creep(**kw):
    prob = ClusterAhead()
    tr = Tracer(jump_steps=JUMPS, **kw)
    tr._creeps, tr.unverified = 0, None
    z = np.array([P0, 0.0, P0])
    a = tr._point(prob, z, prob.evaluate(z[:2], P0), np.array([0.0, 0.0, 1.0]))
    t_in = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    return far_side(tr, prob, a, z, t_in, [], []), a


def test_the_far_creep_jumps_over_the_cluster():
    """The construction: the furthest solve ahead has the last point's number of impacts and
    passes the chord's midpoint check, and its multipliers moved by more than 1."""
    res, a = _creep(creep_mu_step=np.inf)   # every creep allowed (the check off)
    zs, _, b, crossing = res
    assert crossing is None and b.n_impacts == a.n_impacts
    assert abs(b.p - P0 * (1 + JUMPS[-1])) < 1e-12 and b.p > WINDOW[1]
    assert mu_distance(a.multipliers, b.multipliers) > 1.0


def test_a_creep_stops_short_of_the_period_doubling_and_the_window():
    """With the check on (the default): the creep goes to the furthest solve whose multipliers
    moved by at most creep_mu_step, before the period doubling, so that the tracer's own steps
    then meet the period doubling and the grazing points one by one."""
    res, a = _creep()
    _, _, b, crossing = res
    assert crossing is None and b.n_impacts == a.n_impacts
    assert abs(b.p - P0 * (1 + JUMPS[1])) < 1e-12 and b.p < P_PD
    assert mu_distance(a.multipliers, b.multipliers) <= Tracer().creep_mu_step
