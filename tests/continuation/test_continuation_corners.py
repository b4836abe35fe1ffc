"""Corners of a branch (the number of impacts changes) on synthetic problems that implement the
tracer's protocol: a non-smooth fold is passed by turning back, a branch through a corner goes
straight on, a closed curve ends as 'closed (isola)', and a retrace is caught (never silent)."""
import numpy as np
import pytest

import continuation as C
from continuation.corners import Crossing, Retrace
from continuation.pathfollow import Problem, Tracer
from continuation.shooting import Evaluation
from helpers import ToyProblem


class PiecewiseLinear(ToyProblem):
    """R(u, p) = A_s u + b p + (0, u1^2 / 2), s = 0 where u1 < 0 and 1 where u1 >= 0 (the
    'number of impacts'), with A_1 = A_0 + a e1^T so that R is continuous across u1 = 0.
    Multipliers: the eigenvalues of I + dR/du / 10, so that prod(mu - 1) = det(dR/du) / 100
    (the fold sign of a periodic orbit), none near -1. Branches: u1 = -A_s^{-1} b p on each
    side (the quadratic term only bends them in u2)."""

    def __init__(self, A0, a, b):
        self.A = [np.asarray(A0, float), np.asarray(A0, float) + np.outer(a, [1.0, 0.0])]
        self.b = np.asarray(b, float)
        super().__init__()

    def evaluate(self, u, p, jac=True, jac_p=True):
        s = self.side(u)
        R = self.A[s] @ u + self.b * p + np.array([0.0, 0.5 * u[0] ** 2])
        J = self.A[s] + np.array([[0.0, 0.0], [u[0], 0.0]])
        return Evaluation(R, J if jac else None, self.b.copy() if jac_p else None,
                          [np.eye(2) + 0.1 * J] if jac else [], abs(u[0]), s)

    def jacobian_p(self, u, p, ev=None):
        return self.b.copy()



# non-smooth folds at p = 0: side 0 has u1 = -p, side 1 has u1 = k p, so both exist for p > 0
# only; det(A_0) = 1 > 0 and det(A_1) = -1 / k < 0 (a multiplier passes +1). The branch arrives
# along side 0 with p falling and leaves along side 1 with p rising. k = 3: side 1 lies ahead
# of the incoming direction (at 63 degrees): the tracer before corners were checked took a
# trial step's secant onto it for its direction and a fixed-p step back up side 0, and traced
# side 0 a second time (both ends 'left the parameter range', no fold, no grazing point).
# k = 1/3: side 1 lies behind (at 117 degrees); oriented by its projection on the incoming
# direction, its tangent points back at the corner.
FOLDS = {"ahead": dict(A0=[[1.0, 0.0], [0.0, 1.0]], a=[-1.0 - 1.0 / 3.0, 0.5], b=[1.0, 0.0]),
         "behind": dict(A0=[[1.0, 0.0], [0.0, 1.0]], a=[-4.0, 0.5], b=[1.0, 0.0])}
FOLD = FOLDS["behind"]
# the same corner passed straight: side 1 has u1 = -p / 3 for p < 0 (det(A_1) = 3 > 0)
STRAIGHT = dict(A0=[[1.0, 0.0], [0.0, 1.0]], a=[2.0, 0.5], b=[1.0, 0.0])


def _start(prob, p):
    u = np.array([-p, -0.5 * p ** 2])  # side 0: u1 = -p, u2 = -u1^2 / 2
    assert prob.on_branch(u, p) < 1e-14
    return u


def _turns(pts):
    dp = np.diff([q.p for q in pts])
    s = np.sign(dp[dp != 0])
    return int(np.sum(s[1:] != s[:-1]))


