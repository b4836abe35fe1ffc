"""Diagram-level promises: grazing points are marked and passed (no gap in the harmonic
branch), no branch or bifurcation is listed twice, superharmonic resonances against brute-force
spectra, and refined fold / period-doubling frequencies against harmonic balance."""
import dataclasses

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation.diagram import _halves_distance, _harmonic_amplitudes, _on_branch, _polish
from continuation.shooting import _problem_from_state, steady_state
from helpers import DUFF, F, hb_coefficients, hb_fold

A = 1e-4


@pytest.fixture(scope="module")
def grazing_diagram():
    m = nlbeam.BeamImpact.paper()
    return m, C.frequency_response(m, A, (9.0, 16.0), orders=(1,), n_grid=8)


def test_harmonic_branch_passes_grazing_points_without_gaps(grazing_diagram):
    m, frc = grazing_diagram
    iv = sorted((b.frequency.min(), b.frequency.max()) for b in frc.branches if b.order == 1)
    hi = iv[0][1]
    assert iv[0][0] <= 9.0
    for lo_, hi_ in iv[1:]:
        assert lo_ <= hi + 1e-6  # the branches join: no uncovered frequency
        hi = max(hi, hi_)
    assert hi >= 16.0
    graz = [b for b in frc.bifurcations if b.kind == "grazing"]
    assert len(graz) >= 2
    # at a grazing point the orbit touches the stop: the local maximum of delta nearest zero
    # is ~0 (closed form: zero velocity and zero penetration) compared with the orbit's size
    for g in graz:
        # below 9.5 Hz contacts chatter and nearly stick: there the impact count also changes
        # where a sticking contact splits with a gap of ~1e-11 m, which no sampled check sees
        if g.tolerance > 1e-6 * g.frequency or g.frequency < 9.5:
            continue
        tr = nlbeam.integrate(m, nlbeam.Harmonic(A, g.frequency), 1 / g.frequency,
                              x0=g.state0, dt=1 / (g.frequency * 4096), warn=False)
        d = tr.delta[:, 0]
        i = np.nonzero((d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:]))[0] + 1
        assert np.min(np.abs(d[i])) < 1e-3 * np.ptp(d), g


@pytest.fixture(scope="module")
def pd_diagram():
    m = nlbeam.BeamImpact.paper()
    return m, C.frequency_response(m, A, (15.0, 19.0), orders=(1, 2), n_grid=5)


def test_no_branch_or_bifurcation_twice(pd_diagram, grazing_diagram):
    """A branch that runs onto a traced one stops there: apart from its first and last three
    points (a start next to a traced branch, the steps that ran onto one), no point of one
    branch lies on another, except on the other's first or last segment. No bifurcation is
    listed twice."""
    m, frc = pd_diagram
    assert len([b for b in frc.branches if b.order == 1]) >= 1
    for i, b in enumerate(frc.branches):
        for j, o in enumerate(frc.branches):
            # o's own first and last three points are its start and the steps that ran onto
            # a traced branch: a stub of fewer than 7 points has no interior to overlap
            if i == j or len(o.frequency) < 7:
                continue
            trimmed = dataclasses.replace(o, frequency=o.frequency[3:-3], xmax=o.xmax[3:-3],
                                          state0=o.state0[3:-3])
            on = [k for k in range(3, len(b.frequency) - 3)
                  if _on_branch([trimmed], b.order, b.frequency[k], b.xmax[k],
                                b.state0[k][None, :]) is not None]
            assert on == []
    for m, frc in (pd_diagram, grazing_diagram):
        keys = [(bf.kind, bf.order, round(bf.frequency, 6)) for bf in frc.bifurcations]
        assert len(keys) == len(set(keys))
    pds = [bf for bf in pd_diagram[1].bifurcations if bf.kind == "period-doubling"]
    assert len(pds) >= 2


def test_superharmonic_resonance_of_order_2_against_brute_force():
    m = nlbeam.BeamImpact.paper()
    frc = C.frequency_response(m, A, (17.0, 50.0), orders=(1,), n_grid=4, switch=False)
    sup = [s for s in frc.superharmonics if s.harmonic == 2]
    assert len(sup) == 1
    f2 = sup[0].frequency
    f_res = max(frc.branches, key=lambda b: b.xmax.max())
    f_res = f_res.frequency[np.argmax(f_res.xmax)]
    assert abs(2 * f2 / f_res - 1) < 0.05  # near half the harmonic resonance
    # brute force (integration from rest): the second harmonic of x - y peaks there
    X2 = {}
    for f in (f2 - 1.0, f2, f2 + 0.2):  # (above f2 + 0.3: period-2 and irregular responses)
        X = _harmonic_amplitudes(m, A, f, steady_state(m, A, f, efolds=12))
        X2[f] = X[2]
    assert X2[f2] > 1.5 * max(X2[f2 - 1.0], X2[f2 + 0.2])


