"""The path follower's corrector: at fixed p it leaves out dR/dp (a flow saved) and gets the
same solution; ``complete_jacobian`` then fills in the forward difference it would have used."""
import numpy as np

import continuation as C
import nlbeam
from continuation.pathfollow import Tracer
from continuation.shooting import _problem_from_state

A = 1e-4


def _problem(f):
    model = nlbeam.BeamImpact.paper()
    sol = C.periodic_solution(model, A, f)
    prob, u = _problem_from_state(model, A, f, 1, sol.state0, 1, C.Integrator())
    prob.scale_u = prob.make_scale(u, f)
    return prob, u


def test_fixed_p_corrector_leaves_out_dRdp_and_fills_it_in():
    f = 44.0
    prob, u = _problem(f)
    w, wp = prob.scale_u, prob.scale_p
    n = len(u)
    e_p = np.zeros(n + 1)
    e_p[-1] = 1.0
    # start 1e-3 (scaled) off the orbit, at a frequency 1e-4 above
    z0 = np.r_[u / w + 1e-3, (f * (1 + 1e-4)) / wp]
    full, lazy = Tracer(), Tracer()
    z_a, ev_a, it_a = full.correct(prob, z0, e_p)
    z_b, ev_b, it_b = lazy.correct(prob, z0, e_p, fixed_p=True)
    assert z_b[-1] == z0[-1]  # p kept
    assert np.max(np.abs(z_a - z_b)) < 1e-11
    assert lazy.n_evaluations == full.n_evaluations - 1  # the difference left out
    assert np.all(ev_b.B[:, -1] == 0.0)
    lazy.complete_jacobian(prob, ev_b)
    assert lazy.n_evaluations == full.n_evaluations
    # the filled-in column: the forward difference at the start, as the full corrector's
    np.testing.assert_allclose(ev_b.B[:, -1], ev_a.B[:, -1], rtol=1e-6, atol=1e-9)
    # and it is dR/dp at the start: against central differences of the residual there
    h = 1e-6
    us, ps = z0[:-1] * w, z0[-1] * wp
    d = (prob.evaluate(us, ps * (1 + h), jac=False, jac_p=False).R
         - prob.evaluate(us, ps * (1 - h), jac=False, jac_p=False).R) / (2 * h * ps)
    np.testing.assert_allclose(ev_b.B[:, -1], d * wp / w, rtol=1e-4, atol=1e-6)


def test_locate_p_finds_the_period_doubling_located_along_the_arclength():
    # the harmonic branch of the paper model has a period doubling near 15.94 Hz (1 impact per
    # period on both sides): locate_p (bisection in p, as after a jump) and locate (regula
    # falsi along the arclength) must agree to the bracket
    f_a, f_b = 15.90, 15.98
    prob, u_a = _problem(f_a)
    tr = Tracer(bif_tol=1e-10)
    w, wp = prob.scale_u, prob.scale_p
    e_p = np.zeros(len(u_a) + 1)
    e_p[-1] = 1.0
    z_a, ev_a, _ = tr.correct(prob, np.r_[u_a / w, f_a / wp], e_p, fixed_p=True)
    z_b, ev_b, _ = tr.correct(prob, np.r_[u_a / w, f_b / wp], e_p, fixed_p=True)
    pa, pb = tr._point(prob, z_a, ev_a), tr._point(prob, z_b, ev_b)
    assert pa.n_impacts == pb.n_impacts
    ga, gb = tr._tests(pa)[1], tr._tests(pb)[1]
    assert ga * gb < 0  # a period doubling between them
    q, tol = tr.locate_p(prob, pa, pb, 1, ga, gb)
    assert tol < 1e-10 * 16.0 * 2
    assert abs(np.prod(q.multipliers + 1.0).real) < 1e-6  # a multiplier at -1
    ds = float(np.linalg.norm(z_b - z_a))
    t = (z_b - z_a) / ds
    q2, tol2 = tr.locate(prob, z_a, t, ds, 1, ga, gb)
    assert abs(q.p - q2.p) < 2 * (tol + tol2) + 1e-9 * q.p
