"""flow's monodromy is the derivative of the map flow computes: central differences of the same
fixed-step map agree to the differencing error, for every element kind, every fixed-step method
and any position of the step grid, over flows that hold whole contacts (onset and exit), where
the contact steps, the graded phases and the landed event times all depend on the state."""
import functools

import numpy as np
import pytest

import nlbeam

WN = 2 * np.pi * 20.0   # rad/s: the 1-DOF structures' natural frequency
TOL = 1e-7              # relative, entrywise on the scaled monodromy
CD_EPS = (4e-5, 2e-5)  # central-difference steps, relative to the state's scales: the map's
# round-off (1e-15..1e-13 relative) gives 1e-10..4e-9 at 2e-5, the truncation ~1e-9 at 4e-5
OFFSETS = (0.0, 0.23, 0.5, 0.81)  # t0 shifted by these fractions of a step


def _sdof(elements, kind="base", f_n=20.0, zeta=0.02):
    wn = 2 * np.pi * f_n
    extra = {"y_load": [1.0]} if kind == "force" else {}
    return nlbeam.System([[1.0]], [[2 * zeta * wn]], [[wn * wn]], elements=elements,
                         excitation_kind=kind, **extra)


def _systems():
    mu = nlbeam.mu_from_e(0.5, 2.1e8, 0.1)
    K2 = np.array([[2.0, -1.0], [-1.0, 1.0]]) * WN ** 2
    between = nlbeam.System(np.diag([1.0, 0.5]), 1e-3 / WN * K2, K2, elements=(
        nlbeam.Contact([1.0, -1.0], "hertz", 2.1e8, gap=1e-4, on_base=False),))
    wn1 = 2 * np.pi
    return {
        "hertz": (nlbeam.BeamImpact.paper(contact="hertz"), nlbeam.Harmonic(1e-4, 40.0)),
        "lankarani-nikravesh": (nlbeam.BeamImpact.paper(), nlbeam.Harmonic(1e-4, 40.0)),
        "hunt-crossley": (nlbeam.BeamImpact.paper(contact="hunt-crossley", mu=mu),
                          nlbeam.Harmonic(1e-4, 40.0)),
        # a stiff linear stop after a gap, mounted on the moving base
        "pwl-gap-on-base": (_sdof((nlbeam.PiecewiseLinearStop(0, k=100 * WN ** 2, gap=2e-4),)),
                            nlbeam.Harmonic(1e-3, 25.0)),
        # a 4k stop at zero gap under force excitation
        "pwl-zero-gap-force": (_sdof((nlbeam.PiecewiseLinearStop(0, k=4 * WN ** 2, gap=0.0,
                                                                 on_base=False),), "force"),
                               nlbeam.Harmonic(50.0, 27.0)),
        # a Hertz contact between two masses (two contacts a period)
        "hertz-between-dofs": (between, nlbeam.Harmonic(1e-3, 30.0)),
        # a cubic spring with a one-sided stop (the Duffing oscillator with a stop)
        "cubic-with-stop": (_sdof((nlbeam.CubicSpring(0, k3=10.0),
                                   nlbeam.PiecewiseLinearStop(0, k=100 * wn1 ** 2, gap=0.5,
                                                              on_base=False)), "force", f_n=1.0),
                            nlbeam.Harmonic(20.0, 1.3)),
    }


SYSTEMS = _systems()
METHODS = [("rk4", True), ("rk4", False), ("rk2", True), ("rk2", False)]


@functools.lru_cache(maxsize=None)
def _orbit_start(name):
    """(model, excitation, t, state, scales): the settled response's state where it is farthest
    from every stop, and the max |x_i|, |v_i| over a period (the scales of the state)."""
    model, ex = SYSTEMS[name]
    T = 1.0 / ex.frequency
    tr = nlbeam.integrate(model, ex, 40 * T, dt=T / 400)
    last = tr.t >= 39 * T - 1e-12
    last[-1] = False
    ev = [e for e, el in enumerate(model.system.elements)
          if not isinstance(el, nlbeam.CubicSpring)]
    k = np.flatnonzero(last)[np.argmin(np.max(tr.delta[last][:, ev], axis=1))]
    S = np.hstack([tr.x, tr.v])[last]
    # the same phase in the first period: small t, whose last bits (the landed event times are
    # exact to a few of them) perturb the map less than the differences' steps resolve
    t = float(tr.t[k]) - 39 * T
    return model, ex, t, np.r_[tr.x[k], tr.v[k]], np.max(np.abs(S), axis=0)


def central_differences(run, s, scales, eps):
    """d run(s).state / d s by central differences with steps eps * scales."""
    M = np.empty((s.size, s.size))
    for k in range(s.size):
        e = np.zeros(s.size)
        e[k] = eps * scales[k]
        M[:, k] = (run(s + e).state - run(s - e).state) / (2 * e[k])
    return M


