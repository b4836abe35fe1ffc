"""Bifurcation curves in two parameters (continuation.bifurcation_curve): the Duffing fold
curves and their cusp against one-parameter diagrams and a harmonic-balance computation done
here; the paper model's period-doubling curve through 58 Hz against diagrams at other
amplitudes; a grazing curve against brute-force orbits; a curve in (frequency, e); the front
door's checks."""
import dataclasses
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam

DUFFING_F = 0.3


@pytest.fixture(scope="module")
def duffing_fold_curve():
    m = nlbeam.Duffing()  # x'' + 0.1 x' + x + x^3 = F cos(2 pi f t)
    frc = C.frequency_response(m, DUFFING_F, (0.08, 0.4), orders=(1,), accuracy="off")
    fold = [b for b in frc.bifurcations if b.kind == "fold"][0]
    cur = C.bifurcation_curve(m, fold, (0.01, 2.0), amplitude=DUFFING_F, f_range=(0.08, 0.6),
                              at=(0.1, 0.2, 0.5))
    return m, cur


# --- harmonic balance of the Duffing oscillator (odd harmonics up to 9) -----------------------
_TAU = 2 * np.pi * np.arange(64) / 64
_KS = np.arange(3, 10, 2)


def _hb_force(a, om, c=0.1):
    """The forcing amplitude F whose periodic response has first harmonic a cos(tau) (tau =
    om t; the forcing's phase free): the higher harmonics solve their balance equations, F is
    the size of the first harmonic of om^2 x'' + c om x' + x + x^3."""
    from scipy.optimize import fsolve

    C_ = np.cos(np.outer(_KS, _TAU))
    S_ = np.sin(np.outer(_KS, _TAU))

    def lhs(pq):
        p, q = pq[:len(_KS)], pq[len(_KS):]
        x = a * np.cos(_TAU) + p @ C_ + q @ S_
        xd = -a * np.sin(_TAU) + (_KS * q) @ C_ - (_KS * p) @ S_
        xdd = -a * np.cos(_TAU) - (_KS ** 2 * p) @ C_ - (_KS ** 2 * q) @ S_
        return om ** 2 * xdd + c * om * xd + x + x ** 3

    def res(pq):
        r = lhs(pq)
        return np.r_[C_ @ r, S_ @ r] / 32

    pq = fsolve(res, np.zeros(2 * len(_KS)), xtol=1e-13)
    r = lhs(pq)
    return float(np.hypot(np.cos(_TAU) @ r, np.sin(_TAU) @ r) / 32)


def _hb_da(a, om, w=0.05):
    """dF/da and d2F/da2 at fixed om, from a Chebyshev fit of degree 12 on 25 points."""
    from numpy.polynomial import chebyshev as ch

    xs = a + w * np.cos(np.pi * (np.arange(25) + 0.5) / 25)
    cf = ch.chebfit((xs - a) / w, [_hb_force(x, om) for x in xs], 12)
    return ch.chebval(0, ch.chebder(cf)) / w, ch.chebval(0, ch.chebder(cf, 2)) / w ** 2


def test_duffing_fold_curves_meet_in_a_cusp_at_the_harmonic_balance_cusp(duffing_fold_curve):
    """The response at fixed F is the level set F(a, om) = F; folds in frequency are where
    dF/da = 0, and the two fold curves meet where also d2F/da2 = 0 (the cusp). Measured: F and
    f agree to 8e-8 and 1.1e-7 relative at the default step (2e-10 at dt_scale 1/4)."""
    from scipy.optimize import fsolve

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # fsolve at its round-off floor
        a_c, om_c = fsolve(lambda z: _hb_da(*z), [0.41, 1.09], xtol=1e-12)
        F_c = _hb_force(a_c, om_c)
    m, cur = duffing_fold_curve
    cusps = [c for c in cur.special if c.kind == "cusp"]
    assert len(cusps) == 1
    c = cusps[0]
    assert abs(c.value / F_c - 1) < 1e-6
    assert abs(c.frequency / (om_c / (2 * np.pi)) - 1) < 1e-6
    # the cusp is where the hysteresis begins: the smallest force on the fold curve
    assert c.value <= cur.values.min() * (1 + 1e-9)
    # two folds at every force above it (a curve crossing F twice), none below
    assert cur.ends == ("left the parameter range", "left the frequency range") or \
        cur.ends == ("left the frequency range", "left the parameter range")


