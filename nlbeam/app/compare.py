"""Trace the peaks of a stochastic response PSD to the periodic frequency-response diagram.

Front door: :func:`map_peaks` (PSD peaks -> :class:`PeakMatch` list); its figure,
``plot_comparison`` (the PSD and the diagram on one response-frequency axis), is in
``nlbeam.app.plots.compare``. Frequencies in Hz, xmax in m, PSD in units^2/Hz.

The matching rule (paper sections 5 and 7)
------------------------------------------
*Peaks.* ``L = log10 P`` is compared with its running median over ``background_hz`` (the
local background); a peak is a local maximum of ``L - median`` whose prominence (and height
above the background) exceeds ``min_prominence`` by ``confidence`` standard errors of the
estimate (``stochastic.peaks``: the larger of the Welch estimate's chi-square scatter, given
its degrees of freedom ``dof``, and the PSD's measured bin-to-bin scatter), so Welch noise
does not make peaks and the same peaks come out of another record of the same length. The
``prominence`` reported is that of ``L - median``, in decades, with ``prominence_error``;
``frequency_error`` is how far the top may lie from the bin found (the bins within one
standard error of the top).

*Tolerance.* A peak is explained by a diagram point whose response frequency lies within
``tol = max(tol_bins * df, half width at half prominence of the peak, frequency_error)``
(Hz), unless ``tolerance`` (Hz) is given. ``distance`` is ``|response frequency of the
point - peak|``.

*Where a branch resonates.* On each branch, the local maxima of ``xmax`` along the path
(prominence >= 5 % of the branch's largest xmax; on a hardening resonance the top fold) and
the folds located on it. The point's ``stable`` is the branch's stability there (None for a
diagram computed with ``stability=False``).

*Where the excitation holds a frequency.* The frequency band ``excitation.band`` (a
``stochastic.BandLimitedNoise`` / ``SpectralNoise``), a pair ``(f_lo, f_hi)``, a
``(frequencies, G)`` pair of arrays (G > 0), a ``nlbeam.Harmonic`` (its frequency), or None
(everything). A frequency is held when the band meets ``[f - tol, f + tol]``.

*Kinds.* The peaks are explained strongest first (largest P), each by the first of these
steps that succeeds; within a step the closest point within tolerance wins (others within
tolerance are kept in ``alternatives``). ``note`` says which step explained the peak.

1. A resonance (``note = "resonance"``), trying the kinds in this order:

   a. ``"harmonic"`` (order 1): the excitation holds ``f`` and an order-1 branch resonates
      at excitation frequency ``f`` (the linear or the impacting resonance alike: under
      broad-band noise the harmonic resonance peak lies inside the band).
   b. ``"subharmonic"`` (order n >= 2): the excitation holds ``n f`` and an order-n branch
      resonates at excitation frequency ``n f`` (response at ``f = f_exc / n``).
   c. ``"superharmonic"`` (order k >= 2): the excitation holds ``f / k`` and the harmonic
      branch has a superharmonic resonance of order k at ``f / k``: a diagram
      ``Superharmonic`` mark with ``harmonic = k``, or an order-1 resonance at ``f_s`` other
      than the main one (the order-1 resonance of largest xmax, at ``f_r``) with
      ``k = round(f_r / f_s) >= 2`` and ``|k f_s - f_r| <= 0.15 f_r``. Response at ``k f_s``.

2. A multiple of a stronger peak (``note = "multiple"``): ``f`` lies within tolerance of
   ``k f_p`` (k >= 2) where ``f_p`` is a stronger peak explained in step 1 or 3. The impact
   makes the response to each excitation component strongly non-harmonic, so every peak
   comes with its integer multiples (e.g. 2 and 3 x 43.5 Hz under broad-band noise; 3/2 and
   2 times the excitation of a 1/2 subharmonic are 3 and 4 x its response peak). Kind
   ``"superharmonic"``, order ``k``, ``explained_by = f_p``; ``branch_frequency``,
   ``stable``, ``branch`` and ``xmax`` are those of the parent's diagram point. Of several
   parents the strongest wins.
3. Forced response inside a narrow band (``note = "forced"``): the excitation holds ``f``
   and the band holding it is at most ``background_hz`` wide (a narrow band, or a
   ``Harmonic``: the input itself stands out of the running median there, so the response
   to it makes a peak even away from any resonance). Kind ``"harmonic"``, order 1: the
   response at the excitation frequency is the order-1 response; the diagram point is the
   order-1 branch point closest to ``f`` (within tolerance; else none). A peak inside a
   *broad* band away from every resonance is not forced (a flat input through a
   non-resonant transfer makes no peak): it stays ``"unexplained"``.
4. ``"asymmetry"`` (order 0): ``f <= asymmetry_below`` (default a third of the main
   harmonic resonance frequency) and the excitation holds two frequencies ``f`` apart
   (its band is at least ``f`` wide): the difference-frequency (low-frequency) content of
   an asymmetric response.
5. ``"unexplained"`` (order 0): none of the above (e.g. a second beam mode the model lacks).

``branch_frequency`` is the excitation frequency of the explaining diagram point (the
abscissa of the paper's Figure 4); NaN for the last two kinds and when no diagram point
explains it. ``response_frequency`` is where the explanation puts the peak (Hz; for a
multiple ``k f_p``), ``distance = |frequency - response_frequency|``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nlbeam._validate import (ArgumentTypeError, integer, interval, nonnegative, positive,
                              real_array)
from nlbeam.summary import Summary
from stochastic.peaks import DEFAULT_CONFIDENCE, significant_peaks

__all__ = ["PeakMatch", "Resonance", "map_peaks", "find_peaks", "resonances", "welch_dof_of",
           "KINDS"]

KINDS = ("harmonic", "subharmonic", "superharmonic", "asymmetry", "unexplained")


@dataclass(frozen=True, repr=False)
class Resonance(Summary):
    """A point where a branch resonates. frequency: excitation frequency (Hz); response:
    the response frequency where it shows in a PSD (Hz); kind 'harmonic', 'subharmonic'
    or 'superharmonic'; order n (subharmonic) or k (superharmonic), 1 for harmonic;
    branch: index in ``frc.branches``; xmax (m); stable (None: not computed)."""

    kind: str
    order: int
    frequency: float
    response: float
    xmax: float
    stable: bool | None
    branch: int


@dataclass(frozen=True, repr=False)
class PeakMatch(Summary):
    """One PSD peak and its explanation (see the module doc for the rule).

    frequency: peak (Hz); prominence: decades above the local background; psd: P at the
    peak; kind: one of KINDS; order: n of a 1/n subharmonic, k of a superharmonic (or of a
    multiple of a stronger peak), 1 for harmonic, 0 otherwise; branch_frequency: excitation
    frequency of the explaining diagram point (Hz, NaN if none); stable: its stability
    (None if none); distance: Hz between the peak and response_frequency (NaN if none);
    tolerance (Hz); branch: index in ``frc.branches`` (-1 if none); xmax: the point's
    (m); note: "resonance", "multiple" or "forced" (the step that explained the peak, ""
    for asymmetry and unexplained); explained_by: the parent peak of a multiple (Hz, NaN
    otherwise); response_frequency: where the explanation puts the peak (Hz, NaN if none);
    alternatives: other explanations within tolerance; frequency_error (Hz) and
    prominence_error (decades): one-standard-deviation errors of the peak's frequency and
    prominence in the PSD estimate; significance: standard errors by which the prominence
    clears ``min_prominence`` (``stochastic.peaks``; a peak near ``confidence`` may be
    missing from another record of the same length)."""

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
    note: str = ""
    explained_by: float = math.nan
    response_frequency: float = math.nan
    alternatives: tuple = field(default=(), compare=False)
    frequency_error: float = math.nan
    prominence_error: float = math.nan
    significance: float = math.nan

    def as_row(self) -> dict:
        """Plain dict for tables (CSV)."""
        return {"frequency_hz": self.frequency, "frequency_error_hz": self.frequency_error,
                "prominence_dec": self.prominence,
                "prominence_error_dec": self.prominence_error,
                "significance": self.significance,
                "kind": self.kind, "order": self.order,
                "branch_frequency_hz": self.branch_frequency,
                "stable": "" if self.stable is None else bool(self.stable),
                "distance_hz": self.distance, "tolerance_hz": self.tolerance,
                "xmax_m": self.xmax, "note": self.note,
                "explained_by_hz": self.explained_by}


# -- peaks of the PSD ----------------------------------------------------------------------
def _odd(n):
    n = max(int(n), 3)
    return n if n % 2 else n + 1


def find_peaks(psd, *, min_prominence=0.3, background_hz=20.0, tol_bins=2.0, f_range=None,
               dof=None, confidence=DEFAULT_CONFIDENCE):
    """Peaks of a PSD ``(f, P)`` against its running median in log10, by the significance
    rule of ``stochastic.peaks`` (``dof``: the Welch estimate's degrees of freedom, a number
    or one per bin; None: the measured scatter alone). Returns (indices, prominences in
    decades, half widths in Hz, background log10 P); ``significant_peaks`` gives the
    errors as well."""
    ps = significant_peaks(*psd, dof, min_prominence=min_prominence, confidence=confidence,
                           background_hz=background_hz, distance_bins=tol_bins,
                           f_range=f_range)
    return ps.index, ps.prominence, ps.half_width, ps.background


def welch_dof_of(result, ch):
    """The Welch degrees of freedom per bin of channel ``ch``'s PSD in a
    ``stochastic.StochasticResult`` (2 / relative_std^2), for ``map_peaks(dof=...)``; None
    when the result does not carry them (then the PSD's measured scatter is used alone)."""
    try:
        rs = np.asarray(result.psd_relative_std(ch), dtype=float)
    except (AttributeError, KeyError, ValueError, TypeError):
        return None
    if rs.ndim != 1 or rs.size == 0 or not np.all(np.isfinite(rs) & (rs > 0)):
        return None
    return 2.0 / rs ** 2


# -- resonances of the diagram -------------------------------------------------------------
def _stable_at(b, i):
    """Stability of branch point i; None when the diagram was computed without stability
    (``frequency_response(..., stability=False)`` leaves ``stable`` None)."""
    return None if b.stable is None else bool(np.asarray(b.stable)[i])


def resonances(frc, *, main_rel=0.15, max_superharmonic=5):
    """The points where the diagram's branches resonate (module doc), as Resonance list:
    order-1 and order-n points, and the superharmonic reading of order-1 points."""
    from scipy.signal import find_peaks as _fp

    out = []
    order1 = []
    for bi, b in enumerate(frc.branches):
        x = np.asarray(b.xmax, dtype=float)
        fr = np.asarray(b.frequency, dtype=float)
        if x.size < 3:
            continue
        pk, _ = _fp(np.r_[-np.inf, x, -np.inf], prominence=0.05 * np.max(x))
        pts = {int(i) - 1 for i in pk if 1 <= i - 1 <= x.size - 2}
        for bf in frc.bifurcations:
            if bf.kind == "fold" and int(bf.branch) == bi and bf.order == b.order:
                dist = np.abs(fr - bf.frequency) + np.abs(x - bf.xmax) / max(x.max(), 1e-300)
                pts.add(int(np.argmin(dist)))
        for i in sorted(pts):
            n = int(b.order)
            kind = "harmonic" if n == 1 else "subharmonic"
            r = Resonance(kind, n, float(fr[i]), float(fr[i]) / n, float(x[i]), _stable_at(b, i),
                          bi)
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
                                     _stable_at(b, i), int(s.branch)))
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
                    raise ValueError("excitation: band must satisfy 0 <= f_lo <= f_hi Hz, "
                                     f"got {ex!r}")
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

    def width_at(self, f, tol):
        """Width (Hz) of the narrowest band holding ``f``; inf for 'everything', None if
        nothing holds it."""
        if self.bands is None:
            return math.inf
        w = [hi - lo for lo, hi in self.bands if lo - tol <= f <= hi + tol]
        return min(w) if w else None


