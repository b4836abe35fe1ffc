"""The force field: element forces and kinematics, the right-hand side f(t, s) and, with the
variational equations, its sensitivity J P; the custom-force hook."""
import math

from .codes import CUBIC, HERTZ, HUNT_CROSSLEY, INACTIVE, LANKARANI, PWL_STOP
from .excite import excite, excite_yyd
from .hook import _HAS_USER, _USER_FORCE, njit


@njit(cache=True)
def element_force(et, par, delta, ddelta, vminus, in_contact):
    """Force f (>= 0 pushes out when clamped) and df/d(delta), df/d(delta'), df/d(delta'_minus)."""
    if et == CUBIC:
        return par[0] * delta ** 3, 3.0 * par[0] * delta * delta, 0.0, 0.0
    if et == INACTIVE or in_contact == 0.0 or delta <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    K = par[0]
    if et == PWL_STOP:
        return K * delta, K, 0.0, 0.0
    d05 = math.sqrt(delta)
    d15 = delta * d05
    if et == HERTZ:
        f = K * d15
        dfd = 1.5 * K * d05
        dfdd = 0.0
        dfdv = 0.0
    elif et == LANKARANI:
        c = 0.75 * (1.0 - par[1] * par[1]) / vminus
        fac = 1.0 + c * ddelta
        f = K * d15 * fac
        dfd = 1.5 * K * d05 * fac
        dfdd = K * d15 * c
        dfdv = -K * d15 * c * ddelta / vminus
    else:  # HUNT_CROSSLEY
        mu = par[2]
        f = (K + mu * ddelta) * d15
        dfd = 1.5 * (K + mu * ddelta) * d05
        dfdd = mu * d15
        dfdv = 0.0
    if par[3] != 0.0 and f < 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return f, dfd, dfdd, dfdv


@njit(cache=True)
def has_event(et):
    return et == HERTZ or et == LANKARANI or et == HUNT_CROSSLEY or et == PWL_STOP


@njit(cache=True)
def kinematics(e, s, y, yd, sysa):
    """(delta, delta') of element e."""
    return kinematics_inline(e, s, y, yd, sysa)


@njit(cache=True, inline="always")
def kinematics_inline(e, s, y, yd, sysa):
    """``kinematics`` inlined where it is called in every step (a call with the system's
    arrays exploded into ~100 arguments costs more than the loop)."""
    ew = sysa.ew
    N = ew.shape[1]
    d = sysa.ewy[e] * y - sysa.egap[e]
    dd = sysa.ewy[e] * yd
    for j in range(N):
        d += ew[e, j] * s[j]
        dd += ew[e, j] * s[N + j]
    return d, dd


# --- right-hand side with optional variational equations ----------------------------------------
@njit(cache=True)
def deriv(t, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, ks, kP, fel):
    """ks = f(t, s); with want_var also kP = J P + (da/d vminus) dvm. fel (ne,) gets the
    element forces. Returns status."""
    MinvK = sysa.MinvK
    MinvC = sysa.MinvC
    mek = sysa.mek
    mec = sysa.mec
    etype = sysa.etype
    ew = sysa.ew
    epar = sysa.epar
    mw = sysa.mw
    N = MinvK.shape[0]
    ne = etype.shape[0]
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    if st != 0:
        return st
    for i in range(N):
        ks[i] = s[N + i]
        acc = mek[i] * y + mec[i] * yd
        for j in range(N):
            acc -= MinvK[i, j] * s[j] + MinvC[i, j] * s[N + j]
        ks[N + i] = acc
    if want_var:
        m = P.shape[1]
        for c in range(m):
            for i in range(N):
                kP[i, c] = P[N + i, c]
                acc = 0.0
                for j in range(N):
                    acc -= MinvK[i, j] * P[j, c] + MinvC[i, j] * P[N + j, c]
                kP[N + i, c] = acc
    for e in range(ne):
        d, dd = kinematics(e, s, y, yd, sysa)
        f, dfd, dfdd, dfdv = element_force(etype[e], epar[e], d, dd, disc[e, 1], disc[e, 0])
        fel[e] = f
        if f == 0.0 and dfd == 0.0 and dfdd == 0.0:
            continue
        for i in range(N):
            ks[N + i] -= mw[e, i] * f
        if want_var:
            m = P.shape[1]
            for c in range(m):
                dx = 0.0
                dv = 0.0
                for j in range(N):
                    dx += ew[e, j] * P[j, c]
                    dv += ew[e, j] * P[N + j, c]
                g = dfd * dx + dfdd * dv + dfdv * dvm[e, c]
                for i in range(N):
                    kP[N + i, c] -= mw[e, i] * g
    if _HAS_USER:
        _user_force_terms(t, s, P, want_var, y, yd, sysa, ks, kP)
    return 0


