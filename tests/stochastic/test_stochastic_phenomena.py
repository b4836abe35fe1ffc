"""The nonlinear phenomena of the paper's section 5 that a linear model cannot show:
the stochastic 1/2 subharmonic under narrow-band noise around twice the harmonic
resonance, several resonance peaks and low-frequency energy under broad-band noise."""
import warnings

import numpy as np
import pytest
import scipy.signal

import nlbeam
import stochastic as st

PAPER = nlbeam.BeamImpact.paper()
LINEAR = nlbeam.BeamImpact.paper(K_hertz=0.0)


def band_power(f, P, lo, hi):
    sel = (f >= lo) & (f <= hi)
    return float(np.sum(P[sel]) * (f[1] - f[0]))


def run(model, band, rms, seed, duration, resolution):
    noise = st.BandLimitedNoise(band, rms=rms, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # few-steps notes; checked below
        res = st.simulate(model, noise, duration, transient=2.0, outputs=("psd",),
                          psd_resolution=resolution)
    assert res.success, res.message
    return res


@pytest.fixture(scope="module")
def subharmonic_runs():
    # the harmonic resonance of the impacting beam is near 44 Hz (PHYSICS.md section 2), so
    # 78-98 Hz is "twice the harmonic resonance"; 110-130 Hz is a control band that is not.
    # rms 0.1 mm; the result hardly depends on it (tried 0.01, 0.03, 0.1, 0.3 mm: the
    # half-band / band power ratio of delta was 13.0, 13.1, 13.3, 13.2 for seed 5)
    out = {}
    for key, model, band in (("paper", PAPER, (78.0, 98.0)), ("linear", LINEAR, (78.0, 98.0)),
                             ("control", PAPER, (110.0, 130.0))):
        out[key] = run(model, band, 1e-4, 5, 10.0, 0.5)
    return out


def test_narrow_band_at_twice_the_resonance_gives_a_stochastic_half_subharmonic(subharmonic_runs):
    """Paper section 7: excitation in 78-98 Hz puts a response peak in 39-49 Hz, half the
    excitation frequencies; the linear model under the same noise has nothing there."""
    f, P = subharmonic_runs["paper"].psd("delta")
    fl, Pl = subharmonic_runs["linear"].psd("delta")
    half_nl = band_power(f, P, 39.0, 49.0)
    band_nl = band_power(f, P, 78.0, 98.0)
    half_lin = band_power(fl, Pl, 39.0, 49.0)
    band_lin = band_power(fl, Pl, 78.0, 98.0)
    # measured (seed 5, 10 s): half/band 13.3 for the impacting beam, ~3e-12 (window leakage)
    # for the linear one; paper/linear in the half band ~1e13
    assert half_nl > 5.0 * band_nl
    assert half_lin < 1e-6 * band_lin
    assert half_nl > 1e6 * half_lin
    # the peak of the response between 30 and 60 Hz lies in the half band (measured 43.5 Hz)
    sel = (f >= 30.0) & (f <= 60.0)
    f_peak = f[sel][np.argmax(P[sel])]
    assert 39.0 <= f_peak <= 49.0, f_peak
    # the response is a subharmonic response, not an impact-free linear one
    assert subharmonic_runs["paper"].n_impacts > 200


def test_half_subharmonic_needs_twice_the_resonance(subharmonic_runs):
    """Control: the same noise moved to 110-130 Hz leaves 55-65 Hz nearly empty
    (measured half/band 0.02, against 13 at 78-98 Hz)."""
    f, P = subharmonic_runs["control"].psd("delta")
    assert band_power(f, P, 55.0, 65.0) < 0.2 * band_power(f, P, 110.0, 130.0)


def test_broad_band_response_has_several_peaks_and_low_frequency_energy():
    """Paper section 5: under flat 0-200 Hz noise the PSD of delta has several resonance
    peaks (measured 44, 87, 132 Hz: the harmonic resonance and its multiples) and a large
    share of its variance below 15 Hz (measured 0.35, linear model 0.0013), from the
    asymmetry of the stop."""
    kw = dict(band=(0.0, 200.0), rms=1e-4, seed=8, duration=16.0, resolution=1.0)
    nl = run(PAPER, **kw)
    lin = run(LINEAR, **kw)
    shares, peaks = [], []
    for res in (nl, lin):
        f, P = res.psd("delta")
        shares.append(band_power(f, P, 0.0, 15.0) / band_power(f, P, 0.0, f[-1]))
        sel = (f > 2.0) & (f < 190.0)
        idx, _ = scipy.signal.find_peaks(np.log10(P[sel]), prominence=0.5)  # half a decade
        peaks.append(f[sel][idx])
    assert len(peaks[0]) >= 2, peaks[0]
    assert np.any(np.abs(peaks[0] - 44.0) < 5.0)  # the harmonic resonance of the impacting beam
    assert len(peaks[1]) >= 1 and np.any(np.abs(peaks[1] - 22.2) < 1.5)
    assert shares[0] > 0.2 and shares[1] < 0.01
    assert shares[0] > 20 * shares[1]


def test_an_onset_with_non_positive_rate_fails_the_result(monkeypatch):
    """A contact onset whose penetration rate is <= 0 (a grazing re-entry the integrator
    did not resolve) flips the sign of the Lankarani-Nikravesh damping term and feeds
    energy in; simulate marks such a record as failed and warns."""
    real = nlbeam.integrate

    def tampered(*args, **kwargs):
        tr = real(*args, **kwargs)
        if tr.n_events:
            k = int(np.nonzero(tr.events[:tr.n_events, 2] == 1)[0][0])
            tr.events[k, 3] = -1e-3
        return tr

    monkeypatch.setattr(nlbeam, "integrate", tampered)
    with pytest.warns(RuntimeWarning, match="penetration rate <= 0"):
        res = st.simulate(PAPER, nlbeam.Harmonic(1e-4, 40.0), 0.5, transient=0.0,
                          outputs=("moments",), chunk_duration=0.25)
    assert not res.success and res.message.startswith("failed")


def test_a_runaway_response_fails_the_result(monkeypatch):
    """If the integrator gains energy numerically (seen with a stiff low-velocity contact),
    the excursion of x jumps far above its typical size: simulate marks the record failed."""
    real = nlbeam.integrate
    calls = []

    def tampered(*args, **kwargs):
        tr = real(*args, **kwargs)
        calls.append(1)
        if len(calls) == 6:
            tr.x[tr.x.shape[0] // 2, 0] = 1.0  # a 1 m excursion in the sixth chunk
        return tr

    monkeypatch.setattr(nlbeam, "integrate", tampered)
    with pytest.warns(RuntimeWarning, match="ran away"):
        res = st.simulate(PAPER, nlbeam.Harmonic(1e-4, 40.0), 2.0, transient=0.0,
                          outputs=("moments",), chunk_duration=0.25)
    assert not res.success and "t = 1.25 s" in res.message
