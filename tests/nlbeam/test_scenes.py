"""nlbeam.scenes: a scene computes only what its outputs need, caches each analysis under a
key of exactly its inputs, reuses it, and refuses a malformed file before any work.

The analyses are counted by wrapping continuation.frequency_response and stochastic.simulate
(the scene looks them up at call time). Settings are tiny: 1.5 s records, a 3-point diagram.
"""
import json
import os

import pytest

import continuation
import stochastic
from nlbeam.scenes import SceneError, load_scene, plan, run_scene

STOCH = """
[stochastic]
band = [0.0, 100.0]
rms = 1e-4
seed = 1
duration = 1.5
transient = 0.1
psd_resolution = 2.0
"""
PERIODIC = """
[periodic]
amplitude = 1e-4
f_range = [42.0, 45.0]
orders = [1]
n_grid = 3
"""
PSD_FIG = """
[[figure]]
kind = "psd"
file = "psd.png"
"""


@pytest.fixture
def calls(monkeypatch):
    n = {"frc": 0, "sim": 0}
    frc0, sim0 = continuation.frequency_response, stochastic.simulate

    def frc(*a, **k):
        n["frc"] += 1
        return frc0(*a, **k)

    def sim(*a, **k):
        n["sim"] += 1
        return sim0(*a, **k)

    monkeypatch.setattr(continuation, "frequency_response", frc)
    monkeypatch.setattr(stochastic, "simulate", sim)
    return n


def _write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _files(d):
    return sorted(os.path.relpath(os.path.join(r, f), d) for r, _, fs in os.walk(d) for f in fs)


def test_psd_only_scene_runs_no_continuation_and_stores_no_history(tmp_path, calls):
    scene = _write(tmp_path, 'title = "psd only"\n' + PERIODIC + STOCH + PSD_FIG)
    out = tmp_path / "out"
    rep = run_scene(scene, out, quiet=True)
    assert calls == {"frc": 0, "sim": 1}
    assert [j.kind for j in rep.jobs] == ["stochastic"]
    inputs = rep.jobs[0].inputs
    assert inputs["channels"] == ["delta"] and inputs["outputs"] == ["psd"]
    assert inputs["history"] is None
    assert stochastic.load(rep.jobs[0].path).history is None
    assert (out / "psd.png").stat().st_size > 1000


def test_rerun_computes_nothing_and_a_new_seed_recomputes_only_the_stochastic_part(tmp_path, calls):
    text = PERIODIC + STOCH + PSD_FIG + '[[figure]]\nkind = "frc"\nfile = "frc.png"\n' \
        + '[[table]]\nkind = "peaks"\nfile = "peaks.csv"\n'
    scene = _write(tmp_path, text)
    out = tmp_path / "out"
    first = run_scene(scene, out, quiet=True)
    assert calls == {"frc": 1, "sim": 1} and first.computed == 2
    cache = {j.kind: j.path for j in first.jobs}
    stamp = {k: os.stat(p).st_mtime_ns for k, p in cache.items()}
    # unchanged: nothing computed, cache files untouched, outputs rewritten
    again = run_scene(scene, out, quiet=True)
    assert calls == {"frc": 1, "sim": 1} and again.computed == 0
    assert all(j.cached for j in again.jobs)
    assert {k: os.stat(p).st_mtime_ns for k, p in cache.items()} == stamp
    # the key is exactly the inputs, written beside the result
    key = json.loads(open(cache["periodic"][:-3] + ".json").read())
    assert set(key) == {"analysis", "model", "periodic", "version"}
    # a new seed: only the stochastic analysis runs again
    scene.write_text(text.replace("seed = 1", "seed = 2"))
    third = run_scene(scene, out, quiet=True)
    assert calls == {"frc": 1, "sim": 2} and third.computed == 1
    assert [j.kind for j in third.jobs if not j.cached] == ["stochastic"]
    # a model parameter feeds both
    scene.write_text("[model]\ne = 0.6\n" + text)
    run_scene(scene, out, quiet=True)
    assert calls == {"frc": 2, "sim": 3}


def test_dry_run_plans_without_work(tmp_path, calls):
    scene = _write(tmp_path, PERIODIC + STOCH + '[[figure]]\nkind = "history"\nfile = "h.png"\n'
                   'window = [0.0, 0.2]\nchannels = ["y", "x"]\n')
    rep = run_scene(scene, tmp_path / "out", dry_run=True)
    assert calls == {"frc": 0, "sim": 0}
    assert not (tmp_path / "out").exists()
    (job,) = rep.jobs
    assert job.kind == "stochastic" and not job.cached
    assert job.inputs["history"] == [0.0, 0.2] and job.inputs["outputs"] == []
    assert job.inputs["channels"] == ["x", "y"]


BAD = [
    (STOCH.replace("rms = 1e-4", "rsm = 1e-4") + PSD_FIG, "stochastic.rsm", 4, "unknown key"),
    (STOCH.replace("seed = 1", 'seed = "one"') + PSD_FIG, "stochastic.seed", 5, "integer"),
    ("[model]\ne = 1.5\n" + STOCH + PSD_FIG, "model.e", 2, "<= 1"),
    (STOCH + PSD_FIG.replace('"psd"', '"spectrum"'), "figure[0].kind", 11, "one of"),
    (STOCH + PSD_FIG + '[[figure]]\nkind = "frc"\nfile = "f.png"\n', "figure[1].kind", 14,
     "needs a [periodic] section"),
    (STOCH.replace("band = [0.0, 100.0]", "band = [100.0, 10.0]") + PSD_FIG, "stochastic.band",
     3, "lo < hi"),
    ("[model]\ncontact = \"hunt-crossley\"\n" + STOCH + PSD_FIG, "model.mu", None, "required"),
]


@pytest.mark.parametrize("text,key,line,what", BAD)
def test_malformed_scene_fails_before_work_naming_key_and_line(tmp_path, calls, text, key,
                                                               line, what):
    scene = _write(tmp_path, text)
    out = tmp_path / "out"
    with pytest.raises(SceneError) as err:
        run_scene(scene, out, quiet=True)
    msg = str(err.value)
    assert key in msg and what in msg, msg
    if line is not None:
        assert f"scene.toml:{line}:" in msg, msg
    assert calls == {"frc": 0, "sim": 0}
    assert not out.exists()


def test_failed_analysis_leaves_no_output_file(tmp_path, monkeypatch):
    def boom(*a, **k):
        raise RuntimeError("integration failed")

    monkeypatch.setattr(stochastic, "simulate", boom)
    scene = _write(tmp_path, STOCH + PSD_FIG)
    out = tmp_path / "out"
    with pytest.raises(RuntimeError, match="integration failed"):
        run_scene(scene, out, quiet=True)
    assert not out.exists() or _files(out) == []


def test_bundled_scenes_are_valid():
    import glob

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    paths = sorted(glob.glob(os.path.join(root, "figures", "*.toml")))
    assert paths
    for p in paths:
        sc = load_scene(p)
        assert sc.figures, p
        plan(sc, os.path.join(root, "figures"))
