"""Pseudo-arclength continuation with bifurcation detection, over a small protocol.

A problem offers ``evaluate(u, p, jac, jac_p) -> Evaluation(R, Ju, Jp, Ms, xmax)``,
``scale_u`` (n,), ``scale_p``, ``multipliers(Ms)``, ``solve(u, p)`` and ``adapt(u, p)``
(None, or a new problem and u after the unknowns were redefined, e.g. segment boundaries moved)
with ``transfer(old_problem, u, p)``. Work is done in scaled variables (u / scale_u, p / scale_p).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._newton import ConvergenceError

KINDS = ("fold", "period-doubling", "neimark-sacker")  # from the test functions


@dataclass
class Point:
    u: np.ndarray
    p: float
    xmax: float
    multipliers: np.ndarray
    problem: object
    n_impacts: int = 0


@dataclass
class Located:
    """A bifurcation located on a traced branch. tolerance: width of the final bracket in p."""

    kind: str
    point: Point
    tolerance: float
    index: int  # the branch point before it


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
    """Follows one branch. Options: p_min, p_max (stop outside), ds (initial step, scaled),
    ds_min, ds_max, max_angle (rad, between successive tangents), max_points, tol (corrector,
    scaled residual), bif_tol (relative width in p of the bracket of a located bifurcation),
    detect (bool)."""

    def __init__(self, *, p_min=-np.inf, p_max=np.inf, ds=0.02, ds_min=1e-7, ds_max=0.1,
                 max_angle=0.15, max_points=3000, tol=1e-10, bif_tol=1e-10, detect=True,
                 max_iter=8, jump_after=2, jump_steps=(1e-5, 1e-4, 1e-3), jump_max_distance=0.05,
                 grazing_iter=8, contraction=0.5):
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
        self.contraction = contraction
        self.n_evaluations = 0
        self.debug = False

    # --- corrector ------------------------------------------------------------------------------
    def correct(self, prob, zeta_pred, t):
        """Solve R = 0 with t . (zeta - zeta_pred) = 0 by Newton from zeta_pred; dR/dp is taken
        once, at the predictor (a chord in the parameter column). Returns (zeta, evaluation,
        iterations); the evaluation (with the monodromies) is the one at the returned zeta."""
        w, wp = prob.scale_u, prob.scale_p
        z = zeta_pred.copy()
        Jp = None
        dz_norm = np.inf
        res_prev = np.inf
        self.impacts_seen = set()
        for it in range(1, self.max_iter + 1):
            try:
                ev = prob.evaluate(z[:-1] * w, z[-1] * wp, jac=True, jac_p=Jp is None)
            except ConvergenceError:
                break
            self.n_evaluations += 1
            self.impacts_seen.add(ev.n_impacts)
            if Jp is None:
                Jp = ev.Jp
            ev.Jp = Jp
            r, J = _scaled(ev, w, wp)
            res = float(np.max(np.abs(r)))
            if not np.isfinite(res):
                break
            if res < self.tol or (res < 100 * self.tol and dz_norm < 1e-9):
                return z, ev, it
            if it >= 3 and res > self.contraction * res_prev:
                break  # not converging like Newton: the map is not smooth here, or the step is
                # too long; give up early (the caller halves the step)
            res_prev = res
            A = np.vstack([J, t[None, :]])
            try:
                dz = np.linalg.solve(A, -np.r_[r, t @ (z - zeta_pred)])
            except np.linalg.LinAlgError:
                break
            dz_norm = float(np.max(np.abs(dz)))
            z = z + dz
        raise ConvergenceError("corrector did not converge; try a smaller step (ds) or multiple "
                               "shooting (segments=4)")

    def _point(self, prob, z, ev):
        u = z[:-1] * prob.scale_u
        return Point(u=u, p=float(z[-1] * prob.scale_p), xmax=ev.xmax,
                     multipliers=prob.multipliers(ev.Ms), problem=prob, n_impacts=ev.n_impacts)

    # --- one branch ---------------------------------------------------------------------------
    def _tangent_at(self, prob, z, ev, t_ref):
        r, J = _scaled(ev, prob.scale_u, prob.scale_p)
        return tangent(J, t_ref)

    def trace(self, prob, u0, p0, direction=1, stop=None, t0=None):
        """Follow the branch through the solution (u0, p0) in the direction of increasing p
        (direction=1) or decreasing p (-1), or along t0 (scaled tangent) if given.
        ``stop(point) -> bool`` ends the branch (the point is kept). The step adapts to the
        angle between successive tangents (target ``max_angle / 2``) and to the corrector's
        iterations. Where the number of impacts per period changes between two points (a
        grazing orbit in between: the flow map has a square-root singularity there), the
        grazing point is bracketed; where the corrector fails repeatedly, the branch is
        continued by a natural-parameter step beyond the failure (``jump``) when the failed
        corrector's iterates changed the number of impacts (a grazing point ahead).
        Returns (points, located, reason)."""
        w, wp = prob.scale_u, prob.scale_p
        z = np.r_[np.asarray(u0) / w, p0 / wp]
        ev = prob.evaluate(u0, p0, jac=True, jac_p=True)
        self.n_evaluations += 1
        e_p = np.zeros(len(z))
        e_p[-1] = float(direction)
        t = self._tangent_at(prob, z, ev, e_p if t0 is None else t0)
        pts = [self._point(prob, z, ev)]
        tfs = [test_functions(pts[0].multipliers)]
        located = []
        ds = self.ds0
        z_first = z.copy()
        reason = "max_points"
        n_fail = 0
        tried_jump = near_grazing = False
        ds_ok = ds
        self._creeps = 0
        while len(pts) < self.max_points:
            jumped = False
            try:
                zn, evn, iters = self.correct(prob, z + ds * t, t)
                tn = self._tangent_at(prob, zn, evn, t)
                angle = float(np.arccos(np.clip(t @ tn, -1, 1)))
                ok = angle <= self.max_angle
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
                ds *= 0.5
                if (n_fail >= self.jump_after and near_grazing and not tried_jump
                        and self.jump_steps):
                    tried_jump = True
                    res = self.jump(prob, pts[-1], t)
                    if res is not None:
                        zn, evn, tn = res
                        jumped = True
                        ds = ds_ok
                if not jumped:
                    if ds < self.ds_min:
                        reason = "step underflow"
                        break
                    continue
            tried_jump = near_grazing = False
            if not jumped:
                ds_ok = ds
            n_fail = 0
            if not jumped:
                self._creeps = 0
            pt = self._point(prob, zn, evn)
            tf = test_functions(pt.multipliers)
            prev = pts[-1]
            if pt.n_impacts != prev.n_impacts:
                g = self.locate_grazing(prob, z, t, ds, prev, pt, jumped)
                located.append(Located("grazing", g[0], g[1], len(pts) - 1))
            if stop is not None and stop(pt):
                pts.append(pt)
                tfs.append(tf)
                reason = "stop"
                break
            if self.detect and not jumped:
                for k, kind in enumerate(KINDS):
                    if np.sign(tf[k]) != np.sign(tfs[-1][k]) and tf[k] != 0:
                        if kind == "neimark-sacker" and not _has_pair_near_circle(
                                pts[-1].multipliers, pt.multipliers):
                            continue
                        loc = self.locate(prob, z, t, ds, k, tfs[-1][k], tf[k])
                        if loc is not None:
                            located.append(Located(kind, loc[0], loc[1], len(pts) - 1))
            pts.append(pt)
            tfs.append(tf)
            z, t = zn, tn
            if not (self.p_min <= pt.p <= self.p_max):
                reason = "left the parameter range"
                break
            if len(pts) > 8 and np.linalg.norm(z - z_first) < 1.5 * ds:
                reason = "closed"
                break
            if not jumped:
                fac = 0.5 * self.max_angle / max(angle, 1e-12)
                if iters >= 5:
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
                t = self._tangent_at(prob2, z, ev2, sec / np.linalg.norm(sec))
                pts[-1] = self._point(prob2, z, ev2)
                z_first = np.r_[prob2.transfer(pts[0].problem, pts[0].u, pts[0].p) / w,
                                pts[0].p / wp]
                prob = prob2
        return pts, located, reason

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

        def accept(u, p):
            ev = prob.evaluate(u, p, jac=True, jac_p=True)
            zn = np.r_[u / w, p / wp]
            return zn, ev, self._tangent_at(prob, zn, ev, e_p)

        for rel in self.jump_steps:
            dp = sp * rel
            guesses = [z[:-1] + t[:-1] / t[-1] * dp, z[:-1]] if abs(t[-1]) > 1e-3 else [z[:-1]]
            for g in guesses:
                try:
                    u, ev, res, it = prob.solve(g * w, (z[-1] + dp) * wp, tol=self.tol,
                                                max_iter=self.max_iter + 4)
                except ConvergenceError:
                    continue
                self.n_evaluations += it + 1
                if np.max(np.abs(u / w - z[:-1])) > self.jump_max_distance:
                    continue  # another branch
                if ev.n_impacts != pt.n_impacts:
                    return accept(u, (z[-1] + dp) * wp)
                same = (u, (z[-1] + dp) * wp)
                break
        if hasattr(prob, "settle"):
            p_new = (z[-1] + sp * self.jump_steps[-1]) * wp
            try:
                u = prob.settle(pt.u, pt.p, p_new)
                u, ev, _, _ = prob.solve(u, p_new, tol=self.tol, max_iter=self.max_iter + 4)
                if (ev.n_impacts != pt.n_impacts and abs(ev.xmax - pt.xmax) < 0.1 * abs(pt.xmax)
                        and np.max(np.abs(u / w - z[:-1])) < 10 * self.jump_max_distance):
                    return accept(u, p_new)
            except ConvergenceError:
                pass
        if same is not None and self._creeps < 3:
            self._creeps += 1
            return accept(*same)
        return None

    def locate_grazing(self, prob, z_a, t_a, ds, pa, pb, jumped):
        """Bracket the point between pa and pb where the number of impacts per period changes,
        by bisection (on the arclength step, or in the parameter after a jump). Returns
        (Point on the side of pb nearest the grazing point, width of the bracket in p)."""
        best, lo_p, hi_p = pb, pa.p, pb.p
        if jumped:
            w, wp = prob.scale_u, prob.scale_p
            u_lo, u_hi = pa.u, pb.u
            for _ in range(self.grazing_iter):
                pm = 0.5 * (lo_p + hi_p)
                try:
                    u, ev, _, _ = prob.solve(u_lo, pm, tol=self.tol)
                except ConvergenceError:
                    hi_p = pm  # no solution continuing the near side: beyond the grazing point
                    continue
                q = self._point(prob, np.r_[u / w, pm / wp], ev)
                if q.n_impacts == pa.n_impacts:
                    lo_p, u_lo = pm, u
                else:
                    hi_p, u_hi, best = pm, u, q
            return best, abs(hi_p - lo_p)
        lo, hi = 0.0, ds
        for _ in range(self.grazing_iter):
            s = 0.5 * (lo + hi)
            try:
                zs, evs, _ = self.correct(prob, z_a + s * t_a, t_a)
            except ConvergenceError:
                break
            q = self._point(prob, zs, evs)
            if q.n_impacts == pa.n_impacts:
                lo, lo_p = s, q.p
            else:
                hi, hi_p, best = s, q.p, q
            if abs(hi_p - lo_p) <= self.bif_tol * abs(hi_p) * 10:
                break
        return best, abs(hi_p - lo_p)

    # --- bifurcation location -----------------------------------------------------------------
    def locate(self, prob, z_a, t_a, ds, k, g_a, g_b):
        """Illinois regula falsi on the arclength step from z_a (test function k), until the
        bracket's width in p is below bif_tol * |p|. Returns (Point, tolerance) or None."""
        lo, hi = 0.0, ds
        glo, ghi = g_a, g_b
        p_lo = z_a[-1] * prob.scale_p
        zb, _, _ = None, None, None
        best = None
        p_hi = None
        side = 0
        for _ in range(60):
            s = hi - ghi * (hi - lo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
            if not (lo < s < hi):
                s = 0.5 * (lo + hi)
            try:
                zs, evs, _ = self.correct(prob, z_a + s * t_a, t_a)
            except ConvergenceError:
                return None
            pt = self._point(prob, zs, evs)
            g = test_functions(pt.multipliers)[k]
            best = pt
            if np.sign(g) == np.sign(glo):
                lo, glo, p_lo = s, g, pt.p
                if side == -1:
                    ghi *= 0.5
                side = -1
            else:
                hi, ghi, p_hi = s, g, pt.p
                if side == 1:
                    glo *= 0.5
                side = 1
            if (p_hi is not None and abs(p_hi - p_lo) <= self.bif_tol * max(abs(pt.p), 1e-300)
                    and hi - lo < 1e-6):
                break
            if g == 0 or hi - lo < 1e-15:
                break
        tol = abs(p_hi - p_lo) if p_hi is not None else np.inf
        return best, tol


def _has_pair_near_circle(mu_a, mu_b):
    for mu in (mu_a, mu_b):
        c = mu[np.abs(mu.imag) > 1e-9 * np.abs(mu)]
        if c.size and np.any(np.abs(np.abs(c) - 1) < 0.5):
            return True
    return False
