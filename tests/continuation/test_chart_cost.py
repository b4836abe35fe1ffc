"""What the stability chart's cost cuts keep exact: the extended system's evaluation kept for
the same unknowns gives the same residual and Jacobian as a fresh system for one shooting
evaluation less; the test function's row over the shooting states from one evaluation agrees
with central differences of the test function (one evaluation per state); a bifurcation of
an orbit taken m times round (a branch of order m k along an orbit of order k) is recognised
as a point of the order-k curve, by the multiplier power rule mu -> mu^m, and nothing else
is; a curve trace whose start never moves ends after START_HALVINGS halvings."""
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
    # not 2 + 3: the residual's evaluation kept (3: the test function's row over the states
    # from one evaluation, the frequency and parameter columns one each)
    assert a.n_evaluations - n0 == 1 + 3
    ref = b.evaluate(z.copy())
    assert np.array_equal(res.G, ref.G) and np.array_equal(full.G, ref.G)
    assert np.array_equal(full.J, ref.J)
    n1 = a.n_evaluations
    a.renew_borders(z)  # at the point just evaluated with its Jacobian: kept as well
    assert a.n_evaluations == n1
    z2 = z.copy()
    z2[a.n] += 1e-4  # other unknowns: evaluated anew
    assert not np.array_equal(a.evaluate(z2, jac=False).G, res.G)


@pytest.mark.parametrize("model, A, f, kind, segments", [
    (nlbeam.Duffing(), 0.3, 0.2, "fold", 1),
    (nlbeam.Duffing(), 0.3, 0.2, "period-doubling", 3),
    (nlbeam.Duffing(), 0.3, 0.2, "fold", 4),
    (nlbeam.BeamImpact(), 1e-4, 58.0, "period-doubling", 2),  # impacts; segment in contact
    (nlbeam.BeamImpact(), 1e-4, 40.0, "fold", 1),
])
def test_test_function_row_from_one_evaluation_agrees_with_differences(model, A, f, kind,
                                                                       segments):
    """CurveSystem._g_row_states: dg over the shooting states (all segments) from one more
    evaluation (symmetric second derivatives of the flow, chained over the segments), against
    central differences of g, one pair of evaluations per state; and a Jacobian costs 3
    evaluations whatever the number of states."""
    sol = C.periodic_solution(model, A, f, segments=segments, error=False)
    s = CurveSystem(model, kind, 1, A, f, sol.state0, "amplitude", Integrator(),
                    segments=segments)
    z = s.z0
    n0 = s.n_evaluations
    J = s.evaluate(z).J
    assert s.n_evaluations - n0 == 3 and s.n == 2 * model.n_dof * segments
    h = 1e-5
    ref = np.empty(s.n)
    for i in range(s.n):
        e = np.zeros(s.D)
        e[i] = h
        ref[i] = (s.evaluate(z + e, jac=False).G[-1] - s.evaluate(z - e, jac=False).G[-1]) / (2 * h)
    assert np.max(np.abs(J[s.n, :s.n] - ref)) <= 1e-4 * np.max(np.abs(ref))
    # the other rows and columns: as before (variational dR/du; forward differences)
    assert np.max(np.abs(J[:s.n, :s.n] - s.prob.evaluate(*s.unpack(z)[:2], jac_p=False).Ju
                         * s.prob.scale_u[None, :] / s.prob.scale_u[:, None])) < 1e-12
    # the tracer's fallback (row_from_one False): one difference per unknown
    s.row_from_one = False
    n0 = s.n_evaluations
    J1 = s.evaluate(z + 0.0).J
    assert s.n_evaluations - n0 == 1 + s.D  # the point itself, then one per unknown
    assert np.max(np.abs(J1[s.n, :s.n] - ref)) <= 1e-3 * np.max(np.abs(ref))
    np.testing.assert_array_equal(J1[:, s.n:], J[:, s.n:])  # the same other columns


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


class _Stuck:
    """A curve system whose corrector never converges (a start at a non-smooth point)."""

    kind, grazing, one_row_kind, row_from_one = "fold", False, False, True
    n, D, n_evaluations = 2, 4, 0


def test_a_start_that_never_moves_ends_after_start_halvings(monkeypatch):
    """_Tracer.trace: a trace with no accepted step ends 'step underflow' once its first step
    has been halved START_HALVINGS times (11 corrector calls), not at ds_min (16 calls from
    ds = 0.05 to below 1e-6, as without the rule)."""
    from continuation import curve as CU
    from continuation._newton import ConvergenceError

    calls = []

    def never(self, *a, **k):
        calls.append(1)
        raise ConvergenceError("stuck")

    monkeypatch.setattr(CU._Tracer, "correct", never)
    tr = CU._Tracer(_Stuck(), (1.0, 10.0), (0.1, 1.0), (), 0.05, 1e-6, 0.3, 0.3, 100, 1e-9,
                    12)
    p0 = CU._Pt(types.SimpleNamespace(z=np.zeros(4), J=None), np.array([0.0, 0.0, 1.0, 0.0]))
    pts, why = tr.trace(p0, lambda *a: None)
    assert (pts, why) == ([], "step underflow")
    assert len(calls) == 11  # the first step, then one per halving
    assert CU.START_HALVINGS == 10
    calls.clear()
    monkeypatch.setattr(CU, "START_HALVINGS", 10 ** 9)
    tr.trace(p0, lambda *a: None)
    assert len(calls) == 16