def test_duffing_fold_curve_agrees_with_one_parameter_diagrams(duffing_fold_curve):
    m, cur = duffing_fold_curve
    for F in (0.1, 0.2, 0.5):
        frc = C.frequency_response(m, F, (0.08, 0.6), orders=(1,), accuracy="off")
        folds = sorted(b.frequency for b in frc.bifurcations if b.kind == "fold")
        on_curve = np.sort(cur.at(F))
        assert len(folds) == 2 and len(on_curve) == 2, (F, folds, on_curve)
        np.testing.assert_allclose(on_curve, folds, rtol=1e-6)


@pytest.fixture(scope="module")
def paper_pd_curve():
    m = nlbeam.BeamImpact()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        frc = C.frequency_response(m, 1e-4, (55.0, 62.0), orders=(1,), accuracy="off")
    pd = [b for b in frc.bifurcations if b.kind == "period-doubling"]
    assert len(pd) == 1 and abs(pd[0].frequency - 58.08) < 0.05
    cur = C.bifurcation_curve(m, pd[0], (2e-5, 5e-4), amplitude=1e-4, f_range=(5.0, 150.0),
                              at=(3e-5, 2e-4, 4.5e-4))
    return m, cur


@pytest.mark.parametrize("A", [3e-5, 2e-4, 4.5e-4])
def test_paper_period_doubling_curve_agrees_with_diagrams_at_other_amplitudes(paper_pd_curve, A):
    """The same discrete map: the curve's point and the diagram's period doubling (level 0 of
    its error estimate) agree to the solvers' tolerance; against the diagram's refined value
    within the two stated errors (measured: curve 5.8e-3..6.7e-3 Hz off, curve error
    6.9e-3..1.2e-2 Hz, diagram error 3-4e-6 Hz)."""
    m, cur = paper_pd_curve
    assert cur.ends == ("left the parameter range", "left the parameter range")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        frc = C.frequency_response(m, A, (55.0, 62.0), orders=(1,))
    pd = [b for b in frc.bifurcations if b.kind == "period-doubling" and b.order == 1]
    assert len(pd) == 1
    (f_curve,), (err,) = cur.at(A), cur.error_at(A)
    assert abs(f_curve - pd[0].levels[0]) < 1e-7 * f_curve
    assert np.isfinite(err) and np.isfinite(pd[0].error)
    assert abs(f_curve - pd[0].frequency) <= err + pd[0].error


def test_grazing_curve_agrees_with_brute_force_touching_amplitude():
    """At the curve's frequency for A_g = 0.2 mm, brute-force orbits (from the curve's orbit,
    finer step) at amplitudes just above A_g touch the stop near the grazing phase with a
    penetration that grows linearly in A; extrapolated to zero it gives the amplitude where
    they first touch, which must be A_g within the curve's error (mapped to amplitude by the
    curve's slope) and the extrapolation's."""
    m = nlbeam.BeamImpact()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        frc = C.frequency_response(m, 1e-4, (13.0, 16.0), orders=(1,), accuracy="off")
    g = min((b for b in frc.bifurcations if b.kind == "grazing"),
            key=lambda b: abs(b.frequency - 14.457))
    assert abs(g.frequency - 14.457) < 0.01
    Ag = 2e-4
    cur = C.bifurcation_curve(m, g, (5e-5, 4e-4), amplitude=1e-4, f_range=(5.0, 150.0),
                              at=(Ag,))
    i = int(np.nonzero(cur.exact & np.isclose(cur.values, Ag, rtol=1e-9))[0][0])
    fg, ph = cur.frequency[i], cur.phase[i] % 1.0
    slope = np.gradient(cur.frequency, cur.values)[i]  # Hz / m along the curve
    dA_curve = cur.error[i] / abs(slope)

    def touch(A):
        """Largest penetration (m) within 0.05 periods of the grazing phase, steady state."""
        ex = nlbeam.Harmonic(A, fg)
        dt = 1 / (fg * 4000)
        tr = nlbeam.integrate(m, ex, 60 / fg, x0=cur.state0[i], dt=dt, store_every=0)
        tr = nlbeam.integrate(m, ex, 61 / fg, x0=tr.state_end, t0=60 / fg, dt=dt)
        d = tr.delta[:, 0]
        near = np.nonzero(np.abs((tr.t * fg - ph + 0.5) % 1 - 0.5) < 0.05)[0]
        k = near[np.argmax(d[near])]
        y0, y1, y2 = d[k - 1], d[k], d[k + 1]  # parabola through the samples
        return y1 + (y2 - y0) ** 2 / (8 * (2 * y1 - y0 - y2))

    As = Ag * np.array([1.001, 1.002, 1.003, 1.004])
    dmax = np.array([touch(A) for A in As])
    assert np.all(dmax > 0)
    k, d0 = np.polyfit(As, dmax, 1)
    fit = np.max(np.abs(np.polyval([k, d0], As) - dmax)) / k  # its error, in amplitude
    A_touch = -d0 / k
    assert abs(A_touch - Ag) <= dA_curve + 10 * fit + 1e-6 * Ag, (A_touch, Ag, dA_curve, fit)
    # and below A_g the orbit does not touch there any more
    assert touch(Ag * 0.9995) < 0


