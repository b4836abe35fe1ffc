"""Floquet multipliers of a product of segment monodromies M = M_m ... M_1 in product form.

The eigenvalues of the formed product lose the small multipliers of a strongly unstable
orbit: they come out with an absolute error of about eps |mu_max| (|mu_max| = 2e56 leaves no
digit of a multiplier of 6e8). Here the dominant multiplier (or complex pair) is deflated
factor by factor: an orthonormal basis Q_0 whose first k columns span its invariant subspace
is carried through the segments by QR steps M_j Q_{j-1} = Q_j R_j, so that
Q_0^T M Q_0 = C R_m ... R_1 with every R_j upper triangular and C = Q_0^T Q_m orthogonal
and block-diagonal up to round-off. Setting C's off-diagonal blocks to zero perturbs one
factor by about eps, which moves each multiplier by about eps times itself (not eps |mu_max|);
the k leading multipliers are those of C_11 R_11, the others those of the shorter product
C_22 R_m,22 ... R_1,22, deflated again.
"""
from __future__ import annotations

import numpy as np

#: the formed product is used unless its largest multiplier exceeds this times its smallest
SPREAD = 1e8


def _dominant_basis(M):
    """Orthonormal (n, k) basis of the invariant subspace of M's largest multiplier (k = 1) or
    complex pair (k = 2)."""
    lam, V = np.linalg.eig(M)
    i = int(np.argmax(np.abs(lam)))
    v = V[:, i]
    if abs(lam[i].imag) > 0:
        B = np.column_stack([v.real, v.imag])
    else:
        B = v.real[:, None]
    return np.linalg.qr(B)[0]


def product_eigenvalues(Ms):
    """The eigenvalues of M_m ... M_1 (Ms = [M_1, ..., M_m], square, applied in that order),
    each to about eps relative to itself; unsorted."""
    n = Ms[0].shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex)
    M = np.eye(n)
    for Mj in Ms:
        M = Mj @ M
    if n == 1:
        return np.array([np.prod([float(Mj[0, 0]) for Mj in Ms])], dtype=complex)
    B = _dominant_basis(M)
    k = B.shape[1]
    Q0 = np.linalg.qr(np.column_stack([B, np.eye(n)]))[0][:, :n]
    Q = Q0
    Rs = []
    for Mj in Ms:
        Q, R = np.linalg.qr(Mj @ Q)
        Rs.append(R)
    C = Q0.T @ Q
    lead = np.eye(k)
    for R in Rs:
        lead = R[:k, :k] @ lead
    mu_lead = np.linalg.eigvals(C[:k, :k] @ lead).astype(complex)
    if n == k:
        return mu_lead
    rest = [R[k:, k:] for R in Rs] + [C[k:, k:]]
    return np.concatenate([mu_lead, product_eigenvalues(rest)])


def multipliers(Ms, M=None):
    """Floquet multipliers (sorted by modulus, largest first) of the segment monodromies Ms
    (M: their product, if formed already): the eigenvalues of the formed product, unless
    there are several segments and the largest modulus exceeds SPREAD times the smallest;
    then ``product_eigenvalues``."""
    if M is None:
        M = np.eye(Ms[0].shape[0])
        for Mj in Ms:
            M = Mj @ M
    mu = np.linalg.eigvals(M)
    a = np.abs(mu)
    if len(Ms) > 1 and np.all(np.isfinite(a)) and not a.max() <= SPREAD * a.min():
        mu = product_eigenvalues(list(Ms))
        if np.all(mu.imag == 0):
            mu = mu.real
    return mu[np.argsort(-np.abs(mu), kind="stable")]
