"""Exact periodic answers for a harmonically excited single-DOF oscillator with a one-sided
linear stop (the test's independent reference; registered as the module ``exact_pwl`` by
conftest.py, like helpers.py).

    m x'' + c x' + k x + ks max(delta, 0) = F(t),    delta = x + wy y(t) - gap,

force excitation: F = A cos(w t), wy = 0; base excitation: y = A cos(w t), F = k y + c y', and
wy = -1 when the stop sits on the base (else 0). On each side of the switching surface
delta = 0 the equation is linear with harmonic forcing, so with z = [x, v]

    z(t) = E(t - t0) (z(t0) - zp(t0)) + zp(t),   E(s) = expm(A s),
    zp(t) = z_const + Re(Z exp(i w t))  (the particular solution),

exactly. The switching times are roots of delta(t) on that closed form (bracketed on a fine
sample of it, extrema checked for tangential touches, then Brent to round-off). The force
ks max(delta, 0) is continuous across delta = 0 (it vanishes there from both sides, also when
the surface moves with the base, gap > 0 or not), so the vector field is continuous and the
saltation matrix at a switch is the identity: the monodromy is the product of the segments'
state-transition matrices E. (``monodromy_by_differences`` checks this against central
differences of the exact period map.) Periodic orbits solve P(z0) = z0 by Newton with that
exact Jacobian; folds and period doublings solve P(z0, f) = z0 with det(M -+ I) = 0.
Units: m, s, Hz, N."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

import nlbeam


@dataclass(frozen=True)
class StopOscillator:
    """m (kg), c (kg/s), k (N/m), ks (N/m, the stop), gap (m); kind 'force' or 'base';
    on_base: the stop moves with the base (base excitation only); amplitude: N or m."""

    m: float
    c: float
    k: float
    ks: float
    gap: float
    amplitude: float
    kind: str = "force"
    on_base: bool = False

    @classmethod
    def tuned(cls, fn=1.0, zeta=0.02, ratio=100.0, gap=0.1, amplitude=1.0, kind="force",
              on_base=False):
        k = (2 * np.pi * fn) ** 2
        return cls(1.0, 2 * zeta * math.sqrt(k), k, ratio * k, gap, amplitude, kind, on_base)

    def system(self):
        """The same oscillator as an nlbeam System."""
        el = nlbeam.PiecewiseLinearStop(0, k=self.ks, gap=self.gap, on_base=self.on_base)
        if self.kind == "force":
            return nlbeam.System([[self.m]], [[self.c]], [[self.k]], elements=(el,),
                                 excitation_kind="force", y_load=[1.0])
        return nlbeam.System([[self.m]], [[self.c]], [[self.k]], elements=(el,),
                             excitation_kind="base")

    @property
    def wy(self):
        return -1.0 if (self.kind == "base" and self.on_base) else 0.0

    def regions(self, f):
        """The two linear regions at frequency f: a list (free, contact) of
        (A (2, 2), z_const (2,), Z (2,) complex, eigenvalues, V, V^-1)."""
        w = 2 * np.pi * f
        out = []
        for r in (0, 1):
            kk = self.k + r * self.ks
            A = np.array([[0.0, 1.0], [-kk / self.m, -self.c / self.m]])
            b = np.array([0.0, r * self.ks * self.gap / self.m])
            if self.kind == "force":
                B = np.array([0.0, self.amplitude / self.m], dtype=complex)
            else:
                B = np.array([0.0, (self.k + 1j * self.c * w - r * self.ks * self.wy)
                              * self.amplitude / self.m])
            zc = -np.linalg.solve(A, b)
            Z = np.linalg.solve(1j * w * np.eye(2) - A, B)
            lam, V = np.linalg.eig(A)
            out.append((A, zc, Z, lam, V, np.linalg.inv(V)))
        return out


class ExactFlow:
    """The exact flow of a StopOscillator at frequency f (Hz)."""

    def __init__(self, osc, f, samples=96):
        self.osc, self.f, self.w = osc, float(f), 2 * np.pi * f
        self.reg = osc.regions(f)
        # sample spacing: a fraction of the shortest time scale (forcing, either region)
        scales = [1 / f] + [2 * np.pi / abs(lam).max() for (_, _, _, lam, _, _) in self.reg]
        self.h = min(scales) / samples

    def zp(self, r, t):
        """The particular (periodic) solution of region r at the time t (s)."""
        _, zc, Z, _, _, _ = self.reg[r]
        return zc + (Z * np.exp(1j * self.w * t)).real

    def states(self, r, t0, z0, t):
        """z at the times t (array) of region r's solution through (t0, z0); shape (2, n)."""
        _, zc, Z, lam, V, Vi = self.reg[r]
        t = np.atleast_1d(np.asarray(t, dtype=float))
        c = Vi @ (z0 - self.zp(r, t0))
        hom = (V @ (c[:, None] * np.exp(np.outer(lam, t - t0)))).real
        return hom + zc[:, None] + (Z[:, None] * np.exp(1j * self.w * t)[None, :]).real

    def stm(self, r, s):
        return scipy.linalg.expm(self.reg[r][0] * s)

    def delta(self, z, t):
        y = self.osc.amplitude * np.cos(self.w * t) if self.osc.kind == "base" else 0.0
        return z[0] + self.osc.wy * y - self.osc.gap

    def region_at(self, z, t):
        d = self.delta(z, t)
        if d != 0.0:
            return int(d > 0)
        yd = -self.osc.amplitude * self.w * math.sin(self.w * t) if self.osc.kind == "base" \
            else 0.0
        return int(z[1] + self.osc.wy * yd > 0)

    def _next_switch(self, r, t0, z0, t1):
        """The first time in (t0, t1] where region r's solution leaves the region (None)."""
        n = max(4, int(math.ceil((t1 - t0) / self.h)))
        ts = np.linspace(t0, t1, n + 1)
        sgn = 1.0 if r == 0 else -1.0  # g = sgn * delta: negative inside the region

        def g(t):
            return sgn * self.delta(self.states(r, t0, z0, t)[:, 0], t)

        d = sgn * self.delta(self.states(r, t0, z0, ts), ts)
        thr = 1e-13 * (abs(z0[0]) + self.osc.gap + abs(self.osc.amplitude) / self.osc.k)
        eps = 1e-3 * (ts[1] - ts[0])
        out = np.flatnonzero(d[1:] > 0)
        i_out = int(out[0]) + 1 if out.size else n + 1
        # touches between samples: local maxima of g below zero before i_out, close enough to
        # zero that the true maximum may exceed it (within the local change of the samples)
        ii = np.arange(1, min(i_out, n))
        mx = ii[(d[ii] >= d[ii - 1]) & (d[ii] >= d[ii + 1])
                & (d[ii] > -4 * (np.abs(d[ii + 1] - d[ii]) + np.abs(d[ii] - d[ii - 1])))]
        for i in mx:
            res = scipy.optimize.minimize_scalar(
                lambda t: -g(t), bounds=(ts[i - 1], ts[i + 1]), method="bounded",
                options={"xatol": 1e-14 * max(1.0, abs(ts[i]))})
            if -res.fun > thr and res.x > ts[0] + eps:
                lo = ts[i - 1] if g(ts[i - 1]) < 0 else ts[0] + eps
                return scipy.optimize.brentq(g, lo, res.x, xtol=1e-16, rtol=1e-15, maxiter=200)
        if i_out <= n:
            lo = ts[i_out - 1] if (i_out > 1 or g(ts[0]) < 0) else ts[0] + eps
            return scipy.optimize.brentq(g, lo, ts[i_out], xtol=1e-16, rtol=1e-15, maxiter=200)
        return None

    def run(self, z0, t0, duration):
        """Flow over [t0, t0 + duration]: (z_end, monodromy (product of the segments' STMs),
        list of segments (region, ta, tb, z at ta))."""
        t1 = t0 + duration
        t, z = float(t0), np.asarray(z0, dtype=float)
        r = self.region_at(z, t)
        Phi = np.eye(2)
        segs = []
        while True:
            ts = self._next_switch(r, t, z, t1)
            te = t1 if ts is None else ts
            z_new = self.states(r, t, z, te)[:, 0]
            Phi = self.stm(r, te - t) @ Phi
            segs.append((r, t, te, z.copy()))
            t, z = te, z_new
            if ts is None:
                return z, Phi, segs
            r = 1 - r
            if len(segs) > 10000:
                raise RuntimeError("exact flow: more than 10000 switches")

    def xmax(self, segs):
        """max |x| over the segments, from the roots of v in each (Brent) and the ends."""
        best = 0.0
        for (r, ta, tb, za) in segs:
            n = max(4, int(math.ceil((tb - ta) / self.h)))
            ts = np.linspace(ta, tb, n + 1)
            Z = self.states(r, ta, za, ts)
            best = max(best, float(np.abs(Z[0]).max()))
            v = Z[1]
            for i in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
                tr = scipy.optimize.brentq(lambda t: self.states(r, ta, za, t)[1, 0],
                                           ts[i], ts[i + 1], xtol=1e-16, rtol=1e-15)
                best = max(best, abs(float(self.states(r, ta, za, tr)[0, 0])))
        return best


