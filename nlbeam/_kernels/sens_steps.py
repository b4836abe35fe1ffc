"""Runge-Kutta steps whose start time and length depend on the state, with the derivative of
the step map as computed: besides P = d s / d z (z: the flow's initial state and onset
velocities, m columns), the derivatives of the step's time, length and graded variables.

A fixed-step flow is a chain of steps whose lengths (the contact step from the impact velocity,
the graded phases' steps, a step cut at a located boundary) and start times (everything after a
contact event) depend on the state; the loop (``loop.py``) carries those derivatives as rows of
length m in the work array SR, named below, and differentiates the step map in them
(``rk_step_sens``). Per element, rows of SE hold the derivatives of the contact's own step
sizes (``events_sens.py`` sets them at an onset).
"""
import math

import numpy as np

from .codes import (_R3, _R6, _RA21, _RA31, _RA32, _RA41, _RA42, _RA43, _RC1, _RC2, _RC3,
                    _RC4, DP5, ERR_EVENT, ERR_NONFINITE, RK4)
from .excite import excite
from .field import _deriv_var_at_t, deriv, field_dt, kinematics
from .hook import _HAS_USER, njit
from .steps import rk_step_with_var, tableau

SR_T = 0      # d t / d z of the current time t
SR_TN = 1     # d t / d z at the step's end (written by rk_step_sens)
SR_H = 2      # d h / d z of the step, in the step's own variable (t, sigma or u)
SR_U0 = 3     # d u0 / d z: the graded variable at the step's start
SR_TREF = 4   # d t_onset / d z (graded onset steps: t = t_onset + sigma^2)
SR_GH = 5     # d g_h / d z: the nominal step of a graded phase
SR_GEND = 6   # d sigma_end / d z: where the graded onset phase ends
SR_TS = 7     # scratch: d t / d z of a stage
SR_DSC = 8    # scratch: d (dt/du) / d z of a stage
SR_KT = 9     # rows SR_KT + i: d (dt/du) / d z of stage i (the graded exit steps' clock)
SR_ROWS = SR_KT + 7
SE_DTC = 0    # SE[SE_DTC, e]: d / d z of the time step inside element e's contact
SE_DTN = 1    # d / d z of its nominal contact step (contact duration / steps per contact)
SE_DSW = 2    # d / d z of the penetration where its graded exit phase starts
SE_ROWS = 3


@njit(cache=True, inline="always")
def _stage_sens(s, P, h, a, KSj, KPj, Hrow, ytmp, Ptmp):
    """An RK4 stage's state and sensitivities where the step h depends on the state:
    ytmp = s + h a KSj (as _stage_var), Ptmp = P + h a KPj + a KSj (x) Hrow."""
    n = s.shape[0]
    m = P.shape[1]
    for q in range(n):
        ytmp[q] = s[q] + h * a * KSj[q]
    ha = h * a
    for q in range(n):
        ak = a * KSj[q]
        for c in range(m):
            Ptmp[q, c] = P[q, c] + ha * KPj[q, c] + ak * Hrow[c]