@njit(cache=True, inline="always")
def deriv_plain(t, s, P, dvm, disc, sysa, xc, xp, xtab, ks, kP, fel):
    """``deriv`` without variational equations, for the explicit steps: the same operations in
    the same order (bit for bit the same ks and fel), inlined (numba IR) into the unrolled
    Runge-Kutta step: a call with the ~15 arrays of the system exploded into ~100 scalar
    arguments cost about 30 ns, half of a 1-DOF right-hand side."""
    if _HAS_USER:
        return deriv(t, s, P, dvm, disc, False, sysa, xc, xp, xtab, ks, kP, fel)
    y, yd, st = excite_yyd(t, xc, xp, xtab)
    if st != 0:
        return st
    _deriv_plain_at(y, yd, s, disc, sysa, ks, fel)
    return 0


@njit(cache=True, inline="always")
def _deriv_plain_at(y, yd, s, disc, sysa, ks, fel):
    """The body of ``deriv_plain`` with the excitation (y, y') given (the same operations in
    the same order), so that callers that know it at a time evaluate it once (routine.py):
    no custom-force hook (callers check _HAS_USER)."""
    MinvK = sysa.MinvK
    MinvC = sysa.MinvC
    mek = sysa.mek
    mec = sysa.mec
    etype = sysa.etype
    epar = sysa.epar
    mw = sysa.mw
    N = MinvK.shape[0]
    ne = etype.shape[0]
    for i in range(N):
        ks[i] = s[N + i]
        acc = mek[i] * y + mec[i] * yd
        for j in range(N):
            acc -= MinvK[i, j] * s[j] + MinvC[i, j] * s[N + j]
        ks[N + i] = acc
    for e in range(ne):
        d, dd = kinematics_inline(e, s, y, yd, sysa)
        f, dfd, dfdd, dfdv = element_force(etype[e], epar[e], d, dd, disc[e, 1], disc[e, 0])
        fel[e] = f
        if f == 0.0 and dfd == 0.0 and dfdd == 0.0:
            continue
        for i in range(N):
            ks[N + i] -= mw[e, i] * f


@njit(cache=True, inline="always")
def deriv_var(t, s, P, dvm, disc, sysa, xc, xp, xtab, ks, kP, fel):
    """``deriv`` with the variational equations (want_var=True), for the unrolled RK4 steps:
    the same operations in the same order (bit for bit the same ks, kP and fel), inlined into
    the step as ``deriv_plain`` is, y'' skipped (``excite_yyd``)."""
    if _HAS_USER:
        return deriv(t, s, P, dvm, disc, True, sysa, xc, xp, xtab, ks, kP, fel)
    y, yd, st = excite_yyd(t, xc, xp, xtab)
    if st != 0:
        return st
    return _deriv_var_at(y, yd, s, P, dvm, disc, sysa, ks, kP, fel)


@njit(cache=True, inline="always")
def _deriv_var_at(y, yd, s, P, dvm, disc, sysa, ks, kP, fel):
    """The body of ``deriv_var`` with the excitation (y, y') given, so that two stages at the
    same time (RK4's 2nd and 3rd) evaluate it once (the same doubles: it is deterministic).
    Without the custom-force hook: callers check _HAS_USER."""
    return _deriv_var_at_t(y, yd, 0.0, fel, False, s, P, dvm, disc, sysa, ks, kP, fel)


