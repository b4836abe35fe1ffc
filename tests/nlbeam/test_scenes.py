"""nlbeam.scenes: a scene computes only what its outputs need, caches each analysis under a
key of exactly its inputs, reuses it, and refuses a malformed file before any work.

The analyses are counted by wrapping continuation.frequency_response and stochastic.simulate
(the scene looks them up at call time). Settings are tiny: 1.5 s records, a 3-point diagram.
"""
import csv
import functools
import json
import math
import os
from types import SimpleNamespace

import numpy as np
import pytest

import continuation
import stochastic
from helpers import PSD_FIGURE, TINY_STOCHASTIC, write_scene
from nlbeam.scenes import SceneError, load_scene, plan, run_scene

STOCH = TINY_STOCHASTIC
PERIODIC = """
[periodic]
amplitude = 1e-4
f_range = [42.0, 45.0]
orders = [1]
n_grid = 3
"""
PSD_FIG = PSD_FIGURE


@pytest.fixture
def calls(monkeypatch):
    n = {"frc": 0, "sim": 0}
    frc0, sim0 = continuation.frequency_response, stochastic.simulate

    @functools.wraps(frc0)
    def frc(*a, **k):
        n["frc"] += 1
        return frc0(*a, **k)

    @functools.wraps(sim0)
    def sim(*a, **k):
        n["sim"] += 1
        return sim0(*a, **k)

    monkeypatch.setattr(continuation, "frequency_response", frc)
    monkeypatch.setattr(stochastic, "simulate", sim)
    return n


def _files(d):
    return sorted(os.path.relpath(os.path.join(r, f), d) for r, _, fs in os.walk(d) for f in fs)


def test_psd_only_scene_runs_no_continuation_and_stores_no_history(tmp_path, calls):
    scene = write_scene(tmp_path, 'title = "psd only"\n' + PERIODIC + STOCH + PSD_FIG)
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
    scene = write_scene(tmp_path, text)
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
    # the key is exactly the inputs (and the code), written beside the result with its hash
    rec = json.loads(open(cache["periodic"][:-3] + ".json").read())
    assert set(rec) == {"inputs", "result_sha256", "warnings"}
    assert set(rec["inputs"]) == {"analysis", "model", "periodic", "code"}
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
    scene = write_scene(tmp_path, PERIODIC + STOCH + '[[figure]]\nkind = "history"\n'
                        'file = "h.png"\nwindow = [0.0, 0.2]\nchannels = ["y", "x"]\n')
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
    scene = write_scene(tmp_path, text)
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
    scene = write_scene(tmp_path, STOCH + PSD_FIG)
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


@pytest.fixture
def umask_027():
    old = os.umask(0o027)
    yield 0o640
    os.umask(old)


def test_cache_and_outputs_get_the_usual_mode(tmp_path, umask_027):
    # results were written through tempfile.mkstemp (0600); now 0666 minus the umask
    scene = write_scene(tmp_path, PERIODIC + STOCH + PSD_FIG + '[[table]]\nkind = "bifurcations"\n'
                   'file = "b.csv"\n')
    out = tmp_path / "out"
    run_scene(scene, out, quiet=True)
    files = _files(out)
    assert {f for f in files if f.endswith(".h5")} and "psd.png" in files and "b.csv" in files
    modes = {f: oct(os.stat(out / f).st_mode & 0o777) for f in files}
    assert set(modes.values()) == {oct(umask_027)}, modes
    assert not [f for f in files if os.path.basename(f).startswith(".tmp-")]


def _frc_with_stability(seen):
    real = continuation.frequency_response

    def frc(model, amplitude, f_range, orders=(1, 2, 3), *, stability=True, **kw):
        seen.append(stability)
        return real(model, amplitude, f_range, orders=orders, stability=stability, **kw)
    return frc


PEAKS_NO_STAB = '[[table]]\nkind = "peaks"\nfile = "peaks.csv"\nstability = false\n'


