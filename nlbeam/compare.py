"""Trace the peaks of a stochastic response PSD to the periodic frequency-response diagram.

Front door: :func:`map_peaks` (PSD peaks -> :class:`PeakMatch` list) and
:func:`plot_comparison` (the PSD and the diagram on one response-frequency axis; imports
matplotlib when called). Frequencies in Hz, xmax in m, PSD in units^2/Hz.

The matching rule (paper sections 5 and 7)
------------------------------------------
*Peaks.* ``L = log10 P`` is compared with its running median over ``background_hz`` (the
local background); a peak is a local maximum of ``L - median`` that stands above the
background, and has a topographic prominence, of at least ``thr`` decades, where
``thr = max(min_prominence, 5 * scatter)`` and ``scatter`` is the bin-to-bin scatter of
``L - median`` (robust estimate), so Welch noise does not make peaks. The
``prominence`` reported is that of ``L - median``, in decades.

*Tolerance.* A peak is explained by a diagram point whose response frequency lies within
``tol = max(tol_bins * df, half width at half prominence of the peak)`` (Hz), unless
``tolerance`` (Hz) is given. ``distance`` is ``|response frequency of the point - peak|``.

*Where a branch resonates.* On each branch, the local maxima of ``xmax`` along the path
(prominence >= 5 % of the branch's largest xmax; on a hardening resonance the top fold) and
the folds located on it. The point's ``stable`` is the branch's stability there.

*Where the excitation holds a frequency.* The frequency band ``excitation.band`` (a
``stochastic.BandLimitedNoise`` / ``SpectralNoise``), a pair ``(f_lo, f_hi)``, a
``(frequencies, G)`` pair of arrays (G > 0), a ``nlbeam.Harmonic`` (its frequency), or None
(everything). A frequency is held when the band meets ``[f - tol, f + tol]``.

*Kinds*, tried in this order, the closest point within tolerance of the first kind that has
one wins (the others are kept in ``alternatives``):

1. ``"harmonic"`` (order 1): the excitation holds ``f`` and an order-1 branch resonates at
   excitation frequency ``f``.
2. ``"subharmonic"`` (order n >= 2): the excitation holds ``n f`` and an order-n branch
   resonates at excitation frequency ``n f`` (response at ``f = f_exc / n``).
3. ``"superharmonic"`` (order k >= 2): the excitation holds ``f / k`` and the harmonic branch
   has a superharmonic resonance of order k at ``f / k``: a diagram ``Superharmonic`` mark
   with ``harmonic = k``, or an order-1 resonance at ``f_s`` other than the main one (the
   order-1 resonance of largest xmax, at ``f_r``) with ``k = round(f_r / f_s) >= 2`` and
   ``|k f_s - f_r| <= 0.15 f_r``. Response at ``k f_s``.
4. ``"asymmetry"`` (order 0): ``f <= asymmetry_below`` (default a third of the main
   harmonic resonance frequency) and the excitation holds two frequencies ``f`` apart
   (its band is at least ``f`` wide): the difference-frequency (low-frequency) content of
   an asymmetric response.
5. ``"unexplained"`` (order 0): none of the above (e.g. a second beam mode the model lacks).

``branch_frequency`` is the excitation frequency of the explaining diagram point (the
abscissa of the paper's Figure 4); NaN for the last two kinds.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["PeakMatch", "Resonance", "map_peaks", "find_peaks", "resonances", "plot_comparison",
           "KINDS"]

KINDS = ("harmonic", "subharmonic", "superharmonic", "asymmetry", "unexplained")


@dataclass(frozen=True)
class Resonance:
    """A point where a branch resonates. frequency: excitation frequency (Hz); response:
    the response frequency where it shows in a PSD (Hz); kind 'harmonic', 'subharmonic'
    or 'superharmonic'; order n (subharmonic) or k (superharmonic), 1 for harmonic;
    branch: index in ``frc.branches``; xmax (m); stable."""

    kind: str
    order: int
    frequency: float
    response: float
    xmax: float
    stable: bool
    branch: int


@dataclass(frozen=True)
class PeakMatch:
    """One PSD peak and its explanation (see the module doc for the rule).

    frequency: peak (Hz); prominence: decades above the local background; psd: P at the
    peak; kind: one of KINDS; order: n of a 1/n subharmonic, k of a superharmonic, 1 for
    harmonic, 0 otherwise; branch_frequency: excitation frequency of the explaining point
    (Hz, NaN if none); stable: its stability (None if none); distance: Hz between the peak
    and the point's response frequency (NaN if none); tolerance (Hz); branch: index in
    ``frc.branches`` (-1 if none); alternatives: other explanations within tolerance."""

    frequency: float
    prominence: float
    kind: str
    order: int
    branch_frequency: float
    stable: bool | None
    distance: float
    tolerance: float = math.nan
    psd: float = math.nan
    branch: int = -1
    xmax: float = math.nan
    alternatives: tuple = field(default=(), compare=False)

    def as_row(self) -> dict:
        """Plain dict for tables (CSV)."""
        return {"frequency_hz": self.frequency, "prominence_dec": self.prominence,
                "kind": self.kind, "order": self.order,
                "branch_frequency_hz": self.branch_frequency,
                "stable": "" if self.stable is None else bool(self.stable),
                "distance_hz": self.distance, "tolerance_hz": self.tolerance,
                "xmax_m": self.xmax}


# -- peaks of the PSD ----------------------------------------------------------------------
def _odd(n):
    n = max(int(n), 3)
    return n if n % 2 else n + 1


def find_peaks(psd, *, min_prominence=0.3, background_hz=20.0, tol_bins=2.0, f_range=None):
    """Peaks of a PSD ``(f, P)`` against its running median in log10.
    Returns (indices, prominences in decades, half widths in Hz, background log10 P)."""
    from scipy.ndimage import median_filter
    from scipy.signal import find_peaks as _fp
    from scipy.signal import peak_widths

    f, P = (np.asarray(a, dtype=float) for a in psd)
    if f.ndim != 1 or f.shape != P.shape or f.size < 5:
        raise ValueError(f"psd: must be a pair (f, P) of equal 1-D arrays with >= 5 points, "
                         f"got shapes {f.shape} and {P.shape}")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(P))) or np.any(P < 0):
        raise ValueError("psd: frequencies and P must be finite, P >= 0")
    df = float(np.median(np.diff(f)))
    if not df > 0:
        raise ValueError("psd: frequencies must increase")
    floor = max(P.max(), 1e-300) * 1e-16
    L = np.log10(np.maximum(P, floor))
    bg = median_filter(L, size=_odd(round(background_hz / df)), mode="nearest")
    r = L - bg
    scatter = 1.4826 * float(np.median(np.abs(np.diff(r)))) / math.sqrt(2.0)
    thr = max(float(min_prominence), 5.0 * scatter)
    idx, props = _fp(r, height=thr, prominence=thr, distance=max(1, int(round(tol_bins))))
    if f_range is not None:
        keep = (f[idx] >= f_range[0]) & (f[idx] <= f_range[1])
        idx = idx[keep]
        props = {k: v[keep] for k, v in props.items()}
    widths = peak_widths(r, idx, rel_height=0.5, prominence_data=(
        props["prominences"], props["left_bases"], props["right_bases"]))[0] if idx.size else np.zeros(0)
    return idx, props["prominences"], 0.5 * widths * df, bg


# -- resonances of the diagram -------------------------------------------------------------
def resonances(frc, *, main_rel=0.15, max_superharmonic=5):
    """The points where the diagram's branches resonate (module doc), as Resonance list:
    order-1 and order-n points, and the superharmonic reading of order-1 points."""
    from scipy.signal import find_peaks as _fp

    out = []
    order1 = []
    for bi, b in enumerate(frc.branches):
        x = np.asarray(b.xmax, dtype=float)
        fr = np.asarray(b.frequency, dtype=float)
        st = np.asarray(b.stable, dtype=bool)
        if x.size < 3:
            continue
        pk, _ = _fp(np.r_[-np.inf, x, -np.inf], prominence=0.05 * np.max(x))
        pts = {int(i) - 1 for i in pk if 1 <= i - 1 <= x.size - 2}
        for bf in frc.bifurcations:
            if bf.kind == "fold" and int(bf.branch) == bi and bf.order == b.order:
                pts.add(int(np.argmin(np.abs(fr - bf.frequency) + np.abs(x - bf.xmax) / max(x.max(), 1e-300))))
        for i in sorted(pts):
            n = int(b.order)
            kind = "harmonic" if n == 1 else "subharmonic"
            r = Resonance(kind, n, float(fr[i]), float(fr[i]) / n, float(x[i]), bool(st[i]), bi)
            out.append(r)
            if n == 1:
                order1.append(r)
    if order1:
        main = max(order1, key=lambda r: r.xmax)
        marked = {}
        for s in getattr(frc, "superharmonics", []) or []:
            marked[(int(s.branch), round(float(s.frequency), 6))] = int(s.harmonic)
        for r in order1:
            k = marked.get((r.branch, round(r.frequency, 6)))
            if k is None:
                if abs(r.frequency - main.frequency) <= main_rel * main.frequency:
                    continue
                k = int(round(main.frequency / r.frequency))
                if k < 2 or k > max_superharmonic or \
                        abs(k * r.frequency - main.frequency) > main_rel * main.frequency:
                    continue
            out.append(Resonance("superharmonic", k, r.frequency, k * r.frequency, r.xmax,
                                 r.stable, r.branch))
        for s in getattr(frc, "superharmonics", []) or []:  # marks not on a detected peak
            key = (int(s.branch), round(float(s.frequency), 6))
            if not any(r.kind == "superharmonic" and (r.branch, round(r.frequency, 6)) == key
                       for r in out):
                b = frc.branches[int(s.branch)]
                i = int(np.argmin(np.abs(np.asarray(b.frequency) - s.frequency)))
                out.append(Resonance("superharmonic", int(s.harmonic), float(s.frequency),
                                     int(s.harmonic) * float(s.frequency), float(s.xmax),
                                     bool(b.stable[i]), int(s.branch)))
    return out


# -- what the excitation holds -------------------------------------------------------------
class _Holds:
    def __init__(self, excitation):
        self.bands = None  # list of (lo, hi), or None = everything
        self.width = math.inf
        ex = excitation
        if ex is None:
            return
        if hasattr(ex, "band"):
            lo, hi = (float(v) for v in ex.band)
            self.bands = [(lo, hi)]
        elif hasattr(ex, "frequency") and hasattr(ex, "amplitude"):
            f0 = float(ex.frequency)
            self.bands = [(f0, f0)]
        else:
            try:
                a, b = ex
            except (TypeError, ValueError):
                raise ValueError("excitation: must be None, an object with .band, a Harmonic, "
                                 "(f_lo, f_hi) or (frequencies, G) arrays") from None
            if np.ndim(a) == 0 and np.ndim(b) == 0:
                lo, hi = float(a), float(b)
                if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
                    raise ValueError(f"excitation: band must satisfy 0 <= f_lo <= f_hi Hz, got {ex!r}")
                self.bands = [(lo, hi)]
            else:
                fa, G = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
                if fa.shape != G.shape or fa.ndim != 1:
                    raise ValueError("excitation: (frequencies, G) must be equal 1-D arrays")
                on = G > 0
                # runs of positive G -> bands
                self.bands = []
                i = 0
                while i < fa.size:
                    if on[i]:
                        j = i
                        while j + 1 < fa.size and on[j + 1]:
                            j += 1
                        self.bands.append((float(fa[i]), float(fa[j])))
                        i = j + 1
                    else:
                        i += 1
        self.width = max((hi - lo for lo, hi in self.bands), default=0.0)

    def __call__(self, f, tol):
        if self.bands is None:
            return True
        return any(lo - tol <= f <= hi + tol for lo, hi in self.bands)


# -- the mapping ---------------------------------------------------------------------------
def map_peaks(psd, frc, excitation=None, *, min_prominence=0.3, background_hz=20.0,
              tol_bins=2.0, tolerance=None, asymmetry_below=None, f_range=None,
              max_superharmonic=5):
    """Find the peaks of a response PSD ``psd = (f, P)`` and explain each by the periodic
    diagram ``frc`` (a ``continuation.FrequencyResponse``, or any object with ``branches``
    (order, frequency, xmax, stable), ``bifurcations`` (kind, frequency, xmax, order,
    branch) and ``superharmonics``). Returns a list of :class:`PeakMatch`, by frequency.
    The rule, tolerances and defaults are in the module doc; ``f_range`` (Hz) limits the
    peaks considered."""
    if tolerance is not None:
        tolerance = float(tolerance)
        if not (math.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance: must be finite and > 0 Hz, got {tolerance!r}")
    f = np.asarray(psd[0], dtype=float)
    P = np.asarray(psd[1], dtype=float)
    idx, prom, halfw, _ = find_peaks((f, P), min_prominence=min_prominence,
                                     background_hz=background_hz, tol_bins=tol_bins,
                                     f_range=f_range)
    df = float(np.median(np.diff(f)))
    holds = _Holds(excitation)
    res = resonances(frc, max_superharmonic=max_superharmonic)
    harm = [r for r in res if r.kind == "harmonic"]
    if asymmetry_below is None:
        main = max(harm, key=lambda r: r.xmax) if harm else (min(res, key=lambda r: r.response)
                                                             if res else None)
        asymmetry_below = main.response / 3.0 if main is not None else 0.0
    out = []
    for i, pr, hw in zip(idx, prom, halfw):
        fp = float(f[i])
        tol = tolerance if tolerance is not None else max(tol_bins * df, float(hw))
        cands = []
        for r in res:
            d = abs(r.response - fp)
            if d > tol:
                continue
            if r.kind == "harmonic" and not holds(fp, tol):
                continue
            if r.kind == "subharmonic" and not holds(r.order * fp, r.order * tol):
                continue
            if r.kind == "superharmonic" and not holds(fp / r.order, tol / r.order):
                continue
            cands.append((KINDS.index(r.kind), d, r))
        cands.sort(key=lambda c: (c[0], c[1]))
        common = dict(frequency=fp, prominence=float(pr), tolerance=float(tol), psd=float(P[i]))
        if cands:
            _, d, r = cands[0]
            alts = tuple((c[2].kind, c[2].order, c[2].frequency, c[1]) for c in cands[1:])
            out.append(PeakMatch(kind=r.kind, order=r.order, branch_frequency=r.frequency,
                                 stable=r.stable, distance=float(d), branch=r.branch,
                                 xmax=r.xmax, alternatives=alts, **common))
        elif fp <= asymmetry_below and holds.width >= fp - tol:
            out.append(PeakMatch(kind="asymmetry", order=0, branch_frequency=math.nan,
                                 stable=None, distance=math.nan, **common))
        else:
            out.append(PeakMatch(kind="unexplained", order=0, branch_frequency=math.nan,
                                 stable=None, distance=math.nan, **common))
    return out


# -- figure --------------------------------------------------------------------------------
_KIND_COLOUR = {"harmonic": "C0", "subharmonic": "C1", "superharmonic": "C2",
                "asymmetry": "C4", "unexplained": "C3"}
_ORDER_COLOUR = {1: "C0", 2: "C1", 3: "C2", 4: "C3", 5: "C5", 6: "C4"}


def plot_comparison(psd, frc, matches=None, *, excitation=None, f_max=None, label="delta",
                    unit="m", superharmonic_orders=(2, 3), scale=1e3, fig=None, **map_kw):
    """The PSD (top, log) and the periodic diagram (bottom, |x|max in mm) on one
    response-frequency axis: an order-n branch at excitation frequency f is drawn at f/n,
    the harmonic branch also at k f for each k in ``superharmonic_orders`` (thin, grey);
    each peak is marked with its kind and joined to the point that explains it.
    ``matches`` default: ``map_peaks(psd, frc, excitation, **map_kw)``. Returns the Figure."""
    import matplotlib.pyplot as plt

    f, P = (np.asarray(a, dtype=float) for a in psd)
    if matches is None:
        matches = map_peaks((f, P), frc, excitation, **map_kw)
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
    seen = set()
    for m in matches:
        c = _KIND_COLOUR[m.kind]
        name = m.kind if m.kind not in seen else None
        seen.add(m.kind)
        ax1.plot(m.frequency, m.psd, "v", color=c, ms=7, label=name)
        txt = {"harmonic": "1", "subharmonic": f"1/{m.order}", "superharmonic": f"{m.order}",
               "asymmetry": "asym", "unexplained": "?"}[m.kind]
        ax1.annotate(txt, (m.frequency, m.psd), textcoords="offset points", xytext=(0, 6),
                     ha="center", fontsize=8, color=c)
        for ax in (ax1, ax2):
            ax.axvline(m.frequency, color=c, lw=0.6, ls=":")
    if np.any(pos):
        top = float(P[pos].max())
        ax1.set_ylim(max(float(P[pos].min()), top * 1e-8), top * 5.0)
    ax1.set_ylabel(f"PSD of {label} [{unit}$^2$/Hz]")
    ax1.legend(fontsize=8, loc="upper right")
    done = set()
    for b in frc.branches:
        n = int(b.order)
        c = _ORDER_COLOUR.get(n, "k")
        fr, x, st = np.asarray(b.frequency), np.asarray(b.xmax) * scale, np.asarray(b.stable)
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
    for m in matches:
        if m.branch >= 0:
            resp = {"harmonic": m.branch_frequency, "subharmonic": m.branch_frequency / max(m.order, 1),
                    "superharmonic": m.branch_frequency * m.order}[m.kind]
            ax2.plot(resp, m.xmax * scale, "o", mfc="none", color=_KIND_COLOUR[m.kind], ms=8)
    ax2.set_xlabel("response frequency [Hz]")
    ax2.set_ylabel("|x|max [mm]")
    ax2.legend(fontsize=8, loc="upper right")
    hi = f_max if f_max is not None else float(f[-1])
    ax1.set_xlim(0.0, hi)
    ax1.set_title("stochastic response peaks and the periodic diagram")
    fig.tight_layout()
    return fig
