"""Gaussian excitations synthesized block by block (spectral representation).

Units: time s, frequency Hz. The excitation's own unit is written u below: m for a base
motion (the usual case), N for a force-excited system (``nlbeam.System(...,
excitation_kind="force")``); a one-sided PSD is in u^2/Hz and an rms in u.

Method (Shinozuka's spectral representation, computed by FFT)
-------------------------------------------------------------
The record is cut into blocks ``[i B, (i+1) B]`` (``B = block_duration``). Block ``i`` uses
its own independent realization

    z_i(tau) = sum_k a_k cos(2 pi f_k tau + phi_k),  tau = t - i B,
    f_k = f_lo + (k + u_i) df,  k = 0 .. ceil((f_hi - f_lo)/df) - 1,

with ``phi_k ~ U[0, 2 pi)`` and a random line offset ``u_i ~ U[0, 1)`` drawn from the block's
own child seed (``SeedSequence(seed, spawn_key=(i,))``), so any block can be regenerated
alone. ``G`` is zero outside the band. Averaged over ``u_i`` the lines cover every cell
``[f_lo + k df, f_lo + (k+1) df)`` uniformly, so the expected PSD of ``z_i`` equals ``G(f)``
at every frequency (not only at the lines); ``z_i`` never repeats within its span (its
envelope period ``1/df`` exceeds ``B + L``).

Synthesis is two steps, kept apart so that a faster evaluation can replace the second
without touching the statistics: (1) :meth:`components` draws the line spectrum of a block
(offset, phases, amplitudes, scaling: every statistical property lives here);
(2) :func:`lines_on_grid` evaluates that line sum and its first three derivatives on the
grid ``tau_j = j h`` (complex FFTs on a coarser grid, ``z = Re[exp(2 pi i (f_lo + u df) tau)
* N ifft(c)]``, refined by Taylor series).

Line variances and the rms
--------------------------
Line k carries the variance ``s_k = G(f_k) df`` (u^2). When an ``rms`` is requested, every
block's line variances are scaled so that ``sum_k s_k = rms^2`` exactly (to rounding) for
that block's offset ``u_i``: the variance of the synthesized process is the requested one
for any PSD (tables, narrow peaks, steep slopes) with no quadrature at all, and the scale
depends on ``u_i`` only, so the process stays Gaussian. Without ``rms`` the lines carry
``G(f_k) df`` as given and the variance averaged over ``u`` is the integral of ``G``.
A PSD with structure narrower than ``df`` (a peak the lines can straddle) makes
``sum_k s_k`` vary with ``u``: a warning says so (an error if some offset sees no power),
and a longer ``block_duration`` (df = 1/(block + fade) roughly) resolves it.

Amplitudes: ``amplitudes="random"`` (the default) gives ``a_k = sqrt(2 s_k E_k)`` with
``E_k ~ Exp(1)`` (Rayleigh amplitudes): ``z_i`` is then exactly a Gaussian process, so the
response of any linear system is Gaussian at every resonance, however few lines fall
inside it, and Welch estimates scatter as chi-square predicts. ``amplitudes=
"deterministic"`` (the paper's method, for reproducing the paper) gives ``a_k =
sqrt(2 s_k)``: every block's line spectrum is the target exactly, a sample is Gaussian only
through the central limit over the lines, and a linear response whose resonance spans few
lines is sub-Gaussian: its kurtosis is low by about ``1.5 sum_k w_k^2 / (sum_k w_k)^2``
(w_k the response's line variances; ``3 df / (2 pi bw)`` for a resonance of half-power
bandwidth bw, 0.16 for the paper's beam under 0-200 Hz). ``stochastic.simulate`` warns when
the line spacing is too coarse for the model's damping (:meth:`kurtosis_bias`). The phases
and offsets are the same in both modes for the same seed.

Consecutive realizations are joined over the first ``L = fade_duration`` seconds of each
block by the power-complementary pair ``w_in = sin(pi/2 g(s))``, ``w_out = cos(pi/2 g(s))``,
``s = (t - i B)/L``, ``g(s) = s^4 (35 - 84 s + 70 s^2 - 20 s^3)``: ``w_in^2 + w_out^2 = 1``
keeps the variance that of the blocks (``rms^2`` exactly when requested), and ``g' = g'' =
g''' = 0`` at both ends make ``y`` and its first three derivatives (the quintic table's
columns) continuous across joins; ``y' = w' z + w z'`` and
``y'' = w'' z + 2 w' z' + w z''`` (and ``y''' = w''' z + 3 w'' z' + 3 w' z'' + w z'''``) are
exact (product rule). Across a join the covariance
at lag tau is ``R(tau) cos(theta(t) - theta(t + tau))`` instead of ``R(tau)``; averaged
over a block this smooths the PSD by a kernel of width ~ 1/B Hz (band edges only; a flat
band interior is unchanged).

Grid step and interpolation accuracy
------------------------------------
A block is a quintic ``nlbeam.Sampled`` table (columns y, y', y'', y'''): y is interpolated
by the quintic Hermite polynomial through (y, y', y'') at both ends of a cell and y' by the
one through (y', y'', y'''); the error in a cell [a, b] is ``y^(6)(xi)/6! (t-a)^3 (t-b)^3``,
at most ``h^6/46080 max|y^(6)|``. For a signal band-limited to ``f_max``, Bernstein's
inequality gives ``max|y^(6)| <= (2 pi f_max)^6 max|y|``, hence

    |y_interp - y| <= (2 pi f_max h)^6 / 46080 * max|y|   (and the same bound for y',
    relative to 2 pi f_max max|y|).

The default ``h`` makes this bound ``interp_tol = 1e-10``:
``h = (46080 interp_tol)^(1/6) / (2 pi f_max) ~ 0.0205 / f_max`` (:func:`quintic_step`; the
cubic Hermite tables used before needed ``(384 interp_tol)^(1/4) / (2 pi f_max) ~ 0.00223 /
f_max``, :func:`hermite_step`: 9.2x more nodes). The cross-fade windows widen the band by
~ 1/L Hz, a relative change of the bound of order 1/(L f_max). (With the former quintic
smoothstep fade, y''' jumped by (pi/2) 60/L^3 |z| at the fade's ends and moved y' there by
~0.017 h^2 of that: 60x the bound for a 0.2 s fade at 80 Hz; the septic one has no jump.)
"""
from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np
import scipy.fft
import scipy.special

from nlbeam._validate import (ArgumentTypeError, check_memory, choice, finite, positive,
                              real_array)
