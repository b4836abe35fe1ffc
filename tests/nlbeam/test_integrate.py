"""The integrators: analytic answers, convergence orders across impacts, events, energy."""
import math

import numpy as np
import pytest

import nlbeam
from helpers import KernelCall
from nlbeam import _kernels

PAPER = nlbeam.BeamImpact.paper()
F40 = nlbeam.Harmonic(1e-4, 40.0)   # A = 0.1 mm at 40 Hz: an impact every period


def free_mass_on_stop(law="hertz", m=1e-2, K=1e8, e=None, mu=None):
    el = nlbeam.Contact(0, law, K, e=e, mu=mu, on_base=False)
    return nlbeam.System([[m]], [[0.0]], [[0.0]], (el,), "force", output_dof=0)


# --- linear analytic answers ----------------------------------------------------------------------
@pytest.mark.parametrize("method", ["rk4", "adaptive"])
def test_stop_removed_gives_the_analytic_transmissibility(method):
    model = PAPER.replace(K_hertz=0.0)
    f = 30.0
    w = 2 * math.pi * f
    T = 1.0 / f
    kw = {"dt": T / 400} if method == "rk4" else {"rtol": 1e-11, "atol": 1e-16, "dt": T / 400}
    # start on the analytic steady state: no transient to wait for
    H = (model.k + 1j * w * model.b) / (model.k - model.m * w * w + 1j * w * model.b)
    A = 1e-4
    x0 = [A * H.real, -A * w * H.imag]
    tr = nlbeam.integrate(model, nlbeam.Harmonic(A, f), 5 * T, method=method, x0=x0, **kw)
    x_exact = A * np.real(H * np.exp(1j * w * tr.t))
    assert np.max(np.abs(tr.x[:, 0] - x_exact)) / (A * abs(H)) < 1e-6
    assert tr.xmax[0] == pytest.approx(A * abs(H), rel=1e-6)
    assert tr.n_impacts == 0


def test_duffing_runs_through_the_same_integrator():
    # small forcing: the response tends to the linear one, |X| = F / |k - m w^2 + i w b|
    duff = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    F, f = 1e-4, 0.1
    w = 2 * math.pi * f
    H = 1 / (1 - w * w + 1j * 0.1 * w)
    x0 = [F * H.real, -F * w * H.imag]
    tr = nlbeam.integrate(duff, nlbeam.Harmonic(F, f), 10 / f, dt=1 / f / 400, x0=x0)
    # cubic correction is of relative size k3 X^2 / k ~ 1e-8
    assert tr.xmax[0] == pytest.approx(F * abs(H), rel=1e-6)


# --- events ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["rk2", "rk4", "adaptive"])
def test_contact_duration_of_a_free_mass_on_a_hertz_stop(method):
    m, K, v0 = 1e-2, 1e8, 0.2
    dmax = (5 * m * v0 ** 2 / (4 * K)) ** 0.4
    tc = 2.943275 * dmax / v0
    spc = {"rk2": 4096, "rk4": 64, "adaptive": None}[method]
    tr = nlbeam.integrate(free_mass_on_stop(m=m, K=K), nlbeam.Harmonic(0.0, 1.0), 3 * tc,
                          method=method, dt=tc / 5, x0=[-1e-7, v0], steps_per_contact=spc,
                          rtol=1e-12, atol=1e-18)
    (t_on, _, on, v_on), (t_off, _, off, v_off) = tr.events
    assert (on, off) == (1.0, 0.0)
    assert t_on == pytest.approx(1e-7 / v0, rel=1e-12)
    assert (t_off - t_on) / tc == pytest.approx(1.0, abs=1e-6)   # the constant has 7 digits
    assert v_off == pytest.approx(-v0, rel=1e-6)                   # elastic: speed restored
    assert tr.max_landing_residual < 1e-20


def test_no_step_crosses_a_contact_boundary_and_landing_is_to_round_off():
    tr = nlbeam.integrate(PAPER, F40, 1.0, store_every=1)
    assert tr.n_impacts == 40
    assert tr.max_landing_residual < 1e-17  # a few ulps of x (~1e-3 m)
    onsets = tr.events[tr.events[:, 2] == 1]
    ends = tr.events[tr.events[:, 2] == 0]
    assert np.all(onsets[:, 3] > 0) and np.all(ends[:, 3] < 0)
    # contacts alternate onset/end and every contact has >= 8 steps
    assert np.all(np.diff(tr.events[:, 2]) != 0)
    assert tr.min_steps_per_contact >= 8


