"""The derivative of the map at contact events, where a step's length is the time of a
boundary (implicit function) and where an onset sets the contact's own step sizes: the
sensitivities of the landed state, of the onset velocity, of the contact steps, and of the
penetration where the graded exit phase starts (rows of SR and SE: ``sens_steps.py``)."""
from .codes import VMINUS_FLOOR
from .contact import contact_step_sens
from .excite import excite, excite_jerk
from .field import field_sens
from .hook import njit
from .sens_steps import SE_DTC, SE_DTN, SR_DSC, SR_T, SR_TN


@njit(cache=True)
def boundary_time_sens(e, t, Bv, P, SR, dlevel, lw, sysa, xc, xp, xtab):
    """A step that ended at time t on the boundary delta_e = level, its length tau a function
    of the state (the root of delta_e(step(tau)) = level): P (2N, m) and SR[SR_TN] hold the
    sensitivities at a fixed tau on entry, those of the landed step on return, by the implicit
    function: d tau = -(d delta_e - lw dlevel) / (d delta_e / d tau), Bv (2N,) the step's
    derivative in its length, dlevel (m,) the level's sensitivity (lw = 0: a fixed level)."""
    N = P.shape[0] // 2
    m = P.shape[1]
    ew = sysa.ew
    wy = sysa.ewy[e]
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    rate = wy * yd
    for j in range(N):
        rate += ew[e, j] * Bv[j]
    if rate == 0.0:
        return
    for c in range(m):
        num = wy * yd * SR[SR_TN, c] - lw * dlevel[c]
        for j in range(N):
            num += ew[e, j] * P[j, c]
        dtau = -num / rate
        for q in range(2 * N):
            P[q, c] += Bv[q] * dtau
        SR[SR_TN, c] += dtau


@njit(cache=True)
def onset_accel_sens(e, t, s, P, dvm, disc, Trow, sysa, xc, xp, xtab, ks, kP, fel, ft, out):
    """out (m,) = d a0 / d z of the penetration acceleration a0 = w_e . a + wy_e y'' at a
    contact onset (t, s) (the free-flight field, disc before the switch)."""
    st = field_sens(t, s, P, dvm, disc, Trow, sysa, xc, xp, xtab, ks, kP, fel, ft)
    N = s.shape[0] // 2
    ew = sysa.ew
    y3 = sysa.ewy[e] * excite_jerk(t, xc, xp, xtab)
    for c in range(P.shape[1]):
        acc = y3 * Trow[c]
        for j in range(N):
            acc += ew[e, j] * kP[N + j, c]
        out[c] = acc
    return st


@njit(cache=True)
def onset_sens(e, t, s, P, dvm, disc, dd, ydd, a0, capped, SR, SE, sysa, xc, xp, xtab, KS, KP,
               fel, ft, spc):
    """At a contact onset of element e landed at (t, s) with sensitivities P, SR[SR_T] (disc
    before the switch): the sensitivities of the onset velocity (dvm[e], d delta' of the landed
    state, 0 on the floor VMINUS_FLOOR) and of the contact steps (SE[SE_DTN, e], and
    SE[SE_DTC, e] unless dt caps that step) through the onset velocity dd and the penetration
    acceleration a0 (m/s^2)."""
    N = s.shape[0] // 2
    m = P.shape[1]
    ew = sysa.ew
    wy = sysa.ewy[e]
    for c in range(m):
        acc = 0.0
        if dd > VMINUS_FLOOR:
            acc = wy * ydd * SR[SR_T, c]
            for j in range(N):
                acc += ew[e, j] * P[N + j, c]
        dvm[e, c] = acc
    vm = dd if dd > VMINUS_FLOOR else VMINUS_FLOOR
    cs, dcs_dv, dcs_da = contact_step_sens(e, vm, a0, sysa, spc)
    if dcs_da != 0.0:
        onset_accel_sens(e, t, s, P, dvm, disc, SR[SR_T], sysa, xc, xp, xtab, KS[0], KP[0], fel,
                         ft, SR[SR_DSC])
    for c in range(m):
        g = dcs_dv * dvm[e, c]
        if dcs_da != 0.0:
            g += dcs_da * SR[SR_DSC, c]
        SE[SE_DTN, e, c] = g
        SE[SE_DTC, e, c] = 0.0 if capped else g


