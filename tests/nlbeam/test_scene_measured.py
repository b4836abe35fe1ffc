"""A scene driven by a measured base motion and overlaid with a measured response (issue 17):
[stochastic] record = "base.csv" simulates under stochastic.Recorded of that file, [measured]
analyses the 'rig' record by the simulation's estimators and adds it to the tables and
figures. The 'rig' record here is the toolkit's own simulation under the same base motion,
written to CSV: the measured and simulated moments must then agree to the CSV's digits."""
import csv

import numpy as np
import pytest

import nlbeam
import stochastic
from nlbeam.scenes import SceneError, load_scene, run_scene

FS, T, D = 4000.0, 0.5, 3.0  # Hz, transient s, kept s

SCENE = """
title = "measured base motion"
[stochastic]
record = "base.csv"
duration = 3.0
transient = 0.5
psd_resolution = 2.0
band = [0.0, 100.0]
[measured]
file = "rig.csv"
channels = ["delta", "y"]
label = "rig"
psd_resolution = 2.0
[[figure]]
kind = "psd"
file = "psd.png"
[[figure]]
kind = "pdf"
file = "pdf.png"
[[figure]]
kind = "excitation_psd"
file = "y.png"
[[table]]
kind = "moments"
file = "moments.csv"
"""


def _write_csv(path, cols):
    names = list(cols)
    with open(path, "w", newline="") as fh:
        fh.write(",".join(names) + "\n")
        for row in zip(*(cols[n] for n in names)):
            fh.write(",".join(f"{v:.17g}" for v in row) + "\n")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("measured")
    noise = stochastic.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=3, lowpass=40.0)
    t = np.arange(int((T + D) * FS) + 41) / FS  # the record covers transient + duration
    y = noise.sampled(t[-1] + 0.01).evaluate(t)[0]
    _write_csv(d / "base.csv", {"t": t, "y": y})
    # the 'rig': the same model (the scene's default, the paper's) under that base motion
    rig = stochastic.simulate(nlbeam.BeamImpact(), stochastic.Recorded(t, y), D, T,
                              channels=("delta", "y"), outputs=("moments",),
                              keep_history=(0.0, D))
    h = rig.history
    _write_csv(d / "rig.csv", {"t": h["t"], "delta": h["delta"], "y": h["y"]})
    (d / "scene.toml").write_text(SCENE)
    return d


def _moments(path):
    with open(path) as fh:
        return {r["variant"]: r for r in csv.DictReader(fh)}


def test_measured_excitation_and_overlay_end_to_end(folder):
    rep = run_scene(folder / "scene.toml", folder / "out", quiet=True)
    assert rep.computed == 1
    (job,) = rep.jobs
    assert "under the record base.csv (y)" in job.description
    for f in ("psd.png", "pdf.png", "y.png", "moments.csv"):
        assert (folder / "out" / f).stat().st_size > (100 if f.endswith(".csv") else 5000), f
    rows = _moments(folder / "out" / "moments.csv")
    assert set(rows) == {"", "rig"}
    sim = stochastic.load(job.path).moments("delta")
    meas = stochastic.analyze(*_columns(folder / "rig.csv")).moments("delta")
    # the same record through two paths (streamed in simulate; CSV -> analyze)
    for key in ("mean", "std", "skewness", "kurtosis"):
        assert meas[key] == pytest.approx(sim[key], rel=1e-9, abs=1e-15), key
    assert float(rows["rig"]["std"]) == pytest.approx(float(rows[""]["std"]), rel=1e-3)
    assert float(rows[""]["std"]) == pytest.approx(sim["std"], rel=1e-2)


def _columns(path):
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return data[:, 0], {"delta": data[:, 1]}


def test_the_cache_follows_the_record_and_bad_files_are_named(folder, tmp_path):
    d = tmp_path
    for f in ("base.csv", "rig.csv", "scene.toml"):
        (d / f).write_bytes((folder / f).read_bytes())
    first = run_scene(d / "scene.toml", d / "out", quiet=True)
    assert run_scene(d / "scene.toml", d / "out", quiet=True).computed == 0
    t, y = np.loadtxt(d / "base.csv", delimiter=",", skiprows=1).T
    _write_csv(d / "base.csv", {"t": t, "y": 1.1 * y})  # other data, same name
    again = run_scene(d / "scene.toml", d / "out", quiet=True)
    assert again.computed == 1 and again.jobs[0].path != first.jobs[0].path
    std = [stochastic.load(r.jobs[0].path).moments("y")["std"] for r in (first, again)]
    assert std[1] == pytest.approx(1.1 * std[0], rel=1e-6)  # y is the record itself
    (d / "bad.toml").write_text(SCENE.replace('record = "base.csv"',
                                              'record = "base.csv"\nrecord_column = "yb"'))
    with pytest.raises(SceneError, match=r"bad.toml:4: stochastic.record: base.csv: no column "
                                         r"'yb'; the file has 't', 'y'"):
        load_scene(d / "bad.toml")
    (d / "long.toml").write_text(SCENE.replace("duration = 3.0", "duration = 30.0"))
    with pytest.raises(SceneError, match=r"long.toml:5: stochastic.duration: transient \+ "
                                         r"duration = 30.5 s exceed the record base.csv"):
        load_scene(d / "long.toml")
    (d / "bad2.toml").write_text(SCENE.replace('"rig.csv"', '"nowhere.csv"'))
    with pytest.raises(SceneError, match=r"measured.file: nowhere.csv: no such file"):
        load_scene(d / "bad2.toml")


def test_measured_peaks_join_the_comparison(folder, tmp_path):
    """The measured record's PSD peaks are mapped onto the diagram like the simulation's and
    listed under its label; the comparison figure is drawn with it."""
    d = tmp_path
    for f in ("base.csv", "rig.csv"):
        (d / f).write_bytes((folder / f).read_bytes())
    (d / "scene.toml").write_text(
        SCENE + '[periodic]\namplitude = 1e-4\nf_range = [40.0, 48.0]\norders = [1]\n'
        'n_grid = 3\n[[figure]]\nkind = "compare"\nfile = "compare.png"\nf_max = 100.0\n'
        '[[table]]\nkind = "peaks"\nfile = "peaks.csv"\nf_max = 100.0\n')
    run_scene(d / "scene.toml", d / "out", quiet=True)
    with open(d / "out" / "peaks.csv") as fh:
        rows = list(csv.DictReader(fh))
    sim = [(r["frequency_hz"], r["kind"]) for r in rows if r["variant"] == ""]
    rig = [(r["frequency_hz"], r["kind"]) for r in rows if r["variant"] == "rig"]
    assert sim and rig == sim  # the same record: the same peaks, the same explanations
    assert (d / "out" / "compare.png").stat().st_size > 5000
