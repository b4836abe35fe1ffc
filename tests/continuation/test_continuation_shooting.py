"""Shooting: closed forms, derivatives against central differences, and brute-force integration."""
import numpy as np
import pytest

import continuation as C
import nlbeam

A = 1e-4  # m, the paper's 0.1 mm


def test_linear_oscillator_matches_transmissibility_and_exp_lambda_T():
    m = nlbeam.BeamImpact(K_hertz=0.0)
    f = 30.0
    w = 2 * np.pi * f
    sol = C.periodic_solution(m, A, f, dt_scale=0.05)
    X = A * (m.k + 1j * w * m.b) / (m.k - m.m * w ** 2 + 1j * w * m.b)
    expect = np.array([X.real, -w * X.imag])
    scale = np.array([abs(X), w * abs(X)])
    assert np.max(np.abs(sol.state0 - expect) / scale) < 1e-8
    assert abs(sol.xmax - abs(X)) < 1e-8 * abs(X)
    lam = np.linalg.eigvals([[0.0, 1.0], [-m.k / m.m, -m.b / m.m]])
    mu = np.exp(lam / f)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    got = np.sort_complex(sol.multipliers)
    assert np.max(np.abs(got - np.sort_complex(mu))) < 1e-8
    assert sol.stable and sol.period == pytest.approx(1 / f)


LAWS = [("hertz", {}), ("lankarani-nikravesh", {}),
        ("hunt-crossley", {"mu": nlbeam.mu_from_e(0.5, 2.1e8, 0.1)})]
FINE = dict(dt_scale=0.25, steps_per_contact=1024)


@pytest.mark.parametrize("law,kw", LAWS, ids=[l for l, _ in LAWS])
def test_monodromy_equals_central_differences_on_impacting_orbit(law, kw):
    m = nlbeam.BeamImpact.paper(contact=law, **kw)
    f = 40.0
    integ = C.Integrator(**FINE)
    sol = C.periodic_solution(m, A, f, integrator=integ)
    t0, T = sol.boundaries[0] / f, 1 / f
    dt = T / integ.steps_per_period(m, f)
    ex = nlbeam.Harmonic(A, f)

    def run(s, mono=False):
        return nlbeam.flow(m, ex, s, t0, T, monodromy=mono, dt=dt,
                           steps_per_contact=integ.steps_per_contact)

    fl = run(sol.states[0], True)
    assert fl.n_impacts >= 1
    sc = np.array([sol.xmax, sol.xmax * 2 * np.pi * f])
    Mfd = np.zeros((2, 2))
    for i in range(2):
        e = np.zeros(2)
        e[i] = 1e-6 * sc[i]
        Mfd[:, i] = (run(sol.states[0] + e).state - run(sol.states[0] - e).state) / (2 * e[i])
    D = np.diag(sc)
    Ms = np.linalg.solve(D, fl.monodromy @ D)
    Mfs = np.linalg.solve(D, Mfd @ D)
    assert np.max(np.abs(Ms - Mfs)) < 1e-5 * np.max(np.abs(Ms))
    # the solution reports the same monodromy
    assert np.allclose(sol.monodromy, fl.monodromy, rtol=1e-9, atol=1e-12 * np.abs(Ms).max())


@pytest.mark.parametrize("f,order", [(44.0, 1), (30.0, 1), (12.0, 1), (90.0, 2), (125.0, 3)])
def test_stable_solution_agrees_with_brute_force(f, order):
    m = nlbeam.BeamImpact.paper()
    sol = C.periodic_solution(m, A, f, order)
    assert sol.stable
    assert sol.residual < 1e-9
    # brute force: integrate long from rest, then max |x| over the last period (refined)
    from continuation.shooting import steady_state
    s = steady_state(m, A, f, efolds=30.0)
    n = 100 * max(1, int(np.ceil(np.max(m.natural_frequencies()) / f)))
    fl = nlbeam.flow(m, nlbeam.Harmonic(A, f), s, 0.0, order / f, dt=1 / (f * n))
    assert abs(fl.xmax[0] - sol.xmax) < 1e-5 * sol.xmax
    # the reported state at t = 0 lies on the orbit: one period maps it onto itself
    sol_back = nlbeam.flow(m, nlbeam.Harmonic(A, f), sol.state0, 0.0, order / f,
                           disc0=sol.disc0, dt=1 / (f * n),
                           steps_per_contact=sol.integrator.steps_per_contact)
    assert np.max(np.abs(sol_back.state - sol.state0) / np.abs(sol.states).max(axis=0)) < 1e-6


def test_multiple_shooting_gives_the_same_orbit():
    m = nlbeam.BeamImpact.paper()
    one = C.periodic_solution(m, A, 44.0)
    four = C.periodic_solution(m, A, 44.0, guess=one, segments=4)
    assert four.states.shape == (4, 2)
    assert abs(four.xmax - one.xmax) < 1e-7 * one.xmax
    assert np.allclose(np.sort_complex(four.multipliers), np.sort_complex(one.multipliers),
                       atol=1e-6)


def test_nonconvergence_raises_and_says_what_to_try():
    m = nlbeam.BeamImpact.paper()
    with pytest.raises(C.ConvergenceError, match="multiple shooting"):
        C.periodic_solution(m, A, 44.0, guess=[5e-3, -3.0], max_iter=2)
