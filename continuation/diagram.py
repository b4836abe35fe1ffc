"""Frequency-response diagrams: branches of every order, their bifurcations, save and load."""
from __future__ import annotations

import copy
import inspect
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

import nlbeam
from nlbeam.parameters import check_parameter
from nlbeam.pool import Pool
from nlbeam.solver import period_step
from nlbeam.summary import Summary, describe_value

from . import _arguments as _args
from nlbeam import _linalg as la
from ._newton import ContinuationWarning, ConvergenceError
from .parallel import Speculator, take, taken
from .pathfollow import GRAZING_RESOLUTION, Tracer
from .seeding import brute_force
from .turns import unexplained_turns
from .shooting import (Integrator, PeriodicSolution, ShootingProblem, _problem_from_state,
                       forcing, steady_state)


@dataclass(repr=False)
class Branch(Summary):
    """One traced branch (n points). order: period = order / f. parameter: the continued
    parameter's name, values (n,) its values; frequency (n,) Hz, amplitude (n,); xmax (n,) m;
    stable (n,) bool; multipliers (n, 2N) complex (largest modulus first), both None when the
    diagram was computed with stability=False (stability unknown); state0 (n, 2N) the
    state at t = 0; states (n, m, 2N) at the shooting boundaries, boundaries (n, m) their
    excitation phases (periods; NaN rows past a point's own number of segments, where a corner
    was passed by multiple shooting); origin: 'brute-force', 'period-doubling', 'start' or
    'gap' (seeded inside a part of the range no branch covered);
    ends: why the trace stopped at the first and at the last point ('left the parameter
    range', 'closed (isola)' (the branch is a closed curve and came round to its start),
    'stop' (ran onto a traced branch, or a switched branch back at its period doubling),
    'period-doubling' (the first point of a switched branch), 'stuck at a corner' (no
    continuation through a point where the number of impacts changes passed the checks, see
    frequency_response), 'step underflow' (the corrector failed at every step size down to
    ds_min: a non-smooth or too unstable map), 'no progress', 'max_points', 'could not move
    the segment boundaries'; '' unknown). The last five are ends where the tracer gave up:
    the diagram's ContinuationWarning lists them. 'discontinuous map': the fixed-step flow map
    jumps just beyond the last point (continuation.corners.map_jump; e.g. a contact that ends
    and restarts within a step): no continuous branch of the discrete map goes on; listed in
    that warning too, with the interval it leaves uncovered.
    Accuracy (continuation.accuracy.branch_errors): xmax_error (n,) m and multipliers_error
    (n,) (the largest over each point's multipliers; None without stability) estimate the
    integration's error, computed at the points where error_sampled (n,) is True (every point
    whose orbit was found with both steps halved; there multipliers and stable are those of
    that orbit) and elsewhere the larger estimate of the level-0 values' error at the two
    nearest computed points; None when not estimated (accuracy='off')."""

    order: int
    parameter: str
    values: np.ndarray
    frequency: np.ndarray
    amplitude: np.ndarray
    xmax: np.ndarray
    stable: np.ndarray
    multipliers: np.ndarray
    state0: np.ndarray
    states: np.ndarray
    boundaries: np.ndarray
    origin: str = "start"
    ends: tuple = ("", "")
    xmax_error: np.ndarray | None = None
    multipliers_error: np.ndarray | None = None
    error_sampled: np.ndarray | None = None

    def _summary_rows(self):
        n = len(self.values)
        rows = [("order", str(self.order)), ("points", str(n))]
        if self.parameter != "frequency":
            rows.append((self.parameter, describe_value(np.asarray(self.values))))
        rows += [("frequency [Hz]", describe_value(np.asarray(self.frequency))),
                ("xmax [m]", describe_value(np.asarray(self.xmax))),
                ("stable", "not computed" if self.stable is None
                 else f"{int(np.count_nonzero(self.stable))} of {n} points"),
                ("origin", self.origin), ("ends", " / ".join(e or "?" for e in self.ends))]
        if self.xmax_error is not None:
            rows.append(("xmax_error [m]", describe_value(np.asarray(self.xmax_error))))
        return rows


@dataclass(repr=False)
class Bifurcation(Summary):
    """kind: 'fold', 'period-doubling', 'neimark-sacker' or 'grazing' (the number of impacts per
    period changes: an orbit touches a stop with zero velocity; the flow map is not smooth there
    and the branch is continued past it by a checked crossing, see frequency_response);
    frequency (Hz) and value of the continued parameter at the point; error: the estimated error
    of ``value`` (Hz for a frequency diagram) due to the integration, from the point located
    again with the step halved (continuation.accuracy.bifurcation_levels; the value is then the
    finer or extrapolated one; NaN when not estimated: accuracy='off', or the point could not be
    located at a finer step, which the diagram's warning lists) or from refine_bifurcations;
    levels: the values at the successive step halvings (not saved); tolerance: width of the
    tracer's final bracket on the diagram's own branch (where it located the point; not an error
    bar); refine_status: '' (not refined), 'refined' (then ``refined`` holds the record, saved
    and loaded with the diagram, its ``levels`` not) or 'failed: <reason>' (refine_bifurcations
    could not, or would not, refine it); xmax (m); order of the branch it lies on; branch index;
    multipliers (for a grazing point: those of the branch point on the far side of the bracket;
    None without stability); note: '' for a bifurcation of the smooth map, or 'at grazing:
    multiplier jumps from .. to .. (non-smooth)' where a multiplier jumps through +1, -1 or the
    unit circle at a grazing point (reported there, with the grazing bracket as tolerance; see
    Tracer._detect_step; its error is that of the grazing point); 'at grazing: fold located
    .. from the grazing point, within its resolution' for one located on a smooth side within
    GRAZING_RESOLUTION (1e-5 of f) of a grazing point, and 'at grazing: multiplier .. -> .. on
    the smooth side next to it, not located there' for one the locate could not place there
    (continuation.pathfollow.at_grazing_points: a fold-grazing, flip-grazing .. point, one
    event whichever side of the corner round-off puts the root on)."""

    kind: str
    frequency: float
    value: float
    xmax: float
    order: int
    branch: int
    tolerance: float
    multipliers: np.ndarray
    state0: np.ndarray | None = None
    disc0: np.ndarray | None = None  # contact state at t = 0 when inside a contact (LN memory)
    error: float = float("nan")
    refined: object = None  # a continuation.refine.Refined, set by refine_bifurcations
    note: str = ""  # see the class doc; for a grazing point 'k changes of the number of
    # impacts within the bracket' where k close ones were merged (Tracer steps may or may not
    # resolve them one by one)
    levels: np.ndarray | None = None
    refine_status: str = ""  # '' not refined, 'refined', or 'failed: <reason>' (saved)

    @property
    def smooth(self):
        """False for a bifurcation at a grazing point (a multiplier jumps there) or at a kink
        (the branch turns back where the map is not smooth: continuation.kinks.turn)."""
        return not self.note.startswith(("at grazing", "at a kink"))

    def _summary_rows(self):
        rows = [("kind", self.kind), ("order", str(self.order)), ("branch", str(self.branch)),
                ("frequency [Hz]", f"{self.frequency:.10g}"),
                ("error [Hz]", "not estimated" if not np.isfinite(self.error)
                 else f"{self.error:.2g}"),
                ("bracket (tolerance) [Hz]", f"{self.tolerance:.2g}"),
                ("xmax [m]", describe_value(self.xmax)),
                ("refinement", self.refine_status or "not refined")]
        if self.multipliers is not None:
            rows.append(("multipliers", describe_value(np.asarray(self.multipliers))))
        if self.note:
            rows.append(("note", describe_value(self.note)))
        return rows


@dataclass(repr=False)
class Superharmonic(Summary):
    """A superharmonic resonance: a peak of the harmonic branch at frequency (Hz, +- tolerance)
    where ``harmonic`` times f lies near the main resonance; ratio: amplitude of that harmonic
    over the first in the response relative to the base."""

    frequency: float
    xmax: float
    harmonic: int
    branch: int
    ratio: float = float("nan")
    tolerance: float = float("nan")


