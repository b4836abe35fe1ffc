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
def _pivot_row(LU, k):
    """(p, |LU[p, k]|): the first row p >= k of largest modulus in column k (partial
    pivoting)."""
    p = k
    big = abs(LU[k, k])
    for i in range(k + 1, LU.shape[0]):
        if abs(LU[i, k]) > big:
            big = abs(LU[i, k])
            p = i
    return p, big


@njit(cache=True)
def _lu_solve(A, B):
    """X with A X = B (A (n, n), B (n, m)) by LU with partial pivoting (the first row of
    largest modulus); ok False when a pivot is exactly zero."""
    n = A.shape[0]
    m = B.shape[1]
    LU = A.copy()
    X = B.copy()
    for k in range(n):
        p, big = _pivot_row(LU, k)
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
        p, big = _pivot_row(LU, k)
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



# --- eigenvalues: balancing, Hessenberg reduction, Francis double-shift QR ----------------
@njit(cache=True)
def _balance(A):
    """(D^-1 A D, diag D) with D diagonal of powers of 2 (exact; the eigenvalues are
    unchanged) such that each row and column of the off-diagonal part have comparable
    1-norms."""
    n = A.shape[0]
    B = A.copy()
    dg = np.ones(n)
    done = False
    while not done:
        done = True
        for i in range(n):
            c = 0.0
            r = 0.0
            for j in range(n):
                if j != i:
                    c += abs(B[j, i])
                    r += abs(B[i, j])
            if c == 0.0 or r == 0.0 or not (math.isfinite(c) and math.isfinite(r)):
                continue
            f = 1.0
            while c * f < 0.5 * r / f and f < 1e150:
                f *= 2.0
            while c * f > 2.0 * r / f and f > 1e-150:
                f *= 0.5
            if f != 1.0 and c * f + r / f < 0.95 * (c + r):
                done = False
                dg[i] *= f
                for j in range(n):
                    B[j, i] *= f
                    B[i, j] /= f
    return B, dg


@njit(cache=True)
def _hessenberg(A):
    """Upper Hessenberg matrix similar to A (Householder reflections)."""
    n = A.shape[0]
    H = A.copy()
    v = np.zeros(n)
    for k in range(n - 2):
        s = 0.0
        for i in range(k + 1, n):
            s += H[i, k] * H[i, k]
        if s == 0.0:
            continue
        x0 = H[k + 1, k]
        alpha = -math.copysign(math.sqrt(s), x0)
        for i in range(k + 1, n):
            v[i] = H[i, k]
        v[k + 1] = x0 - alpha
        vv = s - x0 * x0 + v[k + 1] * v[k + 1]
        if vv == 0.0:
            continue
        beta = 2.0 / vv
        for j in range(n):  # from the left: rows k+1..n-1
            w = 0.0
            for i in range(k + 1, n):
                w += v[i] * H[i, j]
            w *= beta
            for i in range(k + 1, n):
                H[i, j] -= w * v[i]
        for i in range(n):  # from the right: columns k+1..n-1
            w = 0.0
            for j in range(k + 1, n):
                w += H[i, j] * v[j]
            w *= beta
            for j in range(k + 1, n):
                H[i, j] -= w * v[j]
        for i in range(k + 2, n):
            H[i, k] = 0.0
    return H


@njit(cache=True)
def _reflect(H, k, m, x, y, z, lo, hi):
    """Apply the reflection that maps (x, y[, z]) (m = 3 or 2 components) onto a multiple of
    e_1 to rows k..k+m-1 from the left and the same columns from the right, within the
    active block lo..hi."""
    s = x * x + y * y + (z * z if m == 3 else 0.0)
    if s == 0.0:
        return
    alpha = -math.copysign(math.sqrt(s), x)
    v0 = x - alpha
    v1 = y
    v2 = z if m == 3 else 0.0
    beta = 2.0 / (v0 * v0 + v1 * v1 + v2 * v2)
    for j in range(max(lo, k - 1), hi + 1):
        w = v0 * H[k, j] + v1 * H[k + 1, j]
        if m == 3:
            w += v2 * H[k + 2, j]
        w *= beta
        H[k, j] -= w * v0
        H[k + 1, j] -= w * v1
        if m == 3:
            H[k + 2, j] -= w * v2
    for i in range(lo, min(k + 3, hi) + 1):
        w = H[i, k] * v0 + H[i, k + 1] * v1
        if m == 3:
            w += H[i, k + 2] * v2
        w *= beta
        H[i, k] -= w * v0
        H[i, k + 1] -= w * v1
        if m == 3:
            H[i, k + 2] -= w * v2


