"""nlbeam._linalg: small dense linear algebra in a fixed order of operations, so that a
diagram does not depend on which BLAS/LAPACK kernels OpenBLAS picks for the CPU
(OPENBLAS_CORETYPE). Exact answers, agreement with numpy within round-off, and the same
results, bit for bit, under two OpenBLAS core types (in subprocesses)."""
import os
import platform
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import nlbeam
from nlbeam import _linalg as la
from nlbeam.modal import ModalBeam
from nlbeam.systems import Contact, System


def test_exact_answers():
    A = np.array([[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [4.0, 0.0, 2.0]])  # needs pivoting
    x = np.array([1.0, -2.0, 3.0])
    assert np.array_equal(la.solve(A, A @ x), x)
    assert la.det(A) == -8.0 and la.det_sign(A) == -1.0
    assert la.det_sign(-A) == 1.0
    assert np.array_equal(la.solve(A, np.column_stack([A @ x, 2 * A @ x])),
                          np.column_stack([x, 2 * x]))
    assert np.array_equal(la.matmul(A, la.inv(A) * 6.0).round(12), 6.0 * np.eye(3))
    assert la.norm(np.ldexp([3.0, 4.0], 700)) == np.ldexp(5.0, 700)  # no overflow of squares
    assert la.norm(np.ldexp([3.0, -4.0], -700)) == np.ldexp(5.0, -700)
    assert np.array_equal(la.norm(np.array([[3.0, 4.0], [0.0, -2.0]])), [5.0, 2.0])
    assert la.dot(np.array([1.0, 2.0]), np.array([3.0, -4.0])) == -5.0
    with pytest.raises(np.linalg.LinAlgError):
        la.solve(np.array([[1.0, 2.0], [2.0, 4.0]]), np.ones(2))
    assert la.det_sign(np.array([[1.0, 2.0], [2.0, 4.0]])) == 0.0


def test_eigenvalues_exact():
    # companion matrix of (x - 1)(x + 2)(x - 3)(x^2 + 4) = x^5 - 2x^4 - x^3 - 2x^2 - 20x + 24:
    # roots 1, -2, 3, +-2i; an exact similarity by diag(2^-20 ... 2^20) (balancing has work)
    c = np.array([-2.0, -1.0, -2.0, -20.0, 24.0])
    Cm = np.zeros((5, 5))
    Cm[0] = -c
    Cm[1:, :-1] = np.eye(4)
    s = np.ldexp(1.0, np.arange(-20, 30, 10))
    A = Cm * s[:, None] / s[None, :]
    mu = la.eigvals(A)
    for w in [3.0, -2.0, 1.0, 2j, -2j]:
        assert np.min(np.abs(mu - w)) < 1e-13
    pair = mu[np.abs(mu.imag) > 0.5]
    assert pair[0].imag > 0 and pair[1] == np.conj(pair[0])  # (a + ib, a - ib), b > 0
    lam, V = la.eig(A)
    assert np.allclose(la.norm(V.T.real) ** 2 + la.norm(V.T.imag) ** 2, 1.0, rtol=1e-14)
    assert np.max(np.abs(A @ V - V * lam)) < 1e-10 * np.max(np.abs(A))
    R2 = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    assert np.allclose(la.eigvals(R2), [np.exp(0.3j), np.exp(-0.3j)], rtol=0, atol=1e-15)
    t = la.null_vector(np.array([[1.0, 2.0, 2.0], [0.0, 1.0, -1.0]]))
    assert np.allclose(np.abs(t), np.array([4.0, 1.0, 1.0]) / np.sqrt(18.0), rtol=0, atol=1e-15)
    assert np.allclose(t[1:] / t[0], [-0.25, -0.25], rtol=0, atol=1e-15)
    Q, R = la.qr(np.array([[3.0, 1.0], [4.0, 2.0]]))
    assert np.allclose(R, [[-5.0, -2.2], [0.0, 0.4]], rtol=0, atol=1e-15)
    assert np.allclose(Q, [[-0.6, -0.8], [-0.8, 0.6]], rtol=0, atol=1e-15)


def test_agrees_with_numpy_within_roundoff():
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 7, 21):
        A = rng.normal(size=(n, n)) + n * np.eye(n)
        B = rng.normal(size=(n, 4))
        b = B[:, 0]
        assert np.allclose(la.solve(A, b), np.linalg.solve(A, b), rtol=1e-12, atol=1e-14)
        assert np.allclose(la.solve(A, B), np.linalg.solve(A, B), rtol=1e-12, atol=1e-14)
        assert np.isclose(la.det(A), np.linalg.det(A), rtol=1e-12)
        assert np.allclose(la.matmul(A, B), A @ B, rtol=1e-13, atol=1e-13)
        assert np.allclose(la.matmul(A, b), A @ b, rtol=1e-13, atol=1e-13)
        assert np.allclose(la.matmul(b, A), b @ A, rtol=1e-13, atol=1e-13)
        assert np.isclose(la.norm(b), np.linalg.norm(b), rtol=1e-14)
        assert np.allclose(la.norm(B.T), np.linalg.norm(B.T, axis=1), rtol=1e-14)
        G = rng.normal(size=(n, n)) * np.logspace(-3, 3, n)[:, None]
        mu, mu0 = la.eigvals(G), np.linalg.eigvals(G)
        assert max(np.min(np.abs(mu0 - m)) for m in mu) < 1e-11 * np.max(np.abs(mu0))
        assert max(np.min(np.abs(mu - m)) for m in mu0) < 1e-11 * np.max(np.abs(mu0))
        J = rng.normal(size=(n, n + 1))
        t, t0 = la.null_vector(J), np.linalg.svd(J)[2][-1]
        assert np.isclose(la.norm(t), 1.0, rtol=1e-15) and np.allclose(J @ t, 0.0, atol=1e-13)
        assert np.allclose(t * np.sign(la.dot(t, t0)), t0, atol=1e-12)
        if n > 1:  # nearly singular: s_min 1e-6 s_next
            U0, sv, Vt0 = np.linalg.svd(A)
            S = (U0 * np.r_[sv[:-1], 1e-6 * sv[-2]]) @ Vt0
            u, v = la.smallest_singular_vectors(S)
            assert abs(abs(la.dot(u, U0[:, -1])) - 1.0) < 1e-12
            assert abs(abs(la.dot(v, Vt0[-1])) - 1.0) < 1e-12
        Q, R = la.qr(B)
        Q0, R0 = np.linalg.qr(B)
        assert np.allclose(Q, Q0, atol=1e-13) and np.allclose(R, R0, atol=1e-13)