from nlbeam.excitation import CosineSum, Excitation, Sampled

from . import _kernels

__all__ = ["BandLimitedNoise", "SpectralNoise", "Realization", "Recorded", "hermite_step",
           "quintic_step",
           "lines_on_grid", "AMPLITUDES"]

#: amplitude laws of the block synthesis (see the module doc)
AMPLITUDES = ("random", "deterministic")

_DEFAULT_INTERP_TOL = 1e-10
_DEFAULT_BLOCK_SAMPLES = 2 ** 18  # of a cubic table (Realization.blocks)
# of a block noise's quintic table: 28672 h = 2.94 s at 200 Hz, the span (2.92 s) of the
# former default, 2**18 steps of the cubic grid
_DEFAULT_NOISE_BLOCK_SAMPLES = 28_672
_MAX_TABLE_SAMPLES = 50_000_000
_N_OFFSETS = 32  # line offsets u sampled to check how well the lines resolve a PSD


def hermite_step(f_max, interp_tol=_DEFAULT_INTERP_TOL):
    """Grid step h (s) at which cubic Hermite interpolation of a signal band-limited to
    ``f_max`` (Hz) errs by at most ``interp_tol * max|y|``: (2 pi f_max h)^4/384 = interp_tol."""
    positive("f_max", f_max, unit="Hz")
    positive("interp_tol", interp_tol)
    return (384.0 * interp_tol) ** 0.25 / (2.0 * math.pi * f_max)


def quintic_step(f_max, interp_tol=_DEFAULT_INTERP_TOL):
    """Grid step h (s) at which quintic Hermite interpolation of a signal band-limited to
    ``f_max`` (Hz) errs by at most ``interp_tol * max|y|``: (2 pi f_max h)^6/46080 = interp_tol
    (the error is y^(6)(xi)/6! (t - a)^3 (t - b)^3 in a cell [a, b], and |y^(6)| <= (2 pi
    f_max)^6 max|y| by Bernstein's inequality)."""
    positive("f_max", f_max, unit="Hz")
    positive("interp_tol", interp_tol)
    return (46080.0 * interp_tol) ** (1.0 / 6.0) / (2.0 * math.pi * f_max)


def _seed_entropy(seed):
    if seed is None:
        return int(np.random.SeedSequence().entropy)
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise ValueError(f"seed: must be a non-negative integer or None, got {seed!r}")
    if seed < 0:
        raise ValueError(f"seed: must be a non-negative integer or None, got {seed!r}")
    return int(seed)


def _check_band(band):
    if isinstance(band, (str, bytes, dict)):
        raise ArgumentTypeError(f"band: must be a pair (f_lo, f_hi) in Hz with 0 <= f_lo < f_hi, "
                                f"got {band!r}")
    try:
        lo, hi = band
    except (TypeError, ValueError):
        raise ValueError(f"band: must be a pair (f_lo, f_hi) in Hz with 0 <= f_lo < f_hi, got "
                         f"{band!r}") from None
    lo = finite("band", lo)
    hi = finite("band", hi)
    if lo < 0 or not hi > lo:
        raise ValueError(f"band: must satisfy 0 <= f_lo < f_hi (Hz), got ({lo!r}, {hi!r})")
    return lo, hi


def _int64_or_str(v):
    return int(v) if v < 2 ** 63 else str(v)


def _amplitude_law(amplitudes, random_amplitudes):
    """The amplitude law from ``amplitudes`` ('random' | 'deterministic') and the older
    boolean ``random_amplitudes`` (kept for existing scripts; None when not given)."""
    if random_amplitudes is not None:
        if not isinstance(random_amplitudes, (bool, np.bool_)):
            raise ValueError(f"random_amplitudes: must be True or False, got {random_amplitudes!r}")
        old = "random" if random_amplitudes else "deterministic"
        if amplitudes is not None and amplitudes != old:
            raise ValueError(f"amplitudes: {amplitudes!r} contradicts random_amplitudes="
                             f"{random_amplitudes!r}; give only amplitudes=")
        return old
    if amplitudes is None:
        return "random"
    if amplitudes not in AMPLITUDES:
        raise ValueError(f"amplitudes: must be one of {', '.join(map(repr, AMPLITUDES))}, "
                         f"got {amplitudes!r}")
    return amplitudes


_TAYLOR_REACH = 0.6  # max omega_max * (half a coarse cell) of the coarse-grid synthesis
_TAYLOR_TOL = 1e-16  # truncation bound of its Taylor series, relative to max|z|
_MAX_DECIMATION = 128


def _decimation(n_fft, wh):
    """Largest divisor R <= 128 of n_fft with wh R / 2 <= _TAYLOR_REACH (wh = omega_max h,
    rad), and the Taylor order P with reach^(P+1)/(P+1)! <= _TAYLOR_TOL; (1, 0) if none > 3."""
    best = 1
    for r in range(4, _MAX_DECIMATION + 1):
        if n_fft % r == 0 and wh * r / 2.0 <= _TAYLOR_REACH:
            best = r
    if best == 1:
        return 1, 0
    x = wh * best / 2.0
    p, term = 0, x
    while term > _TAYLOR_TOL:
        p += 1
        term *= x / (p + 1)
    return best, p


def _lines_direct(f0, df, coeffs, h, m, n_fft, n_deriv=2):
    """lines_on_grid by n_deriv + 1 inverse FFTs of length n_fft on the fine grid (reference)."""
    K = coeffs.size
    c = np.zeros((n_deriv + 1, n_fft), dtype=complex)
    w = 2.0 * math.pi * (f0 + df * np.arange(K))
    c[0, :K] = coeffs
    for q in range(1, n_deriv + 1):
        c[q, :K] = c[q - 1, :K] * (1j * w)
    s = scipy.fft.ifft(c, axis=1, overwrite_x=True)[:, :m] * n_fft
    cyc = np.mod(f0 * h * np.arange(m), 1.0)
    return (s * np.exp(2j * math.pi * cyc)).real


def lines_on_grid(f0, df, coeffs, h, m, n_fft, n_deriv=2):
    """The line sum z(tau) = Re sum_k c_k exp(2 pi i (f0 + k df) tau) and its first
    ``n_deriv`` derivatives at tau_j = j h, j = 0 .. m - 1 (s): array (n_deriv + 1, m) in u,
    u/s, u/s^2, ... (the transpose of :func:`_lines_nodes`, which says how).

    coeffs: complex c_k = a_k exp(i phi_k) (u), k = 0 .. K - 1, K <= n_fft; n_fft h must
    exceed the span (m - 1) h and equal 1/df. This is the inner loop of the block synthesis:
    any method with the same output to ~1e-12 relative may replace it without changing a
    statistic."""
    return _lines_nodes(f0, df, coeffs, h, m, n_fft, n_deriv).T


