"""Streaming estimators: consume a record block by block, memory independent of its length.

- :class:`WelchPSD` one-sided PSD (units^2/Hz), Hann window, 50 % overlap, detrend
  'constant' (each segment's mean removed); numerically identical to
  ``scipy.signal.welch(x, fs, window='hann', nperseg=n, noverlap=n//2, detrend='constant',
  scaling='density')`` on the concatenated record.
- :class:`StreamingHistogram` PDF on fixed-width bins, under/overflow counted, extended
  (never silently dropped).
- :class:`StreamingMoments` mean, std, skewness, kurtosis (non-excess: Gaussian = 3),
  merged across blocks by the pairwise formulas of Chan et al. / Pebay; standard errors.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.fft

from nlbeam._validate import positive

from . import _kernels

__all__ = ["WelchPSD", "StreamingHistogram", "StreamingMoments", "correlation_from_psd",
           "welch_dof"]


def _as_block(name, x):
    x = np.ascontiguousarray(np.asarray(x, dtype=float).ravel())
    j = _kernels.all_finite(x)
    if j >= 0:
        raise ValueError(f"{name}: sample {j} of this block is not finite ({x[j]!r})")
    return x


def welch_dof(window, step, n_segments):
    """Equivalent degrees of freedom of a Welch average of ``n_segments`` segments taken
    every ``step`` samples with ``window`` (Welch 1967, Gaussian data, PSD smooth over the
    window's bandwidth): nu = 2 K / (1 + 2 sum_{j>=1} (1 - j/K) c_j),
    c_j = (sum_n w_n w_{n + j step})^2 / (sum_n w_n^2)^2. Hann, 50 %: c_1 = 1/36."""
    K = int(n_segments)
    if K < 1:
        return 0.0
    w = np.asarray(window, dtype=float)
    s2 = float(np.sum(w * w))
    corr = 0.0
    j = 1
    while j < K and j * step < w.size:
        cj = (float(np.sum(w[: w.size - j * step] * w[j * step:])) / s2) ** 2
        corr += (1.0 - j / K) * cj
        j += 1
    return 2.0 * K / (1.0 + 2.0 * corr)


class WelchPSD:
    """Streaming one-sided Welch PSD.

    fs: sampling frequency (Hz). resolution: bin spacing df (Hz); the segment has
    ``nperseg = round(fs / resolution)`` samples (or give ``nperseg``), Hann window
    (periodic, as scipy.signal.get_window('hann')), 50 % overlap, each segment's mean
    removed. A partial segment is carried between blocks. Density scaling: the PSD of a
    signal in units u is in u^2/Hz, and sum(P) * df approximates its variance.
    """

    def __init__(self, fs, resolution=None, *, nperseg=None, max_batch=2 ** 22):
        self.fs = positive("fs", fs, unit="Hz")
        if (resolution is None) == (nperseg is None):
            raise ValueError("resolution, nperseg: give exactly one")
        if nperseg is None:
            resolution = positive("resolution", resolution, unit="Hz")
            nperseg = int(round(self.fs / resolution))
        if isinstance(nperseg, bool) or not isinstance(nperseg, (int, np.integer)) or nperseg < 8:
            raise ValueError(f"nperseg/resolution: the segment must hold >= 8 samples, got nperseg={nperseg!r} "
                             f"(resolution must be <= fs/8 = {self.fs / 8:.6g} Hz)")
        from scipy.signal import get_window

        self.nperseg = int(nperseg)
        self.noverlap = self.nperseg // 2
        self.step = self.nperseg - self.noverlap
        self.window = get_window("hann", self.nperseg)
        self._scale = 1.0 / (self.fs * float(np.sum(self.window ** 2)))
        self._acc = np.zeros(self.nperseg // 2 + 1)
        self._tail = np.zeros(0)
        self.n_segments = 0
        self.n_samples = 0
        self._max_batch = max(int(max_batch) // self.nperseg, 1)

    @property
    def resolution(self) -> float:
        """Bin spacing df = fs / nperseg (Hz)."""
        return self.fs / self.nperseg

    @property
    def frequencies(self):
        """Bin frequencies (Hz), 0 .. fs/2."""
        return np.arange(self.nperseg // 2 + 1) * self.resolution

    def update(self, x):
        """Feed the next consecutive samples ``x`` (1-D)."""
        x = _as_block("x", x)
        self.n_samples += x.size
        data = np.concatenate([self._tail, x]) if self._tail.size else x
        if data.size < self.nperseg:
            self._tail = data.copy()
            return self
        K = (data.size - self.nperseg) // self.step + 1
        segs = np.lib.stride_tricks.sliding_window_view(data, self.nperseg)[:: self.step][:K]
        for a in range(0, K, self._max_batch):
            s = segs[a: a + self._max_batch]
            s = (s - s.mean(axis=1, keepdims=True)) * self.window
            X = scipy.fft.rfft(s, axis=1)
            self._acc += np.sum(X.real ** 2 + X.imag ** 2, axis=0)
        self.n_segments += K
        self._tail = data[K * self.step:].copy()
        return self

    def _require(self):
        if self.n_segments == 0:
            raise ValueError(f"x: fewer samples ({self.n_samples}) than one segment ({self.nperseg}); "
                             f"feed more data or coarsen the resolution")

    @property
    def psd(self):
        """One-sided PSD estimate (units^2/Hz) at :attr:`frequencies`."""
        self._require()
        p = self._acc * (self._scale / self.n_segments)
        if self.nperseg % 2 == 0:
            p[1:-1] *= 2.0
        else:
            p[1:] *= 2.0
        return p

    @property
    def dof(self):
        """Equivalent chi-square degrees of freedom per bin (Welch); half at DC and Nyquist."""
        self._require()
        nu = welch_dof(self.window, self.step, self.n_segments)
        d = np.full(self._acc.size, nu)
        d[0] = nu / 2
        if self.nperseg % 2 == 0:
            d[-1] = nu / 2
        return d

    @property
    def relative_std(self):
        """Relative standard deviation sqrt(2/nu) of each bin's estimate."""
        return np.sqrt(2.0 / self.dof)

    def confidence_interval(self, level=0.95):
        """(lower, upper) bounds of the true PSD at confidence ``level``:
        P nu / chi2_nu((1+level)/2) and P nu / chi2_nu((1-level)/2)."""
        from scipy.stats import chi2

        if not 0 < level < 1:
            raise ValueError(f"level: must lie in (0, 1), got {level!r}")
        p, nu = self.psd, self.dof
        lo = p * nu / chi2.ppf(0.5 + level / 2, nu)
        hi = p * nu / chi2.ppf(0.5 - level / 2, nu)
        return lo, hi

    def result(self) -> dict:
        lo, hi = self.confidence_interval(0.95)
        return {"frequencies": self.frequencies, "psd": self.psd, "n_segments": self.n_segments,
                "dof": self.dof, "relative_std": self.relative_std, "ci95_low": lo, "ci95_high": hi,
                "resolution": self.resolution, "nperseg": self.nperseg}

    def state(self) -> dict:
        """Arrays and counters to save/merge this estimator."""
        return {"acc": self._acc.copy(), "n_segments": self.n_segments, "n_samples": self.n_samples}


def correlation_from_psd(psd, fs, nperseg, max_lag=None):
    """Autocorrelation coefficient rho(j / fs), j = 0 .. max_lag, from a Welch Hann PSD
    estimate: the inverse FFT of the averaged periodogram is the circular autocovariance
    weighted by the window's own autocorrelation, which is divided out. ``max_lag``
    defaults to nperseg // 4 (window correlation >= 0.6 there). The per-segment mean
    removal biases rho by about -S1/nperseg (S1 = sum of rho over all lags)."""
    from scipy.signal import get_window

    w = get_window("hann", nperseg)
    s2 = float(np.sum(w * w))
    p = np.array(psd, dtype=float)
    # undo one-sided doubling and density scale -> mean |X|^2 / (fs * s2)
    q = p.copy()
    q[1:] *= 0.5
    if nperseg % 2 == 0:
        q[-1] *= 2.0
    r = scipy.fft.irfft(q, n=nperseg) * fs  # = (1/s2) sum w_n w_{n+j} R_j, circular
    aw = scipy.fft.irfft(np.abs(scipy.fft.rfft(w)) ** 2, n=nperseg) / s2
    L = nperseg // 4 if max_lag is None else int(max_lag)
    L = min(L, nperseg // 2)
    rho = r[: L + 1] / aw[: L + 1]
    if not rho[0] > 0:
        raise ValueError("psd: has no power; correlation undefined")
    return rho / rho[0]


class StreamingHistogram:
    """Histogram PDF on fixed bin edges.

    edges: explicit increasing bin edges (kept exactly), or None. bins: number of bins when
    the edges are chosen from the first block: ``[min, max]`` of that block widened by
    ``margin`` of its span on each side. on_outside: what to do with later samples outside
    the edges: ``"extend"`` (default; append bins of the same width, existing edges
    unchanged; only for uniform edges, at most ``max_bins``, beyond which samples are
    counted as under/overflow with a warning), ``"count"`` (count as under/overflow, warn
    when the result is read) or ``"raise"``. The density is ``counts / (n_total * width)``
    with ``n_total`` including under/overflow, so it integrates to the fraction of samples
    inside the edges (reported).
    """

    def __init__(self, edges=None, *, bins=100, margin=0.25, on_outside="extend", max_bins=100_000):
        if on_outside not in ("extend", "count", "raise"):
            raise ValueError(f"on_outside: must be one of 'extend', 'count', 'raise', got {on_outside!r}")
        self.on_outside = on_outside
        self.max_bins = int(max_bins)
        if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
            raise ValueError(f"bins: must be an integer >= 1, got {bins!r}")
        self.bins = int(bins)
        self.margin = float(margin)
        if not (math.isfinite(self.margin) and self.margin >= 0):
            raise ValueError(f"margin: must be finite and >= 0, got {margin!r}")
        self.outside = np.zeros(2, dtype=np.int64)
        self.n_total = 0
        self._warned = False
        self._edges = None
        self.counts = None
        if edges is not None:
            e = np.asarray(edges, dtype=float)
            if e.ndim != 1 or e.size < 2 or not np.all(np.isfinite(e)) or np.any(np.diff(e) <= 0):
                raise ValueError("edges: must be a finite, strictly increasing 1-D array of length >= 2")
            self._set(e.copy())

    def _set(self, e):
        self._edges = e
        wd = np.diff(e)
        self.uniform = bool(np.allclose(wd, wd.mean(), rtol=1e-9, atol=0))
        self.width = float(wd.mean())
        if self.counts is None:
            self.counts = np.zeros(e.size - 1, dtype=np.int64)

    @property
    def edges(self):
        """Bin edges (units of the data)."""
        if self._edges is None:
            raise ValueError("x: no data yet; edges are chosen from the first block")
        return self._edges

    def update(self, x):
        """Count the samples ``x``."""
        x = _as_block("x", x)
        if x.size == 0:
            return self
        if self._edges is None:
            lo, hi = float(x.min()), float(x.max())
            span = hi - lo
            if span == 0:
                span = abs(lo) if lo != 0 else 1.0
            lo -= self.margin * span
            hi += self.margin * span
            self._set(np.linspace(lo, hi, self.bins + 1))
        if self.uniform and self.on_outside == "extend":
            self._extend_to(float(x.min()), float(x.max()))
        out = np.zeros(2, dtype=np.int64)
        st = _kernels.histogram_count(x, self._edges, self.uniform, self.counts, out)
        if st != 0:  # pragma: no cover - checked above
            raise ValueError("x: contains non-finite samples")
        if out.sum() and self.on_outside == "raise":
            raise ValueError(f"x: {int(out.sum())} samples outside the histogram edges "
                             f"[{self._edges[0]:.6g}, {self._edges[-1]:.6g}] (on_outside='raise')")
        self.outside += out
        self.n_total += x.size
        return self

    def _extend_to(self, xmin, xmax):
        e, w = self._edges, self.width
        add_lo = int(math.ceil((e[0] - xmin) / w)) + 1 if xmin < e[0] else 0
        add_hi = int(math.ceil((xmax - e[-1]) / w)) + 1 if xmax > e[-1] else 0
        if add_lo == 0 and add_hi == 0:
            return
        nb = self.counts.size
        if nb + add_lo + add_hi > self.max_bins:
            if not self._warned:
                warnings.warn(f"histogram: extending to [{xmin:.6g}, {xmax:.6g}] would need "
                              f"{nb + add_lo + add_hi} bins > max_bins={self.max_bins}; samples "
                              f"outside are counted as under/overflow", RuntimeWarning, stacklevel=3)
                self._warned = True
            return
        new = np.concatenate([e[0] - w * np.arange(add_lo, 0, -1), e, e[-1] + w * np.arange(1, add_hi + 1)])
        self.counts = np.concatenate([np.zeros(add_lo, np.int64), self.counts, np.zeros(add_hi, np.int64)])
        self._edges = new

    def result(self, n_eff=None) -> dict:
        """centres, density (1/units), edges, counts, under/overflow, fraction inside, and
        the per-bin standard error of the density sqrt(p (1 - p) / n_eff) / width with
        ``n_eff`` (default n_total: independent samples, an underestimate for correlated
        records)."""
        if self.counts is None or self.n_total == 0:
            raise ValueError("x: no data fed to the histogram")
        e = self._edges
        w = np.diff(e)
        n = self.n_total
        p = self.counts / n
        dens = p / w
        neff = float(n if n_eff is None else n_eff)
        n_out = int(self.outside.sum())
        if n_out and not self._warned:
            warnings.warn(f"histogram: {n_out} of {n} samples fell outside the edges "
                          f"(below {int(self.outside[0])}, above {int(self.outside[1])})",
                          RuntimeWarning, stacklevel=2)
        return {"centres": 0.5 * (e[1:] + e[:-1]), "density": dens, "edges": e.copy(),
                "counts": self.counts.copy(), "n_total": n, "n_below": int(self.outside[0]),
                "n_above": int(self.outside[1]), "fraction_inside": 1.0 - n_out / n,
                "density_se": np.sqrt(p * (1 - p) / neff) / w, "n_eff": neff}


def _merge(a, b):
    """Pairwise merge of (n, mean, M2, M3, M4) (Chan et al. 1979; Pebay 2008)."""
    na, ma, M2a, M3a, M4a = a
    nb, mb, M2b, M3b, M4b = b
    if na == 0:
        return tuple(b)
    if nb == 0:
        return tuple(a)
    n = na + nb
    d = mb - ma
    dn = d / n
    mean = ma + nb * dn
    M2 = M2a + M2b + d * dn * na * nb
    M3 = (M3a + M3b + d * dn * dn * na * nb * (na - nb)
          + 3.0 * dn * (na * M2b - nb * M2a))
    M4 = (M4a + M4b + d * dn * dn * dn * na * nb * (na * na - na * nb + nb * nb)
          + 6.0 * dn * dn * (na * na * M2b + nb * nb * M2a) + 4.0 * dn * (na * M3b - nb * M3a))
    return (n, mean, M2, M3, M4)


def _stats(s):
    n, mean, M2, M3, M4 = s
    var = M2 / n
    std = math.sqrt(var)
    if M2 > 0:
        skew = math.sqrt(n) * M3 / M2 ** 1.5
        kurt = n * M4 / (M2 * M2)
    else:
        skew = kurt = math.nan
    return mean, std, skew, kurt


class StreamingMoments:
    """One-pass mean, std (ddof=0), skewness sqrt(n) M3 / M2^1.5 and kurtosis n M4 / M2^2
    (non-excess; as scipy.stats.skew/kurtosis with bias=True, fisher=False).

    Each block's central sums are computed in a compiled two-pass kernel about a corrected
    mean and merged by the pairwise update formulas, so a mean offset far above the std
    costs no accuracy. batch_size: if given (samples), the moments of consecutive batches
    are also kept (a few floats per batch) for model-free batch-means standard errors.
    """

    def __init__(self, batch_size=None):
        self._s = (0, 0.0, 0.0, 0.0, 0.0)
        if batch_size is not None:
            if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 8:
                raise ValueError(f"batch_size: must be an integer >= 8 samples or None, got {batch_size!r}")
            batch_size = int(batch_size)
        self.batch_size = batch_size
        self._b = (0, 0.0, 0.0, 0.0, 0.0)
        self._batches = []
        self._buf = np.empty(5)

    def _block(self, x):
        st = _kernels.block_moments(x, self._buf)
        if st != 0:  # pragma: no cover - validated before
            raise ValueError("x: contains non-finite samples")
        b = self._buf
        return (int(b[0]), float(b[1]), float(b[2]), float(b[3]), float(b[4]))

    def update(self, x):
        """Feed the samples ``x`` (1-D)."""
        x = _as_block("x", x)
        if x.size == 0:
            return self
        if self.batch_size is None:
            self._s = _merge(self._s, self._block(x))
            return self
        j = 0
        while j < x.size:
            need = self.batch_size - self._b[0]
            piece = x[j: j + need]
            s = self._block(piece)
            self._s = _merge(self._s, s)
            self._b = _merge(self._b, s)
            j += piece.size
            if self._b[0] == self.batch_size:
                self._batches.append(_stats(self._b))
                self._b = (0, 0.0, 0.0, 0.0, 0.0)
        return self

    @property
    def n(self) -> int:
        return int(self._s[0])

    def sums(self):
        """(n, mean, M2, M3, M4): the merged central sums."""
        return self._s

    def merge(self, other: "StreamingMoments"):
        """Combine with another estimator (e.g. another ensemble member)."""
        self._s = _merge(self._s, other._s)
        self._batches.extend(other._batches)
        return self

    def result(self, rho=None) -> dict:
        """mean, std, skewness, kurtosis, n and standard errors.

        Gaussian-process standard errors: se_mean = std sqrt(S1/n), se_variance =
        std^2 sqrt(2 S2/n), se_skewness =
        sqrt(6 S3/n), se_kurtosis = sqrt(24 S4/n), with S_k = 1 + 2 sum_{j>=1} rho_j^k the
        correlation sums of the sampled record (rho: autocorrelation coefficients at lags
        0, 1, ... samples, e.g. from :func:`correlation_from_psd`; None: independent samples,
        S_k = 1). n_eff_k = n / S_k are reported. With batches (batch_size), batch-means
        standard errors std(batch values)/sqrt(n_batches) are given too (no Gaussian
        assumption; valid when a batch is much longer than the correlation time). When the
        PSD vanishes at f = 0 (band-pass records) S1 -> 0 and se_mean from it is not
        meaningful; use se_batch_mean.
        """
        if self.n < 2:
            raise ValueError(f"x: need at least 2 samples for moments, got {self.n}")
        mean, std, skew, kurt = _stats(self._s)
        if not (math.isfinite(skew) and std > 0):
            raise ValueError("x: the record is constant; skewness and kurtosis are undefined")
        n = self.n
        if rho is None:
            S = [1.0, 1.0, 1.0, 1.0]
        else:
            r = np.asarray(rho, dtype=float)[1:]
            S = [1.0 + 2.0 * float(np.sum(r ** k)) for k in (1, 2, 3, 4)]
            S = [max(s, 1.0 / n) for s in S]
        out = {"mean": mean, "std": std, "skewness": skew, "kurtosis": kurt, "n": n,
               "se_mean": std * math.sqrt(S[0] / n), "variance": std * std,
               "se_variance": std * std * math.sqrt(2.0 * S[1] / n), "se_skewness": math.sqrt(6.0 * S[2] / n),
               "se_kurtosis": math.sqrt(24.0 * S[3] / n),
               "n_eff_mean": n / S[0], "n_eff_skewness": n / S[2], "n_eff_kurtosis": n / S[3],
               "correlation_known": rho is not None, "n_batches": len(self._batches)}
        if len(self._batches) >= 2:
            b = np.array(self._batches)
            se = b.std(axis=0, ddof=1) / math.sqrt(b.shape[0])
            out.update({"se_batch_mean": float(se[0]), "se_batch_std": float(se[1]),
                        "se_batch_skewness": float(se[2]), "se_batch_kurtosis": float(se[3])})
        return out
