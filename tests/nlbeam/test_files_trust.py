"""Result files and the scene cache you can trust (issue 18): every way a file can be bad is
refused with its own one-line message, a flipped byte in any dataset is detected, saving
never leaves a partial file or a temporary and never crashes the interpreter, and the scene
cache recomputes a bad or swapped entry."""
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import h5py
import numpy as np
import pytest

import continuation
import stochastic
from continuation.diagram import Bifurcation, Branch, FrequencyResponse
from helpers import PSD_FIGURE, TINY_STOCHASTIC, write_scene
from nlbeam.app.files import atomic, remove_stale_temporaries
from nlbeam.app.files.keys import _CODE, analysis_fingerprint, code_fingerprint
from nlbeam.app.files.stamped_hdf5 import (LegacyResultWarning, NewerWriterWarning,
                                           ResultFileError)
from stochastic.simulate import StochasticResult

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _frc(n=50):
    rng = np.random.default_rng(3)
    f = np.linspace(40.0, 45.0, n)
    br = Branch(order=1, parameter="frequency", values=f, frequency=f,
                amplitude=np.full(n, 1e-4), xmax=rng.random(n), stable=rng.random(n) > 0.5,
                multipliers=rng.random((n, 4)) + 1j * rng.random((n, 4)),
                state0=rng.random(4), states=rng.random((n, 4)),
                boundaries=rng.random((n, 2)))
    bif = Bifurcation(kind="fold", frequency=42.0, value=42.0, xmax=1e-3, order=1, branch=0,
                      tolerance=1e-6, multipliers=np.array([1.0 + 0j, 0.5 + 0j]))
    return FrequencyResponse(model_parameters={"e": 0.5}, amplitude=1e-4,
                             parameter="frequency", p_range=(40.0, 45.0), branches=[br],
                             bifurcations=[bif], settings={"n_grid": 3})


def _sto():
    f = np.linspace(0.0, 100.0, 51)
    return StochasticResult(
        channels=("delta",), outputs=("psd",), fs=200.0, dt=1e-4, t_start=0.0, transient=0.1,
        duration=1.0, method="rk4", seed=1, model_parameters={"e": 0.5},
        excitation_description={"kind": "band"}, nlbeam_version="0.1.0",
        psd_data={"delta": {"freq": f, "psd": np.exp(-f / 30), "dof": 12.0}})


def _bare(path, attrs):
    """An HDF5 file with one dataset and the given root attributes (no stamp)."""
    with h5py.File(path, "w") as h:
        h.create_dataset("x", data=np.arange(5.0))
        for k, v in attrs.items():
            h.attrs[k] = v


def _refused(fn, path, reason):
    with pytest.raises(ResultFileError) as exc:
        fn(path)
    assert exc.value.reason == reason, str(exc.value)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg
    return msg


def test_round_trip_is_stamped_and_silent(tmp_path):
    frc = _frc()
    frc.save(tmp_path / "a.h5")
    _sto().save(tmp_path / "b.h5")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = continuation.load(tmp_path / "a.h5")
        sto = stochastic.load(tmp_path / "b.h5")
    np.testing.assert_array_equal(back.branches[0].multipliers, frc.branches[0].multipliers)
    np.testing.assert_array_equal(sto.psd_data["delta"]["psd"], np.exp(-np.linspace(0, 100, 51)
                                                                       / 30))
    with h5py.File(tmp_path / "a.h5") as h:
        assert h.attrs["format"] == "nlbeam.frequency_response/2"
        assert "checksums" in h.attrs and h.attrs["written_by"].startswith("nlbeam ")
    assert sorted(os.listdir(tmp_path)) == ["a.h5", "b.h5"]  # no temporaries


