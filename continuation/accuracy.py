"""Error estimates from the integration itself: a periodic orbit or a bifurcation solved again
with the step refined, and the difference taken as the measure of the error.

A *level* k is the integrator with the free-flight step and the contact step both divided by
2^k (``Integrator.refined``; for the adaptive method rtol and atol divided by 32^k).

Orbits (``orbit_error``; every PeriodicSolution): the orbit is solved again at level 1 at the
same parameter; the error of its xmax and multipliers is stated as ``SAFETY`` = 2 times the
change. For a method converging at order q >= 1 the error of the level-0 value is
|change| / (1 - 2^-q) <= 2 |change|; measured against converged values
(tests/continuation/test_accuracy.py) the true error is 0.5-0.7 of the stated one on the paper
model, Duffing, a 2-DOF system and a piecewise-linear stop. This covers whatever the error's
cause: the discretization of the flow, and the variational monodromy's difference from the
derivative of the fixed-step map.

Branch points of a diagram (``branch_errors``): every point is carried to level 1 by one Newton
step of the level-1 map (``refined_point``), on to levels 2 and 3 while the stated error
exceeds the target (4 with more than 6 digits asked for), and the diagram reports the finest
multipliers (and stability flags), stated error their last change (twice the larger change
where the changes do not fall 4-fold), or from level 2 on, where the ratio of the last two
changes shows the method's order 4 (``RICHARDSON_RATIOS``) and the impacts per period stay,
the Richardson extrapolant, stated error twice its correction (``carried_estimate``); xmax
stays the level-0 value (error SAFETY times its change). The multipliers' error at the
defaults comes from the contact steps (32 per contact; halving dt alone leaves it,
benchmarks/multiplier_error_sources.py); on the paper diagram the true error at every 10th
point (181, against level 5) is median 1.7e-7, 26 above 1e-5 (levels 0-1: 6.7e-7, 61; in
the chattering stretches 8.3-9.9 Hz and next to corners at 66-67.7 and 110.7-111 Hz).
Every point is estimated, none interpolated (except where no refined orbit is found).

Bifurcations (``bifurcation_levels``) are located again at levels 1, 2, ...: period doublings
and Neimark-Sacker points by the secant method in the parameter on the critical multiplier (a
regular root), folds as the turning point of the branch (the extremum of the parameter along
it, by successive parabolic interpolation on hyperplanes normal to the tangent: it needs no
monodromy, so it is the fold of the discrete map even where the variational monodromy is off;
located at level 0 too), grazing points by bisection on the number of impacts per period
(level 0 too, where the diagram's bracket is wide). ``combine`` turns the values per level
into the reported value and its stated error: the finest value, error half the last change
with one finer level (order >= 1.6 assumed), 3 |d| / (r - 1) with the observed ratio r of
successive changes (Roache's grid convergence index) when it shows clean convergence (3-40);
with two clean ratios (four levels) the Richardson extrapolant, error the change of the
extrapolant; else the larger of the last two changes; never below 2e-9 relative (the solves'
own resolution). Levels are added until the stated error meets the target (``accuracy``: 6
significant digits by default, 8 with 'high') and two changes are seen (``MIN_VALUES``).
``estimate_diagram`` does all of this for a FrequencyResponse.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

import nlbeam
from nlbeam.parameters import with_parameter

from nlbeam import _linalg as la
from ._newton import ConvergenceError
from .shooting import ShootingProblem, _problem_from_state

SAFETY = 2.0  # error of a level-0 value = SAFETY * |level 0 - level 1| (a bound for order >= 1)
# a bifurcation is located at levels until it has at least this many values (two changes):
# one change alone shows no convergence (paper diagram, order-2 PD at 67.58372 Hz next to a
# fold and a corner: the diagram's value and level 1 agree to 3.8e-7 Hz, level 2 moves it by
# 1.5e-4 Hz); where ``max_levels`` allows (grazing points: one level)
MIN_VALUES = 3
GCI_SAFETY = 3.0  # Roache's factor of safety for an observed order not confirmed by a second
ACCURACY = {"default": 6.0, "high": 8.0}
STAGNATION_FROM = 5  # _on_normal gives up from this iterate on where the residual stagnates
KINDS_LOCATED = ("fold", "period-doubling", "neimark-sacker", "grazing")


def target_digits(accuracy):
    """Significant digits asked for: None or 'default' 6, 'high' 8, or a number in [3, 12]."""
    if accuracy is None:
        return ACCURACY["default"]
    if isinstance(accuracy, str):
        if accuracy not in ACCURACY:
            raise ValueError(f"accuracy: must be 'default', 'high' or a number of significant "
                             f"digits in [3, 12], got {accuracy!r}")
        return ACCURACY[accuracy]
    d = float(accuracy)
    if not (3.0 <= d <= 12.0):
        raise ValueError(f"accuracy: a number of significant digits must lie in [3, 12], "
                         f"got {accuracy!r}")
    return d


def multiplier_target(digits):
    """Absolute accuracy of the multipliers that goes with ``digits``: 10^-(digits - 1)
    (1e-5 at the default 6 digits)."""
    return 10.0 ** -(digits - 1.0)


def refined(integrator, k=1):
    """The Integrator of level k (``Integrator.refined``)."""
    return integrator.refined(k)


def at_level(prob, k=1):
    """A copy of the ShootingProblem prob (same boundaries, scales and parameter) integrated at
    level k relative to its own integrator: the steps per period times 2^k."""
    integ = refined(prob.integrator, k)
    spp = prob.steps_per_period * 2 ** k if prob.steps_per_period else None
    new = ShootingProblem(prob.base_model, prob.amplitude, prob.frequency, prob.order,
                          prob.boundaries, integ, parameter=prob.parameter,
                          steps_per_period=spp, scale_u=prob.scale_u, scale_p=prob.scale_p,
                          variational=prob.variational)
    new.sel_clearance = prob.sel_clearance
    return new


def match_multipliers(ref, other):
    """``other`` reordered so that other[i] is the multiplier nearest ref[i] (a one-to-one
    assignment minimising the total distance)."""
    from scipy.optimize import linear_sum_assignment

    ref, other = np.asarray(ref), np.asarray(other)
    _, col = linear_sum_assignment(np.abs(ref[:, None] - other[None, :]))
    return other[col]


@dataclass
class OrbitError:
    """Error estimate of one periodic orbit: xmax (m) and multipliers ((2N,) absolute, None
    without stability) at the orbit's integrator, SAFETY times the change at level 1;
    xmax_refined and multipliers_refined: the values at level 1 (multipliers in the order of the
    orbit's)."""

    xmax: float
    multipliers: np.ndarray | None
    xmax_refined: float
    multipliers_refined: np.ndarray | None


def orbit_error(prob, u, p, xmax, multipliers=None, *, tol=1e-10, max_iter=10):
    """Error estimate of the orbit u of problem prob at parameter p (its xmax and multipliers
    as computed at prob's integrator): the orbit solved again at level 1 at the same parameter
    (Newton from u), SAFETY times the differences. Raises ConvergenceError when the refined
    solve fails (e.g. next to a fold, where the refined branch may not reach p)."""
    fine = at_level(prob, 1)
    u1, ev, _, _ = fine.solve(np.asarray(u, dtype=float), p, tol=tol, max_iter=max_iter)
    mu1 = None
    mu_err = None
    if multipliers is not None and ev.Ms:
        mu1 = match_multipliers(multipliers, fine.multipliers(ev.Ms))
        mu_err = SAFETY * np.abs(np.asarray(multipliers) - mu1)
    return OrbitError(SAFETY * abs(xmax - ev.xmax), mu_err, float(ev.xmax), mu1)


# --- bifurcations at refined levels -------------------------------------------------------------
def _problem_at(model, amplitude, bif, parameter, integrator, segments):
    """A shooting problem at ``integrator`` through the orbit of the bifurcation (from its
    state and contact state at t = 0), continued in ``parameter``; (problem, u, p)."""
    freq = bif.frequency
    amp = amplitude
    m = model
    if parameter == "amplitude":
        amp = bif.value
    elif parameter != "frequency":
        m = with_parameter(model, parameter, float(bif.value))
    prob, u = _problem_from_state(m, amp, freq, bif.order, bif.state0, segments, integrator,
                                  disc0=bif.disc0)
    if parameter != "frequency":
        prob.parameter = parameter
        prob.scale_p = max(abs(prob.value()), 1e-300)
    return prob, u, float(bif.value)


def _critical(kind, mu):
    """The test quantity of a period doubling (Re mu + 1 of the multiplier nearest -1) or a
    Neimark-Sacker point (|mu| - 1 of the complex multiplier nearest the unit circle)."""
    mu = np.asarray(mu)
    if kind == "period-doubling":
        return float(mu[np.argmin(np.abs(mu + 1.0))].real + 1.0)
    cplx = mu[np.abs(mu.imag) > 1e-12 * np.abs(mu)]
    if not cplx.size:
        raise ConvergenceError("neimark-sacker: no complex multiplier pair at this level")
    return float(np.abs(cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))]) - 1.0)


