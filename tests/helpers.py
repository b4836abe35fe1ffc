"""Helpers shared by the test modules (``from helpers import ...``: conftest.py registers this
file as the module ``helpers``). No test module imports another; what two of them need lives
here, each helper group in its own section."""
import contextlib
import os
import shutil
import subprocess

import numpy as np
import pytest
import scipy.optimize
from numba import njit

import nlbeam
from continuation.pathfollow import Problem
from continuation.shooting import Evaluation
from nlbeam import _kernels


# --- continuation: a small harmonic-balance solver for the Duffing oscillator ----------------
# (odd harmonics, alternating frequency/time), the independent method the folds are checked
# against (tests/continuation/test_continuation_paths.py, _diagram.py)
DUFF = dict(m=1.0, b=0.1, k=1.0, k3=1.0)  # the Duffing oscillator of the fold tests
F = 0.2  # its force amplitude (N)


def hb_residual(c, w, H, n_t=128):
    m, b, k, k3 = DUFF["m"], DUFF["b"], DUFF["k"], DUFF["k3"]
    ks = np.arange(1, 2 * H, 2)
    tau = 2 * np.pi * np.arange(n_t) / n_t
    a, bb = c[0::2], c[1::2]
    x = np.cos(np.outer(tau, ks)) @ a + np.sin(np.outer(tau, ks)) @ bb
    fn = k3 * x ** 3
    fa = 2 / n_t * np.cos(np.outer(ks, tau)) @ fn
    fb = 2 / n_t * np.sin(np.outer(ks, tau)) @ fn
    r = np.empty_like(c)
    kk = k - m * (ks * w) ** 2
    r[0::2] = kk * a + b * ks * w * bb + fa - F * (ks == 1)
    r[1::2] = kk * bb - b * ks * w * a + fb
    return r


def hb_jac(c, w, H, n_t=128):
    """Exact dR/dc of hb_residual."""
    m, b, k, k3 = DUFF["m"], DUFF["b"], DUFF["k"], DUFF["k3"]
    ks = np.arange(1, 2 * H, 2)
    tau = 2 * np.pi * np.arange(n_t) / n_t
    basis = np.empty((n_t, 2 * H))
    basis[:, 0::2] = np.cos(np.outer(tau, ks))
    basis[:, 1::2] = np.sin(np.outer(tau, ks))
    x = basis @ c
    J = 2 / n_t * basis.T @ (3 * k3 * x[:, None] ** 2 * basis)
    kk = k - m * (ks * w) ** 2
    for i, kq in enumerate(ks):
        J[2 * i, 2 * i] += kk[i]
        J[2 * i, 2 * i + 1] += b * kq * w
        J[2 * i + 1, 2 * i + 1] += kk[i]
        J[2 * i + 1, 2 * i] -= b * kq * w
    return J


def hb_fold(f_guess, c_guess, H):
    """Fold of the HB equations: R(c, w) = 0, J(c, w) phi = 0, phi . phi0 = 1."""
    w0 = 2 * np.pi * f_guess
    _, _, Vt = np.linalg.svd(hb_jac(c_guess, w0, H))
    phi0 = Vt[-1]
    n = len(c_guess)

    def G(z):
        c, w, phi = z[:n], z[n], z[n + 1:]
        return np.r_[hb_residual(c, w, H), hb_jac(c, w, H) @ phi, phi @ phi0 - 1]

    z, info, ier, msg = scipy.optimize.fsolve(G, np.r_[c_guess, w0, phi0], full_output=True,
                                              xtol=1e-14)
    assert np.max(np.abs(G(z))) < 1e-11, msg
    return z[n] / (2 * np.pi)


def hb_coefficients(model, state0, f, H):
    tr = nlbeam.integrate(model, nlbeam.Harmonic(F, f), 1 / f, dt=1 / (f * 512), x0=state0)
    x = tr.x[:-1, 0]
    X = np.fft.rfft(x) / len(x)
    ks = np.arange(1, 2 * H, 2)
    c = np.empty(2 * H)
    c[0::2] = 2 * X[ks].real
    c[1::2] = -2 * X[ks].imag
    return c


