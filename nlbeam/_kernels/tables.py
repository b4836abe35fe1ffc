"""Kernel tables built once from an excitation's samples: the per-cell coefficients of a
quintic Hermite table (code 4 of ``excite.py``), so that a lookup is two Horner sums instead
of solving for the twelve coefficients at every evaluation."""
from .excite import _quintic
from .hook import njit


@njit(cache=True)
def quintic_coefficients(tab, h, out):
    """out[i] = (a0 .. a5, b0 .. b5), i = 0 .. n - 2: the quintic Hermite polynomials in th in
    [0, 1] of cell i of the table ``tab`` (n, 4) = (y, y', y'', y''') on a grid of step h (s),
    y through (y, y', y'') and y' through (y', y'', y''') at both ends; the very numbers the
    code-3 evaluation computes per lookup (``excite._quintic``). Returns 0."""
    for i in range(tab.shape[0] - 1):
        a0, a1, a2, a3, a4, a5 = _quintic(tab[i, 0], tab[i, 1], tab[i, 2], tab[i + 1, 0],
                                          tab[i + 1, 1], tab[i + 1, 2], h)
        b0, b1, b2, b3, b4, b5 = _quintic(tab[i, 1], tab[i, 2], tab[i, 3], tab[i + 1, 1],
                                          tab[i + 1, 2], tab[i + 1, 3], h)
        out[i, 0] = a0
        out[i, 1] = a1
        out[i, 2] = a2
        out[i, 3] = a3
        out[i, 4] = a4
        out[i, 5] = a5
        out[i, 6] = b0
        out[i, 7] = b1
        out[i, 8] = b2
        out[i, 9] = b3
        out[i, 10] = b4
        out[i, 11] = b5
    return 0