def _secant_regular(prob, u0, p0, kind, hint, tol=1e-10, max_iter=12):
    """Period doubling / Neimark-Sacker of prob near p0 by the secant method in p on the
    critical multiplier (orbits solved at fixed p by Newton), the first step with the slope
    found at the previous level (``hint['slope']``, updated). Returns (p, u)."""
    def g_at(u, p):
        u, ev, _, _ = prob.solve(u, p, tol=tol, max_iter=10)
        if not ev.Ms:
            raise ConvergenceError(f"{kind}: no multipliers (stability=False)")
        return _critical(kind, prob.multipliers(ev.Ms)), u

    ga, ua = g_at(u0, p0)
    pa = p0
    steps = [1e-7, -1e-7, 1e-9, -1e-9]  # relative; a period doubling may lie next to a fold
    if hint.get("slope") and abs(ga / hint["slope"]) < 1e-3 * abs(p0):
        steps.insert(0, -ga / hint["slope"] / p0)
    for h in steps:
        pb = p0 * (1.0 + h) if p0 != 0 else h
        try:
            gb, ub = g_at(ua, pb)
            break
        except ConvergenceError:
            continue
    else:
        raise ConvergenceError(f"{kind}: no orbit next to {p0:.9g} at this level")
    for _ in range(max_iter):
        if abs(pb - pa) <= 1e-12 * abs(pb) or gb == 0.0:
            break
        if gb == ga:
            raise ConvergenceError(f"{kind}: the critical multiplier does not change with the "
                                   f"parameter near {p0:.9g}")
        pc = pb - gb * (pb - pa) / (gb - ga)
        if not math.isfinite(pc) or abs(pc - p0) > 0.02 * abs(p0):
            raise ConvergenceError(f"{kind}: the secant left the neighbourhood of {p0:.9g}")
        uc = ub + (ub - ua) * (pc - pb) / (pb - pa)
        gc, uc = g_at(uc, pc)
        pa, ga, ua, pb, gb, ub = pb, gb, ub, pc, gc, uc
    if gb != ga and pb != pa:
        hint["slope"] = (gb - ga) / (pb - pa)
    return pb, ub


def _on_normal(prob, z_c, t, z_start, jp, tol=1e-10, max_iter=12, ev0=None, with_ev=False):
    """The point of prob's branch on the hyperplane through z_c normal to t (scaled
    variables z = (u / scale_u, p / scale_p)), by Newton on the bordered system from z_start
    (dR/du from the variational equations at each iterate, the scaled dR/dp ``jp`` kept, or
    with jp None taken afresh by a forward difference). ev0: the evaluation at z_start, if
    already made (with jac). Returns z, or (z, its evaluation) with ``with_ev``. Gives up
    (ConvergenceError) where from iterate STAGNATION_FROM on the residual falls by less than a
    factor 0.7 (the tracer's rule: the map is not smooth there, e.g. where contacts nearly
    stick and it has noise far above tol; Newton on the map's own derivative converges
    quadratically elsewhere)."""
    w, wp = prob.scale_u, prob.scale_p
    z = z_start.copy()
    res = res_prev = np.inf
    for it in range(1, max_iter + 1):
        if ev0 is not None and jp is not None:
            ev, ev0 = ev0, None
        else:
            ev = prob.evaluate(z[:-1] * w, z[-1] * wp, jac=True, jac_p=jp is None)
        r = ev.R / w
        col = ev.Jp * wp / w if jp is None else jp
        A = np.vstack([np.hstack([ev.Ju * w[None, :] / w[:, None], col[:, None]]), t[None, :]])
        try:
            dz = la.solve(A, -np.r_[r, la.dot(t, z - z_c)])
        except np.linalg.LinAlgError:
            raise ConvergenceError("fold: singular bordered Jacobian") from None
        res = float(np.max(np.abs(r)))
        if res <= tol and np.max(np.abs(dz)) <= 1e-7:
            return (z, ev) if with_ev else z
        if it >= STAGNATION_FROM and res > tol and res > 0.7 * res_prev:
            break
        res_prev = res
        z = z + dz
    raise ConvergenceError(f"fold: the corrector did not converge near {z_c[-1] * wp:.9g} "
                           f"(residual {res:.1e})")


def _slope(prob, ev, t, jp):
    """(dp/ds, dz/ds) of prob's branch at the point of ev (scaled; s the position along t, so
    t . dz/ds = 1): the tangent of [dR/du | jp]. dR/du is the derivative of the fixed-step map
    (the variational equations), so dp/ds vanishes exactly where dR/du is singular: at the
    fold of the discrete map, whatever the (kept) dR/dp ``jp``, which only scales it."""
    w = prob.scale_u
    A = np.vstack([np.hstack([ev.Ju * w[None, :] / w[:, None], jp[:, None]]), t[None, :]])
    rhs = np.zeros(len(t))
    rhs[-1] = 1.0
    try:
        tau = la.solve(A, rhs)
    except np.linalg.LinAlgError:
        raise ConvergenceError("fold: singular bordered Jacobian") from None
    return float(tau[-1]), tau