@dataclass(repr=False)
class FrequencyResponse(Summary):
    """A diagram: branches, bifurcations and superharmonic peaks, with what produced them."""

    model_parameters: dict
    amplitude: float
    parameter: str
    p_range: tuple
    branches: list = field(default_factory=list)
    bifurcations: list = field(default_factory=list)
    superharmonics: list = field(default_factory=list)
    settings: dict = field(default_factory=dict)
    wall_time: float = 0.0
    n_points: int = 0
    version: str = nlbeam.__version__

    def uncovered(self, order=1):
        """The parts of p_range (list of (lo, hi)) that no branch of this order covers (a
        branch that ran onto another counts as joined to it)."""
        return _uncovered(_intervals([b for b in self.branches if b.order == order]),
                          min(self.p_range), max(self.p_range))

    def unresolved(self, order=None):
        """The stretches of p_range (list of (order, lo, hi, what)) the diagram declares
        unresolved: around each branch end inside the range where the tracer gave up (not at
        the point budget, 'max_points') or the fixed-step map jumps, within CHATTER_REACH of
        the end and of the branch's chained grazing points and bifurcations there (see
        CHATTER_REACH); the diagram's warning lists them. Only of that order if given."""
        return [s for s in _unresolved(self.branches, self.bifurcations, self.p_range)
                if order is None or s[0] == order]

    def _summary_rows(self):
        from collections import Counter

        unit = "Hz" if self.parameter == "frequency" else ""
        lo, hi = sorted(float(v) for v in self.p_range)
        orders = Counter(int(b.order) for b in self.branches)
        kinds = Counter(b.kind for b in self.bifurcations)
        status = Counter((b.refine_status or "").split(":")[0] for b in self.bifurcations)
        rows = [(self.parameter, f"{lo:g} .. {hi:g} {unit}".rstrip()),
                ("amplitude", f"{self.amplitude:.6g} " + (
                    "N" if self.model_parameters.get("excitation_kind") == "force"
                    or self.model_parameters.get("model") == "Duffing" else "m")),
                ("branches", f"{len(self.branches)}" + (": " + ", ".join(
                    f"order {o}: {k}" for o, k in sorted(orders.items())) if orders else "")),
                ("points", str(self.n_points or sum(len(b.values) for b in self.branches))),
                ("bifurcations", f"{len(self.bifurcations)}" + (": " + ", ".join(
                    f"{k} {n}" for k, n in sorted(kinds.items())) if kinds else ""))]
        if status.get("refined") or status.get("failed"):
            rows.append(("refined", f"{status.get('refined', 0)} refined, "
                                    f"{status.get('failed', 0)} failed"))
        rows.append(("superharmonics", str(len(self.superharmonics))))
        if any(b.order == 1 for b in self.branches):
            gaps = self.uncovered(1)
            rows.append(("order 1 uncovered", "none" if not gaps else ", ".join(
                f"{a:g}..{b:g}" for a, b in gaps)))
        stretches = self.unresolved()
        if stretches:
            rows.append(("unresolved", ", ".join(f"order {o}: {a:.6g}..{c:.6g}"
                                                 for o, a, c, _ in stretches)))
        acc = self.stated_accuracy()
        if acc:
            rows.append(("stated errors", acc))
        rows += [("wall_time [s]", f"{self.wall_time:.3g}"), ("version", str(self.version))]
        return rows

    def stated_accuracy(self):
        """One line on the error estimates (accuracy=, continuation.accuracy), '' without
        them: the multipliers' stated error at the sampled branch points (median, the largest
        and where, how many above 1e-5) and the fold / period-doubling / Neimark-Sacker
        frequencies' (median relative error, how many not estimated)."""
        if self.settings.get("accuracy") == "off":
            return ""
        mu = [(float(e), float(v)) for b in self.branches
              if b.multipliers_error is not None and b.error_sampled is not None
              for e, v in zip(b.multipliers_error[b.error_sampled], b.values[b.error_sampled])]
        rel = [abs(b.error / b.value) if b.value else b.error for b in self.bifurcations
               if b.kind in ("fold", "period-doubling", "neimark-sacker")
               and getattr(b, "error", None) is not None]
        parts = []
        if mu:
            e = np.array([m for m, _ in mu])
            k = int(np.argmax(e))
            parts.append(f"multipliers median {np.median(e):.1e}, largest {e[k]:.1e} at "
                         f"{mu[k][1]:.6g}, {int(np.sum(e > 1e-5))} of {e.size} sampled "
                         f"points above 1e-5")
        if rel:
            r = np.array(rel, dtype=float)
            ok = np.isfinite(r)
            if ok.any():
                parts.append(f"fold/PD/NS {self.parameter} median relative "
                             f"{np.median(r[ok]):.1e}" + (f", {int(np.sum(~ok))} not estimated"
                                                         if not ok.all() else ""))
        return "; ".join(parts)

    def save(self, path):
        """Write to HDF5 (atomically: a temporary file in the same folder, then os.replace;
        the usual file mode under the umask). The file format lives on the application floor
        (nlbeam.app.files.frequency_response_hdf5), which imports h5py."""
        from nlbeam.app.files.frequency_response_hdf5 import save_frequency_response

        save_frequency_response(self, path)


def load(path):
    """Read a FrequencyResponse written by ``FrequencyResponse.save`` (the format:
    nlbeam.app.files.frequency_response_hdf5)."""
    from nlbeam._validate import path_like
    from nlbeam.app.files.frequency_response_hdf5 import load_frequency_response

    return load_frequency_response(path_like("path", path))


# --- building branches ---------------------------------------------------------------------------
def _to_branch(points, order, parameter, origin, ends=("", "")):
    n = len(points)
    probs = [p.problem for p in points]
    values = np.array([p.p for p in points])
    freq = np.empty(n)
    amp = np.empty(n)
    st0 = []
    for i, pt in enumerate(points):
        m, A, f = pt.problem.setup(pt.p)
        freq[i], amp[i] = f, A
        st0.append(pt.state0 if pt.state0 is not None  # (the tracer's signature of it)
                   else pt.problem.state_at_zero(pt.u, pt.p)[0])
    m_max = max(pr.n_seg for pr in probs)
    states = np.full((n, m_max, probs[0].N2), np.nan)  # NaN: fewer segments at that point
    bounds = np.full((n, m_max), np.nan)
    for i, (pt, pr) in enumerate(zip(points, probs)):
        states[i, :pr.n_seg] = pt.u.reshape(pr.n_seg, pr.N2)
        bounds[i, :pr.n_seg] = pr.boundaries
    if any(p.multipliers is None for p in points):  # stability not computed
        mu = stable = None
    else:
        mu = np.array([p.multipliers for p in points])
        stable = np.abs(mu[:, 0]) < 1.0
    return Branch(order=order, parameter=parameter, values=values, frequency=freq, amplitude=amp,
                  xmax=np.array([p.xmax for p in points]),
                  stable=stable, multipliers=mu, state0=np.array(st0),
                  states=states, boundaries=bounds, origin=origin, ends=tuple(ends))


def _bifurcation(L, order, branch):
    """The Bifurcation of a Located on branch number ``branch`` of this order."""
    m_, A_, f_ = L.point.problem.setup(L.point.p)
    return Bifurcation(L.kind, float(f_), float(L.point.p), float(L.point.xmax), order, branch,
                       float(L.tolerance), L.point.multipliers,
                       *L.point.problem.state_at_zero(L.point.u, L.point.p),
                       note=getattr(L, "note", ""))


def _both_ways(tracer, prob, u, p, stop=None):
    """Trace from (u, p) both ways: (points, located, (reason at the first point, at the last)).
    The second half is traced knowing the first (``Tracer.trace(prior=...)``): where it runs
    onto it, the branch is a closed curve."""
    fwd, loc_f, reason = tracer.trace(prob, u, p, direction=1, stop=stop)
    if reason.startswith("closed"):
        return fwd, loc_f, (reason, reason)
    bwd, loc_b, reason_b = tracer.trace(prob, u, p, direction=-1, stop=stop,
                                        prior=tracer.retrace.export())

    nb = len(bwd)
    pts = bwd[::-1][:-1] + fwd
    for L in loc_b:
        L.index = nb - 2 - L.index
    for L in loc_f:
        L.index += nb - 1
    return pts, loc_b + loc_f, (reason_b, reason)


