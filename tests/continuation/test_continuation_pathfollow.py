"""The path follower works on any problem of its written protocol (continuation.pathfollow.
Problem), not only on shooting: a closed-form problem whose branch and folds are known."""
import numpy as np
import pytest

from continuation._newton import ConvergenceError
from continuation.pathfollow import Problem, Tracer
from continuation.shooting import Evaluation


class Circle(Problem):
    """R(u, p) = u^2 + p^2 - 1: one closed branch, folds at p = +-1 (u = 0). No multipliers:
    the folds are found from the tangent; ``settle`` and ``jacobian_u`` are the protocol's
    defaults."""

    def __init__(self, variational=True):
        self.scale_u = np.array([1.0])
        self.scale_p = 1.0
        self.variational = variational

    def evaluate(self, u, p, jac=True, jac_p=True):
        R = np.array([u[0] ** 2 + p ** 2 - 1.0])
        Ju = np.array([[2 * u[0]]]) if jac and self.variational else None
        Jp = np.array([2 * p]) if jac_p else None
        return Evaluation(R, Ju, Jp, [], xmax=abs(u[0]), n_impacts=0)

    def jacobian_p(self, u, p, ev=None):
        return np.array([2 * p])

    def multipliers(self, Ms):
        return None

    def solve(self, u0, p, tol=1e-10):
        raise AssertionError("not called: adapt never asks")

    def adapt(self, u, p):
        return None

    def transfer(self, old, u_old, p):
        return u_old


def test_tracer_follows_a_closed_form_branch_through_its_folds():
    tracer = Tracer(p_min=-2.0, p_max=2.0, ds=0.05, ds_max=0.1, bif_tol=1e-9)
    pts, located, reason = tracer.trace(Circle(), np.array([1.0]), 0.0, direction=1)
    assert reason == "closed (isola)"
    u = np.array([q.u[0] for q in pts])
    p = np.array([q.p for q in pts])
    assert np.max(np.abs(u ** 2 + p ** 2 - 1.0)) < 1e-9  # every point on the circle
    folds = sorted(L.point.p for L in located if L.kind == "fold")
    assert len(folds) == 2
    assert abs(folds[0] + 1.0) < 1e-6 and abs(folds[1] - 1.0) < 1e-6


def test_the_protocol_defaults_are_loud():
    c = Circle(variational=False)
    with pytest.raises(NotImplementedError, match="^jacobian_u:"):
        c.jacobian_u(np.array([1.0]), 0.0)
    with pytest.raises(ConvergenceError, match="^settle:"):
        c.settle(np.array([1.0]), 0.0, 0.1)
    assert Circle().variational and Problem.variational