def test_a_brief_touch_between_step_ends_is_not_missed():
    # an oscillator whose amplitude exceeds the gap by 1e-3 relative: each maximum touches the
    # stop for ~0.9 ms, shorter than the step (1.6 ms), so step ends rarely see the contact
    m, K, k, gap = 1e-2, 1e8, 100.0, 1e-3
    sysm = nlbeam.System([[m]], [[0.0]], [[k]], (nlbeam.Contact(0, "hertz", K, gap=gap,
                                                                  on_base=False),), "force")
    w = math.sqrt(k / m)
    tr = nlbeam.integrate(sysm, nlbeam.Harmonic(0.0, 1.0), 0.2, dt=2 * math.pi / w / 40,
                          x0=[0.0, w * gap * (1 + 1e-3)])
    n_maxima = int((0.2 * w - math.pi / 2) // (2 * math.pi)) + 1
    assert tr.n_impacts == n_maxima == 3
    contact_samples = np.count_nonzero(tr.delta[:, 0] > 0)
    assert contact_samples < tr.n_impacts   # most touches fall between the stored samples


# --- convergence across impacts -------------------------------------------------------------------
@pytest.fixture(scope="module")
def reference_state():
    tr = nlbeam.integrate(PAPER, F40, 0.3, method="adaptive", rtol=1e-13, atol=1e-19,
                          dt=1 / 400, store_every=0)
    assert tr.n_impacts == 12
    return tr.state_end


def _errors(method, dts, spcs, ref, **kw):
    errs = []
    for dt, spc in zip(dts, spcs):
        tr = nlbeam.integrate(PAPER, F40, 0.3, method=method, dt=dt, steps_per_contact=spc,
                              store_every=0, **kw)
        errs.append(abs(tr.state_end[0] - ref[0]) / abs(ref[0]))
    errs = np.array(errs)
    return errs, np.log2(errs[:-1] / errs[1:])


def test_rk2_keeps_order_2_across_impacts(reference_state):
    errs, orders = _errors("rk2", [1 / 4000, 1 / 8000, 1 / 16000], [64, 128, 256], reference_state)
    assert np.all(orders > 1.8), (errs, orders)


def test_rk4_graded_keeps_order_near_4_across_impacts_and_beats_plain_rk4(reference_state):
    # the contact part of the error: free-flight step fine (its own error ~1e-12), contact step
    # halved twice. Graded: 3.7, 3.9; plain RK4 is capped near 2.4 by delta^1.5.
    dts = [1 / 32000] * 3
    spcs = [64, 128, 256]
    e_g, o_g = _errors("rk4", dts, spcs, reference_state, graded=True)
    e_p, o_p = _errors("rk4", dts, spcs, reference_state, graded=False)
    assert np.all(o_g > 3.5), (e_g, o_g)
    assert np.all(o_p < 3.0), (e_p, o_p)
    assert e_g[-1] < e_p[-1] / 20
    # both refined together (dt and contact step halved): error 1.4e-7, 1.5e-8, 1.1e-9
    e_j, o_j = _errors("rk4", [1 / 4000, 1 / 8000, 1 / 16000], spcs, reference_state)
    assert np.all(o_j > 3.0) and e_j[-1] < 3e-9, (e_j, o_j)


def test_without_event_location_the_error_is_far_larger(reference_state):
    dts = [1 / 4000, 1 / 8000]
    e_on, _ = _errors("rk4", dts, [64, 128], reference_state)
    e_off, o_off = _errors("rk4", dts, [64, 128], reference_state, events=False)
    assert np.all(e_off > 1e3 * e_on)
    assert o_off[0] < 2.0


def test_adaptive_error_is_proportional_to_its_tolerance(reference_state):
    errs = []
    tols = [1e-6, 1e-8, 1e-10]
    for rtol in tols:
        tr = nlbeam.integrate(PAPER, F40, 0.3, method="adaptive", rtol=rtol, atol=rtol * 1e-6,
                              dt=1 / 400, store_every=0)
        errs.append(abs(tr.state_end[0] - reference_state[0]) / abs(reference_state[0]))
    slope = np.polyfit(np.log10(tols), np.log10(errs), 1)[0]
    assert 0.7 < slope < 1.3, (errs, slope)
    assert all(e < 100 * t for e, t in zip(errs, tols))


# --- energy ---------------------------------------------------------------------------------------
def energy(model_m, k, K, x, v, delta):
    return 0.5 * model_m * v ** 2 + 0.5 * k * x ** 2 + 0.4 * K * np.clip(delta, 0, None) ** 2.5


def test_elastic_hertz_conserves_energy_over_many_impacts():
    model = nlbeam.BeamImpact.paper(contact="hertz", b=0.0)
    drift = []
    for spc in (128, 256):
        tr = nlbeam.integrate(model, nlbeam.Harmonic(0.0, 1.0), 2.0, x0=[0.0, 0.05], dt=1e-4,
                              steps_per_contact=spc)
        E = energy(model.m, model.k, model.K_hertz, tr.x[:, 0], tr.v[:, 0], tr.delta[:, 0])
        drift.append(np.max(np.abs(E / E[0] - 1)))
    assert tr.n_impacts > 80
    # ~2e-8 per impact at 256 steps per contact, falling with order ~4 in the contact step
    assert drift[1] < 3e-6
    assert drift[0] / drift[1] > 8


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "hunt-crossley"])
def test_hysteretic_laws_only_dissipate(law):
    mu = nlbeam.mu_from_e(0.5, 2.1e8, 0.05) if law == "hunt-crossley" else None
    model = nlbeam.BeamImpact.paper(contact=law, b=0.0, mu=mu)
    tr = nlbeam.integrate(model, nlbeam.Harmonic(0.0, 1.0), 0.5, x0=[0.0, 0.05], dt=1e-4,
                          steps_per_contact=256)
    E = energy(model.m, model.k, model.K_hertz, tr.x[:, 0], tr.v[:, 0], tr.delta[:, 0])
    assert tr.n_impacts > 5
    # never gains more than the integration error (~1e-8 of E per impact at this resolution)
    assert np.all(np.diff(E) <= 1e-8 * E[0])
    assert E[-1] < 0.9 * E[0]


