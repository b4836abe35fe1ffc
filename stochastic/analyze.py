"""Measured records through the estimators of ``simulate``: ``analyze(t, signals)`` returns
the ``StochasticResult`` a simulation gives (Welch PSD, histogram PDF, moments with standard
errors), so that a measured and a simulated record overlay in every stochastic figure and
compare by ``map_peaks``."""
from __future__ import annotations

import math
import re
import warnings

import numpy as np

from nlbeam._validate import positive
from nlbeam.vocabulary import CHANNELS

from .assemble import feed, make_estimators, store_results
from .simulate import OUTPUTS, StochasticResult, _default_resolution

__all__ = ["analyze", "RESAMPLE_METHODS"]

#: how a non-uniform record is brought onto a uniform grid
RESAMPLE_METHODS = ("linear", "cubic")
#: relative spread of the time steps below which a record counts as uniform
UNIFORM_RTOL = 1e-6
#: a gap longer than this many median steps is bridged by interpolation with a warning
GAP_WARN = 4.0


def _channel_name(name):
    name = str(name)
    if re.fullmatch(rf"({'|'.join(CHANNELS)})(?:\[\d+\])?", name) is None:
        raise ValueError(f"signals: unknown channel name {name!r}; use one of "
                         f"{', '.join(CHANNELS)}, optionally indexed like 'x[1]' or 'delta[0]' "
                         "(the channel names of stochastic.simulate, which carry the units)")
    return name


def _time(t):
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"t: must be a 1-D array of times (s), got shape {t.shape}")
    if t.size < 2:
        raise ValueError(f"t: need at least 2 samples, got {t.size}")
    bad = np.nonzero(~np.isfinite(t))[0]
    if bad.size:
        raise ValueError(f"t: sample {bad[0]} is not finite ({t[bad[0]]!r})")
    d = np.diff(t)
    rep = np.nonzero(d == 0)[0]
    if rep.size:
        raise ValueError(f"t: repeated time {t[rep[0]]!r} s at samples {rep[0]} and "
                         f"{rep[0] + 1}; times must be strictly increasing")
    back = np.nonzero(d < 0)[0]
    if back.size:
        j = back[0]
        raise ValueError(f"t: not monotone: t[{j + 1}] = {t[j + 1]!r} s < t[{j}] = {t[j]!r} s; "
                         "times must be strictly increasing")
    return t


def _signal(name, x, n):
    x = np.asarray(x, dtype=float)
    if x.ndim != 1:
        raise ValueError(f"signals[{name!r}]: must be a 1-D array, got shape {x.shape}")
    if x.size != n:
        raise ValueError(f"signals[{name!r}]: {x.size} samples, t has {n}; lengths must agree")
    bad = np.nonzero(~np.isfinite(x))[0]
    if bad.size:
        raise ValueError(f"signals[{name!r}]: sample {bad[0]} is not finite ({x[bad[0]]!r})")
    if not np.ptp(x) > 0:
        raise ValueError(f"signals[{name!r}]: constant ({x[0]!r}): zero variance, no PSD, PDF "
                         "or moments to estimate")
    return x


