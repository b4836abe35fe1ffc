"""Time scales of a contact: the step inside a contact (estimated duration / steps per contact)
and the largest rate of the contact laws (the explicit stability limit)."""
import math

from .codes import _T_C_HERTZ, PWL_STOP
from .excite import excite
from .field import element_force, element_rate_grad, kinematics, kinematics_inline
from .hook import njit


@njit(cache=True)
def contact_step(e, v0, a0, sysa, spc):
    """Time step inside a contact of element e that starts at penetration rate v0 (m/s) and
    free-flight penetration acceleration a0 (m/s^2): the estimated contact duration divided by
    spc. The duration is that of a free mass on the stop, or of a grazing touch, 2 v0 / |a0|,
    when a0 < 0 makes that shorter."""
    return contact_step_sens(e, v0, a0, sysa, spc)[0]


@njit(cache=True)
def grade_multiple(dtn, dt):
    """The graded phases at a contact's ends take grade_multiple * n_grade steps (in sigma, in
    u): the least power of 2, m, with 2 dtn <= m dt (dtn the contact step, dt the free-flight
    step, s), so that no graded step lasts longer than dt. A power of 2 of the ratio: constant
    while the contact step changes by less than a factor 2 (a Hertz contact's velocity by 32),
    so the map stays smooth in the state; halving dt doubles it, every graded step halves."""
    m = 1
    while 2.0 * dtn > m * dt and m < 1 << 20:
        m *= 2
    return m


@njit(cache=True)
def contact_step_sens(e, v0, a0, sysa, spc):
    """``contact_step`` and its derivatives in v0 and a0: (step, d step/d v0, d step/d a0)."""
    etype = sysa.etype
    ew = sysa.ew
    epar = sysa.epar
    mw = sysa.mw
    winv = 0.0
    for j in range(ew.shape[1]):
        winv += ew[e, j] * mw[e, j]
    meff = 1.0 / winv
    K = epar[e, 0]
    dtc_dv = 0.0
    dtc_da = 0.0
    if etype[e] == PWL_STOP:
        tc = math.pi * math.sqrt(meff / K)
    else:
        v = max(v0, 1e-12)
        dmax = (1.25 * meff * v * v / K) ** 0.4
        tc = _T_C_HERTZ * dmax / v
        if v0 > 1e-12:
            dtc_dv = -0.2 * tc / v   # tc ~ v^-0.2
    if a0 < 0.0:
        tg = 2.0 * max(v0, 1e-12) / (-a0)
        if tg < tc:
            tc = tg
            dtc_dv = 2.0 / (-a0) if v0 > 1e-12 else 0.0
            dtc_da = tg / (-a0)
    return tc / spc, dtc_dv / spc, dtc_da / spc


@njit(cache=True)
def contact_rate(t, s, disc, sysa, xc, xp, xtab):
    """Largest rate (1/s) of the contact laws at (t, s): sqrt(stiffness / m_eff) and
    damping / m_eff of every element in contact; explicit steps need rate * h < 0.5."""
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    return _contact_rate_at(y, yd, s, disc, sysa)


@njit(cache=True, inline="always")
def _contact_rate_at(y, yd, s, disc, sysa):
    """``contact_rate`` with the excitation (y, y') at t given (the same expressions; y and
    y' are the doubles ``excite`` returns for every excitation code): for routine.py."""
    etype = sysa.etype
    N = s.shape[0] // 2
    lam = 0.0
    for e in range(etype.shape[0]):
        if disc[e, 0] != 0.0:
            d, dd = kinematics_inline(e, s, y, yd, sysa)
            f, dfd, dfdd, dfdv = element_force(etype[e], sysa.epar[e], d, dd, disc[e, 1],
                                               disc[e, 0])
            winv = 0.0
            for j in range(N):
                winv += sysa.ew[e, j] * sysa.mw[e, j]
            lam = max(lam, math.sqrt(max(dfd, 0.0) * winv), abs(dfdd) * winv)
    return lam


@njit(cache=True)
def contact_rate_sens(t, s, P, dvm, disc, Trow, sysa, xc, xp, xtab, out):
    """contact_rate at (t, s) and its sensitivity out (m,) (the element and term that set it;
    dt through the excitation with Trow)."""
    etype = sysa.etype
    ew = sysa.ew
    N = s.shape[0] // 2
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    lam = 0.0
    best = -1
    damp = False
    for e in range(etype.shape[0]):
        if disc[e, 0] != 0.0:
            d, dd = kinematics(e, s, y, yd, sysa)
            f, dfd, dfdd, dfdv = element_force(etype[e], sysa.epar[e], d, dd, disc[e, 1],
                                               disc[e, 0])
            winv = 0.0
            for j in range(N):
                winv += ew[e, j] * sysa.mw[e, j]
            la = math.sqrt(max(dfd, 0.0) * winv)
            lb = abs(dfdd) * winv
            if la > lam:
                lam = la
                best = e
                damp = False
            if lb > lam:
                lam = lb
                best = e
                damp = True
    for c in range(P.shape[1]):
        out[c] = 0.0
    if best < 0 or lam == 0.0:
        return lam
    e = best
    d, dd = kinematics(e, s, y, yd, sysa)
    f, dfd, dfdd, dfdv = element_force(etype[e], sysa.epar[e], d, dd, disc[e, 1], disc[e, 0])
    g = element_rate_grad(etype[e], sysa.epar[e], d, dd, disc[e, 1])
    winv = 0.0
    for j in range(N):
        winv += ew[e, j] * sysa.mw[e, j]
    wy = sysa.ewy[e]
    for c in range(P.shape[1]):
        dx = wy * yd * Trow[c]
        dv = wy * ydd * Trow[c]
        for j in range(N):
            dx += ew[e, j] * P[j, c]
            dv += ew[e, j] * P[N + j, c]
        if damp:
            r = g[3] * dx + g[4] * dv + g[5] * dvm[e, c]
            out[c] = winv * r if dfdd > 0.0 else -winv * r
        else:
            r = g[0] * dx + g[1] * dv + g[2] * dvm[e, c]
            out[c] = 0.5 * winv * r / lam
    return lam
