"""A branch switched at a period doubling ends where it meets the parent branch again (at its
other period doubling) instead of passing onto the other half of the pitchfork and tracing
the same orbits, shifted by one excitation period, a second time."""
import warnings

import numpy as np

import continuation as C
import nlbeam


def test_switched_branch_is_traced_once_between_two_period_doublings():
    model = nlbeam.BeamImpact.paper()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        frc = C.frequency_response(model, 1e-4, (12.3, 14.2), orders=(1, 2), n_grid=4)
    pds = sorted(b.frequency for b in frc.bifurcations
                 if b.kind == "period-doubling" and b.order == 1)
    assert len(pds) == 2  # 12.68 and 13.79 Hz on the harmonic branch
    main = max((b for b in frc.branches if b.order == 2 and b.origin == "period-doubling"),
               key=lambda b: len(b.values))
    # it joins the two period doublings (their diagram values are off by up to 1.2e-3)...
    assert main.frequency.min() < pds[0] * (1 + 2e-3)
    assert main.frequency.max() > pds[1] * (1 - 2e-3)
    # ...once: before, it went on through the pitchfork and came back (81 points, and each
    # bifurcation on it twice)
    assert len(main.values) < 60
    on_main = [b for b in frc.bifurcations if b.order == 2 and b.kind != "grazing"]
    f = np.array([b.frequency for b in on_main])
    assert len(on_main) >= 2
    assert np.all(np.abs(np.diff(np.sort(f))) > 1e-4 * f.max())
    graz = np.sort([b.frequency for b in frc.bifurcations
                    if b.order == 2 and b.kind == "grazing"])
    assert np.all(np.diff(graz) > 1e-4 * graz.max())


# the order-2 branch born at the harmonic branch's period doubling at 22.4166 Hz (paper model,
# A = 0.1 mm), its second point: states at the two shooting boundaries (phases 0.8, 1.8)
_PD22_STATES = np.array([[-7.6948866315262903e-05, 1.3565338381090844e-02],
                         [-8.3807705823367708e-05, 1.3525035153309663e-02]])
_PD22_F = 22.416655264801143


def _pd22_problem():
    from continuation.shooting import Integrator, ShootingProblem
    m = nlbeam.BeamImpact.paper()
    prob = ShootingProblem(m, 1e-4, _PD22_F, 2, np.array([0.8, 1.8]), Integrator(),
                           steps_per_period=Integrator().steps_per_period(m, _PD22_F))
    u = _PD22_STATES.ravel()
    prob.scale_u = prob.make_scale(u, _PD22_F)
    u, _, _, _ = prob.solve(u, _PD22_F)
    return prob, u


def test_lower_order_orbit_is_told_apart():
    """continuation.corners._lower_order: the parent's order-1 orbit (which solves the
    order-2 problem too) is of lower order, the switched branch's orbit is not."""
    from continuation.corners import _lower_order
    from continuation.pathfollow import Point
    prob, u = _pd22_problem()
    a = Point(u=u, p=_PD22_F, xmax=0.0, multipliers=None, problem=prob, n_impacts=0)
    f1 = 22.4392
    sol = C.periodic_solution(nlbeam.BeamImpact.paper(), 1e-4, f1, error=False)
    model, ex = prob.forcing(f1)  # the order-1 orbit at both boundaries (phases 0.8, 1.8)
    x = nlbeam.flow(model, ex, sol.state0, 0.0, 0.8 / f1).state
    u1, _, _, _ = prob.solve(np.r_[x, x], f1)  # (on the problem's own step grid)
    z1 = np.r_[u1 / prob.scale_u, f1 / prob.scale_p]
    assert prob.minimal_order(u1, f1) == 1
    assert _lower_order(prob, a, z1)
    z = np.r_[u / prob.scale_u, _PD22_F / prob.scale_p]
    assert not _lower_order(prob, a, z)


def test_switched_branch_does_not_jump_onto_its_parent():
    """Traced from its second point towards higher frequency, the order-2 branch passes the
    grazing corner at 22.41682 Hz as an order-2 orbit. Before the fix the far-side solves at the
    corner took the parent's order-1 orbit at 22.4392 Hz (which the order-2 problem solves too)
    as a creep, the branch ran back and forth between the two (22.41677 -> 22.43919 ->
    22.41665 -> ...) and ended 'stuck at a corner' after 8 points: a silent retrace counted
    by benchmarks/robustness.py."""
    from continuation.pathfollow import Tracer
    prob, u = _pd22_problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pts, _, reason = Tracer(p_min=22.3, p_max=22.6).trace(prob, u, _PD22_F, direction=1)
    assert reason != "stuck at a corner"
    assert pts[-1].p > 22.5
    for q in pts:
        assert q.problem.minimal_order(q.u, q.p) == 2, q.p
    f = np.array([q.p for q in pts])
    assert np.all(np.diff(f) > -1e-6 * f[1:]), f  # no turn: this stretch has no fold
