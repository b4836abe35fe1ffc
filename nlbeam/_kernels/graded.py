"""Graded Runge-Kutta steps at a contact boundary: steps in sigma = sqrt(t - t_onset) (onset)
and in u = sqrt(delta) (exit), which remove the delta^1.5 singularity of the contact force."""
import math

from .codes import (_R3, _R6, _RA21, _RA31, _RA32, _RA41, _RA42, _RA43, _RC1, _RC2, _RC3, _RC4,
                    ERR_EVENT, ERR_NONFINITE, RK4)
from .excite import excite, excite_yyd
from .field import deriv, deriv_plain, deriv_var, kinematics
from .hook import _HAS_USER, njit
from .steps import _stage_var, tableau


@njit(cache=True, inline="always")
def _graded_stage(mode, ui, ti, e, ys, Ps, dvm, disc, want_var, sysa, xc, xp, xtab, ks, kp,
                  fel):
    """A stage of the graded RK4 step at (ti, ys, Ps): the field (inlined) times the stage's
    scale dt/du; (status, scale)."""
    if want_var:
        st = deriv_var(ti, ys, Ps, dvm, disc, sysa, xc, xp, xtab, ks, kp, fel)
    else:
        st = deriv_plain(ti, ys, Ps, dvm, disc, sysa, xc, xp, xtab, ks, kp, fel)
    if st != 0:
        return st, 0.0
    if mode == 1:
        sc = 2.0 * ui
    else:
        y, yd, st = excite_yyd(ti, xc, xp, xtab)
        d, dd = kinematics(e, ys, y, yd, sysa)
        if dd >= 0.0:
            return ERR_EVENT, 0.0
        sc = 2.0 * ui / dd
    for q in range(ks.shape[0]):
        ks[q] *= sc
    if want_var:
        for q in range(kp.shape[0]):
            for c in range(kp.shape[1]):
                kp[q, c] *= sc
    return 0, sc