def _on_branch(branches, order, f, xmax, state0, rel=2e-3, state_rel=0.05, same_orbit=None):
    """Index of a traced branch of this order through the solution (f Hz, xmax m, state0: its
    states at t = k / f, k = 0..order-1 (the same orbit seen from each excitation period), or a
    callable giving them), or None. The point must lie within ``rel`` (relative, plus a
    twentieth of the local segment length) of the branch's (f, xmax) polyline, and its state at
    t = 0 within ``state_rel`` of the state interpolated there (in units of the orbit's size).
    Past an end where the map jumps ('discontinuous map') the branch does not go on: there a
    point nearest to a segment's end (not between its ends) is the orbit on the jump's far
    side, not on the branch.
    same_orbit: callable(branch, i, lam) -> bool (``_same_orbit_test``), the branch re-solved at
    f from segment i (lam: where the point projects onto it) and compared with the solution:
    it then decides every point that passes those allowances (at most the two nearest segments
    of each branch). Two different orbits can lie within the allowances (the paper model's
    order-3 branches near 111-113 Hz: xmax within 1 %, multipliers 0.3 against 0.5), and which
    point of a trace first falls inside them is up to round-off; the re-solve's answer has a
    margin (the same orbit to the corrector's tolerance, 1e-8, or another one, > 1e-3)."""
    for bi, b in enumerate(branches):
        if b.order != order or len(b.frequency) < 2:
            continue
        fb = b.frequency
        past_last = b.ends[1] == _JUMP and (f - fb[-1]) * (fb[-1] - fb[-2]) > 0
        past_first = b.ends[0] == _JUMP and (f - fb[0]) * (fb[0] - fb[1]) > 0
        F = b.frequency / f - 1.0
        X = b.xmax / xmax - 1.0
        dF, dX = np.diff(F), np.diff(X)
        L2 = dF ** 2 + dX ** 2
        lam = np.clip(-(F[:-1] * dF + X[:-1] * dX) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
        dist = np.hypot(F[:-1] + lam * dF, X[:-1] + lam * dX)
        allow = rel + 0.05 * np.sqrt(L2)
        ok = np.nonzero(dist <= allow)[0]
        shifts = None
        tried = 0
        # (with the re-solve: segments that reach f within rel first, nearest first: from a
        # segment farther off in frequency the re-solve is not made, see _same_orbit_test)
        near_f = ((np.minimum(fb[:-1], fb[1:]) <= f * (1 + rel))
                  & (f * (1 - rel) <= np.maximum(fb[:-1], fb[1:])))
        key = dist[ok] / allow[ok] + (0.0 if same_orbit is None else 10.0 * ~near_f[ok])
        for i in ok[np.argsort(key, kind="stable")]:
            if (past_last and lam[i] >= 1.0) or (past_first and lam[i] <= 0.0):
                continue
            s_b = b.state0[i] + lam[i] * (b.state0[i + 1] - b.state0[i])
            if shifts is None:
                shifts = state0() if callable(state0) else state0
                shifts = np.atleast_2d(shifts)
            N = shifts.shape[1] // 2
            w = 2 * np.pi * f / order
            sc = np.r_[np.full(N, xmax), np.full(N, xmax * w)]
            if np.min(np.max(np.abs(shifts - s_b) / sc, axis=1)) > state_rel:
                continue
            if same_orbit is None:
                return bi
            if tried >= 2:
                break
            tried += 1
            if same_orbit(b, i, float(lam[i])):
                return bi
    return None


def _same_orbit_test(prob, u, p, rel=1e-5):
    """callable(branch, i, lam) -> bool for ``_on_branch``: Newton at p (a frequency) on a copy
    of prob (the candidate orbit u's problem), started from the branch's state at t = 0
    interpolated on its segment i (at p where the segment spans it, else at lam), lands on the
    orbit u (its state at t = 0 within ``rel`` of the orbit's size, seen from any excitation
    period); False where Newton fails or the segment ends farther than 2e-3 (relative, the
    allowance) from p in frequency (a point beyond a branch's end or fold by more is judged at
    a later step). (For another continued parameter, always True: the allowances decide, as
    before.)"""
    if prob.parameter != "frequency":
        return lambda b, i, lam: True
    got = {}

    def same(b, i, lam):
        if not got:  # the candidate's states, once
            got["prob"] = P = copy.copy(prob)
            got["shifts"] = sh = _shifted_states(P, u, p)
            N = P.N2 // 2
            xs = max(float(np.max(np.abs(sh[:, :N]))), 1e-300)
            got["sc"] = np.r_[np.full(N, xs), np.full(N, xs * 2 * np.pi * p / P.order)]
        P = got["prob"]
        f0, f1 = float(b.frequency[i]), float(b.frequency[i + 1])
        if not (min(f0, f1) <= p * (1 + 2e-3) and p * (1 - 2e-3) <= max(f0, f1)):
            return False  # from a state of the branch 0.5 Hz off (the paper model's order 3
            # at 112.008 Hz) Newton landed on the point's orbit in one run, not in another
        if min(f0, f1) <= p <= max(f0, f1) and f1 != f0:
            lam = (p - f0) / (f1 - f0)  # the branch's state at this frequency
        s = b.state0[i] + lam * (b.state0[i + 1] - b.state0[i])
        try:
            model, ex = P.forcing(p)
            U = [s if b0 == 0 else P.flow_phases(model, ex, s, 0.0, b0).state
                 for b0 in P.boundaries]
            u2, ev, res, it = P.solve(np.ravel(U), p)
            s2 = P.state_at_zero(u2, p)[0]
        except (ConvergenceError, nlbeam.IntegrationError, np.linalg.LinAlgError, ValueError):
            return False
        return bool(np.min(np.max(np.abs(got["shifts"] - s2) / got["sc"], axis=1)) <= rel)
    return same


def _switch(tracer, pt, order):
    """Start the period-2T branch at a period-doubling point: the problem of twice the order
    with the -1 eigenvector as predictor direction. Returns (problem, u, p, t0) or None."""
    prob = pt.problem
    model, A, f = prob.setup(pt.p)
    U = pt.u.reshape(prob.n_seg, prob.N2)
    ev = prob.evaluate(pt.u, pt.p, jac=True, jac_p=False)
    M = prob.monodromy(ev.Ms)
    mu, V = la.eig(M)
    i = int(np.argmin(np.abs(mu + 1)))
    v = V[:, i].real
    vs = [v]
    for Mj in ev.Ms[:-1]:
        vs.append(la.matmul(Mj, vs[-1]))
    b2 = np.r_[prob.boundaries, prob.boundaries + prob.order]
    P2 = ShootingProblem(prob.base_model, prob.amplitude, prob.frequency, 2 * prob.order, b2,
                         prob.integrator, parameter=prob.parameter,
                         steps_per_period=prob.steps_per_period, scale_p=prob.scale_p)
    P2.sel_clearance = None if prob.sel_clearance is None else np.r_[prob.sel_clearance,
                                                                     prob.sel_clearance]
    u2 = np.r_[U.ravel(), U.ravel()]
    P2.scale_u = np.r_[prob.scale_u, prob.scale_u]
    d = np.r_[np.concatenate(vs), -np.concatenate(vs)] / P2.scale_u
    t0 = np.r_[d, 0.0]
    t0 /= la.norm(t0)
    return P2, u2, pt.p, t0


def _halves_vector(pt):
    """(state after half the period - state at the first boundary) / scales, of an orbit of
    even order: zero on an orbit of half the order."""
    prob = pt.problem
    model, ex = prob.forcing(pt.p)
    U = pt.u.reshape(prob.n_seg, prob.N2)
    fl = prob.flow_phases(model, ex, U[0], prob.boundaries[0], prob.order // 2, span_step=False)
    return (fl.state - U[0]) / prob.scale_u[:prob.N2]


def _halves_distance(pt):
    return float(np.max(np.abs(_halves_vector(pt))))


def _trace_switched(tracer, pt, order, branches=(), pd_values=(), overlap=None):
    P2, u2, p, t0 = _switch(tracer, pt, order)
    if overlap is None:  # (continuation.parallel records it instead)
        overlap = _overlap_stop(branches, 2 * order, skip=2)
    d0 = [None, 0.0]
    hist = []  # (p, halves vector, problem) of the points so far

    def stop(q):
        """The branch has come back to an orbit of half its order at a period doubling of the
        parent branch: the halves distance fell well below its maximum, or the branch passed
        through the period doubling's pitchfork onto its other half (the same orbits shifted
        by one parent period, which it would trace a second time). The latter: the halves
        vector turned over between two points (through zero), p turned back there (the two
        halves of a pitchfork lie on the same side of the period doubling; a branch that
        crosses the parent branch elsewhere, e.g. at a grazing point, keeps its direction in p
        and is followed on), and a period doubling of the parent branch (``pd_values``) lies
        within 5e-3 (relative; the diagram's values are off by up to 1.2e-3). The first rule
        alone let the 12.68-13.81 Hz branch of the paper model circle nine times (721 points)
        until it closed: its first point is often already a third of the way to the largest
        halves distance."""
        D = _halves_vector(q)
        d = float(np.max(np.abs(D)))
        if d0[0] is None:
            d0[0] = d
        d0[1] = max(d0[1], d)
        hist.append((q.p, D, q.problem))
        if d0[1] > 5 * d0[0] and d < 0.05 * d0[1]:
            return True
        if len(hist) < 4:
            return False
        (pa, Da, ra), (pb, Db, rb), (pc, Dc, rc), (pd, Dd, rd) = hist[-4:]
        return bool(ra is rb is rc is rd and la.dot(Db, Dc) < 0
                    and min(float(np.max(np.abs(Db))), float(np.max(np.abs(Dc)))) < 0.3 * d0[1]
                    and (pb - pa) * (pd - pc) < 0
                    and any(abs(pc - v) < 5e-3 * abs(v) for v in pd_values))

    # first point off the parent branch: a step along the eigenvector
    w, wp = P2.scale_u, P2.scale_p
    z0 = np.r_[u2 / w, p / wp]
    ds = 0.02
    for _ in range(8):
        try:
            z1, ev1, _ = tracer.correct(P2, z0 + ds * t0, t0)
            break
        except ConvergenceError:
            ds *= 0.5
    else:
        return None
    u1, p1 = z1[:-1] * w, z1[-1] * wp
    # orient along the direction away from the PD point
    pts, loc, reason = tracer.trace(P2, u1, p1, stop=_either(stop, overlap),
                                    t0=(z1 - z0) / la.norm(z1 - z0))
    if _halves_distance(pts[0]) < 1e-6:
        return None
    return pts, loc, ("period-doubling", reason)


def _overlap_stop(branches, order, skip=0):
    """A stop rule: the point has run onto an already traced branch of the same order (checked
    from the ``skip``-th point on): 'overlap' (Tracer.trace then lists the step's
    bifurcations), else False."""
    count = [0]

    def stop(pt):
        count[0] += 1
        if count[0] <= skip:
            return False
        m_, A_, f = pt.problem.setup(pt.p)
        hit = _on_branch(branches, order, f, pt.xmax,
                         lambda: _shifted_states(pt.problem, pt.u, pt.p),
                         same_orbit=_same_orbit_test(pt.problem, pt.u, pt.p))
        return "overlap" if hit is not None else False
    return stop


def _traced_already(branches, pts, order):
    """True when every point of ``pts`` (a traced stretch of this order) lies on one branch
    traced before (``_on_branch``)."""
    hits = set()
    for q in pts:
        m_, A_, f = q.problem.setup(q.p)
        bi = _on_branch(branches, order, f, q.xmax,
                        lambda q=q: _shifted_states(q.problem, q.u, q.p),
                        same_orbit=_same_orbit_test(q.problem, q.u, q.p))
        if bi is None:
            return False
        hits.add(bi)
    return len(hits) == 1


def _shifted_states(prob, u, p):
    """States at t = k / f, k = 0..order-1, of the orbit u of prob (rows)."""
    s0, d0 = prob.state_at_zero(u, p)
    out = [s0]
    if prob.order > 1:
        model, ex = prob.forcing(p)
        s, d = s0, d0
        for k in range(1, prob.order):
            fl = prob.flow_phases(model, ex, s, k - 1, 1, disc0=d, span_step=False)
            s, d = fl.state, fl.disc
            out.append(s)
    return np.array(out)


def _either(*rules):
    """A stop rule: the first true answer of ``rules`` (e.g. 'overlap'), else False."""
    return lambda pt: next((a for a in (r(pt) for r in rules) if a), False)


def _same_point(a, b, rel=1e-6):
    return (a.kind == b.kind and a.order == b.order
            and abs(a.value - b.value) <= rel * max(abs(a.value), 1e-300)
            and abs(a.xmax - b.xmax) <= 1e-4 * max(abs(a.xmax), 1e-300))


# GRAZING_RESOLUTION (continuation.pathfollow): the resolution of a grazing point in the
# parameter, relative (nlbeam.app.scenes.numbers prints grazing frequencies to it,
# GRAZING_REL): two changes of the number of impacts on one branch closer than this are one
# event of the diagram


def _merged_grazing(bf, bifs):
    """True when bf is a grazing point within the bracket of a grazing point of the same
    branch already in ``bifs``, or within GRAZING_RESOLUTION (relative) of it (the number of
    impacts changes more than once there: whether the tracer's steps resolve the changes one
    by one, or land between two of them at all, is up to round-off; measured: the paper
    model's order-2 branch at 67.4999-67.5037 Hz, 2 to 6 changes 4e-5 to 1.3e-3 Hz apart under
    parameters x (1 +- 1e-13)); that one's tolerance is widened to cover bf's bracket and its
    note counts the changes. The same for a bifurcation reported at a grazing point (not
    ``smooth``: a multiplier jumps across the unit circle there) next to one of its kind."""
    if bf.kind != "grazing" and bf.smooth:
        return False
    for o in bifs:
        if (o.kind == bf.kind and o.smooth == bf.smooth and o.branch == bf.branch
                and o.order == bf.order
                and abs(o.value - bf.value) <= (o.tolerance + bf.tolerance
                                                + GRAZING_RESOLUTION * abs(bf.value))):
            o.tolerance = max(o.tolerance, abs(o.value - bf.value) + bf.tolerance)
            o.note = _counted_note(o, _changes(o) + 1)
            return True
    return False


def _stated_error(bf):
    """A grazing point's (or a bifurcation's at one) error in the parameter: the largest of its
    bracket, its estimated integration error (where known) and GRAZING_RESOLUTION of it."""
    e = [float(bf.tolerance), GRAZING_RESOLUTION * abs(float(bf.value))]
    if np.isfinite(bf.error):
        e.append(float(bf.error))
    return max(e)


def _merged_clusters(bifs):
    """``bifs`` with every cluster of grazing points of one branch whose error intervals
    (value +- ``_stated_error``) overlap, one after the other, made one event; the same for
    bifurcations of one kind reported at grazing points. Which changes of the number of impacts
    inside such a cluster the tracer's steps resolve one by one is up to round-off (the paper
    model's order-2 branch at 67.4999-67.5037 Hz: 2 to 6 changes); that they lie within each
    other's errors is not. The member nearest the middle of the cluster is kept (its own value,
    xmax, state), its tolerance widened to cover every member's bracket and its note counting
    the changes (jumps)."""
    groups = {}
    for i, bf in enumerate(bifs):
        if bf.kind == "grazing" or not bf.smooth:
            groups.setdefault((bf.branch, bf.order, bf.kind, bf.smooth), []).append(i)
    drop = set()
    for idx in groups.values():
        idx.sort(key=lambda i: bifs[i].value)
        clusters, hi = [], -np.inf
        for i in idx:
            b = bifs[i]
            e = _stated_error(b)
            if clusters and b.value - e <= hi:
                clusters[-1].append(i)
                hi = max(hi, b.value + e)
            else:
                clusters.append([i])
                hi = b.value + e
        for c in clusters:
            if len(c) < 2:
                continue
            mid = 0.5 * (bifs[c[0]].value + bifs[c[-1]].value)
            keep = min(c, key=lambda i: (abs(bifs[i].value - mid), bifs[i].value))
            k = bifs[keep]
            n = sum(_changes(bifs[i]) for i in c)
            k.tolerance = max(abs(bifs[i].value - k.value) + bifs[i].tolerance for i in c)
            errs = [bifs[i].error for i in c if np.isfinite(bifs[i].error)]
            if errs:
                k.error = max(errs)
            k.note = _counted_note(k, n)
            drop.update(i for i in c if i != keep)
    return [b for i, b in enumerate(bifs) if i not in drop]


def _changes(bf):
    """How many changes of the number of impacts (jumps) a merged event counts (1 unmerged)."""
    note = bf.note
    if note.endswith("within the bracket"):
        return int(note.split()[0])
    if note.endswith("such jumps within the bracket)"):
        return int(note.rsplit(" (", 1)[1].split()[0])
    return 1


def _counted_note(bf, n):
    """bf's note counting n changes of the number of impacts (grazing) or n jumps of a
    multiplier (a bifurcation at grazing points: its own note, the count appended)."""
    if bf.kind == "grazing":
        return f"{n} changes of the number of impacts within the bracket"
    tail = " such jumps within the bracket)"
    head = bf.note
    if head.endswith(tail):
        head = head[:-len(tail)].rpartition(" (")[0]
    return f"{head} ({n}{tail}"


def _polished_starts(model, amplitude, frequency, parameter, orders, cand, segments,
                     integrator, variational, tol, dropped):
    """Newton-polished starting points of the candidates (f, order, state at t = 0, asked):
    a list of (f, order, problem, u, p, asked). A candidate that turns out to be an orbit of
    lower (minimal) order m is started as order m when m is asked for; every candidate that
    gives no start is said in ``dropped`` (and with a ContinuationWarning when the caller
    gave it)."""
    out = []
    for (f, n, s0, asked) in cand:
        d0 = None
        for attempt in range(2):  # the second: as an orbit of its minimal order
            try:
                prob, u0 = _problem_from_state(model, amplitude, f if parameter == "frequency"
                                               else frequency, n, s0, segments, integrator,
                                               variational=variational, disc0=d0)
                pval = f
                if parameter != "frequency":
                    prob.parameter = parameter
                    prob.scale_p = max(abs(prob.value()), 1e-300)
                    pval = prob.value()
                sol_prob, u, p = _polish(prob, u0, pval, tol)
            except (ConvergenceError, nlbeam.IntegrationError) as err:
                why = (f, f"the order-{n} candidate did not converge ({err})")
                if asked:
                    warnings.warn(
                        f"continuation: the start at {f:.9g} Hz (order {n}) did not converge"
                        f" and was dropped ({err}); give a better state (from integration to "
                        "the attractor, or a PeriodicSolution's state0), finer integration or "
                        "segments=4", ContinuationWarning, stacklevel=4)
                dropped.append(why)
                break
            m = sol_prob.minimal_order(u, p) if n > 1 else 1
            if m == n:
                out.append((f, n, sol_prob, u, p, asked))
                break
            why = (f, f"the order-{n} candidate is an orbit of order {m}, "
                   + ("started as such" if m in orders else "not asked for"))
            if asked:
                warnings.warn(f"continuation: the start at {f:.9g} Hz: {why[1]}",
                              ContinuationWarning, stacklevel=4)
            if m not in orders:
                dropped.append(why)
            if m not in orders or attempt:
                break
            s0, d0 = sol_prob.state_at_zero(u, p)
            n = m
    return out


def _run_diagram(model, amplitude, p_range, orders, parameter, frequency, tracer, integrator,
                 segments, n_grid, switch, starts, brute, variational=True, progress=None,
                 pool=None, early=None):
    """early: a continuation.accuracy.Early that starts the error estimates of each branch and
    bifurcation on the pool as it is added (while the next branches are traced)."""
    branches, bifs, pd_points = [], [], []
    ahead = None if pool is None or pool.serial else Speculator(pool)  # continuation.parallel
    t_start = time.perf_counter()
    say = progress if progress is not None else (lambda msg: None)
    cand = []
    dropped = []  # grid integrations and candidates that gave no start, and why
    if brute and parameter == "frequency":
        grid = np.linspace(p_range[0], p_range[1], n_grid)
        cand = brute_force(model, amplitude, grid, orders, integrator, segments=segments,
                           stability=variational, report=dropped, pool=pool)
        say(f"brute-force grid: {len(cand)} periodic attractors at {n_grid} frequencies "
            f"({time.perf_counter() - t_start:.1f} s)")
    cand = [(f, n, s0, False) for (f, n, s0) in cand] + [(f, n, s0, True) for (f, n, s0) in starts]
    seeds = _polished_starts(model, amplitude, frequency, parameter, orders, cand, segments,
                             integrator, variational, tracer.tol, dropped)
    if dropped:
        say(f"{len(dropped)} grid integration(s) or start(s) gave no starting point: "
            + "; ".join(f"{f:.6g} Hz: {why}" for f, why in dropped))

    def add(points, located, order, origin, ends):
        bi = len(branches)
        br = _to_branch(points, order, parameter, origin, ends)
        branches.append(br)
        n_bifs = len(bifs)
        for L in located:
            bf = _bifurcation(L, order, bi)
            if any(_same_point(bf, other) for other in bifs) or _merged_grazing(bf, bifs):
                continue  # where a branch ran onto another one, its end point is already listed
            bifs.append(bf)
            if L.kind == "period-doubling":
                # (one within a grazing point's resolution is reported there: switched from
                # its root on the smooth side, Located.root; one at a jump is not switched)
                root = getattr(L, "root", None)
                pd_points.append((L.point if root is None else root, order,
                                  bi if bf.smooth or root is not None else None))
        if early is not None:  # (once all are added: a grazing point may absorb the next)
            for bf in bifs[n_bifs:]:
                early.bifurcation(amplitude, bf)
            early.branch(bi, br, bifs)
        lo, hi = float(np.min(br.frequency)), float(np.max(br.frequency))
        say(f"branch {bi + 1} (order {order}, {origin}): {lo:.6g}-{hi:.6g} Hz, "
            f"{len(br.values)} points, {len(bifs) - n_bifs} bifurcations, ends: "
            f"{br.ends[0]} / {br.ends[1]} ({time.perf_counter() - t_start:.1f} s)")

    def on_branch(order, f, sol_prob, u, p):
        ev = sol_prob.evaluate(u, p, jac=False, jac_p=False)
        return _on_branch(branches, order, f, ev.xmax,
                          lambda: _shifted_states(sol_prob, u, p),
                          same_orbit=_same_orbit_test(sol_prob, u, p)) is not None

    def trace_from(f, order, sol_prob, u, p, origin, key=None):
        """The branch through the polished start (sol_prob, u, p), unless it lies on a traced
        branch (key: of its trace started ahead, if any)."""
        if on_branch(order, f, sol_prob, u, p):
            if ahead is not None:
                ahead.cancel(key)
            return
        tracer.label = f"order-{order} branch (from {f:.6g} Hz)"
        res = take(ahead, key, _overlap_stop(branches, order))
        pts, loc, ends = res if taken(res) else _both_ways(tracer, sol_prob, u, p,
                                                            stop=_overlap_stop(branches, order))
        add(pts, loc, order, origin, ends)

    def look_ahead(order, after=-1, n=2):
        """Start tracing the next n starts of this order after index ``after`` that lie on no
        traced branch (only where a pool is given; the result does not depend on it)."""
        if ahead is None:
            return
        for i, (f, o, sol_prob, u, p, _) in enumerate(seeds):
            if n <= 0:
                break
            if o != order or i <= after:
                continue
            n -= 1
            if not ahead.pending(i) and not on_branch(o, f, sol_prob, u, p):
                ahead.seed(i, tracer, f"order-{o} branch (from {f:.6g} Hz)", sol_prob, u, p)

    def fill_gaps(order, max_seeds=8):
        """Seed branches of this order inside the parts of p_range no branch covers (the
        tracer gave up at their ends, or the grid found no attractor there): from the steady
        state of an integration at the middle of each gap, then at its quarter points."""
        n_seeds = 0
        for fracs in ((0.5,), (0.25, 0.75)):
            for a, c in _gaps_to_seed(branches, p_range, order):
                for fr in fracs:
                    if n_seeds >= max_seeds:
                        return
                    f = a + fr * (c - a)
                    n_seeds += 1
                    try:
                        s0 = steady_state(model, amplitude, f, integrator=integrator)
                    except nlbeam.IntegrationError:
                        continue
                    for (f2, n2, sol_prob, u, p, _) in _polished_starts(
                            model, amplitude, frequency, parameter, (order,),
                            [(f, order, s0, False)], segments, integrator, variational,
                            tracer.tol, []):
                        trace_from(f2, n2, sol_prob, u, p, "gap")

    handled = set()
    for order in sorted(orders):
        look_ahead(order)
    for order in sorted(orders):
        for i, (f, n, sol_prob, u, p, asked) in enumerate(seeds):
            if n == order:
                trace_from(f, n, sol_prob, u, p, "start" if asked else "brute-force", key=i)
                look_ahead(order, i, n=1)  # (a start next to it often lies on its branch)
        if order == 1 and brute and parameter == "frequency":
            fill_gaps(order)
        # branch switching at period doublings of this order
        if switch and 2 * order in orders:
            pd_values = [q.p for q, o2, _ in pd_points if o2 == order]
            for k, (pt, o, bi) in enumerate(pd_points):
                if ahead is not None and o == order and bi is not None and k not in handled:
                    ahead.switch(("pd", k), tracer, f"order-{2 * order} branch (from the "
                                 f"period doubling at {pt.p:.6g})", pt, order, pd_values)
            for k, (pt, o, bi) in enumerate(pd_points):
                if o != order or k in handled or bi is None:
                    if ahead is not None:
                        ahead.cancel(("pd", k))
                    continue  # (bi None: at a grazing point, no eigenvector to switch along)
                handled.add(k)
                tracer.label = (f"order-{2 * order} branch (from the period doubling at "
                                f"{pt.p:.6g})")
                res = take(ahead, ("pd", k), _overlap_stop(branches, 2 * order, skip=2))
                if not taken(res):
                    res = _trace_switched(tracer, pt, order, branches, pd_values)
                if res is None:
                    continue
                pts, loc, ends = res
                end = pts[-1]
                if ends[1] == "stop" and _traced_already(branches, pts, 2 * order):
                    # the switched branch runs along one traced before (from the period
                    # doubling at its other end, whose end stopped short of this one by
                    # round-off): not a branch of its own
                    continue
                add(pts, loc, 2 * order, "period-doubling", ends)
                for k2, (pt2, o2, bi2) in enumerate(pd_points):
                    if o2 == order and k2 not in handled and \
                            abs(pt2.p - end.p) < 1e-3 * abs(end.p) + 1e-12:
                        handled.add(k2)
    if ahead is not None:
        ahead.close()
    _warn_hidden(dropped, branches, orders, n_grid, p_range)
    return branches, bifs, time.perf_counter() - t_start


def _stable_at(branches, f):
    """True when a stable stretch of some branch (two consecutive stable points) spans f."""
    for b in branches:
        if b.stable is None:
            return True  # stability unknown: nothing to say
        F = b.frequency
        lo, hi = np.minimum(F[:-1], F[1:]), np.maximum(F[:-1], F[1:])
        if np.any((lo <= f) & (f <= hi) & b.stable[:-1] & b.stable[1:]):
            return True
    return False


def _warn_hidden(dropped, branches, orders, n_grid, p_range):
    """One ContinuationWarning naming the grid frequencies where the integration reached an
    attractor that the diagram does not show: no periodic orbit of the orders asked for (or
    one that did not converge or is of another order), and no stable stretch of any branch
    there."""
    spacing = (p_range[1] - p_range[0]) / max(n_grid - 1, 1)
    where = {}
    for f, why in dropped:
        if not _stable_at(branches, f):
            where.setdefault(round(f, 9), why)
    if where:
        fs = sorted(where)
        warnings.warn(
            f"continuation: at {len(fs)} grid frequencies the integration reached no periodic "
            f"attractor of the orders asked for ({', '.join(map(str, orders))}) and no branch is "
            "stable there, so the diagram shows no attractor: "
            + "; ".join(f"{f:.6g} Hz: {where[f]}" for f in fs)
            + ". The attractor is chaotic, quasi-periodic or of another order (or its orbit did "
            "not converge); try more orders, a finer grid (n_grid; spacing now "
            f"{spacing:.3g} Hz), or look at the time series there (nlbeam.integrate).",
            ContinuationWarning, stacklevel=4)


_EARLY_ENDS = ("step underflow", "max_points", "could not move the segment boundaries",
               "stuck at a corner")
_GAVE_UP = _EARLY_ENDS + ("no progress",)  # ends where the tracer gave up (the orbit goes on)
_JUMP = "discontinuous map"  # ends where the fixed-step map jumps: no continuous branch goes on


# a branch end where the tracer gave up, or where the fixed-step map jumps, lies in a stretch
# where the number of impacts changes often (chattering contacts): where exactly the trace ends
# and which of the changes before it the tracer's steps resolve is up to round-off (the paper
# model, A = 0.1 mm, m, k, b, K_hertz x (1 +- 1e-13): the order-2 branch from 58 Hz ends at
# 66.561-66.568 Hz with 0-2 grazing points on its last 0.03 Hz; the one from 75 Hz at
# 67.4999-67.5054 Hz with 2-6 changes). The diagram declares the stretch unresolved: within
# CHATTER_REACH (relative) of the end, widened over the branch's own grazing points and
# bifurcations that follow each other within that reach.
CHATTER_REACH = 1e-3


def _unresolved(branches, bifs, p_range):
    """The stretches of p_range the diagram does not resolve (see CHATTER_REACH; not around
    an end at the point budget, 'max_points', which the coverage warning names with its own
    advice): a list of (order, lo, hi, what) sorted by order and lo, overlapping ones of an
    order merged."""
    lo_r, hi_r = min(p_range), max(p_range)
    raw = []
    events = [sorted(float(x.value) for x in bifs if x.branch == bi)
              for bi in range(len(branches))]
    for bi, b in enumerate(branches):
        for reason, v in ((b.ends[0], b.values[0]), (b.ends[1], b.values[-1])):
            v = float(v)
            if not (reason in _GAVE_UP or reason == _JUMP) or reason == "max_points" \
                    or not lo_r < v < hi_r:
                continue  # (the point budget ends a branch where the count says, anywhere)
            a, c, n = _chained(v, v, events[bi])
            raw.append((b.order, max(a, lo_r), min(c, hi_r),
                        f"branch {bi + 1} ends at {v:.6g} ({reason}); {n} of its "
                        f"bifurcations and grazing points lie there"))
    out = _merged_stretches(raw)
    # a branch that ran onto another one ('stop') inside a stretch of its order: which of the
    # two traces gave up there and which went on to run onto the other is up to round-off
    # (the paper model's order-3 branches at 110.6-110.9 Hz: in the reference the branch from
    # 155 Hz passes 110.90-110.83 Hz and stops on the one from 105 Hz, which gave up at
    # 110.717; with parameters x (1 + 1e-13) it is stuck at a corner at 110.896 Hz): the
    # stretch grows over that branch's events chained from the stretch's edges
    grown = True
    while grown:
        grown = False
        for bi, b in enumerate(branches):
            for reason, v in ((b.ends[0], b.values[0]), (b.ends[1], b.values[-1])):
                v = float(v)
                if reason != "stop":
                    continue
                for k, (o, a, c, what) in enumerate(out):
                    if o != b.order or not a <= v <= c:
                        continue
                    new = [x for x in events[bi] if (x < a and a - x <= CHATTER_REACH * abs(x))
                           or (x > c and x - c <= CHATTER_REACH * abs(x))]
                    if new:  # (each pass takes in one event at least: the loop ends)
                        a2, c2, _ = _chained(min(new), max(new), events[bi])
                        a2, c2 = max(min(a, a2), lo_r), min(max(c, c2), hi_r)
                        n = sum(a2 <= x <= c2 for x in events[bi])
                        note = f"; branch {bi + 1} runs onto another at {v:.6g} inside it"
                        what = what.split(note)[0]  # (its earlier count replaced)
                        out[k] = (o, a2, c2, what + note + f"; {n} of its bifurcations and "
                                  "grazing points lie there")
                        grown = True
        out = _merged_stretches(out)
    return out


def _chained(a, c, ev):
    """(a, c) widened over the events ev (sorted) that follow each other within CHATTER_REACH
    of f, then by CHATTER_REACH on either side; and how many events lie in it."""
    grown = True
    while grown:
        grown = False
        for x in ev:
            r = CHATTER_REACH * abs(x)
            if (x < a and a - x <= r) or (x > c and x - c <= r):
                a, c, grown = min(a, x), max(c, x), True
    a -= CHATTER_REACH * abs(a)
    c += CHATTER_REACH * abs(c)
    return a, c, sum(a <= x <= c for x in ev)


def _merged_stretches(raw):
    """(order, lo, hi, what) stretches sorted, overlapping ones of an order merged."""
    out = []
    for o, a, c, what in sorted(raw):
        if out and out[-1][0] == o and a <= out[-1][2]:
            out[-1] = (o, out[-1][1], max(out[-1][2], c), out[-1][3] + "; " + what)
        else:
            out.append((o, a, c, what))
    return out


def _unresolved_text(stretches, unit):
    return ("unresolved (around a branch end where the tracer gave up or the map jumps, "
            "mostly where the number of impacts changes often: where the branch ends, and "
            "which grazing points and bifurcations near its end are listed, may differ with "
            "round-off): " + "; ".join(
                f"order {o}: {a:.6g}-{c:.6g}{unit} ({what})" for o, a, c, what in stretches))


def _intervals(branches):
    """(lo, hi) parameter interval of each branch; an end where the branch ran onto a traced
    one ('stop', see _on_branch: within 2e-3 relative plus a twentieth of a segment) is
    widened by that tolerance and its last step, so that the two count as joined."""
    out = []
    for b in branches:
        v = np.asarray(b.values, dtype=float)
        lo, hi = float(v.min()), float(v.max())
        for reason, k, k2 in ((b.ends[0], 0, 1), (b.ends[1], -1, -2)):
            if reason == "stop" and len(v) > 1:
                tol = 2e-3 * abs(v[k]) + abs(v[k] - v[k2])
                if v[k] == lo:
                    lo -= tol
                if v[k] == hi:
                    hi += tol
        out.append((lo, hi))
    return out


def _gaps_to_seed(branches, p_range, order):
    """The parts of p_range that no branch of the order covers, except those next to a branch
    end that ran out of its point budget (max_points: the caller limited the work)."""
    lo, hi = min(p_range), max(p_range)
    bs = [b for b in branches if b.order == order]
    iv = _intervals(bs)
    out = []
    for a, c in _uncovered(iv, lo, hi):
        budget = [v for b in bs for r, v in ((b.ends[0], b.values[0]), (b.ends[1], b.values[-1]))
                  if r == "max_points" and min(abs(v - a), abs(v - c)) <= 1e-9 * (hi - lo)]
        if not budget:
            out.append((a, c))
    return out


def _uncovered(intervals, lo, hi):
    """Parts of [lo, hi] outside the union of the intervals (each (a, b), a <= b), as a list of
    (a, b); gaps narrower than 1e-9 of the range are ignored."""
    tol = 1e-9 * (hi - lo)
    gaps, cur = [], lo
    for a, b in sorted(intervals):
        if b < lo or a > hi:
            continue
        if a > cur + tol:
            gaps.append((cur, a))
        cur = max(cur, b)
    if cur < hi - tol:
        gaps.append((cur, hi))
    return gaps


def _coverage(branches, p_range, orders):
    """(gaps, early): the parts of p_range that no branch of a requested order covers, as
    (order, a, b, why), and the branch ends inside p_range where the tracer gave up, as text.
    Order 1 (a forced dissipative system has a periodic orbit of the excitation's period at
    every parameter value): every gap. Orders > 1 (subharmonics exist over parts of the range
    only): the gaps next to a branch end where the tracer gave up."""
    lo, hi = min(p_range), max(p_range)
    early = []
    for i, b in enumerate(branches):
        for reason, v in ((b.ends[0], b.values[0]), (b.ends[1], b.values[-1])):
            if (reason in _GAVE_UP or reason == _JUMP) and lo < v < hi:
                early.append(f"branch {i + 1} (order {b.order}) at {v:.6g} ({reason})")
    gaps = []
    for order in orders:
        bs = [b for b in branches if b.order == order]
        for a, c in _uncovered(_intervals(bs), lo, hi):
            ends = [(r, v) for b in bs for r, v in ((b.ends[0], b.values[0]),
                                                    (b.ends[1], b.values[-1]))
                    if (r in _GAVE_UP or r == _JUMP)
                    and min(abs(v - a), abs(v - c)) <= 1e-9 * (hi - lo)]
            if order == 1 or ends:
                jumps = [v for r, v in ends if r == _JUMP]
                why = ("bounded by a discontinuity of the fixed-step flow map at "
                       + ", ".join(f"{v:.9g}" for v in jumps) if jumps else
                       f"next to a branch end where the tracer gave up ({ends[0][0]})" if ends
                       else "no branch" if not bs else "no branch reaches it")
                gaps.append((order, a, c, why))
    return gaps, early


def _warn_turns(branches, bifs, parameter, unit):
    """One ContinuationWarning naming every place where a branch turns back in the parameter
    with no located fold (of that branch) or period doubling next to it
    (``turns.unexplained_turns``): the branch holds no point of the stretch beyond, and what it
    draws there is a chord across it."""
    found = []
    for i, br in enumerate(branches):
        marks = [(b.value, float(b.tolerance) if np.isfinite(b.tolerance) else 0.0)
                 for b in bifs if (b.kind == "fold" and b.branch == i)
                 or b.kind == "period-doubling"]
        found += [(i, br.order, v) for v in unexplained_turns(br.values, marks)]
    if found:
        where = "; ".join(f"branch {i} (order {n}) at {v:.9g}{' ' + unit if unit else ''}"
                          for i, n, v in found)
        warnings.warn(
            f"continuation: {len(found)} turn(s) of a branch in {parameter} where no fold or "
            f"period doubling was located: {where}. A step there passed a grazing point and a "
            "fold together (or the branch retraced itself), so the stretch beyond the turn has "
            "no point and is drawn as a chord; try a smaller ds_max or max_angle, finer "
            "integration (dt_scale=0.5, steps_per_contact=64), or continue_parameter from a "
            "point next to it", ContinuationWarning, stacklevel=3)


def _warn_coverage(branches, p_range, orders, parameter, unit, what_to_try, bifs=()):
    """One ContinuationWarning listing every part of p_range that no branch of a requested
    order covers (see ``_coverage``), the branch ends inside it where the tracer gave up and
    the stretches around them the diagram does not resolve (``_unresolved``); an empty
    diagram always warns."""
    gaps, early = _coverage(branches, p_range, orders)
    unit = f" {unit}" if unit else ""
    stretches = _unresolved(branches, bifs, p_range)
    parts = []
    if not branches:
        parts.append(f"no branch of order(s) {', '.join(map(str, orders))} was found between "
                     f"{min(p_range):.6g} and {max(p_range):.6g}{unit}")
    if gaps:
        parts.append("not covered: " + "; ".join(
            f"order {o}: {a:.6g}-{c:.6g}{unit} ({why})" for o, a, c, why in gaps))
    jumps = [e for e in early if e.endswith(f"({_JUMP})")]
    early = [e for e in early if e not in jumps]
    if early:
        parts.append(f"{len(early)} branch end(s) inside the range where the tracer gave up: "
                     + "; ".join(early))
    if jumps:
        parts.append(f"{len(jumps)} branch end(s) at a discontinuity of the fixed-step flow "
                     "map (a contact that ends and restarts within a step, or the "
                     "Lankarani-Nikravesh onset-velocity memory reset: no continuous branch "
                     "of the discrete map goes on there): " + "; ".join(jumps))
    if stretches:
        parts.append(_unresolved_text(stretches, unit))
    if parts:
        warnings.warn(
            f"continuation: the {parameter} range is not fully covered: " + ". ".join(parts)
            + ". The diagram may miss what lies there; " + what_to_try
            + " Branch.ends says why each branch ended.", ContinuationWarning, stacklevel=3)
    return gaps, early


def _polish(prob, u0, p, tol):
    """Newton at fixed p, moving the boundaries out of contact once if needed."""
    u, ev, res, it = prob.solve(u0, p, tol=tol)
    if prob.needs_rephase(u, p) or np.any(prob.boundary_clearance(u, p) <= 0):
        prob, u = prob.rephased(u, p)
        u, ev, res, it = prob.solve(u, p, tol=tol)
    return prob, u, p


def _harmonic_amplitudes(model, amplitude, f, state0, n_samples=512, integrator=None):
    """Amplitudes of the harmonics k = 0..n/2 of f of the response relative to the excitation
    (x - y of the output DOF for base excitation, x for force excitation) over one period,
    integrated with ``integrator`` (default Integrator()) at n_samples steps (or, adaptive,
    samples) per period."""
    integrator = integrator or Integrator()
    tr = integrator.integrate(model, forcing(amplitude, f), 1 / f, period_step(f, n_samples),
                              x0=state0)
    sig = tr.x[:-1, model.output_dof]
    if model.excitation_kind == "base":
        sig = sig - tr.y[:-1]
    return 2 * np.abs(np.fft.rfft(sig - sig.mean())) / len(sig)


def _vertex(f, x):
    """Peak (f, x) of the parabola x(s) through three branch points, s the arclength in the
    plane (f / f_mid, x / x_mid); f(s) interpolated by the parabola through the same points."""
    F, X = f / f[1], x / x[1]
    s = np.r_[0.0, np.cumsum(np.hypot(np.diff(F), np.diff(X)))]
    V = np.column_stack([s * s, s, np.ones(3)])  # the parabolas through the three points
    cx = la.solve(V, x)
    if cx[0] >= 0:
        return float(f[1]), float(x[1])
    s_star = float(np.clip(-cx[1] / (2 * cx[0]), s[0], s[-1]))
    return float(np.polyval(la.solve(V, f), s_star)), float(np.polyval(cx, s_star))


def _superharmonics(branches, model, integrator, orders=(2, 3), window=0.15, min_ratio=0.15):
    """Superharmonic resonances of order k on the harmonic (order-1) branches: among the local
    maxima of xmax along a branch with k f within ``window`` (relative) of the main resonance
    (the frequency of the largest xmax), the one where the k-th harmonic of the relative
    response is largest, if it is at least ``min_ratio`` of the first. The frequency is that
    of the branch point (tolerance: half the distance to its neighbours) of the vertex of a
    parabola through the peak point and its neighbours. The harmonics are integrated with
    ``integrator``."""
    out = []
    ones = [(bi, b) for bi, b in enumerate(branches) if b.order == 1 and len(b.xmax) >= 3]
    if not ones:
        return out
    bi_res, b_res = max(ones, key=lambda ib: ib[1].xmax.max())
    f_res = float(b_res.frequency[np.argmax(b_res.xmax)])
    peaks = []
    for bi, b in ones:
        x = b.xmax
        for i in range(1, len(x) - 1):
            if x[i] > x[i - 1] and x[i] >= x[i + 1]:
                peaks.append((bi, i, float(b.frequency[i]), float(x[i])))
    for k in orders:
        best = None
        for bi, i, f, xm in peaks:
            if abs(k * f / f_res - 1) >= window:
                continue
            b = branches[bi]
            X = _harmonic_amplitudes(model, b.amplitude[i], f, b.state0[i],
                                     integrator=integrator)
            if X[k] >= min_ratio * X[1] and (best is None or X[k] > best[0]):
                best = (X[k], float(X[k] / X[1]), bi, i)
        if best is not None:
            _, ratio, bi, i = best
            b = branches[bi]
            f = b.frequency[i]
            fp, xp = _vertex(b.frequency[i - 1:i + 2], b.xmax[i - 1:i + 2])
            tol = 0.5 * float(max(abs(b.frequency[i + 1] - f), abs(f - b.frequency[i - 1])))
            out.append(Superharmonic(fp, xp, k, bi, ratio, tol))
    return out


def frequency_response(model, amplitude, f_range, orders=(1, 2, 3), *, n_grid=30, segments=1,
                       integrator=None, switch=True, brute_force_grid=True, starts=(),
                       ds=0.02, ds_max=0.5, max_angle=0.2, max_points=1000, tol=1e-10,
                       bif_tol=1e-8, stability=True, progress=None, accuracy=None,
                       workers=1, scheduler=None, **integrator_kw):
    """The |x|max-versus-frequency diagram at excitation amplitude (m, or N for force).

    f_range: (f_lo, f_hi) Hz. Branches of each order in ``orders`` start from periodic
    attractors found by integration on a grid of n_grid frequencies (sweeping up and down;
    isolas too) and by branch switching at period doublings (order n -> 2n). Where no order-1
    branch covers part of f_range (the tracer gave up at both sides of it), branches are
    seeded from integrations to the steady state inside it (its middle, then its quarter
    points; origin 'gap'), unless the point budget ended the branches there. Each branch is
    followed by pseudo-arclength continuation (adaptive step ds in scaled units, at most
    max_angle rad between tangents) until it leaves f_range or closes. Folds, period doublings
    and Neimark-Sacker points are located to a bracket of bif_tol relative width in f.

    Corners: where the number of impacts per period changes (a grazing orbit), the flow map is
    not smooth and the branch may go straight through or turn back. It turns back only where
    a real multiplier passes +1 (the sign of prod(mu - 1) changes: a fold, smooth or at the
    corner); every step through a corner is checked for that and for joining the two sides
    through the grazing point (bisection of the chord). Where steps fail at a corner the
    tracer tries, in turn: fixed-frequency solves on the far side, beyond the corner and (for
    a fold) behind it, each checked the same way; shorter steps; multiple shooting (2, then 4
    segments). If all fail the branch ends with 'stuck at a corner' and a ContinuationWarning
    naming the frequency. A point that runs back along a stretch the branch has already
    traced is caught at once: its stretch is dropped and the corner passed again; a branch
    that comes round to its start ends as 'closed (isola)'. Branch.ends says why each branch
    ended (see Branch). One ContinuationWarning lists every part of f_range that no branch of
    order 1 covers, the gaps next to branch ends of higher orders where the tracer gave up,
    and those ends; an empty diagram always warns.
    starts: extra (frequency, order, state at t = 0) starting points.
    stability=False: no variational equations and no Floquet multipliers (quasi-Newton
    corrector from forward differences and secant updates): every branch has ``stable`` and
    ``multipliers`` None (stability unknown), folds are still passed and located (where the
    tangent turns back in frequency), but period doublings and Neimark-Sacker points are not
    detected, so orders > 1 come from the brute-force grid only. xmax is the same as with
    stability (the same discrete orbits).
    progress: callable(str), called with a one-line status after the brute-force grid and after
    each branch (its range in Hz, points, bifurcations, elapsed s); None for silence.
    accuracy: None or 'default' (6 significant digits), 'high' (8), a number of digits, or
    'off': every fold, period doubling and Neimark-Sacker point is located again with the step
    halved, quartered, ... until its stated ``error`` (Hz) meets that many digits (its
    frequency becomes the finer, extrapolated value); grazing points are located once more
    with the step halved; every branch point gets error estimates of xmax and of the
    multipliers, and its multipliers and stability flag are those of the orbit carried to
    the step halved, quartered, ... while their error misses the target (extrapolated where
    the changes show order 4; continuation.accuracy.branch_errors, estimate_diagram). One
    ContinuationWarning lists what misses the target (multipliers: 10^-(digits - 1)); the
    branch points stay those of the integrator (dt_scale, steps_per_contact) given.
    workers: local processes (None: the CPU count; default 1, this process only), scheduler:
    a Dask scheduler address or distributed.Client (nlbeam.pool): the brute-force sweeps,
    branches and error estimates run in parallel, with exactly the serial result (branches
    are traced ahead of their turn and taken only where the serial trace would have been the
    same, continuation.parallel; the error estimates of each branch and bifurcation start as
    it is added, while the next ones are traced, and are taken where their inputs are still
    the same, continuation.accuracy.Early).
    Returns a FrequencyResponse (``settings['stability']`` says which).
    """
    _args.check_integrator("frequency_response", integrator, integrator_kw,
                           inspect.signature(frequency_response).parameters)
    _args.check_frequency_response(model, amplitude, f_range, orders, n_grid, segments, switch,
                                   brute_force_grid, starts, stability, progress)
    _args.check_trace(ds, ds_max, max_angle, max_points, tol, bif_tol)
    _args.check_accuracy(accuracy)
    integrator = integrator or Integrator(**integrator_kw)
    f_lo, f_hi = map(float, f_range)
    if not (0 < f_lo < f_hi):
        raise ValueError(f"f_range: must be (f_lo, f_hi) with 0 < f_lo < f_hi Hz, got {f_range!r}")
    orders = tuple(sorted(set(int(o) for o in orders)))
    tracer = Tracer(p_min=f_lo, p_max=f_hi, ds=ds, ds_max=ds_max, max_angle=max_angle,
                    max_points=max_points, tol=tol, bif_tol=bif_tol)
    t0 = time.perf_counter()
    pool = Pool(workers, scheduler)
    _kernels_before_workers(model, pool, stability)
    early = None
    if not (isinstance(accuracy, str) and accuracy == "off"):
        # (serial too: a branch's estimates right after its trace find its level-0 flows
        # still kept, continuation._flowcache)
        from .accuracy import Early

        early = Early(pool, model, integrator, "frequency", accuracy, segments)
    try:
        branches, bifs, _ = _run_diagram(model, amplitude, (f_lo, f_hi), orders, "frequency", None,
                                         tracer, integrator, segments, n_grid,
                                         switch and stability, list(starts), brute_force_grid,
                                         variational=stability, progress=progress, pool=pool,
                                         early=early)
        _warn_coverage(branches, (f_lo, f_hi), orders, "frequency", "Hz",
                       "try a start inside it (starts=[(f, order, state0)], e.g. from "
                       "periodic_solution), a finer brute-force grid (n_grid), finer integration "
                       "(dt_scale=0.5, steps_per_contact=64), multiple shooting (segments=4), a "
                       "smaller ds_max or max_points larger.", bifs)
        _warn_turns(branches, bifs, "frequency", "Hz")
        sup = _superharmonics(branches, model, integrator)
        frc = FrequencyResponse(model_parameters=model.parameters(), amplitude=float(amplitude),
                                parameter="frequency", p_range=(f_lo, f_hi), branches=branches,
                                bifurcations=bifs, superharmonics=sup,
                                settings=dict(_settings(integrator, segments, n_grid, ds, ds_max,
                                                        max_angle, tol, bif_tol, orders),
                                              stability=int(bool(stability))))
        frc.n_points = int(sum(len(b.values) for b in branches))
        _estimate(frc, model, integrator, accuracy, segments, progress, pool, early)
        frc.bifurcations = _merged_clusters(frc.bifurcations)
        frc.wall_time = time.perf_counter() - t0
        return frc
    finally:
        if early is not None:
            early.close()
        pool.close()


def _kernels_before_workers(model, pool, variational):
    """The integration kernels compiled (or loaded from numba's disk cache) here before the
    pool forks its workers, which inherit them: otherwise every worker compiles the plain
    kernel at once on a fresh machine (each of its step functions too)."""
    if pool.serial:
        return
    from nlbeam.integrate import compile_kernels

    compile_kernels(model, False)
    if variational:
        compile_kernels(model, True)


def continue_parameter(solution, parameter, p_range, *, model, segments=1, integrator=None,
                       ds=0.02, ds_max=0.5, max_angle=0.2, max_points=1000, tol=1e-10,
                       bif_tol=1e-8, accuracy=None, **integrator_kw):
    """Follow a PeriodicSolution of ``model`` in ``parameter`` ('amplitude', 'frequency', or a
    model parameter as nlbeam.parameters names it: 'e', 'K_hertz', 'gap' of the paper beam,
    'elements[1].gap' of a System, ...) over p_range, both ways, through corners as in
    frequency_response. Returns a FrequencyResponse with one branch (and the bifurcations on
    it); a ContinuationWarning lists the parts of p_range the branch does not cover (for an
    order-1 solution; for higher orders the gaps next to ends where the tracer gave up).
    accuracy: as for frequency_response (errors in the units of the parameter)."""
    _args.check_integrator("continue_parameter", integrator, integrator_kw,
                           inspect.signature(continue_parameter).parameters)
    _args.check_model(model)
    check_parameter(model, parameter, extra=("frequency", "amplitude"))
    if not isinstance(solution, PeriodicSolution):
        raise _args.ArgumentTypeError(f"solution: must be a continuation.PeriodicSolution, got "
                                      f"{type(solution).__name__}")
    _args.check_p_range(parameter, model, p_range, solution)
    _args.integer("segments", segments, 1, _args.MAX_SEGMENTS)
    _args.check_trace(ds, ds_max, max_angle, max_points, tol, bif_tol)
    _args.check_accuracy(accuracy)
    integrator = integrator or Integrator(**integrator_kw)
    lo, hi = map(float, p_range)
    tracer = Tracer(p_min=lo, p_max=hi, ds=ds, ds_max=ds_max, max_angle=max_angle,
                    max_points=max_points, tol=tol, bif_tol=bif_tol)
    t0 = time.perf_counter()
    prob, u0 = _problem_from_state(model, solution.amplitude, solution.frequency, solution.order,
                                   solution.state0, segments, integrator)
    prob.parameter = parameter
    # the parameter's scale: its value, or the range where it starts at 0 (a gap of 0 m)
    prob.scale_p = abs(prob.value()) if prob.value() != 0 else max(hi - lo, 1e-300)
    prob, u, p = _polish(prob, u0, prob.value(), tol)
    pts, loc, ends = _both_ways(tracer, prob, u, p)
    br = _to_branch(pts, solution.order, parameter, "start", ends)
    _warn_coverage([br], (lo, hi), (solution.order,), parameter,
                   "Hz" if parameter == "frequency" else "",
                   "try continuing from a solution inside it, finer integration (dt_scale=0.5, "
                   "steps_per_contact=64), multiple shooting (segments=4), a smaller ds_max or "
                   "max_points larger.")
    bifs = []
    for L in loc:
        bifs.append(_bifurcation(L, solution.order, 0))
    _warn_turns([br], bifs, parameter, "Hz" if parameter == "frequency" else "")
    frc = FrequencyResponse(model_parameters=model.parameters(), amplitude=solution.amplitude,
                            parameter=parameter, p_range=(lo, hi), branches=[br],
                            bifurcations=bifs,
                            settings=_settings(integrator, segments, 0, ds, ds_max, max_angle,
                                               tol, bif_tol, (solution.order,)))
    frc.n_points = len(br.values)
    _estimate(frc, model, integrator, accuracy, segments, None)
    frc.bifurcations = _merged_clusters(frc.bifurcations)
    frc.wall_time = time.perf_counter() - t0
    return frc


def _estimate(frc, model, integrator, accuracy, segments, progress, pool=None, early=None):
    """Error estimates of the diagram's points and bifurcations (continuation.accuracy), one
    ContinuationWarning listing what misses the target; settings['accuracy'] says which."""
    if isinstance(accuracy, str) and accuracy == "off":
        frc.settings["accuracy"] = "off"
        return
    from .accuracy import estimate_diagram, target_digits

    digits = target_digits(accuracy)
    frc.settings["accuracy"] = digits
    t = time.perf_counter()
    tied = _grazing_partners(frc.bifurcations)
    notes = estimate_diagram(frc, model, integrator, accuracy=accuracy, segments=segments,
                             pool=pool, early=early)
    for bf, g in tied:  # an event at a grazing point has that grazing point's value and error
        if np.isfinite(g.error):
            bf.value, bf.frequency, bf.error = g.value, g.frequency, g.error
    if progress is not None:
        progress(f"error estimates: {len(frc.bifurcations)} bifurcations, "
                 f"{sum(int(b.error_sampled.sum()) for b in frc.branches)} branch points "
                 f"({time.perf_counter() - t:.1f} s)")
    if notes:
        warnings.warn(
            f"continuation: accuracy below the {digits:g} significant digits asked for "
            f"(multipliers to {10.0 ** -(digits - 1):.0e}): " + notes + ". Branch points are "
            "those of the integrator given: more steps per contact (steps_per_contact=64; "
            "the multipliers' error at the defaults is the contact steps', which halving "
            "dt_scale leaves) and finer integration (dt_scale=0.5) improve them; "
            "Bifurcation.error and Branch.multipliers_error give the estimates.",
            ContinuationWarning, stacklevel=3)


def _grazing_partners(bifs):
    """(bifurcation reported at a grazing point, that grazing point) pairs: the grazing point
    of its branch nearest it within the sum of their brackets. Located again on its own, such
    an event can land elsewhere than its grazing point (the paper model's order-2 fold at
    9.33417 Hz, a turn at the corner reported at the bracket's other end: its own relocation
    failed in the reference and kept its bracket, 9.334172 +- 1.9e-5, while its grazing point
    was estimated at 9.333900 +- 1.4e-4, as the fold was under A x (1 + 1e-13))."""
    out = []
    for bf in bifs:
        if bf.kind == "grazing" or bf.smooth:
            continue
        near = [g for g in bifs if g.kind == "grazing" and g.branch == bf.branch
                and g.order == bf.order and abs(g.value - bf.value)
                <= g.tolerance + bf.tolerance + 1e-12 * abs(g.value)]
        if near:
            out.append((bf, min(near, key=lambda g: abs(g.value - bf.value))))
    return out


def _settings(integ, segments, n_grid, ds, ds_max, max_angle, tol, bif_tol, orders):
    return {"method": integ.method, "dt_scale": integ.dt_scale,
            "steps_per_contact": integ.steps_per_contact, "rtol": integ.rtol, "atol": integ.atol,
            "segments": segments, "n_grid": n_grid, "ds": ds, "ds_max": ds_max,
            "max_angle": max_angle, "tol": tol, "bif_tol": bif_tol,
            "orders": ",".join(map(str, orders))}