def _vertex_by_slope(prob, z0, t, jp, delta, tol, ev0=None, hint=None, s_tol=3e-6,
                     max_iter=10):
    """The turning point of prob's branch near z0 (scaled) by the secant method on dp/ds
    (``_slope``) over points on hyperplanes normal to t at positions s: the first at s = 0
    (ev0: the evaluation at z0), the second a Newton step with the curvature p'' of the last
    level (``hint['curvature']``) or at s = delta, each next one predicted along the last
    tangent. When the secant step is below s_tol, p at the vertex is p + g step / 2 (g = dp/ds,
    step = -g / p'': the parabola's vertex; p is quadratic in s there, so the error of s
    enters squared). Returns (p scaled, z at the vertex)."""
    hint = {} if hint is None else hint
    z_a, ev_a = _on_normal(prob, z0, t, z0, jp, tol, ev0=ev0, with_ev=True)
    g_a, tau_a = _slope(prob, ev_a, t, jp)
    s_a = 0.0
    curv = hint.get("curvature")
    s_b = -g_a / curv if curv else delta
    if not (1e-6 <= abs(s_b) <= 0.02):
        s_b = delta if abs(s_b) < 1e-6 else float(np.sign(s_b)) * 0.02
    for _ in range(max_iter):
        z_b, ev_b = _on_normal(prob, z0 + s_b * t, t, z_a + (s_b - s_a) * tau_a, jp, tol,
                               with_ev=True)
        g_b, tau_b = _slope(prob, ev_b, t, jp)
        if g_b == g_a:
            raise ConvergenceError("fold: dp/ds does not change along the branch near "
                                   f"{z0[-1] * prob.scale_p:.9g}")
        curv = (g_b - g_a) / (s_b - s_a)
        step = -g_b / curv
        if abs(step) <= s_tol:
            hint["curvature"] = curv
            return float(z_b[-1] + 0.5 * g_b * step), z_b + step * tau_b
        s_a, z_a, g_a, tau_a = s_b, z_b, g_b, tau_b
        s_b = s_b + float(np.clip(step, -0.02, 0.02))
    raise ConvergenceError(f"fold: no turning point of the branch found near "
                           f"{z0[-1] * prob.scale_p:.9g}")


def _fold_turning_point(prob, u0, p0, deltas=(1e-4, 1e-5), tol=1e-10, hint=None):
    """Fold of prob near (u0, p0): the extremum of p along prob's branch (its turning point),
    over points of the branch on hyperplanes normal to the tangent t at (u0, p0): by the
    secant method on dp/ds from the variational Jacobian (``_vertex_by_slope``; 3-4 points),
    else by successive parabolic interpolation of p(s) alone (``_vertex_along``: three points
    at s = -delta, 0, delta, then each new point at the vertex of the parabola through the
    last three, until the vertex moves less than 3e-6); started again with the next of
    ``deltas`` when a corrector fails (a sharply curved branch), and at last with dR/dp
    renewed at every corrector iterate. hint: a dict carried from level to level (the
    curvature). Returns (p, u)."""
    w, wp = prob.scale_u, prob.scale_p
    z0 = np.r_[np.asarray(u0) / w, p0 / wp]
    ev = prob.evaluate(u0, p0, jac=True, jac_p=True)
    jp = ev.Jp * wp / w
    J = np.hstack([ev.Ju * w[None, :] / w[:, None], jp[:, None]])
    t = la.null_vector(J)  # the tangent (null vector of [dR/du | dR/dp], scaled)
    err = None
    if prob.variational:
        try:
            ps, z = _vertex_by_slope(prob, z0, t, jp, deltas[0], tol, ev0=ev, hint=hint)
            return float(ps * wp), z[:-1] * w
        except ConvergenceError as exc:
            err = exc
    for delta, jp_ in [(d, jp) for d in deltas] + [(deltas[-1], None)]:
        try:
            z = _vertex_along(prob, z0, t, jp_, delta, tol)
            return float(z[-1] * wp), z[:-1] * w
        except ConvergenceError as exc:
            err = exc
    raise err


def _vertex_along(prob, z0, t, jp, delta, tol, s_tol=3e-6, max_iter=12):
    """The branch point (scaled z) at the turning point, see _fold_turning_point."""
    S, P, Z = [], [], []
    z_prev = z0
    for s in (-delta, 0.0, delta):
        z = _on_normal(prob, z0 + s * t, t, z_prev, jp, tol)
        S.append(s)
        P.append(z[-1])
        Z.append(z)
        z_prev = z
    for _ in range(max_iter):
        s1, s2, s3 = S[-3:]
        p1, p2, p3 = P[-3:]
        # vertex of the parabola through the last three points (divided differences)
        d1 = (p2 - p1) / (s2 - s1)
        d2 = ((p3 - p2) / (s3 - s2) - d1) / (s3 - s1)
        if d2 == 0.0:
            break
        sv = 0.5 * (s1 + s2) - d1 / (2 * d2)
        near = S[int(np.argmin(np.abs(np.array(S) - sv)))]
        sv = float(np.clip(sv, near - 0.02, near + 0.02))
        z_start = Z[int(np.argmin(np.abs(np.array(S) - sv)))]
        z = _on_normal(prob, z0 + sv * t, t, z_start + (sv - near) * t, jp, tol)
        moved = abs(sv - S[-1])
        # keep the three points nearest the vertex, the newest last
        keep = np.argsort(np.abs(np.array(S) - sv))[:2]
        S = [S[i] for i in sorted(keep)] + [sv]
        P = [P[i] for i in sorted(keep)] + [z[-1]]
        Z = [Z[i] for i in sorted(keep)] + [z]
        if moved <= s_tol or min(abs(S[0] - sv), abs(S[1] - sv)) <= s_tol:
            return z
    raise ConvergenceError(f"fold: no turning point of the branch found near "
                           f"{z0[-1] * prob.scale_p:.9g}")


def _one_change_in(solve, u0, n0, p0, dp, n_scan):
    """Raise ConvergenceError unless the number of impacts changes once only on the way from
    p0 (n0 impacts) to p0 + dp, sampled at n_scan equal steps (several changes within a
    bracket: which one a bisection lands on is up to round-off)."""
    counts, u = [n0], u0
    for j in range(1, n_scan + 1):
        try:
            u, n = solve(u, p0 + dp * j / n_scan)
        except ConvergenceError:
            continue
        counts.append(n)
    k = sum(a != b for a, b in zip(counts[:-1], counts[1:]))
    if k > 1:
        raise ConvergenceError(
            f"grazing: {k} changes of the number of impacts ({'/'.join(map(str, counts))}) "
            f"between {p0:.9g} and {p0 + dp:.9g}: a cluster, located no closer than that")


