"""Periodic solutions by (multiple) shooting on the flow of an nlbeam model.

A periodic orbit of order n (period T = n / f) is described by the states ``U[j]`` at m
segment boundaries, given as excitation phases ``b_j`` (in excitation periods, increasing,
b_0 in [0, n), the last segment ends at b_0 + n). The residual is ``R_j = phi_j(U_j) - U_{j+1}``;
its Jacobian holds the segment monodromies from the variational equations (nlbeam.flow).

Boundaries are placed where the orbit is out of contact (the Lankarani-Nikravesh law's
onset-velocity memory is then not part of the state) and moved when the orbit comes close;
the solution is reported at t = 0 by integrating from b_0.
"""
from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import warnings
from dataclasses import dataclass

import numpy as np

import nlbeam
from nlbeam.integrate import FlowMap
from nlbeam.parameters import get_parameter, with_parameter
from nlbeam._validate import choice, positive, real_array
from nlbeam.summary import Summary, field_rows
from nlbeam.solver import Solver, period_step, phase_step
from nlbeam.vocabulary import METHODS as METHOD_NAMES

from . import _flowcache
from nlbeam import _linalg as la
from ._newton import ConvergenceError, ContinuationWarning, newton
from .pathfollow import Problem


def forcing(amplitude, frequency):
    """The excitation of the periodic orbits: y = amplitude cos(2 pi frequency t) (m or N,
    Hz), phase zero at t = 0."""
    return nlbeam.Harmonic(amplitude, frequency)


#: steps per contact of periodic orbits when none are given, per method (else nlbeam's
#: default, nlbeam.solver.STEPS_PER_CONTACT: rk4 32, rk2 96). Empty: 48 for rk4 was measured
#: (multipliers' median stated error on the paper diagram's harmonic branch 2.3e-5 -> 5.4e-6
#: for 7-14 % more CPU) but not made the default: at 48 one stated error of an exact-pwl test
#: is exceeded (docs/continuation_report.md, "Default steps per contact");
#: steps_per_contact=48 asks for it.
CONTACT_STEPS = {}


@dataclass(frozen=True)
class Integrator:
    """How orbits are integrated. method: 'rk4', 'rk2' or 'adaptive' (rtol, atol).
    dt_scale: the fixed step as a fraction of nlbeam's default (1: default; 0.5: half the step).
    The number of steps per excitation period is kept fixed in steps of powers of two, so the
    discrete flow map is smooth along a branch. steps_per_contact: as in nlbeam.flow; None:
    ``CONTACT_STEPS`` for the method if it names one (set here), else nlbeam's default
    (nlbeam.solver.STEPS_PER_CONTACT: rk4 32, rk2 96). The step decisions are those of
    ``solver`` (nlbeam.solver.Solver)."""

    method: str = "rk4"
    dt_scale: float = 1.0
    steps_per_contact: float | None = None
    rtol: float = 1e-10
    atol: float = 1e-14

    def __post_init__(self):
        choice("method", self.method, METHOD_NAMES)
        positive("dt_scale", self.dt_scale)
        if self.steps_per_contact is None and self.method in CONTACT_STEPS:
            object.__setattr__(self, "steps_per_contact", CONTACT_STEPS[self.method])
        _ = self.solver  # a Solver checks steps_per_contact, rtol, atol

    @functools.cached_property
    def solver(self):
        """The Solver of these settings (its dt is chosen per flow from the frequency)."""
        return Solver(self.method, None, self.steps_per_contact, self.rtol, self.atol)

    def steps_per_period(self, model, frequency):
        """Steps per excitation period at frequency (Hz) for fixed-step methods (0: adaptive);
        Solver.steps_per_excitation_period."""
        return self.solver.steps_per_excitation_period(model, frequency, self.dt_scale)

    def refined(self, k=1):
        """This integrator with both steps halved k times: dt_scale / 2^k and steps_per_contact
        (the solver's default if None) * 2^k; for 'adaptive' rtol and atol / 32^k (its error per
        step falls like h^5), rtol not below 1e-14."""
        if k == 0:
            return self
        if self.method == "adaptive":
            return dataclasses.replace(self, rtol=max(self.rtol / 32.0 ** k, 1e-14),
                                       atol=max(self.atol / 32.0 ** k, 1e-300))
        spc = self.solver.contact_steps()
        return dataclasses.replace(self, dt_scale=self.dt_scale / 2 ** k,
                                   steps_per_contact=spc * 2 ** k)

    def flow_map(self, model, ex, steps_per_period):
        """An nlbeam FlowMap of model under the harmonic excitation ex with these settings and
        steps_per_period fixed steps per excitation period (0: adaptive), without the warning
        about few steps per contact (a Newton iterate may be far from any orbit)."""
        return FlowMap(model, ex, method=self.method,
                       dt=period_step(ex.frequency, steps_per_period),
                       steps_per_contact=self.steps_per_contact, rtol=self.rtol, atol=self.atol,
                       warn=False)

    def integrate(self, model, ex, t_end, dt, **kw):
        """nlbeam.integrate of model under ex to t_end (s) with these settings and step (or,
        adaptive, output spacing) dt (s), without the warning about few steps per contact;
        kw: x0, t0, disc0, store_every."""
        return nlbeam.integrate(model, ex, t_end, method=self.method, dt=dt,
                                steps_per_contact=self.steps_per_contact, rtol=self.rtol,
                                atol=self.atol, warn=False, **kw)


