"""The significance rule of PSD peaks (stochastic.peaks) on records of known spectra.

Two digital resonators (40 Hz strong, 120 Hz weaker) driven by white noise have the exact
one-sided PSD S(f) = sum_j 2 / (fs |A_j(e^{i 2 pi f / fs})|^2); the rule applied to S itself
gives the true peaks and prominences. Every independent record (other seeds) must list the
same peaks, each within two of its stated errors of the truth, and no other.
"""
import math

import numpy as np
import pytest
from scipy.signal import lfilter

import stochastic as st
from nlbeam.app.compare import map_peaks, welch_dof_of
from stochastic.peaks import log_scatter, significant_peaks

FS = 1000.0
RESONATORS = ((40.0, 0.995, 1.0), (120.0, 0.99, 0.5))  # (f0 Hz, pole radius, gain)


def _coeffs(f0, r):
    return [1.0, -2 * r * math.cos(2 * math.pi * f0 / FS), r * r]


def _exact_psd(f):
    z = np.exp(-2j * math.pi * f / FS)
    S = np.zeros(f.size)
    for f0, r, g in RESONATORS:
        a = _coeffs(f0, r)
        S += g * g * 2.0 / FS / np.abs(a[0] + a[1] * z + a[2] * z * z) ** 2
    return S


def _record(seed, seconds):
    rng = np.random.default_rng(seed)
    x = np.zeros(int(seconds * FS))
    for f0, r, g in RESONATORS:
        x += g * lfilter([1.0], _coeffs(f0, r), rng.standard_normal(x.size))
    return st.analyze(np.arange(x.size) / FS, {"x": x}, psd_resolution=0.5,
                      band=(0.0, 500.0), outputs=("psd",))


def test_the_log_scatter_of_a_chi_square_estimate():
    """sqrt(trigamma(nu/2)) / ln 10 against the sample scatter of log10(chi2_nu / nu)."""
    rng = np.random.default_rng(1)
    for nu in (4.0, 36.0):
        s = np.std(np.log10(rng.chisquare(nu, 400000) / nu))
        assert log_scatter(nu) == pytest.approx(s, rel=0.01)


@pytest.mark.parametrize("seed", range(4))
def test_every_record_lists_the_true_peaks_within_their_errors(seed):
    """20 s records (19 Welch segments, nu about 36): exactly the two resonances, each at
    the exact PSD's maximum within 2 frequency errors and with its prominence within 3
    prominence errors; the dof reach the rule (welch_dof_of) and set its threshold."""
    res = _record(seed, 20.0)
    f, P = res.psd("x")
    dof = welch_dof_of(res, "x")
    assert dof is not None and 30.0 < np.median(dof) < 45.0
    sel = f <= 250.0
    truth = significant_peaks(f[sel], _exact_psd(f[sel]))
    assert truth.frequency.tolist() == pytest.approx([40.0, 120.0], abs=0.5)
    got = significant_peaks(f[sel], P[sel], dof[sel])
    assert got.index.size == 2, got.frequency
    assert np.all(np.abs(got.frequency - truth.frequency) <= 2 * got.frequency_error)
    assert np.all(np.abs(got.prominence - truth.prominence) <= 3 * got.prominence_error)
    assert np.all(got.prominence_error >= math.sqrt(2) * log_scatter(dof[got.index]) - 1e-12)
    # map_peaks reports the same peaks with their errors
    from types import SimpleNamespace

    m = map_peaks((f[sel], P[sel]), SimpleNamespace(branches=[], bifurcations=[],
                                                    superharmonics=[]), dof=dof[sel])
    assert [p.frequency for p in m] == got.frequency.tolist()
    assert [p.frequency_error for p in m] == got.frequency_error.tolist()


def test_chi_square_noise_makes_no_peak():
    """300 chi-square draws (nu = 30) of a smooth spectrum with one resonance: the rule finds
    that one in every draw and a noise peak in at most 1 % of them (1 of 300 here, on the
    resonance's flank), and its stated frequency error covers the true maximum (2 errors)
    in at least 90 % of them."""
    f = np.arange(0.0, 200.0001, 0.25)
    fn, zeta = 20.0, 0.05
    S = np.maximum(f ** 4 / ((fn ** 2 - f ** 2) ** 2 + (2 * zeta * fn * f) ** 2), 1e-30)
    f_top = f[np.argmax(S)]
    rng = np.random.default_rng(0)
    n_found, covered = [], 0
    for _ in range(300):
        got = significant_peaks(f, S * rng.chisquare(30.0, f.size) / 30.0, 30.0)
        n_found.append(got.index.size)
        j = int(np.argmax(got.prominence))
        covered += int(abs(got.frequency[j] - f_top) <= 2 * got.frequency_error[j])
    assert min(n_found) == 1 and sum(n != 1 for n in n_found) <= 3, np.bincount(n_found)
    assert covered >= 270


@pytest.mark.parametrize("kw, name", [({"confidence": -1.0}, "confidence"),
                                      ({"min_prominence": -0.1}, "min_prominence"),
                                      ({"min_prominence": math.nan}, "min_prominence"),
                                      ({"background_hz": 0.5}, "background_hz"),
                                      ({"dof": 0.0}, "dof")])
def test_bad_arguments_name_the_parameter(kw, name):
    f = np.arange(0.0, 100.0, 0.5)
    P = 1.0 + np.exp(-0.5 * ((f - 40.0) / 2.0) ** 2)
    with pytest.raises(ValueError, match=f"^{name}: "):
        significant_peaks(f, P, **kw)
