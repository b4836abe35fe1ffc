"""Excitations: what drives a model, as arrays the compiled kernels evaluate.

A base-excited model reads the excitation as the base displacement ``y`` (m) and its
velocity ``y'`` (m/s); a force-excited model reads ``y`` as the force (N). Every
excitation reduces to ``kernel_args() -> (code, p, tab)`` so that one set of kernels
serves them all (see ``docs/INTERNALS.md``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._validate import finite, nonnegative, positive, real_array

HARMONIC = 0
SAMPLED = 1
COSINE_SUM = 2
SAMPLED_QUINTIC = 3
SAMPLED_QUINTIC_COEF = 4
#: a quintic table of at most this many nodes is handed to the kernels as per-cell
#: coefficients (12 doubles a cell, 3x the table; code 4): larger ones as nodes (code 3)
COEF_MAX_NODES = 1 << 20

_EMPTY_TAB = np.zeros((1, 3))


class Excitation:
    """Base class. Subclasses implement :meth:`kernel_args` and :meth:`describe`."""

    def kernel_args(self):  # pragma: no cover - interface
        raise NotImplementedError

    def describe(self) -> dict:
        """Flat dict of the parameters (for result files)."""
        return {"kind": type(self).__name__}

    def evaluate(self, t):
        """Return ``(y, y')`` at the times ``t`` (s), computed by the kernel's own code."""
        from ._kernels import excitation_many

        code, p, tab = self.kernel_args()
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((t.size, 2))
        status = excitation_many(code, p, tab, t, out)
        if status != 0:
            raise ValueError("t: outside the time span the excitation is defined on "
                             f"({self.time_span()})")
        return out[:, 0], out[:, 1]

    def time_span(self):
        return (-math.inf, math.inf)

    def max_frequency(self) -> float:
        """Highest frequency (Hz) in the excitation, used to choose a default step."""
        return 0.0


@dataclass(frozen=True)
class Harmonic(Excitation):
    """``y(t) = amplitude * cos(2 pi frequency t + phase)``.

    amplitude: base displacement (m) for base-excited models, force (N) for force-excited ones.
    frequency: Hz (> 0). phase: rad.
    """

    amplitude: float
    frequency: float
    phase: float = 0.0

    def __post_init__(self):
        finite("amplitude", self.amplitude)
        positive("frequency", self.frequency, unit="Hz")
        finite("phase", self.phase)

    def kernel_args(self):
        p = np.array([float(self.amplitude), 2.0 * math.pi * float(self.frequency),
                      float(self.phase)])
        return HARMONIC, p, _EMPTY_TAB

    def describe(self):
        return {"kind": "Harmonic", "amplitude": float(self.amplitude),
                "frequency": float(self.frequency), "phase": float(self.phase)}

    def max_frequency(self):
        return float(self.frequency)

    @property
    def period(self) -> float:
        return 1.0 / float(self.frequency)


@dataclass(frozen=True, eq=False)
class Sampled(Excitation):
    """An excitation tabulated on a uniform grid ``t_start + i h`` (s).

    ``y`` is interpolated by the cubic Hermite polynomial through (y, y') and ``y'`` by the
    one through (y', y''): both errors are O(h^4). ``ydd`` may be omitted (then ``y'`` is
    interpolated linearly, O(h^2), which is only adequate for coarse work). With ``yddd``
    (y''', m/s^3; ``ydd`` then required) both are quintic Hermite polynomials, through
    (y, y', y'') and through (y', y'', y'''): errors O(h^6), at most h^6/46080 max|y^(6)|
    and h^6/46080 max|y^(7)| (a band-limited signal allows a ~9x coarser grid than cubic).
    Evaluating outside ``[t_start, t_start + (n-1) h]`` is an error.
    """

    t_start: float
    h: float
    y: np.ndarray
    yd: np.ndarray
    ydd: np.ndarray | None = None
    max_freq: float = 0.0
    yddd: np.ndarray | None = None
    tab: np.ndarray = field(init=False, repr=False)

    @classmethod
    def from_table(cls, t_start, h, tab, max_freq=0.0):
        """A table from its kernel array ``tab``, (n, 3) [y, y', y''] or (n, 4) [y, y', y'',
        y'''], used as it is (no copy when C-contiguous float64); checked finite."""
        finite("t_start", t_start)
        positive("h", h, unit="s")
        nonnegative("max_freq", max_freq, unit="Hz")
        tab = np.ascontiguousarray(tab, dtype=float)
        if tab.ndim != 2 or tab.shape[1] not in (3, 4) or tab.shape[0] < 2:
            raise ValueError(f"tab: must have shape (n >= 2, 3 or 4), got {tab.shape}")
        if not np.isfinite(tab).all():
            raise ValueError("tab: must be finite")
        obj = object.__new__(cls)
        for name, v in (("t_start", float(t_start)), ("h", float(h)), ("y", tab[:, 0]),
                        ("yd", tab[:, 1]), ("ydd", tab[:, 2]), ("max_freq", float(max_freq)),
                        ("yddd", tab[:, 3] if tab.shape[1] == 4 else None), ("tab", tab)):
            object.__setattr__(obj, name, v)
        return obj

    def __post_init__(self):
        finite("t_start", self.t_start)
        positive("h", self.h, unit="s")
        nonnegative("max_freq", self.max_freq, unit="Hz")
        y = np.ascontiguousarray(real_array("y", self.y, finite_values=False))
        yd = np.ascontiguousarray(real_array("yd", self.yd, finite_values=False))
        if y.ndim != 1 or y.shape != yd.shape or y.size < 2:
            raise ValueError("y, yd: must be 1-D arrays of equal length >= 2")
        if self.yddd is not None and self.ydd is None:
            raise ValueError("yddd: a quintic table needs ydd as well (y, y', y'', y''')")
        tab = np.empty((y.size, 3 if self.yddd is None else 4))
        tab[:, 0] = y
        tab[:, 1] = yd
        if self.ydd is None:
            tab[:, 2] = np.nan  # kernel falls back to linear interpolation of y'
        else:
            ydd = real_array("ydd", self.ydd, finite_values=False)
            if ydd.shape != y.shape:
                raise ValueError("ydd: must have the shape of y")
            tab[:, 2] = ydd
        if self.yddd is not None:
            yddd = real_array("yddd", self.yddd, finite_values=False)
            if yddd.shape != y.shape:
                raise ValueError("yddd: must have the shape of y")
            tab[:, 3] = yddd
            if not np.all(np.isfinite(tab[:, 2:])):
                raise ValueError("ydd, yddd: must be finite")
        if not np.all(np.isfinite(tab[:, :2])):
            raise ValueError("y, yd: must be finite")
        object.__setattr__(self, "tab", tab)

    def kernel_args(self):
        """(code, p, tab) of the kernels: a quintic table of up to COEF_MAX_NODES nodes as
        per-cell coefficients (code 4, built once, the same values as code 3 bit for bit and
        ~2x faster to evaluate), a larger one as its nodes (code 3)."""
        p = np.array([float(self.t_start), float(self.h), float(self.tab.shape[0])])
        if self.tab.shape[1] == 3:
            return SAMPLED, p, self.tab
        if self.tab.shape[0] > COEF_MAX_NODES:
            return SAMPLED_QUINTIC, p, self.tab
        coef = self.__dict__.get("_coef")
        if coef is None:
            from ._kernels.tables import quintic_coefficients

            coef = np.empty((self.tab.shape[0] - 1, 12))
            quintic_coefficients(self.tab, float(self.h), coef)
            object.__setattr__(self, "_coef", coef)
        return SAMPLED_QUINTIC_COEF, p, coef

    def time_span(self):
        return (self.t_start, self.t_start + (self.tab.shape[0] - 1) * self.h)

    def describe(self):
        return {"kind": "Sampled", "t_start": float(self.t_start), "h": float(self.h),
                "n": int(self.tab.shape[0]),
                "interpolation": "cubic Hermite" if self.tab.shape[1] == 3 else "quintic Hermite"}

    def max_frequency(self):
        return float(self.max_freq) if self.max_freq > 0 else 0.25 / float(self.h)


@dataclass(frozen=True, eq=False)
class CosineSum(Excitation):
    """``y(t) = sum_k amplitudes[k] cos(2 pi frequencies[k] t + phases[k])``, evaluated directly
    (O(K) per evaluation; for many components synthesize a :class:`Sampled` table instead).
    frequencies: Hz (>= 0), amplitudes: m (or N), phases: rad."""

    frequencies: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray
    tab: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        f, a, ph = (np.atleast_1d(real_array(n, getattr(self, n), finite_values=False))
                    for n in ("frequencies", "amplitudes", "phases"))
        if not (f.shape == a.shape == ph.shape) or f.ndim != 1 or f.size == 0:
            raise ValueError("frequencies, amplitudes, phases: must be 1-D arrays of one length "
                             ">= 1")
        for name, arr in (("frequencies", f), ("amplitudes", a), ("phases", ph)):
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name}: must be finite")
        if np.any(f < 0):
            raise ValueError("frequencies: must be >= 0 Hz")
        tab = np.column_stack([2.0 * np.pi * f, a, ph])
        object.__setattr__(self, "tab", np.ascontiguousarray(tab))

    def kernel_args(self):
        return COSINE_SUM, np.zeros(1), self.tab

    def describe(self):
        return {"kind": "CosineSum", "n_components": int(self.tab.shape[0])}

    def max_frequency(self):
        return float(self.tab[:, 0].max() / (2 * np.pi))
