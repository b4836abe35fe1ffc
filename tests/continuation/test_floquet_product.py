"""Multipliers of a product of segment monodromies keep every multiplier's digits in product
form (continuation._floquet), where the eigenvalues of the formed product lose the small ones
of a strongly unstable orbit. Products are built with known eigenvalues: M_j = P_j D_j
P_{j-1}^-1 with P_m = P_0, so M_m ... M_1 = P_0 (D_m ... D_1) P_0^-1."""
import numpy as np
import pytest

from continuation._floquet import SPREAD, multipliers


def _segments(eigs, m, seed=1):
    rng = np.random.default_rng(seed)
    n = len(eigs)
    P = [np.eye(n) + 0.3 * rng.standard_normal((n, n)) for _ in range(m)] + []
    P.append(P[0])
    root = np.abs(eigs) ** (1.0 / m)
    out = []
    for j in range(m):
        D = np.diag(root * (np.sign(eigs) if j == 0 else 1.0))
        out.append(P[j + 1] @ D @ np.linalg.inv(P[j]))
    return out


def _formed(Ms):
    M = np.eye(Ms[0].shape[0])
    for Mj in Ms:
        M = Mj @ M
    return M


@pytest.mark.parametrize("eigs, m", [([2e56, 6e8], 128), ([2e56, 6e8, -3e-2, 1e-3], 64),
                                     ([-4e30, 2.0, 0.5], 32)])
def test_every_multiplier_keeps_its_digits(eigs, m):
    eigs = np.array(eigs)
    Ms = _segments(eigs, m)
    ref = eigs[np.argsort(-np.abs(eigs))]
    mu = multipliers(Ms)
    assert np.max(np.abs(mu - ref) / np.abs(ref)) < 1e-11
    # the formed product's eigenvalues miss the second multiplier by orders of magnitude
    plain = np.linalg.eigvals(_formed(Ms))
    plain = plain[np.argsort(-np.abs(plain))]
    assert abs(plain[1] - ref[1]) / abs(ref[1]) > 1e3


def test_a_complex_dominant_pair_is_deflated_together():
    # a rotation by 0.7 rad scaled by 1e40 over the period, with a stable real pair
    m, n = 16, 4
    th = 0.7
    big = 1e40 ** (1.0 / m) * np.array([[np.cos(th / m), -np.sin(th / m)],
                                        [np.sin(th / m), np.cos(th / m)]])
    rng = np.random.default_rng(3)
    P = [np.eye(n) + 0.2 * rng.standard_normal((n, n)) for _ in range(m)]
    P.append(P[0])
    small = np.diag([0.3 ** (1.0 / m), 0.01 ** (1.0 / m)])
    D = np.block([[big, np.zeros((2, 2))], [np.zeros((2, 2)), small]])
    Ms = [P[j + 1] @ D @ np.linalg.inv(P[j]) for j in range(m)]
    mu = multipliers(Ms)
    ref = np.array([1e40 * np.exp(1j * th), 1e40 * np.exp(-1j * th), 0.3, 0.01])
    assert np.allclose(np.abs(mu), np.abs(ref), rtol=1e-11)
    assert np.allclose(sorted(np.angle(mu[:2])), [-th, th], atol=1e-11)
    assert np.allclose(mu[2:].real, [0.3, 0.01], rtol=1e-10)


def test_moderate_spread_keeps_the_formed_product_bit_for_bit():
    from nlbeam import _linalg as la  # the continuation's machine-independent routines
    Ms = _segments(np.array([50.0, 0.02]), 8)
    assert 50.0 / 0.02 < SPREAD
    M = np.eye(2)
    for Mj in Ms:
        M = la.matmul(Mj, M)
    plain = la.eigvals(M)
    plain = plain[np.argsort(-np.abs(plain), kind="stable")]
    assert np.array_equal(multipliers(Ms), plain)