def restitution(e, v0=0.1):
    tr = nlbeam.integrate(free_mass_on_stop("lankarani-nikravesh", e=e), nlbeam.Harmonic(0.0, 1.0),
                          2e-3, x0=[-1e-8, v0], dt=1e-4, steps_per_contact=256)
    return -tr.events[1, 3] / tr.events[0, 3]


def test_restitution_of_an_isolated_impact_approaches_nominal_e_as_e_tends_to_1():
    gaps = [abs(restitution(e) - e) for e in (0.5, 0.8, 0.95, 0.99)]
    assert gaps[-1] < 2e-3
    assert all(a > b for a, b in zip(gaps, gaps[1:]))


# --- a 2-DOF system with a stop -------------------------------------------------------------------
def two_dof(K_stop=1e8, law="hertz", b=0.0):
    M = np.diag([0.04, 0.02])
    Kmat = np.array([[800.0 + 400.0, -400.0], [-400.0, 400.0]])
    C = b * Kmat / 1000
    return nlbeam.System(M, C, Kmat, (nlbeam.Contact(1, law, K_stop, e=0.7),), "base",
                         y_load=np.array([800.0, 0.0]), yd_load=C @ np.ones(2) * 0, name="2dof")


def test_two_dof_without_stop_matches_modal_superposition():
    sysm = two_dof(K_stop=0.0)
    # free vibration from an initial displacement: x(t) = sum_j phi_j q_j cos(w_j t)
    lam, phi = np.linalg.eig(np.linalg.solve(sysm.M, sysm.K))
    x0 = np.array([1e-3, -2e-3])
    q0 = np.linalg.solve(phi, x0)
    tr = nlbeam.integrate(sysm, nlbeam.Harmonic(0.0, 1.0), 0.2, x0=[*x0, 0, 0], dt=1e-5)
    exact = (phi @ (q0[:, None] * np.cos(np.sqrt(lam)[:, None] * tr.t[None, :]))).T
    assert np.max(np.abs(tr.x - exact)) < 1e-9