@njit(cache=True)
def _eigvals(A):
    """(eigenvalues (complex, n), ok): balanced, reduced to Hessenberg form, then Francis
    double-shift QR steps with deflation at negligible subdiagonals; complex pairs come as
    (a + ib, a - ib), b > 0. ok False when 30 n steps did not deflate everything."""
    n = A.shape[0]
    ev = np.zeros(n, dtype=np.complex128)
    H = _hessenberg(_balance(A)[0])
    eps = 2.220446049250313e-16
    p = n - 1
    its = 0
    while p >= 0:
        lo = p
        while lo > 0:
            s = abs(H[lo - 1, lo - 1]) + abs(H[lo, lo])
            if abs(H[lo, lo - 1]) <= eps * s or abs(H[lo, lo - 1]) < 1e-300:
                H[lo, lo - 1] = 0.0
                break
            lo -= 1
        if lo == p:
            ev[p] = H[p, p]
            p -= 1
            its = 0
            continue
        if lo == p - 1:
            a, b, c, d = H[p - 1, p - 1], H[p - 1, p], H[p, p - 1], H[p, p]
            half = 0.5 * (a - d)
            disc = half * half + b * c
            if disc >= 0.0:
                r = half + math.copysign(math.sqrt(disc), half)
                e1 = d + r
                e2 = d - b * c / r if r != 0.0 else d + half
                ev[p - 1] = e1
                ev[p] = e2
            else:
                im = math.sqrt(-disc)
                ev[p - 1] = complex(d + half, im)
                ev[p] = complex(d + half, -im)
            p -= 2
            its = 0
            continue
        its += 1
        if its > 30 * n:
            return ev, False
        if its % 11 == 0:  # exceptional shift (breaks a cycle)
            w = abs(H[p, p - 1]) + abs(H[p - 1, p - 2])
            sh = H[p, p] + 1.5 * w
            tr = 2.0 * sh
            dt = sh * sh
        else:
            tr = H[p - 1, p - 1] + H[p, p]
            dt = H[p - 1, p - 1] * H[p, p] - H[p - 1, p] * H[p, p - 1]
        x = H[lo, lo] * H[lo, lo] + H[lo, lo + 1] * H[lo + 1, lo] - tr * H[lo, lo] + dt
        y = H[lo + 1, lo] * (H[lo, lo] + H[lo + 1, lo + 1] - tr)
        z = H[lo + 1, lo] * H[lo + 2, lo + 1]
        for k in range(lo, p - 1):
            _reflect(H, k, 3, x, y, z, lo, p)
            x = H[k + 1, k]
            y = H[k + 2, k]
            if k < p - 2:
                z = H[k + 3, k]
        _reflect(H, p - 1, 2, x, y, 0.0, lo, p)
    return ev, True


@njit(cache=True)
def _null_vector(A, lam):
    """Unit vector x with (A - lam I) x ~ 0 (inverse iteration, two steps, from ones; pivots
    below eps |A| raised to it), its largest-modulus component real and positive."""
    n = A.shape[0]
    M = A.astype(np.complex128)
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(M[i, j]))
        M[i, i] -= lam
    tiny = 2.220446049250313e-16 * max(scale, 1e-300)
    piv = np.arange(n)
    for k in range(n):
        p = k
        big = abs(M[k, k])
        for i in range(k + 1, n):
            if abs(M[i, k]) > big:
                big = abs(M[i, k])
                p = i
        if p != k:
            for j in range(n):
                M[k, j], M[p, j] = M[p, j], M[k, j]
            piv[k], piv[p] = piv[p], piv[k]
        if abs(M[k, k]) < tiny:
            M[k, k] = tiny
        for i in range(k + 1, n):
            f = M[i, k] / M[k, k]
            M[i, k] = f
            for j in range(k + 1, n):
                M[i, j] -= f * M[k, j]
    x = np.ones(n, dtype=np.complex128)
    for _ in range(2):
        b = np.empty(n, dtype=np.complex128)
        for i in range(n):
            b[i] = x[piv[i]]
        for i in range(n):  # L (unit lower)
            for q in range(i):
                b[i] -= M[i, q] * b[q]
        for i in range(n - 1, -1, -1):  # U
            for q in range(i + 1, n):
                b[i] -= M[i, q] * b[q]
            b[i] /= M[i, i]
        big = 0.0
        ib = 0
        for i in range(n):
            if abs(b[i]) > big:
                big = abs(b[i])
                ib = i
        ph = b[ib] / abs(b[ib])
        s = 0.0
        for i in range(n):
            b[i] = b[i] / ph / big
            s += b[i].real * b[i].real + b[i].imag * b[i].imag
        s = math.sqrt(s)
        for i in range(n):
            x[i] = b[i] / s
    return x


@njit(cache=True)
def _unit_columns(V, dg):
    """The columns of diag(dg) V scaled to unit 2-norm, each largest-modulus component real
    and positive."""
    n, m = V.shape
    W = V.copy()
    for j in range(m):
        s = 0.0
        big = 0.0
        ib = 0
        for i in range(n):
            W[i, j] = V[i, j] * dg[i]
            if abs(W[i, j]) > big:
                big = abs(W[i, j])
                ib = i
        ph = W[ib, j] / big
        for i in range(n):
            W[i, j] = W[i, j] / ph / big
            s += W[i, j].real * W[i, j].real + W[i, j].imag * W[i, j].imag
        s = math.sqrt(s)
        for i in range(n):
            W[i, j] = W[i, j] / s
    return W