def _lines_nodes(f0, df, coeffs, h, m, n_fft, n_deriv=2):
    """:func:`lines_on_grid` node-major: array (m, n_deriv + 1), row j = (z, z', ...) at j h.

    Method: z and its derivatives up to order P + n_deriv on a coarse grid of step R h (R a
    divisor of n_fft, the grid nodes at the centres of runs of R fine nodes) by inverse
    FFTs of length n_fft / R (lines folded mod n_fft / R, exact), then every fine value by
    the Taylor series of order P about its centre: z^(q)(tau_c + d) = sum_n z^(q+n)(tau_c)
    d^n / n! (a compiled loop, _kernels.taylor_nodes). With omega_max R h / 2 <= 0.6 the
    truncation is below 1e-16 max|z| (Bernstein: |z^(n)| <= omega_max^n max|z|). Where no
    such R divides n_fft: n_deriv + 1 inverse FFTs of length n_fft on the fine grid."""
    coeffs = np.asarray(coeffs, dtype=complex)
    K = coeffs.size
    w = 2.0 * math.pi * (f0 + df * np.arange(K))
    wmax = float(np.max(np.abs(w))) if K else 0.0
    R, P = _decimation(n_fft, max(wmax, 2.0 * math.pi * abs(f0)) * h)
    if R == 1:
        return np.ascontiguousarray(_lines_direct(f0, df, coeffs, h, m, n_fft, n_deriv).T)
    M = n_fft // R
    nc = -(-m // R)
    half = 0.5 * (R - 1)
    # spectrum rows d_n = c_k (i w_k h)^n exp(2 pi i k df tau_off), folded mod M
    iwh = 1j * w * h
    base = coeffs * np.exp(2j * math.pi * np.mod(np.arange(K) * (half / n_fft), 1.0))
    nr = P + 1 + n_deriv
    powers = iwh[None, :] ** np.arange(nr)[:, None]
    spec = np.zeros((nr, M), dtype=complex)
    rows = powers * base[None, :]
    if K <= M:
        spec[:, :K] = rows
    else:
        pad = -(-K // M) * M
        full = np.zeros((nr, pad), dtype=complex)
        full[:, :K] = rows
        spec[:] = full.reshape(nr, -1, M).sum(axis=1)
    s = scipy.fft.ifft(spec, axis=1, overwrite_x=True)
    # times M and the carrier exp(2 pi i f0 tau_c) at the coarse nodes tau_c = (R c + half) h,
    # node-major (nc, nr), in one compiled pass
    D = np.empty((nc, nr))
    _kernels.carrier_rows(s, float(M), f0 * h, float(R), half, D)
    d = np.arange(R) - half
    n = np.arange(P + 1)
    T = d[None, :] ** n[:, None] / scipy.special.factorial(n)[:, None]  # (P + 1, R)
    out = np.empty((nc * R, n_deriv + 1))
    # a compiled loop (not BLAS: a threaded BLAS spins on a loaded machine, 4x the CPU; not
    # einsum: its generic loop cost 58 % of the synthesis), node-major rows (a block's table)
    _kernels.taylor_nodes(D, np.ascontiguousarray(T), h ** -np.arange(n_deriv + 1.0), out)
    return out[:m]


class _BlockNoise(Excitation):
    """Common machinery: block grid, seeds, line spectra, FFT synthesis, cross-fades.
    Subclasses provide ``_G(f)`` (target one-sided PSD on the band, vectorized, u^2/Hz),
    ``variance`` (u^2) and ``_rms_target`` (u, or None: lines carry G df unscaled), then
    call ``_check_lines()``."""

    def _setup(self, band, seed, duration, h, block_duration, fade_duration, interp_tol,
               amplitudes=None, random_amplitudes=None):
        self.band = _check_band(band)
        self.amplitudes = _amplitude_law(amplitudes, random_amplitudes)
        self.seed = _seed_entropy(seed)
        if duration is not None:
            duration = positive("duration", duration, unit="s")
        self.duration = duration
        self.interp_tol = positive("interp_tol", interp_tol)
        if h is None:
            h = quintic_step(self.band[1], self.interp_tol)
        else:
            h = positive("h", h, unit="s")
            if self.band[1] * h >= 0.5:
                raise ValueError(f"h: must be < 1/(2 f_hi) = {0.5 / self.band[1]:.6g} s "
                                 f"for the band {self.band} Hz, got {h!r}")
        self.h = float(h)
        if block_duration is None:
            # the default block's duration, whatever h: 28672 steps of the default step
            nb = max(int(round(_DEFAULT_NOISE_BLOCK_SAMPLES
                               * quintic_step(self.band[1], self.interp_tol) / self.h)), 16)
        else:
            block_duration = positive("block_duration", block_duration, unit="s")
            nb = int(round(block_duration / self.h))
            if nb < 16:
                raise ValueError(f"block_duration: must be >= 16 h = {16 * self.h:.6g} s, got "
                                 f"{block_duration!r}")
        self.n_block = nb
        if fade_duration is None:
            nf = nb // 2
        else:
            fade_duration = positive("fade_duration", fade_duration, unit="s")
            nf = int(round(fade_duration / self.h))
            if not 2 <= nf <= nb:
                raise ValueError(f"fade_duration: must lie in [2 h, block_duration] = "
                                 f"[{2 * self.h:.6g}, {nb * self.h:.6g}] s, got {fade_duration!r}")
        self.n_fade = nf
        # one realization spans n_block + n_fade steps; FFT length N with N h = 1/df > span
        self.n_fft = scipy.fft.next_fast_len(nb + nf + 2)
        self.df = 1.0 / (self.n_fft * self.h)
        self.n_lines = int(math.ceil((self.band[1] - self.band[0]) / self.df))
        # one realization: the complex spectrum, the real signal and its derivatives
        check_memory(f"block synthesis: FFTs of {self.n_fft:.3g} points", 80.0 * self.n_fft,
                     "give a shorter block_duration, or a larger h")
        self._cache = OrderedDict()

    @property
    def random_amplitudes(self) -> bool:
        """True for Rayleigh amplitudes (``amplitudes == 'random'``)."""
        return self.amplitudes == "random"

    def _line_frequencies(self, u):
        """Line frequencies (Hz), shape (number of offsets, n_lines), for the offsets ``u``."""
        u = np.atleast_1d(np.asarray(u, dtype=float))[:, None]
        return self.band[0] + (np.arange(self.n_lines) + u) * self.df

    def _raw_line_variances(self, f):
        """G(f_k) df (u^2, the PSD as given, before any rms scaling) at line frequencies
        ``f``, zero outside [f_lo, f_hi); checked finite and >= 0."""
        g = np.zeros(f.shape)
        inside = (f >= self.band[0]) & (f < self.band[1])
        g[inside] = self._G(f[inside])
        if not np.all(np.isfinite(g)) or np.any(g < 0):
            bad = f[~(np.isfinite(g) & (g >= 0))][0]
            raise ValueError(f"psd: must be finite and >= 0 on the band, got "
                             f"{float(self._G(np.array([bad]))[0]):.6g} at {float(bad):.9g} Hz")
        return g * self.df

    def _check_lines(self):
        """How well the lines resolve the PSD: the per-block line variance sum over
        ``_N_OFFSETS`` offsets u. Raises if some offset sees no power (cannot be scaled to the
        rms), warns if the sum varies by more than a factor 1.5 (structure narrower than df)."""
        u = (np.arange(_N_OFFSETS) + 0.5) / _N_OFFSETS
        tot = self._raw_line_variances(self._line_frequencies(u)).sum(axis=-1)
        self._offset_sums = tot
        hint = (f"the PSD has structure narrower than the line spacing df = {self.df:.4g} Hz; "
                f"give a longer block_duration (now {self.block_duration:.4g} s; df is about "
                f"1/(block_duration + fade_duration))")
        if not np.all(tot > 0):
            raise ValueError(f"psd: some line offsets see no power at all: {hint}")
        ratio = float(tot.max() / tot.min())
        if ratio > 1.5:
            import warnings

            warnings.warn(f"psd: the variance carried by the lines varies by a factor "
                          f"{ratio:.3g} from block to block: {hint}", RuntimeWarning, stacklevel=3)

    # -- public description ------------------------------------------------------------
    @property
    def block_duration(self) -> float:
        """Duration B (s) of one block (n_block steps of h)."""
        return self.n_block * self.h

    @property
    def fade_duration(self) -> float:
        """Duration L (s) of the cross-fade at the start of every block after the first."""
        return self.n_fade * self.h

    @property
    def realization_duration(self) -> float:
        """Span (s) of one block's realization, block + fade: its random line amplitudes hold
        this long (the slowest time scale of the synthesized process; ~ 1/df)."""
        return (self.n_block + self.n_fade) * self.h

    @property
    def rms(self) -> float:
        """rms of the synthesized process (u) = sqrt(variance)."""
        return math.sqrt(self.variance)

    def psd(self, f):
        """Target one-sided PSD G(f) (u^2/Hz) at the frequencies ``f`` (Hz); 0 outside the
        band. With a requested rms, each block's lines are scaled by a factor within a
        fraction of a per cent of 1 for a PSD the lines resolve (see the module doc)."""
        f = np.asarray(f, dtype=float)
        out = np.zeros(f.shape)
        inside = (f >= self.band[0]) & (f <= self.band[1])
        if np.any(inside):
            out[inside] = self._psd_scale * self._G(f[inside])
        return out

    def max_frequency(self) -> float:
        return float(self.band[1])

    def check_band_vs_step(self, dt):
        """Raise ValueError unless the band lies below the Nyquist frequency 1/(2 dt) of a
        sampling/integration step ``dt`` (s)."""
        dt = positive("dt", dt, unit="s")
        nyq = 0.5 / dt
        if not self.band[1] < nyq:
            raise ValueError(f"dt: step {dt:.6g} s has Nyquist frequency {nyq:.6g} Hz, not above "
                             f"the band's upper edge {self.band[1]:.6g} Hz; use dt < "
                             f"{0.5 / self.band[1]:.6g} s "
                             f"or lower band")

    def describe(self) -> dict:
        return {"kind": type(self).__name__, "band_lo": float(self.band[0]),
                "band_hi": float(self.band[1]), "rms": float(self.rms),
                "variance": float(self.variance), "seed": _int64_or_str(self.seed),
                "duration": float(self.duration) if self.duration is not None else "none",
                "h": self.h, "block_duration": self.block_duration,
                "fade_duration": self.fade_duration, "df_lines": self.df,
                "interp_tol": self.interp_tol, "amplitudes": self.amplitudes,
                "random_amplitudes": self.random_amplitudes,
                "rms_scaled_per_block": self._rms_target is not None,
                "method": "spectral-representation blocks, FFT, "
                "random line offset, sin/cos cross-fades"}

    # -- synthesis ------------------------------------------------------------------------
    def components(self, i):
        """The line spectrum of block ``i``: dict with ``frequencies`` (Hz), ``amplitudes``
        (u), ``phases`` (rad) referred to the local time ``tau = t - t_ref``, ``t_ref`` (s),
        ``offset`` u_i, and ``line_variances`` s_k (u^2): the expected variance of each line
        (a_k^2 / 2 for deterministic amplitudes, its mean for Rayleigh ones). With a requested
        rms, ``line_variances.sum() == rms**2`` to rounding."""
        i = self._block_index(i)
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(i,)))
        u = rng.random()
        phases = 2.0 * math.pi * rng.random(self.n_lines)
        f = self._line_frequencies(u)[0]
        s = self._raw_line_variances(f)
        if self._rms_target is not None:
            s *= self._rms_target ** 2 / s.sum()
        amps = np.sqrt(2.0 * s)
        if self.random_amplitudes:
            amps *= np.sqrt(rng.standard_exponential(self.n_lines))
        return {"frequencies": f, "amplitudes": amps, "phases": phases,
                "t_ref": i * self.block_duration, "offset": u, "line_variances": s}

    def kurtosis_bias(self, f_n, zeta):
        """Predicted bias of the kurtosis of a linear mode's response (natural frequency
        ``f_n`` Hz, damping ratio ``zeta``) caused by the line spectrum, averaged over the
        line offsets: ``3 var_u(S)/mean_u(S)^2`` (the response variance S(u) = sum_k w_k
        changes with the offset: a scale mixture of Gaussians) minus, for deterministic
        amplitudes, ``1.5 mean_u(sum_k w_k^2 / S^2)`` (a sum of few sinusoids is
        sub-Gaussian); w_k = s_k / ((f_n^2 - f_k^2)^2 + (2 zeta f_n f_k)^2). An estimate
        (the cross-fades mix two blocks and roughly halve the second term)."""
        positive("f_n", f_n, unit="Hz")
        positive("zeta", zeta)
        u = (np.arange(_N_OFFSETS) + 0.5) / _N_OFFSETS
        f = self._line_frequencies(u)
        s = self._raw_line_variances(f)
        if self._rms_target is not None:
            s = s / s.sum(axis=-1, keepdims=True)
        w = s / ((f_n ** 2 - f ** 2) ** 2 + (2.0 * zeta * f_n * f) ** 2)
        S = w.sum(axis=-1)
        if not np.all(S > 0):
            return math.nan
        bias = 3.0 * float(np.var(S) / np.mean(S) ** 2)
        if not self.random_amplitudes:
            bias -= 1.5 * float(np.mean((w ** 2).sum(axis=-1) / S ** 2))
        return bias

    def _block_index(self, i):
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)) or i < 0:
            raise ValueError(f"i: block index must be an integer >= 0, got {i!r}")
        return int(i)

    def _realization(self, i):
        """z_i, z_i', z_i'', z_i''' (columns) on tau_j = j h, j = 0 .. n_block + n_fade (a small
        LRU cache holds the last realizations and blocks: memory stays that of a few blocks)."""
        if i in self._cache:
            self._cache.move_to_end(i)
            return self._cache[i]
        comp = self.components(i)
        a, ph, u = comp["amplitudes"], comp["phases"], comp["offset"]
        z = _lines_nodes(self.band[0] + u * self.df, self.df, a * np.exp(1j * ph), self.h,
                         self.n_block + self.n_fade + 1, self.n_fft, n_deriv=3)
        self._cache[i] = z
        while len(self._cache) > 4:
            self._cache.popitem(last=False)
        return z

    def _fade(self):
        """(8, n_fade + 1): w_in, w_out and their first three derivatives on the fade's nodes
        (rows w_in, w_in', w_in'', w_in''', w_out, ...), computed once per noise (the same
        for every block)."""
        if "_fade_tables" not in self.__dict__:
            win, wout = self._fade_compute()
            self._fade_tables = np.array(win + wout)
        return self._fade_tables

    def _fade_compute(self):
        nf = self.n_fade
        L = self.fade_duration
        s = np.arange(nf + 1) / nf
        # septic smoothstep: g', g'', g''' vanish at both ends (y''' continuous at the joins,
        # as the quintic interpolation of y' assumes)
        g = s ** 4 * (35.0 - 84.0 * s + 70.0 * s * s - 20.0 * s ** 3)
        g1 = 140.0 * (s * (1.0 - s)) ** 3 / L
        g2 = 420.0 * (s * (1.0 - s)) ** 2 * (1.0 - 2.0 * s) / (L * L)
        g3 = 840.0 * s * (1.0 - s) * (1.0 - 5.0 * s + 5.0 * s * s) / (L * L * L)
        th = 0.5 * math.pi * g
        th1 = 0.5 * math.pi * g1
        th2 = 0.5 * math.pi * g2
        th3 = 0.5 * math.pi * g3
        sn, cs = np.sin(th), np.cos(th)
        win = (sn, cs * th1, -sn * th1 * th1 + cs * th2,
               -cs * th1 ** 3 - 3.0 * sn * th1 * th2 + cs * th3)
        wout = (cs, -sn * th1, -cs * th1 * th1 - sn * th2,
                sn * th1 ** 3 - 3.0 * cs * th1 * th2 - sn * th3)
        return win, wout

    def block_table(self, i):
        """(t_start, table) of block ``i``: the table (n_block + 1, 4) holds y, y', y'', y'''
        (m, m/s, m/s^2, m/s^3) on ``t_start + j h``, j = 0 .. n_block."""
        i = self._block_index(i)
        key = ("block", i)
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        nb, nf = self.n_block, self.n_fade
        z = self._realization(i)
        if i == 0:
            tab = z[: nb + 1]  # a view of the cached realization (nothing writes into it)
        else:
            tab = np.empty((nb + 1, 4))
            tab[nf + 1:] = z[nf + 1: nb + 1]
            zp = self._realization(i - 1)[nb: nb + nf + 1]
            # y = w_in z_i + w_out z_(i-1) and its derivatives (product rule), compiled
            _kernels.fade_join(z[: nf + 1], zp, self._fade(), tab[: nf + 1])
        res = (i * self.block_duration, tab)
        self._cache[key] = res
        while len(self._cache) > 4:
            self._cache.popitem(last=False)
        return res

    def block_arrays(self, i):
        """(t_start, y, y', y'') of block ``i`` on ``t_start + j h``, j = 0 .. n_block
        (s, m, m/s, m/s^2; views of :meth:`block_table`, which also holds y''')."""
        t0, tab = self.block_table(i)
        return t0, tab[:, 0], tab[:, 1], tab[:, 2]

    def block(self, i) -> Sampled:
        """Block ``i`` as ``nlbeam.Sampled`` (a quintic table) on [i B, (i+1) B] (s)."""
        t0, tab = self.block_table(i)
        return Sampled.from_table(t0, self.h, tab, max_freq=float(self.band[1]))

    def blocks(self, t_start=0.0, t_end=None, block_duration=None):
        """Yield ``nlbeam.Sampled`` tables covering [t_start, t_end] (s) block by block.

        Consecutive tables share their boundary node; the first and last are trimmed to the
        grid nodes enclosing the span. ``block_duration`` must be None or equal to the
        noise's own (it is fixed when the noise is made, since it determines the numbers).
        Memory: one block (plus two cached realizations), whatever the span."""
        if (block_duration is not None
                and abs(float(block_duration) - self.block_duration) > 0.5 * self.h):
            raise ValueError(f"block_duration: the noise was made with block_duration="
                             f"{self.block_duration!r} s; pass that or None, got "
                             f"{block_duration!r}")
        t_start, t_end = self._span(t_start, t_end)
        B = self.block_duration
        i0 = int(math.floor(t_start / B))
        i1 = max(i0, int(math.ceil(t_end / B)) - 1)
        for i in range(i0, i1 + 1):
            tb, tab = self.block_table(i)
            ja = 0
            jb = self.n_block
            if i == i0:
                ja = min(max(int(math.floor((t_start - tb) / self.h + 1e-9)), 0), jb - 1)
            if i == i1:
                jb = max(min(int(math.ceil((t_end - tb) / self.h - 1e-9)), jb), ja + 1)
            yield Sampled.from_table(tb + ja * self.h, self.h, tab[ja: jb + 1],
                                     max_freq=float(self.band[1]))

    def _span(self, t_start, t_end):
        t_start = finite("t_start", t_start)
        if t_start < 0:
            raise ValueError(f"t_start: must be >= 0 s (the noise starts at t = 0), "
                             f"got {t_start!r}")
        if t_end is None:
            if self.duration is None:
                raise ValueError("t_end: required when the noise has no duration")
            t_end = self.duration
        t_end = finite("t_end", t_end)
        if not t_end > t_start:
            raise ValueError(f"t_end: must be > t_start = {t_start!r} s, got {t_end!r}")
        return t_start, t_end

    def sampled(self, t_end=None, t_start=0.0) -> Sampled:
        """One ``nlbeam.Sampled`` covering [t_start, t_end] (s); memory grows with the span,
        so use :meth:`blocks` for long records."""
        t_start, t_end = self._span(t_start, t_end)
        n = (t_end - t_start) / self.h
        if n > _MAX_TABLE_SAMPLES:
            raise ValueError(f"t_end: a single table of {n:.3g} samples is too large; iterate "
                             f"noise.blocks() or use stochastic.simulate")
        parts = list(self.blocks(t_start, t_end))
        if len(parts) == 1:
            return parts[0]
        t0 = parts[0].t_start
        tab = np.concatenate([parts[0].tab] + [p.tab[1:] for p in parts[1:]])
        return Sampled.from_table(t0, self.h, tab, max_freq=float(self.band[1]))

    def kernel_args(self):
        """Kernel arrays of ``sampled(duration)`` (built once), so that a noise with a
        ``duration`` can be passed to ``nlbeam.integrate`` directly."""
        if "_table" not in self.__dict__:
            if self.duration is None:
                raise ValueError("duration: a noise without duration cannot be integrated as one "
                                 "table; give duration= or use stochastic.simulate")
            self._table = self.sampled(self.duration)
        return self._table.kernel_args()

    def time_span(self):
        return (0.0, self.duration) if self.duration is not None else (0.0, math.inf)

    def __repr__(self):
        d = self.describe()
        keys = ("band_lo", "band_hi", "rms", "seed")
        return f"{type(self).__name__}(" + ", ".join(f"{k}={d[k]!r}" for k in keys) + ")"