def test_two_dof_with_a_stop_conserves_energy_and_methods_agree():
    sysm = two_dof()
    x0 = [0.0, 0.0, 0.1, 0.3]
    ex = nlbeam.Harmonic(0.0, 1.0)
    a = nlbeam.integrate(sysm, ex, 0.5, x0=x0, dt=1e-4, steps_per_contact=256)
    b = nlbeam.integrate(sysm, ex, 0.5, x0=x0, method="adaptive", rtol=1e-11, atol=1e-16, dt=1e-4)
    assert a.n_impacts == b.n_impacts > 5
    E = (0.5 * np.einsum("ni,ij,nj->n", a.v, sysm.M, a.v)
         + 0.5 * np.einsum("ni,ij,nj->n", a.x, sysm.K, a.x)
         + 0.4 * 1e8 * np.clip(a.delta[:, 0], 0, None) ** 2.5)
    assert np.max(np.abs(E / E[0] - 1)) < 1e-6
    assert np.max(np.abs(a.x - b.x)) < 1e-6 * np.max(np.abs(b.x))


# --- storage and bad input ------------------------------------------------------------------------
def test_store_every_and_none():
    full = nlbeam.integrate(PAPER, F40, 0.1, dt=1e-4)
    sparse = nlbeam.integrate(PAPER, F40, 0.1, dt=1e-4, store_every=10)
    none = nlbeam.integrate(PAPER, F40, 0.1, dt=1e-4, store_every=0)
    assert full.t.size == 1001 and sparse.t.size == 101 and none.t.size == 0
    np.testing.assert_array_equal(full.x[::10], sparse.x)
    np.testing.assert_array_equal(full.state_end, none.state_end)
    np.testing.assert_allclose(full.t, np.linspace(0, 0.1, 1001), atol=1e-15)


@pytest.mark.parametrize("kwargs, name", [
    ({"t_end": -1.0}, "t_end"), ({"t_end": float("nan")}, "t_end"), ({"dt": 0.0}, "dt"),
    ({"dt": -1e-4}, "dt"), ({"method": "euler"}, "method"), ({"x0": [0.0]}, "x0"),
    ({"x0": [0.0, float("inf")]}, "x0"), ({"steps_per_contact": 0}, "steps_per_contact"),
])
def test_bad_integration_arguments_name_the_parameter(kwargs, name):
    args = {"t_end": 0.1}
    args.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{name}:"):
        nlbeam.integrate(PAPER, F40, **args)


def test_a_sampled_excitation_is_not_extrapolated():
    tab = nlbeam.Sampled(0.0, 1e-3, np.zeros(11), np.zeros(11), np.zeros(11))
    with pytest.raises(ValueError, match="^t_end:"):
        nlbeam.integrate(PAPER, tab, 0.02)


def test_too_few_steps_per_contact_warns(monkeypatch):
    # the contact step also obeys the explicit stability limit of the law (rate * h < 0.5),
    # so even steps_per_contact=4 gives ~8 steps; raise the threshold to see the warning path
    import nlbeam.solver
    monkeypatch.setattr(nlbeam.solver, "MIN_STEPS_PER_CONTACT", 10_000)
    with pytest.warns(RuntimeWarning, match="steps_per_contact"):
        tr = nlbeam.integrate(PAPER, F40, 0.1, dt=1e-4, steps_per_contact=4, graded=False)
    assert 0 < tr.min_steps_per_contact < 10_000


