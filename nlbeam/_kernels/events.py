"""Dense output (quintic Hermite), extrema within a step, and contact boundaries located as
roots of the step map."""
from .codes import ERR_EVENT
from .excite import excite, excite_yyd
from .field import kinematics, kinematics_inline
from .hook import njit
from .steps import rk_step_free


# --- dense output: quintic Hermite in x through (x, v, a) at both ends -------------------------
@njit(cache=True)
def hermite5(x0, v0, a0, x1, v1, a1, h, th):
    """(x, x') at t0 + th*h of the quintic through x, x', x'' at both ends."""
    t2 = th * th
    t3 = t2 * th
    t4 = t3 * th
    t5 = t4 * th
    H0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5
    H1 = th - 6.0 * t3 + 8.0 * t4 - 3.0 * t5
    H2 = 0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5
    H3 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5
    H4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5
    H5 = 0.5 * t3 - t4 + 0.5 * t5
    D0 = -30.0 * t2 + 60.0 * t3 - 30.0 * t4
    D1 = 1.0 - 18.0 * t2 + 32.0 * t3 - 15.0 * t4
    D2 = th - 4.5 * t2 + 6.0 * t3 - 2.5 * t4
    D3 = 30.0 * t2 - 60.0 * t3 + 30.0 * t4
    D4 = -12.0 * t2 + 28.0 * t3 - 15.0 * t4
    D5 = 1.5 * t2 - 4.0 * t3 + 2.5 * t4
    x = H0 * x0 + h * H1 * v0 + h * h * H2 * a0 + H3 * x1 + h * H4 * v1 + h * h * H5 * a1
    xd = (D0 * x0 + D3 * x1) / h + D1 * v0 + D4 * v1 + h * (D2 * a0 + D5 * a1)
    return x, xd


@njit(cache=True)
def step_extrema(s0, f0, s1, f1, h, N, xmax):
    """Update xmax[i] with max |x_i| over a step, refined on the quintic dense output."""
    for i in range(N):
        a = abs(s1[i])
        if a > xmax[i]:
            xmax[i] = a
        v0 = s0[N + i]
        v1 = s1[N + i]
        if v0 * v1 < 0.0:
            lo = 0.0
            hi = 1.0
            # bisection on the sign of x', from where the linear interpolant of v vanishes
            th = v0 / (v0 - v1)
            for _ in range(60):
                x, xd = hermite5(s0[i], v0, f0[N + i], s1[i], v1, f1[N + i], h, th)
                if (xd > 0.0) == (v0 > 0.0):
                    lo = th
                else:
                    hi = th
                if hi - lo < 1e-15:
                    break
                th = 0.5 * (lo + hi)
            x, xd = hermite5(s0[i], v0, f0[N + i], s1[i], v1, f1[N + i], h, th)
            if abs(x) > xmax[i]:
                xmax[i] = abs(x)


# --- event location on the step map ---------------------------------------------------------------
@njit(cache=True)
def delta_after(meth, t, tau, s, P, dvm, disc, e, sign, level, sysa, xc, xp, xtab, f0,
                s_out, P_out, KS, KP, ytmp, Ptmp, fel, err_w):
    """sign * delta_e after one step of length tau from (t, s); status in the second slot."""
    st = rk_step_free(meth, t, tau, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, P_out, KS,
                      KP, ytmp, Ptmp, fel, err_w)
    if st != 0:
        return 0.0, st
    y, yd, ydd, st = excite(t + tau, xc, xp, xtab)
    d, dd = kinematics(e, s_out, y, yd, sysa)
    return sign * (d - level), st