def _has_avx2():
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return False
    try:
        with open("/proc/cpuinfo") as f:
            return " avx2" in f.read()
    except OSError:
        return False


def _run(coretype, code):
    env = dict(os.environ, OPENBLAS_CORETYPE=coretype)
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env,
                         capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout.strip().splitlines()[-1]


_ROUTINES = """
    import numpy as np
    from nlbeam import _linalg as la
    rng = np.random.default_rng(3)
    A = rng.normal(size=(9, 9)); B = rng.normal(size=(9, 9)); b = rng.normal(size=9)
    out = np.r_[la.solve(A, b), la.matmul(A, B).ravel(), la.norm(b), la.dot(b, A[0]), la.det(A),
                la.eigvals(A), la.eig(A)[1].ravel(), la.qr(A)[0].ravel(),
                la.null_vector(A[:8])]
    print(out.tobytes().hex())
"""

_SCENE = """
    import hashlib, warnings
    import numpy as np
    import continuation as C, nlbeam
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = C.frequency_response(nlbeam.BeamImpact.paper(), 1e-4, (12.3, 14.2),
                                   orders=(1, 2), n_grid=4)
    h = hashlib.sha256()
    for b in frc.branches:
        h.update(np.ascontiguousarray(b.frequency).tobytes())
        h.update(np.ascontiguousarray(b.values).tobytes())
    for b in frc.bifurcations:
        h.update(np.float64(b.frequency).tobytes())
    print(len(frc.branches), sum(len(b.frequency) for b in frc.branches),
          len(frc.bifurcations), h.hexdigest())
"""

needs_avx2 = pytest.mark.skipif(not _has_avx2(), reason="the OpenBLAS core types compared "
                                "(Prescott: SSE3, Haswell: AVX2 + FMA) need an x86-64 CPU with "
                                "AVX2")


@needs_avx2
def test_routines_are_the_same_under_two_openblas_core_types():
    assert _run("Prescott", _ROUTINES) == _run("Haswell", _ROUTINES)


@pytest.mark.slow
@needs_avx2
def test_diagram_is_the_same_under_two_openblas_core_types():
    """The switched-branch scene (paper model, 12.3-14.2 Hz, orders 1-2) gives the same
    branches and bifurcations, bit for bit, with OpenBLAS's SSE3 kernels as with its
    AVX2/FMA ones (before nlbeam._linalg it did not: see the commit)."""
    a, b = _run("Prescott", _SCENE), _run("Haswell", _SCENE)
    assert a == b


def test_resonance_peak_of_three_points_is_exact():
    """continuation.diagram._vertex (the parabola through three branch points, solved by
    _linalg instead of numpy.polyfit): symmetric points peak at the middle one; a parabola
    sampled at three points is reproduced exactly."""
    from continuation.diagram import _vertex
    assert _vertex(np.array([9.0, 10.0, 11.0]), np.array([1.0, 2.0, 1.0])) == (10.0, 2.0)
    f = np.array([10.0, 10.5, 11.0])
    x = np.array([1.0, 2.0, 1.5])
    F, X = f / f[1], x / x[1]
    s = np.r_[0.0, np.cumsum(np.hypot(np.diff(F), np.diff(X)))]
    cx, cf = np.polyfit(s, x, 2), np.polyfit(s, f, 2)
    s_star = -cx[1] / (2 * cx[0])
    assert np.allclose(_vertex(f, x), (np.polyval(cf, s_star), np.polyval(cx, s_star)),
                       rtol=1e-13)


