"""Continuing an element parameter of a general System (issue 14): the gap of a linear stop,
named ``elements[0].gap`` as nlbeam.parameters names it, against solutions and diagrams
recomputed at fixed gaps.

The system: x'' + 0.1 x' + x + 4 max(x - gap, 0) = 0.1 cos(2 pi 0.12 t) (force-excited, the
stop on the mass). At f = 0.12 Hz the linear response is 0.23; continued in the gap from
0.1 over [0.02, 0.3] the order-1 orbit period-doubles twice (near gap 0.159 and 0.225) and
grazes the stop near 0.228.
"""
import warnings

import numpy as np
import pytest

import continuation
import nlbeam
from continuation import ContinuationWarning
from nlbeam.parameters import get_parameter, parameter_names, with_parameter

F, F0 = 0.1, 0.12


def _model(gap):
    stop = nlbeam.PiecewiseLinearStop(0, k=4.0, gap=gap, on_base=False)
    return nlbeam.System([[1.0]], [[0.1]], [[1.0]], (stop,), "force")


@pytest.fixture(scope="module")
def gap_branch():
    m = _model(0.1)
    sol = continuation.periodic_solution(m, F, F0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContinuationWarning)
        frc = continuation.continue_parameter(sol, "elements[0].gap", (0.02, 0.3), model=m,
                                              accuracy="off")
    return frc


def test_the_gap_branch_is_the_solutions_at_fixed_gaps(gap_branch):
    br = gap_branch.branches[0]
    assert br.parameter == "elements[0].gap"
    assert br.values.min() <= 0.02 and br.values.max() >= 0.3  # the whole range
    for g in (0.05, 0.1, 0.2, 0.25):
        j = int(np.argmin(np.abs(br.values - g)))
        fixed = continuation.periodic_solution(_model(float(br.values[j])), F, F0,
                                               guess=br.state0[j], error=False)
        # the same orbit of the same discrete map: to Newton's tolerance
        assert abs(fixed.xmax - br.xmax[j]) <= 1e-8 * fixed.xmax, g


def test_a_period_doubling_in_the_gap_is_one_of_the_diagram_at_that_gap():
    """With error estimates (accuracy 'default'), the frequency diagram recomputed at the
    gap of each period doubling has one at 0.12 Hz. Measured: 6e-6 and 8e-6 of f (its
    stated errors say 1.4e-5 and 3e-7): asserted to 2e-5 of f."""
    m = _model(0.1)
    sol = continuation.periodic_solution(m, F, F0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContinuationWarning)
        frc = continuation.continue_parameter(sol, "elements[0].gap", (0.02, 0.3), model=m)
        pds = [b for b in frc.bifurcations if b.kind == "period-doubling"]
        assert len(pds) == 2
        for b in pds:
            d = continuation.frequency_response(_model(b.value), F, (0.11, 0.13), orders=(1,),
                                                n_grid=3)
            f = [x.value for x in d.bifurcations if x.kind == "period-doubling"
                 and x.order == 1]
            assert min(abs(np.array(f) - F0)) <= 2e-5 * F0, (b.value, f)


def test_a_name_that_does_not_exist_lists_those_that_do():
    m = _model(0.1)
    assert parameter_names(m) == ["elements[0].k", "elements[0].gap"]
    with pytest.raises(ValueError) as err:
        continuation.continue_parameter(None, "gap", (0.0, 1.0), model=m)
    msg = str(err.value)
    assert "'gap'" in msg and "frequency, amplitude, elements[0].k, elements[0].gap" in msg
    m2 = with_parameter(m, "elements[0].gap", 0.2)
    assert get_parameter(m2, "elements[0].gap") == 0.2 and m.element_geometry()[3][0] == 0.1
    assert m2.element_geometry()[3][0] == 0.2  # the arrays the kernels read follow
    beam = with_parameter(nlbeam.BeamImpact(), "gap", 1e-4)
    assert beam.system.element_geometry()[3][0] == 1e-4 and beam.gap == 1e-4


