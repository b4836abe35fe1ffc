"""Every step decision of the integrators in one place: ``Solver``.

A ``Solver`` is the frozen settings of one integration (method, step, steps per contact,
tolerances, events, graded contact steps) and owns the rules that turn them into the numbers
the kernel is called with:

- steps per period of each method (``STEPS_PER_PERIOD``): the default step of ``integrate`` /
  ``flow`` is 1 / (steps per period * the highest frequency of the excitation and of the linear
  structure); continuation's periodic flows keep a whole number of steps per excitation period
  (``steps_per_excitation_period``, doubled in powers of two below the highest natural
  frequency, divided by ``dt_scale``);
- steps per contact (``STEPS_PER_CONTACT``) and the warning when a contact got fewer than
  ``MIN_STEPS_PER_CONTACT`` steps;
- rounding a span to whole steps (``whole_step`` for a flow, ``phase_step`` for a span of
  excitation periods);
- the explicit-stability check of the fixed-step methods (``check_stable``);
- the start-in-contact rule (``start_contact``): a record that starts inside a contact takes
  its penetration rate at the start as delta'_minus when that is positive, else
  ``VMINUS_FLOOR`` = 1e-6 m/s (the floor the kernel applies to a tangential onset).

Units: s, Hz, m, m/s. ``integrate``, ``flow`` and ``FlowMap`` (nlbeam.integrate) and the
periodic flows of ``continuation`` ask a Solver for these decisions and call the kernel.
"""
from __future__ import annotations

import math
import warnings
import weakref
from dataclasses import dataclass

import numpy as np

from . import _kernels as _k
from . import _linalg as la
from ._validate import choice, flag, in_range, positive
from .vocabulary import METHODS as METHOD_NAMES

METHODS = {"rk2": _k.RK2, "rk4": _k.RK4, "adaptive": _k.DP5}  # name -> kernel code
if tuple(METHODS) != METHOD_NAMES:
    raise ImportError(f"nlbeam.solver: the kernel codes are given for {tuple(METHODS)}, the "
                      f"vocabulary has {METHOD_NAMES}: give each method its code")

# defaults: steps per period of the fastest of (excitation, linear natural frequency), and
# steps per contact. Accuracy they give on the paper model is stated in the README. For the
# adaptive method the step per period sets only the spacing of the output samples.
STEPS_PER_PERIOD = {"rk2": 400, "rk4": 100, "adaptive": 32}
STEPS_PER_CONTACT = {"rk2": 96, "rk4": 32, "adaptive": 32}
MIN_STEPS_PER_CONTACT = 8
# the largest steps_per_contact accepted: beyond it one contact alone costs ~1e5 steps, and a
# run with thousands of impacts would run for hours before reaching max_steps
MAX_STEPS_PER_CONTACT = 100_000
# |omega dt| of the highest undamped mode beyond which the explicit step amplifies it: RK4
# 2 sqrt 2 (imaginary axis); Heun grows an undamped mode by ~(omega dt)^4 / 8 per step at any
# dt, its real-axis limit 2 is taken. The defaults stay far below (omega dt = 2 pi / steps per
# period).
STABILITY = {"rk2": 2.0, "rk4": 2.0 * math.sqrt(2.0)}
# output samples per excitation period of a periodic record integrated by the adaptive method
# (continuation's brute-force sweeps; the adaptive step itself follows rtol, atol)
ADAPTIVE_SAMPLES_PER_PERIOD = 200
VMINUS_FLOOR = _k.VMINUS_FLOOR  # m/s: delta'_minus of a start or onset at zero rate
_F_MAX = weakref.WeakKeyDictionary()  # System -> highest natural frequency (Hz)
_CUBIC = weakref.WeakKeyDictionary()  # System -> [(k3, w)] of its hardening cubic springs


def highest_natural_frequency(model):
    """Highest undamped natural frequency (Hz) of the model's linear structure (cached)."""
    sysm = model.system
    fmax = _F_MAX.get(sysm)
    if fmax is None:
        fmax = _F_MAX[sysm] = float(np.max(sysm.natural_frequencies()))
    return fmax


def period_step(frequency, steps_per_period):
    """The step (s) of ``steps_per_period`` steps per period of ``frequency`` (Hz); None when
    steps_per_period is 0 (the adaptive method: the solver's default output spacing)."""
    return 1.0 / (steps_per_period * frequency) if steps_per_period else None


def phase_step(duration, steps):
    """The step (s) that divides ``duration`` (s) into ``steps`` rounded to a whole number
    (at least 1); the whole duration when steps is 0 (the adaptive method)."""
    return duration / max(1, int(round(steps))) if steps else duration


