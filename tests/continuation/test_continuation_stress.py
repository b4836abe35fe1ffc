"""Continuation under stress and the options that skip work: a Neimark-Sacker point where it is
known in closed form, strongly unstable orbits (multipliers > 1e6: single shooting fails,
multiple shooting succeeds), a period-2 request that lands on a period-1 orbit, and
stability=False against stability=True."""
import dataclasses
import warnings

import numpy as np
import pytest
import scipy.optimize

import continuation as C
from continuation.refine import LEVELS
import nlbeam

F = 0.2  # N, Duffing forcing


@dataclasses.dataclass(frozen=True)
class SignedDuffing(nlbeam.Duffing):
    """Duffing whose damping b may be negative (nlbeam.Duffing refuses b < 0)."""

    def __post_init__(self):
        object.__setattr__(self, "system", nlbeam.System(
            [[self.m]], [[self.b]], [[self.k]], (nlbeam.CubicSpring(0, self.k3),), "force",
            y_load=[1.0], yd_load=[0.0], output_dof=0))


def test_neimark_sacker_point_at_zero_damping():
    """A 1-DOF orbit has det M = exp(-b T / m) (Liouville), so a complex pair of multipliers
    has |mu| = exp(-b T / (2 m)) and crosses the unit circle exactly at b = 0."""
    m = SignedDuffing(b=0.05)
    sol = C.periodic_solution(m, F, 0.1, dt_scale=0.5)
    assert abs(sol.multipliers[0].imag) > 0.1  # a complex pair
    assert np.allclose(np.abs(sol.multipliers), np.exp(-0.05 * 10.0 / 2), rtol=1e-7)
    frc = C.continue_parameter(sol, "b", (-0.05, 0.05), model=m, dt_scale=0.5)
    ns = [b for b in frc.bifurcations if b.kind == "neimark-sacker"]
    assert len(ns) == 1, frc.bifurcations
    assert abs(ns[0].value) < 1e-7  # b = 0 kg/s
    assert np.allclose(np.abs(ns[0].multipliers), 1.0, atol=1e-6)
    assert not [b for b in frc.bifurcations if b.kind in ("fold", "period-doubling")]


def _quasi_static(n, f=0.02):
    """States at phases j / n of the slow orbit's quasi-static approximation x + x^3 = F cos."""
    return np.array([[scipy.optimize.brentq(lambda x: x + x ** 3 - F * np.cos(2 * np.pi * j / n),
                                            -2.0, 2.0), 0.0] for j in range(n)])


def test_strongly_unstable_orbit_needs_multiple_shooting():
    """Anti-damped Duffing (b = -0.6) forced at 0.02 Hz: multipliers ~3e6. From the same
    quasi-static guess single shooting fails (its Newton step runs away), 8 segments converge;
    the product of the multipliers equals exp(-b T / m) (Liouville) to 1e-5."""
    m = SignedDuffing(b=-0.6)
    with pytest.raises(C.ConvergenceError, match="multiple"):
        C.periodic_solution(m, F, 0.02, guess=_quasi_static(1), dt_scale=0.5)
    sol = C.periodic_solution(m, F, 0.02, guess=_quasi_static(8), segments=8, dt_scale=0.5)
    assert np.abs(sol.multipliers[0]) > 1e6
    assert sol.residual < 1e-10
    assert abs(np.prod(sol.multipliers).real / np.exp(0.6 * 50.0) - 1) < 1e-5
    assert sol.stable is False


def test_order_2_request_that_finds_a_period_1_orbit_is_flagged():
    m = nlbeam.BeamImpact.paper()
    with pytest.warns(C.ContinuationWarning, match="repeats after 1 excitation period"):
        sol = C.periodic_solution(m, 1e-4, 44.0, order=2)  # the attractor there is period 1
    assert sol.minimal_order == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", C.ContinuationWarning)
        sub = C.periodic_solution(m, 1e-4, 90.0, order=2)  # the stable 1/2 subharmonic
    assert sub.minimal_order == 2


def test_stability_false_agrees_with_stability_true():
    m = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    kw = dict(orders=(1,), n_grid=5, dt_scale=0.2)
    full = C.frequency_response(m, F, (0.1, 0.5), **kw)
    bare = C.frequency_response(m, F, (0.1, 0.5), stability=False, **kw)
    (b,) = bare.branches
    assert b.stable is None and b.multipliers is None and bare.settings["stability"] == 0
    # the same folds (passed, and located from the tangent instead of the multipliers)
    ff = sorted(x.frequency for x in full.bifurcations if x.kind == "fold")
    fb = sorted(x.frequency for x in bare.bifurcations if x.kind == "fold")
    assert len(ff) == len(fb) == 2
    assert np.allclose(fb, ff, rtol=1e-8)
    # the same orbits: xmax of the bare branch's points equals shooting with stability
    for i in np.linspace(0, len(b.values) - 1, 5).astype(int):
        ref = C.periodic_solution(m, F, b.frequency[i], guess=b.state0[i], dt_scale=0.2)
        assert abs(ref.xmax - b.xmax[i]) < 1e-8 * ref.xmax
    # periodic_solution: no multipliers, same xmax
    s1 = C.periodic_solution(nlbeam.BeamImpact.paper(), 1e-4, 44.0)
    s0 = C.periodic_solution(nlbeam.BeamImpact.paper(), 1e-4, 44.0, guess=s1, stability=False)
    assert s0.multipliers is None and s0.stable is None and s0.monodromy is None
    assert abs(s0.xmax - s1.xmax) < 1e-9 * s1.xmax


