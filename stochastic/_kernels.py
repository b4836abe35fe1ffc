"""Compiled kernels of the stochastic package.

Every kernel takes arrays, writes into preallocated ``out`` arrays and returns an integer
status (0 = ok, 1 = a non-finite sample was met). No random numbers, no error handling
beyond the status: the Python wrappers validate and turn status codes into messages.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

OK = 0
NON_FINITE = 1

_CHUNK = 256  # partial sums over chunks of this length keep summation error ~ (256 + n/256) eps


@njit(cache=True)
def block_moments(x, out):
    """Central moment sums of ``x``: out = [n, mean, M2, M3, M4], M_p = sum (x - mean)^p.

    Two passes: a provisional mean m0, then power sums of d = x - m0 (exact subtractions
    when x is near m0), shifted to the corrected mean. Stable for |mean| >> std.
    """
    n = x.size
    out[0] = n
    if n == 0:
        out[1] = 0.0
        out[2] = 0.0
        out[3] = 0.0
        out[4] = 0.0
        return OK
    total = 0.0
    i = 0
    while i < n:
        part = 0.0
        j_end = min(i + _CHUNK, n)
        for j in range(i, j_end):
            v = x[j]
            if not math.isfinite(v):
                return NON_FINITE
            part += v
        total += part
        i = j_end
    m0 = total / n
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    s4 = 0.0
    i = 0
    while i < n:
        p1 = 0.0
        p2 = 0.0
        p3 = 0.0
        p4 = 0.0
        j_end = min(i + _CHUNK, n)
        for j in range(i, j_end):
            d = x[j] - m0
            d2 = d * d
            p1 += d
            p2 += d2
            p3 += d2 * d
            p4 += d2 * d2
        s1 += p1
        s2 += p2
        s3 += p3
        s4 += p4
        i = j_end
    dl = s1 / n
    out[1] = m0 + dl
    m2 = s2 - n * dl * dl
    if m2 < 0.0:
        m2 = 0.0
    out[2] = m2
    out[3] = s3 - 3.0 * dl * s2 + 2.0 * n * dl * dl * dl
    out[4] = s4 - 4.0 * dl * s3 + 6.0 * dl * dl * s2 - 3.0 * n * dl * dl * dl * dl
    return OK


@njit(cache=True)
def bin_index(v, edges, nb, lo, w, uniform):
    """The bin k of a value ``v`` inside [edges[0], edges[nb]] of nb bins (the last closed, as
    np.histogram): for (nearly) uniform edges (lo = edges[0], width w) guessed from the width
    and corrected against the edges themselves; otherwise found by bisection."""
    if v == edges[nb]:
        return nb - 1
    if uniform:
        k = int((v - lo) / w)
        if k > nb - 1:
            k = nb - 1
        while k > 0 and v < edges[k]:
            k -= 1
        while k < nb - 1 and v >= edges[k + 1]:
            k += 1
        return k
    k = 0
    b = nb
    while b - k > 1:
        m = (k + b) // 2
        if v >= edges[m]:
            k = m
        else:
            b = m
    return k


@njit(cache=True)
def histogram_count(x, edges, uniform, counts, outside):
    """Count ``x`` into the bins of increasing ``edges`` (last bin closed, as np.histogram).

    ``counts`` (n_bins,) and ``outside`` ([below, above]) are incremented in place; the bin
    of a value as :func:`bin_index`.
    """
    nb = counts.size
    lo = edges[0]
    hi = edges[nb]
    w = (hi - lo) / nb
    for j in range(x.size):
        v = x[j]
        if not math.isfinite(v):
            return NON_FINITE
        if v < lo:
            outside[0] += 1
        elif v > hi:
            outside[1] += 1
        else:
            counts[bin_index(v, edges, nb, lo, w, uniform)] += 1
    return OK


@njit(cache=True)
def cosine_sum_grid(t0, h, omega, amp, phase, y, yd, ydd):
    """Direct sum y = sum a cos(w t + phi) and its two derivatives at t0 + j h (O(K n))."""
    n = y.size
    for j in range(n):
        t = t0 + j * h
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        for k in range(omega.size):
            arg = omega[k] * t + phase[k]
            c = math.cos(arg)
            s = math.sin(arg)
            s0 += amp[k] * c
            s1 -= amp[k] * omega[k] * s
            s2 -= amp[k] * omega[k] * omega[k] * c
        y[j] = s0
        yd[j] = s1
        ydd[j] = s2
    return OK


@njit(cache=True)
def all_finite(x):
    """Index of the first non-finite entry of ``x``, or -1."""
    for j in range(x.size):
        if not math.isfinite(x[j]):
            return j
    return -1


@njit(cache=True)
def batch_sums(x, size, out):
    """Per-batch sums of consecutive batches of ``size`` samples of ``x`` (x.size a multiple
    of size): out[k] = [n, mean, M2, M3, M4, n_positive] of batch k (central sums as
    :func:`block_moments`; n_positive counts samples > 0). Returns NON_FINITE on a bad
    sample."""
    buf = np.empty(5)
    nb = x.size // size
    for k in range(nb):
        seg = x[k * size: (k + 1) * size]
        st = block_moments(seg, buf)
        if st != OK:
            return st
        npos = 0
        for j in range(seg.size):
            if seg[j] > 0.0:
                npos += 1
        out[k, 0] = buf[0]
        out[k, 1] = buf[1]
        out[k, 2] = buf[2]
        out[k, 3] = buf[3]
        out[k, 4] = buf[4]
        out[k, 5] = npos
    return OK


@njit(cache=True)
def histogram_count_batches(x, edges, uniform, bc, row, fill, size, counts, outside, state):
    """Count ``x`` into the histogram ``counts`` and into the fine-batch rows ``bc[row:]``
    (``fill`` samples already in row ``row``; a row holds ``size`` samples), as
    :func:`histogram_count` does per sample. Stops when the last row of ``bc`` would be
    reached with a full batch (the caller merges rows and calls again). state (out): [samples
    consumed, row, fill] (fill may equal size: the caller closes that row). Returns
    NON_FINITE on a bad sample."""
    nb = counts.size
    lo = edges[0]
    hi = edges[nb]
    w = (hi - lo) / nb
    last = bc.shape[0] - 1
    j = 0
    n = x.size
    while j < n:
        if fill == size:
            row += 1
            fill = 0
            if row == last:
                break
        v = x[j]
        if not math.isfinite(v):
            return NON_FINITE
        if v < lo:
            outside[0] += 1
        elif v > hi:
            outside[1] += 1
        else:
            k = bin_index(v, edges, nb, lo, w, uniform)
            counts[k] += 1
            bc[row, k] += 1
        fill += 1
        j += 1
    state[0] = j
    state[1] = row
    state[2] = fill
    return OK


@njit(cache=True)
def taylor_nodes(D, T, scale, out):
    """out[c R + r, q] = scale[q] sum_n D[c, q + n] T[n, r], n = 0 .. P (T: (P + 1, R)),
    q = 0 .. scale.size - 1: the fine values of z, z', z'', ... from their Taylor series about
    each coarse node c, node-major (rows are a block's table; noise._lines_nodes). One pass,
    no temporaries; the terms summed in the order of n. Returns OK."""
    nc = D.shape[0]
    P1, R = T.shape
    nq = scale.size
    if nq == 4:  # a noise block's z, z', z'', z'''
        return _taylor_nodes4(D, T, scale, out)
    for c in range(nc):
        base = c * R
        for r in range(R):
            for q in range(nq):
                acc = 0.0
                for n in range(P1):
                    acc += D[c, q + n] * T[n, r]
                out[base + r, q] = acc * scale[q]
    return OK


@njit(cache=True)
def _taylor_nodes4(D, T, scale, out):
    """taylor_nodes for four columns, their sums interleaved (each still in the order of n, so
    the same doubles): the four additions of a term are independent, where one sum at a time
    waits for each addition's latency."""
    nc = D.shape[0]
    P1, R = T.shape
    s0, s1, s2, s3 = scale[0], scale[1], scale[2], scale[3]
    for c in range(nc):
        base = c * R
        for r in range(R):
            a0 = 0.0
            a1 = 0.0
            a2 = 0.0
            a3 = 0.0
            for n in range(P1):
                tn = T[n, r]
                a0 += D[c, n] * tn
                a1 += D[c, n + 1] * tn
                a2 += D[c, n + 2] * tn
                a3 += D[c, n + 3] * tn
            out[base + r, 0] = a0 * s0
            out[base + r, 1] = a1 * s1
            out[base + r, 2] = a2 * s2
            out[base + r, 3] = a3 * s3
    return OK


@njit(cache=True)
def fade_join(zi, zp, win, out):
    """out[j] = the cross-faded y, y', y'', y''' (rows of ``zi``, ``zp``: the new and the
    previous realization's z, z', z'', z''' at the fade's nodes j) with the windows ``win``
    (8, n) = (w_in, its 3 derivatives, w_out, its 3 derivatives), by the product rule as
    ``_BlockNoise.block_table`` wrote it with numpy (the same operations in the same order).
    Returns OK."""
    for j in range(out.shape[0]):
        w0 = win[0, j]
        w1 = win[1, j]
        w2 = win[2, j]
        w3 = win[3, j]
        v0 = win[4, j]
        v1 = win[5, j]
        v2 = win[6, j]
        v3 = win[7, j]
        a0 = zi[j, 0]
        a1 = zi[j, 1]
        a2 = zi[j, 2]
        a3 = zi[j, 3]
        b0 = zp[j, 0]
        b1 = zp[j, 1]
        b2 = zp[j, 2]
        b3 = zp[j, 3]
        out[j, 0] = w0 * a0 + v0 * b0
        out[j, 1] = w1 * a0 + w0 * a1 + v1 * b0 + v0 * b1
        out[j, 2] = (w2 * a0 + 2.0 * w1 * a1 + w0 * a2
                     + v2 * b0 + 2.0 * v1 * b1 + v0 * b2)
        out[j, 3] = (w3 * a0 + 3.0 * w2 * a1 + 3.0 * w1 * a2 + w0 * a3
                     + v3 * b0 + 3.0 * v2 * b1 + 3.0 * v1 * b2 + v0 * b3)
    return OK


@njit(cache=True)
def welch_segments(data, first, step, window, out):
    """out[k] = (segment - its mean) * window for the segments data[first + k step:][:n],
    k = 0 .. out.shape[0] - 1, n = window.size (one pass each instead of numpy's temporaries;
    the mean summed in chunks of _CHUNK as block_moments). Returns OK."""
    n = window.size
    for k in range(out.shape[0]):
        a = first + k * step
        total = 0.0
        for c in range(0, n, _CHUNK):
            part = 0.0
            for j in range(a + c, a + min(c + _CHUNK, n)):
                part += data[j]
            total += part
        mean = total / n
        for j in range(n):
            out[k, j] = (data[a + j] - mean) * window[j]
    return OK


@njit(cache=True)
def add_power(X, acc):
    """acc[f] += sum_k |X[k, f]|^2 (the periodograms of a batch of segments, unscaled)."""
    for k in range(X.shape[0]):
        for f in range(X.shape[1]):
            v = X[k, f]
            acc[f] += v.real * v.real + v.imag * v.imag
    return OK


@njit(cache=True)
def carrier_rows(s, scale, f0h, R, half, out):
    """out[j, q] = Re(scale s[q, j] exp(2 pi i cyc_j)), cyc_j = (f0h (R j + half)) mod 1,
    j = 0 .. out.shape[0] - 1: the coarse-grid line sums of noise._lines_nodes moved back
    to their carrier frequency, node-major, in one pass (numpy: five temporaries of the whole
    array). Returns OK."""
    nr = out.shape[1]
    for j in range(out.shape[0]):
        c = f0h * (R * j + half)
        c -= math.floor(c)
        ph = 2.0 * math.pi * c
        cr = math.cos(ph)
        ci = math.sin(ph)
        for q in range(nr):
            v = s[q, j]
            out[j, q] = (v.real * scale) * cr - (v.imag * scale) * ci
    return OK