# -- the mapping ---------------------------------------------------------------------------
def map_peaks(psd, frc, excitation=None, *, min_prominence=0.3, background_hz=20.0,
              tol_bins=2.0, tolerance=None, asymmetry_below=None, f_range=None,
              max_superharmonic=5, max_multiple=8, dof=None, confidence=DEFAULT_CONFIDENCE):
    """Find the peaks of a response PSD ``psd = (f, P)`` and explain each by the periodic
    diagram ``frc`` (a ``continuation.FrequencyResponse``, or any object with ``branches``
    (order, frequency, xmax, stable), ``bifurcations`` (kind, frequency, xmax, order,
    branch) and ``superharmonics``). Returns a list of :class:`PeakMatch`, by frequency.
    The rule, tolerances and defaults are in the module doc; ``f_range`` (Hz, a pair lo <
    hi) limits the peaks considered; ``max_multiple``: the largest k of a multiple of a
    stronger peak; ``dof``: the Welch estimate's equivalent degrees of freedom (a number or
    one per bin, e.g. ``2 / result.psd_relative_std(ch) ** 2``; None: the PSD's measured
    scatter alone) and ``confidence`` (z): the significance test of ``stochastic.peaks``."""
    if tolerance is not None:
        tolerance = positive("tolerance", tolerance, unit="Hz")
    if f_range is not None:
        f_range = interval("f_range", f_range, lo=0.0, unit="Hz")
    integer("max_multiple", max_multiple, 1, 1000)
    integer("max_superharmonic", max_superharmonic, 1, 1000)
    positive("min_prominence", min_prominence)
    positive("background_hz", background_hz, unit="Hz")
    positive("tol_bins", tol_bins)
    if asymmetry_below is not None:
        nonnegative("asymmetry_below", asymmetry_below, unit="m")
    if isinstance(psd, (str, bytes, dict)) or not hasattr(psd, "__len__") or len(psd) != 2:
        raise ArgumentTypeError(f"psd: must be a pair (f Hz, P) of 1-D arrays, got "
                                f"{type(psd).__name__}")
    f = real_array("psd frequencies", psd[0], ndim=1, min_size=3, unit="Hz")
    P = real_array("psd values", psd[1], shape=(f.size,))
    if np.any(np.diff(f) <= 0):
        raise ValueError("psd frequencies: must be strictly increasing (sort (f, P) by f)")
    if not all(hasattr(frc, a) for a in ("branches", "bifurcations")):
        raise ArgumentTypeError(f"frc: must be a continuation.FrequencyResponse (branches, "
                                f"bifurcations), got {type(frc).__name__}")
    nonnegative("confidence", confidence)
    if dof is not None:
        dof = (real_array("dof", dof, shape=(f.size,)) if np.ndim(dof) else
               positive("dof", dof))
    ps = significant_peaks(f, P, dof, min_prominence=min_prominence, confidence=confidence,
                           background_hz=background_hz, distance_bins=tol_bins,
                           f_range=f_range)
    df = float(np.median(np.diff(f)))
    holds = _Holds(excitation)
    res = resonances(frc, max_superharmonic=max_superharmonic)
    harm = [r for r in res if r.kind == "harmonic"]
    if asymmetry_below is None:
        main = max(harm, key=lambda r: r.xmax) if harm else (min(res, key=lambda r: r.response)
                                                             if res else None)
        asymmetry_below = main.response / 3.0 if main is not None else 0.0
    peaks = []
    for i, pr, hw, fe, pe, z in zip(ps.index, ps.prominence, ps.half_width,
                                    ps.frequency_error, ps.prominence_error, ps.significance):
        tol = tolerance if tolerance is not None else max(tol_bins * df, float(hw), float(fe))
        peaks.append(dict(frequency=float(f[i]), prominence=float(pr), tolerance=float(tol),
                          psd=float(P[i]), frequency_error=float(fe), prominence_error=float(pe),
                          significance=float(z)))
    explained = []  # (PeakMatch) of steps 1 and 3: the parents of multiples
    out = []
    for pk in sorted(peaks, key=lambda p: -p["psd"]):  # strongest first
        m = (_resonance_match(pk, res, holds)
             or _multiple_match(pk, explained, max_multiple)
             or _forced_match(pk, frc, holds, background_hz))
        if m is None:
            fp, tol = pk["frequency"], pk["tolerance"]
            kind = "asymmetry" if fp <= asymmetry_below and holds.width >= fp - tol \
                else "unexplained"
            m = PeakMatch(kind=kind, order=0, branch_frequency=math.nan, stable=None,
                          distance=math.nan, **pk)
        elif m.note in ("resonance", "forced"):
            explained.append(m)
        out.append(m)
    return sorted(out, key=lambda m: m.frequency)