@njit(cache=True)
def extremum_sens(e, t, h, th, s, s_new, f0, f1, P, P_new, dvm, disc, T0, T1, sysa, xc, xp,
                  xtab, KS, KP, fel, ft, out):
    """out (m,) = d / d z of delta_e's extremum within a step (t, s) -> (t + h, s_new) on the
    quintic dense output (delta_extremum's value at its theta), the sensitivities P, T0 at the
    step's start and P_new, T1 at its end: at an extremum theta moves nothing to first order,
    so it is the derivative of the interpolant's data at that theta. KS, KP (2 stages) are
    work arrays; status."""
    N = s.shape[0] // 2
    m = P.shape[1]
    ew = sysa.ew
    wy = sysa.ewy[e]
    st = field_sens(t, s, P, dvm, disc, T0, sysa, xc, xp, xtab, KS[0], KP[0], fel, ft)
    if st != 0:
        return st
    st = field_sens(t + h, s_new, P_new, dvm, disc, T1, sysa, xc, xp, xtab, KS[1], KP[1], fel, ft)
    if st != 0:
        return st
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
    wv0 = 0.0
    wa0 = 0.0
    wv1 = 0.0
    wa1 = 0.0
    for j in range(N):
        wv0 += ew[e, j] * s[N + j]
        wa0 += ew[e, j] * f0[N + j]
        wv1 += ew[e, j] * s_new[N + j]
        wa1 += ew[e, j] * f1[N + j]
    ym, ydm, yddm, st = excite(t + th * h, xc, xp, xtab)
    for c in range(m):
        dh = T1[c] - T0[c]
        dx0 = 0.0
        dv0 = 0.0
        da0 = 0.0
        dx1 = 0.0
        dv1 = 0.0
        da1 = 0.0
        for j in range(N):
            dx0 += ew[e, j] * P[j, c]
            dv0 += ew[e, j] * P[N + j, c]
            da0 += ew[e, j] * KP[0, N + j, c]
            dx1 += ew[e, j] * P_new[j, c]
            dv1 += ew[e, j] * P_new[N + j, c]
            da1 += ew[e, j] * KP[1, N + j, c]
        out[c] = (H0 * dx0 + H1 * (h * dv0 + wv0 * dh) + H2 * (h * h * da0 + 2.0 * h * wa0 * dh)
                  + H3 * dx1 + H4 * (h * dv1 + wv1 * dh) + H5 * (h * h * da1 + 2.0 * h * wa1 * dh)
                  + wy * ydm * (T0[c] + th * dh))
    return 0


@njit(cache=True)
def dsw_sens(e, kappa, t, t_new, th, dm, d0, d1, yd0, yd1, s, s_new, f0, f1, P, P_new, dvm,
             disc, SR, sysa, xc, xp, xtab, KS, KP, fel, ft, out):
    """out (m,) = d / d z of kappa max(dm, d0, d1), the penetration where the graded exit phase
    starts: dm the extremum of delta_e on the step's dense output (at theta th), d0, d1 at its
    ends (rates of the excitation there yd0, yd1), with P, SR[SR_T] at the step's start and
    P_new, SR[SR_TN] at its end."""
    N = s.shape[0] // 2
    m = P.shape[1]
    if dm >= d0 and dm >= d1:
        extremum_sens(e, t, t_new - t, th, s, s_new, f0, f1, P, P_new, dvm, disc, SR[SR_T],
                      SR[SR_TN], sysa, xc, xp, xtab, KS, KP, fel, ft, out)
    else:
        ew = sysa.ew
        wy = sysa.ewy[e]
        for c in range(m):
            if d0 >= d1:
                acc = wy * yd0 * SR[SR_T, c]
                for j in range(N):
                    acc += ew[e, j] * P[j, c]
            else:
                acc = wy * yd1 * SR[SR_TN, c]
                for j in range(N):
                    acc += ew[e, j] * P_new[j, c]
            out[c] = acc
    for c in range(m):
        out[c] *= kappa
