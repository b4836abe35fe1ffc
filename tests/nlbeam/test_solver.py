"""nlbeam.solver.Solver: the step decisions of integrate, flow, FlowMap and continuation's
periodic flows, each against its stated rule (closed forms and exact step counts)."""
import math
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
import nlbeam.solver
from nlbeam.integrate import FlowMap
from nlbeam.solver import Solver, period_step, phase_step

PAPER = nlbeam.BeamImpact.paper()
F_N = math.sqrt(PAPER.k / PAPER.m) / (2 * math.pi)  # 22.23 Hz, the linear natural frequency


@pytest.mark.parametrize("method, steps", [("rk4", 100), ("rk2", 400), ("adaptive", 32)])
def test_default_dt_is_a_fixed_fraction_of_the_fastest_period(method, steps):
    # excitation above the natural frequency: its period sets the step
    ex = nlbeam.Harmonic(1e-4, 40.0)
    dt = Solver(method).default_dt(PAPER, ex)
    assert dt == 1.0 / (steps * 40.0)
    assert nlbeam.default_dt(PAPER, ex, method) == dt
    tr = nlbeam.integrate(PAPER, ex, 0.01, method=method, store_every=0, warn=False)
    assert tr.dt == dt
    # excitation below it: the natural period sets the step
    slow = nlbeam.Harmonic(1e-4, 5.0)
    assert Solver(method).default_dt(PAPER, slow) == pytest.approx(1.0 / (steps * F_N),
                                                                   rel=1e-12)


def test_default_steps_per_contact():
    assert [Solver(m).contact_steps() for m in ("rk2", "rk4", "adaptive")] == [96, 32, 32]
    assert Solver("rk4", steps_per_contact=64).contact_steps() == 64.0


def test_a_flow_takes_a_whole_number_of_steps():
    duff = nlbeam.Duffing(m=1.0, b=0.2, k=40.0, k3=10.0)  # no contacts: steps are the grid's
    ex = nlbeam.Harmonic(2.0, 1.2)
    for duration, dt in ((1.0, 0.01), (1.0, 0.3), (0.37, 1e-3), (2.5, 0.0071)):
        n = math.ceil(duration / dt - 1e-9)
        h = Solver("rk4").whole_step(duration, dt)
        assert h == duration / n and h <= dt
        fl = nlbeam.flow(duff, ex, [0.1, 0.0], 0.0, duration, dt=dt)
        assert fl.n_steps == n
    assert Solver("rk4").whole_step(1.0, 0.01) == 0.01  # already whole: unchanged
    assert Solver("adaptive").whole_step(1.0, 0.3) == 0.3  # output spacing: unchanged


def test_steps_per_excitation_period_of_periodic_orbits():
    # 100 (rk4) / 400 (rk2) per period, times the power of two at or above f_n / f, / dt_scale
    s4, s2 = Solver("rk4"), Solver("rk2")
    cases = [(44.0, 1.0, 100), (F_N * 1.01, 1.0, 100), (20.0, 1.0, 200), (F_N / 2, 1.0, 200),
             (5.0, 1.0, 800), (44.0, 0.5, 200), (44.0, 3.0, 34)]
    for f, scale, expected in cases:
        assert s4.steps_per_excitation_period(PAPER, f, scale) == expected, (f, scale)
        assert C.Integrator(dt_scale=scale).steps_per_period(PAPER, f) == expected
    assert s2.steps_per_excitation_period(PAPER, 44.0) == 400
    assert C.Integrator(method="rk2").steps_per_period(PAPER, 20.0) == 800
    assert Solver("adaptive").steps_per_excitation_period(PAPER, 44.0) == 0
    # the step of a span of excitation periods: rounded to whole steps, at least one
    assert period_step(44.0, 100) == 1.0 / 4400.0 and period_step(44.0, 0) is None
    dur = 0.304 / 44.0
    assert phase_step(dur, 100 * 0.304) == dur / 30
    assert phase_step(dur, 0.2) == dur and phase_step(dur, 0) == dur


def _stiff_two_dof():
    """Two DOFs, the stiff one at 1000 rad/s: the RK4 limit is 2 sqrt 2 / 1000 s."""
    return nlbeam.System(np.eye(2), np.zeros((2, 2)), np.diag([1.0, 1e6]),
                         excitation_kind="force", y_load=[1.0, 0.0])


@pytest.mark.parametrize("method, limit", [("rk4", 2 * math.sqrt(2) / 1000), ("rk2", 2e-3)])
def test_the_stability_check_names_dt_and_the_limit(method, limit):
    model = _stiff_two_dof()
    ex = nlbeam.Harmonic(1.0, 1.0)
    Solver(method).check_stable(model, ex, 0.99 * limit)  # inside: no error
    with pytest.raises(ValueError, match=rf"^dt: .* stability limit {limit:.4g} s of '{method}'"):
        Solver(method).check_stable(model, ex, 1.01 * limit)
    with pytest.raises(ValueError, match="^dt:"):
        nlbeam.integrate(model, ex, 0.1, method=method, dt=1.01 * limit)
    with pytest.raises(ValueError, match="^dt:"):
        FlowMap(model, ex, method=method, dt=0.5 * limit)([0.0] * 4, 0.0, 0.1, dt=1.01 * limit)
    Solver("adaptive").check_stable(model, ex, 1.0)  # no limit for the adaptive method


