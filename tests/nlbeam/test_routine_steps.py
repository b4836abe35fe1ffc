"""The lean loop for routine RK4 steps (nlbeam/_kernels/routine.py) gives the general loop's
results bit for bit, and it is taken: its steps are counted by the kernel (counters[8])."""
import importlib

import numpy as np
import pytest

import nlbeam
from nlbeam.integrate import FlowMap, _run
from nlbeam.solver import Solver

integ = importlib.import_module("nlbeam.integrate")

TWO_K = np.array([[1200.0, -400.0], [-400.0, 400.0]])
SYSTEMS = {
    # Lankarani-Nikravesh stop on the base (the paper beam), Hertz, a piecewise-linear stop
    # against the frame with a cubic spring, two DOFs with a stop on the second, two modes
    "ln": (nlbeam.BeamImpact.paper(), nlbeam.Harmonic(1e-4, 40.0)),
    "hertz": (nlbeam.BeamImpact.paper(contact="hertz"), nlbeam.Harmonic(1e-4, 40.0)),
    "pwl": (nlbeam.System([[1.0]], [[0.2513]], [[39.48]], elements=(
        nlbeam.CubicSpring(0, k3=10.0),
        nlbeam.PiecewiseLinearStop(0, k=789.6, gap=0.5, on_base=False)),
        excitation_kind="force", y_load=[1.0]), nlbeam.Harmonic(8.0, 1.2)),
    "twodof": (nlbeam.System(np.diag([0.04, 0.02]), 1e-4 * TWO_K, TWO_K, elements=(
        nlbeam.Contact(dof=1, law="lankarani-nikravesh", K=1e8, e=0.7, gap=0.0),
        nlbeam.CubicSpring(dof=0, k3=1e6)), excitation_kind="base"),
        nlbeam.Harmonic(1e-4, 30.0)),
    "modal2": (nlbeam.ModalBeam.paper(n_modes=2), nlbeam.Harmonic(1e-4, 40.0)),
}


def _noise_table(scale=1.0):
    """A tabulated excitation (cubic Hermite table of a smooth multi-tone base motion, peak
    about 1.2e-4 m times scale)."""
    h = 2e-5
    t = np.arange(0.0, 0.3 + h, h)
    w = 2 * np.pi * np.array([23.0, 41.0, 77.0])
    a = scale * np.array([6e-5, 4e-5, 2e-5])
    y = (a * np.cos(np.outer(t, w))).sum(axis=1)
    yd = -(a * w * np.sin(np.outer(t, w))).sum(axis=1)
    ydd = -(a * w * w * np.cos(np.outer(t, w))).sum(axis=1)
    return nlbeam.Sampled(0.0, h, y, yd, ydd, max_freq=100.0)


def _trajectory(monkeypatch, routine, model, ex, t_end, **kw):
    monkeypatch.setattr(integ, "ROUTINE_STEPS", routine)
    return nlbeam.integrate(model, ex, t_end, warn=False, **kw)


def _routine_count(monkeypatch, routine, model, ex, t_end, graded):
    """(steps, steps taken by routine.py) of an RK4 run from rest with the default steps."""
    monkeypatch.setattr(integ, "ROUTINE_STEPS", routine)
    solver = Solver("rk4", None, None, 1e-8, 1e-12, True, graded)
    dt, spc = integ._prepare(model, ex, solver, 0.0, t_end)
    N, ne = model.n_dof, model.n_elements
    s0, disc = integ._initial(model, None, None, 0.0, ex)
    c = _run(model, ex, 0.0, t_end, "rk4", dt, spc, 1e-8, 1e-12, 10 ** 8, s0, disc, True,
             False, np.zeros((2 * N, 1)), np.zeros((ne, 1)), True, 0, graded, 0, False)[9]
    return int(c[1]), int(c[8])