# --- calling the private kernels ------------------------------------------------------------
class KernelCall:
    """The private kernels of one model and excitation, called with the arguments a test
    varies: the system arrays, the excitation's kernel arguments and work arrays of the right
    shapes are filled in (``m`` sensitivity columns, ``kernels``: the kernel package)."""

    def __init__(self, model, excitation, m=1, kernels=_kernels):
        self.K = kernels
        self.sysa = model.kernel_arrays()
        self.xc, self.xp, self.xtab = excitation.kernel_args()
        self.N, self.ne, self.m = model.n_dof, model.n_elements, m

    def _zeros(self, *shape):
        return np.zeros(shape)

    def _stages(self, meth):
        # (from the Python arrays: the kernels run without reference counting, and an array
        # they return to Python, like tableau's, would crash the interpreter)
        return {self.K.RK2: self.K._B_RK2, self.K.RK4: self.K._B_RK4,
                self.K.DP5: self.K._B_DP5}[meth].shape[0]

    def excite(self, t):
        """(y, y', y'', status) at t."""
        return self.K.excite(t, self.xc, self.xp, self.xtab)

    def excite_yyd(self, t):
        return self.K.excite_yyd(t, self.xc, self.xp, self.xtab)

    def kinematics(self, e, s, y, yd):
        return self.K.kinematics(e, s, y, yd, self.sysa)

    def deriv(self, t, s, P, dvm, disc, want_var=False, variant="deriv"):
        """(status, ks, kP, fel) of the right-hand side; variant 'deriv' (with want_var),
        'deriv_plain' or 'deriv_var' (the inlined copies)."""
        n, m = 2 * self.N, P.shape[1]
        ks, kP, fel = self._zeros(n), self._zeros(n, m), self._zeros(self.ne)
        args = (self.sysa, self.xc, self.xp, self.xtab, ks, kP, fel)
        if variant == "deriv":
            st = self.K.deriv(t, s, P, dvm, disc, want_var, *args)
        else:
            st = getattr(self.K, variant)(t, s, P, dvm, disc, *args)
        return st, ks, kP, fel

    def rk_step(self, meth, t, h, s, P, dvm, disc, want_var, f0):
        """(status, s_out, P_out) of one Runge-Kutta step; f0 = f(t, s)."""
        n, m = 2 * self.N, P.shape[1]
        ns = self._stages(meth)
        s_out, P_out = self._zeros(n), self._zeros(n, m)
        st = self.K.rk_step(meth, t, h, s, P, dvm, disc, want_var, self.sysa, self.xc, self.xp,
                            self.xtab, f0, s_out, P_out, self._zeros(ns, n),
                            self._zeros(ns, n, m), self._zeros(n), self._zeros(n, m),
                            self._zeros(self.ne), self._zeros(n))
        return st, s_out, P_out

    def rk_step_graded(self, meth, mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, want_var):
        """(status, t at the end, s_out, P_out) of one graded step (mode 1 onset, 2 exit)."""
        n, m = 2 * self.N, P.shape[1]
        ns = self._stages(meth)
        s_out, P_out = self._zeros(n), self._zeros(n, m)
        st, t_end = self.K.rk_step_graded(
            meth, mode, u0, hu, t_ref, e, s, tcur, P, dvm, disc, want_var, self.sysa, self.xc,
            self.xp, self.xtab, s_out, P_out, self._zeros(ns, n), self._zeros(ns, n, m),
            self._zeros(ns), self._zeros(n), self._zeros(n, m), self._zeros(self.ne))
        return st, t_end, s_out, P_out


# --- a custom force importable by name (its kernels are cached on disk: nlbeam.custom) -------
@njit
def cubic_force(t, x, v, y, yd, params, out):
    """The Duffing spring -k3 x^3 on DOF 0 as a custom force, k3 = params[0]."""
    out[0] -= params[0] * x[0] ** 3


