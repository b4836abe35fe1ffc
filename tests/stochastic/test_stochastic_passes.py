"""The compiled single passes of the Welch estimator and of the block synthesis give what the
numpy expressions they replaced give, to round-off (two independent computations)."""
import math

import numpy as np
import scipy.fft
from scipy.signal import get_window

from stochastic import _kernels


def test_welch_segments_and_power_equal_the_numpy_expressions():
    rng = np.random.default_rng(12)
    n, step = 1000, 500
    data = 3.0 + rng.normal(size=4 * n)   # a large mean: its removal matters
    w = get_window("hann", n)
    K = (data.size - n) // step + 1
    out = np.empty((K, n))
    assert _kernels.welch_segments(data, 0, step, w, out) == 0
    segs = np.lib.stride_tricks.sliding_window_view(data, n)[::step][:K]
    ref = (segs - segs.mean(axis=1, keepdims=True)) * w
    assert np.max(np.abs(out - ref)) <= 1e-14 * np.max(np.abs(ref))
    # a later first segment (the batches of WelchPSD.update)
    out2 = np.empty((2, n))
    _kernels.welch_segments(data, 2 * step, step, w, out2)
    np.testing.assert_array_equal(out2, out[2:4])
    X = scipy.fft.rfft(ref, axis=1)
    acc = np.zeros(n // 2 + 1)
    _kernels.add_power(X, acc)
    want = np.sum(X.real ** 2 + X.imag ** 2, axis=0)
    assert np.max(np.abs(acc - want)) <= 1e-14 * np.max(want)


def test_carrier_rows_equal_the_complex_product():
    rng = np.random.default_rng(5)
    nr, M, nc, R, f0, h = 6, 540, 531, 8, 0.1234567, 1.03e-4
    half = 0.5 * (R - 1)
    s = rng.normal(size=(nr, M)) + 1j * rng.normal(size=(nr, M))
    out = np.empty((nc, nr))
    assert _kernels.carrier_rows(s, float(M), f0 * h, float(R), half, out) == 0
    cyc = np.mod(f0 * h * (R * np.arange(nc) + half), 1.0)
    ref = (s[:, :nc] * M * np.exp(2j * math.pi * cyc)).real.T
    assert np.max(np.abs(out - ref)) <= 1e-14 * np.max(np.abs(ref))
    # a carrier of many cycles over the block (f0 h R near 1): the phase reduced mod 1 first
    out = np.empty((nc, nr))
    _kernels.carrier_rows(s, float(M), 0.11, float(R), half, out)
    cyc = np.mod(0.11 * (R * np.arange(nc) + half), 1.0)
    ref = (s[:, :nc] * M * np.exp(2j * math.pi * cyc)).real.T
    assert np.max(np.abs(out - ref)) <= 1e-13 * np.max(np.abs(ref))
