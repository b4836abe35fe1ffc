"""Starting points of a diagram: periodic attractors found by integration on a frequency grid.

Each grid integration runs about ``efolds`` decay times of the linear structure and is judged
by a scale-free periodicity test on its states once per excitation period. An integration
that has not settled by then (a lightly damped attractor: multipliers near the unit circle, or
a long transient) is not discarded: shooting from its end state, for each requested order,
finds the orbit it is approaching, which is taken when it lies near the end state and is
stable or only lightly unstable (max |multiplier| <= 1 + ``light``).
"""
from __future__ import annotations

import math

import numpy as np

import nlbeam
from nlbeam.solver import ADAPTIVE_SAMPLES_PER_PERIOD, period_step

from ._newton import ConvergenceError
from .shooting import _problem_from_state, decay_rate, forcing, solve_problem


def state_scales(states, frequency):
    """Scales (2N,) of states (rows, [x, v]) of an orbit at ``frequency`` (Hz): the amplitude
    a = max sqrt(x^2 + (v / w)^2) over the rows and DOFs (w = 2 pi f) for displacements, a w for
    velocities; one amplitude for all DOFs, so that no component near zero (a velocity sampled
    at a turning point, a DOF at rest) sets the scale."""
    S = np.atleast_2d(states)
    N = S.shape[1] // 2
    w = 2 * np.pi * frequency
    a = float(np.sqrt(S[:, :N] ** 2 + (S[:, N:] / w) ** 2).max())
    a = max(a, 1e-300)
    return np.r_[np.full(N, a), np.full(N, a * w)]


def periodicity(strobe, order, frequency):
    """max |s_{k+order} - s_k| / scale over the states ``strobe`` sampled once per excitation
    period (scale: ``state_scales``): zero on an orbit of that order (or one dividing it)."""
    sc = state_scales(strobe, frequency)
    return float(np.max(np.abs(strobe[order:] - strobe[:-order]) / sc))


def shoot_from(model, amplitude, frequency, order, state, integrator, *, segments=1,
               tol=1e-10, max_iter=10, stability=True):
    """The periodic solution of this order found by shooting from ``state`` (at t = 0), or
    None when Newton does not converge (or the integration fails)."""
    try:
        prob, u0 = _problem_from_state(model, amplitude, frequency, order, state, segments,
                                       integrator, variational=stability)
        return solve_problem(prob, u0, frequency, tol=tol, max_iter=max_iter,
                             stability=stability)
    except (ConvergenceError, nlbeam.IntegrationError):
        return None


def brute_force(model, amplitude, freqs, orders, integrator, efolds=6.0, settle=1e-3, *,
                light=1e-3, near=0.2, segments=1, stability=True, report=None, pool=None):
    """Periodic attractors from integrations on a frequency grid, sweeping up and down (the state
    carried over). Returns a list of (frequency, order, state at t = 0).

    An integration whose states once per period repeat after n periods to ``settle`` (relative
    to the orbit's amplitude, ``periodicity``) gives an order-n candidate (the smallest such n
    of ``orders``). One that has not settled is handed to shooting from its end state, for each
    order whose periodicity is at most 2 near, in turn: an orbit within ``near`` (scaled,
    ``state_scales``) of the end state whose largest multiplier has modulus <= 1 + light (any,
    with stability=False) is taken, as an orbit of its minimal order (when that order is asked
    for). report: a list to which
    (frequency, why) is appended for each grid integration that gave nothing."""
    args = [(model, amplitude, sweep, orders, integrator, efolds, settle, light, near,
             segments, stability) for sweep in (freqs, freqs[::-1])]
    outs = pool.map(_sweep, args) if pool is not None else [_sweep(a) for a in args]
    found = []
    for f_, r_ in outs:
        found += f_
        if report is not None:
            report += r_
    return found


def _sweep(args):
    """(found, report) of one sweep of brute_force over its frequencies (the state carried
    over from one frequency to the next)."""
    (model, amplitude, sweep, orders, integrator, efolds, settle, light, near, segments,
     stability) = args
    found, report = [], []
    rate = decay_rate(model)
    nmax = max(orders)
    x = None
    for f in sweep:
        # one stored sample per period: every spp-th step (adaptive: output sample)
        spp = integrator.steps_per_period(model, f) or ADAPTIVE_SAMPLES_PER_PERIOD
        n_tr = int(min(4000, max(40, math.ceil(efolds / rate * f))))
        n_tot = n_tr + 4 * nmax
        tr = integrator.integrate(model, forcing(amplitude, f), n_tot / f,
                                  period_step(f, spp), x0=x, store_every=spp)
        S = np.hstack([tr.x, tr.v])[: n_tot + 1]
        x = tr.state_end
        tail = S[-(3 * nmax + 1):]
        r = {n: periodicity(tail, n, f) for n in sorted(orders)}
        settled = [n for n in sorted(orders) if r[n] < settle]
        if settled:
            found.append((float(f), settled[0], S[-1].copy()))
            continue
        # an orbit within `near` of the end state that attracts the trajectory keeps the
        # states after n periods within about twice that of each other
        tries = [n for n in sorted(orders) if r[n] <= 2 * near]
        seed, seen = _seed_by_shooting(model, amplitude, f, tries, S[-1], tail,
                                       integrator, light, near, segments, stability,
                                       orders)
        if seed is not None:
            found.append(seed)
        else:
            report.append((float(f), "not periodic (change over "
                           + ", ".join(f"{n}: {v:.1e}" for n, v in r.items())
                           + " periods), "
                           + (("near it only " + ", ".join(seen)) if seen else
                              "no periodic orbit near it")))
    return found, report


def _seed_by_shooting(model, amplitude, f, tries, s_end, tail, integrator, light, near,
                      segments, stability, orders):
    """((f, order, state at t = 0) of the orbit an unsettled integration approaches (shooting
    for each order in ``tries``), or None; what shooting found otherwise, as short
    strings)."""
    sc = state_scales(tail, f)
    seen = {}
    for n in tries:
        sol = shoot_from(model, amplitude, f, n, s_end, integrator, segments=segments,
                         stability=stability)
        if sol is None:
            continue
        m = int(sol.minimal_order)
        if np.max(np.abs(sol.state0 - s_end) / sc) > near:
            continue  # Newton went to another orbit
        mu = abs(sol.multipliers[0]) ** (m / n) if stability else None  # of the order-m map
        if m not in orders:
            seen.setdefault(m, f"an orbit of order {m}")
            continue
        if stability and mu > 1.0 + light:
            # not the attractor: an unstable orbit the trajectory wanders near
            seen.setdefault(m, f"an unstable orbit of order {m} (|mu| {mu:.3g})")
            continue
        return (float(f), m, np.asarray(sol.state0, dtype=float).copy()), []
    return None, list(seen.values())
