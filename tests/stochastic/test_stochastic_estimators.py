"""Streaming estimators equal their batch counterparts, and their stated uncertainties
are the scatter actually seen."""
import math
import warnings

import numpy as np
import pytest
import scipy.signal
import scipy.stats

import stochastic as st


def split(x, rng, n_parts=9):
    cuts = np.sort(rng.integers(0, x.size, n_parts))
    cuts[0] = cuts[1]  # one empty block
    return np.split(x, cuts)


@pytest.mark.parametrize("nperseg", [256, 255])
def test_welch_streaming_equals_scipy(nperseg):
    rng = np.random.default_rng(1)
    x = scipy.signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal(60_000)) + 3.0
    fs = 500.0
    w = st.WelchPSD(fs, nperseg=nperseg)
    for part in split(x, rng):
        w.update(part)
    f, P = scipy.signal.welch(x, fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                              detrend="constant", scaling="density")
    assert np.array_equal(w.frequencies, f) or np.allclose(w.frequencies, f, rtol=1e-15)
    assert np.max(np.abs(w.psd - P) / P.max()) < 1e-12
    assert w.n_segments == (x.size - nperseg) // (nperseg - nperseg // 2) + 1


def test_welch_resolution_and_dof():
    w = st.WelchPSD(1000.0, resolution=2.0)
    assert w.nperseg == 500 and w.resolution == 2.0
    # Hann at 50 % overlap: c_1 = (1/6)^2 = 1/36 (Welch 1967)
    K = 100
    expected = 2 * K / (1 + 2 * (1 - 1 / K) / 36)
    assert st.welch_dof(w.window, w.step, K) == pytest.approx(expected, rel=1e-3)
    w.update(np.random.default_rng(0).standard_normal(500 * 51))
    assert w.n_segments == 101
    assert w.relative_std[5] == pytest.approx(math.sqrt(2 / st.welch_dof(w.window, w.step, 101)))
    assert w.dof[0] == pytest.approx(w.dof[5] / 2)


def test_welch_confidence_interval_covers_truth_at_its_level():
    """White noise of variance s2 has the flat one-sided PSD 2 s2 / fs."""
    rng = np.random.default_rng(7)
    fs, s2 = 100.0, 4.0
    w = st.WelchPSD(fs, nperseg=128)
    w.update(np.sqrt(s2) * rng.standard_normal(128 * 20))
    lo, hi = w.confidence_interval(0.95)
    truth = 2 * s2 / fs
    inner = slice(1, -1)
    cover = np.mean((lo[inner] <= truth) & (truth <= hi[inner]))
    # 63 bins, neighbouring bins correlated; 0.95 +- ~4 sigma
    assert 0.80 <= cover <= 1.0
    # pooled over many independent records the coverage is the nominal one
    hits, total = 0, 0
    for _ in range(60):
        w = st.WelchPSD(fs, nperseg=64)
        w.update(np.sqrt(s2) * rng.standard_normal(64 * 10))
        lo, hi = w.confidence_interval(0.95)
        hits += int(((lo[5] <= truth) & (truth <= hi[5])))
        hits += int(((lo[20] <= truth) & (truth <= hi[20])))
        total += 2
    assert abs(hits / total - 0.95) < 4 * math.sqrt(0.95 * 0.05 / total) + 0.01


def test_welch_needs_a_full_segment_and_finite_data():
    w = st.WelchPSD(100.0, nperseg=64)
    w.update(np.zeros(10))
    with pytest.raises(ValueError, match="^x:"):
        w.psd
    with pytest.raises(ValueError, match="^x:"):
        w.update(np.array([0.0, np.nan]))
    with pytest.raises(ValueError, match="^fs"):
        st.WelchPSD(-1.0, 1.0)
    with pytest.raises(ValueError, match="^resolution"):
        st.WelchPSD(100.0, 0.0)
    with pytest.raises(ValueError, match="^nperseg/resolution"):
        st.WelchPSD(100.0, 50.0)
    with pytest.raises(ValueError, match="^resolution, nperseg"):
        st.WelchPSD(100.0)


def test_moments_streaming_equal_scipy_with_huge_offset():
    rng = np.random.default_rng(3)
    offset = 2.0 ** 20  # ~ 1e6 std; x - offset is exact, so scipy on it is the reference
    z = rng.gamma(2.0, size=300_001)  # skewness sqrt(2), kurtosis 6
    x = offset + z
    ref = x - offset
    m = st.StreamingMoments()
    for part in split(x, rng, 13):
        m.update(part)
    r = m.result()
    assert r["mean"] == pytest.approx(np.mean(x), rel=1e-12)  # an ulp of 2^20 is 2.3e-10
    assert r["std"] == pytest.approx(ref.std(), rel=1e-10)
    assert r["skewness"] == pytest.approx(scipy.stats.skew(ref), rel=1e-10)
    assert r["kurtosis"] == pytest.approx(scipy.stats.kurtosis(ref, fisher=False), rel=1e-10)
    assert r["n"] == x.size
    # the naive one-pass power-sum formula fails here: it is a real test of stability
    s1, s2 = np.sum(x), np.sum(x * x)
    naive_var = s2 / x.size - (s1 / x.size) ** 2
    assert abs(naive_var / ref.var() - 1) > 1e-6