def test_curve_in_frequency_and_restitution_agrees_with_diagrams(paper_pd_curve):
    """The period doubling continued in (frequency, e) at A = 0.1 mm, against diagrams
    recomputed with e changed."""
    m, _ = paper_pd_curve
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        frc = C.frequency_response(m, 1e-4, (55.0, 62.0), orders=(1,), accuracy="off")
    pd = [b for b in frc.bifurcations if b.kind == "period-doubling"][0]
    cur = C.bifurcation_curve(m, pd, (0.3, 0.8), amplitude=1e-4, parameter="e",
                              f_range=(20.0, 150.0), at=(0.4, 0.7), error=False)
    for e in (0.4, 0.7):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", C.ContinuationWarning)
            d = C.frequency_response(dataclasses.replace(m, e=e), 1e-4, (50.0, 66.0),
                                     orders=(1,), accuracy="off")
        f_diag = [b.frequency for b in d.bifurcations if b.kind == "period-doubling"]
        (f_curve,) = cur.at(e)
        assert min(abs(f - f_curve) for f in f_diag) < 1e-6 * f_curve, (e, f_diag, f_curve)
    assert np.all(cur.amplitude == 1e-4)


@pytest.mark.parametrize("kw, match", [
    ({"parameter": "gap_mm"}, "parameter: 'gap_mm' is not a parameter.*amplitude, m, b, k, k3"),
    ({"p_range": (2e-4, 5e-4)}, "p_range: must hold the start's amplitude"),
    ({"p_range": (0.0, 1.0)}, "p_range: amplitudes must be > 0"),
    ({"f_range": (60.0, 70.0)}, "f_range: must hold the start frequency"),
    ({"ds": -1.0}, "ds: must be finite and > 0"),
    ({"at": (3.0,)}, "at: values must lie inside p_range"),
    ({"directions": (2,)}, "directions:"),
])
def test_front_door_checks_its_input(kw, match):
    m = nlbeam.Duffing()
    bif = {"kind": "fold", "frequency": 0.2, "order": 1, "state0": np.zeros(2)}
    args = {"p_range": (1e-2, 2.0), "amplitude": 0.3}
    args.update(kw)
    p_range = args.pop("p_range")
    with pytest.raises(ValueError, match=match):
        C.bifurcation_curve(m, bif, p_range, **args)
    with pytest.raises(ValueError, match="kind must be one of"):
        C.bifurcation_curve(m, dict(bif, kind="pitchfork"), (1e-2, 2.0), amplitude=0.3)