@pytest.mark.parametrize("where", sorted(FOLDS))
def test_nonsmooth_fold_is_passed_by_turning_back_once(where):
    prob = PiecewiseLinear(**FOLDS[where])
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    pts, loc, reason = tr.trace(prob, _start(prob, 0.9), 0.9, direction=-1)
    assert reason == "left the parameter range"
    assert max(prob.on_branch(q.u, q.p) for q in pts) < 1e-9
    sides = [q.n_impacts for q in pts]
    k = sides.index(1)
    assert sides == [0] * k + [1] * (len(pts) - k)  # each side once: no retrace
    assert _turns(pts) == 1 and pts[-1].p > 1.0 and min(q.p for q in pts) > -1e-9
    kinds = {L.kind: L for L in loc}
    assert set(kinds) == {"grazing", "fold"}
    assert abs(kinds["fold"].point.p) <= kinds["fold"].tolerance + 1e-9
    assert abs(kinds["fold"].point.p) < 1e-4


def test_corner_without_a_multiplier_through_one_is_passed_straight():
    prob = PiecewiseLinear(**STRAIGHT)
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    pts, loc, reason = tr.trace(prob, _start(prob, 0.9), 0.9, direction=-1)
    assert reason == "left the parameter range" and pts[-1].p < -1.0
    assert _turns(pts) == 0
    assert [L.kind for L in loc] == ["grazing"] and abs(loc[0].point.p) < 1e-4


def _old_orientation(monkeypatch):
    """Make every checked crossing orient the far side as the tracer did before corners were
    checked: by its projection on the incoming direction (here: back towards the corner)."""
    import continuation.pathfollow as pf
    import continuation.corners as co

    real = co.check_crossing

    def projected(tr, prob, a, z_a, t_a, b, z_b, strict):
        cr = real(tr, prob, a, z_a, t_a, b, z_b, strict)
        if cr is None:
            return None
        t = cr.t_far if cr.t_far @ t_a > 0 else -cr.t_far
        return Crossing(cr.lo, cr.hi, cr.z_lo, cr.z_hi, cr.width, cr.gap, t, False,
                        cr.connected)

    monkeypatch.setattr(pf, "check_crossing", projected)
    monkeypatch.setattr(co, "check_crossing", projected)


def test_a_retrace_is_caught_and_never_silent(monkeypatch):
    """With the far side oriented back towards the corner, the branch would run back along the
    side it came from (what the tracer did before at such corners: both ends 'left the
    parameter range', the side traced twice). The retrace detector drops those points, and
    when the corner cannot be passed otherwise the branch ends there, loudly."""
    _old_orientation(monkeypatch)
    prob = PiecewiseLinear(**FOLD)
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    with pytest.warns(C.ContinuationWarning, match=r"stuck at a corner near p = [0-9.e-]+"):
        pts, loc, reason = tr.trace(prob, _start(prob, 0.9), 0.9, direction=-1)
    assert reason == "stuck at a corner" and abs(pts[-1].p) < 1e-3
    for side in (0, 1):  # no stretch of either side traced twice
        ps = np.array([q.p for q in pts if q.n_impacts == side])
        assert np.all(np.diff(ps) < 0)


class Circle(Problem):
    """R(u, p) = (u1^2 + p^2 - 1, u2 - u1 p): a smooth closed branch, u1 = cos, p = sin."""

    scale_u = np.ones(2)
    scale_p = 1.0

    def evaluate(self, u, p, jac=True, jac_p=True):
        R = np.array([u[0] ** 2 + p ** 2 - 1.0, u[1] - u[0] * p])
        J = np.array([[2 * u[0], 0.0], [-p, 1.0]])
        return Evaluation(R, J if jac else None, np.array([2 * p, -u[0]]) if jac_p else None,
                          [np.eye(2) + J] if jac else [], abs(u[0]), 0)

    def jacobian_p(self, u, p, ev=None):
        return np.array([2 * p, -u[0]])

    def multipliers(self, Ms):
        return np.linalg.eigvals(Ms[0])

    def adapt(self, u, p):
        return None


def test_closed_branch_ends_as_isola_after_one_lap():
    prob = Circle()
    tr = Tracer(ds=0.05, ds_max=0.2, max_angle=0.2, max_points=2000)
    pts, loc, reason = tr.trace(prob, np.array([1.0, 0.0]), 0.0, direction=1)
    assert reason == "closed (isola)"
    ang = np.unwrap([np.arctan2(q.p, q.u[0]) for q in pts])
    assert 2 * np.pi - 0.3 < ang[-1] - ang[0] < 2 * np.pi + 0.3  # one lap, not two
    assert len([L for L in loc if L.kind == "fold"]) == 2  # p = +-1


