"""Corners of a branch: where the number of impacts per period changes (a grazing orbit).

The flow map is not smooth there, and a branch may pass straight through the corner or turn
back at it (a non-smooth fold). Which of the two happens is not free: along a branch of a
continuous map the sign of det(dR/du) times the sign of dp/ds does not change (the local degree
of the solution set), and for a periodic orbit det(dR/du) has the sign of prod(mu - 1) (mu the
Floquet multipliers). So the parameter turns back at a corner exactly when an odd number of
real multipliers passes +1 there: a genuine (non-smooth) fold. A turn without that, or a
crossing that lands on another orbit close by, is a failed corner, and the tracer must not
accept it (see ``Tracer.trace``).

This module holds the checks: ``fold_sign`` (the sign of prod(mu - 1) and whether it can be
trusted), ``check_crossing`` (is a point on the far side really the continuation of the
branch: the two are joined through the grazing point, and the turn agrees with the fold
sign), ``far_side`` (fixed-parameter solves on both sides of the corner, each checked), and
``Retrace`` (a point that re-enters a stretch the branch has already traced).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nlbeam import _linalg as la
from ._newton import ConvergenceError


def tangent(J, t_prev):
    """Unit null vector of J (n, n+1) with a positive projection on t_prev."""
    A = np.vstack([J, t_prev[None, :]])
    b = np.zeros(A.shape[0])
    b[-1] = 1.0
    t = la.solve(A, b)
    return t / la.norm(t)


def _real_near_one(mu, margin):
    """Does a real multiplier of mu lie within ``margin`` of +1?"""
    real = mu.real[np.abs(mu.imag) <= 1e-9 * np.maximum(1.0, np.abs(mu))]
    return bool(np.any(np.abs(real - 1.0) < margin))


def fold_sign(pt, margin):
    """(sign of prod(mu - 1), reliable) of a branch point: from its multipliers, or without
    them from det(dR/du) of its Jacobian (the same sign up to a factor fixed by the problem's
    shape). Not reliable where a real multiplier lies within ``margin`` of +1 (its error may
    flip the sign) or nothing is known."""
    mu = pt.multipliers
    if mu is not None:
        tf = float(np.prod(mu - 1.0).real)
        return np.sign(tf), bool(tf != 0.0 and not _real_near_one(mu, margin))
    if pt.jac is not None:
        n = pt.jac.shape[0]
        s = la.det_sign(pt.jac[:, :n])
        return float(s), bool(s != 0.0)
    return 0.0, False


@dataclass
class Crossing:
    """A checked passage through a corner. lo / hi: the points nearest the grazing point on
    the near and the far side (z_lo, z_hi scaled); width: |hi.p - lo.p|; gap: |z_hi - z_lo|
    (scaled: where the parameter turns back at the corner, the turning point lies within
    gap * scale_p of both, though not between them); t_far: the unit
    tangent (scaled) at the far point b, pointing away from the corner; turn: the parameter
    turns back between a and b (a non-smooth fold); connected: True when a bisection of the chord
    joined the two sides, None when it could not be run to the end."""

    lo: object
    hi: object
    z_lo: np.ndarray
    z_hi: np.ndarray
    width: float
    gap: float
    t_far: np.ndarray
    turn: bool
    connected: bool | None


def _oriented(pt, ref):
    if pt.jac is None:
        return ref / la.norm(ref)
    try:
        return tangent(pt.jac, ref)
    except np.linalg.LinAlgError:
        return ref / la.norm(ref)


def _behind(dz, t, cos_max=-0.5):
    """Does the step dz (scaled) from a branch point run back against its direction of travel
    t (unit), at an angle whose cosine is below cos_max?"""
    n = la.norm(dz)
    return n > 0.0 and la.dot(dz, t) < cos_max * n


def _behind_in_p(z, z_a, t, turn_tol, rel=1e-9):
    """Does z (scaled) lie behind z_a in the parameter, against the direction of travel t
    (unit; not judged where its parameter component is below turn_tol), by more than rel of
    the parameter (the paper model at 9.1685 Hz: a bisection point of a's number of impacts
    at 9.1732 Hz, behind a branch point at 9.1685 travelling down)?"""
    if abs(t[-1]) <= turn_tol:
        return False
    return (z[-1] - z_a[-1]) * np.sign(t[-1]) < -rel * max(1.0, abs(z_a[-1]))


def check_crossing(tr, prob, a, z_a, t_a, b, z_b, strict):
    """Is b (another number of impacts than a) the continuation of the branch through a (z_a,
    direction of travel t_a) across a grazing point? The chord from a to b is bisected (the
    corrector on the hyperplane normal to the chord through its midpoint, each solution
    replacing the end with its number of impacts): on one branch the two sides close in on the
    grazing point, from two different orbits they do not (connected: the chord is below 0.3 of
    the first after two or more bisections; where the chord's corrector fails, the corrector
    at the midpoint's parameter is tried; a solution with a's number of impacts behind a,
    against its direction of travel, rejects b: the chord brackets no corner ahead of a).
    Then the travel direction on the far side (away from the grazing point) and the fold
    signs at a and b must agree (``fold_sign``): the parameter turns back if and only if the
    sign of prod(mu - 1) changes, unless that sign or the direction is too uncertain to tell;
    and where it does not turn back, b must not lie behind a in the parameter. strict: the
    bisection must have joined the sides (else an unfinished bisection is accepted). b is
    judged after three bisections; only an accepted b is bracketed on (``tr.grazing_iter``
    bisections in all). Returns a Crossing, or None."""
    lo, z_lo, hi, z_hi = a, z_a, b, z_b
    L0 = la.norm(z_b - z_a)
    e_p = np.zeros(len(z_a))
    e_p[-1] = 1.0
    t_near = _oriented(a, t_a)
    s_a, ok_a = fold_sign(a, tr.fold_margin)
    s_b, ok_b = fold_sign(b, tr.fold_margin)
    done = 0
    judged = False
    while True:
        stop = done >= tr.grazing_iter
        if not stop:
            d = z_hi - z_lo
            L = la.norm(d)
            # (the chord's length, not the bracket's width in p: where the branch turns back at
            # the corner the two sides lie at nearly one p, yet far apart)
            stop = L <= 10 * tr.bif_tol * max(1.0, la.norm(z_a))
        if not stop:
            m = z_lo + 0.5 * d
            try:
                zs, evs, _ = tr.correct(prob, m, d / L, a.corr)
            except ConvergenceError:
                # where the map is too rough for the chord's corrector, the corrector at the
                # midpoint's parameter (the chord's plane turned to p = const), kept if it
                # lands near the chord
                try:
                    zs, evs, _ = tr.correct(prob, m, e_p, a.corr, fixed_p=True)
                    tr.complete_jacobian(prob, evs)
                    stop = bool(la.norm(zs - m) > 0.5 * L)
                except ConvergenceError:
                    stop = True
        if not stop:
            q = tr._point(prob, zs, evs)
            done += 1
            if q.n_impacts == a.n_impacts and _behind(zs - z_a, t_near):
                return None  # the mid-plane cut a's own stretch behind a: the chord brackets
                # no corner ahead of a (b lies on another strand)
            if q.n_impacts == a.n_impacts and _behind_in_p(zs, z_a, t_near, tr.turn_tol):
                return None  # a point of a's number of impacts behind a in the parameter:
                # not on a's strand between a and the corner (which runs ahead of a, unless
                # it turns at a smooth fold first: then the step is too long to tell)
            if q.n_impacts == a.n_impacts:
                lo, z_lo = q, zs
            else:
                hi, z_hi = q, zs
        if judged or not (stop or done == 3):
            if stop:
                break
            continue
        # judged once, after three bisections (or fewer, if they stopped): a rejected b costs
        # no further bisections; an accepted one is bracketed on to grazing_iter
        judged = True
        gap = la.norm(z_hi - z_lo)
        connected = (gap <= 0.3 * L0) if done >= 2 else (True if gap <= 1e-9 else None)
        if connected is False or (strict and not connected):
            return None
        # directions and fold signs at a and at b, b's oriented away from the corner (the
        # chord from lo, the near side's point nearest it); close to the corner the tangents
        # are uncertain (the near side may meet it tangentially in p); a smooth fold between
        # a and the corner or between the corner and b flips both the direction and the sign
        t_far = _oriented(b, z_b - z_lo)
        turn = bool(t_near[-1] * t_far[-1] < 0)
        sure = ok_a and ok_b and min(abs(t_near[-1]), abs(t_far[-1])) > tr.turn_tol
        if sure and turn != (s_a != s_b):
            return None  # a turn with no multiplier through +1 (or the reverse)
        if not turn and (z_b[-1] - z_a[-1]) * t_near[-1] < -1e-12 * max(1.0, abs(z_a[-1])):
            return None  # straight through, yet b lies behind a: the parameter went back and
            # forth, which only two folds could explain: not this branch
        if stop:
            break
    gap = la.norm(z_hi - z_lo)
    return Crossing(lo, hi, z_lo, z_hi, abs(hi.p - lo.p), gap, t_far, turn, connected)


def smooth_fold_beside(tr, a, crossing, b):
    """Does the step from a to b across a corner also pass a smooth fold, on the near side
    (between a and the bracket's near end ``crossing.lo``, both with a's number of impacts) or
    on the far side (between ``crossing.hi`` and b)? Then a real multiplier passed +1 on a
    smooth stretch: the sign of prod(mu - 1) differs between the two points of that stretch,
    where ``fold_sign`` trusts both (no real multiplier within ``tr.fold_margin`` of +1), or,
    where it does not, the sign of det(dR/du) of their Jacobians differs (``_jacobian_sign``:
    trusted where the tangent's parameter component exceeds ``tr.turn_tol``). A turn of such
    a step is the smooth fold's, not the corner's, and the step is too long to place either
    (the paper model at 9.3339 Hz: a step from 9.33459 to 9.33552 Hz passed the grazing point
    9.33421 and the fold 9.333877 behind it, and the grazing point was put at 9.33376, beyond
    the fold, where the branch has no point; at A = 0.2 mm, 14.5282 Hz: a step from 14.538474
    to 14.537021 Hz passed the grazing point 14.528206 and the fold 14.528099 beyond it, and
    the bracket's far end, 1e-4 Hz from that fold, has a real multiplier within fold_margin of
    +1: 9e-3 Hz of two strands had no point). Sides the bisection did not reach (lo is a, or
    hi is b) tell nothing."""
    for p, q in ((a, crossing.lo), (crossing.hi, b)):
        if p is q:
            continue
        if crossing.turn and p is crossing.hi and _near_fold(tr, p):
            return True
        s_p, ok_p = fold_sign(p, tr.fold_margin)
        s_q, ok_q = fold_sign(q, tr.fold_margin)
        if ok_p and ok_q:
            if s_p != s_q:
                return True
            continue
        s_p, ok_p = _jacobian_sign(p, tr.turn_tol)
        s_q, ok_q = _jacobian_sign(q, tr.turn_tol)
        if ok_p and ok_q and p.problem is q.problem and s_p != s_q:
            return True
    return False


def _near_fold(tr, pt):
    """Is the bracket end pt so near a fold that neither sign tells which way its strand runs
    (a real multiplier within ``tr.fold_margin`` of +1, and the Jacobian's tangent within
    ``tr.turn_tol`` of p = const)? Nothing known (no Jacobian) tells nothing."""
    return (pt.jac is not None and not fold_sign(pt, tr.fold_margin)[1]
            and not _jacobian_sign(pt, tr.turn_tol)[1])


def _jacobian_sign(pt, turn_tol):
    """(sign of det(dR/du), reliable) of a branch point from its scaled Jacobian [dR/du |
    dR/dp] (the corrector's: the variational dR/du with its secant correction). Along a smooth
    stretch of one problem it changes sign exactly at a fold, like prod(mu - 1), and it is
    trusted where the parameter component of the Jacobian's unit null vector (the tangent) is
    above ``turn_tol``: that component is |det(dR/du)| over the norm of all n-by-n minors, so
    the point lies clearly off a fold (where a real multiplier within fold_margin of +1
    leaves the multipliers' sign in doubt, the Jacobian's may still be clear)."""
    J = pt.jac
    if J is None:
        return 0.0, False
    n = J.shape[0]
    s = la.det_sign(J[:, :n])
    if s == 0.0:
        return 0.0, False
    try:
        t = tangent(J, np.eye(n + 1)[n])
    except np.linalg.LinAlgError:
        return 0.0, False
    return float(s), bool(abs(t[-1]) > turn_tol)


def fold_ahead(tr, a, crossing):
    """May the near strand turn at a smooth fold before it reaches the corner of this
    crossing? So where a real multiplier of a lies within ``tr.fold_margin`` of +1 (a smooth
    fold of a's strand is near: the sign of prod(mu - 1) there is what ``fold_sign`` cannot
    trust) and the chord's bisection never moved the near end off a (no point of a's strand
    nearer the grazing point was seen: nothing shows that the strand reaches it), or moved it
    to a point of a's number of impacts where the sign of prod(mu - 1) differs from a's (the
    near end lies beyond the fold, on the strand's way back). Such a step
    may land behind the fold, on the strand beyond it (the paper model at 9.1681 Hz: a step
    from 9.168480 Hz, above the 8-impact strand's fold 9.168092, to a 7-impact orbit at
    9.152085 Hz, taken as a corner crossing or not as round-off decided); a shorter step
    decides it: it reaches the fold (and turns there) or brackets the corner from a's side."""
    if a.multipliers is None or not _real_near_one(a.multipliers, tr.fold_margin):
        return False
    if crossing.lo is a:
        return True
    return fold_sign(crossing.lo, tr.fold_margin)[0] != fold_sign(a, tr.fold_margin)[0]


def far_side(tr, prob, a, z_a, t_in, guesses, avoid):
    """Solutions at fixed parameter on the far side of a corner ahead of the branch point a
    (z_a scaled, direction of travel t_in), each checked by ``check_crossing`` (strict): first
    beyond the corner in the direction of travel (the branch passes through it), at relative
    distances ``tr.jump_steps`` (of a's parameter), from the linear predictor and from a's own
    state; then the attractor reached by integrating beyond (``prob.settle``, frequency only;
    not where a's side goes on at the largest distance); then behind it
    (the branch turns back at a non-smooth fold: the far side lies on the near side's
    parameter side), from the latest far-side state the failed steps saw (``guesses``,
    scaled), unless the solves beyond found a's side going on (the corner lies further: the
    branch creeps towards it first, three times in a row at most, unless a's side went on as
    far as the largest distance). Solutions near ``avoid`` (scaled states of a rolled-back
    retrace) are skipped, and so are those that turn back past a smooth fold beside the corner
    (``smooth_fold_beside``: no jump represents that stretch; after one, no further jump
    behind is tried and the creep goes on past three in a row; it is returned only where no
    creep is left); the first one whose check was
    consistent but whose bisection could
    not be finished is kept in ``tr.unverified`` (the tracer's last resort). Returns (z,
    evaluation, Point, Crossing), or (z, evaluation, Point, None) for a solution with a's
    number of impacts a little further in the direction of travel on a's stretch
    (``joined``: a creep towards the corner, at most three in a row), or None."""
    w, wp = prob.scale_u, prob.scale_p
    sp = 1.0 if t_in[-1] >= 0 else -1.0
    e_p = np.zeros(len(z_a))
    e_p[-1] = 1.0
    same = None

    def solve_at(u_scaled, p_scaled):
        zs, evs, _ = tr.correct(prob, np.r_[u_scaled, p_scaled], e_p, a.corr, fixed_p=True)
        return zs, evs

    beside = [None]  # the first candidate dropped for a smooth fold beside the corner

    def candidate(zs, evs):
        if np.max(np.abs(zs[:-1] - z_a[:-1])) > tr.jump_max_distance:
            return None  # another orbit
        if any(np.max(np.abs(zs - v)) < 0.1 * max(np.max(np.abs(v - z_a)), 1e-9)
               for v in avoid):
            return None
        if _lower_order(prob, a, zs):
            return None  # an orbit of a lower order (e.g. the parent branch at a period
            # doubling, which solves this order's problem too): not this branch
        tr.complete_jacobian(prob, evs)
        b = tr._point(prob, zs, evs)
        cr = check_crossing(tr, prob, a, z_a, t_in, b, zs, strict=False)
        if cr is not None and cr.turn and smooth_fold_beside(tr, a, cr, b):
            # a smooth fold beside the corner lies between a and this solution: no
            # fixed-parameter jump represents that stretch (the paper model at A = 0.2 mm: a
            # jump from 14.538474 to 14.537021 Hz passed the fold 14.528099 and the grazing
            # point 14.528206, and 9e-3 Hz of two strands had no point); a's strand is
            # followed on towards the corner instead (creeps, beyond the three in a row)
            if beside[0] is None:
                beside[0] = (zs, evs, b, cr)
            return None
        if cr is not None and cr.connected is None:  # consistent, but the bisection could
            # not be finished (a rough map): kept as the last resort (Tracer.trace)
            if tr.unverified is None:
                tr.unverified = (prob, a, (zs, evs, b, cr))
            return None
        return None if cr is None else (zs, evs, b, cr)

    far = [g[:-1] for g in guesses]
    sames = []  # a's side going on beyond a: (zs, evs) at each distance, nearest first
    same_rel = 0.0  # the furthest relative distance beyond a where a's side goes on
    unit = max(abs(z_a[-1]), 1e-3)  # the distances are relative to a's parameter (scaled)
    for rel in tr.jump_steps:
        dp = sp * rel * unit
        first = [z_a[:-1] + t_in[:-1] / t_in[-1] * dp] if abs(t_in[-1]) > 1e-3 else []
        for g in first + [z_a[:-1]]:
            try:
                zs, evs = solve_at(g, z_a[-1] + dp)
            except ConvergenceError:
                continue
            if evs.n_impacts == a.n_impacts:
                if np.max(np.abs(zs[:-1] - z_a[:-1])) <= tr.jump_max_distance:
                    same = (zs, evs)  # the corner lies further: the furthest one is kept
                    same_rel = rel
                    sames.append(same)
                    break
                continue
            res = candidate(zs, evs)
            if res is not None:
                return res
    p_new = (z_a[-1] + sp * tr.jump_steps[-1] * unit) * wp
    try:  # (a problem without settle raises ConvergenceError: Problem's default)
        if same_rel >= tr.jump_steps[-1]:  # a's side goes on there: the corner is further
            raise ConvergenceError("settle: not needed")
        u = prob.settle(a.u, a.p, p_new, efolds=4.0)
        zs, evs = solve_at(u / w, p_new / wp)
        if evs.n_impacts != a.n_impacts and abs(evs.xmax - a.xmax) < 0.1 * abs(a.xmax):
            res = candidate(zs, evs)
            if res is not None:
                return res
    except ConvergenceError:
        pass
    behind = same is None or (tr._creeps >= 3 and same_rel < tr.jump_steps[-1])
    for rel in tr.jump_steps if behind else ():  # else a's side goes on beyond: creep on
        # towards the corner first
        if beside[0] is not None:
            break  # (a further jump behind lands further along the strand beyond the fold)
        for g in far[-1:]:
            try:
                zs, evs = solve_at(g, z_a[-1] - sp * rel * unit)
            except ConvergenceError:
                continue
            if evs.n_impacts != a.n_impacts:
                res = candidate(zs, evs)
                if res is not None:
                    return res
    for zs, evs in (reversed(sames) if tr._creeps < 3 or beside[0] is not None else ()):
        # the furthest creep whose stretch is smooth: its multipliers moved by at most
        # creep_mu_step from a's, or every test function that changes sign on it has its root
        # located on it (a fixed-parameter jump over a cluster of corners or a fold pair that
        # keeps the number of impacts lands on another sheet, and the bifurcations between
        # would be lost or misplaced), and the chord's midpoint lies on it (``joined``)
        if _lower_order(prob, a, zs) or not joined(tr, prob, a, z_a, zs):
            continue
        tr.complete_jacobian(prob, evs)
        b = tr._point(prob, zs, evs)
        if (mu_distance(a.multipliers, b.multipliers) > tr.creep_mu_step
                and not _smooth_events(tr, prob, a, b)):
            continue
        tr._creeps += 1
        return zs, evs, b, None
    # no creep either: the candidate dropped for a smooth fold beside the corner is taken
    # after all (else the branch would end 'stuck at a corner' where it can go on; the turn
    # it leaves is named by the diagram's warning, diagram._warn_turns)
    return beside[0]


def _smooth_events(tr, prob, a, b):
    """True when every test function (fold, period doubling, Neimark-Sacker) that changes sign
    between the points a and b (one parameter step apart, the same number of impacts) has its
    root located between them by fixed-parameter solves on one smooth stretch
    (``Tracer.locate_p``: None where a solve fails or has another number of impacts)."""
    ta, tb = tr._tests(a), tr._tests(b)
    for k in range(len(ta)):
        if np.sign(ta[k]) != np.sign(tb[k]) and tb[k] != 0:
            if tr.locate_p(prob, a, b, k, ta[k], tb[k]) is None:
                return False
    return True


def mu_distance(mu_a, mu_b):
    """How far the Floquet multipliers moved between two points: the largest distance from a
    multiplier of one set to the nearest of the other, both ways (0 where either is None)."""
    if mu_a is None or mu_b is None:
        return 0.0
    d = np.abs(np.asarray(mu_a)[:, None] - np.asarray(mu_b)[None, :])
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def _lower_order(prob, a, zs):
    """True when the solution zs (scaled) of a problem of order n > 1 repeats after fewer
    excitation periods while the branch point a does not (``minimal_order``, for problems that
    have it): a jump from a switched branch onto its parent branch. (Measured: the paper model's
    order-2 branch from the period doubling at 22.4166 Hz jumped to the order-1 orbit at
    22.4392 Hz, ran back and forth between the two and retraced itself.)"""
    order = getattr(prob, "order", 1)
    mo = getattr(prob, "minimal_order", None)
    if order <= 1 or mo is None:
        return False
    try:
        return (mo(zs[:-1] * prob.scale_u, zs[-1] * prob.scale_p) < order
                and mo(a.u, a.p) == order)
    except (ConvergenceError, ValueError):
        return False


def joined(tr, prob, a, z_a, z_b):
    """Do a and the solution z_b (scaled; a's number of impacts) lie on one smooth stretch of
    a branch? The corrector on the hyperplane normal to the chord through its midpoint must
    land near the chord (within a quarter of its length) with the same number of impacts; on
    two different orbits close by it lands on one of them, half a chord away, or fails."""
    d = z_b - z_a
    L = la.norm(d)
    if L == 0.0:
        return True
    m = z_a + 0.5 * d
    try:
        zs, evs, _ = tr.correct(prob, m, d / L, a.corr)
    except ConvergenceError:
        return False
    return evs.n_impacts == a.n_impacts and la.norm(zs - m) <= 0.25 * L


class Retrace:
    """Finds a branch point that lies on a stretch the branch has already traced.

    A new point re-enters segment i when it lies within ``tol`` times the longer of that
    segment and the new step from it, inside it, with the same number of impacts at both ends,
    its step running along the segment (|cos| > 0.5). Points are compared in the scaled
    unknowns (z) where the new step and the segment lie in one problem (smooth along the
    branch), else by their signatures (``Point.state0``: ``Problem.signature``, for shooting
    the state at excitation phase zero, scaled by the first point's scales, with p), which do
    not depend on how the unknowns are defined but may jump where a contact crosses phase
    zero: a segment or step whose signature moved more than ``jump`` times its length in z is
    not compared. prior: ``export()`` of the other half of the branch, traced before from the
    same first point (its segments in their own direction of travel).

    The parameter is one of the unknowns, compared in the same norm; where a segment's length
    is mostly in the state (a long step), the strand beyond a fold next to it lies within
    ``tol`` of it although its parameter lies outside the segment's. So a point re-enters a
    segment only where its parameter lies within the segment's parameter range (widened by
    ``tol`` times the larger of the two steps' parameter extents), unless a fold may lie on
    the segment (the sign of prod(mu - 1) differs at its ends or is unknown). (Measured: the
    paper model's order-2 branch from 75 Hz passed the fold at 67.6445 Hz and was rolled back
    three times as a retrace of the segment 67.6030-67.6399 Hz from 67.5915 Hz, 0.3 of that
    segment's extent in frequency below it, and ended 'stuck at a corner'.)"""

    def __init__(self, tol, scale, scale_p, prior=None, jump=5.0):
        self.tol = tol
        self.jump = jump
        self.scale = np.asarray(scale, dtype=float)
        self.scale_p = float(scale_p)
        self.rows = []  # signatures
        self.zs = []  # (problem, scaled unknowns)
        self.n = []
        self.dz = []  # length in z of the step that reached each point (0: the first)
        self.fs = []  # sign of prod(mu - 1) at each point (0: unknown)
        self.prior = prior

    def signature(self, pt):
        s = pt.state0 if pt.state0 is not None else pt.u
        m = min(len(s), len(self.scale))
        return np.r_[np.asarray(s[:m]) / self.scale[:m], pt.p / self.scale_p]

    def add(self, pt, z, dz):
        """Record the point pt (z: its scaled unknowns in pt.problem; dz: the length of the
        step that reached it, in z)."""
        self.rows.append(self.signature(pt))
        self.zs.append((pt.problem, np.asarray(z, dtype=float)))
        self.n.append(pt.n_impacts)
        self.dz.append(float(dz))
        mu = getattr(pt, "multipliers", None)
        self.fs.append(0.0 if mu is None else float(np.sign(np.prod(np.asarray(mu) - 1.0).real)))

    def replace_last(self, pt, z):
        """The last point moved into another problem (the same orbit, other unknowns)."""
        self.rows[-1] = self.signature(pt)
        self.zs[-1] = (pt.problem, np.asarray(z, dtype=float))

    def truncate(self, k):
        del self.rows[k:], self.zs[k:], self.n[k:], self.dz[k:], self.fs[k:]

    def export(self):
        return np.array(self.rows), np.array(self.n), np.array(self.dz)

    def _hits(self, A, B, nA, nB, x, dn, n_new, fold=None):
        """(back, fwd): segments A -> B that the new point x (step dn) runs back or forward
        along. fold: per segment, whether a fold may lie on it (None: everywhere)."""
        Ln = la.norm(dn)
        d = B - A
        L = la.norm(d)
        safe = np.where(L > 0, L, 1.0)
        xa = x - A
        dots = xa[:, 0] * d[:, 0]  # row-wise dot products summed in column order (fixed)
        for j in range(1, d.shape[1]):
            dots = dots + xa[:, j] * d[:, j]
        lam = dots / safe ** 2
        dist = la.norm(A + np.clip(lam, 0, 1)[:, None] * d - x)
        cos = la.matmul(d, dn) / (safe * Ln)
        near = ((L > 0) & (lam >= 0) & (lam <= 1) & (dist <= self.tol * np.maximum(L, Ln))
                & (nA == n_new) & (nB == n_new))
        if fold is not None:  # the parameter within the segment's range, unless a fold may
            # lie on it
            margin = (self.tol * np.maximum(np.abs(B[:, -1] - A[:, -1]), abs(float(dn[-1])))
                      + 1e-12 * max(1.0, abs(float(x[-1]))))
            inside = ((x[-1] >= np.minimum(A[:, -1], B[:, -1]) - margin)
                      & (x[-1] <= np.maximum(A[:, -1], B[:, -1]) + margin))
            near &= inside | fold
        return near & (cos < -0.5), near & (cos > 0.5)

    def _smooth(self, S, dz):
        """Segments of the signature rows S whose signature moved at most ``jump`` times
        their length in z (dz: of the step to each row)."""
        L = la.norm(np.diff(S, axis=0))
        return (dz[1:] > 0) & (L <= self.jump * dz[1:])

    def check(self):
        """None, or ('retrace', i): the newest point runs back along segment i of this half;
        ('same', i): it runs along segment i (i <= k - 4) in the same direction (the branch
        closed, or jumped onto itself); ('closed', -1): it runs back along the other half
        (the branch is a loop); ('retrace', -1): it runs forward along the other half."""
        k = len(self.rows) - 1
        if k < 2:
            return None
        X = np.array(self.rows)
        n = np.array(self.n)
        dz = np.array(self.dz)
        fs = np.array(self.fs)
        fold = (fs[:-1] != fs[1:]) | (fs[:-1] == 0)  # per segment i (rows i, i + 1)
        prob, z = self.zs[-1]
        dn_s = X[-1] - X[-2]
        sig_ok = bool(dz[-1] > 0 and 0 < la.norm(dn_s) <= self.jump * dz[-1])
        back = np.zeros(k - 1, dtype=bool)
        fwd = np.zeros(k - 1, dtype=bool)
        handled = np.zeros(k - 1, dtype=bool)
        # the branch's last points in the new point's problem (a problem, once left, is not
        # taken up again, except by a rollback to it): their segments in its scaled unknowns
        s0 = k
        while s0 > 0 and self.zs[s0 - 1][0] is prob:
            s0 -= 1
        if k - 1 - s0 >= 1:
            Z = np.array([zz for _, zz in self.zs[s0:]])
            idx = np.arange(s0, k - 1)
            dn_z = Z[-1] - Z[-2]
            if la.norm(dn_z) > 0:
                back[idx], fwd[idx] = self._hits(Z[:-2], Z[1:-1], n[idx], n[idx + 1], z, dn_z,
                                                 n[-1], fold[idx])
            handled[idx] = True
        if sig_ok:  # the others by their signatures, where these are smooth
            idx = np.nonzero(~handled & self._smooth(X[:-1], dz[:-1]))[0]
            if idx.size:
                b_, f_ = self._hits(X[idx], X[idx + 1], n[idx], n[idx + 1], X[-1], dn_s, n[-1],
                                    fold[idx])
                back[idx] |= b_
                fwd[idx] |= f_
        if np.any(back):
            return "retrace", int(np.nonzero(back)[0][-1])
        fwd[max(0, k - 3):] = False
        if np.any(fwd):
            return "same", int(np.nonzero(fwd)[0][0])
        if self.prior is not None and len(self.prior[0]) >= 2 and sig_ok:
            P, nP, dP = self.prior
            idx = np.nonzero(self._smooth(P, dP))[0]
            if idx.size:
                b_, f_ = self._hits(P[idx], P[idx + 1], nP[idx], nP[idx + 1], X[-1], dn_s,
                                    n[-1])
                if np.any(b_):
                    return "closed", -1
                if np.any(f_):
                    return "retrace", -1
        return None


JUMP_HS = (1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2)  # map_jump's scaled distances


def map_jump(prob, z, t, hs=JUMP_HS, min_jump=1e-5,
             steep=1e3):
    """Is the map R discontinuous just ahead of the solution z (scaled, R(z) = 0) along the
    unit tangent t? R is evaluated at z + h t for the scaled distances ``hs``: along a smooth
    branch |R| grows like h^2 (like h where t is only approximate); across a jump it is at
    least ``min_jump`` and either 100 h or ``steep`` times |R| at the h before (a thousandfold
    rise over a decade of h, where a smooth branch rises a hundredfold at most), and stays
    within a factor 1.5 of that at the next h, ten times further (it does not grow with h; at a
    grazing point of a stiff contact the map is steep but continuous: |R| grows like sqrt(h) or
    faster). The last h only serves that check. Returns (h, |R| there) of the first such h, or
    None. (The fixed-step flow map jumps where, e.g., a contact ends and restarts within a
    step, or its penetration dips to zero and the Lankarani-Nikravesh onset-velocity memory
    resets: no step length passes it. The rise rule finds a jump up to 1e-3 ahead, where the
    smooth residual is already ~1e-7..1e-6; measured on the 4-mode beam at 12.016 Hz: |R|
    3.8e-7 at h = 1e-5, 8.3e-3 at 1e-4 and 8.7e-3 at 1e-3, the number of impacts 8 -> 7.)"""
    w, wp = prob.scale_u, prob.scale_p
    res = []
    for h in hs:
        zh = z + h * t
        try:
            ev = prob.evaluate(zh[:-1] * w, zh[-1] * wp, jac=False, jac_p=False)
            res.append(float(np.max(np.abs(ev.R / w))))
        except ConvergenceError:
            res.append(np.inf)
    for k in range(len(hs) - 1):
        r, r2 = res[k], res[k + 1]
        r0 = res[k - 1] if k > 0 else np.inf
        rises = r >= 100 * hs[k] or (np.isfinite(r0) and r >= steep * r0)
        if np.isfinite(r) and r >= min_jump and rises and r2 <= 1.5 * r:
            return hs[k], r
    return None
