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
CD_EPS = (2e-5, 1e-5)  # central-difference steps, relative to the state's scales (the map's
# round-off, a few 1e-15 relative, gives 3e-10 at 1e-5; the truncation 2e-10 at 2e-5)
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


def scaled_error(M, ref, scales):
    """max |D^-1 (M - ref) D| / max |D^-1 ref D|, D = diag(scales)."""
    D = np.diag(scales)
    A = np.linalg.solve(D, M @ D)
    B = np.linalg.solve(D, ref @ D)
    return float(np.max(np.abs(A - B)) / np.max(np.abs(B)))


def _check_flow(model, ex, t0, s0, scales, duration, **kw):
    def run(s, mono=False):
        return nlbeam.flow(model, ex, s, t0, duration, monodromy=mono, warn=False, **kw)

    fl = run(s0, True)
    M1, M2 = (central_differences(run, s0, scales, eps) for eps in CD_EPS)
    return fl, scaled_error(M1, M2, scales), scaled_error(fl.monodromy, M1, scales)


@pytest.mark.parametrize("method,graded", METHODS,
                         ids=[f"{m}-{'graded' if g else 'plain'}" for m, g in METHODS])
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_monodromy_is_the_derivative_of_the_fixed_step_map(name, method, graded):
    model, ex, t_start, s0, scales = _orbit_start(name)
    T = 1.0 / ex.frequency
    dt = T / (100 if method == "rk4" else 400)
    errs = []
    for off in OFFSETS:
        fl, cd_err, err = _check_flow(model, ex, t_start + off * dt, s0, scales, T,
                                      method=method, dt=dt, graded=graded)
        # the flow holds whole contacts: it starts and ends out of contact
        assert fl.n_impacts >= 1 and not np.any(fl.disc[:, 0])
        # the two difference steps agree: the differencing error is far below TOL
        assert cd_err < 0.05 * TOL, (off, cd_err)
        errs.append(err)
    assert max(errs) < TOL, errs


@pytest.mark.parametrize("name", ["hertz", "lankarani-nikravesh", "pwl-zero-gap-force"])
def test_monodromy_from_inside_a_contact(name):
    # a flow that starts inside a contact: the contact step then follows from the state at the
    # start; with the onset velocity held (disc0), its own sensitivity column too
    model, ex, t_start, s0, scales = _orbit_start(name)
    T = 1.0 / ex.frequency
    tr = nlbeam.integrate(model, ex, t_start + T, t0=t_start, x0=s0, dt=T / 400)
    k = int(np.argmax(tr.delta[:, 0]))
    k = k + (int(np.argmax(tr.delta[k:, 0] < 0.5 * tr.delta[k, 0])) // 2)
    t0, s_in = float(tr.t[k]), np.r_[tr.x[k], tr.v[k]]
    assert tr.delta[k, 0] > 0
    for off in OFFSETS[:2]:
        fl, cd_err, err = _check_flow(model, ex, t0 + off * T / 100, s_in, scales, T,
                                      dt=T / 100)
        assert fl.n_impacts >= 1 and cd_err < 0.05 * TOL and err < TOL, (off, cd_err, err)
    if name != "lankarani-nikravesh":
        return
    # the onset velocity held at the start (disc0) and its sensitivity column
    disc0 = fl.disc.copy()
    disc0[0] = [1.0, 0.3]

    def run(v):
        d = disc0.copy()
        d[0, 1] = v
        return nlbeam.flow(model, ex, s_in, t0, T, disc0=d, dt=T / 100, monodromy=True)

    fl = run(0.3)
    dv = 1e-5 * 0.3
    fd = (run(0.3 + dv).state - run(0.3 - dv).state) / (2 * dv)
    assert np.max(np.abs(fl.dstate_dvminus0[:, 0] - fd) / scales) < TOL * np.max(
        np.abs(fd) / scales)


def test_monodromy_where_the_contact_law_limits_the_step():
    # few steps per contact: the explicit-stability limit of the contact law (a function of
    # the penetration) sets the contact step
    model, ex, t_start, s0, scales = _orbit_start("hertz")
    T = 1.0 / ex.frequency
    for off in OFFSETS:
        fl, cd_err, err = _check_flow(model, ex, t_start + off * T / 100, s0, scales, T,
                                      dt=T / 100, steps_per_contact=6, graded=False)
        assert cd_err < 0.05 * TOL and err < TOL, (off, cd_err, err)