def test_retrace_detector_on_a_polyline():
    """Points along a line, then back along it: the first point back on a traced segment is a
    retrace (compared in the unknowns, and by signatures across problems); a polyline that
    comes round to its start in its first direction is closed."""

    class P:
        def __init__(self, x, p, n=0, problem="a"):
            self.u, self.p, self.n_impacts, self.state0 = np.array([x]), p, n, None
            self.problem = problem

    def run(det, pts):
        out = None
        for k, q in enumerate(pts):
            z = np.r_[q.u, q.p]
            dz = 0.0 if k == 0 else float(np.hypot(q.u[0] - pts[k - 1].u[0],
                                                   q.p - pts[k - 1].p))
            det.add(q, z, dz)
            out = det.check()
            if out is not None:
                return out, k
        return out, len(pts) - 1

    line = [P(x, x) for x in (0.0, 1.0, 2.0, 3.0)]
    assert run(Retrace(0.1, [1.0], 1.0), line + [P(2.5, 2.5)]) == (("retrace", 2), 4)
    # another number of impacts there: another orbit
    assert run(Retrace(0.1, [1.0], 1.0), line + [P(2.5, 2.5, n=1)]) == (None, 4)
    # the same, with the unknowns redefined after the third point (another problem)
    moved = line[:2] + [P(x, x, problem="b") for x in (2.0, 3.0, 2.5)]
    assert run(Retrace(0.1, [1.0], 1.0), moved) == (("retrace", 2), 4)
    loop = [P(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi + 0.3, 30)]
    (kind, i), k = run(Retrace(0.1, [1.0], 1.0), loop)
    assert kind == "same" and i == 0 and np.linspace(0, 2 * np.pi + 0.3, 30)[k] > 2 * np.pi

    # segments long in the state, short in the parameter; a point back along them in the
    # state but beyond their parameter range (the strand past a fold next to them, 2.7 of the
    # last segment's parameter extent away): a retrace only where a fold may lie on the
    # segment (the sign of prod(mu - 1) differs at its ends, or is unknown)
    def flat(mus):
        pts = [P(x, 0.01 * x) for x in (0.0, 1.0, 2.0, 3.0)] + [P(2.5, -0.002)]
        for q, mu in zip(pts, mus):
            q.multipliers = None if mu is None else np.array([mu])
        return pts
    assert run(Retrace(0.1, [1.0], 1.0), flat([0.5] * 5)) == (None, 4)
    assert run(Retrace(0.1, [1.0], 1.0), flat([0.5, 0.5, 0.5, 1.5, 0.5])) == (("retrace", 2), 4)
    assert run(Retrace(0.1, [1.0], 1.0), flat([None] * 5)) == (("retrace", 2), 4)
    # within the parameter range widened by tol (here 0.1 of 0.01): a retrace
    pts = flat([0.5] * 5)
    pts[-1].p = 0.0195
    assert run(Retrace(0.1, [1.0], 1.0), pts) == (("retrace", 2), 4)


class Jump(Problem):
    """R(u, p) = (u1 - p - g(p), u2 - p^2 / 2) with g(p) = kink(p - p0): a jump of height
    ``jump`` at p0 (kind 'jump'), or a continuous but steep sqrt(max(p - p0, 0)) (kind 'sqrt')
    that a grazing point of a stiff contact resembles. The same 'number of impacts' on both
    sides. Multipliers: those of I + dR/du / 10."""

    def __init__(self, p0, kind, jump=1e-2):
        self.p0, self.kind, self.jump = p0, kind, jump
        self.scale_u = np.ones(2)
        self.scale_p = 1.0

    def g(self, p):
        d = p - self.p0
        if self.kind == "jump":
            return self.jump if d > 0 else 0.0
        return float(np.sqrt(max(d, 0.0)))

    def evaluate(self, u, p, jac=True, jac_p=True):
        R = np.array([u[0] - p - self.g(p), u[1] - 0.5 * p ** 2])
        J = np.eye(2)
        return Evaluation(R, J if jac else None, np.array([-1.0, -p]) if jac_p else None,
                          [np.eye(2) + 0.1 * J] if jac else [], abs(u[0]), 3)

    def jacobian_p(self, u, p, ev=None):
        return np.array([-1.0, -p])

    def multipliers(self, Ms):
        return np.sort(np.linalg.eigvals(Ms[0]))[::-1]

    def adapt(self, u, p):
        return None