def event_elements(model):
    """Indices of the elements with a contact boundary (stops with nonzero stiffness)."""
    idx = []
    for i, el in enumerate(model.system.elements):
        if isinstance(el, nlbeam.Contact) and el.K > 0:
            idx.append(i)
        elif isinstance(el, nlbeam.PiecewiseLinearStop) and el.k > 0:
            idx.append(i)
    return idx


def clearance(model, states, y):
    """-max_e delta_e (m) of each state (rows) for base/force value(s) y: > 0 out of contact,
    +inf when the model has no contact elements."""
    states = np.atleast_2d(states)
    idx = event_elements(model)
    if not idx:
        return np.full(states.shape[0], np.inf)
    _, w, wy, gap = model.element_geometry()  # delta = w.x + wy y - gap
    N = model.n_dof
    d = la.matmul(states[:, :N], w[idx].T) + np.outer(np.atleast_1d(y), wy[idx]) - gap[idx]
    return -np.max(d, axis=1)


class ShootingProblem(Problem):
    """The periodic-orbit problem R(u, p) = 0 of one model, excitation amplitude and order.

    parameter: 'frequency' (Hz), 'amplitude' (m or N), or a model parameter as
    nlbeam.parameters names it ('e', 'K_hertz', 'gap', 'elements[1].gap', ...). ``fixed``
    holds the values of the other two of (frequency, amplitude). boundaries: excitation
    phases of the segment starts. The path follower's protocol
    (continuation.pathfollow.Problem), with its optional ``variational``, ``jacobian_u`` and
    ``settle``.
    """

    def __init__(self, model, amplitude, frequency, order, boundaries, integrator,
                 parameter="frequency", steps_per_period=None, scale_u=None, scale_p=None,
                 variational=True):
        self.base_model = model
        self.amplitude = float(amplitude)
        self.frequency = float(frequency)
        self.order = int(order)
        self.boundaries = np.asarray(boundaries, dtype=float)
        self.integrator = integrator
        self.parameter = parameter
        self.n_seg = len(self.boundaries)
        self.N2 = 2 * model.n_dof
        self.n = self.N2 * self.n_seg
        self.out = model.output_dof
        self._cache = (None, None)
        self._fm = None  # the last FlowMap (see _flowmap)
        p0 = self.value()
        if steps_per_period is None:
            m, A, f = self.setup(p0)
            steps_per_period = integrator.steps_per_period(m, f)
        self.steps_per_period = int(steps_per_period)
        self.scale_u = scale_u
        self.scale_p = float(scale_p) if scale_p is not None else max(abs(p0), 1e-300)
        self.sel_clearance = None
        # False: no variational equations (no multipliers; Jacobians by differences / secants)
        self.variational = bool(variational)

    # --- parameters ---------------------------------------------------------------------------
    def value(self):
        """The current value of the continuation parameter."""
        if self.parameter == "frequency":
            return self.frequency
        if self.parameter == "amplitude":
            return self.amplitude
        return get_parameter(self.base_model, self.parameter)

    def setup(self, p):
        """(model, amplitude, frequency) at parameter value p."""
        if self.parameter == "frequency":
            return self.base_model, self.amplitude, float(p)
        if self.parameter == "amplitude":
            return self.base_model, float(p), self.frequency
        key, m = self._cache
        if key != p:
            m = with_parameter(self.base_model, self.parameter, float(p))
            self._cache = (p, m)
        return m, self.amplitude, self.frequency

    # --- segments -----------------------------------------------------------------------------
    def forcing(self, p):
        """(model, excitation) at parameter value p (the last pair kept: a Harmonic is
        immutable, and every flow of an evaluation asks for the same one)."""
        model, A, f = self.setup(p)
        last = self.__dict__.get("_forcing")
        if last is not None and last[0] is model and last[1] == A and last[2] == f:
            return model, last[3]
        ex = forcing(A, f)
        self._forcing = (model, A, f, ex)
        return model, ex

    # --- segments -----------------------------------------------------------------------------
    def _segments(self):
        """(j, phase at its start, its length in excitation periods) of each segment (computed
        once per boundaries and order)."""
        key = (self.boundaries, self.order)
        kept = self.__dict__.get("_segs")
        if kept is None or kept[0][0] is not key[0] or kept[0][1] != key[1]:
            b = np.append(self.boundaries, self.boundaries[0] + self.order)
            kept = self._segs = (key, tuple((j, b[j], b[j + 1] - b[j])
                                            for j in range(self.n_seg)))
        return kept[1]

    def _flowmap(self, model, ex):
        """A FlowMap (nlbeam.integrate.FlowMap: nlbeam.flow without its per-call checks) of
        model and excitation ex with this problem's integrator: the last one, retargeted to
        ex when only the excitation changed."""
        fm = self._fm
        if fm is None or fm.model is not model:
            fm = self._fm = self.integrator.flow_map(model, ex, self.steps_per_period)
            return fm
        if fm.excitation == ex:
            return fm
        self._fm = fm = fm.retarget(ex)
        return fm

    def flow_phases(self, model, ex, state, phase0, dphi, *, disc0=None, monodromy=False,
                    span_step=True, newton=False):
        """The nlbeam.Flow of ``state`` (2N,) from excitation phase ``phase0`` over ``dphi``
        excitation periods of ex (a harmonic excitation), with this problem's integrator:
        steps_per_period fixed steps per period, rounded to a whole number over dphi
        (Solver's phase_step). For the adaptive method the step argument (output spacing) is
        the whole span with ``span_step`` (as the shooting segments), else the Solver's
        default. disc0: the contact state at the start (None: the start-in-contact rule).
        Raises nlbeam.IntegrationError; with ``newton`` (the flows of Newton's residual) at
        most 50 times the nominal steps + 20000, and a failed integration is a failed Newton
        step (ConvergenceError)."""
        f = ex.frequency
        dur = dphi / f
        if self.steps_per_period or span_step:
            dt = phase_step(dur, self.steps_per_period * dphi)
        else:
            dt = self.integrator.solver.default_dt(model, ex)
        fm = self._flowmap(model, ex)
        max_steps = int(50 * dur / dt) + 20000 if newton else 100_000_000
        key = _flowcache.key(fm, state, phase0 / f, dur, disc0, dt, max_steps)
        fl = _flowcache.get(key, model, monodromy)
        if fl is not None:  # computed before: the same flow bit for bit
            return fl
        if not newton:
            fl = fm(state, phase0 / f, dur, monodromy=monodromy, disc0=disc0, dt=dt)
            _flowcache.put(key, model, monodromy, fl)
            return fl
        try:
            fl = fm(state, phase0 / f, dur, monodromy=monodromy, disc0=disc0, dt=dt,
                    max_steps=max_steps)
            _flowcache.put(key, model, monodromy, fl)
            return fl
        except (nlbeam.IntegrationError, ValueError) as exc:
            # an iterate far from any orbit (e.g. a huge penetration, or a parameter so far off
            # that the fixed step is beyond the method's stability limit): a failed Newton step
            raise ConvergenceError(f"shooting: integration failed ({exc}); try a smaller step, "
                                   "a better guess, or for a strongly unstable orbit multiple "
                                   "shooting (segments=8 or more, guess=states at the "
                                   "boundaries)") from None

    def _map(self, U, p, mono):
        """Flows of all segments at parameter p: (ends (m, 2N), [monodromies], xmax).
        mono: the segment monodromies from the variational equations, or (for a problem with
        ``variational = False``) dR/du by forward differences; [] without."""
        try:
            model, ex = self.forcing(p)
        except ValueError as exc:  # the predictor left the parameter's domain
            raise ConvergenceError(f"shooting: {exc}") from None
        ends = np.empty_like(U)
        Ms = []
        xm = 0.0
        n_imp = 0
        var = mono and self.variational
        for j, phase0, dphi in self._segments():
            fl = self.flow_phases(model, ex, U[j], phase0, dphi, monodromy=var, newton=True)
            ends[j] = fl.state
            n_imp += fl.n_impacts
            xm = max(xm, float(fl.xmax[self.out]))
            if var:
                M = fl.monodromy
                if fl.dstate_dvminus0 is not None:
                    # started inside a contact: the memory was taken as the penetration rate
                    # at the start (the solver's rule), a function of the state: chain it in
                    M = M + la.matmul(fl.dstate_dvminus0, Solver.start_contact_derivative(model))
                Ms.append(M)
            elif mono:
                # forward differences of the segment's flow (relative step 1e-7 of the scale)
                sc = self.scale_u if self.scale_u is not None else self.make_scale(U.ravel(), p)
                M = np.empty((self.N2, self.N2))
                for k in range(self.N2):
                    h = 1e-7 * sc[j * self.N2 + k]
                    s1 = U[j].copy()
                    s1[k] += h
                    M[:, k] = (self.flow_phases(model, ex, s1, phase0, dphi,
                                                newton=True).state - fl.state) / h
                Ms.append(M)
        self.last_impacts = n_imp
        if var:
            Ms = SegmentMonodromies(Ms, U.copy(), p)
        return ends, Ms, xm

    def piece_monodromies(self, U, p, pieces):
        """The transition matrices (2N, 2N) of the orbit through the segment starts U (m, 2N)
        at parameter p over (at most) ``pieces`` sub-intervals of whole steps of each
        segment, in order; their product is the monodromy up to round-off. Each piece is
        flowed from the end of the one before with identity sensitivities. A piece never ends
        inside a contact (the steps there depend on where the contact began): one that would
        is flowed again to the next cut. The first piece of a segment that starts in contact
        chains the start-in-contact rule as ``_map`` does. The adaptive method's pieces are
        equal spans."""
        model, ex = self.forcing(p)
        f = ex.frequency
        G = Solver.start_contact_derivative(model)
        fm = self._flowmap(model, ex)
        out = []
        for j, phase0, dphi in self._segments():
            dur = dphi / f
            if self.steps_per_period:
                dt = phase_step(dur, self.steps_per_period * dphi)
                n = max(1, int(round(dur / dt)))
            else:  # adaptive: the output spacing is the piece
                n = pieces
                dt = dur / n
            cuts = np.unique(np.rint(np.linspace(0, n, min(pieces, n) + 1)).astype(int))
            s, disc, a = U[j], None, 0
            for b in cuts[1:]:
                fl = fm(s, phase0 / f + dur * a / n, dur * (b - a) / n, monodromy=True,
                        disc0=disc, dt=dt, max_steps=int(50 * (b - a)) + 20000)
                if b < n and np.any(fl.disc[:, 0] != 0):
                    continue  # ends inside a contact: flow from a to the next cut instead
                M = fl.monodromy
                if fl.dstate_dvminus0 is not None:  # only a segment's start: see _map
                    M = M + la.matmul(fl.dstate_dvminus0, G)
                out.append(M)
                s, disc, a = fl.state, fl.disc, b
        return out

    def evaluate(self, u, p, jac=True, jac_p=True):
        """Residual R (n,) of u (n,) at parameter p; with jac the Jacobian dR/du (n, n) and the
        segment monodromies (from the variational equations; by forward differences for a
        problem with ``variational = False``, whose evaluations then carry no monodromies:
        ``Ms`` is []); with jac_p dR/dp (n,) by a forward difference (it only steers Newton
        and the predictor; the solution does not depend on it)."""
        U = np.asarray(u, dtype=float).reshape(self.n_seg, self.N2)
        ends, Ms, xm = self._map(U, p, jac)
        n_imp = self.last_impacts
        R = (ends - (U if self.n_seg == 1 else np.roll(U, -1, axis=0))).ravel()
        Ju = self._assemble(Ms) if jac else None
        Jp = self._jac_p(U, p, ends) if jac_p else None
        return Evaluation(R, Ju, Jp, Ms if self.variational else [], xm, n_imp)

    def _assemble(self, Ms):
        Ju = np.zeros((self.n, self.n))
        k = self.N2
        eye = self.__dict__.get("_eye")
        if eye is None or eye.shape[0] != k:
            eye = self._eye = np.eye(k)  # (read only here)
        for j in range(self.n_seg):
            Ju[j * k:(j + 1) * k, j * k:(j + 1) * k] += Ms[j]
            jn = (j + 1) % self.n_seg
            Ju[j * k:(j + 1) * k, jn * k:(jn + 1) * k] -= eye
        return Ju

    def _jac_p(self, U, p, ends):
        h = 1e-7 * self.scale_p
        e_hi = self._map(U, p + h, False)[0]
        return ((e_hi - ends) / h).ravel()

    def jacobian_u(self, u, p, ev=None):
        """dR/du (n, n) at (u, p) by forward differences (no variational equations)."""
        U = np.asarray(u, dtype=float).reshape(self.n_seg, self.N2)
        var, self.variational = self.variational, False
        try:
            return self._assemble(self._map(U, p, True)[1])
        finally:
            self.variational = var

    def jacobian_p(self, u, p, ev=None):
        """dR/dp (n,) at (u, p) by a forward difference (ev: the evaluation at (u, p), if any)."""
        U = np.asarray(u, dtype=float).reshape(self.n_seg, self.N2)
        if ev is None:
            ends = self._map(U, p, False)[0]
        else:
            ends = ev.R.reshape(self.n_seg, self.N2) + (U if self.n_seg == 1
                                                         else np.roll(U, -1, axis=0))
        return self._jac_p(U, p, ends)

    # --- derived quantities -----------------------------------------------------------------
    def monodromy(self, Ms):
        M = np.eye(self.N2)
        for Mj in Ms:
            M = la.matmul(Mj, M)
        return M

    def multipliers(self, Ms):
        """Floquet multipliers, largest modulus first; in product form over the segments, or
        over sub-intervals of them (``piece_monodromies``: when Ms came from ``evaluate``),
        when their spread would cost the small ones their digits (continuation._floquet)."""
        from ._floquet import multipliers

        start = getattr(Ms, "start", None)
        if start is None:
            return multipliers(Ms, self.monodromy(Ms))
        return multipliers(Ms, self.monodromy(Ms),
                           subdivide=functools.partial(self.piece_monodromies, *start))

    def boundary_clearance(self, u, p):
        model, ex = self.forcing(p)
        U = np.asarray(u).reshape(self.n_seg, self.N2)
        y = ex.evaluate(self.boundaries / ex.frequency)[0]
        return clearance(model, U, y)

    def make_scale(self, u, p):
        """Scales of the unknowns: an amplitude a = max sqrt(x^2 + (v / w)^2) over the boundaries
        (w = 2 pi f / order) for displacements, a w for velocities."""
        f = self.setup(p)[2]
        w = 2 * np.pi * f / self.order
        U = np.asarray(u).reshape(self.n_seg, self.N2)
        N = self.N2 // 2
        a = max(float(np.sqrt(U[:, :N] ** 2 + (U[:, N:] / w) ** 2).max()), 1e-300)
        return np.tile(np.r_[np.full(N, a), np.full(N, a * w)], self.n_seg)

    def solve(self, u0, p, tol=1e-10, max_iter=12):
        """Newton at fixed p (quasi-Newton for a problem without variational equations).
        Returns (u, evaluation, residual, iterations)."""
        if self.scale_u is None:
            self.scale_u = self.make_scale(u0, p)
        w = self.scale_u
        last = {}

        def fun(z):
            ev = last["ev"] = self.evaluate(z * w, p, jac=True, jac_p=False)
            return ev.R / w, ev.Ju * w[None, :] / w[:, None]

        def residual(z):
            ev = last["ev"] = self.evaluate(z * w, p, jac=False, jac_p=False)
            return ev.R / w

        z, res, it = newton(fun, np.asarray(u0) / w, tol=tol, max_iter=max_iter,
                            what=f"shooting (order {self.order}, {self.parameter} = {p:.9g})",
                            residual=None if self.variational else residual)
        return z * w, last["ev"], res, it

    def minimal_order(self, u, p, tol=1e-6):
        """The smallest k dividing the order such that the orbit u repeats after k excitation
        periods (to ``tol`` in units of the scales): the order it really has."""
        n = self.order
        model, ex = self.forcing(p)
        U = np.asarray(u).reshape(self.n_seg, self.N2)
        w = self.scale_u[:self.N2] if self.scale_u is not None else \
            self.make_scale(u, p)[:self.N2]
        for k in range(1, n):
            if n % k:
                continue
            fl = self.flow_phases(model, ex, U[0], self.boundaries[0], k, span_step=False)
            if np.max(np.abs(fl.state - U[0]) / w) < tol:
                return k
        return n

    # --- boundaries ---------------------------------------------------------------------------
    def trajectory(self, u, p, n_samples=None, disc0=None):
        """Integrate one period from the first boundary, storing samples (nlbeam.Trajectory).
        disc0: the contact state there if the boundary lies inside a contact (the
        Lankarani-Nikravesh memory; None: nlbeam's start-in-contact rule)."""
        model, ex = self.forcing(p)
        f = ex.frequency
        U = np.asarray(u).reshape(self.n_seg, self.N2)
        t0 = self.boundaries[0] / f
        T = self.order / f
        if self.steps_per_period:
            dt = period_step(f, self.steps_per_period)
        else:  # adaptive: the output spacing
            dt = T / (n_samples or 400 * self.order)
        return self.integrator.integrate(model, ex, t0 + T, dt, x0=U[0], t0=t0, disc0=disc0)

    def rephased(self, u, p, n_seg=None, steps_per_period=None, disc0=None):
        """A problem with boundaries moved into free flight (as far from the stops as possible,
        spread over the period), and its u from an integration of the orbit (disc0: the
        contact state at the first boundary, if it lies inside a contact)."""
        n_seg = n_seg or self.n_seg
        spp = self.steps_per_period if steps_per_period is None else steps_per_period
        model, A, f = self.setup(p)
        tr = self.trajectory(u, p, disc0=disc0)
        t, S = tr.t[:-1], np.hstack([tr.x, tr.v])[:-1]
        y = tr.excitation.evaluate(t)[0]
        c = clearance(model, S, y)
        T = self.order / f
        t0 = t[0]
        if not np.isfinite(c[0]):
            idx = [int(round(j * len(t) / n_seg)) for j in range(n_seg)]
        else:
            idx = []
            # window j covers [t0 + j T/m, t0 + (j+1) T/m): best clearance inside each
            k0 = int(np.argmax(c))
            shift = t[k0] - t0
            for j in range(n_seg):
                lo = t0 + shift + (j - 0.5) * T / n_seg
                hi = lo + T / n_seg
                tt = (t - lo) % T + lo  # periodic position
                mask = (tt >= lo) & (tt < hi)
                cand = np.nonzero(mask)[0]
                k = cand[np.argmax(c[cand])] if cand.size else k0
                idx.append(int(k))
            idx = sorted(set(idx), key=lambda k: (t[k] - t[k0]) % T)
        ph = t[idx] * f % self.order
        order = np.argsort(ph)
        ph = ph[order]
        idx = [idx[i] for i in order]
        new = ShootingProblem(self.base_model, A if self.parameter == "amplitude" else
                              self.amplitude, f if self.parameter == "frequency" else
                              self.frequency, self.order, ph, self.integrator,
                              parameter=self.parameter, steps_per_period=spp,
                              scale_p=self.scale_p, variational=self.variational)
        unew = S[idx].ravel()
        new.scale_u = new.make_scale(unew, p)
        new.sel_clearance = c[idx] if np.isfinite(c[0]) else None
        return new, unew

    def settle(self, u, p, p_new, efolds=8.0):
        """Boundary states at parameter p_new of the attractor reached by integrating from the
        orbit u (at p) for about ``efolds`` decay times (frequency continuation only)."""
        if self.parameter != "frequency":
            raise ConvergenceError("settle: only for frequency continuation")
        model, A, f = self.setup(p)
        s0, _ = self.state_at_zero(u, p)
        try:
            s = steady_state(model, A, p_new, x0=s0, efolds=efolds, min_periods=10,
                             integrator=self.integrator)
        except nlbeam.IntegrationError as exc:
            raise ConvergenceError(f"settle: integration failed ({exc})") from None
        tmp = ShootingProblem(self.base_model, A, p_new, self.order, [0.0], self.integrator,
                              steps_per_period=self.steps_per_period, variational=False)
        return self.transfer(tmp, s, p_new)

    def with_segments(self, u, p, n_seg):
        """(problem, u): the orbit u at p with n_seg shooting segments (Problem protocol)."""
        return self.rephased(u, p, n_seg=n_seg)

    def signature(self, u, p):
        """The state at excitation phase zero of the orbit u (Problem protocol)."""
        return self.state_at_zero(u, p)[0]

    def needs_rephase(self, u, p):
        if self.sel_clearance is None:
            return False
        c = self.boundary_clearance(u, p)
        return bool(np.any(c < 0.3 * self.sel_clearance))

    def adapt(self, u, p):
        """None, or (problem, u) with boundaries moved out of contact / the step level changed /
        the scales renewed, when the orbit at p asks for it."""
        model, A, f = self.setup(p)
        spp = self.integrator.steps_per_period(model, f)
        ratio = self.make_scale(u, p) / self.scale_u
        if (spp != self.steps_per_period or self.needs_rephase(u, p)
                or np.any(ratio > 3) or np.any(ratio < 1 / 3)):
            return self.rephased(u, p, steps_per_period=spp)
        return None

    def transfer(self, old, u_old, p):
        """The states at this problem's boundaries of the orbit u_old of problem ``old`` at p."""
        model, ex = old.forcing(p)
        U = np.asarray(u_old).reshape(old.n_seg, old.N2)
        b = old.boundaries
        out = np.empty((self.n_seg, self.N2))
        for i, phi in enumerate(self.boundaries):
            ph = b[0] + (phi - b[0]) % old.order
            j = int(np.searchsorted(b, ph, side="right") - 1)
            dphi = ph - b[j]
            if dphi < 1e-12:
                out[i] = U[j]
                continue
            out[i] = old.flow_phases(model, ex, U[j], b[j], dphi).state
        return out.ravel()

    def state_at_zero(self, u, p):
        """(state, disc) at t = 0 (excitation phase zero) of the orbit u."""
        model, ex = self.forcing(p)
        U = np.asarray(u).reshape(self.n_seg, self.N2)
        b = np.append(self.boundaries, self.boundaries[0] + self.order)
        target = float(self.order)
        for j in range(self.n_seg):
            if abs(b[j] - target) < 1e-13 * self.order or abs(b[j]) < 1e-13 * self.order:
                return U[j].copy(), None
            if b[j] <= target < b[j + 1]:
                fl = self.flow_phases(model, ex, U[j], b[j], target - b[j])
                return fl.state, fl.disc
        return U[0].copy(), None