def test_no_stability_where_none_is_shown(tmp_path, monkeypatch):
    seen = []
    monkeypatch.setattr(continuation, "frequency_response", _frc_with_stability(seen))
    # a 6 s record: 1.5 s at 2 Hz (2 Welch segments) has no significant peak
    scene = write_scene(tmp_path, PERIODIC + STOCH.replace("duration = 1.5", "duration = 6.0")
                        + PEAKS_NO_STAB)
    out = tmp_path / "out"
    rep = run_scene(scene, out, quiet=True)
    assert seen == [False]
    (per,) = [j for j in rep.jobs if j.kind == "periodic"]
    assert per.inputs["periodic"]["stability"] is False
    rec = json.loads(open(per.path[:-3] + ".json").read())
    assert rec["inputs"]["periodic"]["stability"] is False
    rows = list(csv.DictReader(open(out / "peaks.csv")))
    assert rows and all(r["stable"] == "" for r in rows)
    # a diagram figure shows stability: another cache entry, computed with it
    scene.write_text(PERIODIC + STOCH + PEAKS_NO_STAB + '[[figure]]\nkind = "frc"\nfile = '
                                                        '"f.png"\n')
    rep2 = run_scene(scene, out, quiet=True)
    (per2,) = [j for j in rep2.jobs if j.kind == "periodic"]
    assert seen == [False, True] and per2.path != per.path
    assert per2.inputs["periodic"]["stability"] is True


def test_stability_only_for_outputs_that_can_do_without(tmp_path, calls):
    text = PERIODIC + STOCH + '[[figure]]\nkind = "frc"\nfile = "f.png"\nstability = false\n'
    scene = write_scene(tmp_path, text)
    with pytest.raises(SceneError) as err:
        load_scene(scene)
    line = text.splitlines().index("stability = false") + 1
    assert f"scene.toml:{line}: figure[0].stability: only compare and peaks" in str(err.value)
    text = STOCH + '[[table]]\nkind = "moments"\nfile = "m.csv"\nf_max = 50.0\n'
    scene.write_text(text)
    with pytest.raises(SceneError, match="table\\[0\\].f_max: only a peaks table"):
        load_scene(scene)


def test_peaks_table_stops_at_f_max(tmp_path):
    """A peak near the Nyquist frequency (3224 Hz in a bundled run) is not listed: the
    table looks up to f_max (default: the upper end of the band or the diagram)."""
    from nlbeam.app.scenes.outputs import write_table

    f = np.arange(0.0, 3300.0, 0.5)
    P = 1e-10 * (1 + 1e3 / (1 + ((f - 40.0) / 0.8) ** 2) + 30 / (1 + ((f - 3224.0) / 0.8) ** 2))
    sto = SimpleNamespace(psd=lambda ch: (f, P))
    fr1 = np.linspace(5.0, 150.0, 1451)
    per = SimpleNamespace(branches=[SimpleNamespace(
        order=1, frequency=fr1, xmax=1e-4 + 1e-3 / (1 + ((fr1 - 40.0) / 2) ** 2),
        stable=np.ones(fr1.size, bool))], bifurcations=[], superharmonics=[])
    p = {"f_range": [5.0, 150.0]}
    s = {"band": [0.0, 200.0], "rms": 1e-4, "seed": 1, "lowpass": None}
    variants = [("", {}, p, s, per, sto, {"periodic": "a", "stochastic": "b"})]

    def freqs(d):
        write_table(dict(d, kind="peaks", file="t.csv"), variants, tmp_path)
        return [float(r["frequency_hz"]) for r in csv.DictReader(open(tmp_path / "t.csv"))]

    assert freqs({}) == [40.0]
    assert freqs({"f_max": 30.0}) == []
    got = freqs({"f_max": 3300.0})
    assert len(got) == 2 and got[0] == 40.0 and math.isclose(got[1], 3224.0, abs_tol=0.5)