def _resonance_match(pk, res, holds):
    """Step 1 of the rule: the closest resonance of the first kind that explains the peak."""
    fp, tol = pk["frequency"], pk["tolerance"]
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
    if not cands:
        return None
    cands.sort(key=lambda c: (c[0], c[1]))
    _, d, r = cands[0]
    alts = tuple((c[2].kind, c[2].order, c[2].frequency, c[1]) for c in cands[1:])
    return PeakMatch(kind=r.kind, order=r.order, branch_frequency=r.frequency, stable=r.stable,
                     distance=float(d), branch=r.branch, xmax=r.xmax, note="resonance",
                     response_frequency=r.response, alternatives=alts, **pk)


def _multiple_match(pk, parents, max_multiple):
    """Step 2: k times a stronger explained peak (the strongest such parent)."""
    fp, tol = pk["frequency"], pk["tolerance"]
    cands = []
    for q in parents:
        if not (q.psd > pk["psd"] and q.frequency > 0):
            continue
        k = int(round(fp / q.frequency))
        if not 2 <= k <= max_multiple:
            continue
        d = abs(fp - k * q.frequency)
        if d <= tol:
            cands.append((-q.psd, d, k, q))
    if not cands:
        return None
    cands.sort(key=lambda c: (c[0], c[1]))
    _, d, k, q = cands[0]
    alts = tuple(("superharmonic", c[2], c[3].frequency, c[1]) for c in cands[1:])
    return PeakMatch(kind="superharmonic", order=k, branch_frequency=q.branch_frequency,
                     stable=q.stable, distance=float(d), branch=q.branch, xmax=q.xmax,
                     note="multiple", explained_by=q.frequency,
                     response_frequency=k * q.frequency, alternatives=alts, **pk)


def _forced_match(pk, frc, holds, background_hz):
    """Step 3: inside a band no wider than the background window: the order-1 response."""
    fp, tol = pk["frequency"], pk["tolerance"]
    w = holds.width_at(fp, tol)
    if w is None or w > background_hz:
        return None
    best = None
    for bi, b in enumerate(frc.branches):
        if int(b.order) != 1:
            continue
        fr = np.asarray(b.frequency, dtype=float)
        if fr.size == 0:
            continue
        i = int(np.argmin(np.abs(fr - fp)))
        d = abs(float(fr[i]) - fp)
        st = _stable_at(b, i)
        if d <= tol and (best is None or (d, st is not True) < (best[0], best[3] is not True)):
            best = (d, bi, i, st)
    if best is None:
        return PeakMatch(kind="harmonic", order=1, branch_frequency=math.nan, stable=None,
                         distance=math.nan, note="forced", **pk)
    d, bi, i, st = best
    b = frc.branches[bi]
    fb = float(np.asarray(b.frequency)[i])
    return PeakMatch(kind="harmonic", order=1, branch_frequency=fb, stable=st,
                     distance=float(d), branch=bi, xmax=float(np.asarray(b.xmax)[i]),
                     note="forced", response_frequency=fb, **pk)
