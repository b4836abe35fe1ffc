"""Compiled kernels: excitation, element forces, right-hand side, event-exact Runge-Kutta.

Private. Every function here takes arrays, writes into preallocated outputs and returns an
integer status; none validates input, draws random numbers or raises. The Python layer
(``nlbeam.integrate``) checks arguments and turns status codes into messages.

System arrays (``sysa``, built by ``nlbeam.System.kernel_arrays``), N DOFs, ne elements:
    MinvK (N,N), MinvC (N,N), mek (N,), mec (N,)   a = mek*y + mec*y' - MinvC v - MinvK x - sum mw_e f_e
    etype (ne,) int64, ew (ne,N), ewy (ne,), egap (ne,), epar (ne,4), mw (ne,N) = M^-1 w_e
Element e: delta_e = ew_e . x + ewy_e * y - egap_e, generalised force -ew_e f_e.
Discrete state ``disc`` (ne, 2): [in_contact (0/1), delta'_minus].
"""
import math

import numpy as np
from numba import njit as _njit

# A custom force (nlbeam.System(custom_force=...)) is compiled into a private copy of this
# module (nlbeam.custom), which sets _USER_FORCE_OVERRIDE before executing it; that copy is not
# cached on disk. In the default module the hook is a compile-time False and costs nothing.
_USER_FORCE = globals().get("_USER_FORCE_OVERRIDE", None)
_HAS_USER = _USER_FORCE is not None
_CACHE = not _HAS_USER


def njit(*args, **kw):
    """numba.njit with the module's cache setting and, unless ``_nrt=True`` is given, without
    numba's reference counting (NRT). The kernels below allocate nothing: they work on arrays
    the caller owns for the whole call, so the atomic increments and decrements NRT would do
    for every array passed at every call (about 2/3 of a right-hand side's cost) buy nothing.
    Only ``integrate_kernel``, which allocates the work arrays, runs with NRT; a kernel without
    NRT that tried to allocate would fail to compile (loudly)."""
    kw["cache"] = _CACHE
    kw.setdefault("_nrt", False)
    return _njit(*args, **kw)


if not _HAS_USER:
    @_njit(cache=True)
    def _USER_FORCE(t, x, v, y, yd, params, out):
        return

# element types
INACTIVE = -1
HERTZ = 0
LANKARANI = 1
HUNT_CROSSLEY = 2
CUBIC = 3
PWL_STOP = 4

# methods
RK2 = 0
RK4 = 1
DP5 = 2

# status codes
OK = 0
ERR_EXCITATION_RANGE = 1
ERR_NONFINITE = 2
ERR_EVENT = 3
ERR_MAX_STEPS = 4
ERR_STEP_UNDERFLOW = 5

# --- Butcher tableaus: (A, b, b_hat, c) -----------------------------------------------------
_A_RK2 = np.array([[0.0, 0.0], [1.0, 0.0]])
_B_RK2 = np.array([0.5, 0.5])
_C_RK2 = np.array([0.0, 1.0])

_A_RK4 = np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
_B_RK4 = np.array([1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0])
_C_RK4 = np.array([0.0, 0.5, 0.5, 1.0])

_A_DP5 = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
])
_B_DP5 = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0])
_BH_DP5 = np.array([5179.0 / 57600.0, 0.0, 7571.0 / 16695.0, 393.0 / 640.0, -92097.0 / 339200.0,
                    187.0 / 2100.0, 1.0 / 40.0])
_C_DP5 = np.array([0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0])

_T_C_HERTZ = 2.943275
VMINUS_FLOOR = 1e-6  # m/s: delta'_minus of a tangential (zero-rate) onset  # contact time of a free mass on a Hertz stop, in units d_max / v0


# --- excitation ------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _table_cell(t, p, tab):
    """Cell of a sampled table (code 1) holding t: (i, th, th^2, th^3, h, status), th in [0, 1]
    the position inside cell i; status ERR_EXCITATION_RANGE outside the table."""
    h = p[1]
    n = tab.shape[0]
    u = (t - p[0]) / h
    if u < -1e-9 or u > (n - 1) + 1e-9:
        return 0, 0.0, 0.0, 0.0, h, ERR_EXCITATION_RANGE
    i = int(math.floor(u))
    if i < 0:
        i = 0
    if i > n - 2:
        i = n - 2
    th = u - i
    th2 = th * th
    th3 = th2 * th
    return i, th, th2, th3, h, 0


@njit(cache=True, inline="always")
def _table_y_yd(i, th, th2, th3, h, tab):
    """Cubic Hermite y from (y, y') and y' from (y', y'') in cell i (y' linear where the table
    has no y'', column 2 NaN): (y, y', no_ydd)."""
    h00 = 2.0 * th3 - 3.0 * th2 + 1.0
    h10 = th3 - 2.0 * th2 + th
    h01 = -2.0 * th3 + 3.0 * th2
    h11 = th3 - th2
    y = h00 * tab[i, 0] + h10 * h * tab[i, 1] + h01 * tab[i + 1, 0] + h11 * h * tab[i + 1, 1]
    if math.isnan(tab[i, 2]):
        return y, (1.0 - th) * tab[i, 1] + th * tab[i + 1, 1], True
    yd = h00 * tab[i, 1] + h10 * h * tab[i, 2] + h01 * tab[i + 1, 1] + h11 * h * tab[i + 1, 2]
    return y, yd, False


