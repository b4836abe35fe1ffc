"""Figures of a stochastic simulation (matplotlib is imported inside the functions, so
importing this module, or its alias ``stochastic.plot``, does not load it).

Every function takes a result (``StochasticResult``), draws on ``ax`` if given (else on a new
figure), optionally writes ``path`` (PNG, PDF, ... by extension; a figure it opened is then
closed) and returns the matplotlib ``Figure``. Units from ``nlbeam.app.plots.units``:
displacements drawn in mm, velocities in m/s, forces in N; PSDs in SI units (m^2/Hz, N^2/Hz);
under force excitation y is a force (N). Frequencies in Hz; the frequency axis ends at
``f_max`` (default: twice the noise band's upper edge, at most the Nyquist frequency).
"""
from __future__ import annotations

import os

import numpy as np

from .units import axis_label, channel_unit, excitation_kind, log_limits, psd_label

__all__ = ["excitation_psd", "response_psd", "pdf", "time_history", "channel_psds", "kept_time",
           "TIME_LABEL"]


def _figure(ax, figsize=(6.4, 4.0), path=None, flags=()):
    """(figure, axes, opened) after the shared options are checked (path, flags, ax)."""
    import matplotlib.pyplot as plt

    from .files import check_plot_options

    check_plot_options(path, flags, ax)

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax, True
    return ax.figure, ax, False


def _finish(fig, path, opened, dpi=130):
    from .files import finish_figure

    return finish_figure(fig, None if path is None else os.fspath(path), opened,
                         tight_layout=False, dpi=dpi)


def _kind(result):
    return excitation_kind(getattr(result, "model_parameters", {}))


def default_f_max(result):
    """Upper end (Hz) of a frequency axis: twice the noise band's upper edge, at most fs/2."""
    nyq = 0.5 * float(result.fs)
    band_hi = (getattr(result, "excitation_description", None) or {}).get("band_hi")
    try:
        return min(nyq, 2.0 * float(band_hi))
    except (TypeError, ValueError):
        return nyq


def _f_max(result, f_max):
    if f_max is None:
        return default_f_max(result)
    from nlbeam._validate import positive

    return positive("f_max", f_max, unit="Hz")


def excitation_psd(result, excitation=None, *, ch="y", ax=None, path=None, log=False,
                   f_max=None):
    """Realized PSD of the excitation channel ``ch`` of ``result`` (recorded with
    channels=(..., "y")) with its 95 % band, against the target ``excitation.psd(f)`` (a
    ``BandLimitedNoise`` / ``SpectralNoise``; omitted when None)."""
    f, P = result.psd(ch)
    lo, hi = result.psd_interval(ch)
    fmax = _f_max(result, f_max)
    fig, ax, opened = _figure(ax, path=path, flags=(("log", log),))
    ax.fill_between(f, lo, hi, color="C0", alpha=0.25, lw=0, label="95 % interval")
    ax.plot(f, P, color="C0", lw=0.8, label="realized (Welch)")
    if excitation is not None and hasattr(excitation, "psd"):
        fg = np.linspace(0.0, fmax, 4001)
        ax.plot(fg, excitation.psd(fg), color="k", lw=1.2, ls="--", label="target G(f)")
    shown = (f <= fmax)
    if log:
        ax.set_yscale("log")
        lim = log_limits(P[shown])
        if lim:
            ax.set_ylim(*lim)
    else:
        ax.set_ylim(0.0, 1.15 * float(np.max(hi[shown])))
    ax.set_xlabel(axis_label("frequency", "Hz"))
    ax.set_ylabel(psd_label(ch, _kind(result)))
    ax.set_xlim(0.0, fmax)
    ax.legend(frameon=False)
    return _finish(fig, path, opened)


def response_psd(result, ch="delta", *, ax=None, path=None, f_max=None, reference=None,
                 reference_label="linear model", mark_peaks=0.5):
    """PSD of ``ch`` on a log scale with its 95 % band. reference: another result (e.g. the
    linear model under the same noise) drawn for comparison. mark_peaks: prominence in
    decades for ``scipy.signal.find_peaks`` on log10 PSD (None: no marks)."""
    f, P = result.psd(ch)
    lo, hi = result.psd_interval(ch)
    fmax = _f_max(result, f_max)
    fig, ax, opened = _figure(ax, path=path, flags=())
    pos = (P > 0) & (f <= fmax)
    ax.fill_between(f[pos], lo[pos], hi[pos], color="C0", alpha=0.25, lw=0)
    ax.semilogy(f[pos], P[pos], color="C0", lw=0.8, label=f"{ch}")
    drawn = [P[pos]]
    if reference is not None:
        fr, Pr = reference.psd(ch)
        sel = (Pr > 0) & (fr <= fmax)
        ax.semilogy(fr[sel], Pr[sel], color="0.4", lw=0.8, label=reference_label)
        drawn.append(Pr[sel])
    if mark_peaks is not None and np.count_nonzero(pos) > 3:
        import scipy.signal

        idx, _ = scipy.signal.find_peaks(np.log10(P[pos]), prominence=mark_peaks)
        fp, Pp = f[pos][idx], P[pos][idx]
        ax.plot(fp, Pp, "v", color="C3", ms=5, label="peaks")
        for a, b in zip(fp, Pp):
            ax.annotate(f"{a:.0f}", (a, b), textcoords="offset points", xytext=(0, 6),
                        ha="center", fontsize=7, color="C3")
    lim = log_limits(np.concatenate(drawn))
    if lim:
        ax.set_ylim(*lim)
    ax.set_xlim(0.0, fmax)
    ax.set_xlabel(axis_label("frequency", "Hz"))
    ax.set_ylabel(psd_label(ch, _kind(result)))
    ax.legend(frameon=False)
    return _finish(fig, path, opened)


