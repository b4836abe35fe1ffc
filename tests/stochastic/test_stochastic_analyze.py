"""stochastic.analyze: a measured record through simulate's estimators.

A record simulated under actuator-shaped (low-passed) base noise, kept whole, written to CSV
and read back gives the simulation's own PSD, PDF and moments (same samples: equal to
rounding); with 30 % of its samples dropped and resampled, within the standard errors; a
sine sampled at jittered times gives its analytic moments and power; bad input gives
one-line errors naming the argument or column.
"""
import math

import numpy as np
import pytest

import nlbeam
import stochastic as st
from nlbeam.app.cli import main
from nlbeam.app.files.columns import read_columns
from nlbeam.compare import map_peaks

CHANNELS = ("delta", "x", "y")


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    noise = st.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=3, lowpass=40.0)
    res = st.simulate(nlbeam.BeamImpact(), noise, 3.0, transient=0.2, channels=CHANNELS,
                      psd_resolution=2.0, keep_history=(0.0, 3.0))
    path = tmp_path_factory.mktemp("rec") / "record.csv"
    cols = ("t",) + CHANNELS
    table = np.column_stack([res.history[c] for c in cols])
    np.savetxt(path, table, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
    return res, noise, path


def test_record_kept_whole(record):
    res, _, _ = record
    assert res.history["t"].size == res.n_samples and res.n_impacts > 0


def test_same_samples_same_statistics(record):
    res, noise, path = record
    cols = read_columns(path, required=("t",) + CHANNELS)
    got = st.analyze(cols["t"], {c: cols[c] for c in CHANNELS}, psd_resolution=2.0,
                     pdf_edges={c: res.pdf_details(c)["edges"] for c in CHANNELS},
                     min_error_window=2 * noise.realization_duration)
    assert got.method == "measured" and got.excitation_description["resample"] == "none"
    assert got.fs == pytest.approx(res.fs, rel=1e-12)
    for c in CHANNELS:
        f0, p0 = res.psd(c)
        f1, p1 = got.psd(c)
        np.testing.assert_allclose(f1, f0, rtol=1e-9)
        np.testing.assert_allclose(p1, p0, rtol=1e-9, atol=1e-12 * p0.max())
        assert got.n_averages(c) == res.n_averages(c)
        np.testing.assert_array_equal(got.pdf_details(c)["counts"], res.pdf_details(c)["counts"])
        m0, m1 = res.moments(c), got.moments(c)
        for k in ("mean", "std", "skewness", "kurtosis", "p_positive", "se_mean", "se_std",
                  "se_skewness", "se_kurtosis"):
            assert m1[k] == pytest.approx(m0[k], rel=1e-8, abs=1e-12 * abs(m0["std"])), (c, k)


@pytest.mark.parametrize("method", ["linear", "cubic"])
def test_resampled_record_within_errors(record, method):
    res, noise, _ = record
    h = res.history
    rng = np.random.default_rng(7)
    keep = rng.random(h["t"].size) > 0.3
    keep[[0, -1]] = True
    with pytest.warns(RuntimeWarning, match="largest step is 9 times the median"):
        got = st.analyze(h["t"][keep], {c: h[c][keep] for c in CHANNELS}, psd_resolution=2.0,
                         resample=method, min_error_window=2 * noise.realization_duration)
    assert got.excitation_description["resample"] == method
    assert got.fs == pytest.approx(res.fs, rel=1e-9)  # the median step is the original one
    for c in CHANNELS:
        m0, m1 = res.moments(c), got.moments(c)
        for k in ("mean", "std", "skewness", "kurtosis"):
            assert abs(m1[k] - m0[k]) < m0[f"se_{k}"], (c, k, m1[k], m0[k], m0[f"se_{k}"])
        f, p0 = res.psd(c)
        band = (f > 1.0) & (f < 100.0)
        rel = np.abs(got.psd(c)[1][band] / p0[band] - 1.0)
        assert np.all(rel < res.psd_relative_std(c)[band]), (c, rel.max())
        x0, d0 = res.pdf(c)
        x1, d1 = got.pdf(c)
        # same probability below each quartile of the simulated record, within 2 se
        for q in np.quantile(h[c], [0.25, 0.5, 0.75]):
            p_sim = np.mean(h[c] <= q)
            p_got = np.sum(d1[x1 <= q]) * np.diff(x1[:2])[0]
            assert abs(p_got - p_sim) < 0.02, (c, q, p_got, p_sim)


def test_sine_at_jittered_times_analytic():
    # x = A sin(2 pi f0 t) sampled at jittered times: after cubic resampling the std is
    # A / sqrt(2), the kurtosis 1.5, and the PSD holds A^2 / 2 around f0
    rng = np.random.default_rng(3)
    A, f0, fs = 2e-3, 37.0, 2000.0
    t = np.arange(40000) / fs + rng.uniform(-0.3, 0.3, 40000) / fs
    got = st.analyze(t, {"x": A * np.sin(2 * np.pi * f0 * t)}, resample="cubic",
                     psd_resolution=1.0)
    m = got.moments("x")
    assert m["std"] == pytest.approx(A / math.sqrt(2), rel=1e-4)
    assert m["kurtosis"] == pytest.approx(1.5, abs=1e-3)
    f, P = got.psd("x")
    near = np.abs(f - f0) < 4.0
    assert np.sum(P[near]) * (f[1] - f[0]) == pytest.approx(A * A / 2, rel=1e-2)
    assert f[np.argmax(P)] == pytest.approx(f0, abs=1.0)


def test_map_peaks_accepts_the_measured_psd():
    from types import SimpleNamespace

    from scipy.signal import lfilter

    # a resonator at 40 Hz (poles r e^{+-i 2 pi 40 / fs}) driven by white noise, 'measured'
    fs, f0, r = 1000.0, 40.0, 0.995
    rng = np.random.default_rng(5)
    a = [1.0, -2 * r * math.cos(2 * math.pi * f0 / fs), r * r]
    x = lfilter([1.0], a, rng.standard_normal(200000))
    got = st.analyze(np.arange(x.size) / fs, {"x": x}, psd_resolution=0.5, band=(0.0, 200.0))
    f1 = np.linspace(5.0, 80.0, 751)
    branch = SimpleNamespace(order=1, frequency=f1, xmax=1e-4 + 1e-3 / (1 + (f1 - 40.0) ** 2),
                             stable=np.ones(f1.size, bool))
    diagram = SimpleNamespace(branches=[branch], bifurcations=[], superharmonics=[])
    d = got.excitation_description
    m = map_peaks(got.psd("x"), diagram, (d["band_lo"], d["band_hi"]), f_range=(5.0, 100.0))
    top = max(m, key=lambda p: p.prominence)
    assert top.frequency == pytest.approx(f0, abs=1.0)
    assert (top.kind, top.order) == ("harmonic", 1)


_T = np.arange(1000) / 1000.0
_X = np.sin(2 * np.pi * 7.0 * _T)


@pytest.mark.parametrize("t, signals, kw, match", [
    (np.where(_T == _T[5], np.nan, _T), {"x": _X}, {}, r"^t: sample 5 is not finite"),
    (np.r_[_T[:10], _T[9], _T[11:]], {"x": _X}, {}, r"^t: repeated time"),
    (np.r_[_T[:10], _T[8], _T[11:]], {"x": _X}, {}, r"^t: not monotone"),
    (_T, {"x": np.where(_T == _T[3], np.inf, _X)}, {}, r"^signals\['x'\]: sample 3 is not"),
    (_T, {"x": np.full(1000, 0.1)}, {}, r"^signals\['x'\]: constant"),
    (_T, {"x": _X[:-1]}, {}, r"^signals\['x'\]: 999 samples, t has 1000"),
    (_T, {"x": _X}, {"psd_resolution": 0.5}, r"^psd_resolution: 0.5 Hz needs segments of 2 s"),
    (_T, {"disp": _X}, {}, r"^signals: unknown channel name 'disp'; use one of x, v, y"),
    (np.r_[_T[:10], _T[10:] + 1e-4], {"x": _X}, {"resample": "spline"}, r"^resample: must be"),
])
def test_bad_arrays(t, signals, kw, match):
    with pytest.raises(ValueError, match=match) as err:
        st.analyze(t, signals, **kw)
    assert "\n" not in str(err.value)


def _csv(path, text):
    path.write_text(text)
    return str(path)


def test_command_writes_a_statistics_file(record, tmp_path, capsys):
    res, noise, path = record
    out = tmp_path / "stats.h5"
    assert main(["analyze", str(path), "--channels", "delta", "x", "--psd-resolution", "2",
                 "--out", str(out), "--band", "0", "100"]) == 0
    got = st.load(out)
    assert got.channels == ("delta", "x") and got.method == "measured"
    np.testing.assert_allclose(got.psd("x")[1], res.psd("x")[1], rtol=1e-9,
                               atol=1e-12 * res.psd("x")[1].max())
    assert "delta" in capsys.readouterr().out


@pytest.mark.parametrize("text, args, match", [
    ("t,x\n0,1\n1,2\n2,3\n", ["--channels", "delta"], "no column 'delta'; the file has 't', 'x'"),
    ("time,x\n0,1\n1,2\n2,3\n", ["--channels", "x"], "no column 't'"),
    ("t,x\n0,1\n2,2\n1,3\n", ["--channels", "x"], "t: not monotone"),
    ("t,x\n0,1\n1,nan\n2,3\n", ["--channels", "x"], "signals\\['x'\\]: sample 1 is not finite"),
    ("t,x\n0,1\n1,1\n2,1\n", ["--channels", "x"], "signals\\['x'\\]: constant"),
])
def test_command_bad_files(tmp_path, capsys, text, args, match):
    f = _csv(tmp_path / "bad.csv", text)
    assert main(["analyze", f, *args, "--out", str(tmp_path / "o.h5")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert __import__("re").search(match, err), err