class SpectralNoise(_BlockNoise):
    """Zero-mean Gaussian noise with any one-sided PSD on a band.

    psd: callable ``f (Hz, array) -> G (u^2/Hz)``, or a table ``(f, G)`` interpolated
    linearly (it must cover the band); u is the excitation's unit (m for base motion, N for
    a force). band: ``(f_lo, f_hi)`` Hz, ``0 <= f_lo < f_hi``.
    rms: if given (u), every block's line variances are scaled to sum to ``rms^2`` exactly
    (the synthesized process has this rms for any PSD; no quadrature is involved).
    seed: non-negative int (None draws one, reported by ``describe()``).
    duration: record length (s) used by default by ``sampled``/``blocks``/``simulate``.
    amplitudes: 'random' (default, Rayleigh: a Gaussian process) or 'deterministic' (the
    paper's method, for reproducing the paper); ``random_amplitudes`` (bool) is the older
    spelling. h, block_duration, fade_duration, interp_tol: see the module doc.
    """

    def __init__(self, psd, band, *, rms=None, seed=None, duration=None, h=None,
                 block_duration=None, fade_duration=None, interp_tol=_DEFAULT_INTERP_TOL,
                 amplitudes=None, random_amplitudes=None):
        self._setup(band, seed, duration, h, block_duration, fade_duration, interp_tol,
                    amplitudes, random_amplitudes)
        lo, hi = self.band
        if callable(psd):
            self._table_f = None
            self._fn = psd
            probe = np.linspace(lo, hi, 1001)
            try:
                g = psd(probe)
            except Exception as exc:
                raise ValueError(f"psd: the callable raised {type(exc).__name__}: {exc} when "
                                 f"called with an array of {probe.size} frequencies on the band "
                                 f"{self.band} Hz") from exc
            g = real_array("psd", g, finite_values=False)
            if g.shape != probe.shape:
                g = np.broadcast_to(g, probe.shape)
            if not np.all(np.isfinite(g)) or np.any(g < 0):
                raise ValueError("psd: must return finite values >= 0 (u^2/Hz) on the band")
        else:
            if isinstance(psd, (str, bytes, dict)):
                raise ArgumentTypeError(f"psd: must be a callable f -> G or a table (f, G), got "
                                        f"{type(psd).__name__}")
            try:
                f_tab, g_tab = (np.asarray(a, dtype=float) for a in psd)
            except (TypeError, ValueError):
                raise ValueError("psd: must be a callable f -> G or a table (f, G)") from None
            if f_tab.ndim != 1 or f_tab.shape != g_tab.shape or f_tab.size < 2:
                raise ValueError("psd: table (f, G) must be two 1-D arrays of one length >= 2")
            if not (np.all(np.isfinite(f_tab)) and np.all(np.isfinite(g_tab))):
                raise ValueError("psd: table (f, G) must be finite")
            if np.any(np.diff(f_tab) <= 0):
                raise ValueError("psd: table frequencies must be strictly increasing")
            if np.any(g_tab < 0):
                raise ValueError("psd: table values G must be >= 0 u^2/Hz")
            if f_tab[0] > lo or f_tab[-1] < hi:
                raise ValueError(f"psd: table covers [{f_tab[0]}, {f_tab[-1]}] Hz, must cover "
                                 f"band {self.band}")
            self._table_f = (f_tab, g_tab)
            self._fn = None
        self._psd_scale = 1.0
        if rms is not None:
            rms = positive("rms", rms, unit="(m or N, the excitation's unit)")
        self._rms_target = rms
        self._rms_given = rms
        self._check_lines()
        raw_var = self._integral()
        if rms is not None:
            self._psd_scale = rms * rms / raw_var  # for psd() only: the lines are scaled per block
            self.variance = rms * rms
        else:
            self.variance = raw_var

    def _integral(self):
        """Integral of the PSD as given over the band (u^2): exact for a table (trapezoid on
        its knots); for a callable, adaptive quadrature at relative tolerance 1e-11, checked
        against the mean line variance sum over the offsets (which a peak narrower than the
        quadrature's sampling cannot escape): if they differ by more than 1 %, the latter."""
        lo, hi = self.band
        lines = float(np.mean(self._offset_sums))
        if self._fn is None:
            f_tab, g_tab = self._table_f
            inner = f_tab[(f_tab > lo) & (f_tab < hi)]
            knots = np.concatenate([[lo], inner, [hi]])
            return float(np.trapezoid(np.interp(knots, f_tab, g_tab), knots))  # exact: linear G
        import warnings

        from scipy.integrate import IntegrationWarning, quad

        fn = self._fn
        # the line frequencies of offset 1/2 as breakpoints: quad sees every cell
        pts = self._line_frequencies(0.5)[0]
        pts = pts[(pts > lo) & (pts < hi)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IntegrationWarning)
            val = 0.0
            edges = np.concatenate([[lo], pts[::64], [hi]])
            for a, b in zip(edges[:-1], edges[1:]):
                v, _ = quad(lambda f: float(np.asarray(fn(np.array([f])), float).ravel()[0]),
                            a, b, epsabs=0.0, epsrel=1e-11, limit=200,
                            points=pts[(pts > a) & (pts < b)] if b - a > 0 else None)
                val += v
        if not (val > 0 and abs(val - lines) <= 0.01 * lines):
            return lines
        return float(val)

    def _G(self, f):
        if self._fn is not None:
            g = np.asarray(self._fn(f), dtype=float)
            if g.shape != f.shape:
                g = np.broadcast_to(g, f.shape).copy()
        else:
            g = np.interp(f, *self._table_f)
        return g

    def describe(self):
        d = super().describe()
        d["psd_source"] = "callable" if self._fn is not None else "table"
        d["rms_given"] = float(self._rms_given) if self._rms_given is not None else "none"
        return d


