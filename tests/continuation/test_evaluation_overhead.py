"""The per-evaluation set-up of the shooting problems is done once, with the same flows bit for
bit: a FlowMap retargeted to another excitation does not look its kernels up again and
integrates exactly as a fresh map of that excitation; a problem hands out one excitation per
parameter value (a new one when the amplitude, frequency or model changes); a kept flow is
copied field by field into an independent Flow; the state fast path of FlowMap checks what
nlbeam.flow checks."""
import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation import _flowcache
from continuation.shooting import Integrator, ShootingProblem
from nlbeam.integrate import FlowMap
from nlbeam.parameters import with_parameter

A = 1e-4


def _same(a, b):
    for name in ("state", "disc", "xmax", "monodromy"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert x.tobytes() == y.tobytes(), name
    assert a.n_impacts == b.n_impacts and a.n_steps == b.n_steps


def test_retarget_keeps_kernels_and_flows_as_fresh_map(monkeypatch):
    model = beam = nlbeam.BeamImpact.paper()
    looked_up = []
    kernels = type(model).kernels

    def counting(self):
        looked_up.append(1)
        return kernels(self)
    monkeypatch.setattr(type(model), "kernels", counting)
    sol = C.periodic_solution(beam, A, 40.0)
    fm = FlowMap(model, nlbeam.Harmonic(A, 40.0), dt=1e-4, warn=False)
    before = len(looked_up)
    ex = nlbeam.Harmonic(A, 41.0)
    moved = fm.retarget(ex)
    assert len(looked_up) == before  # copy.copy's pickle path looked them up again
    assert moved.kernel_var is fm.kernel_var and moved.excitation is ex
    assert fm.excitation == nlbeam.Harmonic(A, 40.0)  # the original map is left as it was
    fresh = FlowMap(model, ex, dt=1e-4, warn=False)
    s0 = np.asarray(sol.state0, dtype=float)
    for mono in (False, True):
        _same(moved(s0, 0.0, 1 / 41.0, monodromy=mono, dt=1e-4),
              fresh(s0, 0.0, 1 / 41.0, monodromy=mono, dt=1e-4))


def test_problem_keeps_its_excitation_per_parameter():
    model = nlbeam.BeamImpact.paper()
    prob = ShootingProblem(model, A, 40.0, 1, [0.0], Integrator())
    m1, ex1 = prob.forcing(40.0)
    m2, ex2 = prob.forcing(40.0)
    assert ex2 is ex1 and m1 is m2 is model
    _, ex3 = prob.forcing(41.0)
    assert ex3 is not ex1 and ex3 == nlbeam.Harmonic(A, 41.0)
    prob.amplitude = 2 * A  # (continuation in the amplitude sets it so)
    _, ex4 = prob.forcing(41.0)
    assert ex4 == nlbeam.Harmonic(2 * A, 41.0)
    prob.base_model = with_parameter(model, "e", 0.5)
    m5, ex5 = prob.forcing(41.0)
    assert m5 is prob.base_model and ex5 is not ex4


def test_problem_segments_follow_boundaries_and_order():
    model = nlbeam.BeamImpact.paper()
    prob = ShootingProblem(model, A, 40.0, 2, [0.0, 0.5], Integrator())
    assert [(j, float(a), float(d)) for j, a, d in prob._segments()] == [(0, 0.0, 0.5),
                                                                        (1, 0.5, 1.5)]
    prob.boundaries = np.array([0.25, 1.0])
    assert [(j, float(a), float(d)) for j, a, d in prob._segments()] == [(0, 0.25, 0.75),
                                                                        (1, 1.0, 1.25)]


def test_kept_flow_copy_is_independent_and_equal():
    model = nlbeam.BeamImpact.paper()
    sol = C.periodic_solution(model, A, 40.0)
    fm = FlowMap(model, nlbeam.Harmonic(A, 40.0), dt=1e-4, warn=False)
    fl = fm(np.asarray(sol.state0, float), 0.0, 1 / 40.0, monodromy=True, dt=1e-4)
    cp = _flowcache._copy(fl)
    assert type(cp) is type(fl)
    _same(cp, fl)
    for name in _flowcache._ARRAYS:
        a = getattr(fl, name)
        if isinstance(a, np.ndarray):
            assert getattr(cp, name) is not a
    cp.state[0] += 1.0
    cp.monodromy[0, 0] += 1.0
    assert fl.state[0] != cp.state[0] and fl.monodromy[0, 0] != cp.monodromy[0, 0]


@pytest.mark.parametrize("bad", [np.array([np.nan, 0.0]), np.zeros(3), [0.0, np.inf]])
def test_flowmap_state_checks(bad):
    model = nlbeam.BeamImpact.paper()
    fm = FlowMap(model, nlbeam.Harmonic(A, 40.0), dt=1e-4, warn=False)
    with pytest.raises(ValueError, match="state0"):
        fm(bad, 0.0, 1e-3)
    # a list, a strided view and a float64 array of the same state: the same flow
    s = [1e-5, -2e-3]
    ref = fm(np.array(s), 0.0, 1e-3)
    _same(fm(s, 0.0, 1e-3), ref)
    _same(fm(np.array([s, s]).T[:, 0], 0.0, 1e-3), ref)
    st = np.array(s)
    fm(st, 0.0, 1e-3)
    assert st.tolist() == s  # the caller's state is not written to
