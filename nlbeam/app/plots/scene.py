"""The figure kinds of a scene file: ``frc`` (the diagram), ``compare`` (PSD peaks against
the diagram), ``history`` (a kept time window), one file per variant; ``psd``,
``excitation_psd`` and ``pdf``, all variants on one axis. Units: Hz, m (drawn in mm), N.
"""
from __future__ import annotations

import math
import os

import numpy as np

from .. import defaults
from ..scenes.schema import build_noise, default_f_max, history_channels, history_window
from .compare import plot_comparison
from .files import files_backend, save_figure
from .frequency_response import plot_frequency_response
from .stochastic import TIME_LABEL, kept_time
from .units import axis_label, channel_unit, excitation_kind

__all__ = ["scene_figure", "suffixed", "PER_VARIANT"]


#: the figure kinds drawn once per variant (the others draw every variant on one axis)
PER_VARIANT = ("frc", "history", "compare")


def suffixed(path, i, n):
    """The file of variant ``i`` of ``n`` of a per-variant figure: ``path`` itself for one,
    else ``stem_<i+1>.ext``."""
    if n == 1:
        return path
    stem, ext = os.path.splitext(path)
    return f"{stem}_{i + 1}{ext}"


def scene_figure(scene_title, d, variants, out_dir):
    """Write the figure of one [[figure]] table ``d`` to ``out_dir``; ``variants``: the
    distinct [(label, model, periodic, stochastic, diagram, stochastic result, job paths)]
    it shows. Returns the files written (``name_1.png``, ``name_2.png``, ... for a per-variant
    kind with more than one variant)."""
    files_backend()  # files only; an interactive session keeps its backend
    import matplotlib.pyplot as plt

    kind = d["kind"]
    ch = d.get("channel", defaults.CHANNEL)
    target = os.path.join(out_dir, d["file"])
    multi = len(variants) > 1
    title = d.get("title", scene_title)
    if kind in PER_VARIANT:
        written = []
        for i, (label, m, p, s, per, sto, _) in enumerate(variants):
            path = suffixed(target, i, len(variants))
            t = title + (f" ({label})" if label else "")
            if kind == "frc":
                fig, ax = plt.subplots(figsize=(9, 5))
                plot_frequency_response(per, ax)
                ax.set_title(t)
                fig.tight_layout()
            elif kind == "compare":
                f_max = d.get("f_max", default_f_max(p, s))
                fig = plot_comparison(sto.psd(ch), per, excitation=build_noise(s), label=ch,
                                      f_max=f_max, f_range=(0.0, f_max),
                                      stability=d.get("stability", True))
                fig.axes[0].set_title(t)
            else:
                chans = history_channels(d)
                fig, axs = plt.subplots(len(chans), 1, sharex=True,
                                        figsize=(8, 2.2 * len(chans) + 1), squeeze=False)
                h = sto.history
                w = history_window(d, s["duration"])
                tt = kept_time(sto)  # s after the transient, as the window
                sel = (tt >= w[0] - 1e-9) & (tt <= w[1] + 1e-9)
                kind = excitation_kind(sto.model_parameters)
                for ax, c in zip(axs[:, 0], chans):
                    _, unit, sc = channel_unit(c, kind)
                    ax.plot(tt[sel], h[c][sel] * sc, lw=0.8)
                    ax.set_ylabel(axis_label(c, unit))
                axs[-1, 0].set_xlabel(TIME_LABEL)
                axs[-1, 0].set_xlim(w[0], w[1])
                axs[0, 0].set_title(t)
                fig.tight_layout()
            written.append(save_figure(fig, path))
        return written
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, m, p, s, per, sto, _ in variants:
        lab = label or None
        if kind == "psd":
            f, P = sto.psd(ch)
            fmax = d.get("f_max", s["band"][1])
            ax.semilogy(f[P > 0], P[P > 0], lw=0.8, label=lab)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel(f"PSD of {ch} [{_unit(ch)}$^2$/Hz]")
            ax.set_xlim(0, fmax)
            shown = P[(f <= fmax) & (P > 0)]
            if shown.size:  # the band-edge roll-off would stretch the axis over decades
                lo, hi = ax.get_ylim() if ax.lines[:-1] else (np.inf, 0.0)
                ax.set_ylim(min(lo, max(shown.min(), shown.max() * 1e-7) / 2),
                            max(hi, shown.max() * 3))
        elif kind == "excitation_psd":
            f, P = sto.psd("y")
            G = build_noise(s).psd(f)
            ax.plot(f, P * 1e6, lw=0.8, label=("simulated y" + (f" ({label})" if label else "")))
            ax.plot(f, G * 1e6, "k--", lw=1.0, label="target G(f)" if not multi else None)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel("PSD of y [mm$^2$/Hz]")
            ax.set_xlim(0, d.get("f_max", 1.25 * s["band"][1]))
        elif kind == "pdf":
            x, dens = sto.pdf(ch)
            mo = sto.moments(ch)
            sc = 1e3 if ch in ("x", "y", "delta") else 1.0
            ax.semilogy(x * sc, dens / sc, lw=1.0,
                        label=f"{ch}{' ' + label if label else ''}: skew {mo['skewness']:.2f}, "
                              f"kurt {mo['kurtosis']:.2f}")
            g = (np.exp(-0.5 * ((x - mo["mean"]) / mo["std"]) ** 2)
                 / (mo["std"] * math.sqrt(2 * math.pi)))
            ax.semilogy(x * sc, g / sc, "k--", lw=0.8, label="Gaussian, same mean and std"
                        if label == variants[0][0] else None)
            ax.set_xlabel(f"{ch} [{'mm' if sc == 1e3 else _unit(ch)}]")
            ax.set_ylabel("probability density")
            pos = dens[dens > 0]
            if pos.size:
                ax.set_ylim(pos.min() / sc / 2, pos.max() / sc * 3)
    ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return [save_figure(fig, target)]


def _unit(ch):
    return {"x": "m", "y": "m", "delta": "m", "v": "m/s", "yd": "m/s", "force": "N"}[ch]