def test_moments_table_states_how_rough_its_errors_are(tmp_path):
    """A moments row prints each moment to the digits of its standard error and gives the
    errors' degrees of freedom (se_dof); a record without them leaves the cell empty."""
    from nlbeam.app.scenes.outputs import write_table

    mo = {"mean": -9.245293e-4, "std": 7.3966e-4, "skewness": -1.03312, "kurtosis": 4.1032,
          "se_mean": 7.4967e-6, "se_std": 8.5e-6, "se_skewness": 0.034, "se_kurtosis": 0.19,
          "se_dof": 8.68695652}
    rows = []
    for dof in (mo["se_dof"], math.nan):
        sto = SimpleNamespace(moments=lambda ch, dof=dof: dict(mo, se_dof=dof))
        variants = [("", {}, {}, {}, None, sto, {"stochastic": "b"})]
        write_table({"kind": "moments", "file": "m.csv"}, variants, tmp_path)
        rows += list(csv.DictReader(open(tmp_path / "m.csv")))
    assert rows[0]["se_dof"] == "8.7" and rows[1]["se_dof"] == ""
    # the error to one digit (it is itself uncertain by 24 %), the value to that digit
    assert rows[0]["kurtosis"] == "4.1" and rows[0]["se_kurtosis"] == "0.2"
    assert (rows[0]["skewness"], rows[0]["se_skewness"]) == ("-1.03", "0.03")
    assert (rows[0]["mean"], rows[0]["se_mean"]) == ("-0.000925", "7e-06")


def test_a_default_written_out_keys_the_same_analysis(tmp_path):
    # paper_broadband.toml spells the paper's contact parameters out, paper_narrowband.toml
    # leaves them: both must find the one diagram in the cache
    a = load_scene(write_scene(tmp_path, PERIODIC + PSD_FIG.replace("psd", "frc"), "a.toml"))
    b = load_scene(write_scene(tmp_path, '[model]\ne = 0.5\nK_hertz = 2.1e8\ncontact = '
                          '"lankarani-nikravesh"\n' + PERIODIC + PSD_FIG.replace("psd", "frc"),
                          "b.toml"))
    c = load_scene(write_scene(tmp_path, "[model]\ne = 0.6\n" + PERIODIC +
                          PSD_FIG.replace("psd", "frc"), "c.toml"))
    (ja,), (jb,), (jc,) = (plan(x, tmp_path) for x in (a, b, c))
    assert ja.key == jb.key != jc.key
    assert ja.inputs["model"]["e"] == 0.5 and jc.inputs["model"]["e"] == 0.6


def test_peaks_without_stability_on_the_real_continuation(tmp_path, calls):
    scene = write_scene(tmp_path, PERIODIC + STOCH + PEAKS_NO_STAB +
                   '[[figure]]\nkind = "compare"\nfile = "c.png"\nstability = false\n')
    out = tmp_path / "out"
    rep = run_scene(scene, out, quiet=True)
    (per,) = [j for j in rep.jobs if j.kind == "periodic"]
    assert per.inputs["periodic"]["stability"] is False
    frc = continuation.load(per.path)
    assert all(b.stable is None for b in frc.branches)
    assert (out / "c.png").stat().st_size > 1000
    rows = list(csv.DictReader(open(out / "peaks.csv")))
    assert all(r["stable"] == "" for r in rows)


def test_a_cached_rerun_repeats_the_warnings_of_the_computation(tmp_path, monkeypatch):
    """The warnings an analysis gave are stored with its cache entry and issued again, once
    each and saying so, when the entry is reused (issue 16)."""
    import warnings

    from nlbeam.app.scenes.run import CachedResultWarning
    sim0 = stochastic.simulate

    def sim(*a, **k):
        warnings.warn("record gained energy: check dt", RuntimeWarning)
        warnings.warn("record gained energy: check dt", RuntimeWarning)  # once is enough
        return sim0(*a, **k)

    monkeypatch.setattr(stochastic, "simulate", sim)
    scene = write_scene(tmp_path, STOCH + PSD_FIG)
    with pytest.warns(RuntimeWarning, match="record gained energy") as first:
        run_scene(scene, tmp_path / "out", quiet=True)
    assert [str(w.message) for w in first if "energy" in str(w.message)] == [
        "record gained energy: check dt"]
    with pytest.warns(CachedResultWarning) as again:
        rep = run_scene(scene, tmp_path / "out", quiet=True)
    assert rep.computed == 0
    texts = [str(w.message) for w in again if w.category is CachedResultWarning]
    assert texts == ["(cached stochastic, as first computed) record gained energy: check dt"]