def test_refined_duffing_fold_matches_harmonic_balance_to_8_digits():
    model = nlbeam.Duffing(**DUFF)
    sol = C.periodic_solution(model, F, 0.1, dt_scale=0.2)
    frc = C.continue_parameter(sol, "frequency", (0.1, 0.5), model=model, dt_scale=0.2)
    fold = max((b for b in frc.bifurcations if b.kind == "fold"), key=lambda b: b.frequency)
    frc.parameter = "frequency"
    levels = tuple(C.Integrator(dt_scale=s) for s in (0.2, 0.1, 0.05, 0.025))
    r = C.refine(model, fold, F, levels=levels)
    c = hb_coefficients(model, r.state0, r.value, 10)
    f_hb = hb_fold(r.value, c, 10)
    assert r.digits > 8
    assert abs(r.value - f_hb) < 1e-8 * f_hb
    assert abs(r.value - f_hb) < 10 * r.tolerance + 1e-12  # the stated accuracy holds


def test_the_halves_vector_integrates_with_the_problems_steps_per_contact():
    # a period-1 orbit solved as a period-2 problem repeats after half the period: its halves
    # vector is zero to Newton's tolerance when it is integrated with the map that was solved
    # (steps_per_contact=8 here); before, it was integrated with the default 32 steps per
    # contact (issue 12), which leaves the integrator's difference
    from types import SimpleNamespace

    m = nlbeam.BeamImpact.paper()
    f = 44.0
    integ = C.Integrator(steps_per_contact=8)
    s0 = steady_state(m, A, f, integrator=integ)
    prob, u0 = _problem_from_state(m, A, f, 2, s0, 1, integ)
    prob, u, p = _polish(prob, u0, f, 1e-11)
    assert prob.minimal_order(u, p) == 1
    assert _halves_distance(SimpleNamespace(problem=prob, u=u, p=p)) < 1e-8
    # the same distance with the default steps per contact: what the slip computed
    default = _problem_from_state(m, A, f, 2, s0, 1, C.Integrator())[0]
    default.boundaries, default.scale_u = prob.boundaries, prob.scale_u
    default.steps_per_period = prob.steps_per_period
    assert _halves_distance(SimpleNamespace(problem=default, u=u, p=p)) > 1e-6


def test_harmonic_amplitudes_follow_the_integrator():
    # the superharmonics' spectra are integrated with the diagram's integrator: refining its
    # contact steps converges (before, the integrator was ignored and all three were equal)
    m = nlbeam.BeamImpact.paper()
    f = 44.0
    s0 = steady_state(m, A, f, efolds=12)
    X = {spc: _harmonic_amplitudes(m, A, f, s0, integrator=C.Integrator(steps_per_contact=spc))
         for spc in (16, 64, 256)}
    e16 = np.max(np.abs(X[16] - X[256]))
    e64 = np.max(np.abs(X[64] - X[256]))
    assert 0 < 4 * e64 < e16
    assert np.array_equal(_harmonic_amplitudes(m, A, f, s0),
                          _harmonic_amplitudes(m, A, f, s0, integrator=C.Integrator()))


def test_a_point_past_a_discontinuous_map_end_is_not_on_that_branch():
    """The far side of a jump of the map (an orbit just beyond a 'discontinuous map' end, close
    to the end point in (f, xmax, state)) is not taken for the branch: before, the far-side
    branch at 9.19509 Hz (paper model, A = 0.1 mm, dt caps) stopped there as 'ran onto a traced
    branch' and left 9.19460-9.19509 Hz uncovered. Between a segment's ends, or past an end
    of another kind, the same point is on the branch."""
    from types import SimpleNamespace

    f = np.array([9.1940, 9.1943, 9.1945, 9.1946])
    xm = np.full(4, 1.26e-4)
    s0 = np.tile([9.93e-5, -8.33e-4], (4, 1))
    w = 2 * np.pi * 9.195

    def branch(ends):
        return SimpleNamespace(order=1, frequency=f, xmax=xm, state0=s0, ends=ends)

    past = (9.1951, 1.2614e-4, s0[-1] * (1 + 1e-3))  # beyond the last end, within tolerances
    inside = (9.19445, 1.2602e-4, s0[-1] * (1 + 1e-3))
    for fp, xp, sp in (past, inside):
        assert np.max(np.abs(sp - s0[-1]) / np.r_[xp, xp * w]) < 0.05
    assert _on_branch([branch(("", "discontinuous map"))], 1, *past) is None
    assert _on_branch([branch(("", "left the parameter range"))], 1, *past) == 0
    assert _on_branch([branch(("", "discontinuous map"))], 1, *inside) == 0
    # the same at the first end, the branch stored in the other direction
    rev = SimpleNamespace(order=1, frequency=f[::-1], xmax=xm, state0=s0,
                          ends=("discontinuous map", ""))
    assert _on_branch([rev], 1, *past) is None