# --- the kernel arrays of a System and the modal beam's matrices (nlbeam.systems, nlbeam.modal)
# come from this module too: the same bits under two core types (with numpy's BLAS they differed
# for N > 1, so a multi-DOF model's diagram was traced with other matrices on another CPU);
# exact where the arithmetic is exact, within round-off of numpy elsewhere.

FIELDS = ("Minv", "MinvK", "MinvC", "mek", "mec", "mw")


def _two_dof():
    return System([[1.0, 0.1], [0.1, 2.0]], [[0.3, -0.1], [-0.1, 0.2]],
                  [[40.0, -10.0], [-10.0, 30.0]], (Contact(1, "hertz", 1e6),), "base")


def test_one_dof_arrays_are_the_quotients():
    """N = 1: M^-1 = 1/m and each product one multiplication (what numpy's LAPACK / BLAS gave
    too: the paper model's kernels are unchanged bit for bit)."""
    p = nlbeam.BeamImpact.paper()
    a = p.system.kernel_arrays()
    inv = 1.0 / p.m
    assert a.Minv[0, 0] == inv and a.MinvK[0, 0] == inv * p.k and a.MinvC[0, 0] == inv * p.b
    assert a.mek[0] == inv * p.k and a.mec[0] == inv * p.b and a.mw[0, 0] == inv
    assert p.natural_frequencies()[0] == pytest.approx(p.natural_frequency, rel=1e-15)


def test_exact_where_the_arithmetic_is_exact():
    """Masses and stiffnesses in powers of two: every product and quotient is exact."""
    s = System([[2.0, 0.0], [0.0, 4.0]], [[0.5, -0.25], [-0.25, 1.0]], [[8.0, -2.0], [-2.0, 16.0]],
               (Contact(1, "hertz", 1e6),), "base")
    a = s.kernel_arrays()
    assert np.array_equal(a.Minv, [[0.5, 0.0], [0.0, 0.25]])
    assert np.array_equal(a.MinvK, [[4.0, -1.0], [-0.5, 4.0]])
    assert np.array_equal(a.mek, [3.0, 3.5]) and np.array_equal(a.mec, [0.125, 0.1875])
    assert np.array_equal(a.mw, [[0.0, 0.25]])
    d, dd = s.penetration(np.array([[1.0, 3.0, 0.5, -2.0]]), y=1.0, yd=0.5)
    assert d.shape == (1, 1) and d[0, 0] == 2.0 and dd[0, 0] == -2.5  # x1 - y, v1 - y'


@pytest.mark.parametrize("make", [_two_dof, lambda: ModalBeam.calibrated(37.75e-3, 736.3,
                                                                          n_modes=4)])
def test_agree_with_numpy_within_round_off(make):
    m = make()
    s, a = m.system, m.system.kernel_arrays()
    Minv = np.linalg.inv(s.M)
    ref = {"Minv": Minv, "MinvK": Minv @ s.K, "MinvC": Minv @ s.C, "mek": Minv @ s.y_load,
           "mec": Minv @ s.yd_load, "mw": s.element_geometry()[1] @ Minv.T}
    for f in FIELDS:
        scale = np.max(np.abs(ref[f]))
        assert np.max(np.abs(getattr(a, f) - ref[f])) <= 1e-13 * scale, f
    w = np.sqrt(np.abs(np.linalg.eigvals(np.linalg.solve(s.M, s.K)).real)) / (2 * np.pi)
    assert np.allclose(m.natural_frequencies(), np.sort(w), rtol=1e-12)


_ARRAYS = """
    import numpy as np
    from nlbeam.modal import ModalBeam
    from nlbeam.systems import Contact, System
    ms = [System([[1.0, 0.1], [0.1, 2.0]], [[0.3, -0.1], [-0.1, 0.2]],
                 [[40.0, -10.0], [-10.0, 30.0]], (Contact(1, "hertz", 1e6),), "base")]
    ms += [ModalBeam.calibrated(37.75e-3, 736.3, n_modes=n) for n in (2, 4)]
    out = []
    for m in ms:
        a = m.system.kernel_arrays()
        out += [np.ravel(getattr(a, f)) for f in ("Minv", "MinvK", "MinvC", "mek", "mec", "mw")]
        out += [m.system.M.ravel(), m.system.K.ravel(), m.system.C.ravel(),
                m.system.y_load, m.natural_frequencies()]
    print(np.concatenate(out).tobytes().hex())
"""


@needs_avx2
def test_kernel_arrays_are_the_same_under_two_openblas_core_types():
    """A 2-DOF system and the 2- and 4-mode beams (with numpy's BLAS, MinvC, mec, and the
    modal beams' MinvK, mek, y_load differed in their last bits between these two)."""
    assert _run("Prescott", _ARRAYS) == _run("Haswell", _ARRAYS)