class SegmentMonodromies(list):
    """The segment monodromies [M_1, ..., M_m] of one evaluation, with the orbit they were
    computed on: ``start`` = (U (m, 2N), p), the segment starts and the parameter (so that
    the multipliers can be computed again over sub-intervals: Shooting.piece_monodromies)."""

    def __init__(self, Ms, U, p):
        super().__init__(Ms)
        self.start = (U, p)


@dataclass
class Evaluation:
    R: np.ndarray
    Ju: np.ndarray | None
    Jp: np.ndarray | None
    Ms: list
    xmax: float
    n_impacts: int = 0  # contact onsets over the period
    B: np.ndarray | None = None  # scaled [dR/du | dR/dp] of the quasi-Newton corrector
    C: np.ndarray | None = None  # its secant correction (continuation.pathfollow.Tracer.correct)
    lazy_p: object = None  # (start, its evaluation) of a corrector at fixed p (dR/dp left out)


@dataclass(repr=False)
class PeriodicSolution(Summary):
    """A periodic solution of order n (period n / f).

    state0 (2N,): state at t = 0 (excitation phase zero); disc0: its contact state (None if out
    of contact); period (s); frequency (Hz); amplitude (m, or N for force excitation); xmax (m):
    max |x| of the output DOF over the period, of the continuous orbit (refined between steps);
    multipliers (2N,) complex, sorted by modulus, largest first (None if not asked);
    stable: all |multiplier| < 1; residual: max-norm of the scaled shooting residual;
    iterations: Newton iterations; boundaries: the excitation phases (periods) of the shooting
    segments; states (m, 2N): the states there; monodromy (2N, 2N) at the first boundary;
    minimal_order: the number of excitation periods after which the orbit repeats (< order
    when Newton found an orbit of lower order, e.g. a period-1 orbit for order 2).
    Accuracy (continuation.accuracy): xmax_error (m) and multipliers_error ((2N,), absolute,
    per multiplier; None without stability) estimate the error of xmax and of the multipliers
    due to the integration: twice their change when the orbit is solved again with both steps
    halved (a bound for a method of order >= 1; None when not estimated, error=False);
    integrator: the Integrator the orbit was computed with."""

    state0: np.ndarray
    disc0: np.ndarray | None
    order: int
    frequency: float
    amplitude: float
    period: float
    xmax: float
    multipliers: np.ndarray | None
    stable: bool | None
    residual: float
    iterations: int
    boundaries: np.ndarray
    states: np.ndarray
    monodromy: np.ndarray | None
    minimal_order: int = 1
    xmax_error: float | None = None
    multipliers_error: np.ndarray | None = None
    integrator: Integrator | None = None

    def _summary_rows(self):
        return field_rows(self, skip=("integrator",)) + [
            ("integrator", "None" if self.integrator is None
             else type(self.integrator).__name__)]