@njit(cache=True)
def locate(meth, t, lo, hi, phi_lo, phi_hi, s, P, dvm, disc, e, sign, level, sysa, xc, xp, xtab, f0,
           s_out, P_out, KS, KP, ytmp, Ptmp, fel, err_w):
    """Root of phi(tau) = sign*delta_e(step(s, tau)) in [lo, hi], phi_lo <= 0 < phi_hi, by the
    Illinois method. Returns (tau_hi, status): the bracket end on the far side (phi >= 0), at
    most a few ulps of t from the root."""
    side = 0
    if phi_lo >= 0.0:
        return lo, 0
    tol = 4e-16 * (abs(t) + hi)
    for _ in range(200):
        if hi - lo <= tol:
            return hi, 0
        tau = (lo * phi_hi - hi * phi_lo) / (phi_hi - phi_lo)
        if not (tau > lo and tau < hi):
            tau = 0.5 * (lo + hi)
        ph, st = delta_after(meth, t, tau, s, P, dvm, disc, e, sign, level, sysa, xc, xp, xtab, f0,
                             s_out, P_out, KS, KP, ytmp, Ptmp, fel, err_w)
        if st != 0:
            return hi, st
        if ph >= 0.0:
            hi = tau
            phi_hi = ph
            if side == 1:
                phi_lo *= 0.5
            side = 1
            if ph == 0.0:
                return hi, 0
        else:
            lo = tau
            phi_lo = ph
            if side == -1:
                phi_hi *= 0.5
            side = -1
    return hi, ERR_EVENT


@njit(cache=True)
def delta_extremum(e, sign, t, h, s, s_new, f0, f1, sysa, xc, xp, xtab):
    """(theta, delta) at the extremum of delta_e within a step, on the quintic dense output;
    sign = +1 for a maximum, -1 for a minimum."""
    N = s.shape[0] // 2
    ew = sysa.ew
    wx0 = 0.0
    wv0 = 0.0
    wa0 = 0.0
    wx1 = 0.0
    wv1 = 0.0
    wa1 = 0.0
    for j in range(N):
        wx0 += ew[e, j] * s[j]
        wv0 += ew[e, j] * s[N + j]
        wa0 += ew[e, j] * f0[N + j]
        wx1 += ew[e, j] * s_new[j]
        wv1 += ew[e, j] * s_new[N + j]
        wa1 += ew[e, j] * f1[N + j]
    lo_b = 0.0
    hi_b = 1.0
    for _ in range(50):
        th = 0.5 * (lo_b + hi_b)
        xw, xwd = hermite5(wx0, wv0, wa0, wx1, wv1, wa1, h, th)
        ym, ydm, yddm, st2 = excite(t + th * h, xc, xp, xtab)
        if sign * (xwd + sysa.ewy[e] * ydm) > 0.0:
            lo_b = th
        else:
            hi_b = th
    th = 0.5 * (lo_b + hi_b)
    xw, xwd = hermite5(wx0, wv0, wa0, wx1, wv1, wa1, h, th)
    ym, ydm, yddm, st2 = excite(t + th * h, xc, xp, xtab)
    return th, xw + sysa.ewy[e] * ym - sysa.egap[e]


@njit(cache=True, inline="always")
def _may_cross(e, t, h, s, s_new, disc, sysa, xc, xp, xtab):
    """The cheap part of ``_crossing``, inlined into the integrator's loop: False when that
    function would certainly report no boundary in the step (delta_e at the step end on the
    element's own side, and no extremum of delta_e towards the boundary inside the step).
    The same expressions as ``_crossing`` and ``kinematics``, so the same decision bit for bit;
    it saves the call (~25 arrays) on the steps where nothing happens, nearly all of them."""
    y0, yd0, st = excite_yyd(t, xc, xp, xtab)
    y1, yd1, st = excite_yyd(t + h, xc, xp, xtab)
    return _may_cross_at(e, y0, yd0, y1, yd1, s, s_new, disc, sysa)


@njit(cache=True, inline="always")
def _may_cross_at(e, y0, yd0, y1, yd1, s, s_new, disc, sysa):
    """``_may_cross`` with the excitation (y, y') at the step's start and end given (the same
    expressions): for callers that already evaluated it there (routine.py)."""
    sign = -1.0 if disc[e, 0] != 0.0 else 1.0
    ew = sysa.ew
    N = ew.shape[1]
    d1 = sysa.ewy[e] * y1 - sysa.egap[e]
    dd0 = sysa.ewy[e] * yd0
    dd1 = sysa.ewy[e] * yd1
    for j in range(N):
        d1 += ew[e, j] * s_new[j]
        dd0 += ew[e, j] * s[N + j]
        dd1 += ew[e, j] * s_new[N + j]
    return sign * d1 > 0.0 or (sign * dd0 > 0.0 and sign * dd1 < 0.0)


