"""Plot a StabilityChart (continuation.stability_chart) or a BifurcationCurve: the curves in the
(frequency, amplitude) plane, codimension-2 points marked, and the regions where the attractor
reached from rest has order 1, 2, 3 shaded and labelled (matplotlib imported when called)."""
from __future__ import annotations

import numpy as np

from .units import excitation_kind, legend_outside

__all__ = ["plot_stability_chart"]

_STYLE = {"fold": ("C0", "-", "fold"), "period-doubling": ("C3", "-", "period doubling"),
          "neimark-sacker": ("C2", "-", "Neimark-Sacker"), "grazing": ("0.45", ":", "grazing")}
_ORDER_SHADE = {1: "#dde8f5", 2: "#f7dcdc", 3: "#dcf0dc"}
_CODIM2 = {"cusp": "o", "fold-flip": "D", "fold-grazing": "v", "flip-grazing": "s",
           "neimark-sacker-grazing": "^"}


def plot_stability_chart(chart, ax=None, *, path=None, grazing=True, legend=True):
    """Curves in the (frequency [Hz], amplitude) plane on log axes: folds blue, period
    doublings red (their order as line width: thicker for higher orders), Neimark-Sacker green,
    grazing curves grey dotted (``grazing=False``: left out); codimension-2 points marked
    (cusp o, fold-flip D, a curve meeting a grazing curve s/v/^). A chart's label grid is
    drawn as shaded cells: the order of the attractor reached from rest (1 blue, 2 red, 3
    green, each labelled 'n = k'; others blank). ``path``: also write the figure. Returns the
    Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    curves = chart.curves if hasattr(chart, "curves") else [chart]
    opened = ax is None
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 6))
    force = excitation_kind(curves[0].model_parameters if curves else
                            getattr(chart, "model_parameters", {})) == "force"
    scale, unit = (1.0, "N") if force else (1e3, "mm")
    lf = getattr(chart, "label_frequency", np.zeros(0))
    if len(lf):
        fs, As = np.unique(lf), np.unique(chart.label_value)
        fe = _edges(fs)
        ae = _edges(As)
        order = np.zeros((len(As), len(fs)), dtype=int)
        for f, A, n in zip(lf, chart.label_value, chart.label_order):
            order[np.searchsorted(As, A), np.searchsorted(fs, f)] = n
        for i in range(len(As)):
            for j in range(len(fs)):
                n = order[i, j]
                if n in _ORDER_SHADE:
                    ax.fill_between([fe[j], fe[j + 1]], ae[i] * scale, ae[i + 1] * scale,
                                    color=_ORDER_SHADE[n], lw=0, zorder=0)
                    ax.text(fs[j], As[i] * scale, f"n = {n}", ha="center", va="center",
                            fontsize=7, color="0.3", zorder=1)
    seen = set()
    for c in curves:
        if c.kind == "grazing" and not grazing:
            continue
        col, ls, name = _STYLE[c.kind]
        lw = 1.0 + 0.6 * (c.order - 1)
        ax.plot(c.frequency, c.values * (scale if c.parameter == "amplitude" else 1.0),
                color=col, ls=ls, lw=lw, zorder=3)
        seen.add((c.kind, name, col, ls))
        for s in c.special:
            ax.plot(s.frequency, s.value * (scale if c.parameter == "amplitude" else 1.0),
                    _CODIM2.get(s.kind, "*"), color="k", ms=6, mfc="none", zorder=4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("excitation frequency [Hz]")
    par = curves[0].parameter if curves else "amplitude"
    ax.set_ylabel(f"excitation amplitude [{unit}]" if par == "amplitude" else par)
    f_range = getattr(chart, "f_range", None)
    if f_range:
        ax.set_xlim(*f_range)
    p_range = getattr(chart, "p_range", None)
    if p_range:
        ax.set_ylim(p_range[0] * scale, p_range[1] * scale)
    ax.set_title("stability chart: bifurcation curves; shaded: order n of the attractor "
                 "from rest", fontsize=10)
    if legend:
        handles = [Line2D([], [], color=col, ls=ls, label=name)
                   for _, name, col, ls in sorted(seen)]
        kinds = sorted({s.kind for c in curves for s in c.special})
        handles += [Line2D([], [], ls="", marker=_CODIM2.get(k, "*"), color="k", mfc="none",
                           label=k) for k in kinds]
        if handles:
            legend_outside(ax, handles=handles)
    from .files import finish_figure

    return finish_figure(ax.figure, path, opened)


def _edges(v):
    """Cell edges (geometric midpoints) around sorted positive values."""
    v = np.asarray(v, dtype=float)
    if len(v) == 1:
        return np.array([v[0] / 1.2, v[0] * 1.2])
    mid = np.sqrt(v[1:] * v[:-1])
    return np.r_[v[0] ** 2 / mid[0], mid, v[-1] ** 2 / mid[-1]]