@dataclass
class ExactOrbit:
    frequency: float
    order: int
    state0: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray  # sorted by modulus, largest first
    xmax: float
    n_impacts: int
    switch_times: np.ndarray  # (s) within the period

    @property
    def stable(self):
        return bool(np.abs(self.multipliers).max() < 1.0)


def period_map(osc, f, z0, order=1):
    fl = ExactFlow(osc, f)
    z, Phi, segs = fl.run(z0, 0.0, order / f)
    return z, Phi, segs, fl


def orbit(osc, f, guess, order=1, tol=1e-13, max_iter=30):
    """The exact periodic orbit of this order near the state ``guess`` at t = 0 (Newton on
    P(z0) = z0 with the exact monodromy); raises RuntimeError if Newton does not converge."""
    z0 = np.asarray(guess, dtype=float).copy()
    sc = np.array([1.0, 2 * np.pi * f]) * max(abs(z0[0]), abs(z0[1]) / (2 * np.pi * f), 1e-300)
    for it in range(max_iter):
        z, Phi, segs, fl = period_map(osc, f, z0, order)
        R = z - z0
        if np.max(np.abs(R) / sc) < tol:
            break
        z0 = z0 - np.linalg.solve(Phi - np.eye(2), R)
    else:
        raise RuntimeError(f"exact orbit at {f} Hz: Newton did not converge (residual "
                           f"{np.max(np.abs(R) / sc):.2e})")
    mu = np.linalg.eigvals(Phi)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    sw = np.array([s[1] for s in segs[1:]])
    n_imp = sum(1 for s in segs[1:] if s[0] == 1)
    return ExactOrbit(float(f), order, z0, Phi, mu, fl.xmax(segs), n_imp, sw)