def decay_rate(model):
    """Slowest decay rate (1/s) of the linear structure (without the nonlinear elements)."""
    sysm = model.system
    N = model.n_dof
    Minv = la.inv(sysm.M)
    A = np.block([[np.zeros((N, N)), np.eye(N)],
                  [-la.matmul(Minv, sysm.K), -la.matmul(Minv, sysm.C)]])
    lam = la.eigvals(A)
    return max(float(np.min(-lam.real)), 1e-6)


def steady_state(model, amplitude, frequency, *, x0=None, efolds=8.0, min_periods=50,
                 integrator=Integrator(), max_periods=20000):
    """Integrate from x0 (default rest) at t = 0 over a whole number of excitation periods
    (about ``efolds`` decay times of the linear structure). Returns the state at the end, at
    excitation phase zero."""
    n = int(min(max_periods, max(min_periods, math.ceil(efolds / decay_rate(model) * frequency))))
    # adaptive (0 steps per period): the output spacing is one period
    dt = period_step(frequency, integrator.steps_per_period(model, frequency) or 1)
    tr = integrator.integrate(model, forcing(amplitude, frequency), n / frequency, dt, x0=x0,
                              store_every=0)
    return tr.state_end


def _problem_from_state(model, amplitude, frequency, order, state0, segments, integrator,
                        variational=True, disc0=None):
    """A shooting problem with boundaries in free flight, from a state at t = 0 (and its
    contact state disc0 when t = 0 lies inside a contact: with the Lankarani-Nikravesh law the
    onset velocity is memory that the state alone does not hold)."""
    base = ShootingProblem(model, amplitude, frequency, order, [0.0], integrator,
                           variational=variational)
    return base.rephased(np.asarray(state0, dtype=float), frequency, n_seg=segments,
                         disc0=disc0)