@njit(cache=True, inline="always")
def _deriv_var_at_t(y, yd, ydd, Ts, timed, s, P, dvm, disc, sysa, ks, kP, fel):
    """``_deriv_var_at``, and with ``timed`` the sensitivity of the stage's time too: kP gets
    (df/dt) Ts (m,) added, df/dt through y(t), y'(t) (y'' = ydd). Without timed the same
    operations as before, bit for bit."""
    MinvK = sysa.MinvK
    MinvC = sysa.MinvC
    mek = sysa.mek
    mec = sysa.mec
    etype = sysa.etype
    ew = sysa.ew
    ewy = sysa.ewy
    epar = sysa.epar
    mw = sysa.mw
    N = MinvK.shape[0]
    ne = etype.shape[0]
    m = P.shape[1]
    for i in range(N):
        ks[i] = s[N + i]
        acc = mek[i] * y + mec[i] * yd
        for j in range(N):
            acc -= MinvK[i, j] * s[j] + MinvC[i, j] * s[N + j]
        ks[N + i] = acc
    for c in range(m):
        for i in range(N):
            kP[i, c] = P[N + i, c]
            acc = 0.0
            for j in range(N):
                acc -= MinvK[i, j] * P[j, c] + MinvC[i, j] * P[N + j, c]
            if timed:
                acc += (mek[i] * yd + mec[i] * ydd) * Ts[c]
            kP[N + i, c] = acc
    for e in range(ne):
        d, dd = kinematics(e, s, y, yd, sysa)
        f, dfd, dfdd, dfdv = element_force(etype[e], epar[e], d, dd, disc[e, 1], disc[e, 0])
        fel[e] = f
        if f == 0.0 and dfd == 0.0 and dfdd == 0.0:
            continue
        for i in range(N):
            ks[N + i] -= mw[e, i] * f
        for c in range(m):
            dx = 0.0
            dv = 0.0
            for j in range(N):
                dx += ew[e, j] * P[j, c]
                dv += ew[e, j] * P[N + j, c]
            if timed:
                dx += ewy[e] * yd * Ts[c]
                dv += ewy[e] * ydd * Ts[c]
            g = dfd * dx + dfdd * dv + dfdv * dvm[e, c]
            for i in range(N):
                kP[N + i, c] -= mw[e, i] * g
    return 0


@njit(cache=True)
def _user_force_terms(t, s, P, want_var, y, yd, sysa, ks, kP):
    """Add M^-1 q of the custom generalised force q(t, x, v, y, y') (N); for the variational
    equations its Jacobian by forward differences (relative step 1e-7)."""
    upar = sysa.upar
    uf = sysa.uf
    Minv = sysa.Minv
    N = Minv.shape[0]
    for i in range(N):
        uf[0, i] = 0.0
    _USER_FORCE(t, s[:N], s[N:], y, yd, upar, uf[0])
    for i in range(N):
        acc = 0.0
        for j in range(N):
            acc += Minv[i, j] * uf[0, j]
        ks[N + i] += acc
    if want_var:
        # the perturbed state lives in uf[2] (x) and uf[3] (v): no allocation here
        for i in range(N):
            uf[2, i] = s[i]
            uf[3, i] = s[N + i]
        m = P.shape[1]
        for q in range(2 * N):
            hq = 1e-7 * (abs(s[q]) + 1e-8)
            r = 2 if q < N else 3
            qi = q if q < N else q - N
            uf[r, qi] = s[q] + hq
            for i in range(N):
                uf[1, i] = 0.0
            _USER_FORCE(t, uf[2], uf[3], y, yd, upar, uf[1])
            uf[r, qi] = s[q]
            for i in range(N):
                dq = 0.0
                for j in range(N):
                    dq += Minv[i, j] * (uf[1, j] - uf[0, j]) / hq
                for c in range(m):
                    kP[N + i, c] += dq * P[q, c]


