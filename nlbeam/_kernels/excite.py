"""Excitation evaluation: y, y', y'' (m or N and rates) of a harmonic (code 0), a sampled
table (code 1: cubic Hermite from y, y', y''; code 3: quintic Hermite from y, y', y'', y''';
code 4: the same quintic Hermite table as per-cell coefficients, ``tables.py``) or a sum of
cosines (code 2) at time t (s)."""
import math

from .codes import ERR_EXCITATION_RANGE
from .hook import njit


@njit(cache=True, inline="always")
def _table_cell(t, p, tab):
    """Cell of a sampled table (code 1 or 3) holding t: (i, th, th^2, th^3, h, status), th in [0, 1]
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


@njit(cache=True, inline="always")
def _quintic(f0, g0, c0, f1, g1, c1, h):
    """Coefficients (a0 .. a5) of p(th) = sum_k a_k th^k, th in [0, 1] across a cell of length
    h (s), with p = f, dp/dt = g, d2p/dt2 = c at both ends: the quintic Hermite interpolant."""
    a1 = h * g0
    a2 = 0.5 * h * h * c0
    r0 = f1 - f0 - a1 - a2
    r1 = h * g1 - a1 - 2.0 * a2
    r2 = h * h * c1 - 2.0 * a2
    a3 = 10.0 * r0 - 4.0 * r1 + 0.5 * r2
    a4 = -15.0 * r0 + 7.0 * r1 - r2
    a5 = 6.0 * r0 - 3.0 * r1 + 0.5 * r2
    return f0, a1, a2, a3, a4, a5


@njit(cache=True, inline="always")
def _quintic_y_yd(i, th, h, tab):
    """Quintic Hermite y from (y, y', y'') and y' from (y', y'', y''') in cell i of a table with
    the columns y, y', y'', y''' (code 3): (y, y', b1 .. b5), b_k the coefficients of y' in th."""
    a0, a1, a2, a3, a4, a5 = _quintic(tab[i, 0], tab[i, 1], tab[i, 2], tab[i + 1, 0],
                                      tab[i + 1, 1], tab[i + 1, 2], h)
    b0, b1, b2, b3, b4, b5 = _quintic(tab[i, 1], tab[i, 2], tab[i, 3], tab[i + 1, 1],
                                      tab[i + 1, 2], tab[i + 1, 3], h)
    y = a0 + th * (a1 + th * (a2 + th * (a3 + th * (a4 + th * a5))))
    yd = b0 + th * (b1 + th * (b2 + th * (b3 + th * (b4 + th * b5))))
    return y, yd, b1, b2, b3, b4, b5


@njit(cache=True, inline="always")
def _coef_cell(t, p, tab):
    """Cell i of a coefficient table (code 4; p = [t_start, h, nodes]) holding t and the
    position th in [0, 1] inside it, as ``_table_cell``: (i, th, status)."""
    h = p[1]
    n = tab.shape[0] + 1
    u = (t - p[0]) / h
    if u < -1e-9 or u > (n - 1) + 1e-9:
        return 0, 0.0, ERR_EXCITATION_RANGE
    i = int(math.floor(u))
    if i < 0:
        i = 0
    if i > n - 2:
        i = n - 2
    return i, u - i, 0


@njit(cache=True, inline="always")
def _coef_y_yd(i, th, tab):
    """y and y' in cell i of a coefficient table (code 4) by Horner: the values the quintic
    table (code 3) gives, bit for bit (the same coefficients, the same sums)."""
    y = tab[i, 0] + th * (tab[i, 1] + th * (tab[i, 2] + th * (tab[i, 3] + th * (
        tab[i, 4] + th * tab[i, 5]))))
    yd = tab[i, 6] + th * (tab[i, 7] + th * (tab[i, 8] + th * (tab[i, 9] + th * (
        tab[i, 10] + th * tab[i, 11]))))
    return y, yd


@njit(cache=True)
def excite(t, code, p, tab):
    """(y, y', y'', status) at time t (s)."""
    if code == 4:
        i, th, st = _coef_cell(t, p, tab)
        if st != 0:
            return 0.0, 0.0, 0.0, st
        y, yd = _coef_y_yd(i, th, tab)
        ydd = (tab[i, 7] + th * (2.0 * tab[i, 8] + th * (3.0 * tab[i, 9] + th * (
            4.0 * tab[i, 10] + th * 5.0 * tab[i, 11])))) / p[1]
        return y, yd, ydd, 0
    if code == 3:
        i, th, th2, th3, h, st = _table_cell(t, p, tab)
        if st != 0:
            return 0.0, 0.0, 0.0, st
        y, yd, b1, b2, b3, b4, b5 = _quintic_y_yd(i, th, h, tab)
        ydd = (b1 + th * (2.0 * b2 + th * (3.0 * b3 + th * (4.0 * b4 + th * 5.0 * b5)))) / h
        return y, yd, ydd, 0
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


@njit(cache=True, inline="always")
def _coef_yyd(t, p, tab):
    """(y, y', status) of a coefficient table (code 4) at time t."""
    i, th, st = _coef_cell(t, p, tab)
    if st != 0:
        return 0.0, 0.0, st
    y, yd = _coef_y_yd(i, th, tab)
    return y, yd, 0


@njit(cache=True, inline="always")
def _cubic_yyd(t, p, tab):
    """(y, y', status) of a cubic table (code 1) at time t, by ``excite``'s expressions."""
    i, th, th2, th3, h, st = _table_cell(t, p, tab)
    if st != 0:
        return 0.0, 0.0, st
    y, yd, nan_ydd = _table_y_yd(i, th, th2, th3, h, tab)
    return y, yd, 0


@njit(cache=True)
def excite_yyd(t, code, p, tab):
    """(y, y', status) at time t: ``excite`` without y'' (what a right-hand side needs). The
    sampled table (code 1) is evaluated by the same expressions as in ``excite`` (bit for bit
    the same y, y'), without the y'' polynomial; so are the quintic tables (codes 3, 4)."""
    if code == 4:
        return _coef_yyd(t, p, tab)
    if code == 3:
        i, th, th2, th3, h, st = _table_cell(t, p, tab)
        if st != 0:
            return 0.0, 0.0, st
        y, yd, b1, b2, b3, b4, b5 = _quintic_y_yd(i, th, h, tab)
        return y, yd, 0
    if code != 1:
        y, yd, ydd, st = excite(t, code, p, tab)
        return y, yd, st
    return _cubic_yyd(t, p, tab)


@njit(cache=True, inline="always")
def excite_yyd_inline(t, code, p, tab):
    """``excite_yyd`` inlined (numba IR) where it is called in every step (routine.py): a
    coefficient table (code 4) and a cubic table (code 1) by the same expressions (the same
    y, y' bit for bit) without the call, which passes both arrays exploded into ~16 scalar
    arguments; any other code calls ``excite_yyd``."""
    if code == 4:
        return _coef_yyd(t, p, tab)
    if code == 1:
        return _cubic_yyd(t, p, tab)
    return excite_yyd(t, code, p, tab)


@njit(cache=True)
def excite_jerk(t, code, p, tab):
    """y''' at time t: the derivative of the y'' that ``excite`` returns (0 on a sampled table
    without a y'' column, where that y'' is constant in each cell)."""
    if code == 4:
        i, th, st = _coef_cell(t, p, tab)
        if st != 0:
            return 0.0
        return (2.0 * tab[i, 8] + th * (6.0 * tab[i, 9] + th * (
            12.0 * tab[i, 10] + th * 20.0 * tab[i, 11]))) / (p[1] * p[1])
    if code == 3:
        i, th, th2, th3, h, st = _table_cell(t, p, tab)
        if st != 0:
            return 0.0
        y, yd, b1, b2, b3, b4, b5 = _quintic_y_yd(i, th, h, tab)
        return (2.0 * b2 + th * (6.0 * b3 + th * (12.0 * b4 + th * 20.0 * b5))) / (h * h)
    if code == 0:
        return p[0] * p[1] * p[1] * p[1] * math.sin(p[1] * t + p[2])
    elif code == 1:
        i, th, th2, th3, h, st = _table_cell(t, p, tab)
        if st != 0 or math.isnan(tab[i, 2]):
            return 0.0
        return ((12.0 * th - 6.0) / (h * h) * tab[i, 1] + (6.0 * th - 4.0) / h * tab[i, 2]
                + (6.0 - 12.0 * th) / (h * h) * tab[i + 1, 1]
                + (6.0 * th - 2.0) / h * tab[i + 1, 2])
    y3 = 0.0
    for k in range(tab.shape[0]):
        w = tab[k, 0]
        y3 += tab[k, 1] * w * w * w * math.sin(w * t + tab[k, 2])
    return y3


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
