"""The lazy corrector (Tracer(lazy_var=...)) on an iteration that converges linearly below
noise_tol: it is carried on to tol when, at its observed ratio, tol lies within max_iter more
iterations, and fails as before when it does not (or when the corrector is eager).

The problem is closed-form: R(u, p) = u - p with a 'variational' dR/du = g instead of 1, so a
Newton step from a residual r leaves (1 - 1/g) r exactly; from a start 1e-6 off, every step is
shorter than the 1e-6 below which Broyden's update is not applied, so the ratio stays
1 - 1/g (the chord iteration of a Jacobian carried without secant updates)."""
import numpy as np
import pytest

from continuation._newton import ConvergenceError
from continuation.pathfollow import Problem, Tracer
from continuation.shooting import Evaluation


class WrongSlope(Problem):
    """R(u, p) = u - p (one unknown), its dR/du reported as ``slope``."""

    def __init__(self, slope):
        self.slope = slope
        self.scale_u = np.array([1.0])
        self.scale_p = 1.0
        self.variational = True
        self.n_evals = 0

    def evaluate(self, u, p, jac=True, jac_p=True):
        self.n_evals += 1
        R = np.array([u[0] - p])
        Ju = np.array([[self.slope]]) if jac else None
        Jp = np.array([-1.0]) if jac_p else None
        return Evaluation(R, Ju, Jp, [], xmax=abs(u[0]), n_impacts=0)

    def jacobian_p(self, u, p, ev=None):
        return np.array([-1.0])

    def multipliers(self, Ms):
        return None


def _solve(slope, lazy_var=True, start=1e-6, p=0.3):
    tr = Tracer(lazy_var=lazy_var)
    prob = WrongSlope(slope)
    z, ev, iters = tr.correct(prob, np.array([p + start, p]), np.array([0.0, 1.0]),
                              fixed_p=True)
    return z, ev, iters, prob


def test_linear_tail_below_noise_tol_is_carried_to_tol():
    # ratio 0.6: |R| = 1e-6 * 0.6^9 = 1.0e-8 at the 10th iterate, tol 1e-10 nine more away
    z, ev, iters, prob = _solve(2.5)
    assert iters > 10  # (max_iter: the old corrector failed here)
    # accepted by the corrector's own rule: below tol, or below 100 tol after a step < 1e-9
    assert abs(z[0] - z[1]) < 1e-8
    expected = 1e-6 * 0.6 ** (iters - 1)  # the exact residual of the chord iteration
    assert abs(ev.R[0]) == pytest.approx(expected, rel=1e-4)
    assert ev.Ju is not None  # the accepted point carries its variational Jacobian


def test_too_slow_a_tail_still_fails_at_max_iter():
    # ratio 0.68: |R| = 3.1e-8 at the 10th iterate, tol 15 more iterations away: a failure
    with pytest.raises(ConvergenceError):
        _solve(1.0 / 0.32)


def test_the_eager_corrector_is_unchanged():
    # eager (a fresh Jacobian at every iterate, as for one DOF): no extension
    with pytest.raises(ConvergenceError):
        _solve(2.5, lazy_var=False)
