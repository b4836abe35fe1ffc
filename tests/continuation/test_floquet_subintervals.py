"""Multipliers of strongly unstable (or strongly contracting) orbits keep every multiplier's
digits: when the spread is large the orbit is integrated again over sub-intervals of the
period and the multipliers are taken from the product of their transition matrices
(ShootingProblem.piece_monodromies, continuation._floquet.multipliers).

Exact answer: a linear system x'' + C x' + K x = F cos(w t) integrated by RK4 at a fixed step
h has the discrete monodromy R(A h)^n, R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24, whose
multipliers are R(lambda h)^n for the eigenvalues lambda of A = [[0, I], [-K, -C]] (M = I)."""
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation._floquet import SPREAD, factors_needed
from continuation.shooting import Integrator


def _rk4_multipliers(lam, f, model):
    n = Integrator().steps_per_period(model, f)
    z = np.asarray(lam) / f / n
    mu = (1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24) ** n
    return mu[np.argsort(-np.abs(mu))]


def _orbit_guess(K, Cm, F, f, phases):
    """States of the exact periodic orbit of x'' + Cm x' + K x = F cos(2 pi f t) at the
    excitation phases (periods)."""
    w = 2 * np.pi * f
    X = np.linalg.solve(K - w ** 2 * np.eye(len(F)) + 1j * w * Cm, F)
    return np.array([np.r_[(X * np.exp(2j * np.pi * b)).real,
                           (1j * w * X * np.exp(2j * np.pi * b)).real] for b in phases])


def test_single_segment_orbit_keeps_a_multiplier_1e23_below_the_largest():
    # lambda T = ln(1e3) and ln(1e-20): a mildly unstable orbit of a strongly damped system;
    # one monodromy matrix gives the small multiplier with an error of about eps * 1e3
    f = 2.0
    l1, l2 = np.log(1e3) * f, np.log(1e-20) * f
    K, Cm = np.array([[l1 * l2]]), np.array([[-(l1 + l2)]])
    model = nlbeam.System(np.eye(1), Cm, K, excitation_kind="force", y_load=[1.0])
    guess = _orbit_guess(K, Cm, np.array([1.0]), f, [0.0])[0]
    sol = C.periodic_solution(model, 1.0, f, guess=guess, error=False)
    exact = _rk4_multipliers([l1, l2], f, model)
    assert exact[0] / exact[1] > 1e14 * SPREAD
    assert np.max(np.abs(sol.multipliers - exact) / np.abs(exact)) < 1e-10
    plain = np.sort(np.abs(np.linalg.eigvals(sol.monodromy)))
    assert abs(plain[0] - exact[1]) / exact[1] > 0.5  # one matrix: no digit left


def test_few_segments_of_an_orbit_with_multipliers_2e56_and_6e8_are_subdivided():
    # the orbit: multipliers 2e56, 6e8 (and 1/6e8, 1/2e56), two coupled DOFs; 16
    # segments alone leave the smallest multiplier about 1e-7 relative
    f = 1.0
    l1, l2 = np.log(2e56) * f, np.log(6e8) * f
    th = 0.4
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    K = -R @ np.diag([l1 ** 2, l2 ** 2]) @ R.T
    F = np.array([1.0, 0.5])
    model = nlbeam.System(np.eye(2), np.zeros((2, 2)), K, excitation_kind="force", y_load=F)
    seg = 16
    guess = _orbit_guess(K, np.zeros((2, 2)), F, f, np.arange(seg) / seg)
    sol = C.periodic_solution(model, 1.0, f, guess=guess, segments=seg, error=False)
    exact = _rk4_multipliers([l1, l2, -l2, -l1], f, model)
    assert factors_needed(exact[0] / exact[-1]) > seg
    assert np.max(np.abs(sol.multipliers - exact) / np.abs(exact)) < 1e-9
    # and against the ODE's exp(lambda T) within RK4's error
    assert np.allclose(sol.multipliers, np.exp(np.array([l1, l2, -l2, -l1]) / f), rtol=1e-4)


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "hertz"])
def test_piece_monodromies_multiply_to_the_monodromy_through_contacts(law):
    # an impacting orbit of the paper's beam: a piece that would end inside a contact runs
    # on to the next cut (there the steps depend on where the contact began); the product
    # of the pieces is the one-matrix monodromy
    m = nlbeam.BeamImpact.paper(contact=law)
    sol = C.periodic_solution(m, 1e-4, 40.0, error=False)
    from continuation.shooting import ShootingProblem

    prob = ShootingProblem(m, 1e-4, 40.0, 1, sol.boundaries, Integrator())
    U = np.asarray(sol.states, dtype=float).reshape(prob.n_seg, prob.N2)
    ev = prob.evaluate(U.ravel(), 40.0, jac=True, jac_p=False)
    M = prob.monodromy(ev.Ms)
    for pieces in (7, 64):
        P = np.eye(prob.N2)
        Fs = prob.piece_monodromies(U, 40.0, pieces)
        assert 1 < len(Fs) <= pieces
        if pieces == 64:  # some cuts fell inside a contact: those pieces were merged
            assert len(Fs) < pieces
        for Fj in Fs:
            P = Fj @ P
        assert np.max(np.abs(P - M)) < 1e-8 * np.max(np.abs(M))


def test_an_impacting_orbit_keeps_a_multiplier_1e45_below_the_largest():
    # an overdamped oscillator (zeta = 3) with a one-sided stop (exact_pwl), impacting once per
    # 4 s period: multipliers -1.2e-10 and -2.7e-56. The exact reference's formed product
    # loses the small one too, but the damping c is the same on both sides of the stop, so
    # mu1 mu2 = det M = exp(-c T / m) exactly (Liouville): mu2 = exp(-c T / m) / mu1
    from exact_pwl import StopOscillator, orbit

    osc = StopOscillator.tuned(fn=1.0, zeta=3.0, ratio=100.0, gap=0.005, amplitude=1.0)
    f = 0.25
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # few steps per contact
        sol = C.periodic_solution(osc.system(), osc.amplitude, f,
                                  integrator=Integrator().refined(2), error=False)
    ex = orbit(osc, f, sol.state0)
    assert ex.n_impacts == 1
    det = np.exp(-osc.c / osc.m / f)
    mu1 = ex.multipliers[0].real
    exact = np.array([mu1, det / mu1])
    assert abs(exact[0] / exact[1]) > 1e40
    assert np.max(np.abs(sol.multipliers - exact) / np.abs(exact)) < 1e-3  # measured 5.6e-5
    plain = np.linalg.eigvals(sol.monodromy)
    assert np.min(np.abs(plain)) < 1e-3 * abs(exact[1])  # one matrix: 0.0