def free_amplitude(osc, f):
    """Complex amplitude D of delta + gap = Re(D exp(i w t)) on the non-impacting orbit."""
    _, _, Z, _, _, _ = osc.regions(f)[0]
    return Z[0] + osc.wy * osc.amplitude


def grazing_frequencies(osc, f_lo, f_hi, n=4000):
    """Frequencies in (f_lo, f_hi) where the non-impacting orbit just touches the stop,
    |D(f)| = gap (closed form; Brent on a fine bracket)."""
    fs = np.linspace(f_lo, f_hi, n + 1)
    g = np.array([abs(free_amplitude(osc, f)) - osc.gap for f in fs])
    out = []
    for i in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
        out.append(scipy.optimize.brentq(lambda f: abs(free_amplitude(osc, f)) - osc.gap,
                                         fs[i], fs[i + 1], xtol=1e-15, rtol=1e-15))
    return out


def free_orbit_state(osc, f):
    """State at t = 0 of the non-impacting orbit (exact where it does not reach the stop)."""
    _, zc, Z, _, _, _ = osc.regions(f)[0]
    return zc + Z.real


def monodromy_by_differences(osc, f, z0, order=1, rel=1e-6):
    """Central differences of the exact period map (checks the no-saltation reasoning)."""
    sc = np.array([1.0, 2 * np.pi * f]) * max(abs(z0[0]), abs(z0[1]) / (2 * np.pi * f))
    M = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = rel * sc[j]
        M[:, j] = (period_map(osc, f, z0 + e, order)[0]
                   - period_map(osc, f, z0 - e, order)[0]) / (2 * e[j])
    return M


