"""Plot a FrequencyResponse in the style of the paper's Figure 4 (matplotlib is imported when
called; ``continuation.plot`` re-exports this module)."""
from __future__ import annotations

import numpy as np

from .units import excitation_kind, legend_outside

_MARK = {"fold": ("o", "fold", 6), "period-doubling": ("s", "period doubling", 6),
         "neimark-sacker": ("^", "Neimark-Sacker", 6), "grazing": ("x", "grazing", 4)}
_COLOURS = {1: "C0", 2: "C3", 3: "C2", 4: "C1", 6: "C4"}

__all__ = ["plot_frequency_response"]

#: units of the continuation parameters on the x axis (amplitude: by excitation kind)
_PARAMETER_UNITS = {"frequency": "Hz", "e": "-", "K_hertz": "N/m$^{1.5}$", "gap": "m",
                    "m": "kg", "k": "N/m", "b": "kg/s", "mu": "N s/m$^{2.5}$",
                    "K": "N/m$^{1.5}$", "k3": "N/m$^3$"}


def _response_label(params, unit):
    n = params.get("n_dof", params.get("n_modes", 1))
    if params.get("model") == "ModalBeam":
        return f"|x|max at the stop [{unit}]"
    if isinstance(n, (int, np.integer)) and n > 1:
        return f"|x|max of the output DOF [{unit}]"
    return f"|x|max [{unit}]"


def plot_frequency_response(frc, ax=None, *, scale=1e3, unit="mm", grazing=True, legend=True,
                            path=None):
    """|x|max against frequency: stable solid, unstable dashed (all solid for a diagram computed
    with stability=False), one colour per order, bifurcations marked (folds circles, period
    doublings squares, Neimark-Sacker triangles, grazing points small crosses unless
    ``grazing=False``), superharmonic resonances labelled with their order. The legend (orders,
    line styles, markers) stands outside the axes, right of the data (``legend=False``: none, e.g.
for all but the last panel of a row). ``path``: also write the
    figure (then closed if this call opened it). Returns the Figure."""
    from nlbeam._validate import positive

    from .files import check_plot_options

    check_plot_options(path, (("grazing", grazing), ("legend", legend)), ax)
    positive("scale", scale)
    if not isinstance(unit, str):
        raise TypeError(f"unit: must be a string such as 'mm', got {unit!r}")
    if not all(hasattr(frc, a) for a in ("branches", "bifurcations")):
        raise TypeError(f"frc: must be a continuation.FrequencyResponse, got "
                        f"{type(frc).__name__}")
    import matplotlib.pyplot as plt

    opened = ax is None
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5))
    seen = set()
    for b in frc.branches:
        c = _COLOURS.get(b.order, "k")
        x, y, s = b.values, b.xmax * scale, b.stable
        if s is None:  # computed with stability=False: stability unknown, drawn solid
            s = np.ones(len(x), dtype=bool)
        cuts = np.nonzero(np.diff(s.astype(int)))[0] + 1
        for seg in np.split(np.arange(len(x)), cuts):
            if seg.size == 0:
                continue
            seg = np.r_[seg, seg[-1] + 1] if seg[-1] + 1 < len(x) else seg
            if b.order not in seen:  # legend entry: a solid line in the order's colour
                ax.plot([], [], "-", color=c, lw=1.3, label="harmonic (n = 1)" if b.order == 1
                        else f"1/{b.order} subharmonic")
                seen.add(b.order)
            ax.plot(x[seg], y[seg], "-" if s[seg[0]] else "--", color=c,
                    lw=1.3 if s[seg[0]] else 0.9)
    done = set()
    for bf in frc.bifurcations:
        if bf.kind == "grazing" and not grazing:
            continue
        m, name, ms = _MARK[bf.kind]
        ax.plot(bf.value, bf.xmax * scale, m, mfc="none", color="k", ms=ms, mew=0.8,
                label=None if bf.kind in done else name, zorder=5)
        done.add(bf.kind)
    span = abs(frc.p_range[1] - frc.p_range[0])
    level, last = 0, None
    for sh in sorted(frc.superharmonics, key=lambda sh: sh.frequency):
        # labels closer than 12 % of the axis are stacked, so that their texts do not overlap
        level = level + 1 if last is not None and sh.frequency - last < 0.12 * span else 0
        last = sh.frequency
        frac = (sh.frequency - min(frc.p_range)) / span  # near an edge: text inwards
        ha, dx = ("left", -8) if frac < 0.12 else ("right", 8) if frac > 0.88 else ("center", 0)
        ax.annotate(f"superharmonic k = {sh.harmonic}\n{sh.frequency:.2f} Hz",
                    (sh.frequency, sh.xmax * scale), textcoords="offset points",
                    xytext=(dx, 18 + 26 * level), ha=ha, fontsize=8,
                    arrowprops=dict(arrowstyle="-", lw=0.6))
    ax.set_xlim(*sorted(frc.p_range))
    params = dict(frc.model_parameters or {})
    force = excitation_kind(params) == "force"
    a_unit, a_scale = ("N", 1.0) if force else (unit, scale)
    if frc.parameter == "frequency":
        ax.set_xlabel("excitation frequency [Hz]")
    elif frc.parameter == "amplitude":
        ax.set_xlabel(f"{'force' if force else 'base'} amplitude [{'N' if force else 'm'}]")
    else:
        field = frc.parameter.rsplit(".", 1)[-1]  # elements[i].field: the field's unit
        ax.set_xlabel(f"{frc.parameter} "
                      f"[{_PARAMETER_UNITS.get(frc.parameter, _PARAMETER_UNITS.get(field, '-'))}]")
    ax.set_ylabel(_response_label(params, unit))
    known = all(b.stable is not None for b in frc.branches)
    what = "force amplitude" if force else "base amplitude"
    title = f"periodic solutions, {what} {frc.amplitude * a_scale:g} {a_unit}"
    if frc.parameter == "amplitude":
        title = "periodic solutions under amplitude continuation"
    ax.set_title(title, fontsize=10)
    if known:
        ax.plot([], [], "-", color="0.3", lw=1.3, label="stable (solid)")
        ax.plot([], [], "--", color="0.3", lw=0.9, label="unstable (dashed)")
    else:
        ax.plot([], [], "-", color="0.3", lw=1.3, label="stability not computed")
    if legend:
        legend_outside(ax, borderaxespad=0.0, frameon=False)
    from .files import finish_figure

    return finish_figure(ax.figure, path, opened)
