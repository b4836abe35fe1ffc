"""Accurate fold and period-doubling frequencies: the bifurcation as a regular root of an
extended shooting system, solved with a finer integrator, at several accuracy levels.

For a fold (multiplier +1) or a period doubling (multiplier -1) of a periodic orbit of order n
the unknowns are the shooting states u and the parameter p, and the equations

    R(u, p) = 0,        g(u, p) = det(M(u, p) -+ I) = 0,

with M the monodromy (the test function of the path follower). The system is regular at a
generic fold or period doubling, so Newton converges to the bifurcation itself (no bracket);
dg/du and dg/dp come from central differences of the monodromy. Run at two or more integrator
settings, the spread of the answers measures the integrator's error; ``refine`` reports both.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from nlbeam.summary import Summary

from nlbeam import _linalg as la
from ._newton import ConvergenceError
from .pathfollow import located_beside_grazing
from .shooting import Integrator, _problem_from_state

# graded RK4, free-flight step and contact step halved together: the located frequencies
# converge geometrically (observed error ratios 6.5-9 per halving on the paper model), so
# Richardson extrapolation applies. (The adaptive DP5 converges only ~4x per decade of rtol
# across the Hertz onsets, and was 7.5e-6 Hz off at rtol 1e-12 on the 15.94 Hz PD.)
LEVELS = tuple(Integrator(dt_scale=s, steps_per_contact=32 / s) for s in
               (1 / 4, 1 / 8, 1 / 16, 1 / 32))


@dataclass(repr=False)
class Refined(Summary):
    """A fold or period doubling located at several integrator settings.

    values (k,): the parameter value (Hz for frequency) at each of ``levels`` (Integrators,
    coarse to fine, each step half the previous); extrapolated (k-2,): Richardson extrapolants
    from each three consecutive levels, v + d / (r - 1) with d the last difference and r the
    observed ratio of differences; value: the last extrapolant (the finest value if k < 3);
    tolerance: |last two extrapolants| (k >= 4), else |finest - previous| (the integrator's
    error estimate), or the extended system's last Newton step in p if larger;
    digits: -log10(tolerance / |value|); ratios: observed ratios of successive differences;
    seconds (k,): wall time of each level."""

    kind: str
    order: int
    values: np.ndarray
    extrapolated: np.ndarray
    value: float
    tolerance: float
    digits: float
    ratios: np.ndarray
    seconds: np.ndarray
    levels: tuple
    state0: np.ndarray


def _test_function(kind, M):
    s = -1.0 if kind == "fold" else 1.0
    return la.det(M + s * np.eye(len(M)))


def locate_extended(model, amplitude, frequency, order, state0, kind, integrator, *,
                    segments=1, tol=1e-9, max_iter=20, max_dp=2e-4):
    """Solve the extended system for a fold / period doubling of the orbit of order ``order``
    through state0 (state at t = 0, or (state, contact state) when t = 0 lies inside a contact)
    near ``frequency`` (Hz) with ``integrator``. Returns (frequency, (state, contact state) at
    t = 0, solve error in frequency). Raises ConvergenceError."""
    if kind not in ("fold", "period-doubling"):
        raise ValueError(f"kind: must be 'fold' or 'period-doubling', got {kind!r}")
    state0, disc0 = state0 if isinstance(state0, tuple) else (state0, None)
    prob, u0 = _problem_from_state(model, amplitude, frequency, order, state0, segments,
                                   integrator, disc0=disc0)
    w = prob.scale_u
    wp = prob.scale_p
    n = prob.n

    def g_of(u, p):
        ev = prob.evaluate(u, p, jac=True, jac_p=False)
        return _test_function(kind, prob.monodromy(ev.Ms)), ev

    def fun(z):
        u, p = z[:-1] * w, z[-1] * wp
        ev = prob.evaluate(u, p, jac=True, jac_p=True)
        g = _test_function(kind, prob.monodromy(ev.Ms))
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = ev.Ju * w[None, :] / w[:, None]
        J[:n, n] = ev.Jp * wp / w
        h = 1e-6
        for i in range(n + 1):
            zp, zm = z.copy(), z.copy()
            zp[i] += h
            zm[i] -= h
            J[n, i] = (g_of(zp[:-1] * w, zp[-1] * wp)[0] - g_of(zm[:-1] * w, zm[-1] * wp)[0]) \
                / (2 * h)
        return np.r_[ev.R / w, g], J

    z = np.r_[u0 / w, frequency / wp]
    solve_error = np.inf
    what = f"{kind} (order {order}) near {frequency:.9g} Hz"
    res = np.inf
    for it in range(max_iter):
        try:
            G, J = fun(z)
        except ConvergenceError:
            break
        res = float(np.max(np.abs(G)))
        try:
            dz = la.solve(J, -G)
        except np.linalg.LinAlgError:
            break
        solve_error = abs(dz[-1]) * wp  # the Newton step still to go: the solve's error in p
        if res <= tol:
            break
        # damped: at most max_dp (relative) in the parameter and 0.2 in the scaled states
        c = min(1.0, max_dp / max(abs(dz[-1]), 1e-300), 0.2 / max(np.max(np.abs(dz[:-1])), 1e-300))
        z = z + c * dz
        if c == 1.0 and np.max(np.abs(dz)) < 1e-3 * tol:
            break
    else:
        pass
    if not res <= 100 * tol:
        raise ConvergenceError(f"{what}: no convergence after {max_iter} iterations (residual "
                               f"{res:.2e} > tol {tol:.1e}); try segments=4 or a start closer "
                               "to the bifurcation")
    u, p = z[:-1] * w, z[-1] * wp
    return float(p), prob.state_at_zero(u, p), float(solve_error)


def _next_level(integ):
    spc = integ.steps_per_contact
    return Integrator(method=integ.method, dt_scale=integ.dt_scale / 2,
                      steps_per_contact=None if spc is None else 2 * spc, rtol=integ.rtol,
                      atol=integ.atol)


def refine(model, bifurcation, amplitude=None, *, levels=LEVELS, segments=1, tol=1e-9,
           target_digits=8.0, max_levels=6):
    """Refine a fold or period doubling (a continuation.Bifurcation of a frequency diagram) at
    each integrator setting in ``levels`` (coarse to fine), each starting from the previous one;
    while the estimated digits are below ``target_digits``, halve the step again (up to
    ``max_levels`` levels in all; fixed-step levels only). If the first level does not converge
    from the diagram's point, it is approached through dt_scale 1/2 first. Returns a Refined."""
    from ._arguments import check_refine_one

    check_refine_one(model, bifurcation, levels, segments, tol, target_digits, max_levels)
    A = bifurcation_amplitude(bifurcation, amplitude)
    f, s0 = bifurcation.frequency, (bifurcation.state0, getattr(bifurcation, "disc0", None))
    vals, secs, errs = [], [], []
    levels = list(levels)

    def one(integ, f, s0):
        t0 = time.perf_counter()
        out = locate_extended(model, A, f, bifurcation.order, s0, bifurcation.kind, integ,
                              segments=segments, tol=tol)
        return out, time.perf_counter() - t0

    try:
        (f, s0, err), sec = one(levels[0], f, s0)
    except ConvergenceError:
        if levels[0].method == "adaptive":
            raise
        t0 = time.perf_counter()
        bridge = Integrator(dt_scale=2 * levels[0].dt_scale,
                            steps_per_contact=None if levels[0].steps_per_contact is None
                            else levels[0].steps_per_contact / 2)
        (f, s0, _), _ = one(bridge, f, s0)
        (f, s0, err), sec = one(levels[0], f, s0)
        sec += time.perf_counter() - t0
    vals.append(f)
    secs.append(sec)
    errs.append(err)
    k = 1
    while True:
        if k < len(levels):
            integ = levels[k]
        elif (k < max_levels and levels[-1].method != "adaptive"
              and _estimate(vals, errs)[2] < target_digits):
            integ = _next_level(levels[-1])
            levels.append(integ)
        else:
            break
        (f, s0, err), sec = one(integ, f, s0)
        vals.append(f)
        secs.append(sec)
        errs.append(err)
        k += 1
    value, tolv, digits, ext, ratios = _estimate(vals, errs)
    return Refined(bifurcation.kind, bifurcation.order, np.array(vals), ext, float(value),
                   float(tolv), float(digits), ratios, np.array(secs), tuple(levels), s0[0])