@njit(cache=True)
def excite(t, code, p, tab):
    """(y, y', y'', status) at time t (s)."""
    if code == 0:
        arg = p[1] * t + p[2]
        c = math.cos(arg)
        s = math.sin(arg)
        return p[0] * c, -p[0] * p[1] * s, -p[0] * p[1] * p[1] * c, 0
    elif code == 1:
        i, th, th2, th3, h, st = _table_cell(t, p, tab)
        if st != 0:
            return 0.0, 0.0, 0.0, st
        y, yd, nan_ydd = _table_y_yd(i, th, th2, th3, h, tab)
        if nan_ydd:
            ydd = (tab[i + 1, 1] - tab[i, 1]) / h
        else:
            d00 = (6.0 * th2 - 6.0 * th) / h
            d10 = 3.0 * th2 - 4.0 * th + 1.0
            d01 = (-6.0 * th2 + 6.0 * th) / h
            d11 = 3.0 * th2 - 2.0 * th
            ydd = d00 * tab[i, 1] + d10 * tab[i, 2] + d01 * tab[i + 1, 1] + d11 * tab[i + 1, 2]
        return y, yd, ydd, 0
    else:
        y = 0.0
        yd = 0.0
        ydd = 0.0
        for k in range(tab.shape[0]):
            w = tab[k, 0]
            arg = w * t + tab[k, 2]
            c = math.cos(arg)
            s = math.sin(arg)
            y += tab[k, 1] * c
            yd -= tab[k, 1] * w * s
            ydd -= tab[k, 1] * w * w * c
        return y, yd, ydd, 0


@njit(cache=True)
def excite_yyd(t, code, p, tab):
    """(y, y', status) at time t: ``excite`` without y'' (what a right-hand side needs). The
    sampled table (code 1) is evaluated by the same expressions as in ``excite`` (bit for bit
    the same y, y'), without the y'' polynomial."""
    if code != 1:
        y, yd, ydd, st = excite(t, code, p, tab)
        return y, yd, st
    i, th, th2, th3, h, st = _table_cell(t, p, tab)
    if st != 0:
        return 0.0, 0.0, st
    y, yd, nan_ydd = _table_y_yd(i, th, th2, th3, h, tab)
    return y, yd, 0


@njit(cache=True)
def excitation_many(code, p, tab, t, out):
    """Evaluate (y, y') at every t into out (n, 2); status of the first failure."""
    for i in range(t.shape[0]):
        y, yd, ydd, st = excite(t[i], code, p, tab)
        if st != 0:
            return st
        out[i, 0] = y
        out[i, 1] = yd
    return 0


# --- elements ----------------------------------------------------------------------------------
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
    ew = sysa[5]
    N = ew.shape[1]
    d = sysa[6][e] * y - sysa[7][e]
    dd = sysa[6][e] * yd
    for j in range(N):
        d += ew[e, j] * s[j]
        dd += ew[e, j] * s[N + j]
    return d, dd


# --- right-hand side with optional variational equations ----------------------------------------
@njit(cache=True)
def deriv(t, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, ks, kP, fel):
    """ks = f(t, s); with want_var also kP = J P + (da/d vminus) dvm. fel (ne,) gets the
    element forces. Returns status."""
    MinvK = sysa[0]
    MinvC = sysa[1]
    mek = sysa[2]
    mec = sysa[3]
    etype = sysa[4]
    ew = sysa[5]
    epar = sysa[8]
    mw = sysa[9]
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
    MinvK = sysa[0]
    MinvC = sysa[1]
    mek = sysa[2]
    mec = sysa[3]
    etype = sysa[4]
    epar = sysa[8]
    mw = sysa[9]
    N = MinvK.shape[0]
    ne = etype.shape[0]
    y, yd, st = excite_yyd(t, xc, xp, xtab)
    if st != 0:
        return st
    for i in range(N):
        ks[i] = s[N + i]
        acc = mek[i] * y + mec[i] * yd
        for j in range(N):
            acc -= MinvK[i, j] * s[j] + MinvC[i, j] * s[N + j]
        ks[N + i] = acc
    for e in range(ne):
        d, dd = kinematics(e, s, y, yd, sysa)
        f, dfd, dfdd, dfdv = element_force(etype[e], epar[e], d, dd, disc[e, 1], disc[e, 0])
        fel[e] = f
        if f == 0.0 and dfd == 0.0 and dfdd == 0.0:
            continue
        for i in range(N):
            ks[N + i] -= mw[e, i] * f
    return 0


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
    MinvK = sysa[0]
    MinvC = sysa[1]
    mek = sysa[2]
    mec = sysa[3]
    etype = sysa[4]
    ew = sysa[5]
    epar = sysa[8]
    mw = sysa[9]
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
            g = dfd * dx + dfdd * dv + dfdv * dvm[e, c]
            for i in range(N):
                kP[N + i, c] -= mw[e, i] * g
    return 0


@njit(cache=True)
def _user_force_terms(t, s, P, want_var, y, yd, sysa, ks, kP):
    """Add M^-1 q of the custom generalised force q(t, x, v, y, y') (N); for the variational
    equations its Jacobian by forward differences (relative step 1e-7)."""
    upar = sysa[10]
    uf = sysa[11]
    Minv = sysa[12]
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


# --- one explicit Runge-Kutta step --------------------------------------------------------------
@njit(cache=True)
def tableau(meth):
    if meth == RK2:
        return _A_RK2, _B_RK2, _B_RK2, _C_RK2
    elif meth == RK4:
        return _A_RK4, _B_RK4, _B_RK4, _C_RK4
    return _A_DP5, _B_DP5, _BH_DP5, _C_DP5


# the tableaus' nonzero entries as compile-time constants, for the unrolled steps below (the
# same Python expressions as the arrays above, so the same doubles)
_D21 = 1.0 / 5.0
_D31, _D32 = 3.0 / 40.0, 9.0 / 40.0
_D41, _D42, _D43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_D51, _D52, _D53, _D54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_D61, _D62, _D63, _D64, _D65 = (9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0,
                                -5103.0 / 18656.0)
