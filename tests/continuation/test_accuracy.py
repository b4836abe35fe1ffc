"""Error estimates (continuation.accuracy) against converged values computed here independently:
orbits re-solved with both steps divided by 16 and their multipliers from central differences
of that fine map (no variational equations), bifurcation frequencies from another method at a
finer step, grazing frequencies and xmax of a piecewise-linear stop from the exact linear
solution."""
import dataclasses
import warnings

import numpy as np
import pytest
import scipy.optimize

import continuation as C
import nlbeam
from continuation._newton import ConvergenceError
from continuation.accuracy import combine, match_multipliers
from continuation.refine import locate_extended
from continuation.shooting import Integrator

FINE = Integrator(dt_scale=1 / 16, steps_per_contact=512)
PAPER = nlbeam.BeamImpact.paper()
M2 = np.diag([0.03, 0.02])
K2 = np.array([[900.0, -300.0], [-300.0, 600.0]])
TWO_DOF = nlbeam.System(M2, 1e-4 * K2 + 0.1 * M2, K2,
                        elements=(nlbeam.Contact(1, "hertz", 1e9, gap=0.0),))
# a force-excited oscillator (1 Hz, damping ratio 0.02) with a one-sided linear stop 100 times
# stiffer, met after a gap of 0.1 m
K1, C1, GAP = 39.48, 0.2513, 0.1
PWL = nlbeam.System([[1.0]], [[C1]], [[K1]], excitation_kind="force", y_load=[1.0],
                    elements=(nlbeam.PiecewiseLinearStop(0, k=100 * K1, gap=GAP, on_base=False),))


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # few steps in a contact (coarse levels)
        yield


def fd_multipliers(model, amplitude, f, order, sol, integ):
    """Eigenvalues of central differences of the period map of integrator integ, from the
    first segment boundary of sol (which lies out of contact)."""
    spp = integ.steps_per_period(model, f)
    ex = nlbeam.Harmonic(amplitude, f)
    x0, t0 = sol.states[0], sol.boundaries[0] / f

    def period_map(x):
        return nlbeam.flow(model, ex, x, t0, order / f, dt=1 / (f * spp),
                           steps_per_contact=integ.steps_per_contact, warn=False).state

    N = model.n_dof
    w = 2 * np.pi * f / order
    a = np.max(np.abs(x0[:N]) + np.abs(x0[N:]) / w)
    sc = np.r_[np.full(N, a), np.full(N, a * w)]
    M = np.empty((2 * N, 2 * N))
    for k in range(2 * N):
        e = np.zeros(2 * N)
        e[k] = 1e-6 * sc[k]
        M[:, k] = (period_map(x0 + e) - period_map(x0 - e)) / (2 * e[k])
    return np.linalg.eigvals(M)


def converged(model, amplitude, f, order, sol):
    """(xmax, multipliers) of the orbit sol solved again at FINE. The multipliers are FINE's
    variational ones, checked here against central differences of FINE's period map: these
    carry their own error (round-off over the fine map's many steps: 1e-6 on the paper model
    at 12 Hz, 1.7e-7 on the 2-DOF system at 25 Hz, where the variational multipliers at dt / 4
    and dt / 16 agree to 2e-9), so they confirm the variational ones to 2e-6 (times the
    multiplier where it exceeds 1) but are no reference for the default step's 1e-7..1e-6."""
    fine = C.periodic_solution(model, amplitude, f, order, guess=sol, integrator=FINE,
                               error=False)
    fd = fd_multipliers(model, amplitude, f, order, fine, FINE)
    # relative to the multiplier's size where it exceeds 1 (the differences' round-off grows
    # with it: 2.5e-6 at the 2-DOF system's -1.84 at 15 Hz)
    assert np.all(np.abs(fine.multipliers - match_multipliers(fine.multipliers, fd))
                  <= 2e-6 * np.maximum(1.0, np.abs(fine.multipliers)))
    return fine.xmax, fine.multipliers


