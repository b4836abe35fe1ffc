"""A fold (period doubling, Neimark-Sacker point) within a grazing point's resolution is one
event at the grazing point (issue 13 item 4: the paper model's order-2 branch at 9.66425 Hz
has a fold on each side of a corner within 1e-6 Hz of it; the far one was located in one run
only, and the two runs listed one fold and two). What the tracer reports there must not depend
on which side's locate succeeded or on which step the root fell: exact piecewise-smooth
problems on the tracer's protocol, and Tracer._detect_step / at_grazing_points on given
points."""
import numpy as np
import pytest

from continuation import pathfollow as PF
from continuation.pathfollow import GRAZING_RESOLUTION, Located, Point, Tracer, at_grazing_points
from helpers import ScalarToyProblem


class ZCorner(ScalarToyProblem):
    """R = (P(u1) - (p - 1), -u2): side 0 (u1 < 0) P = a (u1 - f0)^2, a smooth fold at
    u1 = f0 < 0, p = 1; side 1 (u1 >= 0) P = a f0^2 + b u1 - c u1^2 with b = -4 a f0 and
    c = b / (2 f1), a smooth fold at u1 = f1 > 0, p = 1 + a f0^2 + b f1 / 2. The corner
    (u1 = 0, p = 1 + a f0^2) lies between the two folds: coming down side 0 the branch turns at
    its fold, runs up through the corner (not turning there: dP/du1 > 0 on both sides) and
    turns again at side 1's fold, a Z of width ~3 a f0^2 in p around the corner.
    Multipliers: eigenvalues of I + dR/du / 10 (the real one passes +1 at each fold)."""

    def __init__(self, a, f0, f1):
        super().__init__()
        self.a, self.f0 = a, f0
        self.b = -4.0 * a * f0
        self.c = self.b / (2.0 * f1)

    def P(self, x):
        if x < 0.0:
            return self.a * (x - self.f0) ** 2, 2.0 * self.a * (x - self.f0)
        return (self.a * self.f0 ** 2 + self.b * x - self.c * x * x, self.b - 2.0 * self.c * x)

    def folds(self):
        f1 = self.b / (2.0 * self.c)
        return 1.0, 1.0 + self.P(f1)[0], 1.0 + self.P(0.0)[0]  # near fold, far fold, corner

    def scalar(self, u, p):
        P, dP = self.P(u[0])
        return P - (p - 1.0), dP


def _trace(a, f, x0):
    prob = ZCorner(a, -f, f)
    p0 = 1.0 + prob.P(x0)[0]
    tr = Tracer(p_min=0.0, p_max=2.0, ds=0.05, ds_max=0.2, max_angle=0.2)
    pts, loc, reason = tr.trace(prob, np.array([x0, 0.0]), p0, direction=-1)
    assert reason == "left the parameter range"
    assert max(prob.on_branch(q.u, q.p) for q in pts) < 1e-9
    return prob, loc


# (a, f): the Z's folds 3 a f^2 apart around the corner, all within GRAZING_RESOLUTION (1e-5
# of p = 1) of it; the starts (a stand-in for round-off) put the tracer's steps differently:
# on 6b2e8f3 two folds were listed, each located on its smooth side, or (a = 10, f = 3e-5) the
# far one reported at the grazing point and the near one on its side
Z_CASES = [(1.0, 1e-3), (1.0, 3e-4), (1.0, 1e-4), (10.0, 3e-4), (10.0, 1e-4), (10.0, 3e-5)]


@pytest.mark.parametrize("a, f", Z_CASES)
def test_a_fold_pair_around_a_corner_is_one_event_at_the_grazing_point(a, f):
    seen = []
    for x0 in (-0.3, -0.31, -0.305):
        prob, loc = _trace(a, f, x0)
        near, far, corner = prob.folds()
        folds = [L for L in loc if L.kind == "fold"]
        graz = [L for L in loc if L.kind == "grazing"]
        assert len(graz) == 1 and abs(graz[0].point.p - corner) <= graz[0].tolerance + 1e-12
        assert len(folds) == 1, [(L.point.p, L.tolerance, L.note) for L in folds]
        L = folds[0]
        assert L.note.startswith("at grazing") and L.point is graz[0].point
        for x in (near, far):  # its bracket holds both folds (the roots it was located at)
            assert abs(L.point.p - x) <= L.tolerance + 1e-12
        assert L.tolerance <= 4 * a * f * f + graz[0].tolerance
        assert L.root is None or min(abs(L.root.p - near), abs(L.root.p - far)) < 1e-9
        seen.append(L)
    for L in seen[1:]:  # the same event from every start, within the stated brackets
        assert abs(L.point.p - seen[0].point.p) <= L.tolerance + seen[0].tolerance