def _grazing_bisect(prob, u0, p0, width, resolution, tol=1e-10, max_iter=60, widen=True,
                    expect=None, n_scan=8, far=None):
    """Grazing point of prob near p0: where the number of impacts per period changes, by
    bisection in p between orbits solved at fixed p, down to a width of ``resolution`` |p0|.
    The change is searched at p0 +- ``width`` first, then (``widen``) 4 times wider at each
    try up to 2^11 ``width``; where it first shows at p0 +- d, the stretch beyond the last
    width tried is scanned outward in at most ``n_scan`` steps and the first step whose
    count differs is bisected: the change nearest p0, not any change the wide bracket holds.
    expect: (impacts below, impacts above) of the change located at an earlier level; a
    change between other numbers of impacts is another event (ConvergenceError), never
    this one's estimate. Without ``widen`` (the diagram's own bracket) a bracket in which the
    number of impacts changes more than once (sampled at ``n_scan`` points) is a cluster:
    ConvergenceError (the diagram's bracket is then the stated error). Returns (the middle of
    the final bracket, u at its end on p0's side, half the bracket's width, (impacts below,
    impacts above)). far: the number of impacts on the grazing point's far side (the
    diagram's point): counts are then classed as that number or another one, so that a count
    flickering between two others next to the grazing point (chattering: 4 / 5 impacts below
    the paper model's 6.648 Hz grazing point, 3 above) is one side, not a change."""
    def solve(u, p):
        u, ev, _, _ = prob.solve(u, p, tol=tol, max_iter=12)
        n = ev.n_impacts
        return u, (n if far is None else int(n == far))

    u_mid, n_mid = solve(u0, p0)
    d = max(width, 1e-9 * abs(p0))
    d_max = min(0.01 * abs(p0), 2.0 ** 11 * d) if widen else d  # the widest bracket tried
    lo = hi = None
    d_prev = 0.0
    while True:
        for s in (-1.0, 1.0):
            try:
                u_s, n_s = solve(u_mid, p0 + s * d)
                lost = False
            except ConvergenceError:
                # no orbit near p0's there (e.g. past a fold of p0's strand): what lies
                # between the last width tried and this one is scanned all the same (the
                # paper model's 9.3342 Hz grazing point at the halved step: its change lies in
                # a stretch 1.5e-4 Hz wide between the strand's fold and the level's corner;
                # the widths tried, which depend on the diagram's bracket, stepped over it
                # into the failures below the fold in one run and not in another)
                if not widen or d_prev == 0.0:
                    continue
                u_s = n_s = None
                lost = True
            if lost or n_s != n_mid:
                near = (p0, u_mid, n_mid)
                if not widen:  # the diagram's own bracket: one change in it, or a cluster
                    _one_change_in(solve, u_mid, n_mid, p0, s * d, n_scan)
                # the first change outward from p0: scan the stretch not tried before
                step = (d - d_prev) / max(1, min(n_scan, int(np.ceil((d - d_prev) / width))))
                q = d_prev
                while q + step < d * (1.0 - 1e-12):
                    q += step
                    try:
                        u_q, n_q = solve(near[1], p0 + s * q)
                    except ConvergenceError:
                        continue
                    if n_q != n_mid:
                        u_s, n_s = u_q, n_q
                        break
                    near = (p0 + s * q, u_q, n_q)
                else:
                    if lost:
                        continue  # no change on this side up to this width
                    q = d
                lo, hi = sorted([near, (p0 + s * q, u_s, n_s)], key=lambda x: x[0])
                break
        if lo is not None:
            break
        if d >= d_max:
            break
        d_prev, d = d, min(4.0 * d, d_max)
    if lo is None:
        raise ConvergenceError(f"grazing: no change of the number of impacts near {p0:.9g}")
    for _ in range(max_iter):
        if hi[0] - lo[0] <= resolution * abs(p0):
            break
        pm = 0.5 * (lo[0] + hi[0])
        try:
            um, nm = solve(0.5 * (lo[1] + hi[1]), pm)
        except ConvergenceError:
            um, nm = None, None
        if nm == lo[2]:
            lo = (pm, um, nm)
        elif nm == hi[2]:
            hi = (pm, um, nm)
        else:  # a third impact count or no solution: stop at the bracket so far
            break
    pair = (int(lo[2]), int(hi[2]))
    if far is not None:
        pair = tuple(far if n else -1 for n in pair)  # -1: another number than far
    if expect is not None and pair != tuple(expect):
        raise ConvergenceError(
            f"grazing: the change of impacts found near {0.5 * (lo[0] + hi[0]):.9g} "
            f"({pair[0]} -> {pair[1]}; -1: another number) is not the one located before "
            f"({expect[0]} -> {expect[1]}): another change of the number of impacts")
    near = lo if lo[2] == n_mid else hi
    return 0.5 * (lo[0] + hi[0]), near[1], 0.5 * (hi[0] - lo[0]), pair


def _locate(kind, prob, u, p, width, resolution, hint):
    """(p, u, half-width of the final bracket) of the bifurcation of this kind near p (hint:
    a dict carried from level to level)."""
    if kind == "grazing":
        # a relocation at the diagram's own step stays inside the diagram's bracket; a finer
        # level takes only the change between the same numbers of impacts (hint['impacts'])
        if "far" not in hint and hint.get("level0"):  # the diagram's point: the far side
            hint["far"] = int(prob.solve(u, p, tol=1e-10, max_iter=12)[1].n_impacts)
        p, u, half, pair = _grazing_bisect(prob, u, p, width, resolution,
                                           widen=not hint.get("level0", False),
                                           expect=hint.get("impacts"), far=hint.get("far"))
        hint["impacts"], hint["level0"] = pair, False
        return p, u, half
    if kind == "fold":
        return (*_fold_turning_point(prob, u, p, hint=hint), 0.0)
    return (*_secant_regular(prob, u, p, kind, hint), 0.0)


