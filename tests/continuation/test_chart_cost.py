"""What the stability chart's cost cuts keep exact: the extended system's evaluation kept for
the same unknowns gives the same residual and Jacobian as a fresh system for one shooting
evaluation less; a bifurcation of an orbit taken m times round (a branch of order m k along an
orbit of order k) is recognised as a point of the order-k curve, by the multiplier power rule
mu -> mu^m, and nothing else is."""
import types

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation.chart import _duplicate
from continuation.extended import CurveSystem
from continuation.shooting import Integrator


def test_kept_evaluation_gives_a_fresh_systems_residual_and_jacobian():
    m = nlbeam.Duffing()  # x'' + 0.1 x' + x + x^3 = F cos(2 pi f t)
    sol = C.periodic_solution(m, 0.3, 0.2, error=False)
    a = CurveSystem(m, "fold", 1, 0.3, 0.2, sol.state0, "amplitude", Integrator())
    b = CurveSystem(m, "fold", 1, 0.3, 0.2, sol.state0, "amplitude", Integrator())
    z = a.z0 + 1e-3  # off the curve: a residual that is not zero
    n0 = a.n_evaluations
    res = a.evaluate(z, jac=False)  # the corrector's last iterate
    full = a.evaluate(z)  # then the point's Jacobian at the same unknowns
    assert a.n_evaluations - n0 == 1 + a.D  # not 2 + D: the residual's evaluation kept
    ref = b.evaluate(z.copy())
    assert np.array_equal(res.G, ref.G) and np.array_equal(full.G, ref.G)
    assert np.array_equal(full.J, ref.J)
    n1 = a.n_evaluations
    a.renew_borders(z)  # at the point just evaluated with its Jacobian: kept as well
    assert a.n_evaluations == n1
    z2 = z.copy()
    z2[a.n] += 1e-4  # other unknowns: evaluated anew
    assert not np.array_equal(a.evaluate(z2, jac=False).G, res.G)


def _curve(kind, order, f, state, A0=1e-4):
    return types.SimpleNamespace(
        kind=kind, order=order, frequency=np.array([0.9 * f, f]), values=np.array([2 * A0, A0]),
        exact=np.array([False, True]), state0=np.array([state * 1.1, state]),
        at=lambda v: np.array([f]) if v == A0 else np.array([]))


@pytest.mark.parametrize("ckind, corder, bkind, border, moved, same", [
    ("fold", 1, "fold", 2, 0.0, True),  # mu = 1 -> mu^2 = 1
    ("fold", 1, "fold", 3, 0.0, True),
    ("fold", 1, "fold", 2, 1e-3, False),  # another orbit at the same frequency
    ("fold", 1, "period-doubling", 2, 0.0, False),  # 1^2 is not -1
    ("period-doubling", 1, "period-doubling", 3, 0.0, True),  # (-1)^3 = -1
    ("period-doubling", 1, "period-doubling", 2, 0.0, False),  # (-1)^2 = 1: a fold
    ("period-doubling", 1, "fold", 2, 0.0, True),
    ("grazing", 1, "grazing", 2, 0.0, True),  # the same touch of the stop
    ("grazing", 2, "grazing", 3, 0.0, False),  # 3 is not a multiple of 2
    ("fold", 1, "grazing", 2, 0.0, False),
])
def test_a_bifurcation_of_a_repeated_orbit_is_the_lower_orders_curve(ckind, corder, bkind,
                                                                     border, moved, same):
    s = np.array([1e-4, -2e-3])
    c = _curve(ckind, corder, 9.9, s)
    bf = types.SimpleNamespace(kind=bkind, order=border, frequency=9.9 * (1 + 1e-7),
                               state0=s * (1 + moved))
    assert (_duplicate([c], bf, 1e-4) is c) is same
    far = types.SimpleNamespace(kind=bkind, order=border, frequency=9.9 * 1.01,
                                state0=s * (1 + moved))
    assert _duplicate([c], far, 1e-4) is None  # another frequency: never
