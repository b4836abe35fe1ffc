"""The samples the integrator stores (delta and force at every grid point, from the excitation
evaluated inside the loop) agree with the excitation evaluated afterwards by its own entry
point (``Excitation.evaluate``) and with the contact law, for every kind of excitation table
and both kinds of loop (adaptive DP5 with dense output, routine RK4 on the grid)."""
import numpy as np
import pytest

import nlbeam
import stochastic as st


def _excitations():
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=3)
    block = noise.block(0)                               # quintic coefficient table
    t = np.arange(0.0, 0.6, 2e-4)
    w = 2 * np.pi * np.array([31.0, 47.0])
    cubic = nlbeam.Sampled(0.0, 2e-4, 1e-4 * np.cos(np.outer(t, w)).sum(1),
                           -1e-4 * (np.sin(np.outer(t, w)) * w).sum(1),
                           -1e-4 * (np.cos(np.outer(t, w)) * w * w).sum(1))
    return {"quintic block": block, "cubic table": cubic,
            "harmonic": nlbeam.Harmonic(1e-4, 40.0)}


@pytest.mark.parametrize("kind", ["quintic block", "cubic table", "harmonic"])
@pytest.mark.parametrize("method", ["adaptive", "rk4"])
def test_stored_delta_and_force_match_the_excitation_and_the_law(kind, method):
    exc = _excitations()[kind]
    model = nlbeam.BeamImpact.paper()
    tr = nlbeam.integrate(model, exc, 0.5, method=method, dt=1 / 6400, x0=[-2e-5, 0.0])
    assert tr.n_impacts > 3
    y, yd = exc.evaluate(tr.t)
    d_ref, dd_ref = model.penetration(np.column_stack([tr.x, tr.v]), y, yd)
    scale = np.abs(tr.x[:, 0]) + np.abs(y) + abs(model.gap)
    assert np.all(np.abs(tr.delta[:, 0] - d_ref[:, 0]) <= 4e-16 * scale)
    # force: zero outside the stop, positive inside, the Hertz part K delta^1.5 times the
    # Lankarani-Nikravesh damping factor 1 + c delta' (c > 0), so >= K delta^1.5 on the way in
    out = tr.delta[:, 0] <= 0.0
    assert np.all(tr.force[out, 0] == 0.0)
    inside = ~out & (dd_ref[:, 0] > 0.0)
    assert np.any(inside)
    assert np.all(tr.force[inside, 0] >= model.K_hertz * tr.delta[inside, 0] ** 1.5 * (1 - 1e-12))