def test_map_jump_tells_a_jump_from_a_steep_continuous_map():
    from continuation.corners import map_jump
    t = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)  # the tangent of the branch u1 = p
    for kind, p0, expect in (("jump", 0.5 + 3e-8, True), ("sqrt", 0.5 + 3e-8, False),
                             ("jump", 0.5 + 0.1, False)):
        prob = Jump(p0, kind)
        z = np.array([0.5, 0.125, 0.5])
        got = map_jump(prob, z, t)
        assert (got is not None) == expect, (kind, p0, got)
        if expect:
            h, r = got
            assert h * t[-1] > 3e-8 and h <= 1e-6 and r == pytest.approx(1e-2, rel=1e-3)


def test_map_jump_finds_a_jump_a_few_steps_ahead_by_how_fast_the_residual_rises():
    """A jump 5e-5 ahead (scaled) of a point where the smooth residual already grows like h:
    |R| rises from ~1e-7 to 5e-3 over a decade of h and then stays flat; a sqrt corner at the
    same place rises too, but keeps growing. The old rule (|R| >= 100 h) missed the jump."""
    from continuation.corners import map_jump
    t = np.array([1.0, 0.48, 1.0])
    t /= np.linalg.norm(t)  # off the branch's tangent (u2' = 0.5): the residual grows like h
    z = np.array([0.5, 0.125, 0.5])
    for kind, expect in (("jump", True), ("sqrt", False)):
        prob = Jump(0.5 + 5e-5, kind, jump=5e-3)
        got = map_jump(prob, z, t)
        assert (got is not None) == expect, (kind, got)
        if expect:
            h, r = got
            assert h == 1e-4 and r == pytest.approx(5e-3, rel=0.05)
            # the old rule alone (no rise test) does not see it
            assert map_jump(prob, z, t, steep=np.inf) is None


def test_branch_that_runs_onto_a_jump_of_the_map_says_so():
    """The tracer cannot pass a jump of the map (no continuous branch goes on): the branch
    ends there as 'discontinuous map' with a warning naming the value, not 'step underflow'.
    (A jump small against the steps is stepped over, as an integration sweep would.)"""
    prob = Jump(0.3, "jump", jump=0.5)
    tr = Tracer(p_min=-1.0, p_max=1.0, ds=0.05, ds_max=0.05)
    with pytest.warns(C.ContinuationWarning, match=r"ends at p = 0\.29999.*discontinuous"):
        pts, loc, reason = tr.trace(prob, np.array([0.0, 0.0]), 0.0, direction=1)
    assert reason == "discontinuous map"
    assert 0.3 - 1e-5 < pts[-1].p <= 0.3
    # the smooth side is traced to the end of the range
    pts, loc, reason = tr.trace(prob, np.array([0.0, 0.0]), 0.0, direction=-1)
    assert reason == "left the parameter range"


