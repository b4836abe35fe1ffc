"""Routine steps of the fixed-step RK4 loop without variational equations: a lean loop for
the steps where nothing happens (free flight onto the next grid point, or an ordinary time
step inside a contact), called by the plain integration loop and handing back at the first
step that needs more (a possible contact boundary, the graded exit phase or the maximum
penetration of a contact, any failure, the end of the record).

The same operations in the same order as the general loop (loop.py), so the same doubles bit
for bit; what it saves is repeated work, not arithmetic: the excitation (y, y') is evaluated
once per time (the general loop evaluates it 7 times a step: stages 2 and 3 share their time,
the step's end serves the next step's start, the contact rate and the event checks), and no
call passes the system's arrays (each such call explodes ~13 arrays into ~100 arguments).
A step it hands back is computed again by the general loop from the same state: a handed-back
step is not counted, so the counters are those of the general loop."""
import math

import numpy as np

from .codes import _RA21, _RA32, _RA43, _R3, _R6, _RC2, _RC4, ERR_NONFINITE
from .contact import _contact_rate_at
from .events import _no_boundary_at
from .excite import excite_yyd, excite_yyd_inline
from .field import _deriv_plain_at, has_event, kinematics_inline
from .hook import njit
from .samples import grid_samples, track_xmax_step


@njit(cache=True, inline="always")
def _rk4_shared(t, h, s, disc, sysa, xc, xp, xtab, f0, s_out, KS, ytmp, fel):
    """``_rk_step_plain``'s RK4 step (steps.py: the same operations in the same order), the
    excitation evaluated once for stages 2 and 3. Returns (status, y, y') with (y, y') at
    t + h (stage 4)."""
    n = s.shape[0]
    for q in range(n):
        KS[0, q] = f0[q]
    for q in range(n):
        ytmp[q] = s[q] + h * _RA21 * KS[0, q]
    y2, yd2, st = excite_yyd_inline(t + _RC2 * h, xc, xp, xtab)
    if st != 0:
        return st, 0.0, 0.0
    _deriv_plain_at(y2, yd2, ytmp, disc, sysa, KS[1], fel)
    for q in range(n):
        ytmp[q] = s[q] + h * _RA32 * KS[1, q]
    _deriv_plain_at(y2, yd2, ytmp, disc, sysa, KS[2], fel)
    for q in range(n):
        ytmp[q] = s[q] + h * _RA43 * KS[2, q]
    y4, yd4, st = excite_yyd_inline(t + _RC4 * h, xc, xp, xtab)
    if st != 0:
        return st, 0.0, 0.0
    _deriv_plain_at(y4, yd4, ytmp, disc, sysa, KS[3], fel)
    for q in range(n):
        acc = s[q] + h * _R6 * KS[0, q]
        acc += h * _R3 * KS[1, q]
        acc += h * _R3 * KS[2, q]
        acc += h * _R6 * KS[3, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE, 0.0, 0.0
    return 0, y4, yd4


@njit(cache=True)
def routine_steps(sysa, xc, xp, xtab, t0, t_end, dt, n_grid, max_steps, events_on,
                  track_xmax, graded, store_every, t, k_grid, n_steps, n_stored, n_rhs, s, f0,
                  s_new, f1, disc, dtc, d_sw, steps_in_contact, KS, ytmp, fel, xmax, out_t,
                  out_s, out_d, out_f):
    """Take RK4 steps from (t, s) with f0 = f(t, s) as the general loop would (phase 0,
    no variational equations, no custom force) while nothing but a step happens. Returns
    (t, k_grid, n_steps, n_stored, n_rhs, steps taken here): s, f0, xmax, steps_in_contact
    and the outputs updated as the general loop would have."""
    etype = sysa.etype
    N = s.shape[0] // 2
    n = 2 * N
    ne = etype.shape[0]
    done = 0
    y0, yd0, st = excite_yyd(t, xc, xp, xtab)
    if st != 0:
        return t, k_grid, n_steps, n_stored, n_rhs, done
    while t < t_end and n_steps < max_steps:
        n_in = 0
        pe = -1
        hc = np.inf
        for e in range(ne):
            if disc[e, 0] != 0.0:
                n_in += 1
                pe = e
                if dtc[e] < hc:
                    hc = dtc[e]
        # the step length: loop.py's "ordinary step in time"
        hit_grid = False
        if n_in > 0:
            lam = _contact_rate_at(y0, yd0, s, disc, sysa)
            if lam * hc > 0.5:
                hc = 0.5 / lam
            h = hc
            if h >= t_end - t:
                h = t_end - t
                hit_grid = True
        else:
            tg = t0 + (k_grid + 1) * dt if k_grid + 1 < n_grid else t_end
            h = tg - t
            hit_grid = True
        st, y4, yd4 = _rk4_shared(t, h, s, disc, sysa, xc, xp, xtab, f0, s_new, KS, ytmp, fel)
        if st != 0:
            break
        if hit_grid:
            t_new = t_end if n_in > 0 else tg
        else:
            t_new = t + h
        # f at the step's end (deriv_plain's operations), the excitation of stage 4 if the
        # same time
        if t_new == t + _RC4 * h:
            y1 = y4
            yd1 = yd4
        else:
            y1, yd1, st = excite_yyd(t_new, xc, xp, xtab)
            if st != 0:
                break
        _deriv_plain_at(y1, yd1, s_new, disc, sysa, f1, fel)
        hh = t_new - t
        if events_on:
            # loop.py's _may_cross and _crossing (e, t, t_new - t, ...) where they find no
            # boundary: the excitation at t + (t_new - t)
            if t + hh == t_new:
                ye = y1
                yde = yd1
            else:
                ye, yde, st = excite_yyd(t + hh, xc, xp, xtab)
            cross = False
            for e in range(ne):
                if has_event(etype[e]) and not _no_boundary_at(e, t, hh, y0, yd0, ye, yde, s,
                                                               s_new, f0, f1, disc, sysa, xc,
                                                               xp, xtab):
                    cross = True
                    break
            if cross:
                break
            if graded and n_in == 1 and d_sw[pe] > 0.0:
                # the graded exit phase would start in this step
                d0, dd0 = kinematics_inline(pe, s, y0, yd0, sysa)
                d1, dd1 = kinematics_inline(pe, s_new, y1, yd1, sysa)
                if d0 > d_sw[pe] and d1 <= d_sw[pe] and dd0 < 0.0:
                    break
        if graded and n_in == 1 and t_new > t:
            # the maximum penetration of this contact lies in this step (it sets d_sw)
            d0, dd0 = kinematics_inline(pe, s, y0, yd0, sysa)
            d1, dd1 = kinematics_inline(pe, s_new, y1, yd1, sysa)
            if dd0 > 0.0 and dd1 <= 0.0:
                break
        # ---- accept, as loop.py does
        n_rhs += 4
        n_steps += 1
        for e in range(ne):
            if disc[e, 0] != 0.0:
                steps_in_contact[e] += 1
        if track_xmax:
            track_xmax_step(s, f0, s_new, f1, hh, N, xmax)
        k_grid, n_stored = grid_samples(k_grid, n_grid, n_stored, store_every, t0, dt, t_end, t,
                                        t_new, hit_grid, s, f0, s_new, f1, ytmp, disc, xc, xp,
                                        xtab, sysa, out_t, out_s, out_d, out_f)
        t = t_new
        for q in range(n):
            s[q] = s_new[q]
            f0[q] = f1[q]
        y0 = y1
        yd0 = yd1
        done += 1
        if k_grid >= n_grid:
            t = t_end
    return t, k_grid, n_steps, n_stored, n_rhs, done
