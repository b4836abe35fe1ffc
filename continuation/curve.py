"""Bifurcation curves in two parameters: the locus of a fold, period doubling, Neimark-Sacker
or grazing point as the frequency and a second parameter vary, by pseudo-arclength
continuation of the extended shooting system (continuation.extended), with the
codimension-2 points met on the way.

Front door: ``bifurcation_curve``. Units: Hz, m (N for force excitation).
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

import nlbeam

from nlbeam.parameters import check_parameter, get_parameter, parameter_names, with_parameter

from nlbeam import _linalg as la
from ._newton import ContinuationWarning, ConvergenceError
from .extended import KINDS, CurveSystem
from .pathfollow import test_functions
from .shooting import Integrator

#: steps accepted in a row after which the extended system's test-function row over the states
#: is again taken from one evaluation (CurveSystem.row_from_one; _Tracer.trace)
SMOOTH_STEPS = 10
#: a trace ends 'corrector-limited' when over its last SLOW_STEPS accepted steps the mean step
#: stayed below SLOW_DS of the first step and the corrector failed at least SLOW_FAILS times,
#: SLOW_FAILS // 2 of them in the last SLOW_STEPS // 3 steps (not a step growing again after a
#: sharp turn such as a cusp), while the tangent's part in the (log f, q) plane is at least
#: half its largest over those steps (not turning out of the plane: the approach to a cusp or
#: a turn, where steps are short too) (_Tracer.trace): a stretch where the extended system is
#: not smooth at the step's scale (the paper chart's chattering orbits near 9-10.3, 66-67,
#: 110-111 Hz)
SLOW_STEPS, SLOW_DS, SLOW_FAILS = 20, 0.2, 5
#: a trace that has not accepted a single step when its first step has been halved
#: START_HALVINGS times ends 'step underflow' there (_Tracer.trace): its start lies where the
#: extended system is not smooth at any step's scale (the paper chart's order-2 and order-3
#: fold and period-doubling starts at a grazing point near 67.7 and 111.7 Hz, and the order-2
#: grazing curve from 9.334 Hz, ran all 16 halvings from ds = 0.05 down to ds_min = 1e-6 for
#: no point; every trace of that chart that moved at all got its first converged step after at
#: most 9 failed corrector calls, i.e. at most 9 halvings; the chart is bit for bit the same
#: with 1339 of its 100460 evaluations saved)
START_HALVINGS = 10
CODIM2 = ("cusp", "fold-flip", "fold-grazing", "flip-grazing", "neimark-sacker-grazing")


@dataclass
class Codim2:
    """A codimension-2 point met on a curve. kind: 'cusp' (two fold curves meet: the fold
    curve turns back in both parameters), 'fold-flip' (a multiplier +1 and one -1),
    'fold-grazing' / 'flip-grazing' / 'neimark-sacker-grazing' (the curve meets a grazing
    curve: the number of impacts per period changes along it; on a grazing curve, a multiplier
    crosses +1 / -1 there). frequency (Hz), value (second parameter); error_frequency,
    error_value: half the width of the final bracket along the curve (regula falsi on the
    test function; bisection for a change of impacts) plus, for a fold-flip or a fold / flip
    point on a grazing curve located with error=True, twice its move when it is located
    again with both steps halved (the integration error); (for a cusp also the
    distance between where the curve turns in frequency and where it turns in the second
    parameter); index: the curve point before it."""

    kind: str
    frequency: float
    value: float
    error_frequency: float
    error_value: float
    index: int
    note: str = ""


@dataclass
class BifurcationCurve:
    """The locus of one bifurcation in (frequency, parameter). kind: as the start's
    ('fold', 'period-doubling', 'neimark-sacker', 'grazing'); order: of the orbits (period
    order / f); parameter: the second parameter's name; frequency (n,) Hz; values (n,) of the
    second parameter; amplitude (n,) m or N; xmax (n,) m of the orbit there; multipliers
    (n, 2N) complex (largest modulus first); state0 (n, 2N) the orbit's state at t = 0;
    phase (n,) the grazing contact's excitation phase (periods; NaN for other kinds);
    n_impacts (n,) contact onsets per period; exact (n,) bool: the point was placed at a
    requested value (``at`` or a range end) exactly; error (n,): the estimated integration
    error of the frequency (Hz) at the start and the ``at`` points (twice its change when the
    point is located again with both steps halved; NaN elsewhere or when not estimated);
    special: the Codim2 points met;
    ends: why the trace stopped at the first and the last point ('left the frequency range',
    'left the parameter range', 'closed', 'step underflow', 'max_points',
    'max_evaluations', 'corrector-limited: ...' (SLOW_STEPS; the message gives where));
    n_evaluations: shooting evaluations; wall_time (s)."""

    kind: str
    order: int
    parameter: str
    frequency: np.ndarray
    values: np.ndarray
    amplitude: np.ndarray
    xmax: np.ndarray
    multipliers: np.ndarray
    state0: np.ndarray
    phase: np.ndarray
    n_impacts: np.ndarray
    exact: np.ndarray
    error: np.ndarray | None = None
    special: list = field(default_factory=list)
    ends: tuple = ("", "")
    f_range: tuple = (0.0, 0.0)
    p_range: tuple = (0.0, 0.0)
    model_parameters: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    n_evaluations: int = 0
    wall_time: float = 0.0
    version: str = nlbeam.__version__

    def at(self, value, rel=1e-9):
        """Frequencies (Hz) of the curve's points placed exactly at this second-parameter
        value (requested with ``at=``; a curve may cross a value more than once)."""
        return self.frequency[self._at(value, rel)]

    def error_at(self, value, rel=1e-9):
        """The error estimates (Hz) of the frequencies ``at(value)``."""
        return self.error[self._at(value, rel)]

    def _at(self, value, rel):
        return self.exact & (np.abs(self.values - value) <= rel * abs(value))

    def save(self, path):
        """Write to HDF5 (nlbeam.app.files.curves_hdf5; atomically)."""
        from nlbeam.app.files.curves_hdf5 import save_curves

        save_curves(self, path)


def load_curves(path):
    """Read a BifurcationCurve or a StabilityChart written by their ``save``."""
    from nlbeam.app.files.curves_hdf5 import load_curves as _load

    return _load(path)


# --- the tracer ---------------------------------------------------------------------------------
@dataclass
class _Pt:
    st: object  # CurveState
    t: np.ndarray  # unit tangent in the direction of travel
    exact: bool = False
    frequency: float = 0.0
    value: float = 0.0
    state0: np.ndarray | None = None
    phase: float = float("nan")


def _tangent(J, t_prev):
    A = np.vstack([J, t_prev[None, :]])
    rhs = np.zeros(A.shape[0])
    rhs[-1] = 1.0
    t = la.solve(A, rhs)
    return t / la.norm(t)


def _null(J):
    """A unit null vector of J (D - 1, D)."""
    return la.null_vector(J)


class _Tracer:
    def __init__(self, sysm, f_range, p_range, at, ds, ds_min, ds_max, max_angle, max_points,
                 tol, max_iter):
        self.s = sysm
        self.f_range, self.p_range = f_range, p_range
        self.at = sorted(at)
        self.ds0, self.ds_min, self.ds_max = ds, ds_min, ds_max
        self.cos_max = math.cos(max_angle)
        self.max_points = max_points
        self.tol = tol
        self.max_iter = max_iter
        self.max_evaluations = None

    # corrector: Newton on G(z) = 0 with one more equation c(z) = 0 (linear: row . z = rhs)
    def correct(self, z, row, rhs, J=None, jac=True, radius=None, max_renewals=None):
        """Newton on G(z) = 0 with the linear condition row . z = rhs; a quasi-Newton
        iteration from the Jacobian J given (the previous point's) with Broyden's rank-one
        updates, the Jacobian renewed when an iterate does not halve the residual (given up
        after ``max_renewals`` renewals: the predictor is too far for the step to pay; or when
        an iterate lies farther than ``radius`` from the prediction z, scaled). Returns
        (CurveState at the solution, with its Jacobian unless jac=False; iterations)."""
        s = self.s
        res_prev = np.inf
        A = None if J is None else np.vstack([J, row[None, :]])
        fresh = J is None
        F_prev = dz = None
        z_first = z
        renewals = 0
        renewed = False  # a Jacobian was computed in this call
        for it in range(self.max_iter):
            st = s.evaluate(z, jac=A is None)
            F = np.r_[st.G, la.dot(row, z) - rhs]
            if A is None:
                A, fresh = np.vstack([st.J, row[None, :]]), True
                renewed = True
            elif dz is not None:
                A = A + np.outer(F - F_prev - la.matmul(A, dz), dz) / la.dot(dz, dz)  # Broyden
            res = float(np.max(np.abs(F)))
            if not np.isfinite(res):
                break
            if res <= self.tol:
                if st.J is None and jac and renewed:
                    # a Jacobian computed in this call, updated since: good enough for the
                    # tangent and the next corrector (saves D evaluations per point)
                    st.J = A[:-1].copy()
                return (st if st.J is not None or not jac else s.evaluate(z)), it
            if not fresh and res > 0.5 * res_prev:
                renewals += 1
                if max_renewals is not None and renewals > max_renewals:
                    break  # stalls with a fresh Jacobian too: the step was too long
                A, dz = None, None  # stalls: a new Jacobian here
                continue
            res_prev = res
            try:
                step = la.solve(A, -F)
            except np.linalg.LinAlgError:
                break
            fresh = False
            # damped: at most 0.5 in the scaled states, 2 % in frequency, 0.1 in q, a
            # fiftieth of a period in the grazing phase (far off: no wild jumps)
            c = min(1.0, 0.5 / max(np.max(np.abs(step[:s.n])), 1e-300),
                    0.02 / max(abs(step[s.n]), 1e-300), 0.1 / max(abs(step[s.n + 1]), 1e-300),
                    0.02 / max(abs(step[-1]), 1e-300) if s.grazing else 1.0)
            dz = c * step
            z = z + dz
            F_prev = F
            if radius is not None and la.norm(z - z_first) > radius:
                break  # wandering off the prediction (towards a neighbouring curve)
        raise ConvergenceError(f"{s.kind} curve: corrector did not converge near "
                               f"{s.point(z)[0]:.9g} Hz, {s.parameter} = {s.point(z)[1]:.6g}")

    def make_point(self, st, t, exact=False):
        s = self.s
        f, p = s.point(st.z)
        s0, _ = s.state_at_zero(st.z)
        return _Pt(st, t, exact, f, p, s0, float(st.z[-1]) if s.grazing else float("nan"))

    def start(self, direction):
        """The start solved at the given second-parameter value; tangent oriented so the
        second parameter moves in ``direction`` (+1 / -1) (or, when the curve starts
        perpendicular to it, the frequency)."""
        s = self.s
        s.row_from_one = True
        z0 = s.z0
        try:  # at the start's second-parameter value
            row = np.zeros(s.D)
            row[s.n + 1] = 1.0
            st, _ = self.correct(z0, row, z0[s.n + 1])
        except ConvergenceError:
            # a curve along the frequency axis (the locus does not depend on the frequency,
            # e.g. a linear structure's flutter): at the start's frequency instead
            row = np.zeros(s.D)
            row[s.n] = 1.0
            st, _ = self.correct(z0, row, z0[s.n])
        t = _null(st.J)
        k = s.n + 1 if abs(t[s.n + 1]) > 1e-8 else s.n
        if np.sign(t[k]) != direction:
            t = -t
        return self.make_point(st, t, exact=True)

    def _bounds(self, z):
        """Signed distances (in q units) of z inside the ranges (negative: outside)."""
        s = self.s
        lf, hf = (math.log(v) for v in self.f_range)
        lq, hq = (s.q_of(v) for v in self.p_range)
        return z[s.n] - lf, hf - z[s.n], z[s.n + 1] - lq, hq - z[s.n + 1]

    def _cross_targets(self, a, b):
        """(coordinate index, target q value, reason) of the first range end or requested
        value crossed from point a to point b, or None."""
        s = self.s
        za, zb = a.st.z, b.st.z
        hits = []
        lf, hf = (math.log(v) for v in self.f_range)
        lq, hq = (s.q_of(v) for v in self.p_range)
        for k, lim, why in ((s.n, lf, "left the frequency range"),
                            (s.n, hf, "left the frequency range"),
                            (s.n + 1, lq, "left the parameter range"),
                            (s.n + 1, hq, "left the parameter range")):
            if (za[k] - lim) * (zb[k] - lim) < 0 or (zb[k] == lim != za[k]):
                hits.append(((lim - za[k]) / (zb[k] - za[k]), k, lim, why))
        for v in self.at:
            q = s.q_of(v)
            if (za[s.n + 1] - q) * (zb[s.n + 1] - q) < 0:
                hits.append(((q - za[s.n + 1]) / (zb[s.n + 1] - za[s.n + 1]), s.n + 1, q, ""))
        if not hits:
            return None
        return min(hits)[1:]

    def _next_ds(self, ds, it, cos_turn):
        """The next step from the last one's corrector iterations and the angle the tangent
        turned: the step is scaled so the tangent turns by about a third of max_angle
        (at most doubled, at least halved); shrunk when the quasi-Newton corrector needed 9
        iterations or more, not grown when it needed more than 7 (it converges linearly:
        5-7 iterations are its usual count, which a count-only rule read as too slow)."""
        turn = math.acos(min(1.0, max(-1.0, cos_turn)))
        target = math.acos(self.cos_max) / 3.0
        factor = min(2.0, max(0.5, target / max(turn, 1e-3)))
        if it >= 9:
            factor = min(factor, 0.6)
        elif it > 7:
            factor = min(factor, 1.0)
        return min(max(ds * factor, self.ds_min), self.ds_max)

    def _closes(self, p0, a, b, ds):
        """The step a -> b passes the start p0 again: in the (log f, q) plane the step crosses
        the line through p0 normal to p0's tangent within a step length of p0, and the orbit's
        state at t = 0 there is p0's (to 2 ds + 1e-3 of its size). In the plane, not in all
        unknowns: after ``adapt`` the shooting states of the same orbit are not the start's."""
        k = slice(self.s.n, self.s.n + 2)
        t0 = p0.t[k]
        if la.norm(t0) < 1e-12:
            return False
        da, db = a.st.z[k] - p0.st.z[k], b.st.z[k] - p0.st.z[k]
        if la.dot(da, t0) * la.dot(db, t0) > 0 or min(la.norm(da), la.norm(db)) > ds:
            return False
        near = a if la.norm(da) < la.norm(db) else b
        size = max(float(np.max(np.abs(p0.state0))), 1e-300)
        # the nearest point lies within a step of the start (a step moves the scaled
        # unknowns by ds): its state within twice that
        return float(np.max(np.abs(near.state0 - p0.state0))) <= (2 * ds + 1e-3) * size

    def _slow_end(self, pts, last):
        """The end reason of a trace whose steps the corrector limits (SLOW_STEPS): where."""
        f = [p.frequency for p in pts[-SLOW_STEPS:]]
        v = [p.value for p in pts[-SLOW_STEPS:]]
        return (f"corrector-limited: {sum(x[1] for x in last)} failures in {SLOW_STEPS} steps, "
                f"{min(f):.6g}-{max(f):.6g} Hz, {self.s.parameter} {min(v):.4g}-{max(v):.4g}")

    def trace(self, p0, on_step):
        """Points from p0 (excluded) on, and the reason the trace stopped. on_step(a, b):
        called for each accepted step (codimension-2 detection). The predictor is the
        parabola that leaves the last point along its tangent and passes through the point
        before it (the tangent alone where there is none: the start, a rephased problem);
        its error is third order in the step, against second order for the tangent alone,
        so the quasi-Newton corrector starts closer and longer steps converge. Not on a
        grazing curve: there the longer steps it allows stepped over a fold-grazing point
        (a sign change of the free-side multipliers' fold test between two points;
        tests/continuation/test_fold_grazing_exact.py)."""
        s = self.s
        pts = []
        a = p0
        prev = None  # the point before a (scaled unknowns), for the quadratic predictor
        quad = True  # the quadratic predictor was the closer one on the last step
        ds = self.ds0
        ds_fail = None  # the last step that failed (growth stays below it for a while)
        n0 = s.n_evaluations
        z_start = p0.st.z
        accepted = 0  # steps accepted since the last failure
        slow = []  # per accepted step: (its step, corrector failures before it)
        fails = 0
        s.row_from_one = True
        while True:
            if len(pts) >= self.max_points:
                return pts, "max_points"
            if self.max_evaluations and s.n_evaluations - n0 >= self.max_evaluations:
                return pts, "max_evaluations"
            z_pred = a.st.z + ds * a.t
            bend = None
            if prev is not None and len(prev) == len(a.st.z) and not s.grazing:
                # quadratic predictor: the parabola along the tangent through the last
                # point back to the one before (the curvature term, if it is small)
                h = la.norm(a.st.z - prev)
                if h > 0:
                    bend = ds * ds * (prev - a.st.z + h * a.t) / h ** 2
                    if la.norm(bend) >= 0.5 * ds:
                        bend = None
            if bend is not None and quad:
                z_pred = z_pred + bend
            try:
                # impatient (one renewal) while the step is long, patient when it is short:
                # a step that fails is cheaper halved than iterated on, but a short step
                # next to a corner needs the iterations (else the trace ends in underflow)
                st, it = self.correct(z_pred, a.t, la.dot(a.t, z_pred), a.st.J,
                                      radius=2 * ds + 0.01,
                                      max_renewals=1 if ds > 0.1 * self.ds0 else None)
                t = _tangent(st.J, a.t)
                if la.dot(t, a.t) < self.cos_max:
                    raise ConvergenceError("angle")
            except ConvergenceError:
                if (s.one_row_kind and s.row_from_one and a.st.J is not None
                        and len(a.st.z) == s.D):
                    # the test function's row from one evaluation assumes a smooth flow
                    # (symmetric second derivatives); where a step fails (a non-smooth,
                    # e.g. chattering, stretch) the point's Jacobian and tangent again with
                    # one difference per unknown, and the step retried; back to the one
                    # evaluation after SMOOTH_STEPS steps accepted in a row
                    s.row_from_one = False
                    accepted = 0
                    st_a = s.evaluate(a.st.z)
                    a = replace(a, st=st_a, t=_tangent(st_a.J, a.t))
                    continue
                ds_fail = ds
                ds *= 0.5
                accepted = 0
                fails += 1
                if ds < self.ds_min or (not pts and ds < self.ds0 * 0.5 ** START_HALVINGS):
                    return pts, "step underflow"
                continue
            accepted += 1
            # (step, failures before it, the tangent's length in the (log f, q) plane)
            slow.append((ds, fails, la.norm(t[s.n:s.n + 2])))
            fails = 0
            if len(slow) >= SLOW_STEPS:
                last = slow[-SLOW_STEPS:]
                if (sum(v[0] for v in last) < SLOW_DS * self.ds0 * SLOW_STEPS
                        and sum(v[1] for v in last) >= SLOW_FAILS
                        and sum(v[1] for v in last[-(SLOW_STEPS // 3):]) >= SLOW_FAILS // 2
                        and last[-1][2] >= 0.5 * max(v[2] for v in last)):
                    return pts, self._slow_end(pts, last)
            if accepted >= SMOOTH_STEPS:
                s.row_from_one = True
            b = self.make_point(st, t)
            if bend is not None:
                # the predictor for the next step: the one that came closer on this one
                # (on a smooth curve the parabola; where the curve bends at kinks, e.g.
                # along a grazing curve, the tangent may)
                z_tan = a.st.z + ds * a.t
                quad = (la.norm(st.z - z_tan - bend) < la.norm(st.z - z_tan))
            hit = self._cross_targets(a, b)
            if hit is not None:
                k, q, why = hit
                row = np.zeros(s.D)
                row[k] = 1.0
                try:
                    st2, _ = self.correct(a.st.z + (q - a.st.z[k]) / (b.st.z[k] - a.st.z[k])
                                          * (b.st.z - a.st.z), row, q, b.st.J)
                    b = self.make_point(st2, _tangent(st2.J, a.t), exact=True)
                except ConvergenceError:
                    if ds > 0.1 * self.ds0:
                        # the chord's interpolation too far from the curve (a long step on
                        # a bending curve): the step again, shorter
                        ds_fail = ds
                        ds *= 0.5
                        continue
                    if why:
                        return pts, why
                    # a requested value not placed exactly: keep the plain step
                else:
                    on_step(a, b, len(pts))
                    pts.append(b)
                    if why:
                        return pts, why
                    prev, a = a.st.z, b
                    continue
            if min(self._bounds(b.st.z)) < 0:
                return pts, hit[2] if hit else "left the range"
            on_step(a, b, len(pts))
            pts.append(b)
            # closed curve: back next to the start after going round
            if len(pts) > 4 and (self._closes(p0, a, b, ds) or (
                    la.norm(b.st.z - z_start) < 0.5 * ds
                    and la.dot(b.st.z - z_start, p0.t) < 0
                    <= la.dot(a.st.z - z_start, p0.t) + 1e-300)):
                return pts, "closed"
            t_plane = b.t[s.n:s.n + 2].copy()
            rephased = False
            new = s.adapt(b.st.z)
            if new is not None:
                st3 = s.evaluate(new)
                t3 = _null(st3.J)
                # orientation: keep the direction in the (frequency, parameter) plane
                if la.dot(t3[s.n:s.n + 2], t_plane) < 0:
                    t3 = -t3
                b = self.make_point(st3, t3, b.exact)
                pts[-1] = b
                rephased = True  # no previous point in these unknowns
            elif it > 6:
                # new borders only when the corrector struggled: the point's Jacobian, which
                # starts the next corrector, holds the test function's row for the borders
                # in use, and a renewal makes that row stale (measured on the paper chart's
                # fold curves near 10 Hz: renewing at every point made the first quasi-Newton
                # step raise the residual, a fresh Jacobian at every point, and failed steps)
                s.renew_borders(b.st.z)
            ds = self._next_ds(ds, it, la.dot(t, a.t))
            if ds_fail is not None:  # not back to a step that failed: grow below it
                ds = min(ds, 0.7 * ds_fail)
                ds_fail = ds_fail * 1.2 if ds_fail * 1.2 < self.ds_max else None
            prev = None if rephased else a.st.z
            a = b


def _side(v):
    return bool(v) if isinstance(v, (bool, np.bool_)) else v > 0


def _locate(tr, a, b, fun, iters=40, rel=1e-9, tangent=False):
    """The point between curve points a and b where fun(point) changes sign (fun: of a
    CurveState and its unit tangent), along the chord: a continuous fun by regula falsi
    with the Illinois modification (superlinear; the bracket shrinks from both sides), a
    bool by bisection; each trial point corrected onto the curve on the plane normal to the
    chord (its Jacobian only when ``tangent``: fun reads the tangent). Returns (point,
    bracket half-width (frequency Hz, value)): the final bracket, which holds the zero of fun
    on the corrected curve (its integration error is not in it)."""
    za, zb = a.st.z, b.st.z
    d = zb - za
    L = la.norm(d)
    if L == 0:
        return a, (0.0, 0.0)
    e = d / L
    fa, fb = fun(a.st, a.t), fun(b.st, b.t)
    continuous = not isinstance(fa, (bool, np.bool_))
    lo, hi = 0.0, L
    flo, fhi = (float(fa), float(fb)) if continuous else (None, None)
    best = a
    plo, phi = a, b
    kept = 0  # Illinois: which end was kept last (-1 lo, +1 hi), twice in a row halves it
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        if continuous and flo != fhi and math.isfinite(flo) and math.isfinite(fhi):
            mid = (lo * fhi - hi * flo) / (fhi - flo)
            w = 1e-3 * (hi - lo)  # strictly inside
            mid = min(max(mid, lo + w), hi - w)
        try:
            st, _ = tr.correct(za + mid * e, e, la.dot(e, za) + mid, a.st.J, jac=tangent)
        except ConvergenceError:
            break
        t = _tangent(st.J, a.t) if st.J is not None else e
        pm = tr.make_point(st, t)
        fm = fun(st, t)
        best = pm
        if _side(fm) == _side(fa):
            lo, plo = mid, pm
            if continuous:
                flo = float(fm)
                fhi = 0.5 * fhi if kept == -1 else fhi
            kept = -1
        else:
            hi, phi = mid, pm
            if continuous:
                fhi = float(fm)
                flo = 0.5 * flo if kept == 1 else flo
            kept = 1
        if hi - lo <= rel * L + 1e-12 or (continuous and fm == 0):
            break
    ef = 0.5 * abs(phi.frequency - plo.frequency)
    ev = 0.5 * abs(phi.value - plo.value)
    return best, (ef, ev)


def _other_tests(kind, mu):
    """The test functions (fold, period-doubling, Neimark-Sacker) that are not identically
    zero on a curve of this kind."""
    tf, tpd, tns = test_functions(mu)
    out = {}
    if kind != "fold":
        out["fold"] = tf
    if kind != "period-doubling":
        out["period-doubling"] = tpd
    return out


def _detector(tr, special, tests):
    """on_step for the tracer: appends the Codim2 points met to ``special``, and (Codim2,
    located point, test name) of those located on a continuous test function to ``tests``."""
    s = tr.s
    kind = s.kind

    def on_step(a, b, index):
        sa, sb = a.st, b.st
        # cusp: a fold curve turning back in both parameters at once
        if kind == "fold":
            kf, kp = s.n, s.n + 1
            if a.t[kf] * b.t[kf] < 0 and a.t[kp] * b.t[kp] < 0:
                pt, (ef, ev) = _locate(tr, a, b, lambda st, t: t[kp], tangent=True)
                pt2, _ = _locate(tr, a, b, lambda st, t: t[kf], tangent=True)
                ef = max(ef, abs(pt2.frequency - pt.frequency))
                ev = max(ev, abs(pt2.value - pt.value))
                special.append(Codim2("cusp", pt.frequency, pt.value, ef, ev, index))
        # a second multiplier through +1 or -1
        if sa.multipliers is not None and sb.multipliers is not None:
            ta, tb = _other_tests(kind, sa.multipliers), _other_tests(kind, sb.multipliers)
            for name in ta:
                if ta[name] * tb[name] < 0:
                    pt, (ef, ev) = _locate(tr, a, b, lambda st, t, nm=name: _other_tests(
                        kind, st.multipliers)[nm])
                    if kind == "grazing":
                        what = {"fold": "fold-grazing", "period-doubling": "flip-grazing"}[name]
                    elif {kind, name} == {"fold", "period-doubling"}:
                        what = "fold-flip"
                    else:
                        continue
                    c2 = Codim2(what, pt.frequency, pt.value, ef, ev, index)
                    special.append(c2)
                    tests.append((c2, pt, name))
        # the number of impacts per period changes: the curve meets a grazing curve
        if kind != "grazing" and sa.n_impacts != sb.n_impacts:
            pt, (ef, ev) = _locate(tr, a, b, lambda st, t: st.n_impacts == sa.n_impacts,
                                   iters=30)
            what = {"fold": "fold-grazing", "period-doubling": "flip-grazing",
                    "neimark-sacker": "neimark-sacker-grazing"}[kind]
            special.append(Codim2(what, pt.frequency, pt.value, ef, ev, index,
                                  note=f"impacts per period {sa.n_impacts} -> {sb.n_impacts}"))

    return on_step


def _point_error(model, sysm, amplitude, pt, integrator, segments, tol):
    """Twice the change of the point's frequency (Hz) when it is located again at its
    second-parameter value with both steps halved (NaN, with a warning, if that fails)."""
    A = pt.value if sysm.parameter == "amplitude" else amplitude
    m = model if sysm.parameter == "amplitude" else with_parameter(model, sysm.parameter,
                                                                     pt.value)
    try:
        s2 = CurveSystem(m, sysm.kind, sysm.order, A, pt.frequency, pt.state0, sysm.parameter,
                         integrator.refined(1), segments=segments,
                         element=getattr(sysm, "element", None),
                         phase=None if math.isnan(pt.phase) else pt.phase)
        tr = _Tracer(s2, (0.5 * pt.frequency, 2 * pt.frequency), (-np.inf, np.inf), (), 0.05,
                     1e-6, 0.3, 0.3, 1, tol, 10)
        return 2.0 * abs(tr.start(1).frequency - pt.frequency)
    except (ConvergenceError, nlbeam.IntegrationError) as exc:
        warnings.warn(f"bifurcation_curve: no error estimate at {pt.frequency:.9g} Hz, "
                      f"{sysm.parameter} = {pt.value:.6g}: not located with the step halved "
                      f"({exc})", ContinuationWarning, stacklevel=3)
        return float("nan")


def _codim2_error(model, sysm, amplitude, c2, pt, name, integrator, segments, tol):
    """Add the integration error to a codimension-2 point's bracket errors (in place): the
    curve is solved with both steps halved at the point's value and at a value 1e-4 (relative)
    beside it, the test function's zero placed by the secant through the two, and twice the
    move of (frequency, value) added to (error_frequency, error_value). A failure leaves the
    bracket errors and says so in the point's note."""
    v0 = pt.value
    out = []
    try:
        for v in (v0, v0 * (1 + 1e-4) if v0 != 0 else 1e-8):
            A = v if sysm.parameter == "amplitude" else amplitude
            m = model if sysm.parameter == "amplitude" else with_parameter(
                model, sysm.parameter, v)
            s2 = CurveSystem(m, sysm.kind, sysm.order, A, pt.frequency, pt.state0,
                             sysm.parameter, integrator.refined(1), segments=segments,
                             element=getattr(sysm, "element", None),
                             phase=None if math.isnan(pt.phase) else pt.phase)
            tr = _Tracer(s2, (0.5 * pt.frequency, 2 * pt.frequency), (-np.inf, np.inf), (),
                         0.05, 1e-6, 0.3, 0.3, 1, tol, 10)
            p = tr.start(1)
            out.append((p.frequency, p.value, _other_tests(sysm.kind, p.st.multipliers)[name]))
    except (ConvergenceError, nlbeam.IntegrationError) as exc:
        c2.note = (c2.note + "; " if c2.note else "") + f"no integration error estimate ({exc})"
        return
    (f0, w0, g0), (f1, w1, g1) = out
    if g1 == g0:
        c2.note = (c2.note + "; " if c2.note else "") + "no integration error estimate"
        return
    r = -g0 / (g1 - g0)
    c2.error_frequency += 2.0 * abs(f0 + r * (f1 - f0) - c2.frequency)
    c2.error_value += 2.0 * abs(w0 + r * (w1 - w0) - c2.value)


# --- front door -----------------------------------------------------------------------------------
def _check_range(name, rng, unit, lo_open=0.0):
    try:
        lo, hi = map(float, rng)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a pair (lo, hi) {unit}, got {rng!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name}: must be finite with lo < hi {unit}, got {rng!r}")
    return lo, hi


def _check_parameter(model, parameter):
    """'amplitude' or a name of nlbeam.parameters (the error lists the names that exist)."""
    if parameter == "frequency":
        raise ValueError("parameter: the frequency is the curve's first parameter; give the "
                         "second one: 'amplitude' or " + ", ".join(
                             repr(n) for n in parameter_names(model)))
    check_parameter(model, parameter, extra=("amplitude",))


def bifurcation_curve(model, bifurcation, p_range, *, amplitude=None, parameter="amplitude",
                      f_range=None, at=(), integrator=None, segments=1, ds=0.05, ds_min=1e-6,
                      ds_max=0.3, max_angle=0.3, max_points=400, tol=1e-9, max_iter=12,
                      directions=(1, -1), element=None, phase=None, error=True,
                      max_evaluations=None, **integrator_kw):
    """The locus of a bifurcation in (frequency, parameter).

    bifurcation: a located point of a frequency diagram (a continuation.Bifurcation of kind
    'fold', 'period-doubling', 'neimark-sacker' or 'grazing', with its state0 and order), or a
    dict with keys kind, frequency (Hz), order, state0 (and optionally disc0). amplitude: the
    diagram's excitation amplitude (m or N); parameter: the second parameter, 'amplitude'
    (default) or any name of nlbeam.parameters (a model field 'e', 'K_hertz', 'b', 'm', 'k';
    an element parameter of a general System 'elements[0].gap', ...), continued together
    with the frequency along the curve; p_range: (lo, hi) of that parameter, which must hold
    the start's value; f_range: (lo, hi) Hz (default: 0.2-5 times the start frequency).
    at: second-parameter values at which exact curve points are placed (BifurcationCurve.at).
    The curve is followed both ways (``directions``) by pseudo-arclength continuation of the
    extended system (continuation.extended) in scaled unknowns: ds, ds_min, ds_max (step),
    max_angle (rad between tangents), max_points (per direction), tol (scaled residual),
    max_iter (corrector), max_evaluations (shooting evaluations per direction, None: no
    limit; a trace that reaches it ends 'max_evaluations'). element, phase: for a grazing
    curve, the stop (element index) and excitation phase (periods) of the grazing contact
    (default: the extremum of the penetration closest to zero on the start orbit).
    Integrator options as for periodic_solution (the diagram's integrator, for the curve to
    pass through its points). error: estimate the integration error of the frequency at the
    start and the ``at`` points (BifurcationCurve.error). Codimension-2 points met (Codim2:
    cusp, fold-flip, a curve meeting a grazing curve, i.e. the number of impacts per period
    changes along it) are in ``special``. Returns a BifurcationCurve; a ContinuationWarning
    says where a trace stopped short of the ranges (step underflow, max_points,
    max_evaluations, corrector-limited: short steps with repeated corrector failures, e.g. a
    chattering stretch, SLOW_STEPS); a start that does not converge raises ConvergenceError.
    """
    t_wall = time.perf_counter()
    integrator = integrator or Integrator(**integrator_kw)
    get = (bifurcation.get if isinstance(bifurcation, dict)
           else lambda k, d=None: getattr(bifurcation, k, d))
    kind, f0, order = get("kind"), get("frequency"), get("order")
    if kind not in KINDS:
        raise ValueError(f"bifurcation: kind must be one of {KINDS}, got {kind!r}")
    if not getattr(bifurcation, "smooth", True) and kind != "grazing":
        raise ValueError(f"bifurcation: this {kind} lies at a grazing point ({bifurcation.note})"
                         "; it has no smooth extended system: trace the grazing curve instead "
                         "(a Bifurcation of kind 'grazing' nearby)")
    state0 = get("state0")
    if state0 is None or f0 is None or order is None:
        raise ValueError("bifurcation: needs frequency, order and state0 (a located point of a "
                         "diagram computed with stability)")
    if amplitude is None:
        amplitude = get("amplitude")
    if amplitude is None:
        raise ValueError("amplitude: give the excitation amplitude of the diagram (m or N)")
    amplitude = float(amplitude)
    _check_parameter(model, parameter)
    p_lo, p_hi = _check_range("p_range", p_range, "(units of the parameter)")
    p0 = amplitude if parameter == "amplitude" else get_parameter(model, parameter)
    if not p_lo <= p0 <= p_hi:
        raise ValueError(f"p_range: must hold the start's {parameter} = {p0:.6g}, got {p_range!r}")
    if parameter == "amplitude" and p_lo <= 0:
        raise ValueError(f"p_range: amplitudes must be > 0, got {p_range!r}")
    f_range = f_range or (0.2 * f0, 5.0 * f0)
    f_lo, f_hi = _check_range("f_range", f_range, "Hz")
    if not (0 < f_lo <= f0 <= f_hi):
        raise ValueError(f"f_range: must hold the start frequency {f0:.6g} Hz and be > 0, got "
                         f"{f_range!r}")
    for name, v, lo in (("ds", ds, 0), ("ds_max", ds_max, ds), ("ds_min", ds_min, 0)):
        if not (math.isfinite(v) and v > lo):
            raise ValueError(f"{name}: must be finite and > {lo:g}, got {v!r}")
    if int(max_points) != max_points or max_points < 1:
        raise ValueError(f"max_points: must be an integer >= 1, got {max_points!r}")
    if not set(directions) <= {1, -1} or not directions:
        raise ValueError(f"directions: a non-empty subset of (1, -1), got {directions!r}")
    at = [float(v) for v in at]
    for v in at:
        if not p_lo < v < p_hi:
            raise ValueError(f"at: values must lie inside p_range {p_range!r}, got {v!r}")

    sysm = CurveSystem(model, kind, order, amplitude, f0, np.asarray(state0, dtype=float),
                       parameter, integrator, disc0=get("disc0"), segments=segments,
                       element=element, phase=phase)
    tr = _Tracer(sysm, (f_lo, f_hi), (p_lo, p_hi), at, ds, ds_min, ds_max, max_angle,
                 max_points, tol, max_iter)
    if max_evaluations is not None:
        if int(max_evaluations) != max_evaluations or max_evaluations < 1:
            raise ValueError(f"max_evaluations: must be an integer >= 1 or None, got "
                             f"{max_evaluations!r}")
        tr.max_evaluations = int(max_evaluations)
    special, tests = [], []
    halves, ends = [], []
    snapshot = sysm.snapshot()
    for d in directions:
        # each direction from the start (the problem may have been rephased by the other)
        sysm.restore(snapshot)
        try:
            start = tr.start(d)
        except ConvergenceError as exc:
            raise sysm.start_failure(exc) from None
        pts, why = tr.trace(start, _detector(tr, special, tests))
        halves.append((start, pts))
        ends.append(why)
        if why == "closed":
            break
    if len(halves) == 2:
        (s1, p1), (s2, p2) = halves
        pts = p2[::-1] + [s1] + p1
        pts_start = s1
        ends = (ends[1], ends[0])
    else:
        pts = [halves[0][0]] + halves[0][1]
        pts_start = halves[0][0]
        ends = (ends[0], ends[0]) if ends[0] == "closed" else ("start", ends[0])
    stuck = [e for e in ends if e in ("step underflow", "max_points", "max_evaluations")
             or e.startswith("corrector-limited")]
    if stuck:
        warnings.warn(f"bifurcation_curve: the {kind} curve (order {order}) from "
                      f"{f0:.6g} Hz stopped short of the ranges ({'; '.join(stuck)}): try a "
                      "smaller ds_max or more max_points, or segments=4 (multiple shooting)"
                      + ("; a corrector-limited stretch (chattering orbits: the extended system "
                         "is not smooth there) is ended on purpose: a smaller dt_scale or "
                         "another start beyond it" if any(e.startswith("corrector-limited")
                                                          for e in stuck) else ""),
                      ContinuationWarning, stacklevel=2)
    f = np.array([p.frequency for p in pts])
    v = np.array([p.value for p in pts])
    amp = v if parameter == "amplitude" else np.full(len(pts), amplitude)
    mu = np.array([p.st.multipliers for p in pts]) if all(
        p.st.multipliers is not None for p in pts) else None
    err = np.full(len(pts), np.nan)
    if error:
        for i, p in enumerate(pts):
            if p.exact and (p is pts_start or any(abs(p.value - a) <= 1e-9 * abs(a) for a in at)):
                err[i] = _point_error(model, sysm, amplitude, p, integrator, segments, tol)
    if error:
        for c2, pt, name in tests:
            _codim2_error(model, sysm, amplitude, c2, pt, name, integrator, segments, tol)
    special.sort(key=lambda c: (c.value, c.frequency))
    for c in special:  # the curve point nearest to it
        c.index = int(np.argmin(np.hypot(np.log(f / c.frequency), (v - c.value) / (
            abs(c.value) + 1e-300))))
    return BifurcationCurve(
        kind=kind, order=int(order), parameter=parameter, frequency=f, values=v, amplitude=amp,
        xmax=np.array([p.st.xmax for p in pts]), multipliers=mu,
        state0=np.array([p.state0 for p in pts]), phase=np.array([p.phase for p in pts]),
        n_impacts=np.array([p.st.n_impacts for p in pts]),
        exact=np.array([p.exact for p in pts]), error=err, special=special, ends=tuple(ends),
        f_range=(f_lo, f_hi), p_range=(p_lo, p_hi),
        model_parameters=model.parameters(),
        settings={"amplitude": amplitude, "segments": segments, "ds": ds, "ds_max": ds_max,
                  "max_angle": max_angle, "tol": tol, "method": integrator.method,
                  "dt_scale": integrator.dt_scale,
                  "steps_per_contact": integrator.steps_per_contact},
        n_evaluations=sysm.n_evaluations, wall_time=time.perf_counter() - t_wall)