def one_sided_column(run, s, k, h, ref_scale):
    """d run(s).state / d s_k by the second-order one-sided difference on the side where the
    map is smooth: of the forward and the backward differences at steps h/2 and h/4, the side
    whose two agree best (the map is piecewise smooth, and a kink lies within h on the other
    side). Returns (column, the disagreement of its two estimates / ref_scale)."""
    def f(a):
        e = np.zeros(s.size)
        e[k] = a
        return run(s + e).state

    f0 = f(0.0)
    best = None
    for sign in (1.0, -1.0):
        est = [sign * (-3 * f0 + 4 * f(sign * hh) - f(2 * sign * hh)) / (2 * hh)
               for hh in (h / 2, h / 4)]
        spread = float(np.max(np.abs(est[0] - est[1]) / ref_scale))
        if best is None or spread < best[1]:
            best = (est[1], spread)
    return best


def scaled_error(M, ref, scales):
    """max |D^-1 (M - ref) D| / max |D^-1 ref D|, D = diag(scales)."""
    D = np.diag(scales)
    A = np.linalg.solve(D, M @ D)
    B = np.linalg.solve(D, ref @ D)
    return float(np.max(np.abs(A - B)) / np.max(np.abs(B)))


def _check_flow(model, ex, t0, s0, scales, duration, cd_scales=None, **kw):
    """(flow with monodromy, its error against differences of the same map, how many columns
    needed one-sided differences). The map is piecewise smooth: where a step count or the
    branch of a min() changes within the difference step, the central differences at two steps
    disagree; that column is then taken by one-sided differences on the smooth side. Asserts
    that the differences agree with themselves to well below TOL."""
    def run(s, mono=False):
        return nlbeam.flow(model, ex, s, t0, duration, monodromy=mono, warn=False, **kw)

    cd_scales = scales if cd_scales is None else cd_scales
    fl = run(s0, True)
    M1, M2 = (central_differences(run, s0, cd_scales, eps) for eps in CD_EPS)
    D = np.diag(scales)
    ref = np.max(np.abs(np.linalg.solve(D, M2 @ D)))   # the scaled monodromy's size
    kinks = 0
    for k in range(s0.size):
        spread = np.max(np.abs(M1[:, k] - M2[:, k]) / scales) * scales[k] / ref
        if spread > 0.2 * TOL:
            kinks += 1
            col, spread = one_sided_column(run, s0, k, CD_EPS[0] * cd_scales[k],
                                           ref / scales[k] * scales)
            M2[:, k] = col
        assert spread < 0.2 * TOL, (k, spread)
    return fl, scaled_error(fl.monodromy, M2, scales), kinks


@pytest.mark.parametrize("method,graded", METHODS,
                         ids=[f"{m}-{'graded' if g else 'plain'}" for m, g in METHODS])
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_monodromy_is_the_derivative_of_the_fixed_step_map(name, method, graded):
    model, ex, t_start, s0, scales = _orbit_start(name)
    T = 1.0 / ex.frequency
    dt = T / (100 if method == "rk4" else 400)
    errs, kinks = [], 0
    for off in OFFSETS:
        fl, err, n_kinks = _check_flow(model, ex, t_start + off * dt, s0, scales, T,
                                       method=method, dt=dt, graded=graded)
        # the flow holds whole contacts: it starts and ends out of contact
        assert fl.n_impacts >= 1 and not np.any(fl.disc[:, 0])
        errs.append(err)
        kinks += n_kinks
    assert max(errs) < TOL, errs
    assert kinks <= s0.size   # central differences apply nearly everywhere


