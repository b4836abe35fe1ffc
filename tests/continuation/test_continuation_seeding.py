"""Seeding finds every attractor the grid passes: a lightly damped attractor that has not
settled after the grid's integration is found by shooting from its end state; the periodicity
test is scale-free; a candidate that is an orbit of lower order is traced as that order, not
dropped."""
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation.diagram import _polished_starts
from continuation.seeding import brute_force, periodicity, state_scales
from continuation.shooting import Integrator, steady_state
from nlbeam import CubicSpring, PiecewiseLinearStop, System


def duffing_with_stop():
    """Issue 13 item 2: a hardening Duffing oscillator (f_n = 1 Hz, damping ratio 0.02) with a
    one-sided stop at 0.5 m, force excitation."""
    return System([[1.0]], [[0.2513]], [[39.48]],
                  elements=(CubicSpring(0, k3=10.0),
                            PiecewiseLinearStop(0, k=789.6, gap=0.5, on_base=False)),
                  excitation_kind="force", y_load=[1.0])


def stiff_stop(fn=20.0, zeta=0.02, ratio=100.0, gap=1e-4):
    """Issue 13 item 7: 1 kg on a spring (f_n Hz, damping ratio zeta) with a one-sided linear
    stop ``ratio`` times stiffer after a gap (m), force excitation."""
    k = (2 * np.pi * fn) ** 2
    return System([[1.0]], [[2 * zeta * np.sqrt(k)]], [[k]],
                  elements=(PiecewiseLinearStop(0, k=ratio * k, gap=gap, on_base=False),),
                  excitation_kind="force", y_load=[1.0])


def _covers(frc, order, lo, hi):
    iv = sorted((b.frequency.min(), b.frequency.max()) for b in frc.branches
                if b.order == order)
    if not iv or iv[0][0] > lo:
        return False
    reach = iv[0][1]
    for a, b in iv[1:]:
        if a > reach:
            return False
        reach = max(reach, b)
    return reach >= hi


def _points_near(frc, order, f, rel=0.05):
    """(frequency, xmax) of the stable branch point of the order nearest f on each branch
    that passes within ``rel`` of f."""
    out = []
    for b in frc.branches:
        if b.order != order:
            continue
        i = int(np.argmin(np.abs(b.frequency - f)))
        if abs(b.frequency[i] - f) < rel * f and b.stable[i]:
            out.append((float(b.frequency[i]), float(b.xmax[i])))
    return out


def test_periodicity_is_scale_free_and_ignores_components_near_zero():
    f = 3.0
    w = 2 * np.pi * f
    k = np.arange(12)
    # a period-1 orbit sampled at its turning point (velocity ~ 0), with a decaying transient
    x = 1e-3 * (1 + 1e-6 * 0.5 ** k)
    v = 1e-3 * w * 1e-9 * (-0.5) ** k  # a velocity of 1e-9 of the orbit's
    S = np.c_[x, v]
    r = periodicity(S, 1, f)
    assert r < 1e-6  # old test: |dv| / max|v| ~ 1.5: "not settled"
    for lam in (1e-6, 1e3):
        assert periodicity(lam * S, 1, f) == pytest.approx(r, rel=1e-12)
    np.testing.assert_allclose(state_scales(S, f), [1e-3 * (1 + 1e-6), 1e-3 * (1 + 1e-6) * w])
    # a period-2 orbit is not of order 1
    S2 = np.c_[1e-3 * (-1.0) ** k, np.zeros(12)]
    assert periodicity(S2, 1, f) == pytest.approx(2.0)
    assert periodicity(S2, 2, f) == 0.0


def test_lightly_damped_attractor_is_found_by_shooting_from_the_grid():
    """Duffing with a stop, 1.5-3 Hz: the non-impacting orbit has multipliers of modulus 0.94
    (the transient at the free frequency, half the forcing's, decays by 6 % a period); the old
    settling test rejected it at every grid frequency: an empty diagram without a warning."""
    sysm = duffing_with_stop()
    ref = C.periodic_solution(sysm, 2.0, 2.0)
    assert ref.stable and abs(abs(ref.multipliers[0]) - 0.94) < 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("error", C.ContinuationWarning)
        frc = C.frequency_response(sysm, 2.0, (1.5, 3.0), orders=(1, 2))
    assert _covers(frc, 1, 1.5, 3.0)
    pts = _points_near(frc, 1, 2.0)
    assert len(pts) == 1
    f, xm = pts[0]
    assert abs(C.periodic_solution(sysm, 2.0, f).xmax - xm) < 1e-8 * xm


def test_lower_order_candidate_is_traced_as_its_order():
    """At 2 Hz the slow transient alternates sign every period: its states repeat after two
    periods long before after one, so the settling test calls the grid's candidate order 2.
    Polished as order 2 it is the order-1 orbit; it used to be dropped silently."""
    sysm = duffing_with_stop()
    integ = Integrator()
    cand = brute_force(sysm, 2.0, np.array([2.0]), (1, 2), integ)
    assert cand and all(n in (1, 2) for _, n, _ in cand)
    s_end = steady_state(sysm, 2.0, 2.0, efolds=6.0, min_periods=40)
    dropped = []
    seeds = _polished_starts(sysm, 2.0, None, "frequency", (1, 2), [(2.0, 2, s_end, False)], 1,
                             integ, True, 1e-10, dropped)
    assert [s[1] for s in seeds] == [1] and dropped == []
    # an order not asked for is said, not dropped quietly
    dropped = []
    seeds = _polished_starts(sysm, 2.0, None, "frequency", (2,), [(2.0, 2, s_end, False)], 1,
                             integ, True, 1e-10, dropped)
    assert seeds == [] and len(dropped) == 1 and "order 1" in dropped[0][1]


