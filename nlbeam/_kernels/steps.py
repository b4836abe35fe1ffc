"""One explicit Runge-Kutta step (RK2, RK4, DP5) of the state and, with the variational
equations, of its sensitivities: the tableau loops and the unrolled RK4/DP5 steps."""
import math

from .codes import (_A_DP5, _A_RK2, _A_RK4, _B_DP5, _B_RK2, _B_RK4, _BH_DP5, _C_DP5, _C_RK2,
                    _C_RK4, _D21, _D31, _D32, _D41, _D42, _D43, _D51, _D52, _D53, _D54, _D61,
                    _D62, _D63, _D64, _D65, _DB1, _DB3, _DB4, _DB5, _DB6, _DC2, _DC3, _DC4, _DC5,
                    _DC6, _DC7, _DE1, _DE3, _DE4, _DE5, _DE6, _DE7, _R3, _R6, _RA21, _RA32, _RA43,
                    _RC1, _RC2, _RC3, _RC4, DP5, ERR_NONFINITE, RK2, RK4)
from .excite import excite_yyd
from .field import _deriv_var_at, deriv, deriv_plain, deriv_var
from .hook import _HAS_USER, njit


@njit(cache=True)
def tableau(meth):
    if meth == RK2:
        return _A_RK2, _B_RK2, _B_RK2, _C_RK2
    elif meth == RK4:
        return _A_RK4, _B_RK4, _B_RK4, _C_RK4
    return _A_DP5, _B_DP5, _BH_DP5, _C_DP5