def test_a_corner_step_that_also_passes_a_smooth_fold_is_told_apart():
    """corners.smooth_fold_beside: the step a -> b crosses a corner (bracket lo, hi); a real
    multiplier through +1 between a and lo (near side) or between hi and b (far side) is a
    smooth fold on the step as well (the tracer then shortens the step); a change of the
    sign of prod(mu - 1) between lo and hi is the corner's own (a non-smooth fold); a
    multiplier within fold_margin of +1 tells nothing. The multipliers are the paper model's
    at 9.3342 Hz (the step 9.33459 -> 9.33552 Hz that passed the grazing point and the fold
    9.333877 behind it)."""
    from continuation.corners import smooth_fold_beside
    from continuation.pathfollow import Point

    def pt(p, mu):
        return Point(u=np.zeros(2), p=p, xmax=1.0, multipliers=np.asarray(mu, dtype=complex),
                     problem=None, n_impacts=0)

    def crossing(lo, hi):
        return Crossing(lo, hi, None, None, abs(hi.p - lo.p), 0.0, None, True, True)

    tr = Tracer()
    a, lo = pt(9.33459, [-1.296, -0.0066]), pt(9.334219, [-1.296, -0.0066])
    hi, b = pt(9.334208, [-1.266, -0.0067]), pt(9.33552, [4.54, 0.0017])
    assert smooth_fold_beside(tr, a, crossing(lo, hi), b)  # far side: + then -
    assert smooth_fold_beside(tr, b, crossing(hi, lo), a)  # the same step the other way
    hi_turn = pt(9.334208, [4.60, 0.0017])  # the sign changes across the corner itself
    assert not smooth_fold_beside(tr, a, crossing(lo, hi_turn), b)
    near_one = pt(9.33552, [1.02, 0.0017])  # within fold_margin 0.05 of +1: no verdict
    assert not smooth_fold_beside(tr, a, crossing(lo, hi), near_one)
    assert not smooth_fold_beside(tr, a, crossing(a, b), b)  # no bisection point: no verdict
    tr.fold_margin = 0.01
    assert smooth_fold_beside(tr, a, crossing(lo, hi), near_one)


def _scripted_crossing(offset):
    """check_crossing from a (0, 0; p = 0, 3 impacts, travelling along u1) to b (0, 1; p = 0,
    2 impacts) with a corrector that lands on the chord's mid-plane at its midpoint plus
    ``offset`` the first time, then at the midpoint (impacts: 3 where u2 < 0.6, else 2)."""
    from types import SimpleNamespace

    from continuation.corners import check_crossing
    from continuation.pathfollow import Point
    tr = Tracer()
    calls = []

    def correct(prob, m, d, corr, fixed_p=False):
        zs = m + (offset if not calls else 0.0)
        calls.append(zs)
        return zs, SimpleNamespace(n_impacts=3 if zs[1] < 0.6 else 2), 1

    tr.correct = correct
    tr._point = lambda prob, zs, evs: Point(u=zs[:-1], p=zs[-1], xmax=1.0, multipliers=None,
                                            problem=None, n_impacts=evs.n_impacts)
    z_a, z_b = np.zeros(3), np.array([0.0, 1.0, 0.0])
    a = tr._point(None, z_a, SimpleNamespace(n_impacts=3))
    b = tr._point(None, z_b, SimpleNamespace(n_impacts=2))
    return check_crossing(tr, None, a, z_a, np.array([1.0, 0.0, 0.0]), b, z_b, strict=False)


def test_a_bisection_that_runs_back_behind_the_near_point_joins_nothing():
    """The bisection of the chord from a to b closes in on a grazing point only between a and
    b. Where the mid-plane's corrector lands on a's own stretch behind a (against a's direction
    of travel), the chord brackets no corner ahead of a and b lies on another strand: the
    paper model's order-2 branch at 67.6267 Hz took a far-side solve at 67.6943 Hz on the
    lower strand that way (the near side's bisection points at 67.6018 and 67.5913 Hz, behind
    it) and skipped the fold at 67.6445 Hz and 0.1 Hz of branch. Run back, the gap still
    closes (to 0.18 of the chord): before this check that was taken as joined."""
    cr = _scripted_crossing(np.zeros(3))
    assert cr is not None and cr.connected and cr.lo.n_impacts == 3 and cr.hi.n_impacts == 2
    assert 0.5 <= cr.z_lo[1] < 0.6 <= cr.z_hi[1] and cr.gap < 0.01
    assert _scripted_crossing(np.array([-0.5, 0.0, 0.0])) is None
    # off the chord sideways or ahead of a (not behind it): still joined
    assert _scripted_crossing(np.array([0.3, 0.0, 0.0])).connected
