"""Figures of a stochastic simulation (matplotlib is imported inside the functions, so
importing this module, or its alias ``stochastic.plot``, does not load it).

Every function takes a result (``StochasticResult``) or the excitation, draws on ``ax`` if
given (else on a new figure), optionally writes ``path`` (PNG, PDF, ... by extension) and
returns the matplotlib ``Figure``. Units: frequency Hz, displacement m (plotted in mm),
PSD m^2/Hz.
"""
from __future__ import annotations

import os

import numpy as np

__all__ = ["excitation_psd", "response_psd", "pdf", "time_history", "channel_psds"]


def _figure(ax, figsize=(6.4, 4.0)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax
    return ax.figure, ax


def _finish(fig, path, dpi=130):
    if path is not None:
        fig.savefig(os.fspath(path), dpi=dpi)
    return fig


def excitation_psd(result, excitation=None, *, ch="y", ax=None, path=None, log=False):
    """Realized PSD of the excitation channel ``ch`` of ``result`` (recorded with
    channels=(..., "y")) with its 95 % band, against the target ``excitation.psd(f)`` (a
    ``BandLimitedNoise`` / ``SpectralNoise``; omitted when None)."""
    f, P = result.psd(ch)
    lo, hi = result.psd_interval(ch)
    fig, ax = _figure(ax)
    ax.fill_between(f, lo, hi, color="C0", alpha=0.25, lw=0, label="95 % interval")
    ax.plot(f, P, color="C0", lw=0.8, label="realized (Welch)")
    if excitation is not None and hasattr(excitation, "psd"):
        fg = np.linspace(0.0, f[-1], 4001)
        ax.plot(fg, excitation.psd(fg), color="k", lw=1.2, ls="--", label="target G(f)")
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"PSD of {ch} (m$^2$/Hz)")
    ax.set_xlim(0.0, f[-1])
    ax.legend(frameon=False)
    return _finish(fig, path)


def response_psd(result, ch="delta", *, ax=None, path=None, f_max=None, reference=None,
                 reference_label="linear model", mark_peaks=0.5):
    """PSD of ``ch`` on a log scale with its 95 % band. reference: another result (e.g. the
    linear model under the same noise) drawn for comparison. mark_peaks: prominence in
    decades for ``scipy.signal.find_peaks`` on log10 PSD (None: no marks)."""
    f, P = result.psd(ch)
    lo, hi = result.psd_interval(ch)
    fig, ax = _figure(ax)
    pos = P > 0
    ax.fill_between(f[pos], lo[pos], hi[pos], color="C0", alpha=0.25, lw=0)
    ax.semilogy(f[pos], P[pos], color="C0", lw=0.8, label=f"{ch}")
    if reference is not None:
        fr, Pr = reference.psd(ch)
        ax.semilogy(fr[Pr > 0], Pr[Pr > 0], color="0.4", lw=0.8, label=reference_label)
    if mark_peaks is not None and np.count_nonzero(pos) > 3:
        import scipy.signal

        idx, _ = scipy.signal.find_peaks(np.log10(P[pos]), prominence=mark_peaks)
        fp, Pp = f[pos][idx], P[pos][idx]
        ax.plot(fp, Pp, "v", color="C3", ms=5, label="peaks")
        for a, b in zip(fp, Pp):
            ax.annotate(f"{a:.0f}", (a, b), textcoords="offset points", xytext=(0, 6),
                        ha="center", fontsize=7, color="C3")
    ax.set_xlim(0.0, f[-1] if f_max is None else f_max)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"PSD of {ch} (m$^2$/Hz)")
    ax.legend(frameon=False)
    return _finish(fig, path)


def pdf(result, ch="delta", *, ax=None, path=None, log=False):
    """Histogram PDF of ``ch`` against the Gaussian of the same mean and variance, with the
    skewness and kurtosis in the title (needs outputs "pdf" and "moments")."""
    c, d = result.pdf(ch)
    mo = result.moments(ch)
    fig, ax = _figure(ax)
    mm = 1e3 if ch in ("x", "y", "delta") else 1.0
    unit = "mm" if mm != 1.0 else "units"
    ax.step(c * mm, d / mm, where="mid", color="C0", lw=1.0, label="simulated")
    g = np.exp(-0.5 * ((c - mo["mean"]) / mo["std"]) ** 2) / (mo["std"] * np.sqrt(2 * np.pi))
    ax.plot(c * mm, g / mm, color="k", ls="--", lw=1.0, label="Gaussian, same mean and std")
    if log:
        ax.set_yscale("log")
        ax.set_ylim(max(d[d > 0].min(), 1e-6 * d.max()) / mm, None)
    ax.set_xlabel(f"{ch} ({unit})")
    ax.set_ylabel(f"probability density (1/{unit})")
    ax.set_title(f"skewness {mo['skewness']:.2f} +- {mo['se_skewness']:.2f}, "
                 f"kurtosis {mo['kurtosis']:.2f} +- {mo['se_kurtosis']:.2f}", fontsize=9)
    ax.legend(frameon=False)
    return _finish(fig, path)


def time_history(result, channels=("y", "x"), *, ax=None, path=None):
    """The kept time window (simulate(..., keep_history=(t0, t1))) of the given channels,
    e.g. the base motion y and the beam x as in the paper's Fig. 8 (in mm)."""
    h = result.history
    if h is None or h["t"].size == 0:
        raise ValueError("result: has no time history; simulate with keep_history=(t0, t1)")
    missing = [ch for ch in channels if ch not in h]
    if missing:
        raise ValueError(f"channels: {missing} were not recorded; recorded {result.channels}")
    fig, ax = _figure(ax, figsize=(7.5, 3.5))
    for k, ch in enumerate(channels):
        scale = 1e3 if ch in ("x", "y", "delta") else 1.0
        ax.plot(h["t"], h[ch] * scale, lw=0.8, color=f"C{k}", label=ch)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("displacement (mm)")
    ax.set_xlim(h["t"][0], h["t"][-1])
    ax.legend(frameon=False, ncols=len(channels))
    return _finish(fig, path)


def channel_psds(result, *, ax=None, path=None):
    """The PSD of every recorded channel of ``result`` on one log axis (``nlbeam simulate
    --plot``; each channel in its own units^2/Hz)."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 5))
    else:
        fig = ax.figure
    for ch in result.channels:
        f, P = result.psd(ch)
        ax.semilogy(f[P > 0], P[P > 0], lw=0.8, label=ch)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("PSD [units$^2$/Hz]")
    ax.legend()
    return _finish(fig, path)