def pdf(result, ch="delta", *, ax=None, path=None, log=False):
    """Histogram PDF of ``ch`` against the Gaussian of the same mean and variance, with the
    skewness and kurtosis in the title (needs outputs "pdf" and "moments")."""
    c, d = result.pdf(ch)
    mo = result.moments(ch)
    _, unit, sc = channel_unit(ch, _kind(result))
    fig, ax, opened = _figure(ax, path=path, flags=(("log", log),))
    label = "measured" if result.method == "measured" else "simulated"
    ax.step(c * sc, d / sc, where="mid", color="C0", lw=1.0, label=label)
    g = np.exp(-0.5 * ((c - mo["mean"]) / mo["std"]) ** 2) / (mo["std"] * np.sqrt(2 * np.pi))
    ax.plot(c * sc, g / sc, color="k", ls="--", lw=1.0, label="Gaussian, same mean and std")
    if log:
        ax.set_yscale("log")
        lim = log_limits(d / sc, decades=6.0)
        if lim:
            ax.set_ylim(*lim)
    else:
        ax.set_ylim(0.0, 1.1 * max(float(np.max(d)), float(np.max(g))) / sc)
    ax.set_xlabel(axis_label(ch, unit))
    ax.set_ylabel(axis_label("probability density", f"1/{unit}"))
    ax.set_title(f"skewness {mo['skewness']:.2f} +- {mo['se_skewness']:.2f}, "
                 f"kurtosis {mo['kurtosis']:.2f} +- {mo['se_kurtosis']:.2f}", fontsize=9)
    ax.legend(frameon=False)
    return _finish(fig, path, opened)


#: the time axis of every history figure: the window of keep_history, after the transient
TIME_LABEL = axis_label("t after the transient", "s")


def kept_time(result):
    """The history's times (s) counted from the end of the transient, as keep_history."""
    return np.asarray(result.history["t"], float) - (float(result.t_start)
                                                     + float(result.transient))


def time_history(result, channels=("y", "x"), *, ax=None, path=None):
    """The kept time window (simulate(..., keep_history=(t0, t1)), drawn against the time
    after the transient, as the window is given) of the given channels,
    e.g. the base motion y and the beam x as in the paper's Fig. 8. Channels of one unit share
    the axis; a second unit gets its own axis on the right."""
    h = result.history
    if h is None or h["t"].size == 0:
        raise ValueError("result: has no time history; simulate with keep_history=(t0, t1)")
    missing = [ch for ch in channels if ch not in h]
    if missing:
        raise ValueError(f"channels: {missing} were not recorded; recorded {result.channels}")
    kind = _kind(result)
    units = []
    for ch in channels:
        u = channel_unit(ch, kind)[1]
        if u not in units:
            units.append(u)
    if len(units) > 2:
        raise ValueError(f"channels: {channels} mix {len(units)} units ({', '.join(units)}); "
                         "draw at most two units on one figure")
    fig, ax, opened = _figure(ax, figsize=(7.5, 3.5), path=path)
    axes = {units[0]: ax}
    if len(units) == 2:
        axes[units[1]] = ax.twinx()
    handles = []
    t = kept_time(result)
    for k, ch in enumerate(channels):
        _, unit, sc = channel_unit(ch, kind)
        handles += axes[unit].plot(t, h[ch] * sc, lw=0.8, color=f"C{k}",
                                   label=f"{ch} [{unit}]")
    ax.set_xlabel(TIME_LABEL)
    for unit, a in axes.items():
        names = ", ".join(ch for ch in channels if channel_unit(ch, kind)[1] == unit)
        a.set_ylabel(axis_label(names, unit))
    ax.set_xlim(t[0], t[-1])
    ax.legend(handles=handles, frameon=False, ncols=len(channels))
    return _finish(fig, path, opened)


def channel_psds(result, *, ax=None, path=None, f_max=None):
    """The PSD of every recorded channel of ``result``, one panel each in its own unit
    (``nlbeam simulate --plot``). With ``ax`` given, all on that axis (then of one unit)."""
    import matplotlib.pyplot as plt

    from .files import check_plot_options

    check_plot_options(path, (), ax)
    fmax = _f_max(result, f_max)
    kind = _kind(result)
    chans = list(result.channels)
    opened = ax is None
    if ax is None:
        fig, axs = plt.subplots(len(chans), 1, figsize=(7.5, 1.2 + 2.2 * len(chans)),
                                sharex=True, layout="constrained", squeeze=False)
        axs = list(axs[:, 0])
    else:
        fig, axs = ax.figure, [ax] * len(chans)
    drawn = []
    for k, (a, ch) in enumerate(zip(axs, chans)):
        f, P = result.psd(ch)
        sel = (P > 0) & (f <= fmax)
        a.semilogy(f[sel], P[sel], lw=0.8, color=f"C{k}", label=ch)
        drawn.append(P[sel])
        if opened and log_limits(P[sel]):
            a.set_ylim(*log_limits(P[sel]))
        a.set_ylabel(psd_label(ch, kind))
        a.set_xlim(0.0, fmax)
        a.legend(frameon=False, loc="upper right")
    if not opened and log_limits(np.concatenate(drawn)):
        ax.set_ylim(*log_limits(np.concatenate(drawn)))
    axs[-1].set_xlabel(axis_label("frequency", "Hz"))
    return _finish(fig, path, opened)
