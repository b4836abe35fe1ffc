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

Each factor still costs the small multipliers about eps times its own spread (the ratio of
its largest to its smallest growth), so a product of few factors over a large spread is not
enough either: ``multipliers`` asks for a product of more factors, over shorter sub-intervals
of the period (``subdivide``), until every factor spreads by at most about FACTOR_SPREAD.
"""
from __future__ import annotations

import math

import numpy as np

from nlbeam import _linalg as la


#: the formed product is used unless its largest multiplier exceeds this times its smallest
SPREAD = 1e8
#: the spread one factor of the product form may carry: the smallest multiplier then keeps
#: about eps * FACTOR_SPREAD * (number of factors) relative (1e-11 with 256 factors)
FACTOR_SPREAD = 100.0
#: the most factors (sub-intervals of the period) asked for: enough for a spread of 1e512
MAX_FACTORS = 256
#: at most this many rounds of subdividing: each round's multipliers give the next round's
#: spread (the first, from the formed product, stops near 1/eps)
ROUNDS = 4


def _dominant_basis(M):
    """Orthonormal (n, k) basis of the invariant subspace of M's largest multiplier (k = 1) or
    complex pair (k = 2)."""
    lam, V = la.eig(M)
    i = int(np.argmax(np.abs(lam)))
    v = V[:, i]
    if abs(lam[i].imag) > 0:
        B = np.column_stack([v.real, v.imag])
    else:
        B = v.real[:, None]
    return la.qr(B)[0]


def product_eigenvalues(Ms):
    """The eigenvalues of M_m ... M_1 (Ms = [M_1, ..., M_m], square, applied in that order),
    each to about eps relative to itself; unsorted."""
    n = Ms[0].shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex)
    M = np.eye(n)
    for Mj in Ms:
        M = la.matmul(Mj, M)
    if n == 1:
        return np.array([np.prod([float(Mj[0, 0]) for Mj in Ms])], dtype=complex)
    B = _dominant_basis(M)
    k = B.shape[1]
    Q0 = la.qr(np.column_stack([B, np.eye(n)]))[0][:, :n]
    Q = Q0
    Rs = []
    for Mj in Ms:
        Q, R = la.qr(la.matmul(Mj, Q))
        Rs.append(R)
    C = la.matmul(Q0.T, Q)
    lead = np.eye(k)
    for R in Rs:
        lead = la.matmul(R[:k, :k], lead)
    mu_lead = la.eigvals(la.matmul(C[:k, :k], lead)).astype(complex)
    if n == k:
        return mu_lead
    rest = [R[k:, k:] for R in Rs] + [C[k:, k:]]
    return np.concatenate([mu_lead, product_eigenvalues(rest)])


def factors_needed(spread):
    """The number of factors (sub-intervals of the period) that keep every multiplier of a
    product whose multipliers spread by ``spread`` (largest / smallest modulus) to about
    eps * FACTOR_SPREAD relative: each factor then spreads by at most FACTOR_SPREAD."""
    if not spread > SPREAD:
        return 1
    if not math.isfinite(spread):
        return MAX_FACTORS
    return min(MAX_FACTORS, math.ceil(math.log(spread) / math.log(FACTOR_SPREAD)))


def _spread(mu):
    a = np.abs(mu)
    if not np.all(np.isfinite(a)):
        return None
    return a.max() / a.min() if a.min() > 0 else math.inf


def _sorted(mu):
    if np.all(mu.imag == 0):
        mu = mu.real
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def multipliers(Ms, M=None, subdivide=None):
    """Floquet multipliers (sorted by modulus, largest first) of the segment monodromies Ms
    (M: their product, if formed already): the eigenvalues of the formed product, unless the
    largest modulus exceeds SPREAD times the smallest; then ``product_eigenvalues`` of a
    product of Ms (several segments), then, while the spread those multipliers show needs
    more than ``factors_needed(spread)`` factors, of ``subdivide(k)`` (a callable: the
    transition matrices of the same orbit over k sub-intervals of each segment, in order)
    with k raised to what the spread needs (at most ROUNDS rounds; without ``subdivide``,
    Ms alone)."""
    if M is None:
        M = np.eye(Ms[0].shape[0])
        for Mj in Ms:
            M = la.matmul(Mj, M)
    mu = la.eigvals(M)
    spread = _spread(mu)
    if spread is None or not spread > SPREAD:
        return mu[np.argsort(-np.abs(mu), kind="stable")]
    m = len(Ms)
    if m > 1:
        mu = product_eigenvalues(list(Ms))
        spread = _spread(mu)
    pieces = 1
    for _ in range(ROUNDS):
        need = factors_needed(spread) if spread is not None else 1
        if subdivide is None or need <= m * pieces or m * pieces >= MAX_FACTORS:
            break
        pieces = max(pieces + 1, math.ceil(need / m))
        mu = product_eigenvalues(list(subdivide(pieces)))
        spread = _spread(mu)
    return _sorted(mu)