@dataclass(frozen=True)
class Solver:
    """How a flow is integrated (every step decision; module doc).

    method: 'rk2' (Heun), 'rk4' (fixed step ``dt`` in free flight, the estimated contact
    duration / ``steps_per_contact`` inside a contact, never longer than ``dt``) or 'adaptive'
    (Dormand-Prince 5(4) with rtol, atol; ``dt`` is then the output spacing). dt (s): None for
    the default 1 / (STEPS_PER_PERIOD[method] * f), f the highest of the excitation's and the
    structure's frequencies. steps_per_contact: None for STEPS_PER_CONTACT[method]. events:
    locate contact boundaries (False only for comparison); graded: graded steps at contact
    onsets and ends (steps_per_contact // 4 of them each, times the least power of 2 m with
    2 contact steps <= m dt: halving dt alone refines them too, and the error falls at the
    method's order; docs/INTERNALS.md)."""

    method: str = "rk4"
    dt: float | None = None
    steps_per_contact: float | None = None
    rtol: float = 1e-8
    atol: float = 1e-12
    events: bool = True
    graded: bool = True

    def __post_init__(self):
        choice("method", self.method, METHOD_NAMES)
        if self.dt is not None:
            positive("dt", self.dt, unit="s")
        if self.steps_per_contact is not None:
            in_range("steps_per_contact", self.steps_per_contact, 1, MAX_STEPS_PER_CONTACT)
        positive("rtol", self.rtol)
        positive("atol", self.atol)
        flag("events", self.events)
        flag("graded", self.graded)

    # --- the method --------------------------------------------------------------------------
    @property
    def fixed(self):
        """True for the fixed-step methods (rk2, rk4)."""
        return self.method != "adaptive"

    @property
    def code(self):
        """The kernel's code of the method."""
        return METHODS[self.method]

    def contact_steps(self):
        """Steps per (estimated) contact duration."""
        spc = self.steps_per_contact
        return float(STEPS_PER_CONTACT[self.method] if spc is None else spc)

    # --- steps ---------------------------------------------------------------------------------
    def default_dt(self, model, excitation):
        """The default step (s): 1 / (STEPS_PER_PERIOD[method] * f), f the highest of the
        excitation's frequency and the linear structure's natural frequencies (Hz); for
        'adaptive' the spacing of the output samples."""
        f = max(excitation.max_frequency(), highest_natural_frequency(model), 1e-9)
        return 1.0 / (STEPS_PER_PERIOD[self.method] * f)

    def step(self, model, excitation):
        """The step (s) of this solver for model and excitation (``dt`` or the default),
        checked against the explicit method's stability limit."""
        dt = self.default_dt(model, excitation) if self.dt is None else self.dt
        self.check_stable(model, excitation, dt)
        return float(dt)

    def check_stable(self, model, excitation, dt):
        """Raise ValueError naming dt when the fixed step dt (s) is beyond the explicit
        method's stability limit for the model's highest natural frequency (a stiff high mode
        of a multi-mode model); nothing for the adaptive method."""
        lim_w = STABILITY.get(self.method)
        if lim_w is None:
            return
        fmax = highest_natural_frequency(model)
        if 2 * math.pi * fmax * dt > lim_w:
            lim = lim_w / (2 * math.pi * fmax)
            raise ValueError(f"dt: {dt:.4g} s is beyond the stability limit {lim:.4g} s of "
                             f"{self.method!r} for the model's highest natural frequency "
                             f"{fmax:.6g} Hz; use a smaller dt or dt=None (default "
                             f"{self.default_dt(model, excitation):.4g} s)")

    def whole_step(self, duration, dt):
        """For the fixed-step methods, dt (s) adjusted down so that ``duration`` (s) is a whole
        number of steps; dt unchanged for the adaptive method."""
        if not self.fixed:
            return dt
        return duration / math.ceil(duration / dt - 1e-9)

    @staticmethod
    def grid_size(duration, dt):
        """Number of output steps of spacing dt (s) in ``duration`` (s) (the last may be
        shorter)."""
        return int(math.ceil(duration / dt - 1e-9))

    @staticmethod
    def first_step_cap(excitation):
        """Upper bound (s) of the adaptive method's first step: 1e-3 of the excitation's
        period (1e-3 s below 1 Hz)."""
        return 1e-3 / max(excitation.max_frequency(), 1.0)

    def steps_per_excitation_period(self, model, frequency, dt_scale=1.0):
        """Fixed steps per excitation period at frequency (Hz) for periodic orbits (0 for the
        adaptive method): STEPS_PER_PERIOD[method] times the power of two at or above (highest
        natural frequency / frequency) (at least 1), divided by dt_scale and rounded up. Kept
        fixed along a branch between the powers of two, so the discrete flow map is smooth."""
        if not self.fixed:
            return 0
        fn = highest_natural_frequency(model)
        ratio = max(1.0, fn / frequency)
        level = 2 ** int(math.ceil(math.log2(ratio) - 1e-12))
        return int(math.ceil(STEPS_PER_PERIOD[self.method] * level / dt_scale))

    # --- contacts ------------------------------------------------------------------------------
    @staticmethod
    def start_contact(geometry, state, y, yd, elements):
        """The contact state (n_elements, 2) [in contact, delta'_minus] of ``state`` (2N,) at
        excitation (y, y'): an event element (index in ``elements``) with penetration delta > 0
        is in contact with delta'_minus = its penetration rate when that exceeds VMINUS_FLOOR,
        else VMINUS_FLOOR. geometry: model.element_geometry() (etype, w, wy, gap)."""
        _, w, wy, gap = geometry
        N = w.shape[1]
        disc = np.zeros((len(gap), 2))
        for e in elements:
            d = la.dot(w[e], state[:N]) + wy[e] * y - gap[e]
            dd = la.dot(w[e], state[N:]) + wy[e] * yd
            if d > 0:
                disc[e, 0] = 1.0
                disc[e, 1] = dd if dd > VMINUS_FLOOR else VMINUS_FLOOR
        return disc

    @staticmethod
    def start_contact_derivative(model):
        """d delta'_minus / d state (n_elements, 2N) of the start-in-contact rule above the
        floor: [0, w_e] for each element (the penetration rate is w_e . v + wy_e y')."""
        N = model.n_dof
        D = np.zeros((model.n_elements, 2 * N))
        D[:, N:] = model.element_geometry()[1]
        return D

    @staticmethod
    def event_elements(model):
        """Indices of the elements with contact events (the stops)."""
        et = model.element_geometry()[0]
        return [e for e in range(model.n_elements) if _k.has_event(et[e])]

    def warn_few_contact_steps(self, fewest, n_contacts, stacklevel):
        """``warn_few_contact_steps`` for this solver's method."""
        warn_few_contact_steps(self.method, fewest, n_contacts, stacklevel + 1)