@pytest.mark.parametrize("name, model, amplitude, f, order", [
    ("paper, harmonic, 40 Hz", PAPER, 1e-4, 40.0, 1),
    ("paper, harmonic, 15 Hz", PAPER, 1e-4, 15.0, 1),
    ("paper, period 2, 59 Hz", PAPER, 1e-4, 59.0, 2),
    ("paper, harmonic, 60 Hz", PAPER, 1e-4, 60.0, 1),
    ("duffing", nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0), 0.2, 0.2, 1),
    ("2-DOF hertz, 25 Hz", TWO_DOF, 1e-4, 25.0, 1),
    ("2-DOF hertz, 15 Hz", TWO_DOF, 1e-4, 15.0, 1),
    ("pwl stop, 1.0 Hz", PWL, 1.0, 1.0, 1),
    ("pwl stop, 1.2 Hz", PWL, 1.0, 1.2, 1),
])
def test_orbit_error_estimates_bound_the_true_error(name, model, amplitude, f, order):
    sol = C.periodic_solution(model, amplitude, f, order)
    assert sol.minimal_order == order
    xm, mu = converged(model, amplitude, f, order, sol)
    mu = match_multipliers(sol.multipliers, mu)
    true_x = abs(sol.xmax - xm)
    true_mu = np.abs(sol.multipliers - mu)
    # the estimate bounds the error (the reference's own error: ~1e-9 of the multipliers)...
    assert true_x <= sol.xmax_error + 1e-12 * xm
    assert np.all(true_mu <= sol.multipliers_error + 1e-9)
    # ...and is not a vacuous bound: within a factor 10 of it (observed 1.5-2.1)
    assert sol.xmax_error <= 10 * true_x + 1e-12 * xm
    assert np.max(sol.multipliers_error) <= 10 * np.max(true_mu) + 1e-9
    # 48 steps per contact (the measured candidate default, docs/continuation_report.md) give
    # the multipliers to 1e-5 here (issue 13 item 5; largest 6.3e-6 at 59 Hz, order 2), the
    # default 32 not everywhere: 3.2e-5 (59 Hz, order 2), 2.2e-5 (60 Hz), 1.3e-5 (2-DOF, 15 Hz)
    s48 = C.periodic_solution(model, amplitude, f, order, guess=sol, error=False,
                              steps_per_contact=48)
    assert np.max(np.abs(s48.multipliers - match_multipliers(s48.multipliers, mu))) <= 1e-5


def test_periodic_solution_meets_the_accuracy_asked_for():
    """accuracy='default' (6 digits, multipliers 1e-5) halves the step until the estimate
    meets it, and the converged values confirm it."""
    sol = C.periodic_solution(PAPER, 1e-4, 40.0, accuracy="default")
    assert np.max(sol.multipliers_error) <= 1e-5 and sol.xmax_error <= 1e-6 * sol.xmax
    xm, mu = converged(PAPER, 1e-4, 40.0, 1, sol)
    assert np.max(np.abs(sol.multipliers - match_multipliers(sol.multipliers, mu))) <= 1e-5
    assert abs(sol.xmax - xm) <= 1e-6 * xm
    with pytest.raises(ValueError, match="accuracy"):
        C.periodic_solution(PAPER, 1e-4, 40.0, accuracy=20)


def test_combine_bounds_the_error_of_geometric_sequences():
    """Levels v_k = v* + c 2^(-q k) (+ a higher-order term): the reported value is within the
    stated error of v*, and the stated error is not vacuous."""
    v_star = 1.2345678
    for q in (2.0, 3.0, 4.0):
        for c in (1e-3, -2e-4):
            for K in (1, 2, 3, 4):
                h = 2.0 ** -np.arange(K + 1)
                v = v_star + c * h ** q * (1 + 0.3 * h)
                value, err = combine(v, floor=0.0)
                assert abs(value - v_star) <= err
                assert err <= abs(v[0] - v_star)  # better than the level-0 value's error
    # no convergence pattern (alternating): the finest value, error the larger last change
    value, err = combine([1.0, 1.1, 1.05, 1.08], floor=0.0)
    assert value == 1.08 and err == pytest.approx(0.05)  # the larger of the last two changes


def _carried(levels, impacts=None):
    """carried_estimate applied along levels 0..K of multiplier arrays as branch_errors does."""
    from continuation.accuracy import _change, carried_estimate

    impacts = impacts or [3] * len(levels)
    d = _change(levels[1], levels[0])
    mu, err, falling = levels[1], d, True
    for k in range(2, len(levels)):
        d_k = _change(levels[k], levels[k - 1])
        mu, err = carried_estimate(levels[k - 1], levels[k], d, d_k,
                                   impacts[k - 2] == impacts[k - 1] == impacts[k], falling)
        falling = falling and d_k <= d / 4
        d = d_k
    return mu, err


