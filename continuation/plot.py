"""Plot a FrequencyResponse in the style of the paper's Figure 4 (imports matplotlib)."""
from __future__ import annotations

import numpy as np

_MARK = {"fold": ("o", "fold"), "period-doubling": ("s", "period doubling"),
         "neimark-sacker": ("^", "Neimark-Sacker")}


def plot_frequency_response(frc, ax=None, *, scale=1e3, unit="mm"):
    """|x|max against frequency: stable solid, unstable dashed, one colour per order,
    bifurcations marked, superharmonic peaks labelled. Returns the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 5))
    colours = {1: "C0", 2: "C1", 3: "C2", 4: "C3", 6: "C4"}
    seen = set()
    for b in frc.branches:
        c = colours.get(b.order, "k")
        x, y, s = b.values, b.xmax * scale, b.stable
        # split into runs of equal stability
        cuts = np.nonzero(np.diff(s.astype(int)))[0] + 1
        for seg in np.split(np.arange(len(x)), cuts):
            if seg.size == 0:
                continue
            seg = np.r_[seg, seg[-1] + 1] if seg[-1] + 1 < len(x) else seg
            label = None
            if b.order not in seen:
                label = "harmonic (1)" if b.order == 1 else f"1/{b.order} subharmonic"
                seen.add(b.order)
            ax.plot(x[seg], y[seg], "-" if s[seg[0]] else "--", color=c, lw=1.2, label=label)
    done = set()
    for bf in frc.bifurcations:
        m, name = _MARK[bf.kind]
        ax.plot(bf.value, bf.xmax * scale, m, mfc="none", color="k", ms=6,
                label=None if bf.kind in done else name)
        done.add(bf.kind)
    for sh in frc.superharmonics:
        ax.annotate(f"({sh.harmonic})", (sh.frequency, sh.xmax * scale), textcoords="offset points",
                    xytext=(0, 6), ha="center", fontsize=9)
    ax.set_xlim(*frc.p_range)
    ax.set_xlabel("excitation frequency [Hz]" if frc.parameter == "frequency" else frc.parameter)
    ax.set_ylabel(f"|x|max [{unit}]")
    ax.set_title(f"periodic solutions, amplitude {frc.amplitude * scale:g} {unit}")
    ax.legend(fontsize=8)
    return ax
