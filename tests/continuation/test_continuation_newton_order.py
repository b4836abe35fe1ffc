"""Newton's corrector converges quadratically on impacting orbits: its Jacobian (the flow's
monodromy) is the derivative of the fixed-step map it solves, contact steps and landed event
times included. With the derivative of the continuous flow instead (main before the exact
variational equations) the residuals fell linearly, by a factor 1e-2 an iteration."""
import math

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation.shooting import _problem_from_state

WN = 2 * np.pi * 20.0  # rad/s


def _stop_oscillator():
    """A 1-DOF oscillator (20 Hz, damping ratio 0.02) on a moving base, with a linear stop
    100 times as stiff as the structure behind a gap of 0.2 mm."""
    return nlbeam.System([[1.0]], [[0.04 * WN]], [[WN * WN]], elements=(
        nlbeam.PiecewiseLinearStop(0, k=100 * WN ** 2, gap=2e-4),), excitation_kind="base")


CASES = {
    "paper-40Hz": (nlbeam.BeamImpact.paper, 1e-4, 40.0),
    "pwl-stop-25Hz": (_stop_oscillator, 1e-3, 25.0),
}


def residual_history(model, amplitude, frequency, offset):
    """The scaled max-norm residuals of the corrector's iterates (ShootingProblem.solve, the
    corrector of periodic_solution) from the orbit's boundary state moved by ``offset`` times
    its scale in every component, and the impacts per period of the orbit."""
    sol = C.periodic_solution(model, amplitude, frequency, error=False)
    prob, u = _problem_from_state(model, amplitude, frequency, 1, sol.state0, 1, C.Integrator())
    w = prob.scale_u = prob.make_scale(u, frequency)
    history = []
    evaluate = prob.evaluate

    def recording(uu, p, jac=True, jac_p=True):
        ev = evaluate(uu, p, jac=jac, jac_p=jac_p)
        history.append(float(np.max(np.abs(ev.R / w))))
        return ev

    prob.evaluate = recording
    prob.solve(u + offset * w, frequency, tol=1e-14, max_iter=12)
    return history, prob.last_impacts


def observed_orders(r, floor):
    """log(r[k+1] / r[k]) / log(r[k] / r[k-1]) for every three successive residuals whose last
    one lies above ``floor`` (where round-off does not yet decide the residual)."""
    return [math.log(r[k + 1] / r[k]) / math.log(r[k] / r[k - 1])
            for k in range(1, len(r) - 1) if r[k + 1] > floor]


@pytest.mark.parametrize("offset", [1e-2, 3e-2])
@pytest.mark.parametrize("name", list(CASES))
def test_newton_residuals_fall_quadratically_on_an_impacting_orbit(name, offset):
    make, amplitude, frequency = CASES[name]
    r, impacts = residual_history(make(), amplitude, frequency, offset)
    assert impacts >= 1   # the orbit impacts: contact steps and event times in the map
    # the map's round-off is ~1e-15 of the scale: ratios of residuals above 1e-11 are
    # decided by the iteration alone
    q = observed_orders(r, 1e-11)
    assert len(q) >= 1, r
    assert min(q) > 1.7 and max(q) < 3.0, (q, r)
    # and it reaches round-off: the residual after the last quadratic step is below 1e-12
    assert min(r) < 1e-12, r
    assert len(r) <= 7, r