@njit(cache=True)
def _rk_step_plain(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, KS, KP, ytmp,
                   fel, err_w):
    """rk_step of RK4 or DP5 without variational equations, unrolled: the same operations in
    the same order as the tableau loops (bitwise the same result), without their loop and
    table overhead. KS[0] gets f0; for DP5, KS[6] = f(t + h, s_out) (first same as last)."""
    n = s.shape[0]
    for q in range(n):
        KS[0, q] = f0[q]
    if meth == RK4:
        for q in range(n):
            ytmp[q] = s[q] + h * _RA21 * KS[0, q]
        st = deriv_plain(t + _RC2 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[1], KP[1], fel)
        if st != 0:
            return st
        for q in range(n):
            ytmp[q] = s[q] + h * _RA32 * KS[1, q]
        st = deriv_plain(t + _RC3 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[2], KP[2], fel)
        if st != 0:
            return st
        for q in range(n):
            ytmp[q] = s[q] + h * _RA43 * KS[2, q]
        st = deriv_plain(t + _RC4 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[3], KP[3], fel)
        if st != 0:
            return st
        for q in range(n):
            acc = s[q] + h * _R6 * KS[0, q]
            acc += h * _R3 * KS[1, q]
            acc += h * _R3 * KS[2, q]
            acc += h * _R6 * KS[3, q]
            s_out[q] = acc
            if not math.isfinite(acc):
                return ERR_NONFINITE
        return 0
    # DP5
    for q in range(n):
        ytmp[q] = s[q] + h * _D21 * KS[0, q]
    st = deriv_plain(t + _DC2 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[1], KP[1], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _D31 * KS[0, q]
        ytmp[q] = acc + h * _D32 * KS[1, q]
    st = deriv_plain(t + _DC3 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[2], KP[2], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _D41 * KS[0, q]
        acc += h * _D42 * KS[1, q]
        ytmp[q] = acc + h * _D43 * KS[2, q]
    st = deriv_plain(t + _DC4 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[3], KP[3], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _D51 * KS[0, q]
        acc += h * _D52 * KS[1, q]
        acc += h * _D53 * KS[2, q]
        ytmp[q] = acc + h * _D54 * KS[3, q]
    st = deriv_plain(t + _DC5 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[4], KP[4], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _D61 * KS[0, q]
        acc += h * _D62 * KS[1, q]
        acc += h * _D63 * KS[2, q]
        acc += h * _D64 * KS[3, q]
        ytmp[q] = acc + h * _D65 * KS[4, q]
    st = deriv_plain(t + _DC6 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[5], KP[5], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _DB1 * KS[0, q]
        acc += h * _DB3 * KS[2, q]
        acc += h * _DB4 * KS[3, q]
        acc += h * _DB5 * KS[4, q]
        acc += h * _DB6 * KS[5, q]
        ytmp[q] = acc
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE
    st = deriv_plain(t + _DC7 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[6], KP[6], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = h * _DE1 * KS[0, q]
        acc += h * _DE3 * KS[2, q]
        acc += h * _DE4 * KS[3, q]
        acc += h * _DE5 * KS[4, q]
        acc += h * _DE6 * KS[5, q]
        err_w[q] = acc + h * _DE7 * KS[6, q]
    return 0


@njit(cache=True, inline="always")
def _stage_var(s, P, h, a, KSj, KPj, ytmp, Ptmp, want_var):
    """An RK4 stage's state and (with want_var) sensitivities: ytmp = s + h a KSj, Ptmp = P +
    h a KPj (the tableau loop's operations without its zero terms)."""
    n = s.shape[0]
    m = P.shape[1]
    for q in range(n):
        ytmp[q] = s[q] + h * a * KSj[q]
    if want_var:
        for q in range(n):
            for c in range(m):
                Ptmp[q, c] = P[q, c] + h * a * KPj[q, c]


@njit(cache=True)
def _rk_step_var(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_out, P_out, KS, KP, ytmp, Ptmp,
                 fel):
    """rk_step of RK4 with the variational equations, unrolled, with the right-hand side and
    its sensitivity inlined (``deriv_var``): the same operations in the same order as the
    tableau loops up to their zero terms, so the same (s_out, P_out) bit for bit (a zero may
    differ in sign). Stage 1 is evaluated, not taken from f0 (as in rk_step)."""
    n = s.shape[0]
    m = P.shape[1]
    st = deriv_var(t + _RC1 * h, s, P, dvm, disc, sysa, xc, xp, xtab, KS[0], KP[0], fel)
    if st != 0:
        return st
    _stage_var(s, P, h, _RA21, KS[0], KP[0], ytmp, Ptmp, True)
    if _HAS_USER:
        st = deriv_var(t + _RC2 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[1], KP[1], fel)
        if st != 0:
            return st
        _stage_var(s, P, h, _RA32, KS[1], KP[1], ytmp, Ptmp, True)
        st = deriv_var(t + _RC3 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[2], KP[2], fel)
        if st != 0:
            return st
    else:
        # stages 2 and 3 at the same time t + c2 h (c2 = c3, codes.check_unrolled): the
        # excitation once
        y, yd, st = excite_yyd(t + _RC2 * h, xc, xp, xtab)
        if st != 0:
            return st
        _deriv_var_at(y, yd, ytmp, Ptmp, dvm, disc, sysa, KS[1], KP[1], fel)
        _stage_var(s, P, h, _RA32, KS[1], KP[1], ytmp, Ptmp, True)
        _deriv_var_at(y, yd, ytmp, Ptmp, dvm, disc, sysa, KS[2], KP[2], fel)
    _stage_var(s, P, h, _RA43, KS[2], KP[2], ytmp, Ptmp, True)
    st = deriv_var(t + _RC4 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[3], KP[3], fel)
    if st != 0:
        return st
    for q in range(n):
        acc = s[q] + h * _R6 * KS[0, q]
        acc += h * _R3 * KS[1, q]
        acc += h * _R3 * KS[2, q]
        acc += h * _R6 * KS[3, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE
    for q in range(n):
        for c in range(m):
            acc = P[q, c] + h * _R6 * KP[0, q, c]
            acc += h * _R3 * KP[1, q, c]
            acc += h * _R3 * KP[2, q, c]
            acc += h * _R6 * KP[3, q, c]
            P_out[q, c] = acc
    return 0


@njit(cache=True)
def rk_step(meth, t, h, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0,
            s_out, P_out, KS, KP, ytmp, Ptmp, fel, err_w):
    """Advance (s, P) by h. f0 is f(t, s) (stage 0, reused when not want_var).
    For DP5 err_w gets the embedded error vector. Returns status."""
    if not want_var and meth != RK2:
        return _rk_step_plain(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, KS, KP,
                              ytmp, fel, err_w)
    if not _HAS_USER and meth == RK4:
        # (with a custom force, the module's copy keeps the loops below: _HAS_USER is a
        # compile-time constant, the branch is pruned, and the unrolled steps, which would
        # only call deriv, are not compiled: about 15 s less to compile, uncached)
        return _rk_step_var(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_out, P_out, KS, KP, ytmp,
                            Ptmp, fel)
    return _rk_step_tableau(meth, t, h, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0, s_out,
                            P_out, KS, KP, ytmp, Ptmp, fel, err_w)


@njit(cache=True)
def rk_step_free(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, P_out, KS, KP,
                 ytmp, Ptmp, fel, err_w):
    """``rk_step`` without the variational equations (want_var False; P and dvm are not read):
    the same calls, so the same doubles. A kernel that calls only this compiles none of the
    variational steps (numba types both sides of rk_step's branch on want_var: ~1/3 of the
    plain loop's first compile went to steps it never takes)."""
    if meth != RK2:
        return _rk_step_plain(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, KS, KP,
                              ytmp, fel, err_w)
    return _rk_step_tableau(meth, t, h, s, P, dvm, disc, False, sysa, xc, xp, xtab, f0, s_out,
                            P_out, KS, KP, ytmp, Ptmp, fel, err_w)


@njit(cache=True)
def rk_step_with_var(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_out, P_out, KS, KP,
                     ytmp, Ptmp, fel, err_w):
    """``rk_step`` with the variational equations (want_var True): the same calls, so the same
    doubles, without the plain steps' code to compile."""
    if not _HAS_USER and meth == RK4:
        return _rk_step_var(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_out, P_out, KS, KP, ytmp,
                            Ptmp, fel)
    return _rk_step_tableau(meth, t, h, s, P, dvm, disc, True, sysa, xc, xp, xtab, f0, s_out,
                            P_out, KS, KP, ytmp, Ptmp, fel, err_w)


@njit(cache=True)
def _rk_step_tableau(meth, t, h, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0, s_out, P_out,
                     KS, KP, ytmp, Ptmp, fel, err_w):
    """``rk_step`` by the tableau loops (RK2; DP5 with the variational equations; every method
    with a custom force). Returns status."""
    A, B, BH, Cc = tableau(meth)
    ns = B.shape[0]
    n = s.shape[0]
    m = P.shape[1]
    for i in range(ns):
        if i == 0 and not want_var:
            for q in range(n):
                KS[0, q] = f0[q]
            continue
        for q in range(n):
            acc = s[q]
            for j in range(i):
                acc += h * A[i, j] * KS[j, q]
            ytmp[q] = acc
        if want_var:
            for q in range(n):
                for c in range(m):
                    acc = P[q, c]
                    for j in range(i):
                        acc += h * A[i, j] * KP[j, q, c]
                    Ptmp[q, c] = acc
        st = deriv(t + Cc[i] * h, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp, xtab, KS[i],
                   KP[i], fel)
        if st != 0:
            return st
    for q in range(n):
        acc = s[q]
        for j in range(ns):
            acc += h * B[j] * KS[j, q]
        s_out[q] = acc
        if not math.isfinite(acc):
            return ERR_NONFINITE
    if meth == DP5:
        for q in range(n):
            acc = 0.0
            for j in range(ns):
                acc += h * (B[j] - BH[j]) * KS[j, q]
            err_w[q] = acc
    if want_var:
        for q in range(n):
            for c in range(m):
                acc = P[q, c]
                for j in range(ns):
                    acc += h * B[j] * KP[j, q, c]
                P_out[q, c] = acc
    return 0