@pytest.mark.slow  # 30 s CPU
def test_a_period_doubling_curve_in_frequency_and_gap_agrees_with_diagrams_at_fixed_gaps():
    """bifurcation_curve with the stop's gap (``elements[0].gap``) as the second parameter:
    the period-doubling curve of the order-1 orbit in (f, gap), traced from the diagram at
    gap 0.19, is U-shaped (two period doublings at each gap in 0.17-0.22). At three fixed gaps
    its two frequencies agree with the closed-form period doublings of tests/exact_pwl.py
    (exact piecewise-linear flow, det(M + I) = 0) and with nlbeam's frequency diagram at that
    gap, within the sum of the stated errors (curve: BifurcationCurve.error; diagram:
    Bifurcation.error). Measured: |curve - exact| up to 4e-8 Hz against stated curve errors
    0.5e-8 to 7e-8 Hz (30 s CPU)."""
    import exact_pwl

    g0, gaps = 0.19, (0.17, 0.2, 0.22)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContinuationWarning)
        d0 = continuation.frequency_response(_model(g0), F, (0.10, 0.14), orders=(1,))
    pd = [b for b in d0.bifurcations if b.kind == "period-doubling"][0]
    c = continuation.bifurcation_curve(_model(g0), pd, (0.15, 0.23), amplitude=F,
                                       parameter="elements[0].gap", f_range=(0.09, 0.16),
                                       at=gaps)
    assert c.parameter == "elements[0].gap" and c.ends == ("left the parameter range",) * 2
    for g in gaps:
        f_curve, err = c.at(g), c.error_at(g)
        assert len(f_curve) == 2 and np.all(np.isfinite(err)), (g, f_curve, err)
        osc = exact_pwl.StopOscillator(1.0, 0.1, 1.0, 4.0, g, F)
        exact = exact_pwl.trace(osc, 0.10, exact_pwl.free_orbit_state(osc, 0.10), 0.10, 0.14)
        assert len(exact.period_doublings) == 2
        for f_ex in exact.period_doublings:
            j = int(np.argmin(np.abs(f_curve - f_ex)))
            assert abs(f_curve[j] - f_ex) <= err[j] + 1e-12 * f_ex, (g, f_curve[j], f_ex, err[j])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ContinuationWarning)
            d = continuation.frequency_response(_model(g), F, (0.10, 0.14), orders=(1,))
        f_diag = [(b.frequency, b.error) for b in d.bifurcations
                  if b.kind == "period-doubling" and b.order == 1]
        assert len(f_diag) == 2, (g, f_diag)
        for f_d, e_d in f_diag:
            j = int(np.argmin(np.abs(f_curve - f_d)))
            assert abs(f_curve[j] - f_d) <= err[j] + e_d, (g, f_curve[j], f_d, err[j], e_d)


def test_bifurcation_curve_names_the_parameters_that_exist():
    m = _model(0.1)
    bf = {"kind": "fold", "frequency": F0, "order": 1, "state0": [0.1, 0.0]}
    with pytest.raises(ValueError) as err:
        continuation.bifurcation_curve(m, bf, (0.0, 1.0), amplitude=F, parameter="gap")
    msg = str(err.value)
    assert "'gap'" in msg and "amplitude, elements[0].k, elements[0].gap" in msg
    with pytest.raises(ValueError, match="first parameter"):
        continuation.bifurcation_curve(m, bf, (0.0, 1.0), amplitude=F, parameter="frequency")


def _two_oscillators(gap):
    """Two uncoupled oscillators forced together (F = 0.1 N on each): a Duffing
    x1'' + 0.1 x1' + 0.18 x1 + x1^3 (a fold near 0.117 Hz) and the stop oscillator of this
    module on x2, whose period doublings in (f, gap) are U-shaped. The monodromy is block
    diagonal: the Duffing's fold curve is the line f = f_fold in (f, gap), and it meets the
    stop oscillator's period-doubling curve in fold-flip points."""
    els = (nlbeam.CubicSpring(0, k3=1.0), nlbeam.PiecewiseLinearStop(1, k=4.0, gap=gap))
    return nlbeam.System(np.eye(2), 0.1 * np.eye(2), np.diag([0.18, 1.0]), els, "force",
                         y_load=[1.0, 1.0], yd_load=[0.0, 0.0], output_dof=1)