def _estimate(vals, errs):
    """(value, tolerance, digits, extrapolants, ratios) from the values at successive halvings."""
    vals = np.array(vals)
    d = np.diff(vals)
    ratios = d[:-1] / np.where(d[1:] != 0, d[1:], np.inf)
    ext = np.array([vals[i + 2] + d[i + 1] / (r - 1) if r > 1.5 else vals[i + 2]
                    for i, r in enumerate(ratios)])
    if len(ext) >= 2:
        value, tolv = ext[-1], abs(ext[-1] - ext[-2])
    else:
        value, tolv = vals[-1], (abs(d[-1]) if len(d) else np.inf)
    tolv = max(tolv, errs[-1], 1e-15 * abs(value))
    return value, tolv, -np.log10(tolv / abs(value)), ext, ratios


def refine_bifurcations(frc, model, *, kinds=("fold", "period-doubling"), orders=None,
                        levels=LEVELS, segments=1, tol=1e-9, target_digits=8.0, max_levels=6):
    """Refine the folds / period doublings of a frequency diagram in place: each listed
    Bifurcation gets ``refined`` (a Refined), its ``frequency`` and ``value`` become the
    extrapolated value and ``error`` its error estimate (Refined.tolerance; ``tolerance`` stays
    the diagram's bracket). Bifurcations whose extended system does not converge, and those at
    a grazing point (``Bifurcation.smooth`` False), keep their values and errors and get
    ``refined = None``, except one the tracer located on a smooth stretch beside a grazing
    point and reports at it ('at grazing: fold located ...'): its extended system is solved,
    and a regular root inside the grazing bracket is taken; ``refine_status`` says which
    ('refined' or 'failed: <reason>'; both saved with the diagram). Returns the list of
    (bifurcation, Refined or the error)."""
    from ._arguments import check_refine

    check_refine(frc, model, kinds, orders, levels, segments, tol, target_digits, max_levels)
    if frc.parameter != "frequency":
        raise ValueError("frc: refine_bifurcations needs a frequency diagram")
    out = []
    for bf in frc.bifurcations:
        if bf.kind not in kinds or (orders is not None and bf.order not in orders):
            continue
        beside = _beside_grazing(bf)
        if not getattr(bf, "smooth", True) and not beside:
            # a multiplier jumps across the unit circle at a grazing point: no regular root of
            # the extended system; the grazing bracket stays the tolerance
            out.append((bf, ConvergenceError(f"not refined: {bf.note}")))
            bf.refine_status = f"failed: at a grazing point ({bf.note})"
            continue
        r = None
        for segs in (segments, 4 * segments):  # multiple shooting as the fallback
            try:
                r = refine(model, bf, frc.amplitude, levels=levels, segments=segs, tol=tol,
                           target_digits=target_digits, max_levels=max_levels)
                break
            except ConvergenceError as exc:
                r = exc
        if beside and not isinstance(r, ConvergenceError) \
                and abs(r.value - bf.frequency) > bf.tolerance:
            r = ConvergenceError(f"the regular root found, {r.value:.9g}, lies outside the "
                                 f"grazing bracket {bf.frequency:.9g} +- {bf.tolerance:.1e}")
        if isinstance(r, ConvergenceError):
            out.append((bf, r))
            bf.refine_status = f"failed: {r}"
            continue
        bf.refined = r
        bf.refine_status = "refined"
        bf.frequency = bf.value = r.value
        bf.error = r.tolerance
        out.append((bf, r))
    return out


def _beside_grazing(bf):
    """A fold / period doubling the tracer located on a smooth stretch next to a grazing point
    and reports at it (pathfollow.at_grazing_points: 'at grazing: <kind> located d from the
    grazing point'): its regular root may exist, and the extended system decides."""
    return (not getattr(bf, "smooth", True)
            and located_beside_grazing(bf.kind, getattr(bf, "note", "")))


def bifurcation_amplitude(bif, amplitude):
    if amplitude is not None:
        return float(amplitude)
    A = getattr(bif, "amplitude", None)
    if A is None:
        raise ValueError("amplitude: give the excitation amplitude of the diagram (m or N)")
    return float(A)


__all__ = ["refine", "refine_bifurcations", "locate_extended", "Refined", "LEVELS"]
