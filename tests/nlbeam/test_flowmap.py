"""nlbeam.integrate.FlowMap: one map called many times (per-call step and contact state)
gives bitwise what fresh nlbeam.flow calls give, with the per-call checks done once."""
import numpy as np
import pytest

import nlbeam
from nlbeam._validate import BudgetError
from nlbeam.integrate import FlowMap

F = 44.0
A = 1e-4


def _same(a, b):
    assert np.array_equal(a.state, b.state)
    assert np.array_equal(a.disc, b.disc)
    assert np.array_equal(a.xmax, b.xmax)
    assert a.n_impacts == b.n_impacts and a.n_steps == b.n_steps and a.n_rhs == b.n_rhs
    for name in ("monodromy", "dstate_dvminus0", "dvminus_dstate0", "dvminus_dvminus0"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert np.array_equal(x, y), name


@pytest.mark.parametrize("mono", [False, True])
def test_flowmap_equals_flow_free_and_in_contact(mono):
    model = nlbeam.BeamImpact.paper()
    ex = nlbeam.Harmonic(A, F)
    dt = 1.0 / (F * 100)
    fm = FlowMap(model, ex, dt=dt)
    # a state in free flight and one inside the stop (delta = x - y > 0: starts in contact)
    for s0, t0, dur in (([0.0, 0.0], 0.0, 1.0 / F), ([2e-4, 0.05], 0.003, 0.37 / F),
                        ([1.5e-4, -0.02], 0.0, 2.0 / F)):
        ref = nlbeam.flow(model, ex, s0, t0, dur, monodromy=mono, dt=dt, warn=False)
        got = fm(s0, t0, dur, monodromy=mono)
        _same(ref, got)
        # a shorter step given per call, and an explicit contact state
        ref = nlbeam.flow(model, ex, s0, t0, dur, monodromy=mono, dt=dt / 3, warn=False,
                          disc0=ref.disc)
        got = fm(s0, t0, dur, monodromy=mono, dt=dt / 3, disc0=got.disc)
        _same(ref, got)


def test_flowmap_checks_like_flow():
    model = nlbeam.BeamImpact.paper()
    fm = FlowMap(model, nlbeam.Harmonic(A, F), dt=1e-4)
    with pytest.raises(ValueError, match="duration"):
        fm([0.0, 0.0], 0.0, 0.0)
    with pytest.raises(ValueError, match="^state0:"):
        fm([0.0, np.nan], 0.0, 0.01)
    with pytest.raises(ValueError, match="^state0:"):
        nlbeam.flow(model, nlbeam.Harmonic(A, F), [0.0, np.nan], 0.0, 0.01)
    with pytest.raises(ValueError, match="dt"):
        fm([0.0, 0.0], 0.0, 0.01, dt=-1e-4)
    with pytest.raises(ValueError, match="stability limit"):
        fm([0.0, 0.0], 0.0, 0.01, dt=1.0)
    # a fixed-step span beyond max_steps is refused before the kernel runs (100 steps > 5)
    with pytest.raises(BudgetError, match="about 100, more than the limit 5.*max_steps"):
        fm([0.0, 0.0], 0.0, 0.01, max_steps=5)