def warn_few_contact_steps(method, fewest, n_contacts, stacklevel):
    """RuntimeWarning when a fixed-step run resolved a contact with fewer than
    MIN_STEPS_PER_CONTACT steps (n_contacts: contacts seen; fewest: the fewest steps of one);
    stacklevel as for warnings.warn, counted from the caller of this function."""
    if n_contacts > 0 and method != "adaptive" and fewest < MIN_STEPS_PER_CONTACT:
        warnings.warn(f"a contact was resolved with only {fewest} steps (< "
                      f"{MIN_STEPS_PER_CONTACT}): the result is inaccurate; reduce dt or raise "
                      "steps_per_contact", RuntimeWarning, stacklevel=stacklevel + 1)


def stiffened_frequency(model, xmax):
    """Highest natural frequency (Hz) of the structure linearized about the largest excursion
    ``xmax`` (N,) (m) of a run: each hardening cubic spring (k3 > 0, displacement d = w . x)
    adds its tangent stiffness 3 k3 d^2 w w^T at |d| = |w| . xmax. None without such a spring."""
    sysm = model.system
    cubic = _CUBIC.get(sysm)
    if cubic is None:
        etype, w, _, _ = sysm.element_geometry()
        k3 = sysm.kernel_arrays().epar[:, 0]
        cubic = _CUBIC[sysm] = [(float(k3[e]), w[e].copy()) for e in range(len(etype))
                                if etype[e] == _k.CUBIC and k3[e] > 0]
    if not cubic:
        return None
    K = np.array(sysm.K, dtype=float)
    for k3, w in cubic:
        d = la.dot(np.abs(w), np.abs(np.asarray(xmax, dtype=float)))
        K += 3.0 * k3 * d * d * np.outer(w, w)
    lam = la.eigvals(la.solve(sysm.M, K))
    return float(np.sqrt(np.abs(lam.real)).max() / (2 * np.pi))


def warn_stiffened(model, method, dt, xmax, stacklevel):
    """RuntimeWarning when a fixed step dt (s) gave fewer than a quarter of
    STEPS_PER_PERIOD[method] steps per period of the stiffened frequency
    (``stiffened_frequency``) reached in the run: the default step looks at the linear
    stiffness only, and a hardening cubic spring then errs by percents (Duffing k3 = 1e6 N/m^3,
    F = 100 N at 0.5 Hz: 2.3 steps per stiffened period, xmax 6 % off)."""
    if method == "adaptive":
        return
    f_eff = stiffened_frequency(model, xmax)
    if f_eff is None or not f_eff > 0:
        return
    steps = 1.0 / (f_eff * dt)
    want = STEPS_PER_PERIOD[method]
    if steps < want / 4:
        warnings.warn(f"dt = {dt:.4g} s gives only {steps:.3g} steps per period of the "
                      f"stiffened frequency {f_eff:.4g} Hz the cubic spring reached (|x| up to "
                      f"{float(np.max(np.abs(xmax))):.4g} m): the result may be off by percents; "
                      f"use dt <= {1.0 / (want * f_eff):.3g} s ({want} steps per period)",
                      RuntimeWarning, stacklevel=stacklevel + 1)
