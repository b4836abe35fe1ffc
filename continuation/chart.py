"""A stability chart: the bifurcation curves of a diagram's folds, period doublings,
Neimark-Sacker and grazing points over a range of a second parameter (the excitation amplitude
first), and the order of the stable periodic response at a grid of points, for labelling the
regions where orders 1, 2, 3 are stable.

Front door: ``stability_chart``. Units: Hz, m (N for force excitation).
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

import nlbeam

from ._newton import ContinuationWarning, ConvergenceError
from .curve import bifurcation_curve
from .diagram import frequency_response
from nlbeam.solver import period_step

from .shooting import Integrator, forcing, steady_state


@dataclass
class StabilityChart:
    """Bifurcation curves in (frequency, parameter) and region labels.

    curves: BifurcationCurve list; parameter: the second parameter ('amplitude'); amplitude:
    the reference diagram's amplitude (m or N) the curves start from; f_range (Hz), p_range;
    label_frequency, label_value (k,): the grid points where the attractor reached from rest
    was classified, label_order (k,): its order (1, 2, 3, ...; 0: none of order <= 6 found,
    e.g. irregular); skipped: one line per bifurcation whose curve was not started
    ('not started: ...', why and what to try) or was traced in part ('traced in part:
    ...', the ends);
    model_parameters, settings, n_evaluations (shooting evaluations of all curves),
    wall_time (s)."""

    curves: list
    parameter: str
    amplitude: float
    f_range: tuple
    p_range: tuple
    label_frequency: np.ndarray = field(default_factory=lambda: np.zeros(0))
    label_value: np.ndarray = field(default_factory=lambda: np.zeros(0))
    label_order: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    skipped: list = field(default_factory=list)
    model_parameters: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    n_evaluations: int = 0
    wall_time: float = 0.0
    version: str = nlbeam.__version__

    def save(self, path):
        """Write to HDF5 (nlbeam.app.files.curves_hdf5; atomically)."""
        from nlbeam.app.files.curves_hdf5 import save_curves

        save_curves(self, path)


def attractor_order(model, amplitude, frequency, *, integrator=None, max_order=6, tol=1e-6):
    """The order n (period n / f) of the periodic attractor reached from rest at this
    amplitude (m or N) and frequency (Hz): the smallest n <= max_order such that the states at
    the next 2 max_order excitation periods repeat after n periods to ``tol`` (relative to the
    orbit's size); tried after 8, 16, 24, 32 decay times of the linear structure; 0 when none
    does (irregular, a higher order, or a transient slower than that)."""
    integrator = integrator or Integrator()
    ex = forcing(amplitude, frequency)
    N = model.n_dof
    s = steady_state(model, amplitude, frequency, integrator=integrator)
    for _ in range(4):  # until the state repeats: 8 more decay times of the structure each
        # the same discrete flow as steady_state (its step): one sample per period
        spp = integrator.steps_per_period(model, frequency)
        tr = integrator.integrate(model, ex, 2 * max_order / frequency,
                                  period_step(frequency, spp or 1), x0=s,
                                  store_every=spp or 1)
        S = np.hstack([tr.x, tr.v])
        scale = np.r_[np.full(N, max(np.abs(S[:, :N]).max(), 1e-300)),
                      np.full(N, max(np.abs(S[:, N:]).max(), 1e-300))]
        for n in range(1, max_order + 1):  # n-periodic over all 2 max_order periods
            if np.max(np.abs(S[n:] - S[:-n]) / scale) < tol:
                return n
        s = steady_state(model, amplitude, frequency, x0=S[-1], integrator=integrator)
    return 0


def _same_locus(c, bf):
    """True when bifurcation bf lies on the locus of curve c by its kind and order alone: the
    same kind and order, or a fold of twice the order of a period-doubling curve (its doubled
    orbit's multiplier (-1)^2 = 1)."""
    return (c.kind == bf.kind and c.order == bf.order) or (
        bf.kind == "fold" and c.kind == "period-doubling" and 2 * c.order == bf.order)


def _repeated(c, bf, amplitude, rel, state_rel=1e-5):
    """True when bf (order m c.order, m >= 2) is a bifurcation of c's own orbit taken m times
    round (a branch of the higher order along an orbit of c's order: the same frequency, the
    same state at t = 0 to ``state_rel`` of its size), whose multipliers are c's to the
    power m: fold -> fold, grazing -> grazing, period doubling -> period doubling (m odd) or
    fold (m even), Neimark-Sacker -> Neimark-Sacker. Measured on the paper chart (A = 0.1 mm):
    four order-2 fold curves of order-1 orbits near 9.2-9.9 Hz, the same curves as the
    order-1 ones (states equal to 3e-11), about 2000 shooting evaluations each."""
    m, r = divmod(bf.order, c.order)
    if m < 2 or r or bf.state0 is None:
        return False
    kind = c.kind
    if kind == "period-doubling" and m % 2 == 0:
        kind = "fold"
    if kind != bf.kind:
        return False
    s0 = np.asarray(bf.state0, dtype=float)
    i = np.flatnonzero(c.exact & (np.abs(c.values - amplitude) <= 1e-9 * amplitude))
    for j in i:
        s = c.state0[j]
        if (abs(c.frequency[j] - bf.frequency) <= rel * bf.frequency and s.shape == s0.shape
                and np.max(np.abs(s - s0)) <= state_rel * max(np.max(np.abs(s)), 1e-300)):
            return True
    return False


def _duplicate(curves, bf, amplitude, rel=1e-4):
    """A traced curve that already passes through this bifurcation at the reference amplitude
    (_same_locus, or _repeated: the same orbit taken several times round), or None."""
    for c in curves:
        if _same_locus(c, bf) and np.any(np.abs(c.at(amplitude) - bf.frequency)
                                         <= rel * bf.frequency):
            return c
        if _repeated(c, bf, amplitude, rel):
            return c
    return None


def stability_chart(model, p_range, f_range, orders=(1, 2, 3), *, amplitude=None,
                    kinds=("fold", "period-doubling", "neimark-sacker", "grazing"),
                    diagram=None, label_grid=(16, 6), integrator=None, max_points=150,
                    ds_max=0.3, max_evaluations=1000, progress=None, **integrator_kw):
    """The stability chart of ``model`` in (frequency, amplitude).

    p_range: (A_lo, A_hi) amplitudes (m or N, > 0); f_range: (f_lo, f_hi) Hz. A frequency
    diagram at the reference ``amplitude`` (default: the geometric mean of p_range), or the
    one given as ``diagram``, supplies the starts: every located bifurcation of a kind in
    ``kinds`` on a branch of an order in ``orders`` that no curve traced so far passes through
    (continuation.bifurcation_curve, each followed both ways until it leaves the ranges, at
    most ``max_points`` points and ``max_evaluations`` shooting evaluations per curve and
    direction: a curve that reaches either is kept as far as it got, and listed in the
    warning; bifurcation_curve with max_evaluations=None extends it). A fold or period
    doubling located at a grazing point (non-smooth) is represented by the grazing curve
    there; one of an orbit of a lower order taken several times round (a branch of order 2
    along an order-1 orbit) by that order's curve (_duplicate). label_grid: (n_f, n_A) grid
    points (log-spaced) where the attractor reached from rest is classified by its order
    (attractor_order); (0, 0) for none. progress: callable(str) or None. Returns a
    StabilityChart; one ContinuationWarning lists the starts that could not be traced.
    """
    t0 = time.perf_counter()
    integrator = integrator or Integrator(**integrator_kw)
    try:
        a_lo, a_hi = map(float, p_range)
    except (TypeError, ValueError):
        raise ValueError(f"p_range: must be (A_lo, A_hi) with 0 < A_lo < A_hi, got "
                         f"{p_range!r}") from None
    if not (0 < a_lo < a_hi and math.isfinite(a_hi)):
        raise ValueError(f"p_range: must be (A_lo, A_hi) with 0 < A_lo < A_hi, got {p_range!r}")
    try:
        f_lo, f_hi = map(float, f_range)
    except (TypeError, ValueError):
        raise ValueError(f"f_range: must be (f_lo, f_hi) Hz, got {f_range!r}") from None
    if not (0 < f_lo < f_hi and math.isfinite(f_hi)):
        raise ValueError(f"f_range: must be (f_lo, f_hi) with 0 < f_lo < f_hi Hz, got "
                         f"{f_range!r}")
    bad = set(kinds) - {"fold", "period-doubling", "neimark-sacker", "grazing"}
    if bad:
        raise ValueError(f"kinds: must be among 'fold', 'period-doubling', 'neimark-sacker', "
                         f"'grazing', got {sorted(bad)}")
    try:
        n_f, n_a = (int(v) for v in label_grid)
    except (TypeError, ValueError):
        raise ValueError(f"label_grid: must be (n_f, n_A), integers >= 0, got "
                         f"{label_grid!r}") from None
    if n_f < 0 or n_a < 0:
        raise ValueError(f"label_grid: must be (n_f, n_A), integers >= 0, got {label_grid!r}")
    A0 = math.sqrt(a_lo * a_hi) if amplitude is None else float(amplitude)
    if diagram is not None:
        A0 = float(diagram.amplitude)
    if not a_lo <= A0 <= a_hi:
        raise ValueError(f"amplitude: the reference amplitude must lie in p_range {p_range!r}, "
                         f"got {A0!r}")
    frc = diagram
    if frc is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ContinuationWarning)
            frc = frequency_response(model, A0, (f_lo, f_hi), orders, integrator=integrator,
                                     accuracy="off")
        if progress:
            progress(f"diagram at {A0:.4g}: {len(frc.bifurcations)} bifurcations "
                     f"({time.perf_counter() - t0:.1f} s)")
    curves, skipped, partial = [], [], []
    advice = {}  # why a start failed and what to try -> the starts
    n_eval = 0
    for bf in frc.bifurcations:
        if bf.kind not in kinds or bf.order not in orders:
            continue
        if not bf.smooth:
            continue  # its grazing point stands for it
        if _duplicate(curves, bf, A0) is not None:
            continue
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", ContinuationWarning)
                c = bifurcation_curve(model, bf, (a_lo, a_hi), amplitude=A0,
                                      f_range=(f_lo, f_hi), at=(A0,) if a_lo < A0 < a_hi else (),
                                      integrator=integrator, max_points=max_points,
                                      ds_max=ds_max, error=False,
                                      max_evaluations=max_evaluations)
        except (ConvergenceError, nlbeam.IntegrationError) as exc:
            skipped.append(f"not started: {bf.kind} (order {bf.order}) at {bf.frequency:.6g} "
                           f"Hz: {exc}")
            advice.setdefault(getattr(exc, "advice", "see the messages above"), []).append(
                f"{bf.kind} (order {bf.order}) at {bf.frequency:.6g} Hz")
            continue
        if caught:
            skipped.append(f"traced in part: {bf.kind} (order {bf.order}) at "
                           f"{bf.frequency:.6g} Hz ({', '.join(c.ends)})")
            partial.append(f"{bf.kind} (order {bf.order}) at {bf.frequency:.6g} Hz "
                           f"({', '.join(c.ends)})")
        n_eval += c.n_evaluations
        curves.append(c)
        if progress:
            progress(f"{bf.kind} (order {bf.order}) from {bf.frequency:.4f} Hz: "
                     f"{len(c.frequency)} points, ends {c.ends} "
                     f"({time.perf_counter() - t0:.1f} s)")
    lf, la, lo = [], [], []
    if n_f and n_a:
        for A in np.geomspace(a_lo, a_hi, n_a + 2)[1:-1]:
            for f in np.geomspace(f_lo, f_hi, n_f + 2)[1:-1]:
                lf.append(f)
                la.append(A)
                lo.append(attractor_order(model, A, f, integrator=integrator))
        if progress:
            progress(f"labels: {len(lf)} attractors ({time.perf_counter() - t0:.1f} s)")
    if skipped:
        msg = []
        for why, starts in advice.items():
            msg.append(f"{len(starts)} curves not started ({'; '.join(starts)}): {why}")
        if partial:
            msg.append(f"{len(partial)} curves traced in part ({'; '.join(partial)}): try a "
                       "smaller ds_max, a larger max_evaluations (None: no limit), more "
                       "max_points, or bifurcation_curve on that point with segments=4")
        warnings.warn("stability_chart: " + ". ".join(msg) + " (StabilityChart.skipped: "
                      "one line each)", ContinuationWarning, stacklevel=2)
    return StabilityChart(
        curves=curves, parameter="amplitude", amplitude=A0, f_range=(f_lo, f_hi),
        p_range=(a_lo, a_hi), label_frequency=np.array(lf), label_value=np.array(la),
        label_order=np.array(lo, dtype=int), skipped=skipped,
        model_parameters=model.parameters(),
        settings={"orders": ",".join(str(o) for o in orders), "kinds": ",".join(kinds),
                  "max_points": max_points, "ds_max": ds_max, "method": integrator.method,
                  "dt_scale": integrator.dt_scale},
        n_evaluations=n_eval, wall_time=time.perf_counter() - t0)
