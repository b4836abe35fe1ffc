"""Kinks of a branch: points where the map R(u, p) is not smooth but the number of impacts per
period stays the same (a contact phase that grazes inside a sustained contact, a step decision
of the fixed-step flow map, the variational equations missing what the discrete map does), so
that the corner machinery (continuation.corners), started by a change of that number, does not
see them. Along the branch the solution stays continuous; its tangent jumps.

A step whose predictor lies beyond a kink shows it: the predictor's residual falls only
linearly with the step (a smooth branch: like ds^2), and the corrector's first Newton step,
with the near side's Jacobian or one the variational equations give, multiplies the residual
instead of dividing it (``signal``). The tracer then crosses from the far side
(``crossing``): a fixed-parameter solve beyond the kink, joined to the near side through it
(``meet``: the near side's tangent line and the far side's, followed back, meet at one point
where R vanishes to first order), instead of halving the step into the kink until the step
underflows. Where no solution lies beyond the kink, the branch may turn back there with the same
number of impacts (a non-smooth fold, as at a corner): ``turn`` looks for the far strand behind
the kink in the parameter, from states beyond the kink, and accepts it where it is joined to
the near side through the kink and the sign of prod(mu - 1) changes (the tracer reports a fold
there).
"""
from __future__ import annotations

import numpy as np

from nlbeam import _linalg as la
from ._newton import ConvergenceError
from .corners import fold_sign, tangent

GROWTH = 10.0  # the first Newton step multiplies the predictor's residual by more than this
ORDER = 1.5  # the predictor's residual falls with the step at a lower order than this


def residual_order(trials):
    """The order q of |R(predictor)| ~ ds^q from the two failed trials of one point with the
    widest ratio of steps (trials: (ds, r0, r1) each), or None with fewer than two, steps
    closer than a factor 1.5 or a residual that is zero or not finite."""
    best = None
    for i in range(len(trials)):
        for j in range(i + 1, len(trials)):
            (d1, a1, _), (d2, a2, _) = trials[i], trials[j]
            ratio = max(d1, d2) / min(d1, d2)
            if ratio < 1.5 or not (a1 > 0 and a2 > 0 and np.isfinite(a1 + a2)):
                continue
            if best is None or ratio > best[0]:
                best = (ratio, np.log(a1 / a2) / np.log(d1 / d2))
    return None if best is None else float(best[1])


def signal(trials, floor):
    """Do the failed trials at one branch point (ds, predictor residual r0, residual after the
    first Newton step r1; all with the point's number of impacts) show a kink ahead? Both: the
    last trial's first Newton step multiplied a residual above ``floor`` (the corrector's
    noise level) by more than GROWTH, and the predictor's residual fell with the step at an
    order below ORDER (``residual_order``). Returns a short description, or None."""
    if len(trials) < 2:
        return None
    ds, r0, r1 = trials[-1]
    if not (r0 > floor and np.isfinite(r0)) or not (r1 > GROWTH * r0):
        return None
    q = residual_order(trials)
    if q is None or q >= ORDER:
        return None
    return f"residual order {q:.2f}, first Newton step x{r1 / r0:.3g}"


def _closest(z_a, t_a, z_b, t_b):
    """(s, r, gap): the points z_a + s t_a and z_b - r t_b nearest each other (unit t_a, t_b)
    and their distance; None where the lines are nearly parallel."""
    c = la.dot(t_a, t_b)
    den = 1.0 - c * c
    if den < 1e-8:
        return None
    d = z_b - z_a
    da, db = la.dot(d, t_a), la.dot(d, t_b)
    s = (da - c * db) / den
    r = (db - c * da) / den
    gap = la.norm(z_a + s * t_a - (z_b - r * t_b))
    return s, r, gap


def meet(tr, prob, z_a, t_a, z_b, t_b, rel=0.05):
    """Are the branch points z_a (direction of travel t_a) and z_b (t_b, pointing away from a;
    all scaled) the two sides of one kink? The lines z_a + s t_a and z_b - r t_b must meet
    (s, r >= 0; the gap between them within ``rel`` of the chord), and R at the meeting point
    must be below ``rel`` times R at the chord's midpoint (on a branch with a kink between the
    two, R vanishes at the kink to the order of the curvature; at the chord's midpoint it is
    of the order of the angle times the chord). Returns the meeting point (scaled) or None.
    Two flows without variational equations."""
    w, wp = prob.scale_u, prob.scale_p
    L = la.norm(z_b - z_a)
    res = _closest(z_a, t_a, z_b, t_b)
    if L == 0.0 or res is None:
        return None
    s, r, gap = res
    if s < 0.0 or r < 0.0 or gap > rel * L:
        return None
    k = 0.5 * (z_a + s * t_a + z_b - r * t_b)
    m = 0.5 * (z_a + z_b)
    out = []
    for q in (k, m):
        try:
            ev = prob.evaluate(q[:-1] * w, q[-1] * wp, jac=False, jac_p=False)
        except ConvergenceError:
            return None
        tr.n_evaluations += 1
        out.append(float(np.max(np.abs(ev.R / w))))
    if tr.debug:
        print("  kink: |R| %.3g at the meeting point, %.3g at the chord's midpoint" % tuple(out))
    # (R at the meeting point within the map's noise, where R at the midpoint lies above it,
    # counts as vanishing: the 4-mode beam at 6.35952 Hz, 2.5e-8 against 1.6e-7)
    if not (np.isfinite(out[0]) and (out[0] <= rel * out[1]
                                     or out[0] <= 0.5 * tr.noise_tol < tr.noise_tol < out[1])):
        return None
    return k