def _uniform_grid(t, resample):
    """(grid or None, dt, largest step / dt): the uniform grid at the median spacing when the
    steps of ``t`` differ by more than UNIFORM_RTOL (None when already uniform)."""
    d = np.diff(t)
    dt = float(np.median(d))
    spread = float(np.max(np.abs(d - dt))) / dt
    if spread <= UNIFORM_RTOL:
        return None, (t[-1] - t[0]) / (t.size - 1), 1.0
    if resample not in RESAMPLE_METHODS:
        raise ValueError(f"resample: must be one of {', '.join(RESAMPLE_METHODS)}, "
                         f"got {resample!r}")
    n = int(math.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1
    return t[0] + dt * np.arange(n), dt, float(np.max(d)) / dt


def _resampled(t, x, grid, method):
    if method == "linear":
        return np.interp(grid, t, x)
    from scipy.interpolate import CubicSpline

    return CubicSpline(t, x)(grid)


def analyze(t, signals, *, outputs=OUTPUTS, psd_resolution=None, pdf_bins=200, pdf_edges=None,
            resample="linear", batch_duration=None, min_error_window=None, band=None,
            excitation_kind="base", description=None) -> StochasticResult:
    """Statistics of a measured record, by the estimators ``simulate`` uses.

    t: sample times (s), strictly increasing. signals: {channel name: samples} with names
    from the simulation's channels (``x``, ``v``, ``y``, ``yd``, ``delta``, ``force``,
    optionally indexed like ``x[1]``), in SI units (m, m/s, N), each as long as ``t``.
    A record whose time steps differ by more than 1e-6 of their median is resampled onto
    the uniform grid at the median step from its first time by ``resample``: "linear"
    (np.interp) or "cubic" (not-a-knot spline); a gap above 4 median steps is bridged with
    a RuntimeWarning. The method is recorded in ``excitation_description["resample"]``
    ("none" for a uniform record).
    outputs, psd_resolution (Hz, default max(0.05, 16 / duration)), pdf_bins / pdf_edges
    (one array for every channel, or {channel: edges}; default: ``pdf_bins`` bins over the
    record's range widened by 25 % each side), batch_duration (s): as ``simulate``.
    min_error_window: a known slow time scale (s) of the record: the standard errors'
    windows are at least this long (``simulate`` uses two realization spans of a block
    noise). band: (lo, hi) Hz of the excitation, recorded for ``nlbeam compare``.
    excitation_kind: "base" or "force" (the units of y, yd in the figures).
    description: extra {key: value} recorded in ``excitation_description``.

    Returns a ``StochasticResult`` with method="measured", model_parameters {"model":
    "measured", "excitation_kind": ...}, seed "none", transient 0, no counters of impacts.
    """
    import nlbeam

    if isinstance(outputs, str):
        outputs = (outputs,)
    outputs = tuple(outputs)
    for o in outputs:
        if o not in OUTPUTS:
            raise ValueError(f"outputs: must be a subset of {OUTPUTS}, got {o!r}")
    if excitation_kind not in ("base", "force"):
        raise ValueError(f"excitation_kind: must be 'base' or 'force', got {excitation_kind!r}")
    if not isinstance(signals, dict) or not signals:
        raise ValueError("signals: give a non-empty dict {channel name: samples}")
    t = _time(t)
    names = tuple(_channel_name(k) for k in signals)
    data = {ch: _signal(ch, signals[k], t.size) for ch, k in zip(names, signals)}
    grid, dt, worst = _uniform_grid(t, resample)
    if grid is not None:
        if worst > GAP_WARN:
            warnings.warn(f"t: the largest step is {worst:.3g} times the median {dt:.6g} s; "
                          f"the gap is bridged by {resample} interpolation", RuntimeWarning,
                          stacklevel=2)
        data = {ch: _resampled(t, x, grid, resample) for ch, x in data.items()}
    n = t.size if grid is None else grid.size
    fs = 1.0 / dt
    duration = n * dt
    if psd_resolution is None:
        psd_resolution = _default_resolution(duration)
    psd_resolution = positive("psd_resolution", psd_resolution, unit="Hz")
    if "psd" in outputs and psd_resolution * duration < 1.0:
        raise ValueError(f"psd_resolution: {psd_resolution:g} Hz needs segments of "
                         f"{1 / psd_resolution:.4g} s, longer than the record ({duration:.4g} s); "
                         f"give at least {1 / duration:.4g} Hz or a longer record")
    batch = 64 if batch_duration is None else max(
        int(round(positive("batch_duration", batch_duration, unit="s") * fs)), 1)
    min_window = None
    if min_error_window is not None:
        min_window = int(math.ceil(positive("min_error_window", min_error_window, unit="s") * fs))
    edges = pdf_edges if isinstance(pdf_edges, dict) else {ch: pdf_edges for ch in names}
    for k in edges:
        if k not in names:
            raise ValueError(f"pdf_edges: {k!r} is not one of the signals {names}")
    est = {}
    for ch in names:
        est.update(make_estimators((ch,), outputs, fs, psd_resolution, edges.get(ch), pdf_bins,
                                   batch))
        feed(est[ch], data[ch])
    exc = {"kind": "measured", "resample": "none" if grid is None else resample,
           "n_recorded": int(t.size)}
    if band is not None:
        try:
            lo, hi = (float(v) for v in band)
        except (TypeError, ValueError):
            raise ValueError(f"band: must be (lo, hi) in Hz, got {band!r}") from None
        if not 0 <= lo < hi:
            raise ValueError(f"band: must satisfy 0 <= lo < hi (Hz), got {band!r}")
        exc.update(band_lo=lo, band_hi=hi)
    exc.update(description or {})
    res = StochasticResult(
        channels=names, outputs=outputs, fs=fs, dt=dt, t_start=float(t[0]), transient=0.0,
        duration=duration, method="measured", seed="none",
        model_parameters={"model": "measured", "excitation_kind": excitation_kind},
        excitation_description=exc,
        nlbeam_version=str(getattr(nlbeam, "__version__", "unknown")), n_samples=n)
    store_results(res, est, min_window)
    return res