def test_a_fold_beyond_the_resolution_stays_a_smooth_fold():
    """a = 10, f = 3e-3: the folds lie 9e-5 and 1.8e-4 from the corner (p = 1.00009), beyond
    1e-5 of p: both smooth, located to round-off, from every start."""
    for x0 in (-0.3, -0.31):
        prob, loc = _trace(10.0, 3e-3, x0)
        near, far, corner = prob.folds()
        folds = sorted((L for L in loc if L.kind == "fold"), key=lambda L: L.point.p)
        assert [L.note for L in folds] == ["", ""]
        assert abs(folds[0].point.p - near) < 1e-9 and abs(folds[1].point.p - far) < 1e-9


# --- Tracer._detect_step and at_grazing_points on given points -----------------------------
def _pt(p, mu, n_impacts):
    return Point(u=np.zeros(2), p=p, xmax=1.0, multipliers=np.asarray(mu, dtype=complex),
                 problem=None, n_impacts=n_impacts)


def _fold_grazing_step(locate):
    """The paper model's order-2 step 9.664281 -> 9.664008 Hz: the real multiplier 0.81 ->
    1.002 on the near side, 1.004 -> 0.15 on the far side of the grazing bracket
    (9.6642515, 9.6642512); ``locate(a, b)`` answers the smooth sides' locates."""
    prev, g_near, g_far, pt = (_pt(p, [mu, 0.01], n) for p, mu, n in (
        (9.664281, 0.81, 6), (9.6642515, 1.002, 6), (9.6642512, 1.004, 7), (9.664008, 0.15, 7)))
    tr = Tracer()
    tr.locate_chord = lambda prob, a, b, k, ga, gb: locate(a, b)
    out = tr._detect_step(None, None, None, 0.1, prev, pt, PF.test_functions(prev.multipliers),
                          PF.test_functions(pt.multipliers), True,
                          (g_far, 3e-7, g_near, None), 3)
    graz = Located("grazing", g_far, 3e-7, 3)
    pts = [None, None, None, prev, pt]
    return g_far, at_grazing_points([graz] + out, pts)


def _at(p):
    return _pt(p, [1.0, 0.01], 6), 1e-9


@pytest.mark.parametrize("which", ["both", "near only", "far only", "neither"])
def test_which_side_the_locate_places_does_not_change_the_event(which):
    """Each side's fold located (at 9.664251 / 9.664252 Hz) or not: one fold at the grazing
    point whose bracket holds the far side (on 6b2e8f3: two folds, the unlocated one reported
    at the step's end 9.664008, later located 3.4e-4 Hz away at another fold)."""
    def locate(a, b):
        near = a.n_impacts == 6
        if which == "both" or (which == "near only") == near and which != "neither":
            return _at(9.664251 if near else 9.664252)
        return None
    g_far, out = _fold_grazing_step(locate)
    folds = [L for L in out if L.kind == "fold"]
    assert len(folds) == 1
    L = folds[0]
    assert L.point is g_far and L.note.startswith("at grazing")
    for x in (9.664251, 9.664252):
        assert abs(L.point.p - x) <= L.tolerance
    if which in ("near only", "neither"):  # a side not placed: that side is the bracket
        assert L.tolerance >= abs(9.664008 - g_far.p)
    if which in ("far only", "neither"):
        assert L.tolerance >= abs(9.664281 - g_far.p)