def test_the_inlined_right_hand_side_is_deriv_bit_for_bit():
    # the unrolled RK4/DP5 steps evaluate the field with deriv_plain (inlined, y'' skipped via
    # excite_yyd); it must give exactly deriv's accelerations and element forces, or every
    # fixed-step and adaptive result would silently change
    rng = np.random.default_rng(5)
    n = 61
    y = 1e-4 * rng.normal(size=n)
    yd = 1e-2 * rng.normal(size=n)
    excitations = [F40, nlbeam.Sampled(0.0, 1e-3, y, yd, rng.normal(size=n)),
                   nlbeam.Sampled(0.0, 1e-3, y, yd),          # y'' omitted: NaN column
                   nlbeam.CosineSum([10.0, 33.0], [1e-4, 2e-5], [0.1, 1.0])]
    models = [PAPER, PAPER.replace(contact="hertz"),
              PAPER.replace(contact="hunt-crossley", mu=1e3),
              nlbeam.ModalBeam.paper(n_modes=3)]
    for model in models:
        N, ne = model.n_dof, model.n_elements
        P, dvm = np.zeros((2 * N, 1)), np.zeros((ne, 1))
        for exc in excitations:
            kc = KernelCall(model, exc)
            for t in (0.0, 0.0123456, 0.0371, 0.06):
                y0 = exc.evaluate([t])[0][0]
                yy = kc.excite(t)
                assert kc.excite_yyd(t) == (yy[0], yy[1], yy[3])
                for pen, inside in ((-1e-5, 0.0), (3e-6, 1.0), (3e-6, 0.0), (-1e-7, 1.0)):
                    s = 1e-3 * rng.normal(size=2 * N)
                    # put the contact point at penetration pen: delta = w.x + wy*y - gap
                    _, w, wy, gap = model.element_geometry()
                    s[:N] += w[0] * (pen - (w[0] @ s[:N] + wy[0] * y0 - gap[0])) / (w[0] @ w[0])
                    disc = np.array([[inside, 0.05]] * ne)
                    st1, ks1, _, f1 = kc.deriv(t, s, P, dvm, disc)
                    st2, ks2, _, f2 = kc.deriv(t, s, P, dvm, disc, variant="deriv_plain")
                    assert st1 == st2 == 0
                    np.testing.assert_array_equal(ks1, ks2)
                    np.testing.assert_array_equal(f1, f2)
                    if inside and pen > 0:
                        assert f1[0] > 0.0
    # outside the sampled table both report the range error
    kc = KernelCall(PAPER, excitations[1])
    assert kc.excite_yyd(0.5)[2] == _kernels.ERR_EXCITATION_RANGE
    assert kc.excite(0.5)[3] == _kernels.ERR_EXCITATION_RANGE


def _field_cases():
    """(model, excitation, t, s, disc) across the contact laws, excitation kinds and a 3-mode
    beam, with the contact point put in and out of contact (the variational tests below)."""
    rng = np.random.default_rng(7)
    n = 61
    y = 1e-4 * rng.normal(size=n)
    yd = 1e-2 * rng.normal(size=n)
    excitations = [F40, nlbeam.Sampled(0.0, 1e-3, y, yd, rng.normal(size=n)),
                   nlbeam.Sampled(0.0, 1e-3, y, yd),
                   nlbeam.CosineSum([10.0, 33.0], [1e-4, 2e-5], [0.1, 1.0])]
    M = np.diag([0.03, 0.02])
    K2 = np.array([[900.0, -300.0], [-300.0, 600.0]])
    two_dof = nlbeam.System(M, 1e-4 * K2 + 0.1 * M, K2, elements=(
        nlbeam.Contact(0, "lankarani-nikravesh", 2e8, e=0.6, gap=0.0),
        nlbeam.PiecewiseLinearStop(1, 5e4, gap=0.0), nlbeam.CubicSpring(1, 1e9)))
    models = [PAPER, PAPER.replace(contact="hertz"),
              PAPER.replace(contact="hunt-crossley", mu=1e3),
              nlbeam.ModalBeam.paper(n_modes=3), two_dof]
    for model in models:
        N, ne = model.n_dof, model.n_elements
        _, w, wy, gap = model.element_geometry()
        for exc in excitations:
            for t in (0.0123456, 0.0371):
                y0 = exc.evaluate([t])[0][0]
                for pen, inside in ((-1e-5, 0.0), (3e-6, 1.0), (3e-6, 0.0), (-1e-7, 1.0)):
                    s = 1e-3 * rng.normal(size=2 * N)
                    s[:N] += w[0] * (pen - (w[0] @ s[:N] + wy[0] * y0 - gap[0])) / (w[0] @ w[0])
                    disc = np.array([[inside, 0.05]] * ne)
                    yield model, exc, t, s, disc, rng