_DB1, _DB3, _DB4, _DB5, _DB6 = (35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                                11.0 / 84.0)
_DE1 = _DB1 - 5179.0 / 57600.0
_DE3 = _DB3 - 7571.0 / 16695.0
_DE4 = _DB4 - 393.0 / 640.0
_DE5 = _DB5 - (-92097.0 / 339200.0)
_DE6 = _DB6 - 187.0 / 2100.0
_DE7 = 0.0 - 1.0 / 40.0
_DC2, _DC3, _DC4, _DC5 = 0.2, 0.3, 0.8, 8.0 / 9.0
_R6, _R3 = 1.0 / 6.0, 1.0 / 3.0


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
            ytmp[q] = s[q] + h * 0.5 * KS[0, q]
        st = deriv_plain(t + 0.5 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[1], KP[1], fel)
        if st != 0:
            return st
        for q in range(n):
            ytmp[q] = s[q] + h * 0.5 * KS[1, q]
        st = deriv_plain(t + 0.5 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[2], KP[2], fel)
        if st != 0:
            return st
        for q in range(n):
            ytmp[q] = s[q] + h * 1.0 * KS[2, q]
        st = deriv_plain(t + 1.0 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[3], KP[3], fel)
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
    st = deriv_plain(t + 1.0 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[5], KP[5], fel)
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
    st = deriv_plain(t + 1.0 * h, ytmp, P, dvm, disc, sysa, xc, xp, xtab, KS[6], KP[6], fel)
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
    st = deriv_var(t + 0.0 * h, s, P, dvm, disc, sysa, xc, xp, xtab, KS[0], KP[0], fel)
    if st != 0:
        return st
    _stage_var(s, P, h, 0.5, KS[0], KP[0], ytmp, Ptmp, True)
    if _HAS_USER:
        st = deriv_var(t + 0.5 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[1], KP[1], fel)
        if st != 0:
            return st
        _stage_var(s, P, h, 0.5, KS[1], KP[1], ytmp, Ptmp, True)
        st = deriv_var(t + 0.5 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[2], KP[2], fel)
        if st != 0:
            return st
    else:
        # stages 2 and 3 at the same time t + h/2: the excitation once
        y, yd, st = excite_yyd(t + 0.5 * h, xc, xp, xtab)
        if st != 0:
            return st
        _deriv_var_at(y, yd, ytmp, Ptmp, dvm, disc, sysa, KS[1], KP[1], fel)
        _stage_var(s, P, h, 0.5, KS[1], KP[1], ytmp, Ptmp, True)
        _deriv_var_at(y, yd, ytmp, Ptmp, dvm, disc, sysa, KS[2], KP[2], fel)
    _stage_var(s, P, h, 1.0, KS[2], KP[2], ytmp, Ptmp, True)
    st = deriv_var(t + 1.0 * h, ytmp, Ptmp, dvm, disc, sysa, xc, xp, xtab, KS[3], KP[3], fel)
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
        st = deriv(t + Cc[i] * h, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp, xtab, KS[i], KP[i], fel)
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
    ui = u0 + 0.0 * hu
    ti = t_ref + ui * ui if mode == 1 else tcur
    st, sc = _graded_stage(mode, ui, ti, e, s, P, dvm, disc, want_var, sysa, xc, xp, xtab,
                              KS[0], KP[0], fel)
    if st != 0:
        return st, tcur
    KT[0] = sc
    # stage 2
    _stage_var(s, P, hu, 0.5, KS[0], KP[0], ytmp, Ptmp, want_var)
    ui = u0 + 0.5 * hu
    ti = t_ref + ui * ui if mode == 1 else tcur + hu * 0.5 * KT[0]
    st, sc = _graded_stage(mode, ui, ti, e, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp,
                              xtab, KS[1], KP[1], fel)
    if st != 0:
        return st, tcur
    KT[1] = sc
    # stage 3
    _stage_var(s, P, hu, 0.5, KS[1], KP[1], ytmp, Ptmp, want_var)
    ui = u0 + 0.5 * hu
    if mode == 1:
        ti = t_ref + ui * ui
    else:
        ti = tcur + hu * 0.0 * KT[0]
        ti += hu * 0.5 * KT[1]
    st, sc = _graded_stage(mode, ui, ti, e, ytmp, Ptmp, dvm, disc, want_var, sysa, xc, xp,
                              xtab, KS[2], KP[2], fel)
    if st != 0:
        return st, tcur
    KT[2] = sc
    # stage 4
    _stage_var(s, P, hu, 1.0, KS[2], KP[2], ytmp, Ptmp, want_var)
    ui = u0 + 1.0 * hu
    if mode == 1:
        ti = t_ref + ui * ui
    else:
        ti = tcur + hu * 0.0 * KT[0]
        ti += hu * 0.0 * KT[1]
        ti += hu * 1.0 * KT[2]
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
            th = v0 / (v0 - v1)
            for _ in range(60):
                x, xd = hermite5(s0[i], v0, f0[N + i], s1[i], v1, f1[N + i], h, th)
                if (xd > 0.0) == (v0 > 0.0):
                    lo = th
                else:
                    hi = th
                # Newton on x' with the second derivative by a secant of the interpolant
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
    st = rk_step(meth, t, tau, s, P, dvm, disc, False, sysa, xc, xp, xtab, f0,
                 s_out, P_out, KS, KP, ytmp, Ptmp, fel, err_w)
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