def test_carried_multipliers_extrapolate_only_where_the_order_shows():
    """Multipliers at levels 0..K with errors c h^q (1 + 0.3 h), h = 2^-k (a complex pair and a
    real one): at order 4 the reported value is the Richardson extrapolant, within its stated
    error of the exact one and at least 5x closer than the finest level, the stated error
    within 3x the finest level's error (not the last change, 15x it); at order 1 or 2 (ratios 2,
    4) nothing is extrapolated and the stated error still bounds the finest level's; with
    the impacts per period changing between the levels nothing is extrapolated either, nor
    after a change that did not fall 4-fold."""
    exact = np.array([0.6 + 0.33j, 0.6 - 0.33j, -0.2 + 0j])
    c = np.array([3e-3 - 1e-3j, 3e-3 + 1e-3j, -2e-3])
    for q in (1.0, 2.0, 4.0):
        for K in (2, 3):
            h = 2.0 ** -np.arange(K + 1)
            lv = [exact + c * hk ** q * (1 + 0.3 * hk) for hk in h]
            mu, err = _carried(lv)
            true = np.max(np.abs(match_multipliers(exact, mu) - exact))
            fine = np.max(np.abs(lv[-1] - exact))
            last = np.max(np.abs(lv[-1] - lv[-2]))
            assert true <= err, (q, K, true, err)
            if q == 4.0:
                assert true <= fine / 5 and err <= 3 * fine and err <= last / 5, (K, fine, err)
            else:
                assert np.array_equal(mu, lv[-1]) and err >= fine
    h = 2.0 ** -np.arange(4)
    lv = [exact + c * hk ** 4 for hk in h]
    mu, err = _carried(lv, impacts=[3, 3, 4, 4])  # an impact more at level 2: ratio 16 by luck
    assert np.array_equal(mu, lv[-1]) and err == pytest.approx(np.max(np.abs(lv[3] - lv[2])))
    # not converging steadily (changes 4e-2, 6e-2, 1e-2 as at a corner of the paper model):
    # the third change falls 6-fold by chance, the error is twice the larger of the last two
    lv = [exact + x for x in (0.0, 4e-2, -2e-2, -1e-2)]
    mu, err = _carried(lv)
    assert np.array_equal(mu, lv[-1]) and err == pytest.approx(2 * 6e-2)


def _bifurcation(frc, kind, near):
    return min((b for b in frc.bifurcations if b.kind == kind),
               key=lambda b: abs(b.frequency - near))


def _fd_period_doubling(model, amplitude, f0, state0, integ):
    """The period doubling near f0 of the orbit through state0 at integrator integ: the secant
    method on the multiplier nearest -1 of central differences of the period map."""
    sol = C.periodic_solution(model, amplitude, f0, guess=state0, integrator=integ, error=False)

    def g(f):
        nonlocal sol
        sol = C.periodic_solution(model, amplitude, f, guess=sol, integrator=integ, error=False)
        mu = fd_multipliers(model, amplitude, f, 1, sol, integ)
        return mu[np.argmin(np.abs(mu + 1))].real + 1

    fa, fb = f0, f0 * (1 + 1e-6)
    ga, gb = g(fa), g(fb)
    for _ in range(20):
        fa, ga, fb = fb, gb, fb - gb * (fb - fa) / (gb - ga)
        gb = g(fb)
        if abs(fb - fa) < 1e-13 * fb:
            break
    return fb


@pytest.fixture(scope="module")
def pd_diagram():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s0 = C.periodic_solution(PAPER, 1e-4, 57.8, error=False).state0
        frc = C.frequency_response(PAPER, 1e-4, (57.6, 58.5), orders=(1,),
                                   brute_force_grid=False, starts=[(57.8, 1, s0)])
    return frc


def test_period_doubling_frequency_error_covers_the_converged_value(pd_diagram):
    """Paper model, A = 0.1 mm: the period doubling near 58.08 Hz. Reference: the multiplier
    -1 of central differences of the period map at dt / 8 (no variational equations; that
    step converges to ~1e-9 relative)."""
    bf = _bifurcation(pd_diagram, "period-doubling", 58.08)
    ref = _fd_period_doubling(PAPER, 1e-4, bf.frequency, bf.state0,
                              Integrator(dt_scale=1 / 8, steps_per_contact=256))
    assert abs(bf.frequency - ref) <= bf.error
    assert bf.error <= 1e-6 * bf.frequency  # the default target: 6 significant digits
    assert len(bf.levels) >= 3  # two changes seen (accuracy.MIN_VALUES), not one
    # the diagram's own bracket is no error bar: the level-0 value is off by far more
    assert abs(bf.levels[0] - ref) > 10 * bf.tolerance