@contextlib.contextmanager
def read_only_folder(path):
    """A folder nobody can write into, at ``path`` (created): mode 0555 for a normal user;
    for root (who writes through modes) a read-only tmpfs mounted there, the test skipped
    only where mounting is impossible. Restored on exit."""
    os.makedirs(path, exist_ok=True)
    if os.geteuid() != 0:
        os.chmod(path, 0o555)
        try:
            yield path
        finally:
            os.chmod(path, 0o755)
        return
    if shutil.which("mount") is None:
        pytest.skip("root writes into read-only folders and there is no mount command")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(path)],
                       capture_output=True)
    if r.returncode:
        pytest.skip(f"root writes into read-only folders; cannot mount a read-only tmpfs: "
                    f"{r.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", str(path)], check=True)


# --- scenes -------------------------------------------------------------------------------------
#: a tiny stochastic analysis (a 1.5 s record of a 0-100 Hz noise), the scene tests' base
TINY_STOCHASTIC = """
[stochastic]
band = [0.0, 100.0]
rms = 1e-4
seed = 1
duration = 1.5
transient = 0.1
psd_resolution = 2.0
"""
#: a tiny diagram (orders 1, 42-45 Hz, three grid frequencies, no error estimates)
TINY_DIAGRAM = """
[periodic]
amplitude = 1e-4
f_range = [42.0, 45.0]
orders = [1]
n_grid = 3
accuracy = "off"
"""
#: a PSD figure and a moments table of it
PSD_FIGURE = """
[[figure]]
kind = "psd"
file = "psd.png"
"""
MOMENTS_TABLE = """
[[table]]
kind = "moments"
file = "moments.csv"
"""


def write_scene(folder, text, name="scene.toml"):
    """The scene file ``name`` in ``folder`` (a pathlib.Path) holding ``text``; its path."""
    p = folder / name
    p.write_text(text)
    return p


class ToyProblem(Problem):
    """Base of the synthetic problems on the tracer's protocol (continuation.pathfollow.Problem)
    that give one monodromy matrix per evaluation: multipliers its eigenvalues, largest modulus
    first (stable order); no adaptation; ``on_branch(u, p)``: the residual's largest entry (for
    the tests' own checks); two unknowns with unit scales; ``side(u)``: which side of the
    switching surface u[0] = 0 the state lies on (0 below, 1 on or above)."""

    def __init__(self):
        self.scale_u = np.ones(2)
        self.scale_p = 1.0

    def side(self, u):
        return int(u[0] >= 0.0)

    def multipliers(self, Ms):
        mu = np.linalg.eigvals(Ms[0])
        return mu[np.argsort(-np.abs(mu), kind="stable")]

    def adapt(self, u, p):
        return None

    def on_branch(self, u, p):
        return float(np.max(np.abs(self.evaluate(u, p, jac=False, jac_p=False).R)))


class ScalarToyProblem(ToyProblem):
    """A ToyProblem whose residual is (r(u, p), -u[1]): ``scalar(u, p)`` gives r and dr/du[0]
    (piecewise in u[0]), ``r_p`` is dr/dp (a constant); Jacobian diag(dr, -1), one monodromy
    I + 0.1 J, the impacts ``side(u)``."""

    r_p = -1.0

    def scalar(self, u, p):
        raise NotImplementedError

    def evaluate(self, u, p, jac=True, jac_p=True):
        r, dr = self.scalar(u, p)
        J = np.array([[dr, 0.0], [0.0, -1.0]])
        return Evaluation(np.array([r, -u[1]]), J if jac else None,
                          self.jacobian_p(u, p) if jac_p else None,
                          [np.eye(2) + 0.1 * J] if jac else [], abs(u[0]), self.side(u))

    def jacobian_p(self, u, p, ev=None):
        return np.array([self.r_p, 0.0])
