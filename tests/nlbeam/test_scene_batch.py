"""`nlbeam figures` runs its scenes as one job (nlbeam.app.scenes.batch.run_scenes): every
missing analysis once, the records while the kernels compile, the costliest diagram here and
the rest in a forked process. The cache entries, tables and figures are those of one scene
after the other (run_scene each), byte for byte."""
import filecmp
import os

import h5py
import numpy as np

from helpers import TINY_DIAGRAM, TINY_STOCHASTIC, write_scene
from nlbeam.app.scenes.batch import run_scenes
from nlbeam.scenes import load_scene, run_scene

DIAGRAM = TINY_DIAGRAM
FIRST = 'title = "first"\n' + DIAGRAM + TINY_STOCHASTIC + """
[[figure]]
kind = "compare"
channel = "delta"
file = "first_compare.png"
[[table]]
kind = "peaks"
channel = "delta"
file = "first_peaks.csv"
"""
SECOND = 'title = "second"\n' + DIAGRAM + TINY_STOCHASTIC.replace("seed = 1", "seed = 2") + """
[[table]]
kind = "moments"
channel = "delta"
file = "second_moments.csv"
[[table]]
kind = "bifurcations"
file = "second_bifurcations.csv"
"""
MODAL = 'title = "modal"\n[model]\nname = "ModalBeam"\nn_modes = 2\n' + DIAGRAM + """
[[table]]
kind = "bifurcations"
file = "modal_bifurcations.csv"
"""


def _scenes(tmp_path):
    return [load_scene(write_scene(tmp_path, text, f"{name}.toml"))
            for name, text in (("first", FIRST), ("modal", MODAL), ("second", SECOND))]


def _h5_arrays(path):
    """Every dataset of an HDF5 file (name -> array); attributes are the file's stamp."""
    out = {}
    with h5py.File(path, "r") as h:
        h.visititems(lambda name, obj: out.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
    return out


def _same(a, b):
    """Equal arrays of one dtype, NaN where the other has NaN."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    try:
        return np.array_equal(a, b, equal_nan=True)
    except TypeError:   # not numbers
        return np.array_equal(a, b)


def test_scenes_as_one_job_give_the_outputs_of_one_after_the_other(tmp_path):
    scenes = _scenes(tmp_path)
    one, batch = tmp_path / "one", tmp_path / "batch"
    computed = sum(run_scene(sc, one, quiet=True).computed for sc in scenes)
    reports = run_scenes(scenes, batch, quiet=True, workers=2)
    assert computed == 4   # the paper diagram shared, the modal one, two records
    assert [r.computed for r in reports] == [0, 0, 0]   # all computed before the drawing
    assert all(r.reused == len({j.path for j in r.jobs}) for r in reports)
    names = sorted(f for f in os.listdir(one) if f.endswith((".csv", ".png")))
    assert names == sorted(f for f in os.listdir(batch) if f.endswith((".csv", ".png")))
    for f in names:
        assert filecmp.cmp(one / f, batch / f, shallow=False), f
    cache = sorted(f for f in os.listdir(one / ".nlbeam-cache") if f.endswith(".h5"))
    assert len(cache) == 4
    assert cache == sorted(f for f in os.listdir(batch / ".nlbeam-cache") if f.endswith(".h5"))
    for f in cache:
        a, b = _h5_arrays(one / ".nlbeam-cache" / f), _h5_arrays(batch / ".nlbeam-cache" / f)
        assert sorted(a) == sorted(b), f
        for k in a:
            if "wall_time" in k:
                continue
            assert _same(a[k], b[k]), (f, k)


def test_a_cached_batch_draws_nothing_again(tmp_path):
    scenes = _scenes(tmp_path)
    out = tmp_path / "o"
    run_scenes(scenes, out, quiet=True)
    written = {f: os.stat(out / f).st_mtime_ns for f in os.listdir(out)
               if f.endswith((".csv", ".png"))}
    again = run_scenes(scenes, out, quiet=True)
    assert [r.computed for r in again] == [0, 0, 0] and len(written) == 5
    assert written == {f: os.stat(out / f).st_mtime_ns for f in written}   # none drawn again