def periodic_solution(model, amplitude, frequency, order=1, guess=None, *, segments=1,
                      integrator=None, tol=1e-10, max_iter=15, stability=True, error=True,
                      accuracy=None, **integrator_kw):
    """Periodic solution of order n (period n / frequency) by (multiple) shooting.

    amplitude: m (base excitation) or N (force); frequency: Hz. guess: state at t = 0 (2N,) or
    a PeriodicSolution (boundaries then placed from an integration of one period from it), or
    the states at the segment boundaries, (segments, 2N) at excitation phases j order /
    segments (for strongly unstable orbits, which an integration from a guess leaves); without
    a guess the model is integrated to a steady state first.
    segments: shooting segments per period (multiple shooting). Newton's Jacobian holds the
    monodromies from the variational equations. stability=False integrates no variational
    equations (Newton's Jacobian by forward differences once, then Broyden updates): no
    multipliers, ``stable`` and ``monodromy`` are None.
    Integrator options (method, dt_scale, steps_per_contact, rtol, atol) may be passed as
    keywords or as an ``Integrator``. Raises ConvergenceError when Newton does not converge.
    For order > 1 the orbit found may repeat after fewer excitation periods (a period-1 orbit
    solves the period-2 problem too): ``minimal_order`` says, and a ContinuationWarning.
    error: estimate the integration's error of xmax and of the multipliers (``xmax_error``,
    ``multipliers_error``: one more solve with both steps halved, about twice the cost).
    accuracy: None (the integrator as given), or 'default' (6 significant digits), 'high' (8)
    or a number of digits: the step is halved (up to 4 times) until the estimated error of xmax
    is at most 10^-digits |xmax| and that of the multipliers 10^-(digits - 1); the solution is
    returned at the first integrator that meets both (``integrator`` says which), with a
    ContinuationWarning if none does.
    """
    from . import _arguments as _args

    _args.check_integrator("periodic_solution", integrator, integrator_kw,
                           inspect.signature(periodic_solution).parameters)
    _args.check_periodic_solution(model, amplitude, frequency, order, segments, tol, max_iter,
                                  stability, error)
    _args.check_accuracy(accuracy)
    if guess is not None and not isinstance(guess, PeriodicSolution):
        real_array("guess", guess)
    if integrator is None:
        integrator = Integrator(**integrator_kw)
    if accuracy is None:
        return _periodic_solution(model, amplitude, frequency, order, guess, segments,
                                  integrator, tol, max_iter, stability, error)
    from .accuracy import multiplier_target, target_digits

    digits = target_digits(accuracy)
    sol = None
    for k in range(5):
        sol = _periodic_solution(model, amplitude, frequency, order,
                                 guess if sol is None else sol, segments, integrator.refined(k),
                                 tol, max_iter, stability, True)
        if sol.xmax_error is not None and sol.xmax_error <= 10.0 ** -digits * abs(sol.xmax) \
                and (sol.multipliers_error is None
                     or np.max(sol.multipliers_error / np.maximum(1.0, np.abs(sol.multipliers)))
                     <= multiplier_target(digits)):
            return sol
    warnings.warn(f"periodic_solution: the accuracy asked for ({digits:g} digits) is not met at "
                  f"{frequency:.9g} Hz with the step halved 4 times (xmax error "
                  f"{sol.xmax_error}, multipliers error "
                  f"{None if sol.multipliers_error is None else np.max(sol.multipliers_error)})",
                  ContinuationWarning, stacklevel=2)
    return sol