def test_at_grazing_points_keeps_other_events_and_the_window():
    """Within 1e-5 of the grazing point, on a stretch that stays inside that window: moved
    there (root kept); beyond it, or with the branch leaving the window in between (it comes
    back to the parameter later), or another kind merged separately: not merged together."""
    g = _pt(10.0, [0.5, 0.1], 7)
    G = Located("grazing", g, 1e-8, 5)
    pts = [_pt(10.0 + d, [0.5, 0.1], 6) for d in (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 1e-5, -1e-5)]

    def ev(kind, p, index, note=""):
        return Located(kind, _pt(p, [1.0, 0.1], 6), 1e-9, index, note=note)
    near = ev("fold", 10.0 + 0.5 * GRAZING_RESOLUTION * 10.0, 5)
    before = ev("fold", 10.0 + 0.9 * GRAZING_RESOLUTION * 10.0, 4)  # the step before: pts[5]
    # lies inside the window
    far = ev("fold", 10.0 + 1.5 * GRAZING_RESOLUTION * 10.0, 5)  # beyond the resolution
    back = ev("period-doubling", 10.0 + 0.5 * GRAZING_RESOLUTION * 10.0, 1)  # pts[2..5]: out
    pd = ev("period-doubling", 10.0 - 0.2 * GRAZING_RESOLUTION * 10.0, 5)
    jump = Located("period-doubling", g, 3e-5, 5, note="at grazing: multiplier jumps from "
                   "-1.2 to 0.5 (non-smooth)")
    out = at_grazing_points([before, G, near, far, back, pd, jump], pts)
    kinds = [(L.kind, L.point is g) for L in out]
    assert kinds == [("fold", True), ("grazing", True), ("fold", False),
                     ("period-doubling", False), ("period-doubling", True)]
    f = out[0]
    assert f.root is before.point and "2 such events" in f.note
    assert f.tolerance == pytest.approx(0.9 * GRAZING_RESOLUTION * 10.0 + 1e-9)
    assert out[2] is far and out[3] is back
    p2 = out[4]  # the jump and the period doubling within the resolution: one event
    assert p2.tolerance == pytest.approx(3e-5) and "2 such events" in p2.note
    assert p2.note.startswith("at grazing") and not p2.smooth if hasattr(p2, "smooth") else True


def test_a_side_not_placed_far_from_the_grazing_point_stays_a_smooth_event():
    """The paper model's order-1 step at 6.649 Hz: the multiplier passes -1 on the near side
    (0.045 -> -4.225; the locates fail there, the root 2.3e-3 Hz before the grazing point)
    and jumps back across it (-4.225 -> -0.0017): two period doublings. The test function's
    chord puts the unplaced root 24 % into the side, beyond the grazing resolution: it stays at
    the side's end with the side as its bracket, apart from the jump (the first version of
    at_grazing_points merged the two: 136 -> 134 bifurcations on the reference diagram)."""
    prev, g_near, g_far, pt = (_pt(p, [mu, 0.01], n) for p, mu, n in (
        (6.6551, 0.045, 5), (6.64937, -4.225, 5), (6.64936, -0.0017, 6), (6.6490, -0.002, 6)))
    tr = Tracer()
    tr.locate_chord = lambda prob, a, b, k, ga, gb: None
    out = tr._detect_step(None, None, None, 0.1, prev, pt, PF.test_functions(prev.multipliers),
                          PF.test_functions(pt.multipliers), True,
                          (g_far, 1e-6, g_near, None), 3)
    out = at_grazing_points([Located("grazing", g_far, 1e-6, 3)] + out, [None] * 5)
    pds = [L for L in out if L.kind == "period-doubling"]
    assert len(pds) == 2
    side, jump = sorted(pds, key=lambda L: bool(L.note))
    assert side.note == "" and side.point is g_near and not side.placed
    assert side.tolerance == pytest.approx(6.6551 - 6.64937)
    assert jump.point is g_far and jump.note.startswith("at grazing: multiplier jumps")


def test_an_event_at_a_grazing_point_is_paired_with_that_grazing_point():
    """diagram._grazing_partners: a bifurcation reported at a grazing point takes that grazing
    point's estimate (value, error) after the error estimates (the paper model's order-2 fold
    at 9.33417 Hz, reported at the bracket's other end of a turning corner: located again on
    its own it kept its bracket, 9.334172 +- 1.9e-5, in the reference, and landed on its
    grazing point 9.333900 +- 1.4e-4 under A x (1 + 1e-13)). Smooth events, other branches,
    grazing points beyond the brackets: not paired; the nearest grazing point wins."""
    from continuation.diagram import Bifurcation, _grazing_partners

    def b(kind, f, tol, branch=6, note=""):
        return Bifurcation(kind, f, f, 1e-4, 2, branch, tol, None, note=note)
    jump = "at grazing: multiplier jumps from 0.9559 to 1.012 (non-smooth)"
    g1, g2 = b("grazing", 9.3339, 1.3e-6), b("grazing", 9.33418, 1e-6)
    fold = b("fold", 9.334172, 1.9e-5, note=jump)
    smooth = b("fold", 9.334172, 1.9e-5)
    other = b("fold", 9.334172, 1.9e-5, branch=5, note=jump)
    far = b("period-doubling", 9.3345, 1e-6, note=jump)
    pairs = _grazing_partners([g1, fold, smooth, other, far, g2])
    assert len(pairs) == 1 and pairs[0][0] is fold and pairs[0][1] is g2
    assert _grazing_partners([g1, fold]) == []  # 2.7e-4 apart, brackets 2e-5