class BandLimitedNoise(_BlockNoise):
    """Zero-mean Gaussian noise, one-sided PSD flat on ``band``, optionally seen through a
    first-order low-pass: ``G(f) = psd_level / (1 + (f/lowpass)^2)`` for f in the band.

    band: ``(f_lo, f_hi)`` Hz, ``0 <= f_lo < f_hi``. Exactly one of ``rms`` (u, of the
    filtered signal; every block's lines are scaled to it exactly) or ``psd_level`` (u^2/Hz,
    the flat level before the filter); u is the excitation's unit: m for base motion, N for
    a force-excited system. lowpass: corner frequency (Hz) or None. seed: non-negative int
    (None draws one). duration: record length (s). amplitudes: 'random' (default, Rayleigh:
    a Gaussian process) or 'deterministic' (the paper's method, for reproducing the paper);
    ``random_amplitudes`` (bool) is the older spelling. h, block_duration, fade_duration,
    interp_tol: see the module doc.
    """

    def __init__(self, band, rms=None, psd_level=None, seed=None, lowpass=None, duration=None, *,
                 h=None, block_duration=None, fade_duration=None, interp_tol=_DEFAULT_INTERP_TOL,
                 amplitudes=None, random_amplitudes=None):
        self._setup(band, seed, duration, h, block_duration, fade_duration, interp_tol,
                    amplitudes, random_amplitudes)
        lo, hi = self.band
        if (rms is None) == (psd_level is None):
            raise ValueError("rms, psd_level: give exactly one of rms (m) or psd_level (m^2/Hz)")
        if lowpass is not None:
            lowpass = positive("lowpass", lowpass, unit="Hz")
            bw = lowpass * (math.atan(hi / lowpass) - math.atan(lo / lowpass))
        else:
            bw = hi - lo
        self.lowpass = lowpass
        self._equiv_band = bw  # integral of |H|^2 over the band (Hz)
        if rms is not None:
            rms = positive("rms", rms, unit="(m or N, the excitation's unit)")
            psd_level = rms * rms / bw
        else:
            psd_level = positive("psd_level", psd_level, unit="(m^2/Hz or N^2/Hz)")
        self.psd_level = float(psd_level)
        self._psd_scale = 1.0
        self._rms_target = rms
        self._check_lines()
        self.variance = rms * rms if rms is not None else self.psd_level * bw

    def _G(self, f):
        if self.lowpass is None:
            return np.full(f.shape, self.psd_level)
        return self.psd_level / (1.0 + (f / self.lowpass) ** 2)

    def describe(self):
        d = super().describe()
        d["psd_level"] = self.psd_level
        d["lowpass"] = float(self.lowpass) if self.lowpass is not None else "none"
        return d


