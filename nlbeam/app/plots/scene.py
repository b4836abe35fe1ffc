"""The figure kinds of a scene file: ``frc`` (the diagram), ``compare`` (PSD peaks against
the diagram), ``history`` (a kept time window), one file per variant; ``psd``,
``excitation_psd`` and ``pdf``, all variants on one axis. Units: Hz, m (drawn in mm), N.
"""
from __future__ import annotations

import math
import os

import numpy as np

from .. import defaults
from ..compare import welch_dof_of
from ..scenes.schema import (build_noise, default_f_max, excitation_for_peaks,
                             history_channels, history_window)
from .compare import plot_comparison
from .files import files_backend, save_figure
from .frequency_response import plot_frequency_response
from .stochastic import TIME_LABEL, kept_time
from .units import axis_label, channel_unit, excitation_kind, log_limits, psd_label

__all__ = ["scene_figure", "suffixed", "variant_label", "overlay_diagrams", "PER_VARIANT"]


#: the figure kinds drawn once per variant (the others draw every variant on one axis)
PER_VARIANT = ("frc", "history", "compare")


#: a swept parameter's unit as drawn: (unit, factor SI -> drawn); an element parameter
#: ``elements[i].field`` by its field
_SWEEP_UNITS = {"rms": ("mm", 1e3), "amplitude": ("mm", 1e3), "band": ("Hz", 1.0),
                "lowpass": ("Hz", 1.0), "K_hertz": ("N/m^1.5", 1.0), "gap": ("mm", 1e3),
                "band[0]": ("Hz", 1.0), "band[1]": ("Hz", 1.0), "duration": ("s", 1.0),
                "psd_level": ("mm^2/Hz", 1e6), "m": ("kg", 1.0), "k": ("N/m", 1.0),
                "b": ("kg/s", 1.0), "e": ("", 1.0), "mu": ("N s/m^2.5", 1.0),
                "K": ("N/m^1.5", 1.0), "k3": ("N/m^3", 1.0)}


def variant_label(label, kind="base"):
    """A sweep variant's label ('rms=2.5e-05') in the units of the axes ('rms = 0.025 mm';
    under force excitation rms and amplitude are forces, N)."""
    name, sep, value = str(label).partition("=")
    field = name.rsplit(".", 1)[-1] if name.startswith("elements[") else name
    if not sep or field not in _SWEEP_UNITS:
        return label
    unit, factor = _SWEEP_UNITS[field]
    if kind == "force" and name in ("rms", "amplitude", "psd_level"):
        unit, factor = ("N^2/Hz", 1.0) if name == "psd_level" else ("N", 1.0)
    try:
        parts = [f"{float(v) * factor:g}" for v in (value.split("-") if name == "band"
                                                    else [value])]
    except ValueError:
        return label
    return f"{name} = {'-'.join(parts)}" + (f" {unit}" if unit else "")


def overlay_diagrams(ax, diagrams):
    """The diagrams [(legend label, FrequencyResponse)] of a sweep on one axis, one colour
    each: |x|max (mm) against frequency, stable solid, unstable dashed, the bifurcations as
    small circles in the diagram's colour."""
    for i, (label, frc) in enumerate(diagrams):
        c = f"C{i}"
        ax.plot([], [], "-", color=c, lw=1.3, label=label)
        for b in frc.branches:
            x, y = np.asarray(b.values), np.asarray(b.xmax) * 1e3
            st = np.ones(len(x), dtype=bool) if b.stable is None else np.asarray(b.stable)
            cuts = np.nonzero(np.diff(st.astype(int)))[0] + 1
            for seg in np.split(np.arange(len(x)), cuts):
                if seg.size == 0:
                    continue
                seg = np.r_[seg, seg[-1] + 1] if seg[-1] + 1 < len(x) else seg
                ax.plot(x[seg], y[seg], "-" if st[seg[0]] else "--", color=c,
                        lw=1.2 if st[seg[0]] else 0.8)
        bf = [b for b in frc.bifurcations if b.kind != "grazing"]
        if bf:
            ax.plot([b.value for b in bf], [b.xmax * 1e3 for b in bf], "o", mfc="none",
                    color=c, ms=4, mew=0.8)
    ax.plot([], [], "k-", lw=1.2, label="stable")
    ax.plot([], [], "k--", lw=0.8, label="unstable")
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("|x|max [mm]")
    ax.legend(fontsize=8)


def suffixed(path, i, n):
    """The file of variant ``i`` of ``n`` of a per-variant figure: ``path`` itself for one,
    else ``stem_<i+1>.ext``."""
    if n == 1:
        return path
    stem, ext = os.path.splitext(path)
    return f"{stem}_{i + 1}{ext}"