def _rk4_var_reference(kc, t, h, s, P, dvm, disc):
    """rk_step's tableau loops (RK4, with the variational equations) on the generic deriv, in
    Python: the same floating-point operations in the same order."""
    A, B, C = _kernels._A_RK4, _kernels._B_RK4, _kernels._C_RK4
    KS, KP = [], []
    for i in range(4):
        ytmp = s.copy()
        Ptmp = P.copy()
        for j in range(i):
            ytmp = ytmp + h * A[i, j] * KS[j]
            Ptmp = Ptmp + h * A[i, j] * KP[j]
        st, ks, kP, _ = kc.deriv(t + C[i] * h, ytmp, Ptmp, dvm, disc, want_var=True)
        assert st == 0
        KS.append(ks)
        KP.append(kP)
    s_out, P_out = s.copy(), P.copy()
    for j in range(4):
        s_out = s_out + h * B[j] * KS[j]
        P_out = P_out + h * B[j] * KP[j]
    return s_out, P_out


def test_the_inlined_variational_step_is_the_tableau_step_bit_for_bit():
    # the RK4 step with variational equations is unrolled with deriv_var inlined (the
    # monodromy of every shooting problem); deriv_var must be deriv(want_var=True) exactly, and
    # the step the tableau loops' step exactly (their zero terms dropped: equal as numbers)
    n_cases = 0
    for model, exc, t, s, disc, rng in _field_cases():
        N, ne = model.n_dof, model.n_elements
        m = 2 * N + ne
        kc = KernelCall(model, exc, m=m)
        P = np.hstack([np.eye(2 * N), 0.1 * rng.normal(size=(2 * N, ne))]) + 0.01 * rng.normal(
            size=(2 * N, m))
        dvm = rng.normal(size=(ne, m))
        st1, ks1, kP1, f1 = kc.deriv(t, s, P, dvm, disc, want_var=True)
        st2, ks2, kP2, f2 = kc.deriv(t, s, P, dvm, disc, variant="deriv_var")
        assert st1 == st2 == 0
        np.testing.assert_array_equal(ks1, ks2)
        np.testing.assert_array_equal(kP1, kP2)
        np.testing.assert_array_equal(f1, f2)
        h = 2e-5
        s_ref, P_ref = _rk4_var_reference(kc, t, h, s, P, dvm, disc)
        st, s_out, P_out = kc.rk_step(_kernels.RK4, t, h, s, P, dvm, disc, True, ks1)
        assert st == 0
        np.testing.assert_array_equal(s_out, s_ref)
        np.testing.assert_array_equal(P_out, P_ref)
        n_cases += 1
    assert n_cases == 160


def test_the_unrolled_dp5_step_is_the_tableau_step_bit_for_bit():
    # the plain DP5 step (stochastic.simulate's default) is unrolled with the field inlined
    # (deriv_plain); it must give the tableau loops' new state and error vector exactly, on
    # every excitation kind, a quintic coefficient table (a noise block) included, or every
    # adaptive result would change
    from nlbeam._kernels import steps

    rng = np.random.default_rng(3)
    n = 41
    quintic = nlbeam.Sampled.from_table(0.0, 2e-3, rng.normal(size=(n, 4)) * [1e-4, 1e-2, 1.0,
                                                                             1e2])
    assert quintic.kernel_args()[0] == 4
    cases = [(m, e, t, s, d) for m, e, t, s, d, _ in _field_cases()]
    cases += [(m, quintic, t, s, d) for m, e, t, s, d in cases[:40]]
    for model, exc, t, s, disc in cases:
        kc = KernelCall(model, exc)
        n2, ne = 2 * model.n_dof, model.n_elements
        P, dvm = np.zeros((n2, 1)), np.zeros((ne, 1))
        st, f0, _, _ = kc.deriv(t, s, P, dvm, disc)
        assert st == 0
        out = []
        for fn in (steps._rk_step_plain, steps._rk_step_tableau):
            s_out, err = np.zeros(n2), np.full(n2, np.nan)
            args = (kc.sysa, kc.xc, kc.xp, kc.xtab)
            work = (np.zeros((7, n2)), np.zeros((7, n2, 1)), np.zeros(n2))
            if fn is steps._rk_step_plain:
                st = fn(_kernels.DP5, t, 3e-5, s, P, dvm, disc, *args, f0, s_out, *work,
                        np.zeros(ne), err)
            else:
                st = fn(_kernels.DP5, t, 3e-5, s, P, dvm, disc, False, *args, f0, s_out,
                        np.zeros((n2, 1)), *work[:2], work[2], np.zeros((n2, 1)), np.zeros(ne),
                        err)
            assert st == 0
            out.append((s_out, err))
        np.testing.assert_array_equal(out[0][0], out[1][0])
        np.testing.assert_array_equal(out[0][1], out[1][1])
        assert np.all(np.isfinite(out[0][1]))
    assert len(cases) == 200