@pytest.mark.parametrize("kwargs, name", [
    ({"method": "euler"}, "method"), ({"dt": 0.0}, "dt"), ({"dt": np.inf}, "dt"),
    ({"steps_per_contact": -1}, "steps_per_contact"),
    ({"method": "adaptive", "rtol": 0.0}, "rtol"), ({"method": "adaptive", "atol": -1.0}, "atol"),
])
def test_bad_solver_settings_name_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name}:"):
        Solver(**kwargs)
    if name in ("steps_per_contact", "rtol", "atol"):
        with pytest.raises(ValueError, match=rf"^{name}:"):
            C.Integrator(**kwargs)


def test_start_in_contact_takes_the_penetration_rate_as_delta_minus():
    # paper model, y = A cos(2 pi f t): at t = 0, y = A, y' = 0, so delta = x - A, delta' = v
    A, f = 1e-4, 44.0
    ex = nlbeam.Harmonic(A, f)
    geo = PAPER.element_geometry()
    el = Solver.event_elements(PAPER)
    assert el == [0]
    start = Solver.start_contact
    assert np.array_equal(start(geo, np.array([2e-4, 0.05]), A, 0.0, el), [[1.0, 0.05]])
    # receding or at rest: the floor
    floor = nlbeam.solver.VMINUS_FLOOR
    assert floor == 1e-6
    assert np.array_equal(start(geo, np.array([2e-4, -0.02]), A, 0.0, el), [[1.0, floor]])
    assert np.array_equal(start(geo, np.array([2e-4, 0.0]), A, 0.0, el), [[1.0, floor]])
    # outside the stop: out of contact
    assert np.array_equal(start(geo, np.array([0.0, 0.05]), A, 0.0, el), [[0.0, 0.0]])
    # flow and integrate apply it: the same result as with that contact state given
    for s0, dm in (([2e-4, 0.05], 0.05), ([2e-4, -0.02], floor)):
        ref = nlbeam.flow(PAPER, ex, s0, 0.0, 0.5 / f, disc0=[[1.0, dm]])
        got = nlbeam.flow(PAPER, ex, s0, 0.0, 0.5 / f)
        assert np.array_equal(got.state, ref.state)
        other = nlbeam.flow(PAPER, ex, s0, 0.0, 0.5 / f, disc0=[[1.0, 2 * dm]])
        assert not np.array_equal(other.state, ref.state)  # delta'_minus matters
        tr = nlbeam.integrate(PAPER, ex, 0.5 / f, x0=s0, store_every=0)
        tr_ref = nlbeam.integrate(PAPER, ex, 0.5 / f, x0=s0, disc0=[[1.0, dm]], store_every=0)
        assert np.array_equal(tr.state_end, tr_ref.state_end)


def test_the_start_in_contact_derivative_is_that_of_the_rule():
    # d delta'_minus / d state = [0, w] above the floor: against a central difference
    A = 1e-4
    geo = PAPER.element_geometry()
    s = np.array([2e-4, 0.05])
    D = Solver.start_contact_derivative(PAPER)
    h = 1e-7
    for k in range(2):
        sp, sm = s.copy(), s.copy()
        sp[k] += h
        sm[k] -= h
        num = (Solver.start_contact(geo, sp, A, 0.0, [0])[0, 1]
               - Solver.start_contact(geo, sm, A, 0.0, [0])[0, 1]) / (2 * h)
        assert num == pytest.approx(D[0, k], abs=1e-9)


def test_flow_and_flowmap_both_warn_about_too_few_steps_per_contact(monkeypatch):
    # (the contact step also obeys the law's stability limit, so raise the threshold)
    monkeypatch.setattr(nlbeam.solver, "MIN_STEPS_PER_CONTACT", 10_000)
    ex = nlbeam.Harmonic(1e-4, 44.0)
    s0 = [0.0, 0.0]  # x = 0, y = A cos: hits the stop within the first period
    with pytest.warns(RuntimeWarning, match="steps_per_contact") as rec:
        nlbeam.flow(PAPER, ex, s0, 0.0, 0.05)
    assert rec[0].filename == __file__  # the warning points at the caller
    fm = FlowMap(PAPER, ex)
    with pytest.warns(RuntimeWarning, match="steps_per_contact") as rec:
        fm(s0, 0.0, 0.05)
    assert rec[0].filename == __file__
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        FlowMap(PAPER, ex, warn=False)(s0, 0.0, 0.05)
        nlbeam.flow(PAPER, ex, s0, 0.0, 0.05, warn=False)
        nlbeam.flow(PAPER, ex, s0, 0.0, 0.05, method="adaptive")  # adaptive: never