def _periodic_solution(model, amplitude, frequency, order, guess, segments, integrator, tol,
                       max_iter, stability, error):
    if not (math.isfinite(frequency) and frequency > 0):
        raise ValueError(f"frequency: must be finite and > 0 Hz, got {frequency!r}")
    if int(order) != order or order < 1:
        raise ValueError(f"order: must be an integer >= 1, got {order!r}")
    if int(segments) != segments or segments < 1:
        raise ValueError(f"segments: must be an integer >= 1, got {segments!r}")
    if guess is not None and np.ndim(guess) == 2:
        # states at the segment boundaries (equally spaced phases): no integration from a
        # guess, which for a strongly unstable orbit would run away
        U = np.asarray(guess, dtype=float)
        if U.shape != (segments, 2 * model.n_dof):
            raise ValueError(f"guess: states at the boundaries must have shape ({segments}, "
                             f"{2 * model.n_dof}), got {U.shape}")
        prob = ShootingProblem(model, amplitude, frequency, order,
                               np.arange(segments) * order / segments, integrator,
                               variational=stability)
        prob.scale_u = prob.make_scale(U.ravel(), frequency)
        sol = solve_problem(prob, U.ravel(), frequency, tol=tol, max_iter=max_iter,
                            stability=stability, error=error)
        return _check_order(sol, frequency)
    d0 = None
    if guess is None:
        s0 = steady_state(model, amplitude, frequency, integrator=integrator)
    elif isinstance(guess, PeriodicSolution):
        s0, d0 = guess.state0, guess.disc0
    else:
        s0 = np.asarray(guess, dtype=float).ravel()
        if s0.shape != (2 * model.n_dof,):
            raise ValueError(f"guess: must be a state of length {2 * model.n_dof} or a "
                             "PeriodicSolution")
    prob, u0 = _problem_from_state(model, amplitude, frequency, order, s0, segments, integrator,
                                   variational=stability, disc0=d0)
    sol = solve_problem(prob, u0, frequency if prob.parameter == "frequency" else prob.value(),
                        tol=tol, max_iter=max_iter, stability=stability, error=error)
    return _check_order(sol, frequency)


