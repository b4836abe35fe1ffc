"""Pseudo-arclength continuation with bifurcation detection, over a small protocol
(``Problem``: what the Tracer asks of a problem; continuation.shooting.ShootingProblem is one).
Work is done in scaled variables (u / scale_u, p / scale_p).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ._newton import ContinuationWarning, ConvergenceError

KINDS = ("fold", "period-doubling", "neimark-sacker")  # from the test functions


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
      at p (the second way past a non-smooth point in ``Tracer.jump``; default: raises
      ConvergenceError, so that way is skipped).
    """

    scale_u: np.ndarray
    scale_p: float
    variational: bool = True

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


@dataclass
class Located:
    """A bifurcation located on a traced branch. tolerance: width of the final bracket in p."""

    kind: str
    point: Point
    tolerance: float
    index: int  # the branch point before it
    note: str = ""  # e.g. 'at grazing: ...' where a multiplier jumps across the unit circle


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


def tangent(J, t_prev):
    """Unit null vector of J (n, n+1) with a positive projection on t_prev."""
    A = np.vstack([J, t_prev[None, :]])
    b = np.zeros(A.shape[0])
    b[-1] = 1.0
    t = np.linalg.solve(A, b)
    return t / np.linalg.norm(t)


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

    The corrector is a quasi-Newton iteration on the bordered system: the Jacobian at the
    predictor is dR/du from the variational equations (or, for a problem without them, the
    previous point's Jacobian, or forward differences) with dR/dp carried from the previous
    point, and every iterate updates it by Broyden's rank-one secant formula. The variational
    monodromy is the derivative of the exact flow, not of the fixed-step map whose fixed point
    is solved for (the contact steps depend on the state); where the two differ by more than a
    few per cent (soft, chattering contacts; orbits with multipliers >> 1) plain Newton only
    converges linearly and the step control used to creep. The secant updates make the
    iteration converge superlinearly to the discrete map's fixed point there too."""

    def __init__(self, *, p_min=-np.inf, p_max=np.inf, ds=0.02, ds_min=1e-7, ds_max=0.1,
                 max_angle=0.15, max_points=3000, tol=1e-10, bif_tol=1e-10, detect=True,
                 max_iter=10, jump_after=2, jump_steps=(1e-5, 1e-4, 1e-3), jump_max_distance=0.05,
                 grazing_iter=8, grazing_ds=0.01, contraction=0.7, noise_tol=1e-7,
                 progress_points=40, progress_min=2e-3, label="branch"):
        self.p_min, self.p_max = p_min, p_max
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
        self.n_evaluations = 0
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
        for it in range(1, self.max_iter + 1):
            try:
                ev = prob.evaluate(z[:-1] * w, z[-1] * wp, jac=var, jac_p=False)
            except ConvergenceError:
                break
            self.n_evaluations += 1
            self.impacts_seen.add(ev.n_impacts)
            r = ev.R / w
            res = float(np.max(np.abs(r)))
            if self.debug:
                print("    it %d res %.2e imp %d" % (it, res, ev.n_impacts))
            if not np.isfinite(res):
                break
            base = self._base(prob, ev)
            if C is None:
                C = self._correction(prob, z, ev, C_prev, fixed_p)
                lazy = (z.copy(), ev) if fixed_p else None
            elif dz_norm > 1e-6:
                # Broyden's update (not from steps so short that the map's noise, ~1e-8 where
                # contacts nearly stick, would dominate the difference)
                C = C + np.outer(r - r_prev - (base + C) @ dz, dz) / (dz @ dz)
            B = base + C
            ev.B, ev.C, ev.lazy_p = B, C, lazy
            if res < self.tol or (res < 100 * self.tol and dz_norm < 1e-9):
                return z, ev, it
            if it >= 3 and res > self.contraction * res_prev:
                if res_prev < self.noise_tol and res < self.noise_tol:
                    # stagnating below noise_tol: the fixed-step map is not smooth at this
                    # level (contact step decisions); accept the better iterate
                    if res_prev < res:
                        return z_prev, ev_prev, it
                    return z, ev, it
                break  # not converging: the map is not smooth here, or the step is too long;
                # give up early (the caller halves the step)
            z_prev, ev_prev = z, ev
            res_prev = res
            r_prev = r
            A = np.vstack([B, t[None, :]])
            try:
                dz = np.linalg.solve(A, -np.r_[r, t @ (z - zeta_pred)])
            except np.linalg.LinAlgError:
                break
            dz_norm = float(np.max(np.abs(dz)))
            z = z + dz
        raise ConvergenceError("corrector did not converge; try a smaller step (ds) or multiple "
                               "shooting (segments=4)")

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
    def trace(self, prob, u0, p0, direction=1, stop=None, t0=None):
        """Follow the branch through the solution (u0, p0) in the direction of increasing p
        (direction=1) or decreasing p (-1), or along t0 (scaled tangent) if given.
        ``stop(point) -> bool`` ends the branch (the point is kept). The predictor follows the
        secant through the last two points (the Jacobian's tangent at the first), and the step
        adapts to the angle between successive secants (target ``max_angle / 2``; the secant
        measures the branch's curvature even where the Jacobian is only approximate) and to
        the corrector's iterations. Where the number of impacts per period changes between two
        points (a grazing orbit in between: the flow map has a square-root singularity there),
        the grazing point is bracketed; where the corrector fails repeatedly, the branch is
        continued by a natural-parameter step beyond the failure (``jump``) when the failed
        corrector's iterates changed the number of impacts (a grazing point ahead).
        A branch that makes no progress (see the class doc) stops with a ContinuationWarning.
        Returns (points, located, reason)."""
        w, wp = prob.scale_u, prob.scale_p
        z = np.r_[np.asarray(u0) / w, p0 / wp]
        ev = prob.evaluate(u0, p0, jac=True, jac_p=True)
        self.n_evaluations += 1
        e_p = np.zeros(len(z))
        e_p[-1] = float(direction)
        pt0 = self._point(prob, z, ev, e_p if t0 is None else t0)
        t = pt0.tangent
        pts = [pt0]
        tfs = [self._tests(pt0)]
        located = []
        ds = self.ds0
        z_first = z.copy()
        t_first = t.copy()
        reason = "max_points"
        n_fail = 0
        tried_jump = near_grazing = False
        ds_ok = ds
        self._creeps = 0
        steps = []  # scaled arclength of each accepted step (the no-progress rule)
        angle_rej = np.inf  # the angle of the last step rejected for its angle
        while len(pts) < self.max_points:
            jumped = False
            try:
                zn, evn, iters = self.correct(prob, z + ds * t, t, pts[-1].corr)
                ptn = self._point(prob, zn, evn, t)
                tn = (zn - z) / np.linalg.norm(zn - z)  # secant: the next predictor
                angle = float(np.arccos(np.clip(t @ tn, -1, 1)))
                ok = angle <= self.max_angle
                if ok and ptn.n_impacts != pts[-1].n_impacts and ds > self.grazing_ds:
                    ok = False  # a grazing point ahead: approach it with short steps, so that
                    # it is bracketed closely and the step does not cut a corner of the branch
                    angle = np.nan
            except ConvergenceError:
                ok = False
                iters = self.max_iter
                angle = np.inf
            if not ok and self.impacts_seen - {pts[-1].n_impacts}:
                near_grazing = True  # the corrector's iterates changed the number of impacts
            if self.debug:
                print("ds %.3g ok %s iters %d angle %.3g p %.9g" % (ds, ok, iters, angle,
                                                                 z[-1] * prob.scale_p))
            if not ok:
                n_fail += 1
                if np.isfinite(angle) and angle > 0.7 * angle_rej:
                    # the angle does not shrink with the step: the predictor's direction (the
                    # last secant) is off, e.g. after a corner; the short trial step's secant
                    # is the local tangent
                    t = tn
                angle_rej = angle if np.isfinite(angle) else np.inf
                ds *= 0.5
                if (n_fail >= self.jump_after and near_grazing and not tried_jump
                        and self.jump_steps):
                    tried_jump = True
                    res = self.jump(prob, pts[-1], t)
                    if res is not None:
                        zn, evn, tn = res
                        ptn = self._point(prob, zn, evn, tn)  # tn: the Jacobian's tangent
                        # (the secant across the jump is no tangent of the far side)
                        jumped = True
                        ds = ds_ok
                if not jumped:
                    if ds < self.ds_min:
                        reason = "step underflow"
                        break
                    continue
            tried_jump = near_grazing = False
            angle_rej = np.inf
            if not jumped:
                ds_ok = ds
            n_fail = 0
            if not jumped:
                self._creeps = 0
            pt = ptn
            tf = self._tests(pt)
            prev = pts[-1]
            grazing = None
            if pt.n_impacts != prev.n_impacts:
                grazing = self.locate_grazing(prob, z, t, ds, prev, pt, jumped)
                located.append(Located("grazing", grazing[0], grazing[1], len(pts) - 1))
            if stop is not None and stop(pt):
                pts.append(pt)
                tfs.append(tf)
                reason = "stop"
                break
            if self.detect:
                located += self._detect_step(prob, z, t, ds, prev, pt, tfs[-1], tf, jumped,
                                             grazing, len(pts) - 1)
            steps.append(float(np.linalg.norm(zn - z)))
            pts.append(pt)
            tfs.append(tf)
            z, t = zn, tn
            if not (self.p_min <= pt.p <= self.p_max):
                reason = "left the parameter range"
                break
            if len(pts) > 8 and _passes(z_first, t_first, pts[-2], z, prob):
                reason = "closed"
                break
            if (len(steps) >= self.progress_points
                    and sum(steps[-self.progress_points:]) < self.progress_min):
                reason = "no progress"
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
                if iters >= 6:
                    fac = min(fac, 0.7)
                ds = min(self.ds_max, ds * min(2.0, max(0.5, fac)))
            new = prob.adapt(pt.u, pt.p)
            if new is not None:
                prob2, u2 = new
                try:
                    u2, ev2, _, _ = prob2.solve(u2, pt.p, tol=self.tol)
                except ConvergenceError:
                    reason = "could not move the segment boundaries"
                    break
                w, wp = prob2.scale_u, prob2.scale_p
                z_prev_new = np.r_[prob2.transfer(pts[-2].problem, pts[-2].u, pts[-2].p) / w,
                                   pts[-2].p / wp]
                z = np.r_[u2 / w, pt.p / wp]
                ev2 = prob2.evaluate(u2, pt.p, jac=True, jac_p=True)
                sec = z - z_prev_new
                t = sec / np.linalg.norm(sec)
                pts[-1] = self._point(prob2, z, ev2, t)
                z1 = np.r_[prob2.transfer(pts[1].problem, pts[1].u, pts[1].p) / w,
                           pts[1].p / wp] if len(pts) > 1 else None
                z_first = np.r_[prob2.transfer(pts[0].problem, pts[0].u, pts[0].p) / w,
                                pts[0].p / wp]
                if z1 is not None:
                    t_first = (z1 - z_first) / np.linalg.norm(z1 - z_first)
                prob = prob2
        return pts, located, reason

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
        listed once, wherever round-off puts it relative to the grazing point."""
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
                    loc = (b, abs(b.p - a.p))
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
        L = float(np.linalg.norm(d))
        if L == 0.0:
            return None
        return self.locate(prob, za, d / L, L, k, g_a, g_b, pa.corr, p_a=pa.p,
                           n_impacts=pa.n_impacts)

    # --- past a non-smooth point ----------------------------------------------------------------
    def jump(self, prob, pt, t):
        """Continue past a point where the corrector fails (typically a grazing orbit, where the
        flow map is not differentiable): (1) solve at fixed parameter a little beyond, in the
        direction of travel, from the linear predictor, taking the first solution close to the
        last one with a different number of impacts; (2) else integrate from the last orbit a
        little beyond until it settles (``problem.settle``) and shoot from there; (3) else take
        the furthest fixed-parameter solution found in (1). Returns (zeta, evaluation,
        tangent) or None."""
        w, wp = prob.scale_u, prob.scale_p
        z = np.r_[pt.u / w, pt.p / wp]
        sp = 1.0 if t[-1] >= 0 else -1.0
        e_p = np.zeros(len(z))
        e_p[-1] = sp
        same = None

        def solve_at(u, p):
            """The quasi-Newton corrector at fixed p (the bordering row fixes p)."""
            zs, evs, _ = self.correct(prob, np.r_[u / w, p / wp], e_p, pt.corr, fixed_p=True)
            return zs, evs

        def accept(zs, evs):
            self.complete_jacobian(prob, evs)
            return zs, evs, tangent(evs.B, e_p)

        for rel in self.jump_steps:
            dp = sp * rel
            guesses = [z[:-1] + t[:-1] / t[-1] * dp, z[:-1]] if abs(t[-1]) > 1e-3 else [z[:-1]]
            for g in guesses:
                try:
                    zs, evs = solve_at(g * w, (z[-1] + dp) * wp)
                except ConvergenceError:
                    continue
                if np.max(np.abs(zs[:-1] - z[:-1])) > self.jump_max_distance:
                    continue  # another branch
                if evs.n_impacts != pt.n_impacts:
                    return accept(zs, evs)
                same = (zs, evs)
                break
        p_new = (z[-1] + sp * self.jump_steps[-1]) * wp
        try:
            u = prob.settle(pt.u, pt.p, p_new, efolds=4.0)
            zs, evs = solve_at(u, p_new)
            if (evs.n_impacts != pt.n_impacts
                    and abs(evs.xmax - pt.xmax) < 0.1 * abs(pt.xmax)
                    and np.max(np.abs(zs[:-1] - z[:-1])) < 10 * self.jump_max_distance):
                return accept(zs, evs)
        except ConvergenceError:
            pass
        if same is not None and self._creeps < 3:
            self._creeps += 1
            return accept(*same)
        return None

    def locate_grazing(self, prob, z_a, t_a, ds, pa, pb, jumped):
        """Bracket the point between pa and pb where the number of impacts per period changes,
        by bisection (on the arclength step, or in the parameter after a jump). Returns
        (Point on the side of pb nearest the grazing point, width of the bracket in p,
        Point on the side of pa nearest it (pa if none), (arclength of the two from z_a along
        t_a, or None after a jump))."""
        best, lo_p, hi_p = pb, pa.p, pb.p
        near = pa
        if jumped:
            w, wp = prob.scale_u, prob.scale_p
            u_lo = pa.u
            for _ in range(self.grazing_iter):
                pm = 0.5 * (lo_p + hi_p)
                e_p = np.zeros(len(u_lo) + 1)
                e_p[-1] = 1.0
                try:
                    zs, ev, _ = self.correct(prob, np.r_[u_lo / w, pm / wp], e_p, pa.corr,
                                             fixed_p=True)
                except ConvergenceError:
                    hi_p = pm  # no solution continuing the near side: beyond the grazing point
                    continue
                u = zs[:-1] * w
                q = self._point(prob, zs, ev)
                if q.n_impacts == pa.n_impacts:
                    lo_p, u_lo, near = pm, u, q
                else:
                    hi_p, best = pm, q
            return best, abs(best.p - lo_p), near, None  # the reported point to the near side
        lo, hi = 0.0, ds
        for _ in range(self.grazing_iter):
            s = 0.5 * (lo + hi)
            try:
                zs, evs, _ = self.correct(prob, z_a + s * t_a, t_a, pa.corr)
            except ConvergenceError:
                break
            q = self._point(prob, zs, evs, t_a)
            if q.n_impacts == pa.n_impacts:
                lo, lo_p, near = s, q.p, q
            else:
                hi, hi_p, best = s, q.p, q
            if abs(hi_p - lo_p) <= self.bif_tol * abs(hi_p) * 10:
                break
        return best, abs(best.p - lo_p), near, (lo, hi)

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
    L = float(np.linalg.norm(d))
    if L == 0.0 or d @ t_first < 0.8 * L:
        return False
    lam = float(np.clip((z_first - za) @ d / (L * L), 0.0, 1.0))
    return float(np.linalg.norm(za + lam * d - z_first)) < 0.1 * L + 1e-9


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


def _has_pair_near_circle(mu_a, mu_b):
    for mu in (mu_a, mu_b):
        c = mu[np.abs(mu.imag) > 1e-9 * np.abs(mu)]
        if c.size and np.any(np.abs(np.abs(c) - 1) < 0.5):
            return True
    return False