class Realization(CosineSum):
    """An explicit sum of cosines ``y = sum a_k cos(2 pi f_k t + phi_k)``: frequencies (Hz,
    >= 0), amplitudes (m), phases (rad). Evaluated directly by the kernels (O(K) per time);
    :meth:`sampled` and :meth:`blocks` tabulate it (O(K) per grid point)."""

    @property
    def variance(self) -> float:
        """Time-averaged variance (m^2) = sum a_k^2 / 2 over components with f_k > 0."""
        w, a = self.tab[:, 0], self.tab[:, 1]
        return float(np.sum(0.5 * a[w > 0] ** 2))

    @property
    def band(self):
        f = self.tab[:, 0] / (2 * math.pi)
        return (float(f.min()), float(f.max()))

    def default_step(self, interp_tol=_DEFAULT_INTERP_TOL):
        """Grid step (s) meeting the Hermite bound (see stochastic.noise) for max frequency."""
        return hermite_step(max(self.max_frequency(), 1e-300), interp_tol)

    def _grid(self, t0, n, h):
        y, yd, ydd = np.empty(n), np.empty(n), np.empty(n)
        _kernels.cosine_sum_grid(float(t0), float(h), self.tab[:, 0].copy(), self.tab[:, 1].copy(),
                                 self.tab[:, 2].copy(), y, yd, ydd)
        return y, yd, ydd

    def sampled(self, t_end, t_start=0.0, h=None) -> Sampled:
        """``nlbeam.Sampled`` on [t_start, t_end] (s) with step ``h`` (default: Hermite bound)."""
        t_start = finite("t_start", t_start)
        t_end = finite("t_end", t_end)
        if not t_end > t_start:
            raise ValueError(f"t_end: must be > t_start = {t_start!r} s, got {t_end!r}")
        h = self.default_step() if h is None else positive("h", h, unit="s")
        n = int(math.ceil((t_end - t_start) / h - 1e-9)) + 1
        y, yd, ydd = self._grid(t_start, max(n, 2), h)
        return Sampled(t_start, h, y, yd, ydd, max_freq=self.max_frequency())

    def blocks(self, t_start=0.0, t_end=None, block_duration=None, h=None):
        """Yield ``Sampled`` tables covering [t_start, t_end] (s), sharing boundary nodes."""
        t_start = finite("t_start", t_start)
        t_end = finite("t_end", t_end)
        if not t_end > t_start:
            raise ValueError(f"t_end: must be > t_start = {t_start!r} s, got {t_end!r}")
        h = self.default_step() if h is None else positive("h", h, unit="s")
        nb = _DEFAULT_BLOCK_SAMPLES if block_duration is None else max(
            int(round(positive("block_duration", block_duration, unit="s") / h)), 2)
        n_total = int(math.ceil((t_end - t_start) / h - 1e-9))
        j = 0
        while j < n_total:
            m = min(nb, n_total - j)
            y, yd, ydd = self._grid(t_start + j * h, m + 1, h)
            yield Sampled(t_start + j * h, h, y, yd, ydd, max_freq=self.max_frequency())
            j += m

    def describe(self):
        return {"kind": "Realization", "n_components": int(self.tab.shape[0]),
                "rms": math.sqrt(self.variance), "band_lo": self.band[0], "band_hi": self.band[1]}