@dataclass
class ExactBranch:
    """Exact orbits along a branch traced in frequency by pseudo-arclength continuation:
    frequency (n,), orbits (n,) ExactOrbit; folds / period_doublings: located frequencies
    (the extended systems solved to ~1e-11 relative)."""

    frequency: np.ndarray
    orbits: list
    folds: list
    period_doublings: list


class _Scaled:
    """The periodicity residual in scaled unknowns u = (x0, v0, f) / S and its Jacobian
    [M - I | dP/df] (dP/df by central differences of the exact map)."""

    def __init__(self, osc, order, S):
        self.osc, self.order, self.S = osc, order, S

    def F(self, u):
        z0, f = u[:2] * self.S[:2], u[2] * self.S[2]
        z, Phi, _, _ = period_map(self.osc, f, z0, self.order)
        return (z - z0) / self.S[:2], Phi

    def jac(self, u, Phi):
        S = self.S
        J = np.empty((2, 3))
        J[:, :2] = (Phi - np.eye(2)) * S[None, :2] / S[:2, None]
        h = 1e-7 * u[2]
        up, um = u.copy(), u.copy()
        up[2] += h
        um[2] -= h
        J[:, 2] = (self.F(up)[0] - self.F(um)[0]) / (2 * h)
        return J

    def on_plane(self, u_guess, tau, c, tol=1e-13):
        """Newton for R(u) = 0 on the plane tau . u = c; (u, monodromy) or None."""
        u = u_guess.copy()
        for _ in range(15):
            R, Phi = self.F(u)
            J = self.jac(u, Phi)
            du = np.linalg.solve(np.vstack([J, tau]), -np.r_[R, tau @ u - c])
            u = u + du
            if np.max(np.abs(du)) < tol:
                R, Phi = self.F(u)
                return (u, Phi) if np.max(np.abs(R)) < 1e-10 else None
        return None