def test_diagram_states_its_accuracy(pd_diagram):
    """The diagram's summary states the multipliers' error at the sampled branch points and
    the fold / PD frequencies' (FrequencyResponse.stated_accuracy), from the estimates it
    carries; nothing without them (accuracy='off')."""
    e = np.concatenate([b.multipliers_error[b.error_sampled] for b in pd_diagram.branches])
    line = pd_diagram.stated_accuracy()
    assert e.size >= 2 and f"multipliers median {np.median(e):.1e}" in line
    assert f"largest {np.max(e):.1e}" in line
    assert f"{int(np.sum(e > 1e-5))} of {e.size} sampled points above 1e-5" in line
    rel = [b.error / b.frequency for b in pd_diagram.bifurcations
           if b.kind in ("fold", "period-doubling")]
    assert rel and f"median relative {np.median(rel):.1e}" in line
    assert "stated errors" in repr(pd_diagram)
    off = dataclasses.replace(pd_diagram, settings={**pd_diagram.settings, "accuracy": "off"})
    assert off.stated_accuracy() == "" and "stated errors" not in repr(off)


def test_high_accuracy_gives_eight_digits_without_a_separate_refine(pd_diagram):
    """accuracy 8 digits on the same period doubling; reference: continuation.refine (the
    extended system at dt / 4 .. dt / 32, Richardson; 9.7 digits)."""
    from continuation.accuracy import bifurcation_levels
    from continuation.refine import refine

    bf = _bifurcation(pd_diagram, "period-doubling", 58.08)
    at_level0 = dataclasses.replace(bf, value=bf.levels[0], frequency=bf.levels[0])
    lv = bifurcation_levels(PAPER, 1e-4, at_level0, Integrator(), digits=8.0, max_levels=5)
    ref = refine(PAPER, at_level0, 1e-4)
    assert lv.error <= 1e-8 * lv.value
    assert abs(lv.value - ref.value) <= lv.error + ref.tolerance


def test_fold_frequency_error_covers_the_extended_system_at_a_finer_step():
    """Paper model: the fold near 21.7321 Hz (harmonic branch). Reference: the extended system
    R = 0, det(M - I) = 0 (continuation.refine, another criterion than the turning point
    used by the estimator) at dt / 8 and dt / 16, extrapolated (its error ~1e-9 Hz)."""
    frc = C.frequency_response(PAPER, 1e-4, (21.6, 21.9), orders=(1,), n_grid=4)
    bf = _bifurcation(frc, "fold", 21.7321)
    vals = []
    s0 = (bf.state0, bf.disc0)
    for k in (3, 4):
        f, s0, _ = locate_extended(PAPER, 1e-4, bf.frequency, 1, s0, "fold",
                                   Integrator().refined(k))
        vals.append(f)
    ref = vals[1] + (vals[1] - vals[0]) / 15
    assert abs(bf.frequency - ref) <= bf.error
    assert bf.error <= 1e-6 * bf.frequency


def _linear_amplitude(f):
    w = 2 * np.pi * f
    return 1.0 / abs(K1 - w ** 2 + 1j * C1 * w)


def test_piecewise_linear_stop_grazing_and_xmax_against_the_exact_linear_solution(tmp_path):
    """Below the grazing frequency the orbit does not reach the stop: it is the linear
    response, xmax = |X(f)| exactly, and the grazing point is where |X(f)| = gap."""
    s0 = C.periodic_solution(PWL, 1.0, 0.75, error=False).state0
    frc = C.frequency_response(PWL, 1.0, (0.2, 0.95), orders=(1,), brute_force_grid=False,
                               starts=[(0.75, 1, s0)])
    f_graze = scipy.optimize.brentq(lambda f: _linear_amplitude(f) - GAP, 0.7, 0.95,
                                    xtol=1e-14)
    g = _bifurcation(frc, "grazing", f_graze)
    assert abs(g.frequency - f_graze) <= g.error
    assert g.error < 1e-5 * f_graze
    n_checked = 0
    for b in frc.branches:
        free = b.frequency < f_graze * (1 - 1e-4)
        exact = np.array([_linear_amplitude(f) for f in b.frequency[free]])
        true = np.abs(b.xmax[free] - exact)
        assert np.all(true[b.error_sampled[free]] <= b.xmax_error[free][b.error_sampled[free]]
                      + 1e-12)
        n_checked += int(b.error_sampled[free].sum())
    assert n_checked >= 3
    # the estimates are saved and loaded
    frc.save(tmp_path / "pwl.h5")
    back = C.load(tmp_path / "pwl.h5")
    for b0, b1 in zip(frc.branches, back.branches):
        np.testing.assert_array_equal(b0.xmax_error, b1.xmax_error)
        np.testing.assert_array_equal(b0.multipliers_error, b1.multipliers_error)
        np.testing.assert_array_equal(b0.error_sampled, b1.error_sampled)
    assert [b.error for b in back.bifurcations] == [b.error for b in frc.bifurcations]