class Recorded(Excitation):
    """A measured base motion ``y(t)`` (s, m), uniform or not.

    The record is interpolated by a C2 cubic spline (scipy ``CubicSpline``, ``bc_type``),
    which gives y, y', y''; these are tabulated on a uniform grid of step ``h`` as
    ``nlbeam.Sampled``. For uniform records the default ``h`` is the sampling step: the
    grid nodes are the spline knots and the Hermite interpolation reproduces the spline
    exactly. For non-uniform records the default is a quarter of the median spacing;
    cells that straddle a knot (where y''' of the spline jumps) err by O(h^3 |jump y'''|).
    The excitation's accuracy is that of the record: no band limit is imposed.
    """

    def __init__(self, t, y, *, h=None, bc_type="not-a-knot"):
        from scipy.interpolate import CubicSpline

        t = real_array("t", t, finite_values=False)
        y = real_array("y", y, finite_values=False)
        if isinstance(bc_type, str):
            choice("bc_type", bc_type, ("not-a-knot", "natural", "clamped", "periodic"))
        if t.ndim != 1 or t.shape != y.shape or t.size < 4:
            raise ValueError("t, y: must be 1-D arrays of one length >= 4")
        if _kernels.all_finite(t) >= 0:
            raise ValueError("t: must be finite")
        if _kernels.all_finite(y) >= 0:
            raise ValueError("y: must be finite")
        dt = np.diff(t)
        if np.any(dt <= 0):
            raise ValueError("t: must be strictly increasing")
        uniform = np.max(np.abs(dt - dt.mean())) <= 1e-9 * dt.mean()
        if h is None:
            h = float(dt.mean()) if uniform else float(np.median(dt)) / 4.0
        else:
            h = positive("h", h, unit="s")
            if h > float(np.median(dt)) * (1 + 1e-12):
                raise ValueError(f"h: {h!r} s is coarser than the record's sampling step "
                                 f"{float(np.median(dt)):.6g} s (median): the table would lose "
                                 f"the record's detail; give h <= that step, or None")
        n = int(math.floor((t[-1] - t[0]) / h * (1 + 1e-12))) + 1
        if n > _MAX_TABLE_SAMPLES:
            raise ValueError(f"h: {h:.6g} s would tabulate {n:.3g} samples (> "
                             f"{_MAX_TABLE_SAMPLES}); "
                             f"give a larger h")
        spline = CubicSpline(t, y, bc_type=bc_type)
        tg = t[0] + h * np.arange(n)
        if uniform and abs(h - dt.mean()) <= 1e-12 * h:
            tg = t.copy()
            n = t.size
        tg = np.minimum(tg, t[-1])
        self.t_start = float(t[0])
        self.t_end = float(t[0] + (n - 1) * h)
        self.h = h
        self.uniform = bool(uniform)
        self._y = spline(tg)
        self._yd = spline(tg, 1)
        self._ydd = spline(tg, 2)
        self._nyq = 0.5 / float(np.median(dt))
        self.variance = float(np.var(y))
        self._table = Sampled(self.t_start, h, self._y, self._yd, self._ydd, max_freq=self._nyq)

    @property
    def duration(self):
        return self.t_end - self.t_start

    def kernel_args(self):
        return self._table.kernel_args()

    def time_span(self):
        return (self.t_start, self.t_end)

    def max_frequency(self):
        return self._nyq

    def sampled(self, t_end=None, t_start=None) -> Sampled:
        """The whole tabulated record as ``nlbeam.Sampled`` (or a trimmed copy)."""
        if t_end is None and t_start is None:
            return self._table
        return next(iter(self.blocks(t_start if t_start is not None else self.t_start,
                                     t_end if t_end is not None else self.t_end,
                                     block_duration=math.inf)))

    def blocks(self, t_start=None, t_end=None, block_duration=None):
        """Yield slices of the table covering [t_start, t_end] (s), sharing boundary nodes."""
        t_start = self.t_start if t_start is None else finite("t_start", t_start)
        t_end = self.t_end if t_end is None else finite("t_end", t_end)
        if not (self.t_start - 1e-9 * self.h <= t_start < t_end <= self.t_end + 1e-9 * self.h):
            raise ValueError(f"t_start, t_end: must satisfy {self.t_start} <= t_start < t_end <= "
                             f"{self.t_end} s (the record), got ({t_start!r}, {t_end!r})")
        ja = max(int(math.floor((t_start - self.t_start) / self.h + 1e-9)), 0)
        jend = min(int(math.ceil((t_end - self.t_start) / self.h - 1e-9)), self._y.size - 1)
        nb = _DEFAULT_BLOCK_SAMPLES if block_duration is None else (
            jend - ja if math.isinf(block_duration) else
            max(int(round(positive("block_duration", block_duration, unit="s") / self.h)), 1))
        j = ja
        while j < jend:
            k = min(j + nb, jend)
            yield Sampled(self.t_start + j * self.h, self.h, self._y[j: k + 1], self._yd[j: k + 1],
                          self._ydd[j: k + 1], max_freq=self._nyq)
            j = k

    def describe(self):
        return {"kind": "Recorded", "t_start": self.t_start, "t_end": self.t_end,
                "n": int(self._y.size), "h": self.h, "uniform": self.uniform,
                "rms": math.sqrt(self.variance)}