def test_a_bifurcation_at_a_grazing_point_is_refused_with_the_way_out():
    bif = C.Bifurcation("period-doubling", 6.6484, 6.6484, 1e-4, 1, 0, 1e-9, None,
                        state0=np.zeros(2), note="at grazing: multiplier jumps from -3.4 to "
                        "-0.001 (non-smooth)")
    with pytest.raises(ValueError, match="trace the grazing curve instead"):
        C.bifurcation_curve(nlbeam.BeamImpact(), bif, (5e-5, 2e-4), amplitude=1e-4)
    with pytest.raises(ValueError, match="bifurcation: needs frequency, order and state0"):
        C.bifurcation_curve(nlbeam.BeamImpact(), {"kind": "fold", "frequency": 58.0,
                                                  "order": 1}, (5e-5, 2e-4), amplitude=1e-4)


# --- a Neimark-Sacker curve with a closed-form locus ----------------------------------------
_K1, _K2, _CD, _A = 1.0, 1.0, 0.1, 0.3


@nlbeam.systems._model_protocol
@dataclasses.dataclass(frozen=True)
class _Flutter:
    """x'' + c x' + K x = [F cos(2 pi f t), 0], K = [[k1 + ks, a], [-a, k2]] (a circulatory
    coupling): linear, so the orbit's multipliers are exp(lambda T) of the eigenvalues lambda
    of the structure, and its Neimark-Sacker locus in (f, ks) is the flutter boundary
    Re lambda = 0, independent of f: with s = lambda^2 + c lambda = -S +- i D
    (S = (k1 + ks + k2) / 2, D^2 = a^2 - (k1 + ks - k2)^2 / 4), lambda = i w needs D = c w and
    w^2 = S, i.e. d^2 + 2 c^2 d + 4 (c^2 k2 - a^2) = 0 for d = k1 + ks - k2."""

    ks: float = 0.6
    system: object = dataclasses.field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "system", nlbeam.System(
            np.eye(2), _CD * np.eye(2), [[_K1 + self.ks, _A], [-_A, _K2]], (), "force",
            y_load=[1.0, 0.0], yd_load=[0.0, 0.0], output_dof=0, name="Flutter"))

    def parameters(self):
        return {"model": "Flutter", "ks": self.ks}


def test_neimark_sacker_curve_is_the_closed_form_flutter_boundary():
    """The NS curve in (f, ks), started from an orbit off the curve (ks = 0.6, the start
    solved at its frequency since the locus runs along the frequency axis), lies on the
    Routh-Hurwitz flutter boundary ks = 0.5557738 over the whole frequency range, where the
    orbit has a complex pair of multipliers on the unit circle. Measured: |ks - ks_crit|
    1.7e-8 (the integration error of the monodromy); ||mu| - 1| asserted to 1e-6."""
    d = -_CD ** 2 + np.sqrt(_CD ** 4 - 4 * _CD ** 2 * _K2 + 4 * _A ** 2)
    ks_crit = d + _K2 - _K1
    m = _Flutter(0.6)
    sol = C.periodic_solution(m, 0.1, 0.1, error=False)
    assert np.all(np.abs(sol.multipliers) < 1)  # stable at ks = 0.6: off the curve
    bf = {"kind": "neimark-sacker", "frequency": 0.1, "order": 1, "state0": sol.state0}
    cur = C.bifurcation_curve(m, bf, (0.3, 0.8), amplitude=0.1, parameter="ks",
                              f_range=(0.07, 0.14), error=False)
    assert cur.kind == "neimark-sacker" and cur.ends == ("left the frequency range",) * 2
    assert cur.frequency.min() == pytest.approx(0.07) and cur.frequency.max() == \
        pytest.approx(0.14)
    assert np.max(np.abs(cur.values - ks_crit)) <= 1e-6 * ks_crit
    mu = cur.multipliers[:, :2]  # largest modulus first: the flutter pair
    assert np.all(np.abs(mu.imag) > 1e-3)  # a complex pair, not a neutral saddle
    assert np.max(np.abs(np.abs(mu) - 1.0)) <= 1e-6
    # off the curve the pair is off the unit circle, on the side Routh-Hurwitz says
    lam = np.linalg.eigvals(np.block([[np.zeros((2, 2)), np.eye(2)],
                                      [-np.array([[_K1 + 0.5, _A], [-_A, _K2]]),
                                       -_CD * np.eye(2)]]))
    assert lam.real.max() > 0  # ks = 0.5 < ks_crit: flutter