def eigvals(A):
    """Eigenvalues (complex) of a real square matrix, in a fixed order of operations; complex
    pairs as (a + ib, a - ib) with b > 0. Raises numpy.linalg.LinAlgError when the QR
    iteration does not converge."""
    A = _f(A)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"eigvals: A must be square (n, n); got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise np.linalg.LinAlgError("Array must not contain infs or NaNs")
    ev, ok = _eigvals(A)
    if not ok:
        raise np.linalg.LinAlgError("Eigenvalues did not converge")
    return ev


def eig(A):
    """(eigenvalues, eigenvectors as columns) of a real square matrix, as ``eigvals`` and by
    inverse iteration on the balanced matrix: unit 2-norm, largest-modulus component real and
    positive."""
    A = _f(A)
    lam = eigvals(A)
    B, dg = _balance(A)
    V = np.column_stack([_null_vector(B, complex(m)) for m in lam])
    return lam, _unit_columns(V, dg)


@njit(cache=True)
def _householder_step(R, k, v):
    """Step k of a Householder QR in place: the reflection H_k = I - beta v v^T (v in v[k:])
    that maps R[k:, k] to -sign(R[k, k]) |R[k:, k]| e_k, applied to R's columns k...
    Returns beta; 0 where R[k:, k] needs no reflection (R and, where it is zero, v left)."""
    n, m = R.shape
    s = 0.0
    for i in range(k, n):
        s += R[i, k] * R[i, k]
    if s == 0.0:
        return 0.0
    x0 = R[k, k]
    alpha = -math.copysign(math.sqrt(s), x0)
    for i in range(k, n):
        v[i] = R[i, k]
    v[k] = x0 - alpha
    vv = s - x0 * x0 + v[k] * v[k]
    if vv == 0.0:
        return 0.0
    beta = 2.0 / vv
    for j in range(k, m):
        w = 0.0
        for i in range(k, n):
            w += v[i] * R[i, j]
        w *= beta
        for i in range(k, n):
            R[i, j] -= w * v[i]
    return beta


@njit(cache=True)
def _qr(A):
    """Householder QR of A (n, m): (Q (n, k), R (k, m)), k = min(n, m); R's diagonal as
    LAPACK's (the reflection maps x to -sign(x_0) |x| e_1)."""
    n, m = A.shape
    R = A.copy()
    Q = np.zeros((n, n))
    for i in range(n):
        Q[i, i] = 1.0
    v = np.zeros(n)
    for k in range(min(m, n - 1)):
        beta = _householder_step(R, k, v)
        if beta == 0.0:
            continue
        for i in range(n):  # Q <- Q H_k
            w = 0.0
            for j in range(k, n):
                w += Q[i, j] * v[j]
            w *= beta
            for j in range(k, n):
                Q[i, j] -= w * v[j]
        for i in range(k + 1, n):
            R[i, k] = 0.0
    k = min(n, m)
    return Q[:, :k].copy(), R[:k, :].copy()


def qr(A):
    """(Q, R) of A (n, m) as numpy.linalg.qr's reduced mode, in a fixed order."""
    A = _f(A)
    if A.ndim != 2:
        raise ValueError(f"qr: A must be 2-D; got {A.shape}")
    return _qr(A)


@njit(cache=True)
def _full_q_last(A):
    """The last column of the full Q of A's Householder QR (A (n, m), n > m): a unit vector
    orthogonal to A's columns."""
    n, m = A.shape
    R = A.copy()
    q = np.zeros(n)
    q[n - 1] = 1.0
    vs = np.zeros((m, n))
    betas = np.zeros(m)
    for k in range(m):
        betas[k] = _householder_step(R, k, vs[k])
    for k in range(m - 1, -1, -1):  # q = H_0 ... H_{m-1} e_{n-1}
        w = 0.0
        for i in range(k, n):
            w += vs[k, i] * q[i]
        w *= betas[k]
        for i in range(k, n):
            q[i] -= w * vs[k, i]
    return q


def null_vector(J):
    """A unit null vector of J (m, m + 1) of full rank (from the QR of J^T); its sign is
    fixed but arbitrary: callers orient it."""
    J = _f(J)
    if J.ndim != 2 or J.shape[1] != J.shape[0] + 1:
        raise ValueError(f"null_vector: J must be (m, m + 1); got {J.shape}")
    return _full_q_last(np.ascontiguousarray(J.T))


def smallest_singular_vectors(A, iterations=4):
    """(u, v): unit left and right singular vectors of the smallest singular value of a square
    A, by inverse iteration on A^T A from a fixed start (converging as (s_min / s_next)^2 per
    iteration: fast where A is nearly singular); signs fixed (the largest component of v
    positive). numpy's SVD where A is exactly singular (a zero pivot)."""
    A = _f(A)
    n = A.shape[0]
    try:
        v = np.ones(n) / math.sqrt(n)
        for _ in range(iterations):
            v = solve(A, solve(A.T, v))
            v = v / norm(v)
        u = solve(A.T, v)
        u = u / norm(u)
    except np.linalg.LinAlgError:
        U, _, Vt = np.linalg.svd(A)
        u, v = U[:, -1].copy(), Vt[-1].copy()
    if v[np.argmax(np.abs(v))] < 0:
        u, v = -u, -v
    return u, v
