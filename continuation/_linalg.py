"""Small dense linear algebra in a fixed order of operations, the same on every machine.

numpy's ``solve``, ``norm``, ``@`` and ``dot`` go through the BLAS/LAPACK kernels OpenBLAS
picks for the CPU at run time (OPENBLAS_CORETYPE): with or without fused multiply-adds, other
blockings and summation orders, so their last bits differ between machines. A continuation
decides (step accepted, corner crossed, bifurcation found) on numbers carrying those bits, so
the same scene traced a different diagram with OpenBLAS's Haswell kernels than with its
SkylakeX ones (paper diagram, A = 0.1 mm: 1877 against 1712 points). The routines here are
numba-compiled plain loops (no fastmath, so no contraction into fused multiply-adds, no
reassociation) for the small matrices of the continuation (a few to a few hundred rows).
Inputs are float arrays; results are new arrays.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _lu_solve(A, B):
    """X with A X = B (A (n, n), B (n, m)) by LU with partial pivoting (the first row of
    largest modulus); ok False when a pivot is exactly zero."""
    n = A.shape[0]
    m = B.shape[1]
    LU = A.copy()
    X = B.copy()
    for k in range(n):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                big = abs(LU[i, k])
                p = i
        if big == 0.0 or not math.isfinite(big):
            return X, big == 0.0
        if p != k:
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
            for j in range(m):
                X[k, j], X[p, j] = X[p, j], X[k, j]
        piv = LU[k, k]
        for i in range(k + 1, n):
            f = LU[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] = LU[i, j] - f * LU[k, j]
                for j in range(m):
                    X[i, j] = X[i, j] - f * X[k, j]
    for j in range(m):
        for i in range(n - 1, -1, -1):
            s = X[i, j]
            for q in range(i + 1, n):
                s = s - LU[i, q] * X[q, j]
            X[i, j] = s / LU[i, i]
    return X, False


@njit(cache=True)
def _lu_det(A):
    """(sign, det) of A by LU with partial pivoting: sign +1, -1 or 0 (a zero pivot); det the
    product of the pivots (may overflow where the sign does not)."""
    n = A.shape[0]
    LU = A.copy()
    sign = 1.0
    det = 1.0
    for k in range(n):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                big = abs(LU[i, k])
                p = i
        if big == 0.0:
            return 0.0, 0.0
        if p != k:
            sign = -sign
            det = -det
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
        piv = LU[k, k]
        det = det * piv
        if piv < 0:
            sign = -sign
        for i in range(k + 1, n):
            f = LU[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] = LU[i, j] - f * LU[k, j]
    return sign, det


@njit(cache=True)
def _matmul(A, B):
    n, k = A.shape
    m = B.shape[1]
    C = np.zeros((n, m))
    for i in range(n):
        for j in range(m):
            s = 0.0
            for q in range(k):
                s = s + A[i, q] * B[q, j]
            C[i, j] = s
    return C


@njit(cache=True)
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s = s + a[i] * b[i]
    return s


@njit(cache=True)
def _norm(a):
    """2-norm, scaled by the largest modulus (no overflow or underflow of the squares)."""
    big = 0.0
    for i in range(a.shape[0]):
        if abs(a[i]) > big or not math.isfinite(a[i]):
            big = abs(a[i])
    if big == 0.0 or not math.isfinite(big):
        return big
    s = 0.0
    for i in range(a.shape[0]):
        r = a[i] / big
        s = s + r * r
    return big * math.sqrt(s)


@njit(cache=True)
def _norm_rows(A):
    out = np.empty(A.shape[0])
    for i in range(A.shape[0]):
        out[i] = _norm(A[i])
    return out


def _f(a):
    return np.ascontiguousarray(a, dtype=float)


def solve(A, b):
    """x with A x = b (A (n, n); b (n,) or (n, m)); raises numpy.linalg.LinAlgError when A is
    exactly singular (a zero pivot), as numpy.linalg.solve does."""
    A, b = _f(A), _f(b)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or b.shape[0] != A.shape[0]:
        raise ValueError(f"solve: A must be square (n, n) and b (n,) or (n, m); got A "
                         f"{A.shape}, b {b.shape}")
    X, singular = _lu_solve(A, b.reshape(len(b), -1))
    if singular:
        raise np.linalg.LinAlgError("Singular matrix")
    return X.reshape(b.shape)


def det_sign(A):
    """Sign of det A (+1.0, -1.0, or 0.0 when a pivot is exactly zero)."""
    return float(_lu_det(_f(A))[0])


def det(A):
    """Determinant of A (n, n) by LU with partial pivoting."""
    return float(_lu_det(_f(A))[1])


def inv(A):
    """Inverse of A (n, n); raises numpy.linalg.LinAlgError when A is exactly singular."""
    A = _f(A)
    return solve(A, np.eye(A.shape[0]))


def matmul(A, B):
    """A @ B for 2-D or 1-D float arrays (the same shapes as numpy's @)."""
    A, B = _f(A), _f(B)
    if A.ndim == 1 and B.ndim == 1:
        return _dot(A, B)
    A2 = A[None, :] if A.ndim == 1 else A
    B2 = B[:, None] if B.ndim == 1 else B
    if A2.shape[1] != B2.shape[0]:
        raise ValueError(f"matmul: shapes {A.shape} and {B.shape} do not match")
    C = _matmul(A2, B2)
    if A.ndim == 1:
        return C[0]
    if B.ndim == 1:
        return C[:, 0]
    return C


def dot(a, b):
    """Inner product of two 1-D float arrays, summed in index order."""
    return float(_dot(_f(a), _f(b)))


def norm(a):
    """Euclidean norm of a 1-D float array; of each row of a 2-D one."""
    a = _f(a)
    if a.ndim == 2:
        return _norm_rows(a)
    return float(_norm(a.ravel()))