def test_progress_lines_when_not_a_terminal(tmp_path):
    """Without a terminal, a scene's progress is plain lines: each analysis, each branch of a
    diagram, the simulated seconds of a record (the last always); --quiet prints none."""
    import io

    from nlbeam.app.progress import Progress
    scene = write_scene(tmp_path, PERIODIC + STOCH + PSD_FIG + '[[figure]]\nkind = "frc"\n'
                   'file = "frc.png"\n')
    buf = io.StringIO()
    run_scene(scene, tmp_path / "out", log=Progress(stream=buf))
    text = buf.getvalue()
    assert "\r" not in text and "[1/2] periodic" in text and "[2/2] stochastic" in text
    assert "simulated: 1.6 / 1.6 s" in text  # transient + duration, the last line
    assert "branch" in text or "brute-force" in text  # continuation's own status lines
    quiet = io.StringIO()
    run_scene(write_scene(tmp_path, STOCH.replace("seed = 1", "seed = 2") + PSD_FIG, "q.toml"),
              tmp_path / "out", log=Progress(stream=quiet, quiet=True))
    assert quiet.getvalue() == ""
    bar = io.StringIO()
    p = Progress(stream=bar, tty=True)
    p.bar("sim", 0.5, 2.0, "s")
    p.bar("sim", 2.0, 2.0, "s")
    assert bar.getvalue().count("\r") == 2 and bar.getvalue().endswith("(100 %)\x1b[K\n")
    # a warning printed while a bar is drawn starts on its own line
    from nlbeam.app.progress import end_bar_line
    bar = io.StringIO()
    p = Progress(stream=bar, tty=True)
    p.bar("sim", 0.5, 2.0, "s")
    end_bar_line()
    assert bar.getvalue().endswith("(25 %)\x1b[K\n")


def test_a_cached_rerun_draws_only_what_changed(tmp_path, monkeypatch):
    """Outputs are stamped with what they show: a rerun of an unchanged scene draws nothing and
    reads no result; a changed figure entry redraws that figure only; a new seed redraws
    what reads the stochastic result; a deleted or altered file is written again."""
    from nlbeam.app.scenes import outputs, run

    text = STOCH + PSD_FIG + '[[figure]]\nkind = "pdf"\nfile = "pdf.png"\n' \
        + '[[table]]\nkind = "moments"\nfile = "moments.csv"\n'
    scene = write_scene(tmp_path, text)
    out = tmp_path / "out"
    run_scene(scene, out, quiet=True)
    drawn, loads = [], []
    fig0, load0 = outputs.scene_figure, run.load_result
    monkeypatch.setattr(outputs, "scene_figure",
                        lambda t, d, v, o, **kw: drawn.append(d["file"]) or fig0(t, d, v, o, **kw))
    monkeypatch.setattr(run, "load_result", lambda j: loads.append(j.kind) or load0(j))
    rep = run_scene(scene, out, quiet=True)
    assert drawn == [] and loads == []
    assert sorted(os.path.basename(f) for f in rep.files) == ["moments.csv", "pdf.png",
                                                             "psd.png"]
    scene.write_text(text.replace('file = "pdf.png"', 'file = "pdf.png"\ntitle = "other"'))
    run_scene(scene, out, quiet=True)
    assert drawn == ["pdf.png"]
    (out / "psd.png").write_bytes(b"not a figure")
    run_scene(scene, out, quiet=True)
    assert drawn == ["pdf.png", "psd.png"] and (out / "psd.png").stat().st_size > 1000
    os.remove(out / "moments.csv")
    run_scene(scene, out, quiet=True)
    assert (out / "moments.csv").exists() and drawn == ["pdf.png", "psd.png"]
    moments = (out / "moments.csv").read_text()
    scene.write_text(text.replace("seed = 1", "seed = 2"))
    run_scene(scene, out, quiet=True)
    assert drawn == ["pdf.png", "psd.png", "psd.png", "pdf.png"]
    assert (out / "moments.csv").read_text() != moments