@njit(cache=True)
def _rk_step_graded4(mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, want_var, sysa, xc, xp,
                     xtab, s_out, P_out, KS, KP, KT, ytmp, Ptmp, fel):
    """rk_step_graded of RK4, unrolled, the field inlined (``deriv_plain`` / ``deriv_var``):
    the same operations in the same order as the tableau loops, without their zero terms in
    the stage states (the scalar stage times keep them), so the same result bit for bit (a
    zero may differ in sign)."""
    n = s.shape[0]
    m = P.shape[1]
    # stage 1 at (u0, s, P)
    ui = u0 + _RC1 * hu
    ti = t_ref + ui * ui if mode == 1 else tcur
    st, sc = _graded_stage(mode, ui, ti, e, s, P, dvm, disc, want_var, sysa, xc, xp, xtab,
                              KS[0], KP[0], fel)
    if st != 0:
        return st, tcur
    KT[0] = sc
    # stage 2
    _stage_var(s, P, hu, _RA21, KS[0], KP[0], ytmp, Ptmp, want_var)
    ui = u0 + _RC2 * hu
    ti = t_ref + ui * ui if mode == 1 else tcur + hu * _RA21 * KT[0]
    st, sc = _graded_stage(mode, ui, ti, e, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp,
                              xtab, KS[1], KP[1], fel)
    if st != 0:
        return st, tcur
    KT[1] = sc
    # stage 3
    _stage_var(s, P, hu, _RA32, KS[1], KP[1], ytmp, Ptmp, want_var)
    ui = u0 + _RC3 * hu
    if mode == 1:
        ti = t_ref + ui * ui
    else:
        ti = tcur + hu * _RA31 * KT[0]
        ti += hu * _RA32 * KT[1]
    st, sc = _graded_stage(mode, ui, ti, e, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp,
                              xtab, KS[2], KP[2], fel)
    if st != 0:
        return st, tcur
    KT[2] = sc
    # stage 4
    _stage_var(s, P, hu, _RA43, KS[2], KP[2], ytmp, Ptmp, want_var)
    ui = u0 + _RC4 * hu
    if mode == 1:
        ti = t_ref + ui * ui
    else:
        ti = tcur + hu * _RA41 * KT[0]
        ti += hu * _RA42 * KT[1]
        ti += hu * _RA43 * KT[2]
    st, sc = _graded_stage(mode, ui, ti, e, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp,
                              xtab, KS[3], KP[3], fel)
    if st != 0:
        return st, tcur
    KT[3] = sc
    for q in range(n):
        acc = s[q] + hu * _R6 * KS[0, q]
        acc += hu * _R3 * KS[1, q]
        acc += hu * _R3 * KS[2, q]
        acc += hu * _R6 * KS[3, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE, tcur
    if want_var:
        for q in range(n):
            for c in range(m):
                acc = P[q, c] + hu * _R6 * KP[0, q, c]
                acc += hu * _R3 * KP[1, q, c]
                acc += hu * _R3 * KP[2, q, c]
                acc += hu * _R6 * KP[3, q, c]
                P_out[q, c] = acc
    if mode == 1:
        ue = u0 + hu
        return 0, t_ref + ue * ue
    tn = tcur + hu * _R6 * KT[0]
    tn += hu * _R3 * KT[1]
    tn += hu * _R3 * KT[2]
    tn += hu * _R6 * KT[3]
    return 0, tn


@njit(cache=True)
def rk_step_graded(meth, mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, want_var, sysa, xc, xp,
                   xtab, s_out, P_out, KS, KP, KT, ytmp, Ptmp, fel):
    """One RK step in a graded variable that removes the delta^1.5 singularity of the contact
    force at a contact boundary of element e (then the solution is smooth in that variable):

    mode 1, onset: sigma = sqrt(t - t_ref), t_ref the onset time; d/dsigma = 2 sigma d/dt.
    mode 2, exit: u = sqrt(delta_e); t is integrated too, dt/du = 2u / delta_e'.
    Advances from u0 by hu (hu < 0 in mode 2). Returns (status, t at the end)."""
    if not _HAS_USER and meth == RK4:
        return _rk_step_graded4(mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, want_var, sysa, xc,
                                xp, xtab, s_out, P_out, KS, KP, KT, ytmp, Ptmp, fel)
    A, B, BH, Cc = tableau(meth)
    ns = B.shape[0]
    n = s.shape[0]
    m = P.shape[1]
    for i in range(ns):
        for q in range(n):
            acc = s[q]
            for j in range(i):
                acc += hu * A[i, j] * KS[j, q]
            ytmp[q] = acc
        if want_var:
            for q in range(n):
                for c in range(m):
                    acc = P[q, c]
                    for j in range(i):
                        acc += hu * A[i, j] * KP[j, q, c]
                    Ptmp[q, c] = acc
        ui = u0 + Cc[i] * hu
        if mode == 1:
            ti = t_ref + ui * ui
        else:
            ti = tcur
            for j in range(i):
                ti += hu * A[i, j] * KT[j]
        st = deriv(ti, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp, xtab, KS[i], KP[i], fel)
        if st != 0:
            return st, tcur
        if mode == 1:
            sc = 2.0 * ui
        else:
            y, yd, ydd, st = excite(ti, xc, xp, xtab)
            d, dd = kinematics(e, ytmp, y, yd, sysa)
            if dd >= 0.0:
                return ERR_EVENT, tcur
            sc = 2.0 * ui / dd
        KT[i] = sc
        for q in range(n):
            KS[i, q] *= sc
        if want_var:
            for q in range(n):
                for c in range(m):
                    KP[i, q, c] *= sc
    for q in range(n):
        acc = s[q]
        for j in range(ns):
            acc += hu * B[j] * KS[j, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE, tcur
    if want_var:
        for q in range(n):
            for c in range(m):
                acc = P[q, c]
                for j in range(ns):
                    acc += hu * B[j] * KP[j, q, c]
                P_out[q, c] = acc
    if mode == 1:
        ue = u0 + hu
        return 0, t_ref + ue * ue
    tn = tcur
    for j in range(ns):
        tn += hu * B[j] * KT[j]
    return 0, tn
