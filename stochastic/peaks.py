"""Peaks of a Welch PSD estimate that stand out of its statistical scatter, with errors.

The rule (``significant_peaks``)
--------------------------------
``L = log10 P`` is compared with its running median over ``background_hz`` (the local
background): ``r = L - median``. Two scatters of ``L`` per bin are known:

- the Welch estimate's own: ``P = S chi2_nu / nu`` for Gaussian data with ``nu``
  equivalent degrees of freedom (``WelchPSD.dof``), so ``log10 P`` has the standard
  deviation ``sigma_W = sqrt(trigamma(nu / 2)) / ln 10`` (0.084 decade at nu = 55, a 60 s
  record at 0.25 Hz);
- the record's measured one: the robust bin-to-bin scatter of ``r`` (``1.4826 MAD(diff r) /
  sqrt 2``), which also holds what the chi-square law misses (a non-Gaussian response, the
  slow block-to-block fluctuation of a block-synthesized noise).

``sigma`` is the larger of the two. A local maximum of ``r`` is a peak when its
topographic prominence ``p`` (top minus the higher of its two bases, each the lowest point
within ``background_hz`` of the top before a higher one, decades) exceeds
``min_prominence`` by ``z`` standard errors of a difference of two bins,
``p >= min_prominence + z sqrt(2) sigma``, and its top stands above the background,
``r >= z sigma`` (``z = confidence``, one-sided: 3 leaves a peak whose true prominence is
``min_prominence`` out of 99.9 % of records). The height is not held to
``min_prominence``: the running median follows a hump a few Hz wide, so a broad peak's
height over it is small and noisy (0.31-0.44 decade for the 4-mode beam's 62-64 Hz hump in
three records whose prominences are 0.76-0.82). Peaks closer than ``distance_bins`` are
merged by scipy's rule (the higher one stays). A PSD that starts at 0 Hz is mirrored there
(it is even in f) for the background and for a peak at 0 Hz.

Errors (one standard deviation) and significance:

- ``prominence_error = sqrt(2) sigma``;
- ``frequency_error``: how far from the top bin the top of another record of the same
  length may lie: the larger of the distance to the farther end of the contiguous bins
  around it whose ``r`` lies within ``sqrt(2) sigma`` of the top, and the same for the
  peak's smooth shape (a parabola in ``r`` through the top and the half width ``w`` at
  half prominence ``p``: ``w sqrt(2 sqrt(2) sigma / p)``; a single high bin makes the
  first too small), and at least half a bin;
- ``significance = (p - min_prominence) / prominence_error``: how many standard errors the
  peak clears ``min_prominence`` by (>= z for every peak listed).

Two records of the same process (or one record under other round-off, which an impacting
response amplifies into another realization) list the same strong peaks, with frequencies
within these errors; a peak of significance near ``z`` may be listed in one record only.
Measured on the 4-mode beam's 60 s scene record and two copies with the excitation scaled
by 1 +- 1e-13: 31 Hz (significance 7-9) and the low-frequency peak at 0.5-1.25 Hz (3.3-4.5)
in all three, the 62-64 Hz hump (2.1-4.0) in one. The stated prominence error is too small
for such a response: over five 40 s records of the 2-mode beam that differ by round-off,
the hump's significance spans 3.3-6.4 while the resonance's spans 6.3-6.7. The Welch
chi-square law and the bin-to-bin scatter miss the slow fluctuation of a block-synthesized
noise (its band energies hold for a realization span, 4.4 s at 0-200 Hz, in all the bins of
a hump together); PSDs of batches of two spans each would measure it, as the moments'
standard errors do (``stochastic.errors``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PeakSet", "significant_peaks", "log_scatter", "DEFAULT_CONFIDENCE"]

#: z of the one-sided test that a peak's prominence exceeds min_prominence
DEFAULT_CONFIDENCE = 3.0


@dataclass(frozen=True)
class PeakSet:
    """The peaks of one PSD (arrays of equal length, by frequency). index: bins;
    frequency (Hz); prominence (decades, of log10 P over the running median);
    prominence_error (decades); frequency_error (Hz); half_width (Hz, at half prominence);
    threshold: the prominence each peak had to reach (decades, per peak); significance:
    (prominence - min_prominence) / prominence_error; background:
    the running median of log10 P at every bin; sigma: the scatter of log10 P used at
    every bin (decades)."""

    index: np.ndarray
    frequency: np.ndarray
    prominence: np.ndarray
    prominence_error: np.ndarray
    frequency_error: np.ndarray
    half_width: np.ndarray
    threshold: np.ndarray
    significance: np.ndarray
    background: np.ndarray
    sigma: np.ndarray


def _odd(n):
    n = max(int(n), 3)
    return n if n % 2 else n + 1


def log_scatter(dof):
    """Standard deviation (decades) of log10 of a chi-square estimate with ``dof``
    degrees of freedom divided by them: sqrt(trigamma(dof / 2)) / ln 10 (elementwise;
    NaN where dof <= 0)."""
    from scipy.special import polygamma

    nu = np.asarray(dof, dtype=float)
    out = np.full(nu.shape, np.nan)
    ok = np.isfinite(nu) & (nu > 0)
    out[ok] = np.sqrt(polygamma(1, nu[ok] / 2.0)) / math.log(10.0)
    return out


def significant_peaks(f, P, dof=None, *, min_prominence=0.3, confidence=DEFAULT_CONFIDENCE,
                      background_hz=20.0, distance_bins=2.0, f_range=None):
    """The peaks of the PSD estimate ``(f, P)`` by the rule of the module doc. ``dof``: the
    estimate's equivalent chi-square degrees of freedom (a number or one per bin; None:
    the measured scatter alone). Returns a :class:`PeakSet`."""
    from scipy.ndimage import median_filter
    from scipy.signal import find_peaks, peak_prominences, peak_widths

    f, P = np.asarray(f, dtype=float), np.asarray(P, dtype=float)
    if f.ndim != 1 or f.shape != P.shape or f.size < 5:
        raise ValueError(f"psd: must be a pair (f, P) of equal 1-D arrays with >= 5 points, "
                         f"got shapes {f.shape} and {P.shape}")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(P))) or np.any(P < 0):
        raise ValueError("psd: frequencies and P must be finite, P >= 0")
    df = float(np.median(np.diff(f)))
    if not df > 0:
        raise ValueError("psd: frequencies must increase")
    if not (math.isfinite(confidence) and confidence >= 0):
        raise ValueError(f"confidence: must be a finite z >= 0, got {confidence!r}")
    if not (math.isfinite(min_prominence) and min_prominence >= 0):
        raise ValueError(f"min_prominence: must be a finite number of decades >= 0, "
                         f"got {min_prominence!r}")
    if not (math.isfinite(background_hz) and background_hz >= 2 * df):
        raise ValueError(f"background_hz: must be at least two bins ({2 * df:g} Hz), "
                         f"got {background_hz!r}")
    floor = max(P.max(), 1e-300) * 1e-16
    L = np.log10(np.maximum(P, floor))
    # a PSD from 0 Hz is even in f: mirrored there (the background and the peaks), content
    # rising towards 0 Hz is one peak at 0 Hz, not a top at whichever low bin is highest
    dc = abs(f[0]) <= 0.5 * df
    bg = median_filter(L, size=_odd(round(background_hz / df)),
                       mode="mirror" if dc else "nearest")
    r = L - bg
    measured = 1.4826 * float(np.median(np.abs(np.diff(r)))) / math.sqrt(2.0)
    sigma = np.full(f.size, measured)
    if dof is not None:
        nu = np.broadcast_to(np.asarray(dof, dtype=float), f.shape)
        if np.any(~np.isfinite(nu)) or np.any(nu <= 0):
            raise ValueError("dof: the Welch degrees of freedom must be finite and > 0 "
                             "(WelchPSD.dof, or 2 / StochasticResult.psd_relative_std(ch)**2)")
        sigma = np.maximum(sigma, log_scatter(nu))
    s2 = math.sqrt(2.0) * sigma
    dist = max(1, int(round(distance_bins)))
    wlen = 2 * _odd(round(background_hz / df)) + 1  # bases within a background window
    idx, props = find_peaks(r, prominence=float(min_prominence), distance=dist, wlen=wlen)
    prom = props["prominences"]
    hw = np.zeros(idx.size)
    if idx.size:
        hw = 0.5 * df * peak_widths(r, idx, rel_height=0.5, prominence_data=(
            prom, props["left_bases"], props["right_bases"]))[0]
    if dc and r[0] > r[1] and not np.any(idx < dist):  # a peak at 0 Hz, in the mirrored PSD
        rx = np.concatenate([r[:0:-1], r])
        data = peak_prominences(rx, [f.size - 1], wlen=wlen)
        w0 = 0.5 * df * peak_widths(rx, [f.size - 1], rel_height=0.5, prominence_data=data)[0]
        idx, prom, hw = np.r_[0, idx], np.r_[data[0], prom], np.r_[w0, hw]
    thr = float(min_prominence) + confidence * s2[idx]
    keep = (prom >= thr) & (r[idx] >= confidence * sigma[idx])
    if f_range is not None:
        keep &= (f[idx] >= f_range[0]) & (f[idx] <= f_range[1])
    idx, thr, prom, hw = idx[keep], thr[keep], prom[keep], hw[keep]
    ferr = np.empty(idx.size)
    for n, i in enumerate(idx):  # a few peaks: the loop is over peaks, not bins
        level = r[i] - s2[i]
        lo = i
        while lo > 0 and r[lo - 1] >= level:
            lo -= 1
        hi = i
        while hi < f.size - 1 and r[hi + 1] >= level:
            hi += 1
        shape = hw[n] * math.sqrt(2.0 * s2[i] / prom[n])  # a parabolic top (module doc)
        ferr[n] = max(f[i] - f[lo], f[hi] - f[i], shape, 0.5 * df)
    e = s2[idx]
    z = np.full(idx.size, np.inf)  # a noiseless PSD (an exact spectrum): every peak certain
    np.divide(prom - float(min_prominence), e, out=z, where=e > 0)
    return PeakSet(index=idx, frequency=f[idx], prominence=prom, prominence_error=e,
                   frequency_error=ferr, half_width=hw, threshold=thr, significance=z,
                   background=bg,
                   sigma=sigma)
