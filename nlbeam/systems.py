"""Models: a linear structure with local nonlinear elements, described as arrays.

``System`` is the general description every analysis works on::

    M x'' + C x' + K x + sum_e w_e f_e(delta_e, delta_e') = y_load * y(t) + yd_load * y'(t)

with the penetration of element e ``delta_e = w_e . x + wy_e * y - gap_e`` (positive in
contact) and ``f_e >= 0`` pushing out of the stop. ``BeamImpact`` (the paper's SDOF beam with
elastic stop) and ``Duffing`` are thin constructors of a ``System``; they hold no numerics.
Units: SI (kg, N/m, kg/s, N/m^1.5, m, s).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import _kernels as _k
from . import _linalg as la
from ._validate import (ArgumentTypeError, choice, finite, flag, in_range, integer,
                        nonnegative, positive, real, real_array)
from .vocabulary import CONTACT_LAWS

_LAW_CODE = {"hertz": _k.HERTZ, "lankarani-nikravesh": _k.LANKARANI,
             "hunt-crossley": _k.HUNT_CROSSLEY}


# --- helpers of the contact laws (paper eqs. 3 and 6) -------------------------------------------
def hertz_stiffness(E1, nu1, R1, E2, nu2, R2):
    """K_hertz (N/m^1.5) of two spheres (paper eq. 3): K = 2/3 E_r sqrt(R_r), with
    E_r = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) and R_r = R1 R2 / (R1 + R2). E in Pa, R in m
    (R = inf for a flat)."""
    for n, v in (("E1", E1), ("E2", E2)):
        positive(n, v, unit="Pa")
    for n, v in (("nu1", nu1), ("nu2", nu2)):
        in_range(n, v, -1.0, 0.5, lo_open=True, hi_open=True)
    for n, v in (("R1", R1), ("R2", R2)):
        if not (real(n, v) > 0):
            raise ValueError(f"{n}: must be > 0 m (inf for a flat), got {v!r}")
    Er = 2.0 / ((1 - nu1 ** 2) / E1 + (1 - nu2 ** 2) / E2)
    Rr = 1.0 / (1.0 / R1 + 1.0 / R2)
    return 2.0 / 3.0 * Er * math.sqrt(Rr)


def mu_from_e(e, K_hertz, v_ref):
    """Hunt-Crossley mu (N s/m^2.5) equivalent to restitution e at impact velocity v_ref (m/s),
    paper eq. 6: mu = 3 K (1 - e^2) / (4 v_ref)."""
    in_range("e", e, 0.0, 1.0, lo_open=True)
    nonnegative("K_hertz", K_hertz, unit="N/m^1.5")
    positive("v_ref", v_ref, unit="m/s")
    return 3.0 * K_hertz * (1.0 - e * e) / (4.0 * v_ref)


def e_from_mu(mu, K_hertz, v_ref):
    """Restitution e equivalent to Hunt-Crossley mu at impact velocity v_ref (paper eq. 6)."""
    nonnegative("mu", mu)
    positive("K_hertz", K_hertz, unit="N/m^1.5")
    positive("v_ref", v_ref, unit="m/s")
    arg = 1.0 - 4.0 * mu * v_ref / (3.0 * K_hertz)
    if arg <= 0:
        raise ValueError("mu: too large for v_ref (4 mu v_ref / (3 K) must be < 1)")
    return math.sqrt(arg)


# --- elements -------------------------------------------------------------------------------------
def _location(dof, n_dof, name="dof"):
    w = np.zeros(n_dof)
    if np.ndim(dof) == 0:
        w[integer(name, dof, 0, n_dof - 1)] = 1.0
    else:
        w = real_array(name, dof, shape=(n_dof,))
    return w


def _check_dof(dof, name="dof"):
    """A DOF index (integer >= 0) or a finite vector (the model's size is checked later)."""
    if isinstance(dof, str) or np.ndim(dof) == 0:
        integer(name, dof, 0)
    else:
        real_array(name, dof, ndim=1, min_size=1)


def _check_element(self):
    """The checks every element shares: dof, on_base."""
    _check_dof(self.dof)
    flag("on_base", self.on_base)


@dataclass(frozen=True)
class Contact:
    """A one-sided elastic stop with a contact law (paper eqs. 2, 4, 6).

    dof: DOF index, or a vector w giving the contact displacement w . x.
    law: 'hertz', 'lankarani-nikravesh' (needs e) or 'hunt-crossley' (needs mu).
    K: contact stiffness (N/m^1.5, >= 0; 0 removes the stop). gap: m (negative = preload).
    side: +1 the stop is met when the DOF moves in + direction, -1 in - direction.
    on_base: True if the stop is mounted on the moving base (delta measured relative to y).
    clamp: the force is set to 0 where the law would make it pull (f < 0).
    """

    dof: object = 0
    law: str = "hertz"
    K: float = 0.0
    e: float | None = None
    mu: float | None = None
    gap: float = 0.0
    side: int = 1
    on_base: bool = True
    clamp: bool = True

    def __post_init__(self):
        _check_element(self)
        flag("clamp", self.clamp)
        choice("law", self.law, CONTACT_LAWS)
        nonnegative("K", self.K, unit="N/m^1.5")
        finite("gap", self.gap)
        choice("side", self.side, (1, -1))
        for n in ("e", "mu"):
            if getattr(self, n) is not None:
                real(n, getattr(self, n))
        if self.law == "lankarani-nikravesh":
            if self.e is None:
                raise ValueError("e: required by the lankarani-nikravesh law, must lie in (0, 1]")
            in_range("e", self.e, 0.0, 1.0, lo_open=True)
        if self.law == "hunt-crossley":
            if self.mu is None:
                raise ValueError("mu: required by the hunt-crossley law, must be finite and >= 0")
            nonnegative("mu", self.mu, unit="N s/m^2.5")

    def arrays(self, n_dof, kind):
        w = self.side * _location(self.dof, n_dof)
        wy = -float(self.side) if (self.on_base and kind == "base") else 0.0
        code = _LAW_CODE[self.law] if self.K > 0 else _k.INACTIVE
        par = [float(self.K), float(self.e or 0.0), float(self.mu or 0.0),
               1.0 if self.clamp else 0.0]
        return code, w, wy, float(self.gap), par


@dataclass(frozen=True)
class PiecewiseLinearStop:
    """A one-sided linear spring k (N/m) met after a gap (m): f = k delta for delta > 0."""

    dof: object = 0
    k: float = 0.0
    gap: float = 0.0
    side: int = 1
    on_base: bool = True

    def __post_init__(self):
        _check_element(self)
        nonnegative("k", self.k, unit="N/m")
        finite("gap", self.gap)
        choice("side", self.side, (1, -1))

    def arrays(self, n_dof, kind):
        w = self.side * _location(self.dof, n_dof)
        wy = -float(self.side) if (self.on_base and kind == "base") else 0.0
        code = _k.PWL_STOP if self.k > 0 else _k.INACTIVE
        return code, w, wy, float(self.gap), [float(self.k), 0.0, 0.0, 1.0]


@dataclass(frozen=True)
class CubicSpring:
    """A cubic spring, force k3 * d^3 (N, k3 in N/m^3) on the displacement d = w . x (relative to
    the base when on_base and base-excited)."""

    dof: object = 0
    k3: float = 0.0
    on_base: bool = False

    def __post_init__(self):
        _check_element(self)
        finite("k3", self.k3)

    def arrays(self, n_dof, kind):
        w = _location(self.dof, n_dof)
        wy = -1.0 if (self.on_base and kind == "base") else 0.0
        return _k.CUBIC, w, wy, 0.0, [float(self.k3), 0.0, 0.0, 0.0]


def _rows_dot(x, w):
    """x (..., N) against each row of w (ne, N): (..., ne), summed over N in index order by
    elementwise products (numpy's @ goes through BLAS, whose last bits differ between CPUs)."""
    out = x[..., :1] * w[:, 0]
    for j in range(1, w.shape[1]):
        out = out + x[..., j:j + 1] * w[:, j]
    return out


def _load(name, value):
    return real_array(name, value, finite_values=False)


# --- the general system ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class System:
    """A linear structure (M, C, K, N x N) with local nonlinear elements.

    excitation_kind: 'base' (y is the base displacement; by default the structure is tied to
    the base so the load is K 1 y + C 1 y') or 'force' (y is a force applied through y_load).
    y_load, yd_load: vectors (N,) multiplying y and y' on the right-hand side (override the
    defaults). output_dof: the DOF whose max |x| diagrams plot (default: the first contact DOF).
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    elements: tuple = ()
    excitation_kind: str = "base"
    y_load: np.ndarray | None = None
    yd_load: np.ndarray | None = None
    output_dof: int | None = None
    name: str = "System"
    custom_force: object = None
    custom_params: tuple = ()
    _arrays: tuple = field(init=False, repr=False)

    def __post_init__(self):
        M, C, K = (np.atleast_2d(real_array(n, getattr(self, n), finite_values=False))
                   for n in ("M", "C", "K"))
        N = M.shape[0]
        for name, A in (("M", M), ("C", C), ("K", K)):
            if A.shape != (N, N):
                raise ValueError(f"{name}: must be a square matrix of size {N} (the size of M)")
            if not np.all(np.isfinite(A)):
                raise ValueError(f"{name}: must be finite")
        if not np.allclose(M, M.T) or np.linalg.eigvalsh(0.5 * (M + M.T)).min() <= 0:
            raise ValueError("M: must be symmetric positive definite (masses > 0 kg)")
        choice("excitation_kind", self.excitation_kind, ("base", "force"))
        if isinstance(self.elements, (str, bytes)) or not hasattr(self.elements, "__iter__"):
            raise ArgumentTypeError(f"elements: must be a tuple of elements (Contact, "
                                    f"PiecewiseLinearStop, CubicSpring), got {self.elements!r}")
        for i, el in enumerate(self.elements):
            if not hasattr(el, "arrays"):
                raise ArgumentTypeError(f"elements[{i}]: must be an element (Contact, "
                                        f"PiecewiseLinearStop, CubicSpring), got {el!r}")
        if self.output_dof is not None:
            integer("output_dof", self.output_dof, 0, N - 1)
        if not isinstance(self.name, str):
            raise ArgumentTypeError(f"name: must be a string, got {self.name!r}")
        ones = np.ones(N)
        if self.excitation_kind == "base":
            yl = la.matmul(K, ones) if self.y_load is None else _load("y_load", self.y_load)
            ydl = la.matmul(C, ones) if self.yd_load is None else _load("yd_load", self.yd_load)
        else:
            yl = np.eye(N)[0] if self.y_load is None else _load("y_load", self.y_load)
            ydl = np.zeros(N) if self.yd_load is None else _load("yd_load", self.yd_load)
        for name, v in (("y_load", yl), ("yd_load", ydl)):
            if v.shape != (N,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name}: must be a finite vector of length {N}")
        els = tuple(self.elements)
        ne = len(els)
        etype = np.empty(ne, dtype=np.int64)
        ew = np.zeros((ne, N))
        ewy = np.zeros(ne)
        egap = np.zeros(ne)
        epar = np.zeros((ne, 4))
        for i, el in enumerate(els):
            code, w, wy, gap, par = el.arrays(N, self.excitation_kind)
            etype[i] = code
            ew[i] = w
            ewy[i] = wy
            egap[i] = gap
            epar[i] = par
        Minv = la.inv(M)  # fixed order: the kernel arrays are the same on every CPU
        out = self.output_dof
        if out is None:
            out = 0
            for i, el in enumerate(els):
                if isinstance(el, (Contact, PiecewiseLinearStop)):
                    out = int(np.argmax(np.abs(ew[i])))
                    break
        if not 0 <= int(out) < N:
            raise ValueError(f"output_dof: must be in [0, {N - 1}], got {out!r}")
        object.__setattr__(self, "M", M)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "elements", els)
        object.__setattr__(self, "y_load", yl)
        object.__setattr__(self, "yd_load", ydl)
        object.__setattr__(self, "output_dof", int(out))
        if self.custom_force is not None and not hasattr(self.custom_force, "py_func"):
            raise ValueError("custom_force: must be a numba-jitted function "
                             "force(t, x, v, y, yd, params, out) (see nlbeam.custom)")
        upar = np.atleast_1d(real_array("custom_params", self.custom_params,
                                        finite_values=False)).copy()
        if upar.size == 0:
            upar = np.zeros(1)
        if not np.all(np.isfinite(upar)):
            raise ValueError("custom_params: must be finite")
        arrays = _k.SystemArrays(
            MinvK=la.matmul(Minv, K), MinvC=la.matmul(Minv, C), mek=la.matmul(Minv, yl),
            mec=la.matmul(Minv, ydl), etype=etype, ew=ew, ewy=ewy, egap=egap, epar=epar,
            mw=la.matmul(ew, np.ascontiguousarray(Minv.T)), upar=upar, uf=np.zeros((4, N)),
            Minv=np.ascontiguousarray(Minv))
        object.__setattr__(self, "_arrays", arrays)

    # the protocol the analyses use
    @property
    def system(self) -> "System":
        return self

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    def kernel_arrays(self):
        """The arrays the compiled kernels take: a ``SystemArrays`` (nlbeam._kernels.bundles)."""
        return self._arrays

    def element_geometry(self):
        """(etype, w, wy, gap) of the elements: the law codes and the penetration geometry
        delta = w . x + wy * y - gap (w shape (n_elements, n_dof); m). Python-side code reads the
        geometry here; ``kernel_arrays`` is the kernels' private layout."""
        a = self._arrays
        return a.etype, a.ew, a.ewy, a.egap

    def kernels(self):
        """The compiled kernel module for this system (a private copy with a custom force)."""
        from .custom import kernels_for
        return kernels_for(self.custom_force)

    def natural_frequencies(self):
        """Undamped natural frequencies (Hz) of the linear structure without the elements."""
        lam = la.eigvals(la.solve(self.M, self.K))
        return np.sort(np.sqrt(np.abs(lam.real))) / (2 * np.pi)

    def has_events(self) -> bool:
        return any(_k.has_event(t) for t in self.element_geometry()[0])

    @property
    def contact_elements(self) -> np.ndarray:
        """Indices of the elements with contact events (the stops)."""
        return np.flatnonzero([_k.has_event(t) for t in self.element_geometry()[0]])

    def penetration(self, state, y=0.0, yd=0.0):
        """(delta, delta') of every element (m, m/s) at ``state`` [x, v] (shape (..., 2N)) and
        excitation (y, y'); positive delta is inside the stop."""
        state = np.asarray(state, dtype=float)
        N = self.n_dof
        _, ew, ewy, egap = self.element_geometry()
        x, v = _rows_dot(state[..., :N], ew), _rows_dot(state[..., N:], ew)
        d = x + np.multiply.outer(np.asarray(y, dtype=float), ewy) - egap
        dd = v + np.multiply.outer(np.asarray(yd, dtype=float), ewy)
        return d, dd

    def parameters(self) -> dict:
        d = {"model": self.name, "n_dof": self.n_dof, "excitation_kind": self.excitation_kind}
        for i, el in enumerate(self.elements):
            for k, v in el.__dict__.items():
                if isinstance(v, (int, float, str, bool)) or v is None:
                    d[f"element{i}.{k}"] = "None" if v is None else v
        return d


def _model_protocol(cls):
    """Give a model wrapper the protocol of System by delegation."""
    for name in ("n_dof", "n_elements", "output_dof", "excitation_kind"):
        setattr(cls, name, property(lambda self, _n=name: getattr(self.system, _n)))
    cls.kernel_arrays = lambda self: self.system.kernel_arrays()
    cls.kernels = lambda self: self.system.kernels()
    cls.element_geometry = lambda self: self.system.element_geometry()
    cls.natural_frequencies = lambda self: self.system.natural_frequencies()
    cls.has_events = lambda self: self.system.has_events()
    cls.contact_elements = property(lambda self: self.system.contact_elements)
    cls.penetration = lambda self, state, y=0.0, yd=0.0: self.system.penetration(state, y, yd)
    return cls


@_model_protocol
@dataclass(frozen=True)
class BeamImpact:
    """The paper's SDOF beam with an elastic stop (PHYSICS.md section 1)::

        m x'' + b x' + k x + f(delta) = b y' + k y,   delta = x - y (penetration, > 0 in contact)

    m: kg (> 0); k: N/m (>= 0); b: kg/s (>= 0); K_hertz: N/m^1.5 (>= 0, 0 removes the stop);
    e: coefficient of restitution in (0, 1]; contact: 'hertz', 'lankarani-nikravesh' (paper
    eq. 4) or 'hunt-crossley' (needs mu, N s/m^2.5). clamp: the stop cannot pull (f >= 0).
    gap: m between the beam at rest and the stop (0: the paper's stop touches it; negative: a
    preload), delta = x - y - gap.
    """

    m: float = 37.75e-3
    k: float = 736.3
    b: float = 0.16
    K_hertz: float = 2.1e8
    e: float = 0.5
    contact: str = "lankarani-nikravesh"
    mu: float | None = None
    clamp: bool = True
    gap: float = 0.0
    system: System = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        positive("m", self.m, unit="kg")
        nonnegative("k", self.k, unit="N/m")
        nonnegative("b", self.b, unit="kg/s")
        nonnegative("K_hertz", self.K_hertz, unit="N/m^1.5")
        flag("clamp", self.clamp)
        in_range("e", self.e, 0.0, 1.0, lo_open=True)
        choice("contact", self.contact, CONTACT_LAWS)
        if self.contact == "hunt-crossley" and self.mu is None:
            raise ValueError("mu: required when contact='hunt-crossley' (finite, >= 0 N s/m^2.5); "
                             "see nlbeam.mu_from_e")
        if self.mu is not None:
            nonnegative("mu", self.mu, unit="N s/m^2.5")
        finite("gap", self.gap)
        el = Contact(0, self.contact, self.K_hertz, e=self.e, mu=self.mu, gap=self.gap,
                     clamp=self.clamp)
        sysm = System([[self.m]], [[self.b]], [[self.k]], (el,), "base",
                      y_load=[self.k], yd_load=[self.b], output_dof=0, name="BeamImpact")
        object.__setattr__(self, "system", sysm)

    @classmethod
    def paper(cls, **overrides):
        """The paper's parameter set: m = 37.75e-3 kg, k = 736.3 N/m, b = 0.16 kg/s,
        K_hertz = 2.1e8 N/m^1.5, e = 0.5, Lankarani-Nikravesh law."""
        return cls(**overrides)

    def replace(self, **changes):
        kw = {k: getattr(self, k)
              for k in ("m", "k", "b", "K_hertz", "e", "contact", "mu", "clamp", "gap")}
        kw.update(changes)
        return BeamImpact(**kw)

    @property
    def natural_frequency(self) -> float:
        """Linear natural frequency sqrt(k/m)/2pi (Hz) without the stop."""
        return math.sqrt(self.k / self.m) / (2 * math.pi)

    def parameters(self) -> dict:
        return {"model": "BeamImpact", "m": self.m, "k": self.k, "b": self.b,
                "K_hertz": self.K_hertz, "e": self.e, "contact": self.contact,
                "mu": "None" if self.mu is None else self.mu, "clamp": self.clamp,
                **({"gap": self.gap} if self.gap != 0.0 else {})}


@_model_protocol
@dataclass(frozen=True)
class Duffing:
    """m x'' + b x' + k x + k3 x^3 = F cos(2 pi f t): force-excited (the excitation's amplitude
    is the force F in N). m: kg (> 0), b: kg/s (>= 0), k: N/m (>= 0), k3: N/m^3."""

    m: float = 1.0
    b: float = 0.1
    k: float = 1.0
    k3: float = 1.0
    system: System = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        positive("m", self.m, unit="kg")
        nonnegative("b", self.b, unit="kg/s")
        nonnegative("k", self.k, unit="N/m")
        finite("k3", self.k3)
        sysm = System([[self.m]], [[self.b]], [[self.k]], (CubicSpring(0, self.k3),), "force",
                      y_load=[1.0], yd_load=[0.0], output_dof=0, name="Duffing")
        object.__setattr__(self, "system", sysm)

    def parameters(self) -> dict:
        return {"model": "Duffing", "m": self.m, "b": self.b, "k": self.k, "k3": self.k3}