# --- the integrator ---------------------------------------------------------------------------------
@njit(cache=True)
def contact_step(e, v0, a0, sysa, spc):
    """Time step inside a contact of element e that starts at penetration rate v0 (m/s) and
    free-flight penetration acceleration a0 (m/s^2): the estimated contact duration divided by
    spc. The duration is that of a free mass on the stop, or of a grazing touch, 2 v0 / |a0|,
    when a0 < 0 makes that shorter."""
    etype = sysa[4]
    ew = sysa[5]
    epar = sysa[8]
    mw = sysa[9]
    winv = 0.0
    for j in range(ew.shape[1]):
        winv += ew[e, j] * mw[e, j]
    meff = 1.0 / winv
    K = epar[e, 0]
    if etype[e] == PWL_STOP:
        tc = math.pi * math.sqrt(meff / K)
    else:
        v = max(v0, 1e-12)
        dmax = (1.25 * meff * v * v / K) ** 0.4
        tc = _T_C_HERTZ * dmax / v
    if a0 < 0.0:
        tg = 2.0 * max(v0, 1e-12) / (-a0)
        if tg < tc:
            tc = tg
    return tc / spc


@njit(cache=True, inline="always")
def _store(n_stored, t, s, disc, xc, xp, xtab, sysa, out_t, out_s, out_d, out_f):
    """Write sample n_stored: t, s, and delta and force of every element. Inlined into the
    integrator's loop, with y'' skipped and the penetration computed in place (the same
    expressions as ``kinematics``): a call with the system's arrays cost ~100 ns a sample."""
    y, yd, st = excite_yyd(t, xc, xp, xtab)
    etype = sysa[4]
    ew = sysa[5]
    N = ew.shape[1]
    out_t[n_stored] = t
    for q in range(s.shape[0]):
        out_s[n_stored, q] = s[q]
    for e in range(etype.shape[0]):
        d = sysa[6][e] * y - sysa[7][e]
        dd = sysa[6][e] * yd
        for j in range(N):
            d += ew[e, j] * s[j]
            dd += ew[e, j] * s[N + j]
        out_d[n_stored, e] = d
        f, a1, a2, a3 = element_force(etype[e], sysa[8][e], d, dd, disc[e, 1], disc[e, 0])
        out_f[n_stored, e] = f
    return n_stored + 1


@njit(cache=True)
def delta_extremum(e, sign, t, h, s, s_new, f0, f1, sysa, xc, xp, xtab):
    """(theta, delta) at the extremum of delta_e within a step, on the quintic dense output;
    sign = +1 for a maximum, -1 for a minimum."""
    N = s.shape[0] // 2
    ew = sysa[5]
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
        if sign * (xwd + sysa[6][e] * ydm) > 0.0:
            lo_b = th
        else:
            hi_b = th
    th = 0.5 * (lo_b + hi_b)
    xw, xwd = hermite5(wx0, wv0, wa0, wx1, wv1, wa1, h, th)
    ym, ydm, yddm, st2 = excite(t + th * h, xc, xp, xtab)
    return th, xw + sysa[6][e] * ym - sysa[7][e]


@njit(cache=True, inline="always")
def _may_cross(e, t, h, s, s_new, disc, sysa, xc, xp, xtab):
    """The cheap part of ``_crossing``, inlined into the integrator's loop: False when that
    function would certainly report no boundary in the step (delta_e at the step end on the
    element's own side, and no extremum of delta_e towards the boundary inside the step).
    The same expressions as ``_crossing`` and ``kinematics``, so the same decision bit for bit;
    it saves the call (~25 arrays) on the steps where nothing happens, nearly all of them."""
    sign = -1.0 if disc[e, 0] != 0.0 else 1.0
    ew = sysa[5]
    N = ew.shape[1]
    y0, yd0, st = excite_yyd(t, xc, xp, xtab)
    y1, yd1, st = excite_yyd(t + h, xc, xp, xtab)
    d1 = sysa[6][e] * y1 - sysa[7][e]
    dd0 = sysa[6][e] * yd0
    dd1 = sysa[6][e] * yd1
    for j in range(N):
        d1 += ew[e, j] * s_new[j]
        dd0 += ew[e, j] * s[N + j]
        dd1 += ew[e, j] * s_new[N + j]
    return sign * d1 > 0.0 or (sign * dd0 > 0.0 and sign * dd1 < 0.0)


@njit(cache=True)
def _crossing(meth, t, h, s, s_new, f0, f1, P, dvm, disc, e, sysa, xc, xp, xtab,
              s_try, dummyP, KS, KP, ytmp, Ptmp, fel, err_w):
    """Does element e change contact status within the time step (t, s) -> (t+h, s_new)?
    Returns (tau of the boundary, status); tau < 0 when there is none."""
    N = s.shape[0] // 2
    ew = sysa[5]
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


@njit(cache=True)
def contact_rate(t, s, disc, sysa, xc, xp, xtab):
    """Largest rate (1/s) of the contact laws at (t, s): sqrt(stiffness / m_eff) and
    damping / m_eff of every element in contact; explicit steps need rate * h < 0.5."""
    etype = sysa[4]
    N = s.shape[0] // 2
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    lam = 0.0
    for e in range(etype.shape[0]):
        if disc[e, 0] != 0.0:
            d, dd = kinematics(e, s, y, yd, sysa)
            f, dfd, dfdd, dfdv = element_force(etype[e], sysa[8][e], d, dd, disc[e, 1], disc[e, 0])
            winv = 0.0
            for j in range(N):
                winv += sysa[5][e, j] * sysa[9][e, j]
            lam = max(lam, math.sqrt(max(dfd, 0.0) * winv), abs(dfdd) * winv)
    return lam