def test_moments_gaussian_and_merge():
    rng = np.random.default_rng(4)
    x = 5.0 + 0.1 * rng.standard_normal(200_000)
    a, b = st.StreamingMoments(), st.StreamingMoments()
    a.update(x[:70_000])
    b.update(x[70_000:])
    r = a.merge(b).result()
    assert r["mean"] == pytest.approx(x.mean(), rel=1e-12)
    assert r["std"] == pytest.approx(x.std(), rel=1e-10)
    assert r["skewness"] == pytest.approx(scipy.stats.skew(x), rel=1e-9, abs=1e-12)
    assert r["kurtosis"] == pytest.approx(scipy.stats.kurtosis(x, fisher=False), rel=1e-10)
    # independent Gaussian samples: the model-free errors equal the textbook ones within
    # their own uncertainty (~3125 fine batches, window 10 -> dof ~ 460, ~ 3.3 % each)
    assert r["se_dof"] > 300
    assert r["se_mean"] == pytest.approx(0.1 / math.sqrt(x.size), rel=0.15)
    assert r["se_std"] == pytest.approx(0.1 / math.sqrt(2 * x.size), rel=0.15)
    assert r["se_skewness"] == pytest.approx(math.sqrt(6 / x.size), rel=0.15)
    assert r["se_kurtosis"] == pytest.approx(math.sqrt(24 / x.size), rel=0.15)
    assert r["p_positive"] == np.mean(x > 0) and r["p_positive"] == 1.0  # mean 5, std 0.1
    assert abs(r["skewness"]) < 4 * r["se_skewness"]
    assert abs(r["kurtosis"] - 3) < 4 * r["se_kurtosis"]
    # merged: the fine batches of both halves are kept for the errors
    assert r["n_batches"] == (70_000 // 64) + (130_000 // 64)
    # a known slow time scale sets a minimum window (independent samples: same error)
    r2 = a.result(min_window=6400)
    assert r2["se_batch_samples"] >= 6400 > r["se_batch_samples"]
    assert r2["se_dof"] == pytest.approx(1.5 * (r["n_batches"] / 100 - 1))
    assert r2["se_kurtosis"] == pytest.approx(r["se_kurtosis"], rel=0.3)


def _ar1(rng, phi, n, skewed=False):
    e = rng.standard_normal(n + 500)
    if skewed:
        e = np.exp(0.4 * e) - math.exp(0.08)  # lognormal innovations: non-Gaussian record
    return scipy.signal.lfilter([1.0], [1.0, -phi], e)[500:]


@pytest.mark.parametrize("skewed", [False, True], ids=["gaussian", "lognormal-innovations"])
def test_moment_standard_errors_cover_the_scatter_of_correlated_records(skewed):
    """AR(1), phi = 0.9 (integrated correlation time 19 samples), 150 records of 40 000
    samples, Gaussian or with skewed innovations (record skewness 0.4, kurtosis 3.3): the stated
    errors of mean, std, skewness, kurtosis and P(x > 0) must match the scatter over the
    records (ratio within 0.75 .. 1.33: the sample std of 150 values is uncertain by ~6 %,
    the mean error by ~ 1/sqrt(2 dof) ~ 8 %), and |z| <= 2 must hold in 88 .. 99 % of the
    records for each (nominal ~ 95 %). For the skewed record the Gaussian-process formula
    is shown to be wrong (the test of that error would fail)."""
    phi, n, reps = 0.9, 40_000, 150
    rng = np.random.default_rng(5 + skewed)
    rho = phi ** np.arange(300)
    keys = ("mean", "std", "skewness", "kurtosis", "p_positive")
    vals = {k: [] for k in keys}
    ses = {k: [] for k in keys}
    gk = []
    for _ in range(reps):
        x = _ar1(rng, phi, n, skewed)
        m = st.StreamingMoments()
        for part in np.array_split(x, 5):
            m.update(part)
        r = m.result(rho=rho)
        for k in keys:
            vals[k].append(r[k])
            ses[k].append(r[f"se_{k}"])
        gk.append(r["se_kurtosis_gaussian"])
    for k in keys:
        v, se = np.array(vals[k]), np.array(ses[k])
        ratio = v.std(ddof=1) / se.mean()
        assert 0.75 < ratio < 1.33, (k, ratio)
        cover = np.mean(np.abs(v - v.mean()) <= 2 * se)
        assert 0.88 <= cover <= 0.99, (k, cover)
    # the closed form for a Gaussian process holds for the Gaussian record only
    S4 = 1 + 2 * phi ** 4 / (1 - phi ** 4)
    assert r["se_kurtosis_gaussian"] == pytest.approx(math.sqrt(24 * S4 / n), rel=1e-6)
    g_ratio = np.std(vals["kurtosis"], ddof=1) / np.mean(gk)
    if skewed:
        assert g_ratio > 1.5, g_ratio
    else:
        assert 0.75 < g_ratio < 1.33, g_ratio


def test_errors_module_recovers_ar1_correlation_and_obm_formula():
    rng = np.random.default_rng(11)
    phi = 0.8
    x = _ar1(rng, phi, 200_000)
    tau, W = st.errors.integrated_time(x)
    assert tau == pytest.approx((1 + phi) / (1 - phi), rel=0.1) and W > 0
    assert st.errors.integrated_time(rng.standard_normal(50_000))[0] == pytest.approx(1.0, abs=0.1)
    # overlapping batch means against the brute-force definition
    u, L = rng.standard_normal(200), 7
    ybar = u.mean()
    means = np.array([u[j: j + L].mean() for j in range(u.size - L + 1)])
    ref = u.size * L / ((u.size - L + 1) * (u.size - L)) * np.sum((means - ybar) ** 2)
    assert st.errors.overlapping_batch_variance(u, L) == pytest.approx(ref, rel=1e-12)
    # a series far too short for its correlation: the window is capped, dof is small
    se, L, dof = st.errors.series_se(_ar1(rng, 0.999, 64))
    assert L == 16 and dof < 5


def test_correlation_from_psd_recovers_ar1():
    phi, fs = 0.7, 1.0
    rng = np.random.default_rng(6)
    x = scipy.signal.lfilter([1.0], [1.0, -phi], rng.standard_normal(400_000))
    w = st.WelchPSD(fs, nperseg=512).update(x)
    rho = st.correlation_from_psd(w.psd, fs, w.nperseg, max_lag=20)
    S1 = (1 + phi) / (1 - phi)  # detrending bias ~ S1 / nperseg = 0.011
    assert np.max(np.abs(rho - phi ** np.arange(21))) < 2 * S1 / 512


def test_histogram_streaming_equals_numpy_with_given_edges():
    rng = np.random.default_rng(8)
    x = rng.standard_normal(100_000)
    x[:5] = [-2.0, 0.0, 2.0, -2.5, 2.5]  # samples exactly on edges
    edges = np.linspace(-2.0, 2.0, 41)
    h = st.StreamingHistogram(edges, on_outside="count")
    for part in split(x, rng):
        h.update(part)
    counts, _ = np.histogram(x, bins=edges)
    with pytest.warns(RuntimeWarning, match="outside"):
        r = h.result()
    assert np.array_equal(r["counts"], counts)
    assert r["n_below"] == np.sum(x < -2.0) and r["n_above"] == np.sum(x > 2.0)
    assert np.sum(r["density"] * np.diff(r["edges"])) == pytest.approx(r["fraction_inside"])
    # non-uniform edges
    e2 = np.array([-3.0, -1.0, -0.2, 0.0, 0.7, 3.0])
    h2 = st.StreamingHistogram(e2, on_outside="count")
    for part in split(x, rng):
        h2.update(part)
    assert np.array_equal(h2.counts, np.histogram(x, bins=e2)[0])


def test_histogram_chooses_edges_and_extends_without_dropping():
    rng = np.random.default_rng(9)
    x = rng.standard_normal(50_000)
    h = st.StreamingHistogram(bins=50)
    h.update(x[:100])  # edges from a small first block
    h.update(x[100:])
    h.update(np.array([25.0]))  # far outlier: extended, not dropped
    r = h.result()
    assert r["n_below"] == 0 and r["n_above"] == 0 and r["n_total"] == 50_001
    assert r["counts"].sum() == 50_001
    counts, _ = np.histogram(np.append(x, 25.0), bins=r["edges"])
    assert np.array_equal(counts, r["counts"])
    w = np.diff(r["edges"])
    assert np.allclose(w, w[0], rtol=1e-9)
    # density of a Gaussian within its standard error (bins near the centre)
    c = r["centres"]
    near = np.abs(c) < 1.5
    pdf = scipy.stats.norm.pdf(c[near])
    assert np.all(np.abs(r["density"][near] - pdf) < 5 * r["density_se"][near] + 0.5 * w[0] ** 2)


def test_histogram_cap_warns_and_raise_mode_raises():
    h = st.StreamingHistogram(np.linspace(0, 1, 11), max_bins=20)
    with pytest.warns(RuntimeWarning, match="max_bins"):
        h.update(np.array([0.5, 100.0]))
    assert h.result()["n_above"] == 1
    h2 = st.StreamingHistogram(np.linspace(0, 1, 11), on_outside="raise")
    with pytest.raises(ValueError, match="^x:"):
        h2.update(np.array([2.0]))
    with pytest.raises(ValueError, match="^on_outside"):
        st.StreamingHistogram(on_outside="drop")
    with pytest.raises(ValueError, match="^edges"):
        st.StreamingHistogram([1.0, 0.0])
    with pytest.raises(ValueError, match="^x:"):
        st.StreamingHistogram().update([np.inf])


def test_moments_reject_bad_input():
    m = st.StreamingMoments()
    with pytest.raises(ValueError, match="^x:"):
        m.update([1.0, np.nan])
    with pytest.raises(ValueError, match="^x:"):
        m.result()
    m.update(np.ones(10))
    with pytest.raises(ValueError, match="^x:"):
        m.result()
    with pytest.raises(ValueError, match="^batch_size"):
        st.StreamingMoments(batch_size=0)
    with pytest.raises(ValueError, match="^max_batches"):
        st.StreamingMoments(max_batches=15)


def test_fine_batches_coarsen_and_keep_the_totals():
    """More batches than the buffer holds: neighbours merge (batch size doubles); the
    merged batch sums equal the sums of the samples they cover."""
    rng = np.random.default_rng(12)
    x = rng.standard_normal(5000) + 3.0
    m = st.StreamingMoments(batch_size=8, max_batches=16)
    for part in np.array_split(x, 17):
        m.update(part)
    assert m.batch_size == 8 * 2 ** 6 and m.n_batches == 9  # 5000 // 512
    b = m._bat[: m.n_batches]
    for k in (0, 4, 8):
        seg = x[k * 512: (k + 1) * 512]
        assert b[k, 1] == pytest.approx(seg.mean(), rel=1e-13)
        assert b[k, 2] == pytest.approx(np.sum((seg - seg.mean()) ** 2), rel=1e-11)
        assert b[k, 5] == np.sum(seg > 0)
    h = st.StreamingHistogram(np.linspace(-1, 7, 9), batch_size=8, max_batches=16)
    for part in np.array_split(x, 17):
        h.update(part)
    assert h.batch_size == 8 * 2 ** 6
    assert np.array_equal(h._bc[:9].sum(axis=0) + h._bc[9],
                          np.histogram(x, np.linspace(-1, 7, 9))[0])
    assert np.array_equal(h._bc[4], np.histogram(x[4 * 512: 5 * 512], np.linspace(-1, 7, 9))[0])


def test_density_errors_account_for_correlation():
    """AR(1), phi = 0.95 (integrated time 39 samples), 120 records of 60 000 samples: the
    stated density errors match the scatter of the density over the records in the central
    bins (ratio 0.75 .. 1.33) with |z| <= 2 in 88 .. 99 % of cases, and are far above the
    independent-sample formula (too small by a factor 2.4 .. 3.4 here)."""
    phi, n, reps = 0.95, 60_000, 120
    rng = np.random.default_rng(13)
    sd = 1 / math.sqrt(1 - phi ** 2)
    edges = np.linspace(-3, 3, 13) * sd
    D, S, S_iid = [], [], []
    for _ in range(reps):
        x = _ar1(rng, phi, n)
        h = st.StreamingHistogram(edges, on_outside="count")
        for part in np.array_split(x, 4):
            h.update(part)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a few samples beyond 3 sd
            r = h.result()
            r_iid = h.result(n_eff=n)
        D.append(r["density"])
        S.append(r["density_se"])
        S_iid.append(r_iid["density_se"])
    D, S, S_iid = np.array(D), np.array(S), np.array(S_iid)
    mid = slice(3, 9)  # -1.5 .. 1.5 sd
    ratio = D[:, mid].std(axis=0, ddof=1) / S[:, mid].mean(axis=0)
    assert np.all((ratio > 0.75) & (ratio < 1.33)), ratio
    cover = np.mean(np.abs(D[:, mid] - D[:, mid].mean(axis=0)) <= 2 * S[:, mid])
    assert 0.88 <= cover <= 0.99, cover
    assert np.all(S[:, mid].mean(axis=0) > 2 * S_iid[:, mid].mean(axis=0))