@njit(cache=True, inline="always")
def _rk4_end_sens(s, P, h, KS, KP, Hrow, s_out, P_out):
    """The end of an RK4 step with sensitivities: s_out as rk_step (bit for bit), P_out = P +
    h sum b KP + (sum b KS) (x) Hrow; status."""
    n = s.shape[0]
    m = P.shape[1]
    for q in range(n):
        acc = s[q] + h * _R6 * KS[0, q]
        acc += h * _R3 * KS[1, q]
        acc += h * _R3 * KS[2, q]
        acc += h * _R6 * KS[3, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE
    for q in range(n):
        kb = _R6 * KS[0, q] + _R3 * KS[1, q] + _R3 * KS[2, q] + _R6 * KS[3, q]
        for c in range(m):
            acc = P[q, c] + h * _R6 * KP[0, q, c]
            acc += h * _R3 * KP[1, q, c]
            acc += h * _R3 * KP[2, q, c]
            acc += h * _R6 * KP[3, q, c]
            P_out[q, c] = acc + kb * Hrow[c]
    return 0


@njit(cache=True)
def _rk4_time_sens(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_out, P_out, KS, KP, ytmp, Ptmp,
                   fel, SR, row_t):
    """rk_step_sens of RK4 in time (mode 0), unrolled with the field inlined: the state as
    rk_step's bit for bit, the sensitivities those of the tableau loops to round-off."""
    m = P.shape[1]
    T = SR[row_t]
    H = SR[SR_H]
    TS = SR[SR_TS]
    for c in range(m):
        TS[c] = T[c]
    y, yd, ydd, st = excite(t + _RC1 * h, xc, xp, xtab)
    if st != 0:
        return st, t
    _deriv_var_at_t(y, yd, ydd, TS, True, s, P, dvm, disc, sysa, KS[0], KP[0], fel)
    # stages 2 and 3 at t + h/2: the excitation once
    _stage_sens(s, P, h, _RA21, KS[0], KP[0], H, ytmp, Ptmp)
    for c in range(m):
        TS[c] = T[c] + _RC2 * H[c]
    y, yd, ydd, st = excite(t + _RC2 * h, xc, xp, xtab)
    if st != 0:
        return st, t
    _deriv_var_at_t(y, yd, ydd, TS, True, ytmp, Ptmp, dvm, disc, sysa, KS[1], KP[1], fel)
    _stage_sens(s, P, h, _RA32, KS[1], KP[1], H, ytmp, Ptmp)
    _deriv_var_at_t(y, yd, ydd, TS, True, ytmp, Ptmp, dvm, disc, sysa, KS[2], KP[2], fel)
    _stage_sens(s, P, h, _RA43, KS[2], KP[2], H, ytmp, Ptmp)
    for c in range(m):
        TS[c] = T[c] + _RC4 * H[c]
    y, yd, ydd, st = excite(t + _RC4 * h, xc, xp, xtab)
    if st != 0:
        return st, t
    _deriv_var_at_t(y, yd, ydd, TS, True, ytmp, Ptmp, dvm, disc, sysa, KS[3], KP[3], fel)
    st = _rk4_end_sens(s, P, h, KS, KP, H, s_out, P_out)
    if st != 0:
        return st, t
    for c in range(m):
        SR[SR_TN, c] = T[c] + H[c]
    return 0, t + h


@njit(cache=True, inline="always")
def _graded_stage_sens(mode, ui, ci, ti, e, ys, Ps, dvm, disc, sysa, xc, xp, xtab, ks, kp, fel,
                       SR, i):
    """A stage of the graded RK4 step with sensitivities (stage time's row SR[SR_TS]): the
    field times the stage's scale dt/du (as ``_graded_stage``, bit for bit), the sensitivity
    sc dF + F (x) d sc, and d sc in row SR[SR_KT + i]; (status, scale)."""
    N = ys.shape[0] // 2
    m = Ps.shape[1]
    y, yd, ydd, st = excite(ti, xc, xp, xtab)
    if st != 0:
        return st, 0.0
    _deriv_var_at_t(y, yd, ydd, SR[SR_TS], True, ys, Ps, dvm, disc, sysa, ks, kp, fel)
    if mode == 1:
        sc = 2.0 * ui
        for c in range(m):
            SR[SR_KT + i, c] = 2.0 * (SR[SR_U0, c] + ci * SR[SR_H, c])
    else:
        d, dd = kinematics(e, ys, y, yd, sysa)
        if dd >= 0.0:
            return ERR_EVENT, 0.0
        sc = 2.0 * ui / dd
        ew = sysa.ew
        wy = sysa.ewy[e]
        for c in range(m):
            ddd = wy * ydd * SR[SR_TS, c]
            for j in range(N):
                ddd += ew[e, j] * Ps[N + j, c]
            SR[SR_KT + i, c] = (2.0 * (SR[SR_U0, c] + ci * SR[SR_H, c]) - sc * ddd) / dd
    for q in range(ks.shape[0]):
        for c in range(m):
            kp[q, c] = sc * kp[q, c] + ks[q] * SR[SR_KT + i, c]
        ks[q] *= sc
    return 0, sc


@njit(cache=True)
def _rk4_graded_sens(mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, sysa, xc, xp, xtab, s_out,
                     P_out, KS, KP, KT, ytmp, Ptmp, fel, SR, row_t):
    """rk_step_sens of RK4 in the graded variables (modes 1, 2), unrolled with the field
    inlined: the state and time as _rk_step_graded4's bit for bit, the sensitivities those of
    the tableau loops to round-off."""
    m = P.shape[1]
    T = SR[row_t]
    H = SR[SR_H]
    U0 = SR[SR_U0]
    TR = SR[SR_TREF]
    TS = SR[SR_TS]
    # stage 1 at (u0, s, P)
    ui = u0 + _RC1 * hu
    if mode == 1:
        ti = t_ref + ui * ui
        for c in range(m):
            TS[c] = TR[c] + 2.0 * ui * U0[c]
    else:
        ti = tcur
        for c in range(m):
            TS[c] = T[c]
    st, sc = _graded_stage_sens(mode, ui, _RC1, ti, e, s, P, dvm, disc, sysa, xc, xp, xtab,
                                KS[0], KP[0], fel, SR, 0)
    if st != 0:
        return st, tcur
    KT[0] = sc
    # stage 2
    _stage_sens(s, P, hu, _RA21, KS[0], KP[0], H, ytmp, Ptmp)
    ui = u0 + _RC2 * hu
    if mode == 1:
        ti = t_ref + ui * ui
        for c in range(m):
            TS[c] = TR[c] + 2.0 * ui * (U0[c] + _RC2 * H[c])
    else:
        ti = tcur + hu * _RA21 * KT[0]
        for c in range(m):
            TS[c] = T[c] + _RA21 * KT[0] * H[c] + hu * _RA21 * SR[SR_KT, c]
    st, sc = _graded_stage_sens(mode, ui, _RC2, ti, e, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab,
                                KS[1], KP[1], fel, SR, 1)
    if st != 0:
        return st, tcur
    KT[1] = sc
    # stage 3
    _stage_sens(s, P, hu, _RA32, KS[1], KP[1], H, ytmp, Ptmp)
    ui = u0 + _RC3 * hu
    if mode == 1:
        ti = t_ref + ui * ui
        for c in range(m):
            TS[c] = TR[c] + 2.0 * ui * (U0[c] + _RC3 * H[c])
    else:
        ti = tcur + hu * _RA31 * KT[0]
        ti += hu * _RA32 * KT[1]
        for c in range(m):
            TS[c] = T[c] + _RA32 * KT[1] * H[c] + hu * _RA32 * SR[SR_KT + 1, c]
    st, sc = _graded_stage_sens(mode, ui, _RC3, ti, e, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab,
                                KS[2], KP[2], fel, SR, 2)
    if st != 0:
        return st, tcur
    KT[2] = sc
    # stage 4
    _stage_sens(s, P, hu, _RA43, KS[2], KP[2], H, ytmp, Ptmp)
    ui = u0 + _RC4 * hu
    if mode == 1:
        ti = t_ref + ui * ui
        for c in range(m):
            TS[c] = TR[c] + 2.0 * ui * (U0[c] + _RC4 * H[c])
    else:
        ti = tcur + hu * _RA41 * KT[0]
        ti += hu * _RA42 * KT[1]
        ti += hu * _RA43 * KT[2]
        for c in range(m):
            TS[c] = T[c] + _RA43 * KT[2] * H[c] + hu * _RA43 * SR[SR_KT + 2, c]
    st, sc = _graded_stage_sens(mode, ui, _RC4, ti, e, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab,
                                KS[3], KP[3], fel, SR, 3)
    if st != 0:
        return st, tcur
    KT[3] = sc
    st = _rk4_end_sens(s, P, hu, KS, KP, H, s_out, P_out)
    if st != 0:
        return st, tcur
    if mode == 1:
        ue = u0 + hu
        for c in range(m):
            SR[SR_TN, c] = TR[c] + 2.0 * ue * (U0[c] + H[c])
        return 0, t_ref + ue * ue
    tn = tcur + hu * _R6 * KT[0]
    tn += hu * _R3 * KT[1]
    tn += hu * _R3 * KT[2]
    tn += hu * _R6 * KT[3]
    kt = _R6 * KT[0] + _R3 * KT[1] + _R3 * KT[2] + _R6 * KT[3]
    for c in range(m):
        SR[SR_TN, c] = T[c] + kt * H[c] + hu * (_R6 * SR[SR_KT, c] + _R3 * SR[SR_KT + 1, c]
                                                + _R3 * SR[SR_KT + 2, c] + _R6 * SR[SR_KT + 3, c])
    return 0, tn


@njit(cache=True)
def rk_step_sens(meth, mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, sysa, xc, xp, xtab,
                 s_out, P_out, KS, KP, KT, ytmp, Ptmp, fel, ft, err_w, SR, row_t):
    """One Runge-Kutta step with the variational equations and the sensitivities of the step's
    own parameters: the derivative of the step map as computed, where the start time, the step
    and the graded variables depend on the state.

    mode 0: a step hu in time from tcur; 1: in sigma = sqrt(t - t_ref) from u0 (graded onset);
    2: in u = sqrt(delta_e) from u0, t integrated alongside (graded exit), as rk_step_graded.
    Rows of SR read: row_t (d tcur), SR_H (d hu), SR_U0 (d u0; modes 1, 2), SR_TREF (d t_ref;
    mode 1); written: SR_TN (d t at the step's end; may be row_t). For DP5 err_w gets the
    embedded error. Returns (status, t at the step's end)."""
    if not _HAS_USER and meth == RK4:
        # RK4 unrolled, the field inlined (with a custom force these are pruned)
        if mode == 0:
            return _rk4_time_sens(tcur, hu, s, P, dvm, disc, sysa, xc, xp, xtab, s_out, P_out,
                                  KS, KP, ytmp, Ptmp, fel, SR, row_t)
        return _rk4_graded_sens(mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, sysa, xc, xp,
                                xtab, s_out, P_out, KS, KP, KT, ytmp, Ptmp, fel, SR, row_t)
    A, B, BH, Cc = tableau(meth)
    ns = B.shape[0]
    n = s.shape[0]
    N = n // 2
    m = P.shape[1]
    ew = sysa.ew
    for i in range(ns):
        # the stage's state and sensitivities: s + hu sum a K, d(.) + d hu sum a K
        for q in range(n):
            acc = s[q]
            ka = 0.0
            for j in range(i):
                acc += hu * A[i, j] * KS[j, q]
                ka += A[i, j] * KS[j, q]
            ytmp[q] = acc
            for c in range(m):
                acc = P[q, c]
                for j in range(i):
                    acc += hu * A[i, j] * KP[j, q, c]
                Ptmp[q, c] = acc + ka * SR[SR_H, c]
        # the stage's time and its sensitivity
        ui = u0 + Cc[i] * hu
        if mode == 0:
            ti = tcur + Cc[i] * hu
            for c in range(m):
                SR[SR_TS, c] = SR[row_t, c] + Cc[i] * SR[SR_H, c]
        elif mode == 1:
            ti = t_ref + ui * ui
            for c in range(m):
                SR[SR_TS, c] = SR[SR_TREF, c] + 2.0 * ui * (SR[SR_U0, c] + Cc[i] * SR[SR_H, c])
        else:
            ti = tcur
            kt = 0.0
            for j in range(i):
                ti += hu * A[i, j] * KT[j]
                kt += A[i, j] * KT[j]
            for c in range(m):
                acc = SR[row_t, c] + kt * SR[SR_H, c]
                for j in range(i):
                    acc += hu * A[i, j] * SR[SR_KT + j, c]
                SR[SR_TS, c] = acc
        # the field: d f = J d s + (df/d vminus) dvm + (df/dt) d t
        st = deriv(ti, ytmp, Ptmp, dvm, disc, True, sysa, xc, xp, xtab, KS[i], KP[i], fel)
        if st != 0:
            return st, tcur
        st = field_dt(ti, ytmp, disc, sysa, xc, xp, xtab, ft)
        for q in range(N, n):
            for c in range(m):
                KP[i, q, c] += ft[q] * SR[SR_TS, c]
        if mode == 0:
            KT[i] = 1.0
            for c in range(m):
                SR[SR_KT + i, c] = 0.0
            continue
        # graded: the scale dt/du of the stage and its sensitivity
        if mode == 1:
            sc = 2.0 * ui
            for c in range(m):
                SR[SR_DSC, c] = 2.0 * (SR[SR_U0, c] + Cc[i] * SR[SR_H, c])
        else:
            y, yd, ydd, st = excite(ti, xc, xp, xtab)
            d, dd = kinematics(e, ytmp, y, yd, sysa)
            if dd >= 0.0:
                return ERR_EVENT, tcur
            sc = 2.0 * ui / dd
            for c in range(m):
                ddd = sysa.ewy[e] * ydd * SR[SR_TS, c]
                for j in range(N):
                    ddd += ew[e, j] * Ptmp[N + j, c]
                SR[SR_DSC, c] = (2.0 * (SR[SR_U0, c] + Cc[i] * SR[SR_H, c]) - sc * ddd) / dd
        KT[i] = sc
        for q in range(n):
            for c in range(m):
                KP[i, q, c] = sc * KP[i, q, c] + KS[i, q] * SR[SR_DSC, c]
            KS[i, q] *= sc
        for c in range(m):
            SR[SR_KT + i, c] = SR[SR_DSC, c]
    # the step's end
    for q in range(n):
        acc = s[q]
        kb = 0.0
        for j in range(ns):
            acc += hu * B[j] * KS[j, q]
            kb += B[j] * KS[j, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE, tcur
        for c in range(m):
            acc = P[q, c]
            for j in range(ns):
                acc += hu * B[j] * KP[j, q, c]
            P_out[q, c] = acc + kb * SR[SR_H, c]
    if meth == DP5:
        for q in range(n):
            acc = 0.0
            for j in range(ns):
                acc += hu * (B[j] - BH[j]) * KS[j, q]
            err_w[q] = acc
    if mode == 0:
        for c in range(m):
            SR[SR_TN, c] = SR[row_t, c] + SR[SR_H, c]
        return 0, tcur + hu
    if mode == 1:
        ue = u0 + hu
        for c in range(m):
            SR[SR_TN, c] = SR[SR_TREF, c] + 2.0 * ue * (SR[SR_U0, c] + SR[SR_H, c])
        return 0, t_ref + ue * ue
    tn = tcur
    kt = 0.0
    for j in range(ns):
        tn += hu * B[j] * KT[j]
        kt += B[j] * KT[j]
    for c in range(m):
        acc = SR[row_t, c] + kt * SR[SR_H, c]
        for j in range(ns):
            acc += hu * B[j] * SR[SR_KT + j, c]
        SR[SR_TN, c] = acc
    return 0, tn


@njit(cache=True)
def var_time_step(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, P_out, KS, KP, KT,
                  ytmp, Ptmp, fel, err_w, ft, SR, row_t):
    """rk_step over h from (t, s) with the variational equations, by rk_step_sens where the
    start time or the length depends on the state (rows row_t, SR_H of SR not zero), and
    SR[SR_TN] = d t / d z at the step's end. Status. (Without them the loop calls
    ``rk_step_free``: the same step.)"""
    m = P.shape[1]
    fixed_ends = True
    for c in range(m):
        if SR[row_t, c] != 0.0 or SR[SR_H, c] != 0.0:
            fixed_ends = False
    if not fixed_ends:
        # (phase and element as int64, not literals: the loop's own copy of rk_step_sens)
        st, tn = rk_step_sens(meth, np.int64(0), 0.0, h, 0.0, np.int64(-1), s, t, P, dvm,
                              disc, sysa, xc, xp, xtab, s_out, P_out, KS, KP, KT, ytmp, Ptmp,
                              fel, ft, err_w, SR, row_t)
        return st
    for c in range(m):
        SR[SR_TN, c] = 0.0
    return rk_step_with_var(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, P_out,
                            KS, KP, ytmp, Ptmp, fel, err_w)


@njit(cache=True)
def step_length_derivative(meth, t, h, s, disc, sysa, xc, xp, xtab, s_tmp, KS, KT, ytmp, fel,
                           ft, err_w, W1, KP1, SR1, Bv):
    """Bv (2N,) = d step(t, h, s) / d h, the time step's derivative in its length h (one
    sensitivity column seeded with dh = 1). W1 (4, >= max(2N, ne), 1), KP1 (stages, 2N, 1) and
    SR1 (SR_ROWS, 1) are work arrays; status."""
    n = s.shape[0]
    ne = disc.shape[0]
    for r in range(SR1.shape[0]):
        SR1[r, 0] = 0.0
    SR1[SR_H, 0] = 1.0
    for q in range(W1.shape[1]):
        W1[0, q, 0] = 0.0
        W1[3, q, 0] = 0.0
    st, tn = rk_step_sens(meth, np.int64(0), 0.0, h, 0.0, np.int64(-1), s, t, W1[0, :n],
                          W1[3, :ne], disc, sysa, xc, xp, xtab, s_tmp, W1[1, :n], KS, KP1, KT,
                          ytmp, W1[2, :n], fel, ft, err_w, SR1, np.int64(SR_T))
    for q in range(n):
        Bv[q] = W1[1, q, 0]
    return st
