"""Streaming estimators: consume a record block by block, memory independent of its length.

- :class:`WelchPSD` one-sided PSD (units^2/Hz), Hann window, 50 % overlap, detrend
  'constant' (each segment's mean removed); numerically identical to
  ``scipy.signal.welch(x, fs, window='hann', nperseg=n, noverlap=n//2, detrend='constant',
  scaling='density')`` on the concatenated record.
- :class:`StreamingHistogram` PDF on fixed-width bins, under/overflow counted, extended
  (never silently dropped).
- :class:`StreamingMoments` mean, std, skewness, kurtosis (non-excess: Gaussian = 3),
  fraction of samples > 0, merged across blocks by the pairwise formulas of Chan et al. /
  Pebay; standard errors from the record's own correlation (:mod:`stochastic.errors`).
"""
from __future__ import annotations

import copy
import math
import warnings

import numpy as np
import scipy.fft

from nlbeam._validate import positive

from . import _kernels
from . import errors as _errors

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
            raise ValueError(f"nperseg/resolution: the segment must hold >= 8 samples, got "
                             f"nperseg={nperseg!r} "
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
        for a in range(0, K, self._max_batch):
            # each segment less its mean, windowed, in one compiled pass (numpy's temporaries
            # cost as much as the FFT of an 80000-sample segment), then its periodogram
            s = np.empty((min(self._max_batch, K - a), self.nperseg))
            _kernels.welch_segments(data, a * self.step, self.step, self.window, s)
            X = scipy.fft.rfft(s, axis=1, overwrite_x=True)
            _kernels.add_power(X, self._acc)
        self.n_segments += K
        self._tail = data[K * self.step:].copy()
        return self

    def _require(self):
        if self.n_segments == 0:
            raise ValueError(f"x: fewer samples ({self.n_samples}) than one segment "
                             f"({self.nperseg}); "
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
        # the bins share two values of nu: the quantiles once per value (identical numbers)
        nu_u, inv = np.unique(nu, return_inverse=True)
        lo = p * nu / chi2.ppf(0.5 + level / 2, nu_u)[inv]
        hi = p * nu / chi2.ppf(0.5 - level / 2, nu_u)[inv]
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
    inside the edges (reported). The counts of consecutive fine batches (``batch_size``
    samples, doubling when ``max_batches`` are held; the batch table stays below ~16 MB) are
    kept for standard errors that account for the record's correlation.
    """

    def __init__(self, edges=None, *, bins=100, margin=0.25, on_outside="extend", max_bins=100_000,
                 batch_size=256, max_batches=512):
        if on_outside not in ("extend", "count", "raise"):
            raise ValueError(f"on_outside: must be one of 'extend', 'count', 'raise', got "
                             f"{on_outside!r}")
        self.on_outside = on_outside
        self.max_bins = int(max_bins)
        if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
            raise ValueError(f"bins: must be an integer >= 1, got {bins!r}")
        self.bins = int(bins)
        self.margin = float(margin)
        if not (math.isfinite(self.margin) and self.margin >= 0):
            raise ValueError(f"margin: must be finite and >= 0, got {margin!r}")
        if (isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer))
                or batch_size < 1):
            raise ValueError(f"batch_size: must be an integer >= 1 sample, got {batch_size!r}")
        if (isinstance(max_batches, bool) or not isinstance(max_batches, (int, np.integer))
                or max_batches < 16 or max_batches % 2):
            raise ValueError(f"max_batches: must be an even integer >= 16, got {max_batches!r}")
        self.batch_size = int(batch_size)
        self._max_batches = int(max_batches)
        self._bc = None     # (rows + 1, bins) counts of the fine batches; row _nbat is filling
        self._nbat = 0
        self._bfill = 0
        self.outside = np.zeros(2, dtype=np.int64)
        self.n_total = 0
        self._warned = False
        self._edges = None
        self.counts = None
        if edges is not None:
            e = np.asarray(edges, dtype=float)
            if e.ndim != 1 or e.size < 2 or not np.all(np.isfinite(e)) or np.any(np.diff(e) <= 0):
                raise ValueError("edges: must be a finite, strictly increasing 1-D array of "
                                 "length >= 2")
            self._set(e.copy())

    def _set(self, e):
        self._edges = e
        wd = np.diff(e)
        self.uniform = bool(np.allclose(wd, wd.mean(), rtol=1e-9, atol=0))
        self.width = float(wd.mean())
        if self.counts is None:
            self.counts = np.zeros(e.size - 1, dtype=np.int64)
            self._bc = np.zeros((self._rows(e.size - 1) + 1, e.size - 1), dtype=np.int64)

    def _rows(self, nbins):
        """Rows of the batch table for ``nbins`` bins (even, 16 .. max_batches, <= 2^21 cells)."""
        r = min(self._max_batches, max(16, (2 ** 21) // max(nbins, 1)))
        return r - r % 2

    def _coarsen(self):
        """Merge neighbouring fine batches pairwise (half as many, twice as long); an odd
        completed batch joins the filling one."""
        J = self._nbat
        bc = self._bc
        pairs = bc[0: J - J % 2: 2] + bc[1: J - J % 2: 2]
        fill_row = bc[J].copy()
        if J % 2:
            fill_row += bc[J - 1]
            self._bfill += self.batch_size
        bc[:] = 0
        bc[: J // 2] = pairs
        bc[J // 2] = fill_row
        self._nbat = J // 2
        self.batch_size *= 2

    def _count_batches(self, x):
        """Count ``x`` into the totals and the fine-batch rows (compiled), merging rows
        whenever the table is full; returns [below, above] of this block."""
        out = np.zeros(2, dtype=np.int64)
        state = np.zeros(3, dtype=np.int64)
        j = 0
        while True:
            st = _kernels.histogram_count_batches(x[j:], self._edges, self.uniform, self._bc,
                                                  self._nbat, self._bfill, self.batch_size,
                                                  self.counts, out, state)
            if st != 0:  # pragma: no cover - checked before
                raise ValueError("x: contains non-finite samples")
            j += int(state[0])
            self._nbat, self._bfill = int(state[1]), int(state[2])
            if self._bfill == self.batch_size:
                self._nbat += 1
                self._bfill = 0
            if self._nbat == self._bc.shape[0] - 1:
                self._coarsen()
            if j >= x.size:
                return out

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
        if self.on_outside == "raise":
            below, above = int(np.sum(x < self._edges[0])), int(np.sum(x > self._edges[-1]))
            if below + above:
                raise ValueError(f"x: {below + above} samples outside the histogram edges "
                                 f"[{self._edges[0]:.6g}, {self._edges[-1]:.6g}] "
                                 "(on_outside='raise')")
        out = self._count_batches(x)
        if out.sum() and self.on_outside == "raise":  # pragma: no cover - checked above
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
                              "outside are counted as under/overflow",
                              RuntimeWarning, stacklevel=3)
                self._warned = True
            return
        new = np.concatenate([e[0] - w * np.arange(add_lo, 0, -1), e,
                              e[-1] + w * np.arange(1, add_hi + 1)])
        self.counts = np.concatenate([np.zeros(add_lo, np.int64), self.counts,
                                      np.zeros(add_hi, np.int64)])
        self._edges = new
        rows = self._rows(self.counts.size)
        while self._nbat >= rows:
            self._coarsen()
        r = self._bc.shape[0]
        self._bc = np.concatenate([np.zeros((r, add_lo), np.int64), self._bc,
                                   np.zeros((r, add_hi), np.int64)], axis=1)[:rows + 1]

    def result(self, n_eff=None, min_window=None) -> dict:
        """centres, density (1/units), edges, counts, under/overflow, fraction inside, and
        ``density_se``: the standard error of each bin's density over independent records of
        the same length (one sigma), from overlapping batch means of the bin's indicator
        over windows of 10 integrated correlation times of the fine-batch counts (pooled
        over the bins; :mod:`stochastic.errors`), so correlated samples are not counted as
        independent. A bin with no count has se 0 (it says nothing about rare values);
        ``se_dof``: approximate degrees of freedom of these errors. ``min_window``: at least
        this many samples per window (as :meth:`StreamingMoments.result`). ``n_eff``:
        instead the independent-sample formula sqrt(p (1 - p) / n_eff) / width."""
        if self.counts is None or self.n_total == 0:
            raise ValueError("x: no data fed to the histogram")
        e = self._edges
        w = np.diff(e)
        n = self.n_total
        p = self.counts / n
        dens = p / w
        n_out = int(self.outside.sum())
        if n_out and not self._warned:
            warnings.warn(f"histogram: {n_out} of {n} samples fell outside the edges "
                          f"(below {int(self.outside[0])}, above {int(self.outside[1])})",
                          RuntimeWarning, stacklevel=2)
        out = {"centres": 0.5 * (e[1:] + e[:-1]), "density": dens, "edges": e.copy(),
               "counts": self.counts.copy(), "n_total": n, "n_below": int(self.outside[0]),
               "n_above": int(self.outside[1]), "fraction_inside": 1.0 - n_out / n}
        if n_eff is not None:
            neff = float(n_eff)
            out.update(density_se=np.sqrt(p * (1 - p) / neff) / w, n_eff=neff)
            return out
        J = self._nbat
        if J < 4:
            out.update(density_se=np.full(p.shape, np.nan), se_dof=0.0, se_batch_samples=0)
            return out
        U = self._bc[:J] / float(self.batch_size)  # fraction of each batch in each bin
        tau, _ = _errors.integrated_time(U)
        min_L = 1 if min_window is None else int(math.ceil(min_window / self.batch_size))
        L, dof = _errors.window_for(tau, J, min_L)
        var = np.maximum(_errors.overlapping_batch_variance(U, L), 0.0)
        out.update(density_se=np.sqrt(var / J) / w, se_dof=float(dof),
                   se_batch_samples=int(L * self.batch_size))
        return out


def _merge(a, b):
    """Pairwise merge of (n, mean, M2, M3, M4, n_positive) (Chan et al. 1979; Pebay 2008).
    Elementwise on arrays too (then every n must be > 0)."""
    na, ma, M2a, M3a, M4a, pa = a
    nb, mb, M2b, M3b, M4b, pb = b
    if np.isscalar(na):
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
    return (n, mean, M2, M3, M4, pa + pb)


_EMPTY = (0, 0.0, 0.0, 0.0, 0.0, 0)
#: statistics with standard errors, in the order of the influence-function rows
STATISTICS = ("mean", "variance", "std", "skewness", "kurtosis")


def _stats(s):
    n, mean, M2, M3, M4 = s[:5]
    var = M2 / n
    std = math.sqrt(var)
    if M2 > 0:
        skew = math.sqrt(n) * M3 / M2 ** 1.5
        kurt = n * M4 / (M2 * M2)
    else:
        skew = kurt = math.nan
    return mean, std, skew, kurt


def _gaussian_errors(std, n, rho):
    """Standard errors for a stationary *Gaussian* process with autocorrelation ``rho``."""
    r = np.asarray(rho, dtype=float)[1:]
    S = [max(1.0 + 2.0 * float(np.sum(r ** k)), 1.0 / n) for k in (1, 2, 3, 4)]
    return {"se_mean_gaussian": std * math.sqrt(S[0] / n),
            "se_variance_gaussian": std * std * math.sqrt(2.0 * S[1] / n),
            "se_skewness_gaussian": math.sqrt(6.0 * S[2] / n),
            "se_kurtosis_gaussian": math.sqrt(24.0 * S[3] / n)}


class StreamingMoments:
    """One-pass mean, std (ddof=0), skewness sqrt(n) M3 / M2^1.5, kurtosis n M4 / M2^2
    (non-excess; as scipy.stats.skew/kurtosis with bias=True, fisher=False) and the
    fraction of samples > 0, with standard errors that hold for correlated, non-Gaussian
    records.

    Each block's central sums are computed in a compiled two-pass kernel about a corrected
    mean and merged by the pairwise update formulas, so a mean offset far above the std
    costs no accuracy. The same sums are kept for consecutive fine batches of
    ``batch_size`` samples (default 64; at most ``max_batches`` of them: when full,
    neighbours merge and the batch size doubles), from which :meth:`result` computes the
    standard errors as described in :mod:`stochastic.errors`.
    """

    def __init__(self, batch_size=None, *, max_batches=4096):
        if batch_size is None:
            batch_size = 64
        if (isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer))
                or batch_size < 1):
            raise ValueError(f"batch_size: must be an integer >= 1 sample or None, "
                             f"got {batch_size!r}")
        if (isinstance(max_batches, bool) or not isinstance(max_batches, (int, np.integer))
                or max_batches < 16 or max_batches % 2):
            raise ValueError(f"max_batches: must be an even integer >= 16, got {max_batches!r}")
        self.batch_size = int(batch_size)
        self._s = _EMPTY
        self._cur = _EMPTY
        self._bat = np.zeros((int(max_batches), 6))
        self._nbat = 0

    def _sums(self, x, size):
        out = np.empty((x.size // size, 6))
        st = _kernels.batch_sums(x, size, out)
        if st != 0:  # pragma: no cover - validated before
            raise ValueError("x: contains non-finite samples")
        return out

    def _push(self, rows):
        k = rows.shape[0]
        self._bat[self._nbat: self._nbat + k] = rows
        self._nbat += k
        if self._nbat == self._bat.shape[0]:
            self._coarsen()

    def _coarsen(self):
        """Merge neighbouring batches pairwise: half as many, twice as long."""
        J = self._nbat - self._nbat % 2
        a, b = self._bat[0:J:2].T, self._bat[1:J:2].T
        merged = np.array(_merge(tuple(a), tuple(b))).T
        tail = self._bat[J: self._nbat].copy()
        self._bat[:] = 0.0
        self._bat[: J // 2] = merged
        self._nbat = J // 2
        self.batch_size *= 2
        if tail.size:  # an odd batch out becomes the partial batch
            self._cur = _merge(tuple(tail[0]), self._cur)

    def update(self, x):
        """Feed the samples ``x`` (1-D)."""
        x = _as_block("x", x)
        if x.size == 0:
            return self
        whole = self._sums(x, x.size)[0]
        self._s = _merge(self._s, tuple(whole))
        j, n = 0, x.size
        while j < n:
            bs = self.batch_size
            if self._cur[0] > 0 or n - j < bs:
                take = min(bs - int(self._cur[0]), n - j)
                piece = x[j: j + take]
                self._cur = _merge(self._cur, tuple(self._sums(piece, piece.size)[0]))
                j += take
                if self._cur[0] == bs:
                    done, self._cur = self._cur, _EMPTY
                    self._push(np.array([done], dtype=float))
            else:
                k = min((n - j) // bs, self._bat.shape[0] - self._nbat)
                self._push(self._sums(x[j: j + k * bs], bs))
                j += k * bs
        return self

    @property
    def n(self) -> int:
        return int(self._s[0])

    @property
    def n_batches(self) -> int:
        """Completed fine batches held (each ``batch_size`` samples)."""
        return self._nbat

    def sums(self):
        """(n, mean, M2, M3, M4): the merged central sums."""
        return self._s[:5]

    def merge(self, other: "StreamingMoments"):
        """Combine with another estimator (e.g. another ensemble member): the totals are
        merged; the fine batches are brought to the larger batch size (sizes must differ by a
        power of 2) and appended (partial batches are left out of the errors)."""
        self._s = _merge(self._s, other._s)
        o = copy.deepcopy(other)
        while o.batch_size < self.batch_size:
            o._coarsen()
        while self.batch_size < o.batch_size:
            self._coarsen()
        if o.batch_size != self.batch_size:
            raise ValueError(f"other: batch sizes {self.batch_size} and {other.batch_size} "
                             "do not differ by a power of 2")
        rows = o._bat[: o._nbat]
        while rows.shape[0]:
            k = min(rows.shape[0], self._bat.shape[0] - self._nbat)
            self._push(rows[:k])
            rows = rows[k:]
        return self

    def result(self, rho=None, min_window=None) -> dict:
        """mean, std, variance, skewness, kurtosis, p_positive (fraction of samples > 0),
        n and their standard errors ``se_<name>``.

        What an error means: ``se_x`` is the standard deviation of the estimate ``x`` over
        independent records of the same length (one sigma; 95 % is about +-2 se when
        ``se_dof`` >= 20). It is computed without a Gaussian assumption, from the
        record's own correlation: each statistic is linearized (influence function), and the
        variance of the mean of that per-sample quantity is estimated by overlapping batch
        means over windows of 10 integrated correlation times measured on the record, and
        at least ``min_window`` samples if given (a known slow time scale of the record;
        :mod:`stochastic.errors`). ``se_dof``: the smallest approximate degrees of freedom
        of these errors (few when the record is short for its correlation time: then the
        errors themselves are rough). ``n_eff_mean`` = variance / se_mean^2 (independent
        samples worth of the mean); ``n_eff_skewness`` = 6 / se_skewness^2 and
        ``n_eff_kurtosis`` = 24 / se_kurtosis^2 are the Gaussian-equivalent counts.
        ``rho``: if the record is known to be a stationary Gaussian process with this
        autocorrelation (coefficients at lags 0, 1, ... samples), the closed-form
        Gaussian-process errors are added as ``se_<name>_gaussian`` (not valid otherwise).
        """
        if self.n < 2:
            raise ValueError(f"x: need at least 2 samples for moments, got {self.n}")
        mean, std, skew, kurt = _stats(self._s)
        if not (math.isfinite(skew) and std > 0):
            raise ValueError("x: the record is constant; skewness and kurtosis are undefined")
        n = self.n
        p_pos = self._s[5] / n
        out = {"mean": mean, "std": std, "variance": std * std, "skewness": skew,
               "kurtosis": kurt, "p_positive": p_pos, "n": n, "n_batches": self._nbat,
               "batch_size": self.batch_size, "correlation_known": rho is not None}
        ses, dofs, Ls = self._errors(mean, std, min_window)
        out.update(ses)
        out["se_dof"] = float(min(dofs)) if dofs else 0.0
        out["se_batch_samples"] = int(max(Ls) * self.batch_size) if Ls else 0
        v = std * std
        for key, num in (("mean", v), ("skewness", 6.0), ("kurtosis", 24.0)):
            se = out[f"se_{key}"]
            out[f"n_eff_{key}"] = num / se ** 2 if se > 0 else math.inf
        if rho is not None:
            out.update(_gaussian_errors(std, n, rho))
        return out

    def _errors(self, mean, std, min_window=None):
        """{se_<statistic>}, degrees of freedom and windows from the fine batches."""
        min_L = 1 if min_window is None else int(math.ceil(min_window / self.batch_size))
        nan = {f"se_{k}": math.nan for k in STATISTICS + ("p_positive",)}
        J = self._nbat
        if J < 4:
            return nan, [], []
        b = self._bat[:J]
        nb = b[:, 0]
        m2 = std * std
        n, _, M2, M3, M4 = self._s[:5]
        m3, m4 = M3 / n, M4 / n
        # batch means of (x - mean)^p, p = 1..4, from each batch's central sums
        d = b[:, 1] - mean
        c2, c3, c4 = b[:, 2] / nb, b[:, 3] / nb, b[:, 4] / nb
        P1 = d
        P2 = c2 + d * d
        P3 = c3 + 3.0 * d * c2 + d ** 3
        P4 = c4 + 4.0 * d * c3 + 6.0 * d * d * c2 + d ** 4
        IF2 = P2 - m2
        rows = {"mean": P1, "variance": IF2, "std": IF2 / (2.0 * std),
                "skewness": (P3 - m3 - 3.0 * m2 * P1) / m2 ** 1.5 - 1.5 * m3 / m2 ** 2.5 * IF2,
                "kurtosis": (P4 - m4 - 4.0 * m3 * P1) / (m2 * m2) - 2.0 * m4 / m2 ** 3 * IF2,
                "p_positive": b[:, 5] / nb}
        ses, dofs, Ls = {}, [], []
        for k, u in rows.items():
            se, L, dof = _errors.series_se(u, min_L)
            ses[f"se_{k}"] = se
            if k != "p_positive":
                dofs.append(dof)
                Ls.append(L)
        return ses, dofs, Ls