@njit(cache=True, inline="always")
def _no_boundary_at(e, t, h, y0, yd0, y1, yd1, s, s_new, f0, f1, disc, sysa, xc, xp, xtab):
    """True where ``_crossing(e, t, h, ...)`` certainly reports no boundary, decided by its
    own expressions (the same decision bit for bit), the excitation (y, y') at the step's ends
    given: delta_e at the end on the element's side, and where delta_e has an extremum
    towards the boundary inside the step, that extremum on the dense output
    (``delta_extremum``, the same call) below ``_crossing``'s threshold. For routine.py: a
    swing of delta towards the stop that stays far from it no longer leaves the lean loop."""
    if not _may_cross_at(e, y0, yd0, y1, yd1, s, s_new, disc, sysa):
        return True
    sign = -1.0 if disc[e, 0] != 0.0 else 1.0
    d0, dd0 = kinematics_inline(e, s, y0, yd0, sysa)
    d1, dd1 = kinematics_inline(e, s_new, y1, yd1, sysa)
    if sign * d1 > 0.0:
        return False
    # here _may_cross_at found sign * dd0 > 0 > sign * dd1: _crossing's extremum check
    th, dmh = delta_extremum(e, sign, t, h, s, s_new, f0, f1, sysa, xc, xp, xtab)
    return not sign * dmh > -1e-3 * max(abs(d0), abs(d1))


@njit(cache=True)
def _crossing(meth, t, h, s, s_new, f0, f1, P, dvm, disc, e, sysa, xc, xp, xtab,
              s_try, dummyP, KS, KP, ytmp, Ptmp, fel, err_w):
    """Does element e change contact status within the time step (t, s) -> (t+h, s_new)?
    Returns (tau of the boundary, status); tau < 0 when there is none."""
    sign = -1.0 if disc[e, 0] != 0.0 else 1.0
    y0, yd0, ydd0, st = excite(t, xc, xp, xtab)
    y1, yd1, ydd1, st = excite(t + h, xc, xp, xtab)
    d0, dd0 = kinematics(e, s, y0, yd0, sysa)
    d1, dd1 = kinematics(e, s_new, y1, yd1, sysa)
    phi0 = sign * d0
    phi1 = sign * d1
    hi = -1.0
    phihi = 0.0
    if phi1 > 0.0:
        hi = h
        phihi = phi1
    elif sign * dd0 > 0.0 and sign * dd1 < 0.0:
        # the boundary may be touched between the step ends: find the extremum of delta on the
        # quintic dense output, then check it on the step map
        th, dmh = delta_extremum(e, sign, t, h, s, s_new, f0, f1, sysa, xc, xp, xtab)
        dmh = sign * dmh
        if dmh > -1e-3 * max(abs(d0), abs(d1)):
            tm = th * h
            dm, st = delta_after(meth, t, tm, s, P, dvm, disc, e, sign, 0.0, sysa, xc, xp,
                                 xtab, f0, s_try, dummyP, KS, KP, ytmp, Ptmp, fel, err_w)
            if dm > 0.0:
                hi = tm
                phihi = dm
    if hi <= 0.0:
        return -1.0, 0
    lo = 0.0
    if phi0 >= 0.0:
        # the step starts on the boundary (just after an event, or at a record's start): a
        # switch at tau = 0 only if delta moves to the new side; otherwise look for the next
        # crossing beyond a first sub-step where delta is back on the old side
        if sign * dd0 > 0.0:
            return 0.0, 0
        found = False
        tl = 1e-6 * hi
        for _ in range(6):
            pl, st = delta_after(meth, t, tl, s, P, dvm, disc, e, sign, 0.0, sysa, xc, xp,
                                 xtab, f0, s_try, dummyP, KS, KP, ytmp, Ptmp, fel, err_w)
            if pl < 0.0:
                found = True
                break
            tl *= 10.0
            if tl >= hi:
                break
        if not found:
            return 0.0, 0   # tangential start onto the new side
        lo = tl
        phi0 = pl
    return locate(meth, t, lo, hi, phi0, phihi, s, P, dvm, disc, e, sign, 0.0, sysa, xc, xp, xtab,
                  f0, s_try, dummyP, KS, KP, ytmp, Ptmp, fel, err_w)