@pytest.mark.parametrize("which", ["frc", "sto"])
def test_a_flipped_byte_in_any_dataset_is_detected(tmp_path, which):
    obj, load = (_frc(), continuation.load) if which == "frc" else (_sto(), stochastic.load)
    good = tmp_path / "good.h5"
    obj.save(good)
    with h5py.File(good) as h:
        names = []
        h.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        where = {n: (h[n].id.get_offset(), h[n].id.get_storage_size()) for n in names}
    assert len(names) >= (20 if which == "frc" else 2)
    flipped = 0
    for name in names:
        bad = tmp_path / "bad.h5"
        off, size = where[name]
        if off is None or size == 0:  # an empty dataset: no bytes to flip; change its shape
            shutil.copy(good, bad)
            with h5py.File(bad, "r+") as h:
                data = h[name][()]
                del h[name]
                h.create_dataset(name, data=np.zeros((len(data) + 1,) + data.shape[1:],
                                                     data.dtype))
        else:
            raw = bytearray(good.read_bytes())
            raw[off + size // 2] ^= 0x01  # one bit of one byte in the middle of the data
            bad.write_bytes(bytes(raw))
            flipped += 1
        msg = _refused(load, bad, "corrupted")
        assert f"dataset '{name}'" in msg, msg
    assert flipped >= len(names) // 2


def test_an_edited_attribute_is_detected_version_9_included(tmp_path):
    p = tmp_path / "a.h5"
    _frc().save(p)
    with h5py.File(p, "r+") as h:
        h.attrs["version"] = "9.0.0"  # claims to come from nlbeam 9.0.0
    msg = _refused(continuation.load, p, "corrupted")
    assert "attributes" in msg


def test_a_file_from_nlbeam_9_is_not_read_silently(tmp_path, monkeypatch):
    import nlbeam

    p = tmp_path / "a.h5"
    monkeypatch.setattr(nlbeam, "__version__", "9.0.0")
    _frc().save(p)  # a genuine file of format 2 written by nlbeam 9.0.0
    monkeypatch.undo()
    with pytest.warns(NewerWriterWarning, match="written by nlbeam 9.0.0"):
        assert len(continuation.load(p).branches) == 1


def test_wrong_kind_names_the_right_loader(tmp_path):
    _frc().save(tmp_path / "frc.h5")
    _sto().save(tmp_path / "sto.h5")
    msg = _refused(continuation.load, tmp_path / "sto.h5", "wrong-kind")
    assert "this is a stochastic result, use stochastic.load" in msg
    msg = _refused(stochastic.load, tmp_path / "frc.h5", "wrong-kind")
    assert "use continuation.load" in msg
    _bare(tmp_path / "other.h5", {})
    assert "not an nlbeam result" in _refused(continuation.load, tmp_path / "other.h5",
                                              "unknown")


def test_a_newer_format_asks_for_an_update(tmp_path):
    p = tmp_path / "a.h5"
    _sto().save(p)
    with h5py.File(p, "r+") as h:
        h.attrs["format"] = "nlbeam.stochastic.result/3"
    msg = _refused(stochastic.load, p, "newer-format")
    assert "written by format 3" in msg and "reads up to 2: update nlbeam" in msg


def test_empty_truncated_and_non_hdf5_files_each_have_their_message(tmp_path):
    good = tmp_path / "good.h5"
    _frc().save(good)
    raw = good.read_bytes()
    (tmp_path / "empty.h5").write_bytes(b"")
    (tmp_path / "half.h5").write_bytes(raw[:len(raw) // 2])
    (tmp_path / "text.h5").write_text("not a result\n")
    msgs = {_refused(continuation.load, tmp_path / "empty.h5", "empty"),
            _refused(continuation.load, tmp_path / "half.h5", "truncated"),
            _refused(stochastic.load, tmp_path / "text.h5", "not-hdf5")}
    assert len(msgs) == 3
    # a measured record given to a result loader: the message names the reader of records
    (tmp_path / "record.csv").write_text("t,x\n0.0,1.0\n")
    assert "stochastic.analyze" in _refused(continuation.load, tmp_path / "record.csv",
                                            "not-hdf5")
    with pytest.raises(FileNotFoundError, match="no such file"):
        continuation.load(tmp_path / "missing.h5")


def test_files_before_the_stamp_load_with_a_warning_unless_newer(tmp_path):
    p = tmp_path / "old.h5"
    _sto().save(p)
    with h5py.File(p, "r+") as h:  # what the writer produced before this change
        h.attrs["format"] = "nlbeam.stochastic.result/1"
        for k in ("checksums", "written_by"):
            del h.attrs[k]
    with pytest.warns(LegacyResultWarning, match="read without verification"):
        res = stochastic.load(p)
    assert res.channels == ("delta",)
    with h5py.File(p, "r+") as h:
        h.attrs["nlbeam_version"] = "9.0.0"
    assert "update nlbeam" in _refused(stochastic.load, p, "newer-format")
    # an old file missing a dataset: a clean message, not h5py's KeyError
    _bare(tmp_path / "broken.h5", {"format": "nlbeam.stochastic.result/1",
                                   "nlbeam_version": "0.1.0"})
    with pytest.warns(LegacyResultWarning):
        _refused(stochastic.load, tmp_path / "broken.h5", "incomplete")


class _HalfWriter:
    """A file whose writes fail half way, like a disk that fills up."""

    def __init__(self, fh):
        self.fh, self.fileno = fh, fh.fileno

    def write(self, data):
        self.fh.write(bytes(data[:len(data) // 2]))
        raise OSError(28, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.fh.close()


def test_a_write_failing_half_way_leaves_nothing_and_raises_one_line(tmp_path, monkeypatch):
    target = tmp_path / "sto.h5"
    target.write_bytes(b"previous")
    monkeypatch.setattr(atomic, "open", lambda p, m: _HalfWriter(open(p, m)), raising=False)
    with pytest.raises(OSError) as exc:
        _sto().save(target)
    msg = str(exc.value)
    assert "No space left on device" in msg and str(target) in msg and "\n" not in msg
    assert exc.value.errno == 28
    assert os.listdir(tmp_path) == ["sto.h5"] and target.read_bytes() == b"previous"


_CHILD = """
import importlib.util, os, sys
import numpy as np
# tests/helpers.py as the module "helpers" (as conftest.py registers it), then this file
spec = importlib.util.spec_from_file_location("helpers", {helpers!r})
sys.modules["helpers"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sys.modules["helpers"])
sys.path.insert(0, {tests!r})
from test_files_trust import _HalfWriter, _sto
from nlbeam.app.files import atomic
import h5py
if {mode!r} == "disk":
    atomic.open = lambda p, m: _HalfWriter(open(p, m))
else:  # HDF5 itself fails in the middle of the file
    real = h5py.Group.create_dataset
    def fail(self, name, *a, **k):
        if name == "psd":
            raise OSError(28, "No space left on device")
        return real(self, name, *a, **k)
    h5py.Group.create_dataset = fail
try:
    _sto().save(os.path.join({folder!r}, "sto.h5"))
except OSError as err:
    print("refused:", err)
"""


@pytest.mark.parametrize("mode", ["disk", "hdf5"])
def test_a_failed_save_does_not_crash_the_interpreter(tmp_path, mode):
    folder = tmp_path / "out"
    folder.mkdir()
    here = os.path.dirname(os.path.abspath(__file__))
    code = _CHILD.format(tests=here, helpers=os.path.join(os.path.dirname(here), "helpers.py"),
                         mode=mode, folder=str(folder))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.startswith("refused:") and "No space left" in r.stdout
    assert "HDF5-DIAG" not in r.stderr
    assert os.listdir(folder) == []


def test_saving_onto_a_full_tmpfs_leaves_nothing(tmp_path):
    mnt = tmp_path / "full"
    mnt.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a tmpfs needs root")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)],
                       capture_output=True)
    if r.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")
    try:
        big = _frc(n=20000)  # about 2.5 MB of arrays
        with pytest.raises(OSError, match="No space left on device"):
            big.save(mnt / "frc.h5")
        assert os.listdir(mnt) == []
    finally:
        subprocess.run(["umount", str(mnt)], check=True)


def test_a_read_only_folder_raises_one_line(tmp_path):
    from helpers import read_only_folder   # here: a child process above imports this module

    with read_only_folder(tmp_path / "ro") as ro:
        with pytest.raises(OSError, match="Permission denied|Read-only file system"):
            _frc().save(ro / "frc.h5")
        assert os.listdir(ro) == []


def test_sigterm_while_writing_removes_the_temporary(tmp_path):
    code = textwrap.dedent(f"""
        import sys, time
        from nlbeam.app.files import atomic_path
        with atomic_path({str(tmp_path / 'x.h5')!r}) as tmp:
            open(tmp, 'wb').write(b'0' * 100000)
            print(tmp, flush=True)
            time.sleep(60)
    """)
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, cwd=ROOT)
    tmp = p.stdout.readline().strip()
    assert os.path.exists(tmp)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=30)
    assert p.returncode == -signal.SIGTERM
    assert "terminated (SIGTERM)" in err and not os.path.exists(tmp)
    assert os.listdir(tmp_path) == []


def test_stale_temporaries_are_removed_young_ones_kept(tmp_path):
    old, young, other = tmp_path / ".tmp-aa.h5", tmp_path / ".tmp-bb.h5", tmp_path / "r.h5"
    for p in (old, young, other):
        p.write_bytes(b"x")
    t = time.time() - 7200
    os.utime(old, (t, t))
    os.utime(other, (t, t))
    assert remove_stale_temporaries(tmp_path, max_age=3600, dry_run=True) == [str(old)]
    assert old.exists()
    assert remove_stale_temporaries(tmp_path, max_age=3600) == [str(old)]
    assert sorted(os.listdir(tmp_path)) == [".tmp-bb.h5", "r.h5"]


def test_the_code_fingerprint_follows_the_source(tmp_path, monkeypatch):
    pkg = tmp_path / "fakepkg_ft"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("x = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    a = code_fingerprint(("fakepkg_ft",))
    (pkg / "__init__.py").write_text("x = 2\n")
    _CODE.clear()
    b = code_fingerprint(("fakepkg_ft",))
    (pkg / "__init__.py").write_text("x = 1\n")
    _CODE.clear()
    assert a != b and code_fingerprint(("fakepkg_ft",)) == a
    assert len(code_fingerprint()) == 16
    # a file left out (as the drawing code is left out of the analyses' keys) changes nothing
    (pkg / "plots").mkdir()
    (pkg / "plots" / "draw.py").write_text("y = 1\n")
    _CODE.clear()
    c = code_fingerprint(("fakepkg_ft",), exclude=("fakepkg_ft/plots",))
    assert c == a != code_fingerprint(("fakepkg_ft",))
    (pkg / "plots" / "draw.py").write_text("y = 2\n")
    _CODE.clear()
    assert code_fingerprint(("fakepkg_ft",), exclude=("fakepkg_ft/plots",)) == a
    (pkg / "__init__.py").write_text("x = 3\n")
    _CODE.clear()
    assert code_fingerprint(("fakepkg_ft",), exclude=("fakepkg_ft/plots",)) != a
    _CODE.clear()


def test_each_analysis_is_keyed_by_the_code_it_runs():
    from nlbeam.app.files.keys import ANALYSIS_CODE

    per, sto = ANALYSIS_CODE["periodic"], ANALYSIS_CODE["stochastic"]
    assert "stochastic" not in per[0] and "continuation" not in sto[0]
    assert "nlbeam" in per[0] and "nlbeam" in sto[0]
    # the scene code that builds the model and runs the analyses stays in both keys
    for pkgs, excl in (per, sto):
        assert not any(x.startswith("nlbeam/app/scenes/run") or x.startswith("nlbeam/_kernels")
                       or x in ("nlbeam/app", "nlbeam", "nlbeam/app/scenes") for x in excl)
    assert analysis_fingerprint("periodic") != analysis_fingerprint("stochastic")


SCENE = TINY_STOCHASTIC + PSD_FIGURE


def _scene_job(tmp_path, text, name):
    from nlbeam.app.scenes import load_scene, plan

    scene = load_scene(write_scene(tmp_path, text, name))
    (job,) = plan(scene, tmp_path / "out")
    return scene, job


def test_a_bom_at_the_start_of_a_scene_is_accepted(tmp_path):
    from nlbeam.app.scenes import load_scene

    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + SCENE.encode())
    assert load_scene(p).stochastic["seed"] == 1


def test_the_cache_refuses_swapped_truncated_and_empty_entries(tmp_path, monkeypatch):
    from nlbeam.app.scenes import format_plan, plan, run
    from nlbeam.app.scenes.run import run_scene, store_result

    scene, job = _scene_job(tmp_path, SCENE, "a.toml")
    assert job.inputs["code"] == analysis_fingerprint("stochastic")
    assert not job.cached and not job.problem
    store_result(job, _sto())
    (job,) = plan(scene, tmp_path / "out")
    assert job.cached and not job.problem
    other = _sto()
    other.psd_data["delta"]["psd"] = other.psd_data["delta"]["psd"] * 4.0
    _, job7 = _scene_job(tmp_path, SCENE.replace("seed = 1", "seed = 7"), "b.toml")
    store_result(job7, other)
    assert job7.path != job.path
    good = open(job.path, "rb").read(), open(job.path[:-3] + ".json").read()

    def problem():
        (j,) = plan(scene, tmp_path / "out")
        assert not j.cached
        return j.problem

    # another valid result swapped in: its bytes are not the recorded ones
    shutil.copy(job7.path, job.path)
    assert "differ from the recorded checksum" in problem()
    # its record swapped in too: the inputs recorded are another scene's
    shutil.copy(job7.path[:-3] + ".json", job.path[:-3] + ".json")
    assert "records other inputs" in problem()
    # truncated, and empty
    with open(job.path[:-3] + ".json", "w") as fh:
        fh.write(good[1])
    with open(job.path, "wb") as fh:
        fh.write(good[0][:len(good[0]) // 2])
    assert "differ" in problem()
    open(job.path, "wb").close()
    assert problem()
    # a damaged file whose record was rewritten to match: the file's own checksums
    raw = bytearray(good[0])
    with open(job.path, "wb") as fh:
        fh.write(good[0])
    with h5py.File(job.path, "r+") as h:
        off = h["channels/delta/psd/psd"].id.get_offset()
    raw[off + 3] ^= 0x10
    with open(job.path, "wb") as fh:
        fh.write(bytes(raw))
    from nlbeam.app.scenes.plan import entry_record
    with open(job.path[:-3] + ".json", "w") as fh:
        fh.write(entry_record(job.inputs, job.path))
    assert "dataset 'channels/delta/psd/psd'" in problem()
    # --dry-run says what it would recompute; run recomputes it with a warning naming it
    assert "cached entry refused, recomputed" in format_plan(scene, plan(scene, tmp_path
                                                                         / "out"), "out")
    monkeypatch.setattr(run, "compute", lambda inputs: _sto())
    monkeypatch.setattr(run, "write_outputs", lambda *a: [])
    stale = tmp_path / "out" / ".nlbeam-cache" / ".tmp-dead.h5"
    stale.write_bytes(b"x")
    os.utime(stale, (time.time() - 2 * run.STALE_AGE,) * 2)
    lines = []
    rep = run_scene(scene, tmp_path / "out", log=lines.append)
    assert rep.computed == 1
    assert any("warning: cache entry" in ln and job.path in ln for ln in lines), lines
    assert not stale.exists()
    (job,) = plan(scene, tmp_path / "out")
    assert job.cached