@njit(cache=True, _nrt=True)
def integrate_kernel(sysa, xc, xp, xtab, meth, t0, t_end, dt, spc, rtol, atol, h_init, max_steps,
                     s0, disc0, events_on, want_var, P0, dvm0, track_xmax, store_every, graded,
                     out_t, out_s, out_d, out_f, ev_log,
                     s_end, disc_end, P_end, dvm_end, xmax, counters, fcounters):
    """Integrate from t0 to t_end.

    Fixed-step methods (RK2, RK4) step on the grid t0 + k dt in free flight; inside a contact
    they take steps of (estimated contact duration) / spc, starting from the onset and ignoring
    the grid (grid samples inside a contact come from the quintic Hermite dense output), so that
    the step sequence is a smooth function of the initial state. Every contact boundary is a
    root of the step map, landed on to a few ulps of t. With ``graded`` (one element in contact)
    the first quarter of a contact is stepped uniformly in sigma = sqrt(t - t_onset), and from
    the point where delta has fallen back to KAPPA * (its maximum) uniformly in u = sqrt(delta)
    down to delta = 0 (then polished to round-off): this removes the delta^1.5 singularity of
    the contact force at both boundaries. DP5 controls its error with (rtol, atol); grid samples
    come from dense output. Samples: every store_every-th grid point, t0 and t_end included.

    counters: [n_stored, n_steps, n_rejected, n_rhs, n_impacts, min_steps_per_contact,
               n_contacts, n_events]
    fcounters: [t_reached, max |delta| at a landed event]
    ev_log (cap, 4): [t, element, 1 onset / 0 end, delta' at the boundary] of the first cap events.
    """
    KAPPA = 0.25
    etype = sysa[4]
    N = sysa[0].shape[0]
    n = 2 * N
    ne = etype.shape[0]
    m = P0.shape[1]
    A, B, BH, Cc = tableau(meth)
    ns = B.shape[0]
    KS = np.zeros((ns, n))
    KP = np.zeros((ns, n, m))
    KT = np.zeros(ns)
    ytmp = np.zeros(n)
    Ptmp = np.zeros((n, m))
    fel = np.zeros(ne)
    err_w = np.zeros(n)
    s = s0.copy()
    P = P0.copy()
    dvm = dvm0.copy()
    disc = disc0.copy()
    s_new = np.zeros(n)
    P_new = np.zeros((n, m))
    s_try = np.zeros(n)
    f0 = np.zeros(n)
    f1 = np.zeros(n)
    dummyP = np.zeros((n, m))
    steps_in_contact = np.zeros(ne, dtype=np.int64)
    # a contact under way at t0 started before this call: its steps here are not all of its
    # steps, so it does not enter the steps-per-contact count
    from_before = np.zeros(ne, dtype=np.bool_)
    dtc = np.full(ne, np.inf)
    d_sw = np.full(ne, -1.0)     # delta at which the graded exit phase starts (-1: unknown)
    return _integrate_loop(sysa, xc, xp, xtab, meth, t0, t_end, dt, spc, rtol, atol, h_init,
                           max_steps, events_on, want_var, track_xmax, store_every, graded,
                           out_t, out_s, out_d, out_f, ev_log, s_end, disc_end, P_end, dvm_end,
                           xmax, counters, fcounters, KS, KP, KT, ytmp, Ptmp, fel, err_w, s, P,
                           dvm, disc, s_new, P_new, s_try, f0, f1, dummyP, steps_in_contact,
                           from_before, dtc, d_sw)


