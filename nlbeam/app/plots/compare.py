"""The comparison figure: a stochastic PSD and the periodic diagram on one response-frequency
axis, each PSD peak marked with the explanation ``nlbeam.app.compare.map_peaks`` gives it
(matplotlib is imported when called). Frequencies in Hz, xmax in m (drawn in mm).
"""
from __future__ import annotations

import math

import numpy as np

from ..compare import _Holds, map_peaks

__all__ = ["plot_comparison"]

_KIND_COLOUR = {"harmonic": "C0", "subharmonic": "C1", "superharmonic": "C2",
                "asymmetry": "C4", "unexplained": "C3"}
_ORDER_COLOUR = {1: "C0", 2: "C1", 3: "C2", 4: "C3", 5: "C5", 6: "C4"}


def plot_comparison(psd, frc, matches=None, *, excitation=None, f_max=None, label="delta",
                    unit="m", superharmonic_orders=(2, 3), scale=1e3, fig=None, stability=True,
                    ax=None, path=None, **map_kw):
    """The PSD (top, log) and the periodic diagram (bottom, |x|max in mm) on one
    response-frequency axis: an order-n branch at excitation frequency f is drawn at f/n,
    the harmonic branch also at k f for each k in ``superharmonic_orders`` (thin, grey);
    each peak is marked with its kind (``k x f_p`` for a multiple of a stronger peak,
    "1 forced" for the forced response in a narrow band) and joined to the point that
    explains it. ``matches`` default: ``map_peaks(psd, frc, excitation, **map_kw)``.
    ``stability=False`` draws every branch solid (for a diagram computed without Floquet
    multipliers). ``ax``: a pair of axes (PSD, diagram) to draw into (sharing x is the
    caller's choice); else ``fig`` (its two panels are added) or a new figure. ``path``: also
    write the figure (then closed if this call opened it). Returns the Figure."""
    import matplotlib.pyplot as plt

    f, P = (np.asarray(a, dtype=float) for a in psd)
    if matches is None:
        matches = map_peaks((f, P), frc, excitation, **map_kw)
    opened = fig is None and ax is None
    if ax is not None:
        try:
            ax1, ax2 = ax
        except (TypeError, ValueError):
            raise ValueError("ax: give two axes (the PSD's and the diagram's), got "
                             f"{ax!r}") from None
        fig = ax1.figure
    else:
        if fig is None:
            fig = plt.figure(figsize=(9, 7))
        ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1]})
    pos = P > 0
    ax1.semilogy(f[pos], P[pos], color="k", lw=0.8, label=f"PSD of {label}")
    holds = _Holds(excitation)
    if holds.bands is not None:
        for lo, hi in holds.bands:
            ax1.axvspan(lo, max(hi, lo + 1e-9), color="0.9", zorder=0,
                        label="excitation band" if (lo, hi) == holds.bands[0] else None)
    hi = f_max if f_max is not None else float(f[-1])
    matches = [m for m in matches if m.frequency <= hi]  # no legend entry for a peak not drawn
    seen = set()
    for m in matches:
        c = _KIND_COLOUR[m.kind]
        name = m.kind if m.kind not in seen else None
        seen.add(m.kind)
        ax1.plot(m.frequency, m.psd, "v", color=c, ms=7, label=name)
        txt = {"harmonic": "1", "subharmonic": f"1/{m.order}", "superharmonic": f"{m.order}",
               "asymmetry": "asym", "unexplained": "?"}[m.kind]
        if m.note == "forced":
            txt = "1 forced"
        elif m.note == "multiple":
            txt = f"{m.order}\u00d7{m.explained_by:.4g}"
        near_axis = m.frequency < 0.04 * hi  # centred there, the text crosses the y axis
        ax1.annotate(txt, (m.frequency, m.psd), textcoords="offset points",
                     xytext=(3 if near_axis else 0, 6), ha="left" if near_axis else "center",
                     fontsize=8, color=c)
        for ax in (ax1, ax2):
            ax.axvline(m.frequency, color=c, lw=0.6, ls=":")
    shown = pos & (f <= (f_max if f_max is not None else np.inf))  # y range from what is seen
    if np.any(shown):
        top = float(P[shown].max())
        ax1.set_ylim(max(float(P[shown].min()) / 2.0, top * 1e-8), top * 5.0)
    ax1.set_ylabel(f"PSD of {label} [{unit}$^2$/Hz]")
    ax1.legend(fontsize=8, loc="upper right")
    done = set()
    for b in frc.branches:
        n = int(b.order)
        c = _ORDER_COLOUR.get(n, "k")
        fr, x = np.asarray(b.frequency), np.asarray(b.xmax) * scale
        if stability and b.stable is not None:
            st = np.asarray(b.stable, dtype=bool)
        else:  # not asked for, or not computed: one style
            st = np.ones(fr.size, dtype=bool)
        cuts = np.nonzero(np.diff(st.astype(int)))[0] + 1
        for seg in np.split(np.arange(fr.size), cuts):
            if seg.size == 0:
                continue
            seg = np.r_[seg, seg[-1] + 1] if seg[-1] + 1 < fr.size else seg
            lab = None
            if n not in done:
                lab = "harmonic branch at f" if n == 1 else f"order-{n} branch at f/{n}"
                done.add(n)
            ax2.plot(fr[seg] / n, x[seg], "-" if st[seg[0]] else "--", color=c, lw=1.1,
                     label=lab)
            if n == 1:
                for k in superharmonic_orders:
                    ax2.plot(k * fr[seg], x[seg], "-" if st[seg[0]] else "--", color="0.6",
                             lw=0.6, label=None)
    if superharmonic_orders:
        ax2.plot([], [], color="0.6", lw=0.6,
                 label="harmonic branch at k f, k = " + ", ".join(map(str, superharmonic_orders)))
    for m in matches:  # the diagram point that explains the peak (a multiple has none)
        if m.branch >= 0 and m.note != "multiple" and math.isfinite(m.response_frequency):
            ax2.plot(m.response_frequency, m.xmax * scale, "o", mfc="none",
                     color=_KIND_COLOUR[m.kind], ms=8)
    ax2.set_xlabel("response frequency [Hz]")
    ax2.set_ylabel("|x|max [mm]")
    ax2.legend(fontsize=8, loc="upper right")
    ax1.set_xlim(0.0, hi)
    ax1.set_title("stochastic response peaks and the periodic diagram")
    from .files import finish_figure

    return finish_figure(fig, path, opened, tight_layout=ax is None)