def test_fold_flip_points_where_a_fold_curve_meets_a_period_doubling_curve():
    """The fold curve of the two oscillators in (f, elements[1].gap) meets two fold-flip
    points; each is where the stop oscillator alone has a multiplier -1 at that frequency,
    solved in closed form (tests/exact_pwl: det(M + I) = 0 in the gap, Brent), to the stated
    error (bracket + integration error); the stop oscillator's diagram at that gap has a
    period doubling at the fold's frequency. Measured: the gaps 0.1649073 and 0.2127250 agree
    with the exact ones to 4e-8 and 1e-8 (bracket 1e-11)."""
    import scipy.optimize

    import exact_pwl

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContinuationWarning)
        d = continuation.frequency_response(_two_oscillators(0.2), F, (0.1, 0.13), orders=(1,))
    fold = [b for b in d.bifurcations if b.kind == "fold"][0]
    c = continuation.bifurcation_curve(_two_oscillators(0.2), fold, (0.15, 0.23), amplitude=F,
                                       parameter="elements[1].gap", f_range=(0.1, 0.13))
    ff = [p for p in c.special if p.kind == "fold-flip"]
    assert len(ff) == 2, c.special
    for p in ff:
        assert abs(p.frequency - fold.frequency) <= 1e-6 * fold.frequency  # the line

        def det(g, f=p.frequency):
            osc = exact_pwl.StopOscillator(1.0, 0.1, 1.0, 4.0, g, F)
            o = exact_pwl.orbit(osc, f, exact_pwl.free_orbit_state(osc, f))
            return np.linalg.det(o.monodromy + np.eye(2))

        g = scipy.optimize.brentq(det, p.value - 0.01, p.value + 0.01, xtol=1e-14)
        assert abs(p.value - g) <= p.error_value, (p, g)
        assert p.error_value <= 1e-6 * g  # located, not only bracketed
        # one-parameter diagrams: the stop oscillator alone at that gap doubles its period
        # at the fold's frequency (at the fold-flip gap the two oscillators' branch turns
        # where the multiplier reaches -1, so their own diagram shows the fold only)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ContinuationWarning)
            dg = continuation.frequency_response(_model(p.value), F, (0.11, 0.125),
                                                 orders=(1,))
        f = [(b.frequency, b.error) for b in dg.bifurcations if b.kind == "period-doubling"]
        # the point's gap error moves the period doubling by slope * error_value (the slope
        # df/dgap of det(M + I) = 0, from the closed form)
        h = 1e-6
        slope = -(det(g + h) - det(g - h)) / (det(g, p.frequency + h * 1e-2)
                                              - det(g, p.frequency - h * 1e-2)) * 1e-2
        assert min(abs(fb - p.frequency) - eb for fb, eb in f) <= p.error_frequency + \
            fold.error + abs(slope) * p.error_value, (f, p, slope)


@pytest.mark.slow  # 20 s CPU
def test_a_closed_period_doubling_curve_in_frequency_and_gap_is_closed_once():
    """Over gaps 0.15-0.26 the period-doubling curve of the module's system is a closed loop
    (its two period doublings merge near gap 0.241): the trace stops 'closed' after one
    round (before, it went round until max_points: the states of the same orbit differ
    after the shooting problem is rephased, so a closure test in all unknowns missed it).
    Checked against the closed form: at 0.98 of the loop's largest gap the exact branch
    has two period doublings, at 1.02 of it none."""
    import exact_pwl

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContinuationWarning)
        d0 = continuation.frequency_response(_model(0.19), F, (0.10, 0.14), orders=(1,),
                                             accuracy="off")
    pd = [b for b in d0.bifurcations if b.kind == "period-doubling"][0]
    c = continuation.bifurcation_curve(_model(0.19), pd, (0.15, 0.26), amplitude=F,
                                       parameter="elements[0].gap", f_range=(0.09, 0.16),
                                       error=False)
    assert c.ends == ("closed", "closed") and len(c.frequency) < 200, (c.ends, len(c.frequency))
    g_top = float(c.values.max())
    # one round: the loop's largest gap is reached once (one local maximum of the gap)
    dv = np.sign(np.diff(c.values))
    dv = dv[dv != 0]
    assert np.sum((dv[:-1] > 0) & (dv[1:] < 0)) == 1, c.values
    for g, n in ((0.98 * g_top, 2), (1.02 * g_top, 0)):
        osc = exact_pwl.StopOscillator(1.0, 0.1, 1.0, 4.0, g, F)
        ex = exact_pwl.trace(osc, 0.10, exact_pwl.free_orbit_state(osc, 0.10), 0.10, 0.14)
        assert len(ex.period_doublings) == n, (g, ex.period_doublings)