@pytest.mark.parametrize("name", ["hertz", "lankarani-nikravesh", "pwl-zero-gap-force"])
def test_monodromy_from_inside_a_contact(name):
    # a flow that starts inside a contact: the contact step then follows from the state at the
    # start; the onset velocity is held (disc0), with its own sensitivity column
    model, ex, t_start, s0, scales = _orbit_start(name)
    T = 1.0 / ex.frequency
    tr = nlbeam.integrate(model, ex, t_start + T, t0=t_start, x0=s0, dt=T / 400)
    k = int(np.argmax(tr.delta[:, 0]))
    k = k + (int(np.argmax(tr.delta[k:, 0] < 0.5 * tr.delta[k, 0])) // 2)
    assert tr.delta[k, 0] > 0
    t0 = float(tr.t[k])
    for off in OFFSETS[:2]:
        t1 = t0 + off * T / 100
        inside = nlbeam.flow(model, ex, s0, t_start, t1 - t_start, dt=T / 400)
        assert inside.disc[0, 0] == 1.0
        # differences in x of the order of the penetration (the map is far from linear in
        # the penetration on the scale of the orbit's amplitude)
        cd_scales = np.array([tr.delta[k, 0], scales[1]])
        fl, err, _ = _check_flow(model, ex, t1, inside.state, scales, T, cd_scales, dt=T / 100,
                                 disc0=inside.disc)
        assert fl.n_impacts >= 1 and err < TOL, (off, err)
        if name != "lankarani-nikravesh":
            continue
        vm = inside.disc[0, 1]

        def run(v):
            d = inside.disc.copy()
            d[0, 1] = v
            return nlbeam.flow(model, ex, inside.state, t1, T, disc0=d, dt=T / 100)

        fd = [(run(vm * (1 + eps)).state - run(vm * (1 - eps)).state) / (2 * eps * vm)
              for eps in CD_EPS]
        assert np.max(np.abs(fd[0] - fd[1]) / scales) < 0.1 * TOL * np.max(np.abs(fd[1]) / scales)
        assert np.max(np.abs(fl.dstate_dvminus0[:, 0] - fd[1]) / scales) < TOL * np.max(
            np.abs(fd[1]) / scales)


def test_monodromy_where_the_contact_law_limits_the_step():
    # few steps per contact: the explicit-stability limit of the contact law (a function of
    # the penetration) sets the contact step
    model, ex, t_start, s0, scales = _orbit_start("hertz")
    T = 1.0 / ex.frequency
    for off in OFFSETS:
        fl, err, _ = _check_flow(model, ex, t_start + off * T / 100, s0, scales, T,
                                 dt=T / 100, steps_per_contact=6, graded=False)
        assert err < TOL, (off, err)


def test_onset_velocity_sensitivities_against_differences():
    # the flows whose sensitivities test_integrate once pinned to main's numbers (then the
    # derivative of the continuous flow, not of the map): against central differences of the
    # map; the second starts inside a contact with its onset velocity held in disc0
    model, ex = SYSTEMS["lankarani-nikravesh"]
    sc = np.array([1e-4, 2 * np.pi * 40.0 * 1e-4])

    def run(s, disc0=None, mono=False):
        return nlbeam.flow(model, ex, s, 0.0, 0.025, disc0=disc0, monodromy=mono, warn=False)

    for s0, disc0 in (([0.0, 0.0], None), ([1.03e-4, 0.02], np.array([[1.0, 0.02]]))):
        s0 = np.array(s0)
        fl = run(s0, disc0, True)
        assert fl.n_impacts >= 1
        M = np.empty((2, 2))
        dv = np.empty((1, 2))
        for k in range(2):
            e = np.zeros(2)
            e[k] = 1e-6 * sc[k]
            hi, lo = run(s0 + e, disc0), run(s0 - e, disc0)
            M[:, k] = (hi.state - lo.state) / (2 * e[k])
            dv[0, k] = (hi.disc[0, 1] - lo.disc[0, 1]) / (2 * e[k])
        assert scaled_error(fl.monodromy, M, sc) < TOL
        np.testing.assert_allclose(fl.dvminus_dstate0 * sc, dv * sc, rtol=0,
                                   atol=TOL * np.max(np.abs(dv * sc)))
        if disc0 is None:
            continue
        h = 1e-6 * disc0[0, 1]
        hi, lo = (run(s0, disc0 + [[0.0, a]]) for a in (h, -h))
        ds = (hi.state - lo.state) / (2 * h)
        np.testing.assert_allclose(fl.dstate_dvminus0[:, 0] / sc, ds / sc, rtol=0,
                                   atol=TOL * np.max(np.abs(ds / sc)))
        dvv = (hi.disc[0, 1] - lo.disc[0, 1]) / (2 * h)
        assert abs(fl.dvminus_dvminus0[0, 0] - dvv) < TOL * abs(dvv) + 1e-12


@pytest.mark.parametrize("method", ["rk4", "rk2"])
@pytest.mark.parametrize("name", ["hertz", "lankarani-nikravesh", "pwl-gap-on-base"])
def test_monodromy_where_dt_limits_the_contact_steps(name, method):
    # dt well below the contact step: the graded onset's steps in sigma and the exit's steps
    # in u are shortened so that none lasts longer than dt, with the onset's span and the
    # exit's start still functions of the state
    model, ex, t_start, s0, scales = _orbit_start(name)
    T = 1.0 / ex.frequency
    dt = T / (4000 if method == "rk4" else 8000)
    for off in OFFSETS[:2]:
        fl, err, _ = _check_flow(model, ex, t_start + off * dt, s0, scales, T, method=method,
                                 dt=dt)
        assert fl.n_impacts >= 1 and not np.any(fl.disc[:, 0])
        assert err < TOL, (off, err)