def trace(osc, f0, guess, f_lo, f_hi, order=1, ds=0.02, max_points=3000):
    """Follow the exact order-``order`` branch through the orbit near ``guess`` at f0 in both
    directions until it leaves [f_lo, f_hi] (pseudo-arclength in scaled (z0, f); the map's
    f-derivative by central differences). Folds (a real multiplier through +1) and period
    doublings (through -1) are located by bisection along the chord between two branch
    points (each point solved on a plane normal to the chord)."""
    o0 = orbit(osc, f0, guess, order)
    a = max(abs(o0.state0[0]), abs(o0.state0[1]) / (2 * np.pi * f0), osc.gap, 1e-300)
    S = np.array([a, a * 2 * np.pi * f0, f0])  # scales of (x0, v0, f)
    P = _Scaled(osc, order, S)
    u0 = np.r_[o0.state0 / S[:2], f0 / S[2]]
    sides = []
    for direction in (1.0, -1.0):
        u = u0.copy()
        R, Phi = P.F(u)
        tau = scipy.linalg.null_space(P.jac(u, Phi))[:, 0]
        tau *= direction * (np.sign(tau[2]) if tau[2] != 0 else 1.0)
        pts = []
        h = ds
        while len(pts) < max_points:
            res = P.on_plane(u + h * tau, tau, tau @ u + h)
            if res is None:
                h *= 0.5
                if h < 1e-9:
                    break
                continue
            up, Phi = res
            tnew = scipy.linalg.null_space(P.jac(up, Phi))[:, 0]
            if tnew @ tau < 0:
                tnew = -tnew
            if tnew @ tau < math.cos(0.1) and h > 1e-6:
                h *= 0.5
                continue
            u, tau = up, tnew
            pts.append(u.copy())
            h = min(h * 1.3, ds)
            if not (f_lo <= u[2] * S[2] <= f_hi):
                break
        sides.append(pts)
    us = sides[1][::-1] + [u0] + sides[0]
    orbits = [orbit(osc, v[2] * S[2], v[:2] * S[:2], order) for v in us]
    freqs = np.array([o.frequency for o in orbits])
    folds, pds = [], []
    for k in range(len(orbits) - 1):
        for sign, out in ((1.0, folds), (-1.0, pds)):
            da = np.linalg.det(orbits[k].monodromy - sign * np.eye(2))
            db = np.linalg.det(orbits[k + 1].monodromy - sign * np.eye(2))
            if da * db < 0:
                out.append(_locate(P, us[k], us[k + 1], sign))
    return ExactBranch(freqs, orbits, folds, pds)


def _locate(P, ua, ub, sign):
    """Frequency (Hz) where det(M - sign I) = 0 on the branch between the scaled points ua and
    ub: Brent on the chord parameter s, each point solved on the plane through
    ua + s (ub - ua) normal to the chord."""
    tau = (ub - ua) / np.linalg.norm(ub - ua)

    def point(s):
        g = ua + s * (ub - ua)
        res = P.on_plane(g, tau, tau @ g)
        if res is None:
            raise RuntimeError(f"exact branch: no orbit on the chord at s = {s}")
        return res

    def det(s):
        return np.linalg.det(point(s)[1] - sign * np.eye(2))

    s = scipy.optimize.brentq(det, 0.0, 1.0, xtol=1e-14)
    return float(point(s)[0][2] * P.S[2])


def turning_points(osc, f, z0, maxima=True):
    """x (m) at every maximum (``maxima``: v from + to -) or minimum (v from - to +) of the
    exact orbit through z0 at t = 0 over one period: bracketed on 400 samples per segment,
    then Brent on v."""
    _, _, segs, fl = period_map(osc, f, z0)
    out = []
    for (r, ta, tb, za) in segs:
        ts = np.linspace(ta, tb, 401)
        v = fl.states(r, ta, za, ts)[1]
        turn = (v[:-1] > 0) & (v[1:] <= 0) if maxima else (v[:-1] < 0) & (v[1:] >= 0)
        for i in np.flatnonzero(turn):
            t = scipy.optimize.brentq(lambda t: fl.states(r, ta, za, t)[1, 0], ts[i],
                                      ts[i + 1], xtol=1e-15, rtol=1e-15)
            out.append(float(fl.states(r, ta, za, t)[0, 0]))
    return out


def damped_newton(eqs, u, max_iter=20, tol=1e-11):
    """Solve eqs(u) = 0 (scaled unknowns) by Newton with a forward-difference Jacobian (1e-7)
    and steps capped at 0.01; asserts that the residual ends below tol. Returns u."""
    for _ in range(max_iter):
        r = eqs(u)
        J = np.array([(eqs(u + 1e-7 * e) - r) / 1e-7 for e in np.eye(len(u))]).T
        du = np.linalg.solve(J, -r)
        u = u + du * min(1.0, 0.01 / np.max(np.abs(du)))
        if np.max(np.abs(du)) < 1e-12:
            break
    assert np.max(np.abs(eqs(u))) < tol, eqs(u)
    return u