def test_paper_model_grid_at_low_frequency_finds_the_harmonic_orbit():
    """Issue 18: 0.5-2 Hz (n_grid 5) gave 0 branches: the velocity sampled once a period is
    near zero there, and the old test divided by it. Each grid candidate is the orbit that
    periodic_solution finds at its frequency."""
    m = nlbeam.BeamImpact.paper()
    grid = np.linspace(0.5, 2.0, 5)
    cand = brute_force(m, 1e-4, grid, (1,), Integrator())
    assert sorted({f for f, _, _ in cand}) == pytest.approx(list(grid))
    for f, n, s0 in cand[::3]:
        ref = C.periodic_solution(m, 1e-4, f)
        assert n == 1
        sol = C.periodic_solution(m, 1e-4, f, guess=s0)
        assert abs(sol.xmax - ref.xmax) < 1e-9 * ref.xmax


def test_a_range_with_no_periodic_attractor_says_so():
    """Issue 18: 500-1000 Hz (n_grid 5) returned 0 branches without a word. There the
    integration reaches no periodic attractor and shooting does not converge either (at 750 Hz:
    residual 9e-2 after 15 iterations): an empty diagram must come with the grid's verdict and
    the uncovered range."""
    m = nlbeam.BeamImpact.paper()
    with pytest.raises(C.ConvergenceError):
        C.periodic_solution(m, 1e-4, 750.0, error=False)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        frc = C.frequency_response(m, 1e-4, (500.0, 1000.0), orders=(1,), n_grid=5)
    text = [str(x.message) for x in w if issubclass(x.category, C.ContinuationWarning)]
    assert not frc.branches
    assert any("no periodic attractor" in t and "750 Hz: not periodic" in t for t in text)
    assert any("not covered: order 1: 500-1000 Hz (no branch)" in t for t in text)


@pytest.mark.slow
def test_paper_model_at_low_frequency_finds_the_harmonic_branch():
    m = nlbeam.BeamImpact.paper()
    ref = C.periodic_solution(m, 1e-4, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        frc = C.frequency_response(m, 1e-4, (0.5, 2.0), orders=(1,), n_grid=5)
    assert _covers(frc, 1, 0.5, 2.0)
    x = [b.xmax[np.argmin(np.abs(b.frequency - 1.0))] for b in frc.branches
         if abs(b.frequency - 1.0).min() < 0.05]
    assert x and min(abs(v - ref.xmax) for v in x) < 0.02 * ref.xmax


def test_stiff_stop_diagram_is_not_empty():
    """Issue 13 item 7: a stop 100x the structure's stiffness, gap 0.1 mm, 15-100 Hz: the grid's
    candidates were classed order 2 (their transient alternates) and dropped when they turned
    out to be order 1: an empty diagram. Now the harmonic branch covers the range, and where it
    is stable it agrees with a long integration (an independent method)."""
    sysm = stiff_stop()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        frc = C.frequency_response(sysm, 1.0, (15.0, 100.0), orders=(1, 2))
    assert _covers(frc, 1, 15.0, 100.0)
    for f in (25.0, 40.0, 60.0, 90.0):
        s = steady_state(sysm, 1.0, f, efolds=30.0)  # the attractor reached from rest
        tr = nlbeam.integrate(sysm, nlbeam.Harmonic(1.0, f), 2 / f, x0=s, dt=1 / (f * 4000),
                              warn=False)
        xm = np.max(np.abs(tr.x[:, 0]))
        on = _interpolated(frc, f)
        assert on and min(abs(v - xm) for v in on) < 1e-2 * xm, (f, xm, on)


def _interpolated(frc, f):
    """xmax of every stable stretch of every branch at f, linear between branch points."""
    out = []
    for b in frc.branches:
        F, X = b.frequency, b.xmax
        for i in range(len(F) - 1):
            if (min(F[i], F[i + 1]) <= f <= max(F[i], F[i + 1]) and b.stable[i]
                    and b.stable[i + 1] and F[i] != F[i + 1]):
                out.append(X[i] + (f - F[i]) / (F[i + 1] - F[i]) * (X[i + 1] - X[i]))
    return out


def test_grid_attractor_that_the_diagram_does_not_show_is_loud():
    """An attractor the grid integrated is never hidden: where it is of an order not asked for
    (the Duffing's order-1 orbit, orders=(2,)), or not periodic (the paper model at 25 Hz,
    A = 0.1 mm: no orbit of orders 1-3 is stable there), and no branch is stable, one
    ContinuationWarning names each grid frequency."""
    with pytest.warns(C.ContinuationWarning, match=r"4 grid frequencies.*2 Hz: the order-2 "
                      r"candidate is an orbit of order 1, not asked for"):
        frc = C.frequency_response(duffing_with_stop(), 2.0, (1.5, 3.0), orders=(2,), n_grid=4)
    assert frc.branches == []
    with pytest.warns(C.ContinuationWarning, match=r"2 grid frequencies.*24\.9 Hz: not periodic"
                      r".*25\.1 Hz: not periodic"):
        frc = C.frequency_response(nlbeam.BeamImpact.paper(), 1e-4, (24.9, 25.1),
                                   orders=(1, 2, 3), n_grid=2)
    assert not any(b.stable.any() for b in frc.branches)
    # and where the diagram has the attractor, no such warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", C.ContinuationWarning)
        C.frequency_response(duffing_with_stop(), 2.0, (1.5, 3.0), orders=(1, 2), n_grid=4)