def scene_figure(scene_title, d, variants, out_dir, measured=None):
    """Write the figure of one [[figure]] table ``d`` to ``out_dir``; ``variants``: the
    distinct [(label, model, periodic, stochastic, diagram, stochastic result, job paths)]
    it shows. Returns the files written (``name_1.png``, ``name_2.png``, ... for a per-variant
    kind with more than one variant; the diagrams of a sweep, ``frc``, are overlaid in one
    figure, one colour per value, the legend in units). ``measured``: (label,
    StochasticResult) of a measured record drawn over the psd, pdf, excitation_psd and
    compare figures (black) where it has the channel."""
    files_backend()  # files only; an interactive session keeps its backend
    import matplotlib.pyplot as plt

    kind = d["kind"]
    ch = d.get("channel", defaults.CHANNEL)
    target = os.path.join(out_dir, d["file"])
    multi = len(variants) > 1
    title = d.get("title", scene_title)
    if kind == "frc" and multi:  # a sweep's diagrams: one figure, one colour per value
        fig, ax = plt.subplots(figsize=(9, 5))
        overlay_diagrams(ax, [(variant_label(label, excitation_kind(per.model_parameters)),
                               per) for label, m, p, s, per, sto, _ in variants])
        ax.set_title(title)
        fig.tight_layout()
        return [save_figure(fig, target)]
    if kind in PER_VARIANT:
        written = []
        for i, (label, m, p, s, per, sto, _) in enumerate(variants):
            path = suffixed(target, i, len(variants))
            res = sto if sto is not None else per
            kind_e = excitation_kind(getattr(res, "model_parameters", {}))
            t = title + (f" ({variant_label(label, kind_e)})" if label else "")
            if kind == "frc":
                fig, ax = plt.subplots(figsize=(9, 5))
                plot_frequency_response(per, ax)
                ax.set_title(t)
                fig.tight_layout()
            elif kind == "compare":
                f_max = d.get("f_max", default_f_max(p, s))
                fig = plot_comparison(sto.psd(ch), per, excitation=excitation_for_peaks(s),
                                      label=ch, f_max=f_max, f_range=(0.0, f_max),
                                      stability=d.get("stability", True),
                                      dof=welch_dof_of(sto, ch),
                                      min_prominence=d.get("min_prominence",
                                                           defaults.MIN_PROMINENCE))
                fig.axes[0].set_title(t)
                if measured is not None and ch in measured[1].channels:
                    fm, Pm = measured[1].psd(ch)
                    fig.axes[0].semilogy(fm[Pm > 0], Pm[Pm > 0], color="C3", lw=0.7,
                                         alpha=0.8, label=f"PSD of {ch}, {measured[0]}")
                    fig.axes[0].legend(fontsize=8, loc="upper right")
            else:
                chans = history_channels(d)
                fig, axs = plt.subplots(len(chans), 1, sharex=True,
                                        figsize=(8, 2.2 * len(chans) + 1), squeeze=False)
                h = sto.history
                w = history_window(d, s["duration"])
                tt = kept_time(sto)  # s after the transient, as the window
                sel = (tt >= w[0] - 1e-9) & (tt <= w[1] + 1e-9)
                ekind = excitation_kind(sto.model_parameters)
                for ax, c in zip(axs[:, 0], chans):
                    _, unit, sc = channel_unit(c, ekind)
                    ax.plot(tt[sel], h[c][sel] * sc, lw=0.8)
                    ax.set_ylabel(axis_label(c, unit))
                axs[-1, 0].set_xlabel(TIME_LABEL)
                axs[-1, 0].set_xlim(w[0], w[1])
                axs[0, 0].set_title(t)
                fig.tight_layout()
            written.append(save_figure(fig, path))
        return written
    fig, ax = plt.subplots(figsize=(8, 5))
    ekind = excitation_kind(variants[0][5].model_parameters)
    runs = [(variant_label(label, ekind) if label else label, s, sto)
            for label, m, p, s, per, sto, _ in variants]
    s0 = variants[0][3]
    if measured is not None:  # drawn last, in black, where it has the channel
        want = "y" if kind == "excitation_psd" else ch
        if want in measured[1].channels:
            runs.append((measured[0], None, measured[1]))
    drawn = []
    for k, (label, s, sto) in enumerate(runs):
        colour = "k" if s is None else f"C{k}"
        ls = "--" if s is None else "-"  # a measured record over a simulation: both seen
        lab = label if (s is None or multi) else ("simulated" if len(runs) > 1 else None)
        if kind in ("psd", "excitation_psd"):
            c = ch if kind == "psd" else "y"
            f, P = sto.psd(c)
            fmax = d.get("f_max", s0["band"][1] if kind == "psd" else 1.25 * s0["band"][1])
            ax.semilogy(f[P > 0], P[P > 0], lw=0.8, color=colour, ls=ls,
                        label=lab if kind == "psd" else (
                            label if s is None else "simulated y" + (f" ({label})" if label
                                                                     else "")))
            drawn.append(P[(f <= fmax) & (P > 0)])
            if kind == "excitation_psd" and s is not None:
                exc = build_noise(s)
                if hasattr(exc, "psd"):  # a noise: its target (a measured record has none)
                    ax.semilogy(f[f > 0], exc.psd(f[f > 0]), "--", color=colour, lw=1.0,
                                label="target G(f)" + (f" ({label})" if label else ""))
            ax.set_xlabel(axis_label("frequency", "Hz"))
            ax.set_ylabel(psd_label(c, ekind))
            ax.set_xlim(0, fmax)
        elif kind == "pdf":
            x, dens = sto.pdf(ch)
            mo = sto.moments(ch)
            _, unit, sc = channel_unit(ch, ekind)
            ax.semilogy(x * sc, dens / sc, lw=1.0, color=colour, ls=ls,
                        label=f"{ch}{' ' + label if label else ''}: skew {mo['skewness']:.2f}, "
                              f"kurt {mo['kurtosis']:.2f}")
            if s is not None:  # each simulated curve's Gaussian, in its colour, dotted
                g = (np.exp(-0.5 * ((x - mo["mean"]) / mo["std"]) ** 2)
                     / (mo["std"] * math.sqrt(2 * math.pi)))
                ax.semilogy(x * sc, g / sc, ":", color=colour, lw=1.0,
                            label="dotted: Gaussian of the same mean and std" if k == 0
                            else None)
            ax.set_xlabel(axis_label(ch, unit))
            ax.set_ylabel(axis_label("probability density", f"1/{unit}"))
            drawn.append(dens / sc)
    lim = log_limits(np.concatenate(drawn), decades=7.0 if kind != "pdf" else 6.0) \
        if drawn else None
    if lim:  # the band-edge roll-off or the histogram's tails would stretch the axis
        ax.set_ylim(*lim)
    ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    return [save_figure(fig, target)]
