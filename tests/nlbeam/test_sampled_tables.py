"""Sampled tables: the cubic and quintic Hermite interpolants converge at their orders under
refinement of the table step, and the quintic one stays within its stated bound."""
import math

import numpy as np
import pytest

import nlbeam
from nlbeam._kernels.excite import excite, excite_jerk

F = np.array([7.0, 23.0, 50.0])     # Hz
A = np.array([1.0, 0.6, 0.3])       # m
PH = np.array([0.3, 1.9, -0.7])     # rad
W = 2 * np.pi * F


def exact(t, q):
    """q-th derivative of y = sum A cos(W t + PH) at times t."""
    arg = np.outer(t, W) + PH + q * np.pi / 2
    return np.cos(arg) @ (A * W ** q)


def table(h, quintic):
    t = np.arange(0.0, 0.5 + h / 2, h)
    return nlbeam.Sampled(0.0, h, exact(t, 0), exact(t, 1), exact(t, 2),
                          yddd=exact(t, 3) if quintic else None)


def errors(tab, t):
    """Max errors of y, y', y'', y''' of the kernel's interpolant at t (excite, excite_jerk)."""
    code, p, arr = tab.kernel_args()
    got = np.array([excite(ti, code, p, arr)[:3] + (excite_jerk(ti, code, p, arr),) for ti in t])
    return np.array([np.max(np.abs(got[:, q] - exact(t, q))) for q in range(4)])


T = np.sort(np.random.default_rng(5).uniform(0.01, 0.49, 2000))


@pytest.mark.parametrize("quintic, orders", [(True, (6, 6, 5, 4)), (False, (4, 4, 3, 2))])
def test_interpolation_error_falls_at_the_order_of_the_table(quintic, orders):
    hs = (2e-3, 1e-3, 5e-4)
    e = np.array([errors(table(h, quintic), T) for h in hs])
    slopes = np.log2(e[:-1] / e[1:])          # (2 refinements, 4 derivatives)
    for q, order in enumerate(orders):
        assert np.all(np.abs(slopes[:, q] - order) < 0.35), (q, slopes[:, q], e[:, q])


def test_quintic_table_meets_its_stated_bound_and_the_noise_step():
    ymax = A.sum()
    wmax = W.max()
    for h in (2e-3, 1e-3, 5e-4):
        e = errors(table(h, True), T)
        bound = (wmax * h) ** 6 / 46080
        assert e[0] <= bound * ymax and e[1] <= bound * wmax * ymax, (h, e, bound)
        assert e[0] > 0.01 * bound * ymax   # the bound is not vacuous at these steps
    # the step a noise uses by default makes the bound its interp_tol
    import stochastic as st
    h = st.quintic_step(200.0, 1e-10)
    assert math.isclose((2 * np.pi * 200.0 * h) ** 6 / 46080, 1e-10, rel_tol=1e-12)
    assert st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1).h == h


def test_quintic_table_rejects_a_missing_ydd_and_evaluates_outside_as_error():
    t = np.arange(5) * 0.1
    with pytest.raises(ValueError, match="ydd"):
        nlbeam.Sampled(0.0, 0.1, t, t, None, yddd=t)
    tab = nlbeam.Sampled(0.0, 0.1, t, t, t, yddd=t)
    with pytest.raises(ValueError, match="outside"):
        tab.evaluate([0.5])
    same = nlbeam.Sampled.from_table(0.0, 0.1, tab.tab)
    assert same.kernel_args()[0] == tab.kernel_args()[0] == 4
    np.testing.assert_array_equal(same.evaluate([0.17])[0], tab.evaluate([0.17])[0])


def test_coefficient_table_gives_the_node_tables_values_bit_for_bit(monkeypatch):
    """The kernels get a quintic table as per-cell coefficients (code 4, two Horner sums per
    lookup); they must give exactly what the node table (code 3, coefficients solved at every
    lookup) gives, at random times and at the nodes, and a table above COEF_MAX_NODES goes
    as nodes."""
    from nlbeam import excitation as ex
    from nlbeam._kernels.excite import excite_yyd
    tab = table(1e-3, True)
    code, p, coef = tab.kernel_args()
    assert code == 4 and coef.shape == (tab.tab.shape[0] - 1, 12)
    t = np.concatenate([T, np.arange(tab.tab.shape[0]) * 1e-3])
    t = t[t <= tab.time_span()[1]]
    for f in (excite, excite_jerk, excite_yyd):
        got = np.array([f(ti, 4, p, coef) for ti in t])
        ref = np.array([f(ti, 3, p, tab.tab) for ti in t])
        np.testing.assert_array_equal(got, ref)
    assert excite(tab.time_span()[1] + 1e-3, 4, p, coef)[3] != 0  # outside: an error status
    monkeypatch.setattr(ex, "COEF_MAX_NODES", tab.tab.shape[0] - 1)
    big = nlbeam.Sampled.from_table(0.0, 1e-3, tab.tab)
    assert big.kernel_args()[0] == 3
    np.testing.assert_array_equal(big.evaluate(T[:50]), tab.evaluate(T[:50]))