@njit(cache=True)
def _integrate_loop(sysa, xc, xp, xtab, meth, t0, t_end, dt, spc, rtol, atol, h_init, max_steps,
                    events_on, want_var, track_xmax, store_every, graded, out_t, out_s, out_d,
                    out_f, ev_log, s_end, disc_end, P_end, dvm_end, xmax, counters, fcounters,
                    KS, KP, KT, ytmp, Ptmp, fel, err_w, s, P, dvm, disc, s_new, P_new, s_try, f0,
                    f1, dummyP, steps_in_contact, from_before, dtc, d_sw):
    """The body of integrate_kernel, on the work arrays it allocated (no reference counting
    here: see ``njit``)."""
    KAPPA = 0.25
    etype = sysa[4]
    N = sysa[0].shape[0]
    n = 2 * N
    ne = etype.shape[0]
    m = P.shape[1]
    A, B, BH, Cc = tableau(meth)
    ns = B.shape[0]
    y, yd, ydd, st = excite(t0, xc, xp, xtab)
    for e in range(ne):
        if disc[e, 0] != 0.0:
            from_before[e] = True
            # a record that starts inside a contact: the impact velocity with the same energy
            d, dd = kinematics(e, s, y, yd, sysa)
            winv = 0.0
            for j in range(N):
                winv += sysa[5][e, j] * sysa[9][e, j]
            K = sysa[8][e, 0]
            pot = 0.8 * K * max(d, 0.0) ** 2.5 if etype[e] != PWL_STOP else K * max(d, 0.0) ** 2
            dtc[e] = min(contact_step(e, math.sqrt(dd * dd + pot * winv), 0.0, sysa, spc), dt)

    n_stored = 0
    n_steps = 0
    n_rej = 0
    n_rhs = 0
    n_imp = 0
    min_spc = 1 << 62
    n_contacts = 0
    n_events = 0
    max_land = 0.0
    fixed = meth != DP5
    n_grade = max(2, int(spc // 4))
    k_grid = 0
    n_grid = int(math.ceil((t_end - t0) / dt - 1e-9))
    t = t0
    h = h_init
    status = 0
    en = 1.0
    phase = 0       # 0: time steps; 1: onset, steps in sigma; 2: exit, steps in u
    pe = -1         # the element of the graded phase
    g_t0 = 0.0
    g_u = 0.0
    g_end = 0.0
    g_h = 0.0

    st = deriv(t, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0, KP[0], fel)
    n_rhs += 1
    if st != 0:
        return st
    if track_xmax:
        for i in range(N):
            xmax[i] = max(xmax[i], abs(s[i]))
    if store_every > 0 and out_t.shape[0] > 0:
        n_stored = _store(n_stored, t, s, disc, xc, xp, xtab, sysa, out_t, out_s, out_d, out_f)

    while t < t_end and status == 0:
        if n_steps >= max_steps:
            status = ERR_MAX_STEPS
            break
        n_in = 0
        for e in range(ne):
            if disc[e, 0] != 0.0:
                n_in += 1
                if phase == 0:
                    pe = e
        ev = -1
        tau_ev = 0.0
        hit_grid = False
        landed = False
        enter_exit = False
        if phase == 2:
            y, yd, ydd, st = excite(t, xc, xp, xtab)
            d, dd = kinematics(pe, s, y, yd, sysa)
            if disc[pe, 0] == 0.0 or dd >= 0.0 or n_in != 1:
                phase = 0
        if phase == 1 and n_in != 1:
            phase = 0
        if phase != 0:
            # a graded step longer than the stability limit of the contact law (a slow, stiff
            # contact): fall back to time steps, which respect it
            if phase == 1:
                dt_est = (g_u + g_h) ** 2 - g_u ** 2
            else:
                y, yd, ydd, st = excite(t, xc, xp, xtab)
                d, dd = kinematics(pe, s, y, yd, sysa)
                dt_est = 2.0 * g_u * g_h / max(-dd, 1e-300)
            if contact_rate(t, s, disc, sysa, xc, xp, xtab) * dt_est > 0.5:
                phase = 0
        if phase == 1:
            # onset phase: uniform steps in sigma = sqrt(t - t_onset)
            hs = min(g_h, g_end - g_u)
            cut = False
            if g_t0 + (g_u + hs) ** 2 >= t_end:
                hs = math.sqrt(t_end - g_t0) - g_u
                cut = True
            st, t_new = rk_step_graded(meth, 1, g_u, hs, g_t0, pe, s, t, P, dvm, disc, want_var,
                                       sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT, ytmp, Ptmp, fel)
            n_rhs += ns
            if cut:
                t_new = t_end
            ok = st == 0
            if ok:
                st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0], fel)
                n_rhs += 1
                yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                for e in range(ne):
                    if has_event(etype[e]):
                        d, dd = kinematics(e, s_new, yv, ydv, sysa)
                        if (disc[e, 0] != 0.0 and d < 0.0) or (disc[e, 0] == 0.0 and d > 0.0):
                            ok = False
            if not ok:
                phase = 0  # something happens inside the onset phase: fall back to time steps
                continue
            g_u += hs
            if g_u >= g_end * (1.0 - 1e-12):
                phase = 0
        elif phase == 2:
            # exit phase: uniform steps in u = sqrt(delta) down to u = 0
            hu = min(g_h, g_u)
            if g_u - hu < 1e-9 * g_h:
                hu = g_u
            st, t_new = rk_step_graded(meth, 2, g_u, -hu, 0.0, pe, s, t, P, dvm, disc, want_var,
                                       sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT, ytmp, Ptmp, fel)
            n_rhs += ns
            if st != 0 or t_new > t_end or t_new <= t:
                phase = 0  # the record ends inside the exit phase (or it failed): time steps
                continue
            # the step in u is only valid while delta falls monotonically: if delta' reached 0
            # inside it (a slow contact held by the base), the state no longer has delta =
            # u^2 and delta' < 0; retake the step in time
            yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
            d, dd = kinematics(pe, s_new, yv, ydv, sysa)
            u_new = g_u - hu
            if not (dd < 0.0 and abs(d - u_new * u_new) <= 0.05 * (g_u * g_u - u_new * u_new)):
                phase = 0
                continue
            g_u -= hu
            st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0], fel)
            n_rhs += 1
            if g_u <= 0.0:
                # landed on delta = 0 up to the truncation error: polish to round-off by Newton
                # steps in time, then switch
                for _ in range(4):
                    yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                    d, dd = kinematics(pe, s_new, yv, ydv, sysa)
                    if d == 0.0 or abs(d) <= 1e-15 * (abs(yv) + abs(sysa[7][pe]) + 1e-300):
                        break
                    tau = -d / dd
                    for q in range(n):
                        s_try[q] = s_new[q]
                        if want_var:
                            for c in range(m):
                                dummyP[q, c] = P_new[q, c]
                    st = rk_step(meth, t_new, tau, s_try, dummyP, dvm, disc, want_var, sysa, xc,
                                 xp, xtab, f1, s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                    t_new = t_new + tau
                    st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1,
                               KP[0], fel)
                yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                d, dd = kinematics(pe, s_new, yv, ydv, sysa)
                if d > 0.0 and dd < 0.0:
                    # land on the far side (delta <= 0) of the boundary
                    tau = -2.0 * d / dd
                    for q in range(n):
                        s_try[q] = s_new[q]
                        if want_var:
                            for c in range(m):
                                dummyP[q, c] = P_new[q, c]
                    st = rk_step(meth, t_new, tau, s_try, dummyP, dvm, disc, want_var, sysa, xc,
                                 xp, xtab, f1, s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                    t_new = t_new + tau
                    st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1,
                               KP[0], fel)
                ev = pe
                tau_ev = t_new - t
                landed = True
                phase = 0
        else:
            # ---- an ordinary step in time
            if fixed:
                tg = t0 + (k_grid + 1) * dt if k_grid + 1 < n_grid else t_end
                if n_in > 0:
                    hc = np.inf
                    for e in range(ne):
                        if disc[e, 0] != 0.0 and dtc[e] < hc:
                            hc = dtc[e]
                    # explicit stability: the law's stiffness and damping rates
                    lam = contact_rate(t, s, disc, sysa, xc, xp, xtab)
                    if lam * hc > 0.5:
                        hc = 0.5 / lam
                    h = hc
                    if h >= t_end - t:
                        h = t_end - t
                        hit_grid = True
                else:
                    h = tg - t
                    hit_grid = True
            else:
                if h >= t_end - t:
                    h = t_end - t
                if h < 1e-14 * max(abs(t), 1.0):
                    status = ERR_STEP_UNDERFLOW
                    break
            if not want_var and meth != RK2:
                # without variational equations: straight to the unrolled RK4/DP5 step (what
                # rk_step would call), one call level less per step
                st = _rk_step_plain(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0, s_new,
                                    KS, KP, ytmp, fel, err_w)
            elif not _HAS_USER and meth == RK4:
                # with them: the unrolled RK4 step with the variational equations, likewise
                st = _rk_step_var(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_new, P_new, KS, KP,
                                  ytmp, Ptmp, fel)
            else:
                st = rk_step(meth, t, h, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0,
                             s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
            n_rhs += ns - (0 if want_var else 1)
            if st != 0:
                status = st
                break
            if not fixed:
                en = 0.0
                for q in range(n):
                    sc = atol + rtol * max(abs(s[q]), abs(s_new[q]))
                    en += (err_w[q] / sc) ** 2
                en = math.sqrt(en / n)
                if en > 1.0:
                    h = h * max(0.2, 0.9 * en ** -0.2)
                    n_rej += 1
                    n_steps += 1
                    continue
            if fixed:
                if hit_grid:
                    t_new = t_end if n_in > 0 else tg
                else:
                    t_new = t + h
            else:
                t_new = t_end if t + h >= t_end else t + h
            if not fixed and t_new == t + h:
                # first same as last: DP5's stage 7 is f(t + h, s_new), bit for bit
                for q in range(n):
                    f1[q] = KS[6, q]
                st = 0
            else:
                # f at the step end (the next step's stage 1), inlined: the same values as deriv
                st = deriv_plain(t_new, s_new, P_new, dvm, disc, sysa, xc, xp, xtab, f1, KP[0],
                                 fel)
                n_rhs += 1
            if st != 0:
                status = st
                break
            if events_on:
                for e in range(ne):
                    if not has_event(etype[e]):
                        continue
                    if not _may_cross(e, t, t_new - t, s, s_new, disc, sysa, xc, xp, xtab):
                        continue
                    tau, st = _crossing(meth, t, t_new - t, s, s_new, f0, f1, P, dvm, disc, e,
                                        sysa, xc, xp, xtab, s_try, dummyP, KS, KP, ytmp, Ptmp,
                                        fel, err_w)
                    if st != 0:
                        status = st
                        break
                    if tau >= 0.0 and (ev < 0 or tau < tau_ev):
                        tau_ev = tau
                        ev = e
                if status != 0:
                    break
                # the start of the graded exit phase: delta falls through d_sw
                if fixed and graded and n_in == 1 and phase == 0:
                    if d_sw[pe] > 0.0:
                        y0, yd0, ydd0, st2 = excite(t, xc, xp, xtab)
                        y1, yd1, ydd1, st2 = excite(t_new, xc, xp, xtab)
                        d0, dd0 = kinematics(pe, s, y0, yd0, sysa)
                        d1, dd1 = kinematics(pe, s_new, y1, yd1, sysa)
                        if d0 > d_sw[pe] and d1 <= d_sw[pe] and dd0 < 0.0:
                            tau, st = locate(meth, t, 0.0, t_new - t, d_sw[pe] - d0,
                                             d_sw[pe] - d1, s, P, dvm, disc, pe, -1.0, d_sw[pe],
                                             sysa, xc, xp, xtab, f0, s_try, dummyP, KS, KP, ytmp,
                                             Ptmp, fel, err_w)
                            if st != 0:
                                status = st
                                break
                            if ev < 0 or tau < tau_ev:
                                ev = -1
                                tau_ev = tau
                                enter_exit = True
            if ev >= 0 or enter_exit:
                # re-take the step up to the boundary
                st = rk_step(meth, t, tau_ev, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0,
                             s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                if st != 0:
                    status = st
                    break
                t_new = t + tau_ev
                hit_grid = False
                st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0], fel)
                n_rhs += 1
        # ---- accept the step (t, s) -> (t_new, s_new)
        n_steps += 1
        for e in range(ne):
            if disc[e, 0] != 0.0:
                steps_in_contact[e] += 1
        if track_xmax:
            # the refinement on the dense output only where a velocity changes sign and the
            # quintic can exceed the current max: |x(theta)| <= max(|x0|, |x1|) + h (|v0| + |v1|)
            # max|H1| + h^2 (|a0| + |a1|) max|H2| (H0 + H3 = 1, both in [0, 1]; max|H4| = max|H1|
            # = 16/81, max|H5| = max|H2| = 0.01728), so a skipped refinement could not have
            # raised xmax: the same xmax bit for bit, without most of the bisections
            refine = False
            hh = t_new - t
            for i in range(N):
                a = abs(s_new[i])
                if a > xmax[i]:
                    xmax[i] = a
                if s[N + i] * s_new[N + i] < 0.0:
                    bnd = (max(abs(s[i]), a) + hh * 0.19754 * (abs(s[N + i]) + abs(s_new[N + i]))
                           + hh * hh * 0.017281 * (abs(f0[N + i]) + abs(f1[N + i])))
                    if bnd * (1.0 + 1e-12) >= xmax[i]:
                        refine = True
            if refine:
                step_extrema(s, f0, s_new, f1, t_new - t, N, xmax)
        if fixed and graded and n_in == 1 and disc[pe, 0] != 0.0 and t_new > t:
            # the maximum penetration of this contact sets where the graded exit phase starts
            y0, yd0, ydd0, st2 = excite(t, xc, xp, xtab)
            y1, yd1, ydd1, st2 = excite(t_new, xc, xp, xtab)
            d0, dd0 = kinematics(pe, s, y0, yd0, sysa)
            d1, dd1 = kinematics(pe, s_new, y1, yd1, sysa)
            if dd0 > 0.0 and dd1 <= 0.0:
                th, dm = delta_extremum(pe, 1.0, t, t_new - t, s, s_new, f0, f1, sysa, xc, xp, xtab)
                d_sw[pe] = KAPPA * max(dm, d0, d1)
        # grid samples passed by this step: exact at a grid hit, dense output otherwise
        while k_grid < n_grid:
            kk = k_grid + 1
            tgk = t0 + kk * dt if kk < n_grid else t_end
            exact = hit_grid and (kk == n_grid or tgk >= t_new - 1e-15 * abs(t_new))
            if tgk > t_new and not exact:
                break
            k_grid = kk
            if store_every > 0 and (kk % store_every == 0 or kk == n_grid):
                if exact:
                    n_stored = _store(n_stored, t_new, s_new, disc, xc, xp, xtab, sysa,
                                      out_t, out_s, out_d, out_f)
                else:
                    th = (tgk - t) / (t_new - t)
                    for i in range(N):
                        xk, vk = hermite5(s[i], s[N + i], f0[N + i], s_new[i], s_new[N + i],
                                          f1[N + i], t_new - t, th)
                        ytmp[i] = xk
                        ytmp[N + i] = vk
                    n_stored = _store(n_stored, tgk, ytmp, disc, xc, xp, xtab, sysa,
                                      out_t, out_s, out_d, out_f)
            if exact:
                break
        t = t_new
        for q in range(n):
            s[q] = s_new[q]
            f0[q] = f1[q]
        if want_var:
            for q in range(n):
                for c in range(m):
                    P[q, c] = P_new[q, c]
        if enter_exit:
            phase = 2
            g_u = math.sqrt(d_sw[pe])
            g_h = g_u / n_grade
        # ---- switch the discrete state at an event
        if ev >= 0:
            y, yd, ydd, st = excite(t, xc, xp, xtab)
            d, dd = kinematics(ev, s, y, yd, sysa)
            if n_events < ev_log.shape[0]:
                ev_log[n_events, 0] = t
                ev_log[n_events, 1] = ev
                ev_log[n_events, 2] = 1.0 if disc[ev, 0] == 0.0 else 0.0
                ev_log[n_events, 3] = dd
            n_events += 1
            if abs(d) > max_land:
                max_land = abs(d)
            if disc[ev, 0] == 0.0:
                disc[ev, 0] = 1.0
                disc[ev, 1] = dd if dd > VMINUS_FLOOR else VMINUS_FLOOR
                n_imp += 1
                steps_in_contact[ev] = 0
                d_sw[ev] = -1.0
                dd2 = sysa[6][ev] * ydd
                for j in range(N):
                    dd2 += sysa[5][ev, j] * f0[N + j]
                dtc[ev] = contact_step(ev, disc[ev, 1], dd2, sysa, spc)
                if fixed and dtc[ev] > dt:
                    dtc[ev] = dt  # a soft contact never gets a longer step than free flight
                if want_var:
                    # sensitivity of the onset velocity: d vminus = [0,w] P + delta'' dt_e,
                    # dt_e = -([w,0] P) / delta'
                    ew = sysa[5]
                    dd2 = sysa[6][ev] * ydd
                    for j in range(N):
                        dd2 += ew[ev, j] * f0[N + j]
                    for c in range(m):
                        wx = 0.0
                        wv = 0.0
                        for j in range(N):
                            wx += ew[ev, j] * P[j, c]
                            wv += ew[ev, j] * P[N + j, c]
                        dvm[ev, c] = wv - dd2 * wx / disc[ev, 1]
                if fixed and graded and dd > 0.0 and n_in == 0:
                    phase = 1
                    pe = ev
                    g_t0 = t
                    g_u = 0.0
                    g_end = math.sqrt(n_grade * dtc[ev])
                    g_h = g_end / n_grade
                else:
                    phase = 0
            else:
                disc[ev, 0] = 0.0
                if from_before[ev]:
                    from_before[ev] = False
                else:
                    n_contacts += 1
                    if steps_in_contact[ev] < min_spc:
                        min_spc = steps_in_contact[ev]
                dtc[ev] = np.inf
                d_sw[ev] = -1.0
                phase = 0
            # f0 after the switch (the field is continuous; the law's memory changed)
            st = deriv(t, s, P, dvm, disc, False, sysa, xc, xp, xtab, f0, KP[0], fel)
            n_rhs += 1
        if k_grid >= n_grid:
            t = t_end
        if not fixed:
            if en == 0.0:
                fac = 5.0
            else:
                fac = min(5.0, max(0.2, 0.9 * en ** -0.2))
            h = h * fac
            if ev >= 0:
                h = min(h, max(1e-3 * dt, 1e-9))

    for q in range(n):
        s_end[q] = s[q]
        for c in range(m):
            P_end[q, c] = P[q, c]
    for e in range(ne):
        disc_end[e, 0] = disc[e, 0]
        disc_end[e, 1] = disc[e, 1]
        for c in range(m):
            dvm_end[e, c] = dvm[e, c]
    counters[0] = n_stored
    counters[1] = n_steps
    counters[2] = n_rej
    counters[3] = n_rhs
    counters[4] = n_imp
    counters[5] = min_spc if n_contacts > 0 else -1
    counters[6] = n_contacts
    counters[7] = n_events
    fcounters[0] = t
    fcounters[1] = max_land
    return status