def test_fold_by_the_slope_is_the_turning_point_of_p_alone():
    """Paper model, the fold near 21.7321 Hz located again at level 1: by the secant method
    on dp/ds from the map's own Jacobian (accuracy._fold_turning_point) and as the vertex of
    p along the branch from values of p alone (accuracy._vertex_along, no Jacobian in the
    criterion): the same turning point, moved from the diagram's by the finer step."""
    from continuation.accuracy import _fold_turning_point, _problem_at, _vertex_along

    frc = C.frequency_response(PAPER, 1e-4, (21.6, 21.9), orders=(1,), n_grid=4,
                               accuracy="off")
    bf = _bifurcation(frc, "fold", 21.7321)
    prob, u, p = _problem_at(PAPER, 1e-4, bf, "frequency", Integrator().refined(1), 1)
    p_slope, _ = _fold_turning_point(prob, u, p)
    w, wp = prob.scale_u, prob.scale_p
    ev = prob.evaluate(u, p, jac=True, jac_p=True)
    jp = ev.Jp * wp / w
    t = np.linalg.svd(np.hstack([ev.Ju * w[None, :] / w[:, None], jp[:, None]]))[2][-1]
    p_vertex = _vertex_along(prob, np.r_[u / w, p / wp], t, jp, 1e-4, 1e-10)[-1] * wp
    assert abs(p_slope - p_vertex) <= 1e-10 * p
    assert abs(p_slope - p) > 1e-8 * p  # the finer step moved it (6.6e-8 relative)


@pytest.mark.parametrize("name, model, amplitude, f_range, f0", [
    ("paper 10.4-12.4 Hz", PAPER, 1e-4, (10.4, 12.4), 11.0),
    ("2-DOF hertz 14-16 Hz", TWO_DOF, 1e-4, (14.0, 16.0), 15.0),
])
def test_diagram_multipliers_meet_the_default_target(name, model, amplitude, f_range, f0):
    """At the defaults the diagram reports each point's multipliers from its orbit carried to
    the step halved, or finer while that misses 1e-5 (accuracy.branch_errors): against
    the converged values (FINE) they are within their stated error at every checked point,
    the stated error is not vacuous, and 1e-5 (issue 13 item 5) is met at most points; the
    level-0 multipliers of the same points miss it far more often (the contact steps' error:
    1e-4 on the paper model at 12 Hz, 1.4e-5 on the 2-DOF system at 15 Hz). Measured on the
    paper case: 8 of 100 points above 1e-5 (next to the fold at 12.17 Hz and the large
    multipliers at 11.63 and 14.46 Hz), level 0: most."""
    s0 = C.periodic_solution(model, amplitude, f0, error=False).state0
    frc = C.frequency_response(model, amplitude, f_range, orders=(1,), brute_force_grid=False,
                               starts=[(f0, 1, s0)])
    true, stated, true0 = [], [], []
    for b in frc.branches:
        assert b.error_sampled.all()  # every point estimated, none interpolated
        for i in range(0, len(b.values), 4):
            f = float(b.frequency[i])
            sol = C.periodic_solution(model, amplitude, f, guess=b.state0[i], error=False)
            # FINE's variational multipliers (``converged`` checks them against central
            # differences at four cases; at |mu| = 6.7 those differences' round-off exceeds
            # its 2e-6)
            try:  # (next to 14.46 Hz, |mu| ~ 100, FINE's Newton stagnates at 2e-10)
                mu = C.periodic_solution(model, amplitude, f, guess=sol, integrator=FINE,
                                         error=False).multipliers
            except ConvergenceError:
                continue
            big = np.maximum(1.0, np.abs(mu))
            true.append(np.max(np.abs(b.multipliers[i] - match_multipliers(b.multipliers[i], mu))
                               / big))
            stated.append(b.multipliers_error[i])
            assert true[-1] <= stated[-1], (f, true[-1], stated[-1])
            if abs(np.abs(mu).max() - 1.0) > stated[-1]:
                assert bool(b.stable[i]) == bool(np.abs(mu).max() < 1.0), f
            mu0 = sol.multipliers  # the level-0 values at this point
            true0.append(np.max(np.abs(mu0 - match_multipliers(mu0, mu)) / big))
    true, stated, true0 = map(np.array, (true, stated, true0))
    assert true.size >= 10
    assert np.median(true / stated) >= 0.01  # not a vacuous bound (measured 0.05-0.15)
    assert np.mean(true <= 1e-5) >= 0.85
    assert np.sum(true0 > 1e-5) >= 2 * max(np.sum(true > 1e-5), 1)