def combine(values, floor=2e-9):
    """(value, error) from the values of one quantity at levels 0, 1, ..., K (each step half
    the previous), d_k = v_k - v_(k-1), r_k = d_(k-1) / d_k; a ratio is clean when 3 <= r <= 40
    (convergence of order 1.6-5.3). K >= 3 with the last two ratios clean: the Richardson
    extrapolant E_K = v_K + d_K / (r_K - 1), error |E_K - E_(K-1)|. Else the finest value
    v_K: with the last ratio clean, error GCI_SAFETY |d_K| / (r_K - 1) (Roache's grid
    convergence index with his factor 3 for an order observed once, not confirmed); K = 1,
    error |d_1| / 2 (order >= 1.6 assumed); otherwise the larger of |d_K| and |d_(K-1)|
    (paper diagram, order-2 PD at 67.5837 Hz next to a fold and a corner: changes 3.8e-7,
    1.5e-4, -1.4e-5, -7e-6). Never below
    ``floor`` |value| (the solves' own resolution)."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return float(v[-1]), float("nan")
    d = np.diff(v)
    r = [d[i - 1] / d[i] if d[i] != 0.0 else np.inf for i in range(1, len(d))]
    clean = [3.0 <= x <= 40.0 for x in r]
    if len(r) >= 2 and clean[-1] and clean[-2]:
        e_k = v[-1] + d[-1] / (r[-1] - 1.0)
        e_prev = v[-2] + d[-2] / (r[-2] - 1.0)
        value, error = float(e_k), abs(e_k - e_prev)
    elif r and clean[-1]:
        value, error = float(v[-1]), GCI_SAFETY * abs(d[-1]) / (r[-1] - 1.0)
    elif len(d) >= 2 and d[-1] == 0.0:  # no change at the last level
        value, error = float(v[-1]), abs(d[-2]) / 8.0
    elif len(d) >= 2:  # no convergence pattern: the larger of the last two changes
        value, error = float(v[-1]), max(abs(d[-1]), abs(d[-2]))
    else:
        value, error = float(v[-1]), 0.5 * abs(d[-1])
    return value, float(max(error, floor * abs(value)))


@dataclass
class BifurcationLevels:
    """One bifurcation located at levels 0 (the diagram's value), 1, ..., K: values (K + 1,)
    of the continued parameter; value, error: the reported value and its error estimate (see
    ``combine``); failed: the message of a level that did not converge ('' if none)."""

    kind: str
    values: np.ndarray
    value: float
    error: float
    failed: str = ""


# the kinds whose diagram value may not be the level-0 value of the method used at the finer
# levels, located again at level 0 unless the diagram's bracket is narrow (grazing points) or,
# for folds, the diagram had the variational equations: its fold test function (the sign of
# prod(mu - 1), mu from the derivative of the fixed-step map) changes sign exactly where dR/du
# is singular, the turning point of the discrete map (paper diagram, 0.1 mm: the diagram's
# folds and their level-0 turning points agree to 1e-13..3e-9 relative, 3.5e-6 at one in the
# chattering stretch that no finer level locates either)
_RELOCATE_LEVEL0 = ("fold", "grazing")


def bifurcation_levels(model, amplitude, bif, integrator, *, parameter="frequency", digits=6.0,
                       max_levels=4, segments=1):
    """Locate the bifurcation ``bif`` (a continuation.Bifurcation of a diagram computed with
    ``integrator``) at levels 1, 2, ... until the stated error is at most 10^-digits |value|
    (at least three values, two changes, where ``max_levels`` allows: MIN_VALUES; at most
    ``max_levels``); folds of a diagram without stability, and
    folds and grazing points whose bracket is wider than half the target, at level 0 too
    (their diagram values come from another criterion or a wider bracket; see
    _RELOCATE_LEVEL0); one reported at a grazing point (``smooth`` False) as a grazing
    point. Returns a
    BifurcationLevels; a level that does not converge ends the sequence (``failed`` says why;
    with fewer than two levels the error is NaN, except at a grazing point: the width of the
    diagram's bracket, which holds it)."""
    if bif.kind not in KINDS_LOCATED:
        raise ValueError(f"bif.kind: must be one of {KINDS_LOCATED}, got {bif.kind!r}")
    p = float(bif.value)
    # a bifurcation reported at a grazing point (a multiplier jumps there) is located as one
    kind = bif.kind if getattr(bif, "smooth", True) else "grazing"
    relocate = kind in _RELOCATE_LEVEL0
    narrow = math.isfinite(bif.tolerance) and bif.tolerance <= 0.5 * 10.0 ** -digits * abs(p)
    if narrow and (kind == "grazing" or bif.multipliers is not None):
        relocate = False  # the diagram's bracket is narrow enough (a fold: see above)
    values = [] if relocate else [p]
    value, error = p, float("nan")
    failed = ""
    prob = u = None
    hint = {"level0": relocate}  # (grazing: the level-0 search stays in the diagram's bracket)
    width = max(float(bif.tolerance) if math.isfinite(bif.tolerance) else 0.0,
                0.5 * 10.0 ** -digits * abs(p))
    for k in range(0 if relocate else 1, max_levels + 1):
        try:
            if prob is None:
                prob, u, p = _problem_at(model, amplitude, bif, parameter, refined(integrator, k),
                                         segments)
            else:
                prob = at_level(prob, 1)
            p, u, half = _locate(kind, prob, u, p, width, 0.5 * 10.0 ** -digits, hint)
        except (ConvergenceError, ValueError) as exc:
            failed = f"level {k}: {exc}"
            break
        values.append(float(p))
        if len(values) < 2:
            continue
        value, error = combine(values)
        error = max(error, half)
        if error <= 10.0 ** -digits * abs(value) and len(values) >= min(MIN_VALUES,
                                                                         max_levels + 1):
            break
        width = max(abs(values[-1] - values[-2]), 0.5 * 10.0 ** -digits * abs(p))
    if len(values) < 2:
        value, error = (values[0] if values else float(bif.value)), float("nan")
        if kind == "grazing" and math.isfinite(bif.tolerance) and bif.tolerance > 0:
            # a corner the fixed-parameter bisection cannot bracket (e.g. a fold at the
            # grazing point: beyond it no orbit of either kind lies near): the diagram's
            # bracket, which holds the grazing point (and a turning point at it), is the bound
            value, error = float(bif.value), float(bif.tolerance)
            failed = failed or "not located again"
    error = max(error, 1e-15 * abs(value)) if math.isfinite(error) else error
    return BifurcationLevels(bif.kind, np.array(values), float(value), float(error), failed)


# --- whole diagrams ------------------------------------------------------------------------------
def _branch_problem(model, branch, i, integrator):
    """(problem at integrator, u, p) of point i of a Branch, rebuilt from its stored states."""
    m0 = model
    f = float(branch.frequency[i])
    A = float(branch.amplitude[i])
    p = float(branch.values[i])
    if branch.parameter not in ("frequency", "amplitude"):
        m0 = with_parameter(model, branch.parameter, p)
    seg = ~np.isnan(branch.boundaries[i])  # (NaN: fewer segments at this point than others)
    u = np.asarray(branch.states[i][seg], dtype=float).ravel()
    spp0 = integrator.steps_per_period(m0, f)
    # a branch keeps its steps per period over a stretch (the discrete map stays smooth), so
    # near a frequency where the default count doubles a point may hold half or twice it: the
    # count whose orbit the stored states are (smallest residual) is the one estimated
    best = None
    for spp in ((spp0, spp0 // 2, 2 * spp0) if spp0 else (spp0,)):
        if spp0 and spp < 1:
            continue
        prob = ShootingProblem(model, A, f, branch.order, branch.boundaries[i][seg], integrator,
                               parameter=branch.parameter, steps_per_period=spp,
                               variational=branch.multipliers is not None)
        prob.scale_u = prob.make_scale(u, p)
        try:
            r = float(np.max(np.abs(prob.evaluate(u, p, jac=False, jac_p=False).R
                                    / prob.scale_u)))
        except nlbeam.IntegrationError:
            continue
        if best is None or r < best[0]:
            best = (r, prob)
        if r < 1e-9:
            break
    if best is None:
        raise ConvergenceError(f"branch point {i}: its orbit could not be integrated")
    return best[1], u, p


def sample_indices(n, every, corners=()):
    """Every ``every``-th of n branch points, the first and the last always, and both points
    around each corner (``corners``: i for a corner between points i and i + 1), so that no
    estimate is interpolated across a corner."""
    if not n:
        return np.array([], int)
    near = [j for i in corners for j in (i, i + 1) if 0 <= j < n]
    return np.unique(np.r_[np.arange(0, n, max(1, int(every))), n - 1, near]).astype(int)


def corner_indices(branch, bifurcations, index):
    """The corners of ``branch`` (number ``index``): i for each grazing point, or bifurcation
    reported at one, of the diagram on it, where i, i + 1 are the branch points around it (the
    segment of the (parameter, xmax) polyline nearest it, in units of the branch's ranges)."""
    n = len(branch.values)
    if n < 2:
        return []
    v, x = np.asarray(branch.values, float), np.asarray(branch.xmax, float)
    sv, sx = max(np.ptp(v), 1e-300), max(np.ptp(x), 1e-300)
    V, X = v / sv, x / sx
    dV, dX = np.diff(V), np.diff(X)
    L2 = np.where(dV ** 2 + dX ** 2 > 0, dV ** 2 + dX ** 2, 1.0)
    out = set()
    for bf in bifurcations:
        if bf.branch != index or not (bf.kind == "grazing" or not bf.smooth):
            continue
        pv, px = bf.value / sv, bf.xmax / sx
        lam = np.clip(((pv - V[:-1]) * dV + (px - X[:-1]) * dX) / L2, 0.0, 1.0)
        d = np.hypot(V[:-1] + lam * dV - pv, X[:-1] + lam * dX - px)
        out.add(int(np.argmin(d)))
    return sorted(out)


def refined_point(prob, u, p, mu0, *, level=1, jac=None, newton_limit=1e-3,
                  with_impacts=False):
    """The orbit u of prob at p (converged at prob's integrator or at level - 1 of it; mu0:
    its multipliers, None without) carried to ``level`` by one Newton step of that level's map
    from u, with the Jacobian ``jac`` of the coarser level at u if given (one evaluation
    without and one with monodromy; else two with). The orbit moves by its discretization
    error, ~1e-6 of its scale on the paper model, and the multipliers on the unmoved orbit are
    off by as much as their change itself; after the step they equal a fully converged solve
    to 2 digits (measured). Returns (xmax, multipliers largest modulus first or None, the
    moved u, its Jacobian or None; with ``with_impacts`` also the impacts per period at that
    level). Where the step exceeds ``newton_limit`` of the orbit's
    scale (next to a fold or a corner) Newton is run to convergence; raises ConvergenceError
    where that fails."""
    fine = at_level(prob, level)
    ev = fine.evaluate(u, p, jac=jac is None, jac_p=False)
    try:
        du = la.solve(ev.Ju if jac is None else jac, -ev.R)
    except np.linalg.LinAlgError:
        du = np.full_like(u, np.nan)
    want = mu0 is not None
    if not np.all(np.isfinite(du)) or np.max(np.abs(du / prob.scale_u)) > newton_limit:
        # a large step (next to a fold or a corner): Newton to convergence instead
        u1, ev, _, _ = fine.solve(u, p, tol=1e-10, max_iter=8)
    else:
        u1 = u + du
        ev = fine.evaluate(u1, p, jac=want, jac_p=False)
    mu1 = fine.multipliers(ev.Ms) if (want and ev.Ms) else None
    if with_impacts:
        return float(ev.xmax), mu1, u1, ev.Ju, int(ev.n_impacts)
    return float(ev.xmax), mu1, u1, ev.Ju


def _change(mu_new, mu_old):
    """Largest |mu_new - mu_old| / max(1, |mu_new|) over the multipliers (matched)."""
    d = np.abs(mu_new - match_multipliers(mu_new, mu_old)) / np.maximum(1.0, np.abs(mu_new))
    return float(np.max(d))


# observed ratios of successive multiplier changes d_(k-1) / d_k taken as the method's
# asymptotic convergence (RK4: 16; order 3.5-4.5), where Richardson extrapolation is valid.
# Measured on the paper diagram (every 10th point, 181, levels 0-5; python
# /tmp/s10acc/rules.py): d_1 / d_2 percentiles 5/25/50/75/95 1.1 / 8.6 / 13.9 / 16.5 / 37.8,
# d_3 / d_4 2.0 / 14.8 / 15.7 / 16.2 / 23.7: level 0 is often not yet asymptotic, so a wider
# band (8-40) let through points whose ratio was 16 by chance (8.34 Hz: d_1 / d_2 = 23, true
# error 3.5x the extrapolant's stated one)
RICHARDSON_RATIOS = (11.0, 22.0)
RICHARDSON_SAFETY = 2.0  # stated error of the extrapolant: this times its correction


def carried_estimate(mu_prev, mu_k, d_prev, d_k, same_impacts, falling=True):
    """(multipliers reported, their stated error) from the multipliers at two successive
    levels (mu_k at the finer, matched to mu_prev) and the largest relative changes d_prev
    (level k-2 to k-1) and d_k (k-1 to k). Where the ratio r = d_prev / d_k shows the
    method's order (RICHARDSON_RATIOS) and the number of impacts per period did not change
    (``same_impacts``; a change of impact number is no smooth convergence): the Richardson
    extrapolant mu_k + (mu_k - mu_prev) / (r - 1), error RICHARDSON_SAFETY times the size of
    that correction, d_k / (r - 1) (what the extrapolation removed: the error of mu_k). Else
    mu_k with error d_k where the changes fall at least 4-fold (order >= 2), otherwise
    (a corner, chattering) twice the larger change; so too where an earlier change did not
    fall 4-fold (``falling`` False: a sequence that is not converging steadily may fall by
    chance once; paper 110.944 Hz, order 3: changes 4e-2, 6e-2, 1.1e-2, 1.5e-2)."""
    r = d_prev / d_k if d_k > 0.0 else math.inf
    lo, hi = RICHARDSON_RATIOS
    if not falling:
        return np.asarray(mu_k), 2.0 * max(d_prev, d_k)
    if same_impacts and lo <= r <= hi:
        mu = np.asarray(mu_k) + (np.asarray(mu_k) - np.asarray(mu_prev)) / (r - 1.0)
        return mu[np.argsort(-np.abs(mu), kind="stable")], RICHARDSON_SAFETY * d_k / (r - 1.0)
    if d_k <= d_prev / 4:
        return np.asarray(mu_k), d_k
    return np.asarray(mu_k), 2.0 * max(d_prev, d_k)


def branch_errors(model, branch, integrator, *, every=1, corners=(), target=1e-5, levels=3):
    """Error estimates of a Branch's xmax (m) and multipliers, and its multipliers (and
    stability flags) carried to level 1, at every ``every``-th point (default: every point),
    the two ends and both sides of every corner (``corners``: see ``corner_indices``).

    At each such point the stored orbit is carried to level 1 (``refined_point``: one Newton
    step, two evaluations with monodromy at half the steps). xmax stays the level-0 value,
    its error SAFETY times the change (as ``orbit_error``). The multipliers reported become
    the level-1 ones, their error the change (a bound for order >= 1; measured order 4: the
    level-1 error 0.04-0.13 of the change on the paper model at 10.5-60 Hz, Duffing, a 2-DOF
    Hertz system and a piecewise-linear stop), as the largest over the point's multipliers of
    error / max(1, |mu|), never below 1e-10. Where that exceeds ``target`` the point is
    carried on to level 2, 3 (up to ``levels``, while the stated error misses ``target``) and
    reports what ``carried_estimate`` makes of the last two levels: the Richardson
    extrapolant where the ratio of the last two changes shows order 4 and the impacts per
    period stay, else the finest multipliers (error the last change where it fell at least
    4-fold, else twice the larger change). Paper diagram, every 10th point (181) against
    level 5: true error median 6.7e-7 -> 1.7e-7, above 1e-5 61 -> 26, stated above 1e-5
    91 -> 43, true above stated 3 (up to 9.6x) -> 2 (up to 1.7x, at corners where level 5
    itself still changes) against levels=2 without extrapolation. A point whose level-1
    orbit is not found (next to a fold) keeps its level-0 multipliers; it and, with every >
    1, the points between samples get the larger level-0 estimate (SAFETY times the change)
    of their two nearest computed neighbours along the branch. Returns (xmax_error (n,),
    multipliers_error (n,) or None without stability, sampled (n,) bool: where computed,
    multipliers (n, 2N) or None, stable (n,) or None: the branch's with the level-1 values
    where computed)."""
    n = len(branch.values)
    xe = np.full(n, np.nan)
    me = np.full(n, np.nan)  # the error of the reported (level-1) multipliers
    me0 = np.full(n, np.nan)  # the error of the level-0 multipliers
    sampled = np.zeros(n, dtype=bool)
    has_mu = branch.multipliers is not None
    mus = np.array(branch.multipliers, copy=True) if has_mu else None
    for i in sample_indices(n, every, corners):
        try:
            prob, u, p = _branch_problem(model, branch, i, integrator)
            xm0, mu0 = float(branch.xmax[i]), (mus[i] if has_mu else None)
            ev = prob.evaluate(u, p, jac=True, jac_p=False)
            if np.max(np.abs(ev.R / prob.scale_u)) > 1e-9:  # not the stored discretization
                u, ev, _, _ = prob.solve(u, p, max_iter=6)
                xm0 = float(ev.xmax)
                mu0 = prob.multipliers(ev.Ms) if (has_mu and ev.Ms) else None
            n_0 = int(ev.n_impacts)
            xm1, mu1, u1, J, n_1 = refined_point(prob, u, p, mu0, jac=ev.Ju, with_impacts=True)
        except (ConvergenceError, ValueError, nlbeam.IntegrationError):
            continue
        xe[i] = SAFETY * abs(xm0 - xm1)
        sampled[i] = True
        if not (has_mu and mu0 is not None and mu1 is not None):
            continue
        d = _change(mu1, mu0)
        me0[i] = SAFETY * d
        err = d  # level 1: err1 = d / (2^q - 1) <= d for order q >= 1
        mu_rep = mu1
        falling = True  # every change from level 1 on fell at least 4-fold
        # an impact more or less per period between two levels: the finer level follows
        # another orbit class (chattering; paper 9.664 Hz, order 2: 12 impacts at levels 0-1,
        # 10 from level 2 on, which converge to 1.13445 while a solve at dt / 16 from the
        # diagram's orbit finds 0.8493): the error is at least the change across it
        jump = d if n_0 != n_1 else 0.0
        for k in range(2, levels + 1):
            if err <= target:
                break
            try:
                _, mu_k, u_k, J, n_k = refined_point(prob, u1, p, mu1, level=k, jac=J,
                                                     with_impacts=True)
            except (ConvergenceError, ValueError, nlbeam.IntegrationError):
                break
            mu_k = match_multipliers(mu1, mu_k)
            d_k = _change(mu_k, mu1)
            # the three levels of the ratio d / d_k have the same impacts per period
            mu_rep, err = carried_estimate(mu1, mu_k, d, d_k, n_0 == n_1 == n_k, falling)
            falling = falling and d_k <= d / 4
            jump = max(jump, d_k) if n_k != n_1 else jump
            d, mu1, u1, n_0, n_1 = d_k, mu_k, u_k, n_1, n_k
        err = max(err, jump)
        me[i] = max(err, 1e-10)
        mus[i] = mu_rep
    idx = np.nonzero(sampled)[0]
    if idx.size:
        left = np.searchsorted(idx, np.arange(n), side="right") - 1
        right = np.minimum(left + 1, idx.size - 1)
        left = np.maximum(left, 0)
        xe[~sampled] = np.fmax(xe[idx[left]], xe[idx[right]])[~sampled]
        me[~sampled] = np.fmax(me0[idx[left]], me0[idx[right]])[~sampled]
    if not has_mu:
        return xe, None, sampled, None, None
    return xe, me, sampled, mus, np.abs(mus[:, 0]) < 1.0


def _short(values, n=8):
    s = ", ".join(v if isinstance(v, str) else f"{v:.7g}" for v in values[:n])
    return s + (f" and {len(values) - n} more" if len(values) > n else "")


def point_levels(digits):
    """The finest level a branch point is carried to: 3 up to 6 digits, else 4 (a point goes
    on to the next level only while its stated multiplier error misses the target)."""
    return 3 if digits <= 6.0 else 4


def _branch_job(args):
    model, branch, integrator, every, corners, digits = args
    return branch_errors(model, branch, integrator, every=every, corners=corners,
                         target=multiplier_target(digits), levels=point_levels(digits))


def _levels_job(args):
    model, amplitude, bf, integrator, kw = args
    return bifurcation_levels(model, amplitude, bf, integrator, **kw)


class Early:
    """Error estimates started on a pool while the diagram is still being traced (continuation
    .diagram submits each branch and bifurcation as it is added); ``estimate_diagram`` takes a
    result only where its inputs are still those it was started with (``_job_key``; a grazing
    point's bracket may be widened by a later merge), so the numbers are those of the serial
    estimate."""

    def __init__(self, pool, model, integrator, parameter, accuracy, segments, every=1,
                 max_levels=4, grazing_levels=1):
        self.pool, self.model, self.integrator = pool, model, integrator
        self.parameter, self.segments, self.every = parameter, segments, every
        self.digits = target_digits(accuracy)
        self.max_levels, self.grazing_levels = max_levels, grazing_levels
        self.branches = {}  # branch index -> (branch, future)
        self.levels = {}  # _job_key -> future

    def branch(self, index, branch, bifurcations):
        """Start the estimate of a Branch just added, with its bifurcations (it is not changed
        afterwards; its corners are taken from ``bifurcations``, see corner_indices)."""
        corners = corner_indices(branch, bifurcations, index)
        self.branches[index] = (branch, corners, self.pool.submit(
            _branch_job, (self.model, branch, self.integrator, self.every, corners,
                          self.digits)))

    def bifurcation(self, amplitude, bf):
        """Start locating a Bifurcation just added at the finer levels (a copy: the diagram
        may still change its bracket, which changes its key)."""
        if bf.kind not in KINDS_LOCATED:
            return
        bf = copy.copy(bf)
        g = _at_grazing(bf)
        key = _job_key(bf, g)
        if key not in self.levels:
            self.levels[key] = self.pool.submit(_levels_job, (
                self.model, amplitude, bf, self.integrator,
                self._levels_kw(g)))

    def _levels_kw(self, grazing):
        return dict(parameter=self.parameter, digits=self.digits, segments=self.segments,
                    max_levels=self.grazing_levels if grazing else self.max_levels)

    def close(self):
        for _, _, fut in self.branches.values():
            fut.cancel()
        for fut in self.levels.values():
            fut.cancel()


def _at_grazing(bf):
    return bf.kind == "grazing" or not getattr(bf, "smooth", True)


def _job_key(bf, grazing):
    """What bifurcation_levels computes from: bifurcations with equal keys get equal levels."""
    def raw(a):
        return None if a is None else np.asarray(a).tobytes()
    return ("grazing" if grazing else bf.kind, bf.kind if not grazing else "", bf.order,
            float(bf.value), float(bf.frequency), float(bf.tolerance), raw(bf.state0),
            raw(bf.disc0), bf.multipliers is None)


def estimate_diagram(frc, model, integrator, *, accuracy=None, every=1, segments=1,
                     max_levels=4, grazing_levels=1, pool=None, early=None):
    """Attach error estimates to a diagram computed with ``integrator``, in place: each Branch
    gets xmax_error, multipliers_error and error_sampled (``branch_errors``); each fold, period
    doubling and Neimark-Sacker point is located again at levels 1, 2, ... (at most
    ``max_levels``) until its stated error meets the target digits of ``accuracy``, grazing
    points (and bifurcations reported at one) at levels 0 and 1 only (``grazing_levels``): its
    ``value`` (and ``frequency`` for a frequency diagram) becomes the reported value of
    ``bifurcation_levels``, ``error`` its
    error estimate, ``levels`` the values per level; ``tolerance`` stays the width of the
    diagram's bracket. Returns a message for one warning ('' if all is met): sampled branch
    points whose multiplier error exceeds 10^-(digits - 1), bifurcations that could not be
    located at a finer step, folds / period doublings / Neimark-Sacker points whose error
    exceeds the target. pool: an nlbeam.pool.Pool running the branches and the bifurcations
    in parallel (the same numbers as in this process)."""
    digits = target_digits(accuracy)
    run = pool.map if pool is not None else (lambda f, items: [f(x) for x in items])
    mt = multiplier_target(digits)
    n_bad = n_tot = 0
    worst = None
    early_b = early.branches if early is not None else {}
    corners = [corner_indices(b, frc.bifurcations, bi) for bi, b in enumerate(frc.branches)]
    todo = [bi for bi, b in enumerate(frc.branches)
            if bi not in early_b or early_b[bi][0] is not b or early_b[bi][1] != corners[bi]]
    errs = dict(zip(todo, run(_branch_job, [(model, frc.branches[bi], integrator, every,
                                             corners[bi], digits) for bi in todo])))
    errs = [errs[bi] if bi in errs else early_b[bi][2].result()
            for bi in range(len(frc.branches))]
    for bi, (b, (xe, me, sm, mus, stable)) in enumerate(zip(frc.branches, errs)):
        b.xmax_error, b.multipliers_error, b.error_sampled = xe, me, sm
        if mus is not None:
            b.multipliers, b.stable = mus, stable
        if me is None or not sm.any():
            continue
        n_tot += int(sm.sum())
        n_bad += int(np.sum(me[sm] > mt))
        k = int(np.nanargmax(np.where(sm, me, np.nan)))
        if worst is None or me[k] > worst[0]:
            worst = (float(me[k]), float(b.values[k]), bi, b.order)
    failed, above = [], []
    located = [bf for bf in frc.bifurcations if bf.kind in KINDS_LOCATED]

    at_grazing = _at_grazing
    # a bifurcation at a grazing point is listed with the grazing point itself, and both are
    # located as grazing points from the same orbit: each distinct job is run once
    # (with ``early``: those started while the diagram was traced are taken where their
    # inputs are unchanged)
    started = early.levels if early is not None else {}
    jobs, index = [], {}
    for bf in located:
        key = _job_key(bf, at_grazing(bf))
        if key not in index and key not in started:
            index[key] = len(jobs)
            jobs.append((model, frc.amplitude, bf, integrator,
                         dict(parameter=frc.parameter, digits=digits, segments=segments,
                              max_levels=grazing_levels if at_grazing(bf) else max_levels)))
    done = run(_levels_job, jobs)

    def result(bf):
        key = _job_key(bf, at_grazing(bf))
        return done[index[key]] if key in index else started[key].result()
    levels = [result(bf) for bf in located]
    bracketed = []
    for bf, lv in zip(located, levels):
        bf.levels = lv.values
        bf.error = lv.error
        if not math.isfinite(lv.error):
            failed.append(bf)
            continue
        if lv.failed and len(lv.values) < 2:
            bracketed.append(bf)
        bf.value = lv.value
        if frc.parameter == "frequency":
            bf.frequency = lv.value
        if not at_grazing(bf) and lv.error > 10.0 ** -digits * abs(lv.value):
            above.append(bf)
    parts = []
    if n_bad:
        parts.append(f"multiplier errors above {mt:.0e} at {n_bad} of {n_tot} sampled branch "
                     f"points (largest {worst[0]:.1e} at {worst[1]:.7g} on branch "
                     f"{worst[2] + 1}, order {worst[3]})")
    for kinds, what in ((("fold", "period-doubling", "neimark-sacker"), "fold/PD/NS"),
                        (("grazing",), "grazing")):
        f_ = [b.value for b in failed
              if (b.kind if getattr(b, "smooth", True) else "grazing") in kinds]
        if f_:
            parts.append(f"{len(f_)} {what} point(s) could not be located again with a finer "
                         f"step (error NaN): at {_short(f_)}")
    if bracketed:
        parts.append(f"{len(bracketed)} grazing point(s) or bifurcation(s) at one could not be "
                     "located again by bisection at a fixed frequency (a fold at the corner, or "
                     "several changes of the number of impacts in the bracket, or at the finer "
                     "step only a change between other numbers of impacts nearby): their error "
                     "is the width of the diagram's bracket: at "
                     + _short([f"{b.value:.9g} +- {b.error:.1e}" for b in bracketed]))
    if above:
        parts.append(f"{len(above)} fold/PD/NS point(s) with errors above the target after "
                     f"{max_levels} step halvings: at "
                     + ", ".join(f"{b.value:.9g} +- {b.error:.1e}" for b in above[:8])
                     + (f" and {len(above) - 8} more" if len(above) > 8 else ""))
    return "; ".join(parts)


__all__ = ["orbit_error", "bifurcation_levels", "branch_errors", "estimate_diagram", "refined",
           "at_level", "combine", "target_digits", "multiplier_target", "OrbitError",
           "BifurcationLevels", "SAFETY", "ACCURACY"]