def test_branch_passes_a_grazing_point_where_the_linear_amplitude_reaches_the_gap():
    """A linear oscillator (m = k = 1, b = 0.1) forced by 0.5 cos(2 pi f t), with a Hertz stop
    at x = 1 m: below resonance the orbit is linear (amplitude F / |k - m w^2 + i b w|) until
    that amplitude equals the gap; there an impact appears. The branch goes on past it, and
    the grazing point is reported at the closed-form frequency."""
    m_, b_, k_, gap, force = 1.0, 0.1, 1.0, 1.0, 0.5
    model = nlbeam.System([[m_]], [[b_]], [[k_]],
                          (nlbeam.Contact(0, "hertz", K=1e3, gap=gap, on_base=False),), "force",
                          y_load=[1.0], yd_load=[0.0], output_dof=0)

    def amplitude(f):
        w = 2 * np.pi * f
        return force / np.hypot(k_ - m_ * w ** 2, b_ * w)

    f_graze = scipy.optimize.brentq(lambda f: amplitude(f) - gap, 0.05, 0.159)
    sol = C.periodic_solution(model, force, 0.1)
    assert abs(sol.xmax - amplitude(0.1)) < 1e-6 * amplitude(0.1)  # linear below grazing
    frc = C.continue_parameter(sol, "frequency", (0.08, 0.16), model=model)
    (br,) = frc.branches
    assert br.frequency.min() <= 0.08 and br.frequency.max() >= 0.16  # passed, both ways
    graz = [b for b in frc.bifurcations if b.kind == "grazing"]
    assert len(graz) == 1
    assert abs(graz[0].frequency - f_graze) <= graz[0].tolerance + 1e-6 * f_graze
    assert graz[0].tolerance < 1e-5 * f_graze


def test_refinement_restarts_inside_a_contact_with_its_memory(tmp_path):
    """The period doubling near 12.68 Hz (paper model) has t = 0 inside a Lankarani-Nikravesh
    contact: restarting from the state alone loses the onset velocity and the refinement did
    not converge. With the contact state kept (Bifurcation.disc0, saved too) it converges, to a
    frequency near the diagram's."""
    m = nlbeam.BeamImpact.paper()
    frc = C.frequency_response(m, 1e-4, (12.0, 13.5), orders=(1,), n_grid=4)
    (pd,) = [b for b in frc.bifurcations if b.kind == "period-doubling"]
    assert pd.disc0 is not None and pd.disc0[0, 0] == 1.0  # in contact at t = 0
    frc.save(tmp_path / "d.h5")
    i = frc.bifurcations.index(pd)
    assert np.array_equal(C.load(tmp_path / "d.h5").bifurcations[i].disc0, pd.disc0)
    f_diagram = pd.frequency
    (bf, r), = C.refine_bifurcations(frc, m, kinds=("period-doubling",),
                                     levels=LEVELS[:3], max_levels=3)
    assert isinstance(r, C.Refined), r
    assert abs(r.value - f_diagram) < 1e-2 and r.tolerance < 1e-4  # 3 levels only
    # the refinement is saved with the diagram and loaded back (issue 16)
    frc.save(tmp_path / "r.h5")
    back = C.load(tmp_path / "r.h5").bifurcations[i]
    assert back.refine_status == "refined" and back.refined is not None
    assert back.refined.value == r.value and back.refined.tolerance == r.tolerance
    assert np.array_equal(back.refined.values, r.values) and back.error == r.tolerance
    assert back.frequency == r.value


def test_no_progress_rule_stops_the_branch_loudly():
    """A branch whose last points advance less than progress_min (here set so that every
    branch qualifies) stops with a ContinuationWarning that says where and what to change."""
    from continuation.pathfollow import Tracer
    from continuation.shooting import _problem_from_state

    m = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    sol = C.periodic_solution(m, F, 0.3, dt_scale=0.5)
    prob, u0 = _problem_from_state(m, F, 0.3, 1, sol.state0, 1, C.Integrator(dt_scale=0.5))
    tracer = Tracer(p_min=0.1, p_max=0.5, progress_points=5, progress_min=1e3, label="test branch")
    with pytest.warns(C.ContinuationWarning,
                      match=r"test branch made no progress near 0\.\d+ .*dt_scale=0\.5"):
        pts, _, reason = tracer.trace(prob, u0, 0.3)
    assert reason == "no progress" and len(pts) == 6


def test_every_branch_says_why_it_ended_and_early_ends_are_loud(tmp_path):
    """Branch.ends records why the trace stopped at each end; an end inside the range where the
    tracer gave up (here: the point budget) raises one ContinuationWarning naming it, and a start
    given by the caller that does not converge is not dropped silently."""
    m = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    kw = dict(orders=(1,), n_grid=3, dt_scale=0.2, switch=False)
    full = C.frequency_response(m, F, (0.1, 0.5), **kw)
    assert [b.ends for b in full.branches] == [("left the parameter range",) * 2]
    early = r"branch 1 \(order 1\) at [0-9.]+ \(max_points\)"
    with pytest.warns(C.ContinuationWarning, match=early):
        short = C.frequency_response(m, F, (0.1, 0.5), max_points=5, **kw)
    b = short.branches[0]  # (the grid's other attractors start short branches of their own)
    assert b.ends == ("left the parameter range", "max_points") and 0.1 < b.values[-1] < 0.5
    short.save(tmp_path / "short.h5")
    assert C.load(tmp_path / "short.h5").branches[0].ends == b.ends
    bad = (0.3, 1, np.array([1e9, -1e9]))  # far from any orbit: Newton cannot converge
    with pytest.warns(C.ContinuationWarning, match="start at 0.3 Hz .order 1. did not converge"):
        C.frequency_response(m, F, (0.1, 0.5), brute_force_grid=False, starts=[bad], **kw)
