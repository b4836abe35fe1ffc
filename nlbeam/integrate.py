"""Time integration with exact contact events: ``integrate`` (time histories) and ``flow``
(the end state of one interval, optionally with its monodromy matrix)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _kernels as _k
from ._validate import (ArgumentTypeError, check_count, check_memory, finite, flag, integer,
                        positive, real_array)
from .excitation import Excitation, Harmonic
from .solver import (METHODS, MIN_STEPS_PER_CONTACT, Solver, warn_few_contact_steps,
                     warn_stiffened)
from .summary import Summary

__all__ = ["integrate", "flow", "FlowMap", "Trajectory", "Flow", "IntegrationError",
           "default_dt", "METHODS", "MIN_STEPS_PER_CONTACT", "compile_kernels"]

# RK4 steps where nothing happens run in the kernels' lean loop (nlbeam/_kernels/routine.py),
# with the same results bit for bit; tests and benchmarks set this False to time and compare
# the general loop alone
ROUTINE_STEPS = True


class IntegrationError(RuntimeError):
    """The integrator could not complete; the message says what to change."""


def _status_message(status, t, method):
    if status == _k.ERR_EXCITATION_RANGE:
        return (f"the excitation is not defined at t = {t:.9g} s: the time span must lie inside "
                "the span of the sampled excitation (t0, t_end)")
    if status == _k.ERR_NONFINITE:
        return (f"the state became non-finite near t = {t:.9g} s with method={method!r}: "
                "reduce dt (or raise steps_per_contact), or use method='adaptive'")
    if status == _k.ERR_EVENT:
        return (f"a contact boundary could not be located near t = {t:.9g} s: reduce dt")
    if status == _k.ERR_MAX_STEPS:
        return (f"max_steps reached at t = {t:.9g} s: raise max_steps, loosen rtol, or "
                "integrate a shorter span")
    if status == _k.ERR_STEP_UNDERFLOW:
        return (f"the adaptive step fell below round-off at t = {t:.9g} s: loosen rtol/atol")
    return f"integration failed with status {status} at t = {t:.9g} s"


def default_dt(model, excitation, method="rk4"):
    """Default step (s): a fixed fraction of the shortest period among the excitation's highest
    frequency and the linear structure's highest natural frequency (for 'adaptive', the spacing
    of the output samples). Solver.default_dt."""
    return Solver(method).default_dt(model, excitation)


@dataclass(repr=False)
class Trajectory(Summary):
    """A time history on a uniform grid.

    t (n,) s; x, v (n, N) m and m/s; delta (n, n_elements) m, penetration (> 0 in contact);
    force (n, n_elements) N, element forces (>= 0 push out of the stop); n_impacts: contact
    onsets; state_end (2N,), disc_end (n_elements, 2) [in contact, delta'_minus] at t_end.
    events (n, 4): [t (s), element, 1 onset / 0 end, delta' (m/s)] of each contact event (the
    first ``event_log``); max_landing_residual: largest |delta| (m) at a located boundary.
    xmax (N,): max |x_i| over the run, refined between steps on the quintic dense output.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    delta: np.ndarray
    force: np.ndarray
    n_impacts: int
    state_end: np.ndarray
    disc_end: np.ndarray
    t_end: float
    method: str
    dt: float
    steps_per_contact: float
    n_steps: int
    n_rejected: int
    n_rhs: int
    min_steps_per_contact: int
    excitation: Excitation
    xmax: np.ndarray | None = None
    events: np.ndarray | None = None
    n_events: int = 0
    max_landing_residual: float = 0.0

    @property
    def y(self):
        """Excitation y at the samples (m for base excitation, N for force)."""
        return self.excitation.evaluate(self.t)[0]

    @property
    def yd(self):
        return self.excitation.evaluate(self.t)[1]


@dataclass(repr=False)
class Flow(Summary):
    """End of one interval: state (2N,), disc (n_elements, 2), xmax (N,) max |x_i| over the
    interval (refined between steps on the quintic dense output), n_impacts, and with
    ``monodromy=True`` the matrix d state(t0+T) / d state(t0) (2N, 2N) from the variational
    equations, plus the sensitivities through the Lankarani-Nikravesh onset velocities."""

    state: np.ndarray
    disc: np.ndarray
    xmax: np.ndarray
    n_impacts: int
    monodromy: np.ndarray | None
    dstate_dvminus0: np.ndarray | None
    dvminus_dstate0: np.ndarray | None
    dvminus_dvminus0: np.ndarray | None
    n_steps: int
    n_rhs: int
    min_steps_per_contact: int = -1


def _check_span(span, t0, t_end):
    """Raise unless [t0, t_end] (s) lies inside the excitation's span (lo, hi) (s)."""
    lo, hi = span
    tol = 1e-9 * max(abs(t0), abs(t_end), 1.0)
    if t0 < lo - tol or t_end > hi + tol:
        raise ValueError(f"t_end: the span [{t0}, {t_end}] s must lie inside the excitation's "
                         f"span [{lo}, {hi}] s")


def _check_model(model, excitation):
    if not hasattr(model, "kernel_arrays"):
        raise ArgumentTypeError(f"model: must be an nlbeam model (BeamImpact, Duffing, System, "
                                f"...), got {type(model).__name__}")
    if not isinstance(excitation, Excitation):
        raise ArgumentTypeError(f"excitation: must be an nlbeam.Excitation (Harmonic, Sampled, "
                                f"...), got {type(excitation).__name__}")


def _check_steps(where, duration, dt, method, max_steps):
    """Refuse a fixed-step span of duration (s) at step dt (s) longer than max_steps steps
    before any work starts (the adaptive method's steps are not known in advance: its kernel
    stops at max_steps)."""
    if method != "adaptive":
        check_count(f"{where}: steps of dt = {dt:.4g} s over {duration:.6g} s", duration / dt,
                    max_steps, "give a larger dt (or dt=None), a shorter span, or raise "
                    "max_steps")


def _check_disc(model, disc0, name="disc0"):
    """The contact state (n_elements, 2): [in contact 0/1, delta'_minus >= 0 (m/s)]."""
    ne = model.n_elements
    disc = real_array(name, disc0, shape=(ne, 2)) if np.ndim(disc0) == 2 else \
        real_array(name, disc0, shape=(2 * ne,)).reshape(ne, 2)
    if np.any((disc[:, 0] != 0) & (disc[:, 0] != 1)) or np.any(disc[:, 1] < 0):
        raise ValueError(f"{name}: rows must be [in contact 0 or 1, onset rate >= 0 m/s], got "
                         f"{disc.tolist()}")
    return np.array(disc, dtype=float)


def _prepare(model, excitation, solver, t0, t_end):
    """Check the arguments of one integration from t0 to t_end (s) with ``solver``; returns
    (dt (s), steps per contact)."""
    _check_model(model, excitation)
    t0 = finite("t0", t0, unit="s")
    t_end = finite("t_end", t_end, unit="s")
    if not t_end > t0:
        raise ValueError(f"t_end: must be > t0 = {t0!r} s, got {t_end!r}")
    dt = solver.step(model, excitation)
    _check_span(excitation.time_span(), t0, t_end)
    return dt, solver.contact_steps()


def _state(model, state, name):
    """The initial state as a float array (2N,), checked (name: the argument's name)."""
    N = model.n_dof
    if state is None:
        return np.zeros(2 * N)
    if not (isinstance(state, np.ndarray) and state.dtype.kind == "f"):  # the fast path
        state = real_array(name, state, finite_values=False)
    s0 = np.array(state, dtype=float).ravel()
    if s0.shape != (2 * N,) or not np.all(np.isfinite(s0)):
        raise ValueError(f"{name}: must be a finite state [x_1..x_N, v_1..v_N] of length {2 * N}")
    return s0


def _initial(model, x0, disc0, t0, excitation):
    """(state (2N,), contact state (n_elements, 2)) at t0: disc0, or the solver's
    start-in-contact rule (Solver.start_contact)."""
    s0 = _state(model, x0, "x0")
    if disc0 is None:
        y, yd = excitation.evaluate([t0])
        disc = Solver.start_contact(model.element_geometry(), s0, y[0], yd[0],
                                    Solver.event_elements(model))
    else:
        disc = _check_disc(model, disc0)
    return s0, disc


def _run(model, excitation, t0, t_end, method, dt, spc, rtol, atol, max_steps, s0, disc,
         events, want_var, P0, dvm0, track_xmax, store_every, graded=True, event_log=0,
         warn=True):
    sysa = model.kernel_arrays()
    xc, xp, xtab = excitation.kernel_args()
    N = model.n_dof
    ne = model.n_elements
    n_grid = Solver.grid_size(t_end - t0, dt)
    if store_every > 0:
        n_out = n_grid // store_every + 2
    else:
        n_out = 0
    check_memory(f"integrate: {n_out:.3g} stored samples of {2 * N + 2 * ne + 1} values",
                 8.0 * n_out * (2 * N + 2 * ne + 1) + 32.0 * int(event_log),
                 "raise store_every (0 keeps only the end state), a larger dt or a shorter "
                 "span")
    out_t = np.empty(n_out)
    out_s = np.empty((n_out, 2 * N))
    out_d = np.empty((n_out, ne))
    out_f = np.empty((n_out, ne))
    s_end = np.empty(2 * N)
    disc_end = np.empty((ne, 2))
    P_end = np.empty_like(P0)
    dvm_end = np.empty_like(dvm0)
    xmax = np.zeros(N)
    counters = np.zeros(9, dtype=np.int64)
    fcounters = np.zeros(2)
    ev_log = np.zeros((int(event_log), 4))
    h_init = min(dt, Solver.first_step_cap(excitation))
    k = model.kernels()
    status = (k.integrate_var if want_var else k.integrate_plain)(
        tuple(sysa), xc, xp, xtab,
        _k.settings(meth=METHODS[method], t0=t0, t_end=t_end, dt=dt, spc=spc, rtol=rtol,
                    atol=atol, h_init=h_init, max_steps=max_steps, events_on=events,
                    want_var=want_var, track_xmax=track_xmax, store_every=store_every,
                    graded=graded, routine=ROUTINE_STEPS),
        _k.start(s0=s0, disc0=disc, P0=P0, dvm0=dvm0),
        _k.outputs(t=out_t, s=out_s, delta=out_d, force=out_f, ev_log=ev_log, s_end=s_end,
                   disc_end=disc_end, P_end=P_end, dvm_end=dvm_end, xmax=xmax,
                   counters=counters, fcounters=fcounters))
    if status != 0:
        raise IntegrationError(_status_message(status, fcounters[0], method))
    n = counters[0]
    if warn:
        warn_few_contact_steps(method, counters[5], counters[6], stacklevel=3)
    ev_log = ev_log[:min(int(counters[7]), ev_log.shape[0])]
    return (out_t[:n], out_s[:n], out_d[:n], out_f[:n], s_end, disc_end, P_end, dvm_end,
            xmax, counters, fcounters, ev_log)


def integrate(model, excitation, t_end, method="rk4", dt=None, x0=None, *, t0=0.0,
              disc0=None, store_every=1, steps_per_contact=None, rtol=1e-8, atol=1e-12,
              events=True, graded=True, event_log=10_000, warn=True, max_steps=100_000_000):
    """Integrate ``model`` driven by ``excitation`` from t0 to t_end (s).

    method: 'rk2' (the paper's constant-step scheme, Heun), 'rk4', both with step ``dt`` (s)
    outside contact and min(dt, (estimated contact duration)/steps_per_contact) inside, or
    'adaptive' (Dormand-Prince 5(4) with tolerances rtol, atol and quintic Hermite dense output;
    ``dt`` is then the output spacing). Every contact onset and end is located to a few ulps
    of t and stepped onto; no step crosses a contact boundary (``events=False`` switches this
    off, for comparison only). With ``graded`` (default) the fixed-step methods step the start
    of each contact uniformly in sqrt(t - t_onset) and its end uniformly in sqrt(delta), which
    keeps their order across the delta^1.5 singularity of Hertz-type contact forces; these
    graded steps double in number each time dt halves below twice the contact step, so
    halving dt alone converges at the method's order (steps_per_contact refines the contacts
    also where dt is above their steps).
    x0: initial state [x_1..x_N, v_1..v_N] (default: at rest).
    store_every: keep every k-th grid sample (0: none, only the end state).
    event_log: how many contact events to record in ``Trajectory.events`` (memory bound).
    warn: warn when a contact got fewer than 8 steps (``Trajectory.min_steps_per_contact`` tells
    in any case).
    Returns a :class:`Trajectory`.
    """
    solver = Solver(method, dt, steps_per_contact, rtol, atol, events, graded)
    dt, spc = _prepare(model, excitation, solver, t0, t_end)
    t0, t_end = float(t0), float(t_end)
    store_every = integer("store_every", store_every, 0)
    event_log = integer("event_log", event_log, 0)
    max_steps = integer("max_steps", max_steps, 1)
    flag("warn", warn)
    _check_steps("integrate", t_end - t0, dt, method, max_steps)
    s0, disc = _initial(model, x0, disc0, t0, excitation)
    N = model.n_dof
    ne = model.n_elements
    P0 = np.zeros((2 * N, 1))
    dvm0 = np.zeros((ne, 1))
    (t, S, D, F, s_end, disc_end, _, _, xmax, c, fc, evl) = _run(
        model, excitation, t0, t_end, method, dt, spc, rtol, atol, max_steps, s0, disc, events,
        False, P0, dvm0, True, store_every, graded, event_log, warn)
    if warn:
        warn_stiffened(model, method, dt, xmax, stacklevel=2)
    return Trajectory(t=t, x=S[:, :N], v=S[:, N:], delta=D, force=F, n_impacts=int(c[4]),
                      state_end=s_end, disc_end=disc_end, t_end=float(t_end), method=method,
                      dt=dt, steps_per_contact=spc, n_steps=int(c[1]), n_rejected=int(c[2]),
                      n_rhs=int(c[3]), min_steps_per_contact=int(c[5]), excitation=excitation,
                      xmax=xmax, events=evl, n_events=int(c[7]),
                      max_landing_residual=float(fc[1]))


def flow(model, excitation, state0, t0, duration, *, monodromy=False, disc0=None,
         method="rk4", dt=None, steps_per_contact=None, rtol=1e-10, atol=1e-14, events=True,
         graded=True, warn=True, max_steps=100_000_000):
    """The state at t0 + duration (s) from ``state0`` at t0, with ``xmax`` over the interval.

    With ``monodromy=True`` the variational equations are integrated alongside with the same
    Runge-Kutta stages (the exact derivative of the fixed-step map between events), and the
    Lankarani-Nikravesh onset velocity carries its own sensitivity row, updated at every onset.
    For a fixed-step method, dt is adjusted down so that duration / dt is an integer.
    warn: warn when a contact got fewer than 8 steps (fixed-step methods). One call of a
    ``FlowMap``; the step decisions are those of nlbeam.solver.Solver.
    """
    t0 = finite("t0", t0, unit="s")
    duration = finite("duration", duration, unit="s")
    max_steps = integer("max_steps", max_steps, 1)
    flag("monodromy", monodromy)
    if disc0 is not None:
        _check_model(model, excitation)
        disc0 = _check_disc(model, disc0)
    fm = FlowMap(model, excitation, method=method, dt=dt, steps_per_contact=steps_per_contact,
                 rtol=rtol, atol=atol, events=events, graded=graded, warn=warn)
    fm._stacklevel = 3  # a warning points at flow's caller
    return fm(state0, t0, duration, monodromy=monodromy, disc0=disc0, max_steps=max_steps)


def _sensitivity_seed(N, ne, in_contact, monodromy):
    """Initial sensitivities (P0 (2N, m), dvm0 (ne, m)): the identity on the state, and on the
    onset velocities delta'_minus when the interval starts in contact; one dummy column
    without monodromy."""
    if not monodromy:
        return np.zeros((2 * N, 1)), np.zeros((ne, 1))
    m = 2 * N + (ne if in_contact else 0)
    P0 = np.zeros((2 * N, m))
    P0[:, :2 * N] = np.eye(2 * N)
    dvm0 = np.zeros((ne, m))
    if in_contact:
        dvm0[:, 2 * N:] = np.eye(ne)
    return P0, dvm0


def _flow_result(s_end, disc_end, P, dvm, xmax, c, N, in_contact, monodromy):
    """A Flow from the kernel's outputs (P, dvm: the sensitivities; c: its counters)."""
    if monodromy:
        M = P[:, :2 * N].copy()
        dS_dv = P[:, 2 * N:].copy() if in_contact else None
        dv_dS = dvm[:, :2 * N].copy()
        dv_dv = dvm[:, 2 * N:].copy() if in_contact else None
    else:
        M = dS_dv = dv_dS = dv_dv = None
    return Flow(state=s_end, disc=disc_end, xmax=xmax, n_impacts=int(c[4]), monodromy=M,
                dstate_dvminus0=dS_dv, dvminus_dstate0=dv_dS, dvminus_dvminus0=dv_dv,
                n_steps=int(c[1]), n_rhs=int(c[3]), min_steps_per_contact=int(c[5]))


class FlowMap:
    """``flow`` of one model and excitation over many intervals, with the per-call Python work
    done once: the arguments are validated and the kernel's arrays prepared at construction,
    and each call integrates one interval (``flow`` is one call of a FlowMap). For callers
    that integrate thousands of short intervals (shooting and continuation), where the checks
    cost as much as the integration. The step decisions are its ``solver``'s
    (nlbeam.solver.Solver). ``dt``: the fixed step (adjusted down per call so that the
    duration is a whole number of steps); ``max_steps``: per interval; ``warn``: warn when a
    contact got fewer than MIN_STEPS_PER_CONTACT steps (fixed-step methods)."""

    def __init__(self, model, excitation, *, method="rk4", dt=None, steps_per_contact=None,
                 rtol=1e-10, atol=1e-14, events=True, graded=True, warn=True):
        self.solver = solver = Solver(method, dt, steps_per_contact, rtol, atol, events, graded)
        _check_model(model, excitation)
        lo, hi = excitation.time_span()
        t_lo = lo if math.isfinite(lo) else 0.0
        # the checks of one integration, on a representative span (each call checks its own)
        self.dt, self.spc = _prepare(model, excitation, solver, t_lo,
                                     t_lo + 1.0 if not math.isfinite(hi) else hi)
        self.model, self.excitation, self.method = model, excitation, method
        self.meth = solver.code
        self.sysa = tuple(model.kernel_arrays())  # a plain tuple: see _kernels.bundles
        self.xc, self.xp, self.xtab = excitation.kernel_args()
        self._kernels(model)
        self.span = (lo, hi)
        self.rtol, self.atol = float(rtol), float(atol)
        self.events, self.graded = bool(events), bool(graded)
        self.h_init_cap = solver.first_step_cap(excitation)
        N, ne = model.n_dof, model.n_elements
        self.N, self.ne = N, ne
        self.geometry = model.element_geometry()
        self.event_el = solver.event_elements(model)
        self.warn = flag("warn", warn)
        self._stacklevel = 2  # a warning points at the caller
        self._empty1 = np.empty(0)
        self._empty2 = np.empty((0, 2 * N))
        self._empty_e = np.empty((0, ne))
        self._ev_log = np.zeros((0, 4))
        self._dt_checked = self.dt

    def _kernels(self, model):
        # two dispatchers: a map that never asks for a monodromy never compiles (or loads) the
        # variational one
        k = model.kernels()
        self.kernel_plain, self.kernel_var = k.integrate_plain, k.integrate_var

    def __getstate__(self):
        # the compiled kernels are not pickled: a rebuilt numba dispatcher would compile again
        # (minutes) in the process that unpickles it; they are looked up there instead
        state = self.__dict__.copy()
        state.pop("kernel_plain", None)
        state.pop("kernel_var", None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._kernels(self.model)

    def retarget(self, excitation):
        """This map for another excitation (same model, method, dt, tolerances): only the
        excitation's kernel arguments are renewed."""
        new = object.__new__(FlowMap)  # (not copy.copy: that would pickle the state and look
        new.__dict__.update(self.__dict__)  # the kernels up again, see __setstate__)
        new.excitation = excitation
        new.xc, new.xp, new.xtab = excitation.kernel_args()
        new.span = excitation.time_span()
        new.h_init_cap = self.solver.first_step_cap(excitation)
        return new

    def _disc(self, s0, t0):
        """The contact state at t0 of a state s0 by the solver's start-in-contact rule."""
        if not self.event_el:
            return np.zeros((self.ne, 2))
        y, yd, _, st = _k.excite(float(t0), self.xc, self.xp, self.xtab)  # as evaluate
        if st != 0:
            raise ValueError("t: outside the time span the excitation is defined on "
                             f"({self.span})")
        return self.solver.start_contact(self.geometry, s0, y, yd, self.event_el)

    def __call__(self, state0, t0, duration, *, monodromy=False, disc0=None, dt=None,
                 max_steps=100_000_000):
        """The Flow from ``state0`` (2N,) at t0 (s) over ``duration`` (s), as
        ``flow(model, excitation, state0, t0, duration, ...)`` with this map's settings; dt (s)
        overrides the map's step for this call. Raises IntegrationError as flow does."""
        if not duration > 0:
            raise ValueError(f"duration: must be > 0 s, got {duration!r}")
        t_end = t0 + duration
        _check_span(self.span, t0, t_end)
        if dt is None:
            dt = self.dt
        else:
            dt = float(dt)
            if dt > self._dt_checked:  # a longer step than checked so far: check it
                positive("dt", dt, unit="s")
                self.solver.check_stable(self.model, self.excitation, dt)
                self._dt_checked = dt
            elif not dt > 0:
                raise ValueError(f"dt: must be > 0 s, got {dt!r}")
        if duration > max_steps * dt:  # cheap: checked on every call
            _check_steps("flow", duration, dt, self.method, max_steps)
        dt = self.solver.whole_step(duration, dt)
        N, ne = self.N, self.ne
        if (type(state0) is np.ndarray and state0.dtype == np.float64
                and state0.shape == (2 * N,)):  # the fast path of _state: the same checks
            s0 = state0.copy()
            if not np.isfinite(s0).all():
                s0 = _state(self.model, s0, "state0")  # (raises)
        else:
            s0 = _state(self.model, state0, "state0")
        if disc0 is None:
            disc = self._disc(s0, t0)
        else:
            disc = np.array(disc0, dtype=float).reshape(ne, 2)
        in_contact = bool((disc[:, 0] != 0).any())
        P0, dvm0 = _sensitivity_seed(N, ne, in_contact, monodromy)
        s_end = np.empty(2 * N)
        disc_end = np.empty((ne, 2))
        P_end = np.empty(P0.shape)
        dvm_end = np.empty(dvm0.shape)
        xmax = np.zeros(N)
        c = np.zeros(9, dtype=np.int64)
        fc = np.zeros(2)
        status = (self.kernel_var if monodromy else self.kernel_plain)(
            self.sysa, self.xc, self.xp, self.xtab,
            _k.settings(meth=self.meth, t0=t0, t_end=t_end, dt=dt, spc=self.spc, rtol=self.rtol,
                        atol=self.atol, h_init=min(dt, self.h_init_cap), max_steps=max_steps,
                        events_on=self.events, want_var=monodromy, track_xmax=True,
                        store_every=0, graded=self.graded, routine=ROUTINE_STEPS),
            _k.start(s0=s0, disc0=disc, P0=P0, dvm0=dvm0),
            _k.outputs(t=self._empty1, s=self._empty2, delta=self._empty_e, force=self._empty_e,
                       ev_log=self._ev_log, s_end=s_end, disc_end=disc_end, P_end=P_end,
                       dvm_end=dvm_end, xmax=xmax, counters=c, fcounters=fc))
        if status != 0:
            raise IntegrationError(_status_message(status, fc[0], self.method))
        if self.warn:
            self.solver.warn_few_contact_steps(c[5], c[6], self._stacklevel)
        return _flow_result(s_end, disc_end, P_end, dvm_end, xmax, c, N, in_contact,
                            monodromy)


def compile_kernels(model, monodromy=False):
    """Compile, or load from numba's disk cache, the integration kernel that ``model``'s flows
    without (``monodromy=False``: integrate, records) or with the variational equations
    (``monodromy=True``: shooting, diagrams) run, by one step at rest in this process. The
    arguments have the types of every integrate, flow and FlowMap call, so the kernel is not
    compiled again for them. Returns the CPU seconds it took (minutes on a fresh machine for
    the variational kernel, well under a second once cached)."""
    import time

    t = time.process_time()
    N = model.n_dof
    fm = FlowMap(model, Harmonic(0.0, 1.0), warn=False)
    fm(np.zeros(2 * N), 0.0, fm.dt, monodromy=bool(monodromy))
    return time.process_time() - t