def test_the_unrolled_graded_step_is_the_tableau_step_bit_for_bit():
    # rk_step_graded (the steps in sqrt(t - t_onset) and sqrt(delta) at a contact's ends) is
    # unrolled for RK4 with the field inlined; the reference is its tableau loops in Python
    A, B, C = _kernels._A_RK4, _kernels._B_RK4, _kernels._C_RK4
    n_cases = 0
    for model, exc, t, s, disc, rng in _field_cases():
        if disc[0, 0] == 0.0:
            continue
        N, ne = model.n_dof, model.n_elements
        m = 2 * N
        kc = KernelCall(model, exc, m=m)
        y, yd, _, _ = kc.excite(t)
        s[N:] -= 0.3 * np.abs(s[N:])  # mode 2 needs delta' < 0 on the step
        dd0 = kc.kinematics(0, s, y, yd)[1]
        w0 = model.element_geometry()[1][0]
        s[N:] += w0 * (-0.05 - dd0) / (w0 @ w0)
        P = np.eye(2 * N) + 0.01 * rng.normal(size=(2 * N, m))
        dvm = rng.normal(size=(ne, m))
        for mode, u0, hu in ((1, 0.0, 1e-3), (1, 2e-3, 1e-3), (2, 1.7e-3, -2e-4)):
            for want_var in (True, False):
                KS, KP, KT = np.zeros((4, 2 * N)), np.zeros((4, 2 * N, m)), np.zeros(4)
                t_ref = t - u0 * u0
                for i in range(4):
                    ytmp, Ptmp = s.copy(), P.copy()
                    for j in range(i):
                        ytmp = ytmp + hu * A[i, j] * KS[j]
                        Ptmp = Ptmp + hu * A[i, j] * KP[j]
                    ui = u0 + C[i] * hu
                    if mode == 1:
                        ti = t_ref + ui * ui
                    else:
                        ti = t
                        for j in range(i):
                            ti += hu * A[i, j] * KT[j]
                    st, KS[i], KP[i], _ = kc.deriv(ti, ytmp, Ptmp, dvm, disc, want_var)
                    assert st == 0
                    if mode == 1:
                        sc = 2.0 * ui
                    else:
                        yi, ydi, _, _ = kc.excite(ti)
                        sc = 2.0 * ui / kc.kinematics(0, ytmp, yi, ydi)[1]
                    KT[i] = sc
                    KS[i] *= sc
                    KP[i] *= sc
                s_ref, P_ref, t_end = s.copy(), P.copy(), t
                for j in range(4):
                    s_ref = s_ref + hu * B[j] * KS[j]
                    P_ref = P_ref + hu * B[j] * KP[j]
                    t_end += hu * B[j] * KT[j]
                if mode == 1:
                    t_end = t_ref + (u0 + hu) * (u0 + hu)
                st, tn, s_out, P_out = kc.rk_step_graded(_kernels.RK4, mode, u0, hu, t_ref, 0, s,
                                                         t, P, dvm, disc, want_var)
                assert st == 0
                np.testing.assert_array_equal(s_out, s_ref)
                assert tn == t_end
                if want_var:
                    np.testing.assert_array_equal(P_out, P_ref)
                n_cases += 1
    assert n_cases == 480


def test_xmax_is_the_max_of_the_dense_output():
    # xmax is refined on the quintic dense output only where a velocity changes sign and a
    # bound says the quintic could exceed the running max; a wrong skip leaves xmax below the
    # dense-output samples of some step (the adaptive steps are long, the grid fine here)
    exc = nlbeam.CosineSum([23.0, 61.0, 137.0], [1e-4, 5e-5, 2e-5], [0.0, 1.0, 2.0])
    tr = nlbeam.integrate(PAPER, exc, 0.4, method="adaptive", dt=1e-5, x0=[-2e-4, 0.0])
    assert tr.n_impacts > 5
    top = np.max(np.abs(tr.x[:, 0]))
    assert top <= tr.xmax[0] * (1 + 1e-14)
    assert tr.xmax[0] <= top * (1 + 1e-6)
