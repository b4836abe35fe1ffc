"""Plot a FrequencyResponse in the style of the paper's Figure 4 (matplotlib is imported when
called; ``continuation.plot`` re-exports this module)."""
from __future__ import annotations

import numpy as np

_MARK = {"fold": ("o", "fold", 6), "period-doubling": ("s", "period doubling", 6),
         "neimark-sacker": ("^", "Neimark-Sacker", 6), "grazing": ("x", "grazing", 4)}
_COLOURS = {1: "C0", 2: "C3", 3: "C2", 4: "C1", 6: "C4"}

__all__ = ["plot_frequency_response"]


def plot_frequency_response(frc, ax=None, *, scale=1e3, unit="mm", grazing=True):
    """|x|max against frequency: stable solid, unstable dashed (all solid for a diagram computed
    with stability=False), one colour per order,
    bifurcations marked (folds circles, period doublings squares, Neimark-Sacker triangles,
    grazing points small crosses unless ``grazing=False``), superharmonic resonances labelled
    with their order. Returns the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 5))
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
    ax.set_xlim(*frc.p_range)
    ax.set_xlabel("excitation frequency [Hz]" if frc.parameter == "frequency" else frc.parameter)
    ax.set_ylabel(f"|x|max [{unit}]")
    known = all(b.stable is not None for b in frc.branches)
    ax.set_title(f"periodic solutions, base amplitude {frc.amplitude * scale:g} {unit} "
                 + ("(solid stable, dashed unstable)" if known else "(stability not computed)"))
    ax.legend(fontsize=8, loc="upper right")
    return ax
