"""A multi-mode Euler-Bernoulli beam with an elastic stop (the paper's future work).

``ModalBeam`` reduces a uniform Euler-Bernoulli beam, clamped to the moving frame, to its first
N free-vibration modes (assumed modes / Rayleigh-Ritz with the exact mode shapes of the boundary
conditions) and builds an ``nlbeam.System`` from them: modal damping, base excitation through
the modal participation factors, an elastic stop (``Contact``) at a point along the beam.

Equations (u(s, t): deflection relative to the frame, s in [0, L]; q_i modal coordinates, m)::

    u(s, t) = sum_i phi_i(s / L) q_i(t),        int_0^1 phi_i phi_j dxi = delta_ij
    m_i q_i'' + c_i q_i' + k_i q_i + phi_i(a/L) f = -m_i Gamma_i y''
    m_i = rho A L,  k_i = E I beta_i^4 / L^3,  c_i = 2 zeta_i sqrt(k_i m_i),
    Gamma_i = int_0^1 phi_i dxi  (participation factor of a uniform base translation)

The kernels take y and y' (not y'') on the right-hand side, so the state uses the "absolute
modal" coordinates z = q + Gamma y (M z'' + C z' + K z = K Gamma y + C Gamma y', exact), and the
first generalised coordinate is replaced by the contact-point coordinate
x = sum_i phi_i(a/L) z_i = u(a) + s_N y, with s_N = sum_i phi_i(a/L) Gamma_i (-> 1 as N grows).
DOF 0 is x (the output DOF); DOFs 1..N-1 are z_2..z_N. The penetration of the stop is exact:
delta = u(a) - gap = x - s_N y - gap. For N = 1 this is the paper's SDOF model
m x'' + b x' + k x + f = s_1 (k y + b y'), which is BeamImpact itself where s_1 = 1
(``ModalBeam.paper`` puts the stop there; see docs/modal_beam.md).
Units: SI (m, kg, Pa, kg/m^3, N/m^1.5, s).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from . import _linalg as la
from ._validate import choice, in_range, integer, positive, real_array
from .systems import Contact, System, _model_protocol
from .vocabulary import BOUNDARY_CONDITIONS

MAX_MODES = 20
_QUAD = np.polynomial.legendre.leggauss(240)


def beta_roots(bc, n_modes):
    """Dimensionless roots beta_i L (i = 1..n) of the characteristic equation:
    clamped-free cos(b) cosh(b) = -1, clamped-clamped cos(b) cosh(b) = 1."""
    from scipy.optimize import brentq  # not at module level: it costs `import nlbeam` ~0.5 s

    choice("bc", bc, BOUNDARY_CONDITIONS)
    sgn = 1.0 if bc == "clamped-free" else -1.0
    shift = 0.5 if bc == "clamped-free" else 1.5

    def g(b):  # cos b cosh b + sgn, divided by cosh b (bounded for large b)
        return math.cos(b) + sgn / math.cosh(b)

    out = np.empty(int(n_modes))
    for i in range(int(n_modes)):
        c = (i + shift) * math.pi
        out[i] = brentq(g, c - 0.5, c + 0.5, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return out


def mode_shape(bc, beta, xi):
    """Unnormalised mode shape cosh(b xi) - cos(b xi) - sigma (sinh(b xi) - sin(b xi)) at
    xi = s / L in [0, 1], evaluated without cancellation for large b (dimensionless)."""
    b = float(beta)
    xi = np.asarray(xi, dtype=float)
    em = math.exp(-b)
    if bc == "clamped-free":
        sigma = (math.cosh(b) + math.cos(b)) / (math.sinh(b) + math.sin(b))
        one_minus = (math.sin(b) - math.cos(b) - em) / (math.sinh(b) + math.sin(b))
    else:
        sigma = (math.cosh(b) - math.cos(b)) / (math.sinh(b) - math.sin(b))
        one_minus = (math.cos(b) - math.sin(b) - em) / (math.sinh(b) - math.sin(b))
    bx = b * xi
    return (0.5 * (one_minus * np.exp(bx) + (1.0 + sigma) * np.exp(-bx))
            - np.cos(bx) + sigma * np.sin(bx))


def _quadrature(fun):
    x, w = _QUAD
    return float(np.sum(0.5 * w * fun(0.5 * (x + 1.0))))


@dataclass(frozen=True)
class _FrameStop(Contact):
    """Contact whose penetration sees the frame with weight ``base_weight``:
    delta = w . x - base_weight * y - gap (the modal beam's s_N)."""

    base_weight: float = 1.0

    def arrays(self, n_dof, kind):
        code, w, wy, gap, par = super().arrays(n_dof, kind)
        return code, w, wy * float(self.base_weight), gap, par


@_model_protocol
@dataclass(frozen=True)
class ModalBeam:
    """Uniform Euler-Bernoulli beam clamped to the moving frame, N modes, elastic stop at s = a.

    length: L (m); width, thickness: rectangular section (m), or give I (m^4) and A (m^2)
    instead; E: Young's modulus (Pa); density: kg/m^3; stop_position: a (m), in (0, L] for
    'clamped-free', (0, L) for 'clamped-clamped'; gap: m (negative = preload); zeta: modal
    damping ratio (one value, or one per mode); K_hertz, e, contact, mu, clamp: the stop as in
    BeamImpact. n_modes: N in [1, 20]. bc: 'clamped-free' or 'clamped-clamped'.
    The output DOF 0 is the contact-point coordinate x (m); delta = x - s_N y - gap.
    """

    length: float = 0.4
    width: float | None = 0.02
    thickness: float | None = 1e-3
    E: float = 2.1e11
    density: float = 7850.0
    stop_position: float = 0.3
    n_modes: int = 4
    bc: str = "clamped-clamped"
    zeta: object = 0.0152
    gap: float = 0.0
    K_hertz: float = 2.1e8
    e: float = 0.5
    contact: str = "lankarani-nikravesh"
    mu: float | None = None
    clamp: bool = True
    I: float | None = None
    A: float | None = None
    system: System = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        positive("length", self.length, unit="m")
        integer("n_modes", self.n_modes, 1, MAX_MODES)
        choice("bc", self.bc, BOUNDARY_CONDITIONS)
        L = float(self.length)
        hi_open = self.bc == "clamped-clamped"
        in_range("stop_position", self.stop_position, 0.0, L, lo_open=True, hi_open=hi_open)
        positive("E", self.E, unit="Pa")
        positive("density", self.density, unit="kg/m^3")
        if self.I is not None or self.A is not None:
            if self.I is None or self.A is None:
                raise ValueError("I, A: give both (m^4 and m^2), or width and thickness instead")
            positive("I", self.I, unit="m^4")
            positive("A", self.A, unit="m^2")
        else:
            if self.width is None or self.thickness is None:
                raise ValueError("width, thickness: give both (m), or I and A instead")
            positive("width", self.width, unit="m")
            positive("thickness", self.thickness, unit="m")
        stop = _FrameStop(0, self.contact, self.K_hertz, e=self.e, mu=self.mu, gap=self.gap,
                          clamp=self.clamp)  # validates the stop's parameters
        N = int(self.n_modes)
        z = np.atleast_1d(real_array("zeta", self.zeta, finite_values=False))
        if z.size == 1:
            z = np.full(N, z[0])
        if z.shape != (N,) or not np.all(np.isfinite(z)) or np.any(z < 0):
            raise ValueError(f"zeta: must be one finite value >= 0 or {N} of them (one per mode)")
        object.__setattr__(self, "n_modes", N)
        m, k = self.modal_mass, self.modal_stiffness
        c = 2.0 * z * np.sqrt(k * m)
        gam = self.participation_factors
        ph = self.shape_at(self.stop_position)
        s = la.dot(ph, gam)
        # z = T xi with xi = [x, z_2..z_N], x = phi(a) . z
        T = np.eye(N)
        T[0, 0] = 1.0 / ph[0]
        T[0, 1:] = -ph[1:] / ph[0]
        Md, Kd, Cd = np.diag(np.full(N, m)), np.diag(k), np.diag(c)
        Tt = np.ascontiguousarray(T.T)  # products in a fixed order (la): the same on every CPU
        M = la.matmul(la.matmul(Tt, Md), T)
        K = la.matmul(la.matmul(Tt, Kd), T)
        C = la.matmul(la.matmul(Tt, Cd), T)
        stop = dataclasses.replace(stop, base_weight=s)
        sysm = System(0.5 * (M + M.T), 0.5 * (C + C.T), 0.5 * (K + K.T), (stop,), "base",
                      y_load=la.matmul(Tt, la.matmul(Kd, gam)),
                      yd_load=la.matmul(Tt, la.matmul(Cd, gam)), output_dof=0,
                      name="ModalBeam")
        object.__setattr__(self, "system", sysm)

    # --- geometry and modes ---------------------------------------------------------------
    @property
    def section(self):
        """(I m^4, A m^2) of the cross-section."""
        if self.I is not None:
            return float(self.I), float(self.A)
        w, t = float(self.width), float(self.thickness)
        return w * t ** 3 / 12.0, w * t

    @property
    def betas(self):
        """beta_i L of the N modes (dimensionless)."""
        return beta_roots(self.bc, self.n_modes)

    @property
    def modal_mass(self) -> float:
        """rho A L (kg), the mass of every mode normalised to int_0^1 phi^2 = 1."""
        return float(self.density) * self.section[1] * float(self.length)

    @property
    def modal_stiffness(self) -> np.ndarray:
        """E I beta_i^4 / L^3 (N/m), shape (N,)."""
        I, _ = self.section
        return float(self.E) * I * self.betas ** 4 / float(self.length) ** 3

    @property
    def modal_frequencies(self) -> np.ndarray:
        """Natural frequencies of the beam without the stop (Hz), shape (N,)."""
        return np.sqrt(self.modal_stiffness / self.modal_mass) / (2 * math.pi)

    def shapes(self, s):
        """Mode shapes phi_i(s / L) (dimensionless, int_0^1 phi^2 = 1) at positions s (m):
        shape (..., N)."""
        s = np.asarray(s, dtype=float)
        xi = s / float(self.length)
        if np.any((xi < -1e-12) | (xi > 1 + 1e-12)):
            raise ValueError(f"s: positions must lie in [0, {self.length}] m")
        out = [mode_shape(self.bc, b, xi)
               / math.sqrt(_quadrature(lambda x, b=b: mode_shape(self.bc, b, x) ** 2))
               for b in self.betas]
        return np.stack(out, axis=-1)

    def shape_at(self, s) -> np.ndarray:
        """phi_i at one position s (m), shape (N,)."""
        return self.shapes(np.array([float(s)]))[0]

    @property
    def participation_factors(self) -> np.ndarray:
        """Gamma_i = int_0^1 phi_i dxi (dimensionless), shape (N,)."""
        xg, wg = _QUAD
        xi = 0.5 * (xg + 1.0)
        ph = self.shapes(xi * float(self.length))
        return la.matmul(0.5 * wg, ph)

    @property
    def base_weight(self) -> float:
        """s_N = sum_i phi_i(a/L) Gamma_i: delta = x - s_N y - gap."""
        return la.dot(self.shape_at(self.stop_position), self.participation_factors)

    @property
    def contact_mass(self) -> float:
        """Mass of the first mode seen at the stop, rho A L / phi_1(a/L)^2 (kg)."""
        return self.modal_mass / self.shape_at(self.stop_position)[0] ** 2

    @property
    def contact_stiffness(self) -> float:
        """Stiffness of the first mode seen at the stop, k_1 / phi_1(a/L)^2 (N/m)."""
        return float(self.modal_stiffness[0]) / self.shape_at(self.stop_position)[0] ** 2

    def deflection(self, state, y=0.0):
        """Deflection relative to the frame at the stop, u(a) = x - s_N y (m), from states
        (..., 2N) [x, z_2.., v...] and y (m)."""
        state = np.asarray(state, dtype=float)
        return state[..., 0] - self.base_weight * np.asarray(y, dtype=float)

    def modal_coordinates(self, state, y=0.0):
        """q (..., N) (m) from states (..., 2N) and y: u(s) = shapes(s) @ q."""
        state = np.asarray(state, dtype=float)
        N = self.n_modes
        ph = self.shape_at(self.stop_position)
        zc = np.array(state[..., :N], copy=True)
        zc[..., 0] = (state[..., 0] - state[..., 1:N] @ ph[1:]) / ph[0]
        return zc - np.multiply.outer(np.asarray(y, dtype=float), self.participation_factors)

    # --- construction ------------------------------------------------------------------------
    @classmethod
    def calibrated(cls, m, k, *, bc="clamped-clamped", stop_ratio=None,
                   width=0.02, E=2.1e11, density=7850.0, **kw):
        """A beam whose first mode, seen at the stop, has mass m (kg) and stiffness k (N/m).

        stop_ratio: a / L; None puts the stop where s_1 = phi_1(a/L) Gamma_1 = 1 (there the
        one-mode model is exactly m x'' + b x' + k x + f = k y + b y'). Length and thickness
        follow from m, k, width (m), E (Pa) and density (kg/m^3)."""
        positive("m", m, unit="kg")
        positive("k", k, unit="N/m")
        positive("width", width, unit="m")
        b1 = beta_roots(bc, 1)[0]
        unit = ModalBeam(length=1.0, width=1.0, thickness=1.0, E=1.0, density=1.0,
                         stop_position=0.5, n_modes=1, bc=bc, K_hertz=0.0)
        if stop_ratio is None:
            from scipy.optimize import brentq  # not at module level (see beta_roots)

            gam1 = float(unit.participation_factors[0])

            def s1(r):
                return float(unit.shape_at(r)[0]) * gam1 - 1.0
            hi = 1.0 if bc == "clamped-free" else 0.5
            stop_ratio = brentq(s1, 1e-3, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        hi_open = bc == "clamped-clamped"
        in_range("stop_ratio", stop_ratio, 0.0, 1.0, lo_open=True, hi_open=hi_open)
        p1 = float(unit.shape_at(stop_ratio)[0])
        rhoAL = m * p1 ** 2                      # rho w t L
        EI_L3 = k * p1 ** 2 / b1 ** 4            # E w t^3 / (12 L^3)
        # t L = rhoAL / (rho w);  (t / L)^3 = 12 EI_L3 / (E w)
        tL = rhoAL / (density * width)
        t_over_L = (12.0 * EI_L3 / (E * width)) ** (1.0 / 3.0)
        L = math.sqrt(tL / t_over_L)
        t = t_over_L * L
        return cls(length=L, width=width, thickness=t, E=E, density=density,
                   stop_position=stop_ratio * L, bc=bc, **kw)

    @classmethod
    def paper(cls, n_modes=4, **overrides):
        """Calibrated to the paper (docs/modal_beam.md): steel (E 2.1e11 Pa, 7850 kg/m^3),
        clamped-clamped, 20 mm wide; first mode at the stop m = 37.75e-3 kg, k = 736.3 N/m
        (22.23 Hz); the stop where s_1 = 1, so n_modes = 1 is BeamImpact.paper(); modal damping
        zeta = 0.16 / (2 sqrt(k m)) on every mode; K_hertz 2.1e8 N/m^1.5, e 0.5,
        Lankarani-Nikravesh."""
        m, k, b = 37.75e-3, 736.3, 0.16
        kw = dict(zeta=b / (2.0 * math.sqrt(k * m)), n_modes=n_modes)
        geo = {key: overrides.pop(key) for key in ("bc", "stop_ratio", "width", "E", "density")
               if key in overrides}
        kw.update(overrides)
        return cls.calibrated(m, k, **geo, **kw)

    def replace(self, **changes):
        kw = {f: getattr(self, f) for f in self.__dataclass_fields__ if f != "system"}
        kw.update(changes)
        return ModalBeam(**kw)

    def parameters(self) -> dict:
        I, A = self.section
        z = np.atleast_1d(real_array("zeta", self.zeta, finite_values=False))
        return {"model": "ModalBeam", "n_modes": self.n_modes, "bc": self.bc,
                "length": float(self.length), "I": I, "A": A, "E": float(self.E),
                "density": float(self.density), "stop_position": float(self.stop_position),
                "gap": float(self.gap), "zeta": ",".join(repr(float(v)) for v in z),
                "K_hertz": float(self.K_hertz), "e": float(self.e), "contact": self.contact,
                "mu": "None" if self.mu is None else float(self.mu), "clamp": bool(self.clamp)}
