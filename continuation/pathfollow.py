"""Pseudo-arclength continuation with bifurcation detection, over a small protocol
(``Problem``: what the Tracer asks of a problem; continuation.shooting.ShootingProblem is one).
Work is done in scaled variables (u / scale_u, p / scale_p).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from nlbeam import _linalg as la
from ._newton import ContinuationWarning, ConvergenceError
from . import kinks
from .corners import (JUMP_HS, Retrace, check_crossing, far_side, fold_ahead, map_jump,
                      smooth_fold_beside, tangent)

KINDS = ("fold", "period-doubling", "neimark-sacker")  # from the test functions

# the resolution of a grazing point in the parameter, relative (nlbeam.app.scenes.numbers
# prints grazing frequencies to it, GRAZING_REL): two events of one branch closer than this
# to each other are one event of the diagram (continuation.diagram merges grazing points;
# ``at_grazing_points`` puts a fold, period doubling or Neimark-Sacker point within it of a
# grazing point at the grazing point)
GRAZING_RESOLUTION = 1e-5


class Problem(Protocol):
    """The problem R(u, p) = 0 (n equations, n unknowns u, one parameter p) a Tracer follows.

    Required:
    - ``scale_u`` (n,), ``scale_p``: the scales of the unknowns and of the parameter;
    - ``evaluate(u, p, jac=True, jac_p=True)`` -> an evaluation with ``R`` (n,), ``Ju``
      (dR/du (n, n) or None), ``Jp`` (dR/dp (n,) or None), ``Ms`` (what ``multipliers``
      takes; empty without), ``xmax`` and ``n_impacts`` (an int that changes at a grazing
      point); the Tracer sets ``B``, ``C`` and ``lazy_p`` on it;
    - ``jacobian_p(u, p, ev=None)`` -> dR/dp (n,) (ev: the evaluation at (u, p), if any);
    - ``multipliers(Ms)`` -> Floquet multipliers, largest modulus first;
    - ``solve(u0, p, tol=...)`` -> (u, evaluation, residual, iterations) at fixed p, or
      raises ConvergenceError;
    - ``adapt(u, p)`` -> None, or (problem, u) after the unknowns were redefined (e.g. the
      segment boundaries moved), with ``transfer(old_problem, u_old, p)`` -> u of the same
      orbit in this problem's unknowns.

    Optional (a problem class that subclasses Problem inherits these defaults):
    - ``variational`` (default True): ``evaluate(jac=True)`` gives dR/du (from variational
      equations). False: ``evaluate`` gives none, and the Tracer takes dR/du from
      ``jacobian_u``, which such a problem must then provide;
    - ``jacobian_u(u, p, ev=None)`` -> dR/du (n, n) by differences (default: raises);
    - ``settle(u, p, p_new, efolds)`` -> u at p_new of the attractor reached from the orbit u
      at p (one of the ways past a corner in ``corners.far_side``; default: raises
      ConvergenceError, so that way is skipped);
    - ``parameter`` (default 'p'): the parameter's name, for messages;
    - ``signature(u, p)`` -> a vector that identifies the orbit independently of how the
      unknowns are defined (the retrace detector compares points by it across ``adapt``;
      default: u);
    - ``n_seg`` (default 1) and ``with_segments(u, p, n_seg)`` -> (problem, u) of the same orbit
      with n_seg shooting segments (the last way past a corner; default: None, not offered).
    """

    scale_u: np.ndarray
    scale_p: float
    variational: bool = True
    parameter: str = "p"
    n_seg: int = 1

    def evaluate(self, u, p, jac=True, jac_p=True): ...

    def jacobian_p(self, u, p, ev=None): ...

    def multipliers(self, Ms): ...

    def solve(self, u0, p, tol=1e-10): ...

    def adapt(self, u, p): ...

    def transfer(self, old, u_old, p): ...

    def jacobian_u(self, u, p, ev=None):
        raise NotImplementedError(f"jacobian_u: {type(self).__name__} has variational = False "
                                  "and must give dR/du")

    def settle(self, u, p, p_new, efolds=8.0):
        raise ConvergenceError(f"settle: not offered by {type(self).__name__}")

    def signature(self, u, p):
        return np.asarray(u, dtype=float)

    def with_segments(self, u, p, n_seg):
        return None


@dataclass
class Point:
    u: np.ndarray
    p: float
    xmax: float
    multipliers: np.ndarray
    problem: object
    n_impacts: int = 0
    jac: np.ndarray | None = None  # scaled [dR/du | dR/dp] (n, n + 1) at the point (quasi-Newton)
    corr: np.ndarray | None = None  # its secant correction (see Tracer.correct)
    tangent: np.ndarray | None = None  # unit tangent (scaled) in the direction of travel
    how: str = "step"  # how it was reached: 'start', 'step', 'corner' (a step through a
    # grazing point, checked), 'jump' (a fixed-parameter solve past a corner)
    state0: np.ndarray | None = None  # Problem.signature (shooting: the state at phase zero)


@dataclass
class Located:
    """A bifurcation located on a traced branch. tolerance: width of the final bracket in p."""

    kind: str
    point: Point
    tolerance: float
    index: int  # the branch point before it
    note: str = ""  # e.g. 'at grazing: ...' where a multiplier jumps across the unit circle
    root: Point | None = None  # where one reported at a grazing point was located on a smooth
    # side next to it (at_grazing_points): the point on the smooth branch (branch switching)
    placed: bool = True  # False: not located (reported at the end of its bracket)


def test_functions(mu):
    """(fold, period-doubling, Neimark-Sacker) test functions of the multipliers: each changes
    sign when a multiplier crosses +1, -1, or a complex pair the unit circle."""
    mu = np.asarray(mu)
    tf = float(np.prod(mu - 1.0).real)
    tpd = float(np.prod(mu + 1.0).real)
    n = len(mu)
    tns = 1.0 + 0j
    for i in range(n):
        for j in range(i + 1, n):
            tns *= mu[i] * mu[j] - 1.0
    return np.array([tf, tpd, tns.real])


def _scaled(ev, w, wp):
    J = np.hstack([ev.Ju * w[None, :], (ev.Jp * wp)[:, None]]) / w[:, None]
    return ev.R / w, J


class Tracer:
    """Follows one branch of a ``Problem``. Options: p_min, p_max (stop outside), ds (initial
    step, scaled), ds_min, ds_max, max_angle (rad, between successive tangents), max_points,
    tol (corrector, scaled residual; where the iteration stagnates below noise_tol, as where
    contacts nearly stick and the fixed-step map has noise of 1e-8..1e-7, the better iterate
    is accepted), bif_tol (relative width in p of the bracket of a located bifurcation),
    detect (bool), grazing_ds (longest step, scaled, that may change the number of impacts per
    period: longer ones are halved), progress_points / progress_min (the no-progress rule: a
    branch whose last ``progress_points`` points together advance less than ``progress_min``
    in scaled arclength is stopped with a ContinuationWarning), label (names the branch in
    that warning).
    Corners (where the number of impacts per period changes; see continuation.corners):
    fold_margin (a real multiplier closer than this to +1 leaves the fold sign uncertain),
    turn_tol (a tangent's parameter component below this leaves the direction uncertain),
    retrace_tol (a point within this fraction of a segment's length of a traced segment
    re-enters it), corner_segments (shooting segments tried, in turn, at a corner that single
    shooting cannot pass), probe_after (after this many failed steps in a row at one point,
    and after every as many more, the map is probed for a jump just ahead, corners.map_jump,
    at the cost of eight flows without variational equations: where it jumps, no shorter step,
    far-side solve or extra segment can go on, and the branch ends there as 'discontinuous
    map' at once; 0: only once every other way has failed), creep_mu_step (a fixed-parameter
    creep towards a corner that keeps the number of impacts is taken only where the
    multipliers moved by at most this, or every test function that changes sign on it is
    located on it; else a shorter one: see ``corners.far_side``).
    Kinks (the map not smooth, the number of impacts the same; see continuation.kinks): where
    failed steps at one point show one ahead (``kinks.signal``: the predictor's residual falls
    only linearly with the step and the first Newton step multiplies it), after ``jump_after``
    failures the kink is crossed from the far side once per point (``kinks.crossing``) at
    the parameter distances ``kink_steps`` times the longest failed step's (scaled) and the
    relative ``jump_steps``, nearest first; where no solution lies beyond it, the same
    distances behind the point are tried for a strand that turns back at the kink
    (``kinks.turn``: started beyond the kink, joined through it, the sign of prod(mu - 1)
    changed), reported as a fold with the note 'at a kink'; () turns both off.

    The corrector is a quasi-Newton iteration on the bordered system: the Jacobian at the
    predictor is dR/du from the variational equations (or, for a problem without them, the
    previous point's Jacobian, or forward differences) with dR/dp carried from the previous
    point, and every iterate updates it by Broyden's rank-one secant formula. With lazy_var
    the iterates after the predictor are flows without the variational equations (a flow
    with them costs 3.2 times one without at N = 1, 5.8 at N = 4), except one whose residual,
    at the last ratio of residuals, is expected below tol; an accepted iterate without them
    is evaluated again with them (the multipliers are always those of the accepted point).
    A lazy iteration that converges steadily but linearly below noise_tol gets up to max_iter
    more iterations where, at its last ratios, tol lies within them.
    lazy_var None (default): for systems of more than one DOF (more than two states);
    True / False: always / never. (On the 1-DOF paper diagram,
    lazy_var=True took 25.5 against 33.3 s CPU but converged to other points within tol,
    which changed the step sequence and the diagram: 1843 against 1743 points, 17 against 14
    branches: three more period-doubling bubbles found, 38 against 42 folds.) The variational
    monodromy is the derivative of the exact flow, not of the fixed-step map whose fixed point
    is solved for (the contact steps depend on the state); where the two differ by more than a
    few per cent (soft, chattering contacts; orbits with multipliers >> 1) plain Newton only
    converges linearly and the step control used to creep. The secant updates make the
    iteration converge superlinearly to the discrete map's fixed point there too."""

    def __init__(self, *, p_min=-np.inf, p_max=np.inf, ds=0.02, ds_min=1e-7, ds_max=0.1,
                 max_angle=0.15, max_points=3000, tol=1e-10, bif_tol=1e-10, detect=True,
                 max_iter=10, jump_after=2, jump_steps=(1e-5, 1e-4, 1e-3), jump_max_distance=0.05,
                 grazing_iter=8, grazing_ds=0.01, contraction=0.7, noise_tol=1e-7,
                 progress_points=40, progress_min=2e-3, label="branch", fold_margin=0.05,
                 turn_tol=1e-3, retrace_tol=0.1, corner_segments=(2, 4), probe_after=3,
                 creep_mu_step=0.25, lazy_var=None, kink_steps=(2.0, 16.0)):
        self.p_min, self.p_max = p_min, p_max
        self.kink_steps = tuple(kink_steps)
        self.creep_mu_step = creep_mu_step
        self.ds0, self.ds_min, self.ds_max = ds, ds_min, ds_max
        self.max_angle = max_angle
        self.max_points = max_points
        self.tol = tol
        self.bif_tol = bif_tol
        self.detect = detect
        self.max_iter = max_iter
        self.jump_after = jump_after
        self.jump_steps = tuple(jump_steps)
        self.jump_max_distance = jump_max_distance
        self.grazing_iter = grazing_iter
        self.grazing_ds = grazing_ds
        self.contraction = contraction
        self.noise_tol = max(noise_tol, tol)
        self.progress_points = progress_points
        self.progress_min = progress_min
        self.label = label
        self.fold_margin = fold_margin
        self.turn_tol = turn_tol
        self.retrace_tol = retrace_tol
        self.corner_segments = tuple(corner_segments)
        self.probe_after = int(probe_after)
        self.lazy_var = lazy_var
        self.n_evaluations = 0  # flows asked for (with or without variational equations)
        self.n_variational = 0  # of those, the correctors' flows with them
        self.end_evaluations = 0  # of those, the ones the last trace spent after its last point
        self.debug = False

    # --- corrector ------------------------------------------------------------------------------
    def _base(self, prob, ev):
        """The scaled Jacobian part the evaluation provides: [dR/du | 0] from the variational
        equations, or zeros for a problem without them."""
        w = prob.scale_u
        n = len(w)
        B = np.zeros((n, n + 1))
        if ev.Ju is not None and prob.variational:
            B[:, :n] = ev.Ju * w[None, :] / w[:, None]
        return B

    def _correction(self, prob, z, ev, C_prev, fixed_p=False):
        """The secant correction to start from: zero (or, without variational equations,
        dR/du by forward differences), with dR/dp by a forward difference at z, or zero with
        ``fixed_p`` (a corrector at fixed p does not use it: see ``correct``). (C_prev is
        not used: a carried correction went stale over a step.)"""
        w, wp = prob.scale_u, prob.scale_p
        n = len(w)
        C = np.zeros((n, n + 1))
        if not prob.variational:
            # forward differences at every corrector start: Broyden updates alone, carried from
            # point to point, drift (spurious folds, creeping); n flows without variational
            # equations cost about what the variational equations would
            C[:, :n] = prob.jacobian_u(z[:-1] * w, z[-1] * wp, ev) * w[None, :] / w[:, None]
            self.n_evaluations += n
        # dR/dp changes fastest along a branch: a fresh forward difference (one flow without
        # variational equations) saves more iterations than it costs
        if not fixed_p:
            C[:, n] = self._dRdp(prob, z, ev)
        return C

    def _dRdp(self, prob, z, ev):
        """Scaled dR/dp at z (ev: the evaluation there) by a forward difference (one flow)."""
        w, wp = prob.scale_u, prob.scale_p
        self.n_evaluations += 1
        return prob.jacobian_p(z[:-1] * w, z[-1] * wp, ev) * wp / w

    def complete_jacobian(self, prob, ev):
        """Fill in the dR/dp column of the Jacobian of an evaluation returned by a corrector
        at fixed p (``correct(..., fixed_p=True)``), by the forward difference at its start
        (what the corrector would have used), for a tangent there."""
        if getattr(ev, "lazy_p", None) is not None:
            z0, ev0 = ev.lazy_p
            col = self._dRdp(prob, z0, ev0)
            ev.B = ev.B.copy()
            ev.B[:, -1] += col
            ev.C = ev.C.copy()
            ev.C[:, -1] += col
            ev.lazy_p = None
        return ev

    def correct(self, prob, zeta_pred, t, C_prev=None, fixed_p=False):
        """Solve R = 0 with t . (zeta - zeta_pred) = 0 from zeta_pred by quasi-Newton (see the
        class doc): the Jacobian is B = [dR/du from the variational equations at the iterate
        | 0] + C, with the correction C (its last column dR/dp) updated by Broyden's formula so
        that B meets the secant condition of every step, and carried from point to point
        (C_prev: that of a nearby point). Returns (zeta, evaluation, iterations); the
        evaluation (with the monodromies, if computed) is the one at the returned zeta, with
        ``B`` the final Jacobian and ``C`` its correction.
        fixed_p: t is the unit vector of p (the iterates keep p = zeta_pred's): the dR/dp column
        does not enter the Newton steps (their p component is zero) nor Broyden's updates, so
        its forward difference is left out (a flow saved); ``complete_jacobian`` fills it in
        when a tangent is wanted."""
        w, wp = prob.scale_u, prob.scale_p
        var = prob.variational
        z = zeta_pred.copy()
        C = None
        dz = None
        dz_norm = np.inf
        res_prev = np.inf
        r_prev = None
        z_prev = ev_prev = None  # the previous iterate and its evaluation
        self.impacts_seen = set()
        self.iterates = []  # (z, number of impacts) of every iterate evaluated
        self.residuals = []  # the scaled residual (max-norm) of every iterate evaluated
        base = None
        rate = None  # the last residual ratio (res / res_prev)
        lazy = (self.lazy_var if self.lazy_var is not None
                else getattr(prob, "N2", len(w)) > 2)  # (N2: states per shooting segment)
        it, n_iter = 0, self.max_iter
        rate_prev = None
        while it < n_iter:
            it += 1
            # the variational equations at the predictor, then only at an iterate expected to
            # be the last (its residual, at the last ratio, below tol): the others are
            # flows without them, the Jacobian carried by Broyden's updates
            if not var or base is None or not lazy:
                fresh = var
            else:
                fresh = res_prev * min(0.1 if rate is None else rate, 0.5) < self.tol
            try:
                ev = prob.evaluate(z[:-1] * w, z[-1] * wp, jac=fresh, jac_p=False)
            except ConvergenceError:
                break
            self.n_evaluations += 1
            self.n_variational += bool(fresh)
            self.impacts_seen.add(ev.n_impacts)
            self.iterates.append((z, ev.n_impacts))
            r = ev.R / w
            res = float(np.max(np.abs(r)))
            self.residuals.append(res)
            if self.debug:
                print("    it %d res %.2e imp %d var %s" % (it, res, ev.n_impacts, fresh))
            if not np.isfinite(res):
                break
            if fresh or base is None:
                base = self._base(prob, ev)
            if C is None:
                C = self._correction(prob, z, ev, C_prev, fixed_p)
                lazy_p = (z.copy(), ev) if fixed_p else None
            elif dz_norm > 1e-6:
                # Broyden's update (not from steps so short that the map's noise, ~1e-8 where
                # contacts nearly stick, would dominate the difference)
                C = C + np.outer(r - r_prev - la.matmul(base + C, dz), dz) / la.dot(dz, dz)
            B = base + C
            ev.B, ev.C, ev.lazy_p = B, C, lazy_p
            if res < self.tol or (res < 100 * self.tol and dz_norm < 1e-9):
                return z, self._with_monodromy(prob, z, ev), it
            if it >= 3 and res > self.contraction * res_prev:
                if res_prev < self.noise_tol and res < self.noise_tol:
                    # stagnating below noise_tol: the fixed-step map is not smooth at this
                    # level (contact step decisions); accept the better iterate
                    if res_prev < res:
                        return z_prev, self._with_monodromy(prob, z_prev, ev_prev), it
                    return z, self._with_monodromy(prob, z, ev), it
                break  # not converging: the map is not smooth here, or the step is too long;
                # give up early (the caller halves the step)
            rate_prev, rate = rate, (res / res_prev if np.isfinite(res_prev) and res_prev > 0
                                     else None)
            if (lazy and var and it == n_iter == self.max_iter and res < self.noise_tol
                    and rate is not None and rate_prev is not None
                    and 0 < max(rate, rate_prev) <= self.contraction
                    and np.log(self.tol / res) >= self.max_iter * np.log(max(rate, rate_prev))):
                n_iter += self.max_iter  # converging steadily but linearly (a Jacobian only
                # carried by secant updates), below noise_tol and, at its slower last ratio,
                # within max_iter more iterations of tol: going on costs fewer flows than a
                # failed step (halved and corrected again, or a far-side solve repeated)
            z_prev, ev_prev = z, ev
            res_prev = res
            r_prev = r
            A = np.vstack([B, t[None, :]])
            try:
                dz = la.solve(A, -np.concatenate((r, (la.dot(t, z - zeta_pred),))))
            except np.linalg.LinAlgError:
                break
            dz_norm = float(np.max(np.abs(dz)))
            z = z + dz
        raise ConvergenceError("corrector did not converge; try a smaller step (ds) or multiple "
                               "shooting (segments=4)")

    def _with_monodromy(self, prob, z, ev):
        """The accepted iterate's evaluation with the variational equations (its monodromies
        and dR/du), re-evaluated at z where the iterate was a flow without them; the Jacobian
        B keeps the corrector's correction C on top of the fresh dR/du."""
        if not prob.variational or ev.Ju is not None:
            return ev
        w, wp = prob.scale_u, prob.scale_p
        ev2 = prob.evaluate(z[:-1] * w, z[-1] * wp, jac=True, jac_p=False)
        self.n_evaluations += 1
        self.n_variational += 1
        ev2.B, ev2.C, ev2.lazy_p = self._base(prob, ev2) + ev.C, ev.C, ev.lazy_p
        return ev2

    def _point(self, prob, z, ev, t_ref=None):
        u = z[:-1] * prob.scale_u
        mu = prob.multipliers(ev.Ms) if ev.Ms else None
        B = getattr(ev, "B", None)
        if B is None and ev.Ju is not None and ev.Jp is not None:
            B = _scaled(ev, prob.scale_u, prob.scale_p)[1]
        tn = tangent(B, t_ref) if (t_ref is not None and B is not None) else None
        C = getattr(ev, "C", None)
        if C is None and B is not None:
            C = B - self._base(prob, ev)
        return Point(u=u, p=float(z[-1] * prob.scale_p), xmax=ev.xmax, multipliers=mu,
                     problem=prob, n_impacts=ev.n_impacts, jac=B, tangent=tn, corr=C)

    def _tests(self, pt):
        """Test functions (fold, period doubling, Neimark-Sacker) of a point: from its
        multipliers, or without them the fold's alone, as the parameter component of the
        tangent (it changes sign where the branch turns back)."""
        if pt.multipliers is not None:
            return test_functions(pt.multipliers)
        return np.array([pt.tangent[-1], 0.0, 0.0])

    # --- one branch ---------------------------------------------------------------------------
    def _state0(self, prob, pt):
        """The point with its signature (``Problem.signature``; for shooting the state at
        excitation phase zero), by which ``Retrace`` compares points."""
        if pt.state0 is None:
            pt.state0 = np.asarray(prob.signature(pt.u, pt.p), dtype=float)
        return pt

    def _rebase(self, prob2, u2, pts, direction):
        """Move the branch's last point into the problem prob2 (same orbit, other unknowns:
        boundaries moved, step level changed, more segments), solved from u2. Returns (z, t,
        z_first, t_first) in prob2's scaled unknowns; raises ConvergenceError."""
        pt = pts[-1]
        u2, _, _, _ = prob2.solve(u2, pt.p, tol=self.tol)
        w, wp = prob2.scale_u, prob2.scale_p
        z = np.r_[u2 / w, pt.p / wp]
        ev2 = prob2.evaluate(u2, pt.p, jac=True, jac_p=True)
        if len(pts) > 1:
            z_prev = np.r_[prob2.transfer(pts[-2].problem, pts[-2].u, pts[-2].p) / w,
                           pts[-2].p / wp]
            sec = z - z_prev
            t = sec / la.norm(sec)
        else:
            t = np.zeros(len(z))
            t[-1] = float(direction)
        new = self._point(prob2, z, ev2, t)
        new.how, new.state0 = pt.how, pt.state0
        pts[-1] = new
        if len(pts) == 1:
            t = new.tangent
        z_first = np.r_[prob2.transfer(pts[0].problem, pts[0].u, pts[0].p) / w, pts[0].p / wp]
        t_first = t
        if len(pts) > 1:
            z1 = np.r_[prob2.transfer(pts[1].problem, pts[1].u, pts[1].p) / w, pts[1].p / wp]
            t_first = (z1 - z_first) / la.norm(z1 - z_first)
        return z, t, z_first, t_first

    def _more_segments(self, prob, pt):
        """(problem, u) of the orbit pt with the next number of shooting segments in
        ``corner_segments`` (multiple shooting), or None."""
        nxt = [k for k in self.corner_segments if k > prob.n_seg]
        if not nxt:
            return None
        try:
            return prob.with_segments(pt.u, pt.p, nxt[0])
        except (ConvergenceError, ValueError):
            return None

    def _warn_stuck(self, prob, p):
        name = prob.parameter
        warnings.warn(
            f"continuation: the {self.label} is stuck at a corner near {name} = {p:.9g}: the "
            "number of impacts per period changes there, and no continuation across it passed "
            "the checks (the far side must join the branch through the grazing point, and the "
            "branch may turn back only where a multiplier passes +1); tried: jumps across from "
            f"both sides at relative distances {', '.join(f'{s:g}' for s in self.jump_steps)},"
            f" steps down to {self.ds_min:g}, segments={', '.join(map(str, self.corner_segments))}"
            ". The branch ends there ('stuck at a corner'). Try finer integration (dt_scale=0.5,"
            " steps_per_contact=64), multiple shooting from the start (segments=4), or a start "
            "beyond the corner (starts=...)", ContinuationWarning, stacklevel=3)

    def _jump_end(self, prob, pt, z, t, reason, jump=None):
        """The end reason of a branch whose steps failed at the point pt (z scaled, direction
        of travel t): 'discontinuous map', with a ContinuationWarning naming the parameter
        value, where the map jumps just ahead (``corners.map_jump``, unless ``jump``, its
        (h, |R|), is known), else ``reason``."""
        if jump is None:
            jump = map_jump(prob, z, t)
            self.n_evaluations += len(JUMP_HS)
        if jump is None:
            return reason
        h, r = jump
        warnings.warn(
            f"continuation: the {self.label} ends at {prob.parameter} = {pt.p:.9g}: the "
            f"fixed-step flow map is discontinuous just beyond it (the residual jumps to "
            f"{r:.1e} within {h:.0e} in scaled arclength; {pt.n_impacts} impacts per period "
            "at the end): a contact ends and restarts within a step, or its penetration dips "
            "to zero and restarts (the Lankarani-Nikravesh law's onset-velocity memory resets "
            "there), so the orbits on the two sides are not joined by a continuous branch of the "
            "discrete map. Finer integration (dt_scale=0.5, steps_per_contact=64) moves or "
            "removes the jump; a start beyond it (starts=...) traces the far side",
            ContinuationWarning, stacklevel=3)
        return "discontinuous map"

    def _jump_bracket(self, prob, z, t, lo, hi, r_hi, ratio=1.01):
        """The largest scaled distance s along t from z known to lie before a jump of the map
        between lo and hi (|R| at hi: r_hi): geometric bisection, flows without variational
        equations, until hi / lo < ratio; a point whose |R| is below a tenth of r_hi lies
        before the jump."""
        w, wp = prob.scale_u, prob.scale_p
        while hi / lo >= ratio:
            mid = float(np.sqrt(lo * hi))
            zm = z + mid * t
            self.n_evaluations += 1
            try:
                ev = prob.evaluate(zm[:-1] * w, zm[-1] * wp, jac=False, jac_p=False)
                before = float(np.max(np.abs(ev.R / w))) < 0.1 * r_hi
            except ConvergenceError:
                before = False
            if before:
                lo = mid
            else:
                hi = mid
        return lo, hi

    def _warn_unverified(self, prob, p_a, p_b):
        warnings.warn(
            f"continuation: the {self.label} passed a corner near {prob.parameter} = {p_a:.9g} "
            f"to {p_b:.9g} without proof that the far side joins it: no other way passed, and "
            "the bisection between the two could not be finished (the flow map is rough "
            "there: contacts that graze or nearly stick). Check that stretch with finer "
            "integration (dt_scale=0.5, steps_per_contact=64)", ContinuationWarning,
            stacklevel=3)

    def trace(self, prob, u0, p0, direction=1, stop=None, t0=None, prior=None):
        """Follow the branch through the solution (u0, p0) in the direction of increasing p
        (direction=1) or decreasing p (-1), or along t0 (scaled tangent) if given.
        ``stop(point) -> bool`` ends the branch (the point is kept; where it returns 'overlap',
        the point lies on a branch traced before, the bifurcations on the step to it are
        detected first: which step of a trace runs onto the other branch is up to round-off,
        a fold or period doubling on it is not). prior: the other half of
        the branch (``Retrace.export()`` of its trace from the same first point), so that a
        half that runs onto the other is caught. The predictor follows the secant through the
        last two points (the Jacobian's tangent at the first), and the step adapts to the angle
        between successive secants (target ``max_angle / 2``; the secant measures the
        branch's curvature even where the Jacobian is only approximate) and to the corrector's
        iterations.

        Corners (the number of impacts per period changes between two points: a grazing orbit
        in between, where the flow map is not smooth) are approached with steps of at most
        ``grazing_ds`` and every step through one is checked (``corners.check_crossing``): the
        two sides must join through the grazing point, which is bracketed, and the branch may
        turn back there only where the sign of prod(mu - 1) changes (a non-smooth fold,
        reported as a fold); the far side is then followed away from the grazing point. Where
        the corrector fails near a corner, the strategies are, in turn: fixed-parameter solves
        on the far side, beyond the corner and behind it, each checked the same way
        (``corners.far_side``); shorter steps, down to ds_min; a far-side solution that passed
        every check but the bisection joining it, which could not be finished (taken with a
        ContinuationWarning); multiple shooting (``corner_segments``); else the branch stops
        with end reason 'stuck at a corner' and a ContinuationWarning naming the parameter
        value. Every new point is compared with the
        points traced so far (``corners.Retrace``): one that runs back along a traced stretch
        (a corner that failed unnoticed) is dropped with what followed the last corner before
        it, and the corner is passed again by the far-side solves, avoiding it; one that runs
        along the branch's beginning again ends the branch as 'closed (isola)'.
        A branch that makes no progress (see the class doc) stops with a ContinuationWarning.
        Returns (points, located, reason)."""
        w, wp = prob.scale_u, prob.scale_p
        z = np.r_[np.asarray(u0) / w, p0 / wp]
        ev = prob.evaluate(u0, p0, jac=True, jac_p=True)
        self.n_evaluations += 1
        e_p = np.zeros(len(z))
        e_p[-1] = float(direction)
        pt0 = self._point(prob, z, ev, e_p if t0 is None else t0)
        pt0.how = "start"
        t = pt0.tangent
        pts = [self._state0(prob, pt0)]
        tfs = [self._tests(pt0)]
        retrace = Retrace(self.retrace_tol, prob.scale_u, prob.scale_p, prior)
        retrace.add(pt0, z, 0.0)
        n_at_point = self.n_evaluations  # (end_evaluations: the work after the last point)
        located = []
        ds = self.ds0
        z_first = z.copy()
        t_first = t.copy()
        t_in = t.copy()  # the direction of travel at the last point (trial steps may change t)
        reason = "max_points"
        n_fail = 0
        tried_jump = near_grazing = tried_kink = False
        trials = []  # (ds, predictor residual, first iterate's) of failed steps at this point
        # that kept its number of impacts (kinks.signal)
        ds_ok = ds
        self._creeps = 0
        self.unverified = None  # (problem, point, far-side candidate): see corners.far_side
        steps = []  # scaled arclength of each accepted step (the no-progress rule)
        angle_rej = np.inf  # the angle of the last step rejected for its angle
        guesses = []  # far-side states (scaled) that failed steps saw near the last point
        avoid = []  # (problem, scaled state) of points dropped after a retrace
        forced = False  # after a retrace: pass the corner by far-side solves first
        rolled = {}  # rollbacks per point index
        avoid_until = 0  # avoid is cleared once the branch has this many points
        budget = None  # failed steps left with more shooting segments at a corner (None: any)
        far_failed = None  # (problem, scaled p) where the far-side solves last found nothing
        approach = None  # (points, (h, |R|)): a step taken up to a located jump of the map
        n_approach = 0
        pending_end = None  # a located jump of the map where the branch ends (far side first)
        while len(pts) < self.max_points:
            jumped = kink_turn = False
            crossing = None
            ok = False
            iters = self.max_iter
            angle = np.inf
            seen = set()
            if len(pts) > avoid_until:
                avoid = []
            if approach is not None and len(pts) == approach[0] + 1:
                # the step up to a located jump of the map was taken: probe again from there
                approach = None
                jump = map_jump(prob, z, t_in)
                self.n_evaluations += len(JUMP_HS)
                if jump is not None:
                    if jump[0] > 1e-5 and n_approach < 3:
                        s_lo, s_hi = self._jump_bracket(prob, z, t_in, 0.1 * jump[0], jump[0],
                                                        jump[1])
                        n_approach += 1
                        approach = (len(pts), (s_hi, jump[1]))
                        t = t_in.copy()
                        ds = 0.98 * s_lo
                    elif self.jump_steps:
                        # the far side has not been tried from this point: before the branch
                        # ends at the jump, it is (a jump of the map can be a jump of the
                        # branch, with fixed points beyond it)
                        pending_end, forced = jump, True
                    else:
                        reason = self._jump_end(prob, pts[-1], z, t_in, "", jump)
                        break
            strict = any(q is prob for q, _ in avoid)
            if not forced:
                try:
                    zn, evn, iters = self.correct(prob, z + ds * t, t, pts[-1].corr)
                    seen = set(self.impacts_seen)
                    iterates = list(self.iterates)
                    ptn = self._point(prob, zn, evn, t)
                    tn = (zn - z) / la.norm(zn - z)  # secant: the next predictor
                    angle = float(np.arccos(np.clip(la.dot(t, tn), -1, 1)))
                    ok = angle <= self.max_angle
                    if ptn.n_impacts != pts[-1].n_impacts:
                        guesses.append(zn)
                        if ds > self.grazing_ds:
                            ok = False  # a grazing point ahead: approach it with short steps,
                            # so that it is bracketed closely and no step cuts a corner
                            angle = np.nan
                        else:
                            crossing = check_crossing(self, prob, pts[-1], z, t_in, ptn, zn,
                                                      strict=strict or not ok)
                            if (crossing is not None and ds > 4 * self.ds_min
                                    and ((crossing.turn and smooth_fold_beside(
                                        self, pts[-1], crossing, ptn))
                                         or fold_ahead(self, pts[-1], crossing))):
                                crossing = None  # the turn may be a smooth fold's on the
                                # step, or the step may land behind a smooth fold of the near
                                # strand: a shorter step separates the two (which one turns
                                # the branch and where the grazing point lies is not up to
                                # round-off)
                                angle = np.nan
                            ok = crossing is not None
                            if ok:
                                ptn.tangent = crossing.t_far
                                if crossing.turn or angle > self.max_angle:
                                    tn = crossing.t_far  # the far side, away from the corner
                    if ok and strict and _near_any(prob, zn, z, avoid):
                        ok = False
                except ConvergenceError:
                    seen = set(self.impacts_seen)
                    iterates = list(self.iterates)
                    if seen == {pts[-1].n_impacts} and len(self.residuals) >= 2:
                        trials.append((ds, self.residuals[0], self.residuals[1]))
                far = [zi for zi, ni in iterates if ni != pts[-1].n_impacts]
                if far:
                    guesses.append(far[-1])
                if not ok and seen - {pts[-1].n_impacts}:
                    near_grazing = True  # the corrector's iterates changed the number of impacts
                if self.debug:
                    print("ds %.3g ok %s iters %d angle %.3g p %.9g" % (
                        ds, ok, iters, angle, z[-1] * prob.scale_p))
            if not ok:
                n_fail += 1
                if budget is not None:
                    budget -= 1
                if not forced:
                    if np.isfinite(angle) and angle > 0.7 * angle_rej:
                        # the angle does not shrink with the step: the predictor's direction
                        # (the last secant) is off, e.g. after a corner; the short trial
                        # step's secant is the local tangent
                        t = tn
                    angle_rej = angle if np.isfinite(angle) else np.inf
                    ds *= 0.5
                again = (far_failed is not None and far_failed[0] is prob
                         and abs(z[-1] - far_failed[1])
                         < self.jump_steps[0] * max(abs(z[-1]), 1e-3))
                if self.jump_steps and (forced or (n_fail >= self.jump_after and near_grazing
                                                   and not tried_jump and not again)):
                    tried_jump = True
                    near_grazing = True
                    res = far_side(self, prob, pts[-1], z, t_in, guesses[-3:],
                                   [v for q, v in avoid if q is prob])
                    if res is not None:
                        zn, evn, ptn, crossing = res
                        if crossing is not None:
                            tn = crossing.t_far  # away from the corner
                        else:  # a creep: the Jacobian's tangent, in the direction of travel
                            e_s = np.zeros(len(z))
                            e_s[-1] = 1.0 if t_in[-1] >= 0 else -1.0
                            tn = tangent(evn.B, e_s)
                        ptn.tangent = tn
                        jumped = True
                        ds = ds_ok
                    else:  # not again before the branch has moved on (creeping to the corner)
                        far_failed = (prob, z[-1])
                    forced = False
                kink = (None if jumped or tried_kink or not self.kink_steps
                        or n_fail < self.jump_after else kinks.signal(trials, self.noise_tol))
                if kink is not None:
                    # a kink ahead that keeps the number of impacts: crossed from the far side
                    # (continuation.kinks) rather than crept into by halved steps
                    tried_kink = True
                    d_fail = max(d for d, _, _ in trials) * abs(t_in[-1])
                    unit = max(abs(z[-1]), 1e-3)
                    dps = sorted({k * d_fail for k in self.kink_steps if k * d_fail > 0}
                                 | {s * unit for s in self.jump_steps})
                    res = kinks.crossing(self, prob, pts[-1], z, t_in, dps)
                    if res is None:  # no solution beyond: does the branch turn back there?
                        res = kinks.turn(self, prob, pts[-1], z, t_in, dps,
                                         max(d for d, _, _ in trials))
                        kink_turn = res is not None
                    if self.debug:
                        print("kink ahead of p %.9g (%s): %s" % (
                            z[-1] * wp, kink, "crossed to p %.9g%s" % (
                                res[0][-1] * wp, " (turned back)" if kink_turn else "")
                            if res is not None else "not crossed"))
                    if res is not None:
                        zn, evn, ptn, tn, kink_at = res
                        jumped = True
                        ds = ds_ok
                last = self.unverified
                far = (last is not None and last[0] is prob and last[1] is pts[-1])
                if (not jumped and (ds < self.ds_min or (budget is not None and budget <= 0))
                        and (near_grazing or strict) and far):
                    # every strategy failed, but a far-side solution passed the checks except
                    # that the bisection joining it could not be finished: taken, loudly
                    zn, evn, ptn, crossing = last[2]
                    tn = ptn.tangent = crossing.t_far
                    jumped = True
                    ds = ds_ok
                    self._warn_unverified(prob, pts[-1].p, ptn.p)
                if not jumped and approach is not None and len(pts) == approach[0]:
                    pending_end = approach[1]  # the step up to the located jump failed
                if not jumped and pending_end is not None:
                    if not tried_jump and self.jump_steps:
                        forced = True  # the far side first (next pass), then the end
                        continue
                    if not far:
                        reason = self._jump_end(prob, pts[-1], z, t_in, "", pending_end)
                        break
                    # a far-side solution beyond the jump passed every check but the
                    # bisection joining it (which a jump of the map cannot finish): taken,
                    # loudly
                    zn, evn, ptn, crossing = last[2]
                    tn = ptn.tangent = crossing.t_far
                    jumped = True
                    ds = ds_ok
                    self._warn_unverified(prob, pts[-1].p, ptn.p)
                pending_end = None
                if (not jumped and self.probe_after and n_fail % self.probe_after == 0
                        and ds >= self.ds_min and pts[-1].problem is prob):
                    # steps keep failing at this point: is the map discontinuous just ahead
                    # (corners.map_jump, a few flows without variational equations)? Then no
                    # shorter step, far-side solve or extra shooting segment goes on: rather
                    # than halving down to ds_min and trying them all, the jump is bracketed
                    # along the line (flows without variational equations) and one step taken
                    # to just before it (up to three times, while it lies more than 1e-5
                    # ahead); then the branch ends
                    jump = map_jump(prob, z, t_in)
                    self.n_evaluations += len(JUMP_HS)
                    if jump is not None:
                        if jump[0] > 1e-5 and n_approach < 3:
                            s_lo, s_hi = self._jump_bracket(prob, z, t_in, 0.1 * jump[0],
                                                            jump[0], jump[1])
                            n_approach += 1
                            approach = (len(pts), (s_hi, jump[1]))
                            t = t_in.copy()
                            ds = 0.98 * s_lo
                            continue
                        if not tried_jump and self.jump_steps:
                            pending_end, forced = jump, True  # the far side first
                            continue
                        if not far:
                            reason = self._jump_end(prob, pts[-1], z, t_in, "", jump)
                            break
                        zn, evn, ptn, crossing = last[2]  # as above: taken, loudly
                        tn = ptn.tangent = crossing.t_far
                        jumped = True
                        ds = ds_ok
                        self._warn_unverified(prob, pts[-1].p, ptn.p)
                if not jumped:
                    if ds < self.ds_min or (budget is not None and budget <= 0):
                        if not (near_grazing or strict or budget is not None):
                            reason = self._jump_end(prob, pts[-1], z, t_in, "step underflow")
                            break
                        new = self._more_segments(prob, pts[-1])
                        if self.debug:
                            print("corner: segments", None if new is None else new[0].n_seg,
                                  "evaluations so far", self.n_evaluations)
                        if new is not None:
                            try:
                                z, t, z_first, t_first = self._rebase(new[0], new[1], pts,
                                                                      direction)
                                retrace.replace_last(pts[-1], z)
                            except ConvergenceError:
                                new = None
                        if new is None:
                            reason = self._jump_end(prob, pts[-1], z, t_in, "stuck at a corner")
                            if reason == "stuck at a corner":
                                self._warn_stuck(prob, pts[-1].p)
                            break
                        prob = new[0]
                        w, wp = prob.scale_u, prob.scale_p
                        t_in = t.copy()
                        ds = min(ds_ok, self.grazing_ds)
                        n_fail, tried_jump, guesses, trials = 0, False, [], []
                        tried_kink = False
                        forced, budget = True, 8  # far-side solves first, then a few steps
                    continue
            tried_jump = near_grazing = tried_kink = False
            angle_rej = np.inf
            guesses = []
            trials = []
            self.unverified = None
            if not jumped:
                ds_ok = ds
            n_fail = 0
            if not jumped:
                self._creeps = 0
            pt = self._state0(prob, ptn)
            pt.how = "jump" if jumped else ("corner" if crossing is not None else "step")
            if crossing is not None:
                budget = None  # the corner is passed
            tf = self._tests(pt)
            prev = pts[-1]
            grazing = None
            if crossing is not None:
                located.append(Located("grazing", crossing.hi, crossing.width, len(pts) - 1))
                # the bracket of the grazing point for the bifurcations on the step: where the
                # branch turns back at the corner, the turning point lies within the chord
                # between the bracket's ends, not between their parameters
                g_tol = crossing.width
                if crossing.turn:
                    g_tol = max(g_tol, crossing.gap * prob.scale_p
                                * max(abs(t_in[-1]), abs(crossing.t_far[-1])))
                grazing = (crossing.hi, g_tol, crossing.lo, None)
            stopped = stop(pt) if stop is not None else False
            if stopped and stopped != "overlap":
                pts.append(pt)
                tfs.append(tf)
                reason = "stop"
                break
            if self.detect:
                found = self._detect_step(prob, z, t, ds, prev, pt, tfs[-1], tf, jumped,
                                          grazing, len(pts) - 1)
                if crossing is not None and crossing.turn:
                    # a fold at the corner is reported at the bracket's end further in the
                    # direction of travel (nearer the turning point: both lie on one side of it);
                    # where the fold's test function did not tell (a multiplier too near +1),
                    # the turn is a fold all the same
                    ext = max((crossing.lo, crossing.hi), key=lambda q: q.p * np.sign(t_in[-1]))
                    folds = [L for L in found if L.kind == "fold" and L.point is crossing.hi]
                    for L in folds:
                        L.point = ext
                    if not any(L.kind == "fold" for L in found):
                        found.append(Located("fold", ext, g_tol, len(pts) - 1,
                                             note=_jump_note("fold", prev, pt)))
                if kink_turn:  # the branch turned back at a kink (kinks.turn): a fold there,
                    # between the near point and the kink (the far point lies behind both)
                    found.append(Located(
                        "fold", prev, abs(kink_at[-1] * wp - pt.p), len(pts) - 1,
                        note="at a kink: the branch turns back (non-smooth)"))
                located += found
            if stopped:  # ran onto a traced branch: the step's bifurcations are listed too
                pts.append(pt)
                tfs.append(tf)
                reason = "stop"
                break
            steps.append(la.norm(zn - z))
            pts.append(pt)
            tfs.append(tf)
            n_at_point = self.n_evaluations
            retrace.add(pt, zn, steps[-1])
            z, t = zn, tn
            t_in = t.copy()
            hit = retrace.check()
            if hit is not None:
                kind, i = hit
                if kind == "closed" or (kind == "same" and (i <= 1 or pt.how == "step")):
                    reason = "closed (isola)"
                    break
                # a retrace: what followed the first corner or jump since segment i is dropped
                # and that corner passed again by checked far-side solves, avoiding it
                lo_j = i + 1 if i >= 0 else 0
                j = next((q for q in range(lo_j, len(pts) - 1)
                          if pts[q + 1].how in ("corner", "jump")), len(pts) - 2)
                rolled[j] = rolled.get(j, 0) + 1
                n_ret = pts[i].n_impacts if i >= 0 else pt.n_impacts
                for q in pts[j + 1:]:
                    if q.n_impacts == n_ret:
                        avoid.append((q.problem, np.r_[q.u / q.problem.scale_u,
                                                       q.p / q.problem.scale_p]))
                del pts[j + 1:], tfs[j + 1:], steps[j:]
                retrace.truncate(j + 1)
                located = [L for L in located if L.index < j]
                if rolled[j] > 2:
                    reason = "stuck at a corner"
                    self._warn_stuck(prob, pts[-1].p)
                    break
                if pts[-1].problem is not prob:
                    prob = pts[-1].problem
                    z_first, t_first = _firsts(prob, pts)
                w, wp = prob.scale_u, prob.scale_p
                z = np.r_[pts[-1].u / w, pts[-1].p / wp]
                avoid_until = len(pts) + 10
                approach = None
                t = pts[-1].tangent if pts[-1].tangent is not None else t
                t_in = t.copy()
                forced = True
                ds = min(ds_ok, self.grazing_ds)
                n_fail, tried_jump, guesses, trials = 0, False, [], []
                tried_kink = False
                continue
            if not (self.p_min <= pt.p <= self.p_max):
                reason = "left the parameter range"
                break
            if len(pts) > 8 and _passes(z_first, t_first, pts[-2], z, prob):
                reason = "closed (isola)"
                break
            if (len(steps) >= self.progress_points
                    and sum(steps[-self.progress_points:]) < self.progress_min):
                reason = self._jump_end(prob, pt, z, t_in, "no progress")
                if reason != "no progress":
                    break
                advanced = sum(steps[-self.progress_points:])
                warnings.warn(
                    f"continuation: the {self.label} made no progress near {pt.p:.9g} (its last "
                    f"{self.progress_points} points advanced {advanced:.1e}"
                    f" < {self.progress_min:.0e} in scaled arclength) and is stopped there. The "
                    "flow map is probably not smooth there (grazing or chattering contacts, or "
                    "an orbit too unstable for single shooting): try finer integration "
                    "(dt_scale=0.5, steps_per_contact=64), multiple shooting (segments=4), or "
                    "a smaller max_angle", ContinuationWarning, stacklevel=2)
                break
            if not jumped:
                fac = 0.5 * self.max_angle / max(angle, 1e-12)
                if iters >= 6 and ds > 0.1 * self.grazing_ds:
                    fac = min(fac, 0.7)  # (for shorter steps many iterations are the map's
                    # noise, where contacts nearly stick, not the branch's curvature)
                ds = min(self.ds_max, ds * min(2.0, max(0.5, fac)))
            if crossing is not None:  # past the corner the branch is smooth again: not the
                # tiny steps that approached it (they would trip the no-progress rule)
                ds = max(ds, 0.1 * self.grazing_ds)
            new = prob.adapt(pt.u, pt.p)
            if new is not None:
                try:
                    z, t, z_first, t_first = self._rebase(new[0], new[1], pts, direction)
                    retrace.replace_last(pts[-1], z)
                except ConvergenceError:
                    reason = "could not move the segment boundaries"
                    break
                prob = new[0]
                w, wp = prob.scale_u, prob.scale_p
                t_in = t.copy()
        self.retrace = retrace
        self.end_evaluations = self.n_evaluations - n_at_point
        return pts, at_grazing_points(located, pts), reason

    # --- bifurcations on a step ---------------------------------------------------------------
    def _detect_step(self, prob, z, t, ds, prev, pt, tf_prev, tf, jumped, grazing, index):
        """The bifurcations on the accepted step from prev (scaled z, tangent t; test functions
        tf_prev) to pt (tf), a step of arclength ds or a jump; grazing: what locate_grazing
        returned when the number of impacts per period changes on the step, else None.
        Returns a list of Located.

        A smooth step (or a jump that kept the number of impacts; folds not there: p does not
        parametrise one) is searched for sign changes of the test functions between its ends.
        A step through a grazing point is split there (the multipliers are not smooth across
        it): each smooth side, from its end to the point nearest the grazing point, is searched
        and its sign changes located on it; a sign change between the two points that bracket
        the grazing point (a multiplier jumps through +1, -1 or the unit circle there) is
        reported at the grazing point with the grazing bracket as tolerance and a ``note``
        naming the jump. So a stability change at (or within round-off of) a grazing point is
        listed once, wherever round-off puts it relative to the grazing point. A sign change
        on a smooth side that the locate cannot place there is reported at the grazing point
        too (the root lies between it and the side's end), with the side as its bracket, where
        the test function's chord puts the root within GRAZING_RESOLUTION of the grazing
        point: not at the side's end, a point of the branch the event is not at (the paper
        model's order-2 branch at 9.66425 Hz: the far side's locate failed in one run only,
        and its fold, reported at the step's end, was later located at another fold 3.4e-4
        Hz away). Farther, it stays at the side's end (the paper model's order-1 period
        doubling at 6.647 Hz, 2.3e-3 Hz before the grazing point where the multiplier jumps
        back across -1: two events).
        ``at_grazing_points`` (at the end of ``trace``) then makes the events within a
        grazing point's resolution one event there."""
        out = []
        if grazing is None:
            for k, kind in enumerate(KINDS):
                if jumped and kind == "fold":
                    continue
                if np.sign(tf[k]) != np.sign(tf_prev[k]) and tf[k] != 0:
                    if kind == "neimark-sacker" and not _has_pair_near_circle(
                            prev.multipliers, pt.multipliers):
                        continue
                    if jumped:
                        loc = self.locate_p(prob, prev, pt, k, tf_prev[k], tf[k])
                    else:
                        loc = self.locate(prob, z, t, ds, k, tf_prev[k], tf[k], prev.corr)
                        if loc is None and prev.problem is prob and pt.problem is prob:
                            loc = self.locate_chord(prob, prev, pt, k, tf_prev[k], tf[k])
                    if loc is None:  # not located: the bracket is the step
                        loc = (pt, abs(pt.p - prev.p))
                    out.append(Located(kind, loc[0], loc[1], index))
            return out
        g_far, g_tol, g_near, s_pair = grazing[:4]
        s_near, s_far = s_pair if s_pair is not None else (None, None)
        nodes = [(prev, tf_prev, 0.0)]
        for q, s in ((g_near, s_near), (g_far, s_far)):
            if q is not prev and q is not pt and (q.multipliers is not None
                                                  or q.tangent is not None):
                nodes.append((q, self._tests(q), s))
        nodes.append((pt, tf, ds))
        for (a, ta, sa), (b, tb, sb) in zip(nodes[:-1], nodes[1:]):
            across = a.n_impacts != b.n_impacts
            for k, kind in enumerate(KINDS):
                if not (np.sign(tb[k]) != np.sign(ta[k]) and tb[k] != 0):
                    continue
                if kind == "neimark-sacker" and not _has_pair_near_circle(a.multipliers,
                                                                          b.multipliers):
                    continue
                if across:  # at the grazing point
                    out.append(Located(kind, g_far, max(g_tol, abs(b.p - a.p)), index,
                                       note=_jump_note(kind, a, b)))
                    continue
                loc = None
                if s_pair is not None and sa is not None and sb is not None:
                    loc = self.locate(prob, z, t, sb, k, ta[k], tb[k], prev.corr, s_a=sa,
                                      p_a=a.p, n_impacts=a.n_impacts)
                if loc is None and a.problem is prob and b.problem is prob:
                    # (after a jump; or the step's own predictors failed next to the grazing
                    # point, where the branch bends fastest: the chord's)
                    loc = self.locate_chord(prob, a, b, k, ta[k], tb[k])
                if loc is None:
                    # not placed on the side: where the test function's chord puts its root
                    # within GRAZING_RESOLUTION of the grazing point, it is reported there,
                    # the side (between it and the side's end) its bracket; else at the
                    # side's end, the side its bracket (and left so: ``placed`` False)
                    p_est = a.p + ta[k] / (ta[k] - tb[k]) * (b.p - a.p)
                    if abs(p_est - g_far.p) <= GRAZING_RESOLUTION * abs(g_far.p):
                        out.append(Located(kind, g_far, max(g_tol, abs(a.p - g_far.p),
                                                            abs(b.p - g_far.p)), index,
                                           note=_side_note(kind, a, b)))
                    else:
                        out.append(Located(kind, b, abs(b.p - a.p), index, placed=False))
                    continue
                out.append(Located(kind, loc[0], loc[1], index))
        return out

    def locate_chord(self, prob, pa, pb, k, g_a, g_b):
        """Regula falsi (``locate``) for test function k between two points on one smooth
        stretch of a branch (the same number of impacts), with the corrector's hyperplanes
        normal to the chord from pa to pb (a short stretch: folds included). Returns (Point,
        tolerance) or None."""
        w, wp = prob.scale_u, prob.scale_p
        za = np.r_[pa.u / w, pa.p / wp]
        d = np.r_[pb.u / w, pb.p / wp] - za
        L = la.norm(d)
        if L == 0.0:
            return None
        return self.locate(prob, za, d / L, L, k, g_a, g_b, pa.corr, p_a=pa.p,
                           n_impacts=pa.n_impacts)

    # --- bifurcation location -----------------------------------------------------------------
    def locate_p(self, prob, pa, pb, k, g_a, g_b):
        """Illinois regula falsi in p between the points pa and pb (a jump: a natural-parameter
        step), solving at fixed p from the linear interpolation of their unknowns, until the
        bracket's width is below bif_tol * |p|. Returns (Point, tolerance), or None when a
        solve fails or leaves the stretch (another number of impacts)."""
        w, wp = prob.scale_u, prob.scale_p
        if pa.problem is not prob or pb.problem is not prob:
            return None
        e_p = np.zeros(len(w) + 1)
        e_p[-1] = 1.0
        lo, hi, glo, ghi = pa.p, pb.p, g_a, g_b
        tlo, thi = g_a, g_b  # the test function's values at lo, hi (glo, ghi: Illinois')
        best, side = None, 0

        def solve(p):
            lam = (p - pa.p) / (pb.p - pa.p)
            u = pa.u + lam * (pb.u - pa.u)
            zs, evs, _ = self.correct(prob, np.r_[u / w, p / wp], e_p, fixed_p=True)
            pt = self._point(prob, zs, evs)
            if pt.n_impacts != pa.n_impacts or pt.multipliers is None:
                raise ConvergenceError("left the stretch")
            return pt

        for _ in range(60):
            p = hi - ghi * (hi - lo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
            if not (min(lo, hi) < p < max(lo, hi)):
                p = 0.5 * (lo + hi)
            try:
                pt = solve(p)
            except ConvergenceError:
                return None
            g = self._tests(pt)[k]
            best = pt
            if g == 0:
                return best, 0.0
            if np.sign(g) == np.sign(glo):
                lo, glo, tlo = p, g, g
                if side == -1:
                    ghi *= 0.5
                side = -1
            else:
                hi, ghi, thi = p, g, g
                if side == 1:
                    glo *= 0.5
                side = 1
            if abs(hi - lo) <= self.bif_tol * abs(p):
                break
        return self._secant_root(best, lo, hi, tlo, thi, solve, abs(hi - lo)), abs(hi - lo)

    def _secant_root(self, best, lo, hi, tlo, thi, solve, width_p):
        """The point at the secant root of the final bracket [lo, hi] (test function tlo,
        thi there; its width in p: width_p) when it solves, else ``best``: the reported point
        then does not depend on which end of the bracket the regula falsi happened to try last
        (so round-off moves it by far less than the bracket)."""
        if not (np.isfinite(tlo) and np.isfinite(thi)) or tlo == thi:
            return best
        if width_p < 1e-2 * self.bif_tol * abs(best.p):
            return best  # a bracket far below bif_tol: round-off moves best by less
        x = lo - tlo * (hi - lo) / (thi - tlo)
        if not (min(lo, hi) < x < max(lo, hi)):
            return best
        try:
            return solve(x)
        except ConvergenceError:
            return best

    def locate(self, prob, z_a, t_a, ds, k, g_a, g_b, C_a=None, s_a=0.0, p_a=None,
               n_impacts=None):
        """Illinois regula falsi on the arclength step from z_a (test function k) between
        s_a (the point there: parameter p_a, test function g_a) and ds (g_b), until the
        bracket's width in p is below bif_tol * |p|. Returns (Point, tolerance) or None (a
        corrector failed, or with ``n_impacts`` given a trial point had another number of
        impacts per period: the stretch is not smooth)."""
        lo, hi = s_a, ds
        glo, ghi = g_a, g_b
        tlo, thi = g_a, g_b  # the test function's values at lo, hi (glo, ghi: Illinois')
        p_lo = z_a[-1] * prob.scale_p if p_a is None else p_a
        best = None
        p_hi = None
        side = 0

        def solve(s):
            zs, evs, _ = self.correct(prob, z_a + s * t_a, t_a, C_a)
            if not prob.variational:
                # the fold's test function is the tangent's p-component: from the Jacobian
                # at the solution itself (the corrector's is the predictor's, updated), or
                # the fold moves by ~1e-5
                evs = prob.evaluate(zs[:-1] * prob.scale_u, zs[-1] * prob.scale_p,
                                    jac=True, jac_p=True)
                self.n_evaluations += len(zs) + 1
            pt = self._point(prob, zs, evs, t_a)
            if n_impacts is not None and pt.n_impacts != n_impacts:
                raise ConvergenceError("left the stretch")
            return pt

        for _ in range(60):
            s = hi - ghi * (hi - lo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
            if not (lo < s < hi):
                s = 0.5 * (lo + hi)
            try:
                pt = solve(s)
            except ConvergenceError:
                return None
            g = self._tests(pt)[k]
            best = pt
            if np.sign(g) == np.sign(glo):
                lo, glo, p_lo, tlo = s, g, pt.p, g
                if side == -1:
                    ghi *= 0.5
                side = -1
            else:
                hi, ghi, p_hi, thi = s, g, pt.p, g
                if side == 1:
                    glo *= 0.5
                side = 1
            if g == 0:
                return best, 0.0
            if (p_hi is not None and abs(p_hi - p_lo) <= self.bif_tol * max(abs(pt.p), 1e-300)
                    and hi - lo < 1e-6):
                break
            if hi - lo < 1e-15:
                break
        tol = abs(p_hi - p_lo) if p_hi is not None else np.inf
        if p_hi is None:
            return best, tol
        return self._secant_root(best, lo, hi, tlo, thi, solve, tol), tol


def _passes(z_first, t_first, prev, z, prob):
    """True when the step from the point ``prev`` to z (scaled, in prob's unknowns) passes
    the branch's first point z_first in its first direction t_first: the branch has closed."""
    if prev.problem is not prob:
        return False
    za = np.r_[prev.u / prob.scale_u, prev.p / prob.scale_p]
    d = z - za
    L = la.norm(d)
    if L == 0.0 or la.dot(d, t_first) < 0.8 * L:
        return False
    lam = float(np.clip(la.dot(z_first - za, d) / (L * L), 0.0, 1.0))
    return la.norm(za + lam * d - z_first) < 0.1 * L + 1e-9


def _critical(mu, kind):
    """The multiplier of ``mu`` that crosses at a bifurcation of ``kind`` (+1: fold, -1: period
    doubling, the unit circle: Neimark-Sacker): on the side where the test function is
    negative (an odd number of real multipliers beyond +1 / below -1) the one of those nearest
    the crossing point, else the largest real one inside."""
    mu = np.asarray(mu)
    if kind == "neimark-sacker":
        c = mu[np.abs(mu.imag) > 1e-9 * np.abs(mu)]
        c = c if c.size else mu
        return c[np.argmin(np.abs(np.abs(c) - 1.0))]
    one = 1.0 if kind == "fold" else -1.0
    real = mu[np.abs(mu.imag) <= 1e-9 * np.abs(mu)].real
    out = real[(real - one) * one > 0]
    if out.size % 2:
        return out[np.argmin(np.abs(out - one))]
    pool = real if real.size else mu
    return pool[np.argmax(np.abs(pool))]


def _fmt_mu(m):
    m = complex(m)
    if abs(m.imag) <= 1e-9 * abs(m):
        return f"{m.real:.4g}"
    return f"{m.real:.4g}{m.imag:+.4g}i (|mu| {abs(m):.4g})"


def _jump_note(kind, a, b):
    """The note of a bifurcation reported at a grazing point: which multiplier jumps there
    (points a and b on the two sides of the grazing point)."""
    if a.multipliers is None or b.multipliers is None:
        return "at grazing: the branch turns back at a corner (non-smooth)"
    return (f"at grazing: multiplier jumps from {_fmt_mu(_critical(a.multipliers, kind))} to "
            f"{_fmt_mu(_critical(b.multipliers, kind))} (non-smooth)")


def _side_note(kind, a, b):
    """The note of a sign change on a smooth side (a .. b) next to a grazing point that the
    locate could not place on the side: reported at the grazing point."""
    if a.multipliers is None or b.multipliers is None:
        return f"at grazing: {kind} on the smooth side next to it, not located (non-smooth)"
    return (f"at grazing: multiplier {_fmt_mu(_critical(a.multipliers, kind))} -> "
            f"{_fmt_mu(_critical(b.multipliers, kind))} on the smooth side next to it, not "
            "located there (non-smooth)")


def _within_resolution(L, G, pts, res):
    """Does the smooth event L lie within the resolution of the grazing point G (``res`` of
    its parameter), with every branch point between them inside that window too (one local
    event, not the branch coming back to the same parameter later)? (Not the grazing
    bracket: near p = 0 a bracket of 6e-6 holds a smooth fold and a corner's fold 2.5e-7
    apart that the tracer tells apart all the same, tests/continuation/
    test_crossing_behind_fold.py.)"""
    g = G.point.p
    window = res * abs(g)
    if abs(L.point.p - g) > window:
        return False
    lo, hi = sorted((L.index, G.index))
    return all(abs(pts[j].p - g) <= window for j in range(lo + 1, min(hi, len(pts) - 1) + 1))


def _beside_grazing_head(kind):
    return f"at grazing: {kind} located"


def located_beside_grazing(kind, note):
    """Is this event (kind, note) one that at_grazing_points moved from its smooth root to a
    grazing point? (Its regular root may exist: refine_bifurcations tries it.)"""
    return str(note).startswith(_beside_grazing_head(kind))


def at_grazing_points(located, pts, res=GRAZING_RESOLUTION):
    """``located`` (of one trace through the points ``pts``) with every fold, period doubling
    and Neimark-Sacker point located on a smooth stretch within ``res`` (relative) of a
    grazing point of the trace (``_within_resolution``) reported at that grazing point (not
    smooth: a fold-grazing, flip-grazing ... point, a codimension-2-like event), with a
    bracket covering both and its root kept (``Located.root``); and the events of one kind
    reported at one grazing point made one (the widest bracket). Whether the tracer's steps
    put such a root on the step before the corner, on the near or the far side of the step
    through it, or could not locate it there (``_detect_step``), is up to round-off; that the
    event lies at the grazing point is not. (The paper model's order-2 branch at 9.66425 Hz:
    a fold on each side of the corner within 1e-6 Hz of it; the far one was located in one
    run only, and the other run merged the two by their value.)"""
    graz = [G for G in located if G.kind == "grazing"]
    out = []
    for L in located:
        G = (None if L.kind == "grazing" or L.note or not L.placed else
             next((G for G in graz if _within_resolution(L, G, pts, res)), None))
        if G is None:
            out.append(L)
            continue
        d = abs(L.point.p - G.point.p)
        out.append(Located(L.kind, G.point, max(G.tolerance, d + L.tolerance), L.index,
                           note=f"{_beside_grazing_head(L.kind)} {d:.1e} from the grazing "
                                "point, within its resolution (non-smooth)",
                           root=L.point))
    merged = []
    for L in out:
        o = next((o for o in merged if L.note.startswith("at grazing")
                  and o.note.startswith("at grazing") and o.kind == L.kind
                  and o.point is L.point), None)
        if o is None:
            merged.append(L)
            continue
        o.tolerance = max(o.tolerance, L.tolerance)
        o.root = o.root if o.root is not None else L.root
        if not o.note.endswith("within the bracket)"):
            o.note += " (2 such events within the bracket)"
        else:
            head, _, tail = o.note.rpartition(" (")
            o.note = f"{head} ({int(tail.split()[0]) + 1} such events within the bracket)"
    return merged


def _near_any(prob, zn, z, avoid):
    """zn (scaled) lies near one of the avoided states of prob: closer than a tenth of that
    state's distance from z."""
    return any(q is prob and np.max(np.abs(zn - v)) < 0.1 * max(np.max(np.abs(v - z)), 1e-9)
               for q, v in avoid)


def _firsts(prob, pts):
    """(z_first, t_first): the branch's first point and first direction in prob's unknowns."""
    w, wp = prob.scale_u, prob.scale_p

    def zz(q):
        u = q.u if q.problem is prob else prob.transfer(q.problem, q.u, q.p)
        return np.r_[u / w, q.p / wp]

    z0 = zz(pts[0])
    if len(pts) < 2:
        return z0, pts[0].tangent
    d = zz(pts[1]) - z0
    return z0, d / la.norm(d)


def _has_pair_near_circle(mu_a, mu_b):
    for mu in (mu_a, mu_b):
        c = mu[np.abs(mu.imag) > 1e-9 * np.abs(mu)]
        if c.size and np.any(np.abs(np.abs(c) - 1) < 0.5):
            return True
    return False
