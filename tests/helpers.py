"""Helpers shared by the test modules (importable as ``from helpers import ...``: conftest.py
puts this folder on sys.path). No test module imports another; what two of them need lives
here, each helper group in its own section."""
import numpy as np
import scipy.optimize

import nlbeam


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