def _check_order(sol, frequency):
    if sol.minimal_order != sol.order:
        warnings.warn(
            f"periodic_solution: asked for order {sol.order} at {frequency:.9g} Hz, but the orbit "
            f"found repeats after {sol.minimal_order} excitation period(s) (its minimal_order): "
            f"it is an order-{sol.minimal_order} orbit. For a true order-{sol.order} orbit give "
            "a guess on one (a branch point of that order, or a state from brute-force "
            "integration where it is the attractor)", ContinuationWarning, stacklevel=3)
    return sol


def solve_problem(prob, u0, p, *, tol=1e-10, max_iter=15, stability=True, error=False,
                  _rephased=0):
    """Newton on a ShootingProblem at fixed p; moves boundaries out of contact if needed.
    error: attach the error estimate (see make_solution)."""
    u, ev, res, it = prob.solve(u0, p, tol=tol, max_iter=max_iter)
    if prob.needs_rephase(u, p) or np.any(prob.boundary_clearance(u, p) <= 0):
        if _rephased >= 2:
            raise ConvergenceError("shooting: the segment boundaries keep falling inside a "
                                   "contact; try more segments or a better guess")
        prob2, u2 = prob.rephased(u, p)
        return solve_problem(prob2, u2, p, tol=tol, max_iter=max_iter, stability=stability,
                             error=error, _rephased=_rephased + 1)
    return make_solution(prob, u, p, ev, res, it, stability, error)