@njit(cache=True)
def field_dt(t, s, disc, sysa, xc, xp, xtab, ft):
    """ft (2N,) = the partial derivative in t of the field f(t, s) at a fixed state (through
    the excitation y(t), y'(t)); status."""
    mek = sysa.mek
    mec = sysa.mec
    etype = sysa.etype
    ewy = sysa.ewy
    epar = sysa.epar
    mw = sysa.mw
    N = mek.shape[0]
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    if st != 0:
        return st
    for i in range(N):
        ft[i] = 0.0
        ft[N + i] = mek[i] * yd + mec[i] * ydd
    for e in range(etype.shape[0]):
        if ewy[e] == 0.0:
            continue
        d, dd = kinematics(e, s, y, yd, sysa)
        f, dfd, dfdd, dfdv = element_force(etype[e], epar[e], d, dd, disc[e, 1], disc[e, 0])
        g = ewy[e] * (dfd * yd + dfdd * ydd)
        for i in range(N):
            ft[N + i] -= mw[e, i] * g
    if _HAS_USER:
        _user_force_dt(t, s, sysa, xc, xp, xtab, ft)
    return 0


@njit(cache=True)
def _user_force_dt(t, s, sysa, xc, xp, xtab, ft):
    """Add M^-1 dq/dt of the custom force q(t, x, v, y(t), y'(t)) at a fixed state, by central
    differences (step 1e-6 (|t| + 1e-3) s; one-sided where the excitation ends)."""
    upar = sysa.upar
    uf = sysa.uf
    Minv = sysa.Minv
    N = Minv.shape[0]
    ht = 1e-6 * (abs(t) + 1e-3)
    ta = t - ht
    tb = t + ht
    ya, yda, sta = excite_yyd(ta, xc, xp, xtab)
    yb, ydb, stb = excite_yyd(tb, xc, xp, xtab)
    if sta != 0:
        ta = t
        ya, yda, sta = excite_yyd(ta, xc, xp, xtab)
    if stb != 0:
        tb = t
        yb, ydb, stb = excite_yyd(tb, xc, xp, xtab)
    if tb == ta:
        return
    for i in range(N):
        uf[0, i] = 0.0
        uf[1, i] = 0.0
        uf[2, i] = s[i]
        uf[3, i] = s[N + i]
    _USER_FORCE(ta, uf[2], uf[3], ya, yda, upar, uf[0])
    _USER_FORCE(tb, uf[2], uf[3], yb, ydb, upar, uf[1])
    for i in range(N):
        acc = 0.0
        for j in range(N):
            acc += Minv[i, j] * (uf[1, j] - uf[0, j])
        ft[N + i] += acc / (tb - ta)


@njit(cache=True)
def field_sens(t, s, P, dvm, disc, Trow, sysa, xc, xp, xtab, ks, kP, fel, ft):
    """ks = f(t, s) and kP = its sensitivity J P + (df/d vminus) dvm + (df/dt) Trow; status."""
    st = deriv(t, s, P, dvm, disc, True, sysa, xc, xp, xtab, ks, kP, fel)
    if st != 0:
        return st
    st = field_dt(t, s, disc, sysa, xc, xp, xtab, ft)
    N = s.shape[0] // 2
    for q in range(N, 2 * N):
        for c in range(P.shape[1]):
            kP[q, c] += ft[q] * Trow[c]
    return st


@njit(cache=True)
def element_rate_grad(et, par, delta, ddelta, vminus):
    """Derivatives of the rates df/d(delta) and df/d(delta') of element_force (in contact,
    delta > 0) in (delta, delta', vminus): six numbers, d(df/d delta)/d(delta, delta', vminus)
    then d(df/d delta')/d(delta, delta', vminus)."""
    if et == PWL_STOP or et == CUBIC or et == INACTIVE or delta <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    K = par[0]
    d05 = math.sqrt(delta)
    d15 = delta * d05
    if et == HERTZ:
        return 0.75 * K / d05, 0.0, 0.0, 0.0, 0.0, 0.0
    if et == LANKARANI:
        c = 0.75 * (1.0 - par[1] * par[1]) / vminus
        fac = 1.0 + c * ddelta
        if par[3] != 0.0 and fac < 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        return (0.75 * K * fac / d05, 1.5 * K * d05 * c, -1.5 * K * d05 * c * ddelta / vminus,
                1.5 * K * d05 * c, 0.0, -K * d15 * c / vminus)
    mu = par[2]
    if par[3] != 0.0 and K + mu * ddelta < 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return 0.75 * (K + mu * ddelta) / d05, 1.5 * mu * d05, 0.0, 1.5 * mu * d05, 0.0, 0.0