def _same_trajectory(a, b):
    for name in ("t", "x", "v", "delta", "force", "state_end", "disc_end", "xmax", "events"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for name in ("n_steps", "n_rhs", "n_impacts", "n_events", "min_steps_per_contact",
                 "max_landing_residual"):
        assert getattr(a, name) == getattr(b, name), name


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_routine_steps_give_the_general_loops_trajectory(monkeypatch, name):
    model, ex = SYSTEMS[name]
    t_end = 5.0 / ex.frequency
    for graded in (True, False):
        for kw in ({}, {"store_every": 3}):
            fast = _trajectory(monkeypatch, True, model, ex, t_end, graded=graded, **kw)
            slow = _trajectory(monkeypatch, False, model, ex, t_end, graded=graded, **kw)
            assert fast.n_impacts > 0
            _same_trajectory(fast, slow)
        steps, routine = _routine_count(monkeypatch, True, model, ex, t_end, graded)
        # most steps are routine ones (free flight, the middle of contacts)
        assert routine > 0.5 * steps, (steps, routine)
        assert _routine_count(monkeypatch, False, model, ex, t_end, graded) == (steps, 0)


def test_routine_steps_on_a_table_and_in_a_preloaded_contact(monkeypatch):
    model = nlbeam.BeamImpact.paper()
    table = _noise_table()
    fast = _trajectory(monkeypatch, True, model, table, 0.25, store_every=1)
    slow = _trajectory(monkeypatch, False, model, table, 0.25, store_every=1)
    assert fast.n_impacts > 0
    _same_trajectory(fast, slow)
    # permanently in contact: every step an ordinary step inside the contact
    pre = nlbeam.System([[model.m]], [[model.b]], [[model.k]],
                        (nlbeam.Contact(0, "hertz", model.K_hertz, gap=-1e-3),), "base",
                        y_load=[model.k], yd_load=[model.b])
    x0 = [-1e-3 + 2.3e-6, 0.0]   # near the static equilibrium on the stop
    table = _noise_table(1e-3)
    for graded in (True, False):
        a = _trajectory(monkeypatch, True, pre, table, 0.05, x0=x0, graded=graded)
        b = _trajectory(monkeypatch, False, pre, table, 0.05, x0=x0, graded=graded)
        assert a.disc_end[0, 0] == 1.0
        _same_trajectory(a, b)
    steps, routine = _routine_count(monkeypatch, True, pre, table, 0.05, False)
    assert routine > 0.9 * steps, (steps, routine)


def test_routine_steps_in_a_flow_map(monkeypatch):
    model, ex = SYSTEMS["ln"]
    fm = FlowMap(model, ex)
    for s0, t0, dur in (([0.0, 0.0], 0.0, 1.0 / 40.0), ([2e-4, 0.05], 0.003, 0.37 / 40.0)):
        got = []
        for routine in (True, False):
            monkeypatch.setattr(integ, "ROUTINE_STEPS", routine)
            got.append(fm(s0, t0, dur))
        a, b = got
        for name in ("state", "disc", "xmax"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        assert (a.n_steps, a.n_rhs, a.n_impacts) == (b.n_steps, b.n_rhs, b.n_impacts)


def test_swings_far_from_the_stop_stay_in_the_routine_loop(monkeypatch):
    """delta has several maxima in this run (a three-tone table, a stop 1 m away): the
    lean loop decides these steps by _crossing's own extremum check, so it takes every step,
    and the trajectory is the general loop's bit for bit. With the stop 0.1 mm away, steps
    where delta crosses or comes near the stop are handed back to the general loop."""
    model = nlbeam.BeamImpact.paper()
    far = nlbeam.System([[model.m]], [[model.b]], [[model.k]],
                        (nlbeam.Contact(0, "lankarani-nikravesh", model.K_hertz, e=0.5,
                                        gap=1.0),), "base", y_load=[model.k], yd_load=[model.b])
    table = _noise_table()
    for graded in (True, False):
        a = _trajectory(monkeypatch, True, far, table, 0.25, graded=graded, store_every=1)
        b = _trajectory(monkeypatch, False, far, table, 0.25, graded=graded, store_every=1)
        _same_trajectory(a, b)
        assert a.n_impacts == 0
    # delta's maxima in the run (from the grid samples): each one a step the general loop
    # checks on the dense output
    dd = np.diff(a.delta[:, 0])
    assert np.count_nonzero((dd[:-1] > 0.0) & (dd[1:] <= 0.0)) >= 5
    steps, routine = _routine_count(monkeypatch, True, far, table, 0.25, True)
    assert routine == steps, (steps, routine)
    near = nlbeam.System([[model.m]], [[model.b]], [[model.k]],
                         (nlbeam.Contact(0, "lankarani-nikravesh", model.K_hertz, e=0.5,
                                         gap=1e-4),), "base", y_load=[model.k],
                         yd_load=[model.b])
    steps, routine = _routine_count(monkeypatch, True, near, table, 0.25, True)
    assert 0 < routine < steps, (steps, routine)