def make_solution(prob, u, p, ev, res, it, stability=True, error=False):
    """The PeriodicSolution of the converged orbit u of prob at p (ev: its evaluation); with
    ``error`` its error estimate (continuation.accuracy.orbit_error: one more solve with both
    steps halved; a refined solve that fails warns and leaves the estimate None)."""
    model, A, f = prob.setup(p)
    s0, d0 = prob.state_at_zero(u, p)
    mu = prob.multipliers(ev.Ms) if (stability and ev.Ms) else None
    xerr = mu_err = None
    if error:
        from .accuracy import orbit_error  # the estimator builds on this module

        try:
            oe = orbit_error(prob, u, p, ev.xmax, mu)
            xerr, mu_err = oe.xmax, oe.multipliers
        except ConvergenceError as exc:
            warnings.warn(f"periodic_solution: no error estimate at {f:.9g} Hz: the orbit "
                          f"did not converge with both steps halved ({exc}); the solution "
                          "may lie next to a fold or be resolved too coarsely: try dt_scale=0.5",
                          ContinuationWarning, stacklevel=3)
    return PeriodicSolution(
        state0=s0, disc0=d0, order=prob.order, frequency=f, amplitude=A, period=prob.order / f,
        xmax=ev.xmax, multipliers=mu, stable=None if mu is None else bool(np.abs(mu[0]) < 1.0),
        residual=float(res), iterations=int(it), boundaries=prob.boundaries.copy(),
        states=np.asarray(u).reshape(prob.n_seg, prob.N2).copy(),
        monodromy=prob.monodromy(ev.Ms) if ev.Ms else None,
        minimal_order=prob.minimal_order(u, p) if prob.order > 1 else 1,
        xmax_error=xerr, multipliers_error=mu_err, integrator=prob.integrator)