def _same_strand_solutions(tr, prob, a, z_a, trials, tag):
    """For each (state guess, scaled parameter) of ``trials`` (lazily, in order): the
    fixed-parameter solution with a's number of impacts within ``tr.jump_max_distance`` of a
    (scaled), as (z, evaluation, Point, tangent away from a); trials that do not converge or
    land elsewhere are passed over. ``tag`` names the caller in debug output."""
    e_p = np.zeros(len(z_a))
    e_p[-1] = 1.0
    for g, p in trials:
        try:
            zs, evs, _ = tr.correct(prob, np.r_[g, p], e_p, a.corr, fixed_p=True)
        except ConvergenceError:
            if tr.debug:
                print("  %s: no solution at p %.9g" % (tag, p * prob.scale_p))
            continue
        dist = np.max(np.abs(zs[:-1] - z_a[:-1]))
        if tr.debug:
            print("  %s: p %.9g impacts %d (a: %d), distance %.3g" % (
                tag, zs[-1] * prob.scale_p, evs.n_impacts, a.n_impacts, dist))
        if evs.n_impacts != a.n_impacts or dist > tr.jump_max_distance:
            continue
        tr.complete_jacobian(prob, evs)
        b = tr._point(prob, zs, evs)
        try:
            t_b = tangent(b.jac, zs - z_a)
        except np.linalg.LinAlgError:
            continue
        yield zs, evs, b, t_b


def crossing(tr, prob, a, z_a, t_in, dps):
    """A branch point beyond a kink ahead of the branch point a (z_a scaled, direction of
    travel t_in, unit): fixed-parameter solves at the scaled parameter distances ``dps``
    beyond a (nearest first), from the linear predictor along t_in and from a's own state,
    each with a's number of impacts, within ``tr.jump_max_distance`` of a, and joined to a
    through a kink (``meet``: a solution whose tangent is a's, before the kink, is passed
    over). Returns (z, evaluation, Point, tangent away from a, kink point)
    or None."""
    sp = 1.0 if t_in[-1] >= 0 else -1.0
    t_a = tangent(a.jac, t_in) if a.jac is not None else t_in

    def trials():
        for dp in dps:
            if abs(t_in[-1]) > 1e-3:
                yield z_a[:-1] + t_in[:-1] / t_in[-1] * sp * dp, z_a[-1] + sp * dp
            yield z_a[:-1], z_a[-1] + sp * dp
    for zs, evs, b, t_b in _same_strand_solutions(tr, prob, a, z_a, trials(), "kink"):
        k = meet(tr, prob, z_a, t_a, zs, t_b)
        if tr.debug:
            print("  kink: lines %s, meet %s" % (_closest(z_a, t_a, zs, t_b), k is not None))
        # (None where the tangents are parallel:
        # b lies before the kink, on a's smooth stretch; a larger distance is tried)
        if k is not None:
            b.tangent = t_b
            return zs, evs, b, t_b, k
    return None


def turn(tr, prob, a, z_a, t_in, dps, d_fail):
    """A branch point on a strand that turns back at a kink ahead of the branch point a (z_a
    scaled, direction of travel t_in, unit): fixed-parameter solves at the scaled parameter
    distances ``dps`` behind a (nearest first), started from states beyond the kink (a's state
    moved d_fail and 2 d_fail along t_in, d_fail: the longest failed step, whose predictor lay
    beyond it), so that the first Newton step uses the far side's Jacobian. A solution must keep
    a's number of impacts, lie within ``tr.jump_max_distance`` of a, be joined to a through the
    kink (``meet``; a solution on a's own strand, tangent parallel to a's, is passed over) and
    have the other sign of prod(mu - 1) (``corners.fold_sign``: unless either sign is
    uncertain, as a corner's turn must). Returns (z, evaluation, Point, tangent away from the
    kink, kink point) or None."""
    sp = 1.0 if t_in[-1] >= 0 else -1.0
    t_a = tangent(a.jac, t_in) if a.jac is not None else t_in
    s_a, ok_a = fold_sign(a, tr.fold_margin)
    starts = [z_a[:-1] + k * d_fail * t_in[:-1] for k in (1.0, 2.0)]
    trials = ((g, z_a[-1] - sp * dp) for dp in dps for g in starts)
    for zs, evs, b, t_b in _same_strand_solutions(tr, prob, a, z_a, trials, "kink turn"):
        if t_b[-1] * sp > 0:
            continue  # not back in the parameter: no turn (crossing's case)
        s_b, ok_b = fold_sign(b, tr.fold_margin)
        if ok_a and ok_b and s_a == s_b:
            if tr.debug:
                print("  kink turn: the sign of prod(mu - 1) does not change")
            continue
        k = meet(tr, prob, z_a, t_a, zs, t_b)
        if tr.debug:
            print("  kink turn: lines %s, meet %s" % (_closest(z_a, t_a, zs, t_b),
                                                     k is not None))
        if k is not None:
            b.tangent = t_b
            return zs, evs, b, t_b, k
    return None
