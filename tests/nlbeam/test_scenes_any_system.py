"""Any system in a scene (issue 14): a 2-DOF rig written out in TOML and the same rig from a
Python factory run end to end (diagram, noise record, comparison) and are cached; the cache key
follows the element parameters and the factory's arrays; a sweep of an element parameter draws
its diagrams in one figure and its tables carry the swept value; every key of every section is
documented in docs/usage.md and every [periodic] / [stochastic] key is an option of
``nlbeam frc`` / ``nlbeam simulate`` with the same default.

The rig: masses 0.5 and 0.2 kg, springs 2000 and 1000 N/m (7.63 and 14.85 Hz), a linear stop
(2e4 N/m) 0.5 mm from the second mass; 0.1 mm base motion. Settings are tiny: a 3 Hz diagram
without error estimates (0.5 s CPU), 1.5 s records.
"""
import csv
import importlib
import os
import re
import sys

import numpy as np
import pytest

import nlbeam
from helpers import write_scene
from nlbeam.app.cli import _parser, main
from nlbeam.app.defaults import PERIODIC, STOCHASTIC
from nlbeam.app.scenes import models, schema
from nlbeam.app.sweeps import BAND_EDGES, PARAMETERS
from nlbeam.scenes import SceneError, load_scene, plan, run_scene

DOCS = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "usage.md")

RIG_TOML = """
[model]
name = "System"
M = [[0.5, 0.0], [0.0, 0.2]]
C = [[6.0, -2.0], [-2.0, 2.0]]
K = [[3000.0, -1000.0], [-1000.0, 1000.0]]
excitation_kind = "base"

[[model.elements]]
type = "CubicSpring"
dof = 0
k3 = 0.0

[[model.elements]]
type = "PiecewiseLinearStop"
dof = 1
k = 2e4
gap = {gap}
"""
FACTORY_TOML = """
[model]
factory = "{module}:rig"

[model.args]
gap = {gap}
"""
FACTORY_PY = """
import nlbeam

def rig(gap=5e-4, k_stop=2e4, scale=1.0):
    M = [[0.5, 0.0], [0.0, 0.2]]
    K = [[3000.0 * scale, -1000.0], [-1000.0, 1000.0]]
    C = [[6.0, -2.0], [-2.0, 2.0]]
    return nlbeam.System(M, C, K, (nlbeam.PiecewiseLinearStop(1, k=k_stop, gap=gap),), "base")
"""
ANALYSES = """
[periodic]
amplitude = 1e-4
f_range = [8.0, 11.0]
orders = [1]
n_grid = 3
accuracy = "off"

[stochastic]
band = [0.0, 40.0]
rms = 2e-4
duration = 1.5
transient = 0.5
psd_resolution = 2.0

[[figure]]
kind = "frc"
file = "frc.png"

[[figure]]
kind = "compare"
file = "compare.png"
channel = "x"

[[table]]
kind = "bifurcations"
file = "bifurcations.csv"

[[table]]
kind = "moments"
file = "moments.csv"
channel = "x"
"""


@pytest.fixture
def factory_module(tmp_path, monkeypatch):
    """A module on the path defining ``rig(gap, k_stop, scale)``; returns its name."""
    d = tmp_path / "pkg"
    d.mkdir()
    name = f"rig_factory_{abs(hash(str(tmp_path))) % 10 ** 8}"
    (d / f"{name}.py").write_text(FACTORY_PY)
    monkeypatch.syspath_prepend(str(d))
    importlib.invalidate_caches()
    yield name
    sys.modules.pop(name, None)


def _end_to_end(scene_path, out):
    rep = run_scene(scene_path, out, quiet=True, workers=1)
    assert rep.computed == 2  # the diagram and the record
    files = sorted(os.path.basename(f) for f in rep.files)
    assert files == ["bifurcations.csv", "compare.png", "frc.png", "moments.csv"]
    with open(out / "bifurcations.csv") as fh:
        rows = list(csv.DictReader(fh))
    # the stop bends the resonance over: a fold pair and the grazing point between them
    kinds = sorted(r["kind"] for r in rows)
    assert kinds.count("fold") == 2 and "grazing" in kinds, rows
    with open(out / "moments.csv") as fh:
        mo = list(csv.DictReader(fh))
    assert len(mo) == 1 and float(mo[0]["std"]) > 0
    again = run_scene(scene_path, out, quiet=True, workers=1)
    assert again.computed == 0 and again.reused == 2
    return rep


def test_a_system_written_out_runs_end_to_end_and_is_cached(tmp_path):
    scene = write_scene(tmp_path, RIG_TOML.format(gap=5e-4) + ANALYSES)
    rep = _end_to_end(scene, tmp_path / "out")
    per = next(j for j in rep.jobs if j.kind == "periodic")
    # the diagram is that of the system the TOML describes (the Python API on the same arrays)
    import continuation
    frc = continuation.load(per.path)
    sysm = nlbeam.System([[0.5, 0.0], [0.0, 0.2]], [[6.0, -2.0], [-2.0, 2.0]],
                         [[3000.0, -1000.0], [-1000.0, 1000.0]],
                         (nlbeam.CubicSpring(0, 0.0),
                          nlbeam.PiecewiseLinearStop(1, k=2e4, gap=5e-4)), "base")
    br = frc.branches[0]
    # the impacting point of largest |x|max (on the upper branch, past the grazing point)
    j = int(np.argmax(br.xmax))
    assert br.xmax[j] > 5e-4  # beyond the 0.5 mm gap
    sol = continuation.periodic_solution(sysm, 1e-4, float(br.values[j]), error=False,
                                         guess=br.state0[j])
    assert abs(sol.xmax - br.xmax[j]) <= 1e-8 * br.xmax[j]


def test_a_factory_runs_end_to_end_and_its_arrays_key_the_cache(tmp_path, factory_module,
                                                                  monkeypatch):
    scene = write_scene(tmp_path, FACTORY_TOML.format(module=factory_module, gap=5e-4) + ANALYSES)
    rep = _end_to_end(scene, tmp_path / "out")
    inputs = rep.jobs[0].inputs["model"]
    assert inputs["factory"] == f"{factory_module}:rig" and inputs["args"] == {"gap": 5e-4}
    # the same name and arguments but other arrays (the factory's code changed): a new key
    keys = {j.kind: j.key for j in plan(load_scene(scene), tmp_path / "out")}
    mod = importlib.import_module(factory_module)
    rig0 = mod.rig
    monkeypatch.setattr(mod, "rig", lambda gap, **kw: rig0(gap, scale=1.01))
    changed = {j.kind: j.key for j in plan(load_scene(scene), tmp_path / "out")}
    assert all(changed[k] != keys[k] for k in keys)
    monkeypatch.setattr(mod, "rig", rig0)
    assert {j.kind: j.key for j in plan(load_scene(scene), tmp_path / "out")} == keys


@pytest.mark.parametrize("text, where, what", [
    (FACTORY_TOML.format(module="no_such_module_xyz", gap=1e-3), ":3: model.factory",
     "cannot import module"),
    ('[model]\nfactory = "builtins:dict"\n[model.args]\nfoo = 1\n', ":2: model.factory",
     "returned a"),
    (RIG_TOML.format(gap=5e-4).replace('type = "CubicSpring"', 'type = "Spring"'),
     ":10: model.elements[0].type", "PiecewiseLinearStop"),
    (RIG_TOML.format(gap=5e-4).replace("k = 2e4", "k = -1.0"), ":17: model.elements[1].k",
     ">= 0"),
    (RIG_TOML.format(gap=5e-4).replace("k = 2e4", "kk = 2.0"), ":17: model.elements[1].kk",
     "unknown key for a PiecewiseLinearStop"),
    (RIG_TOML.format(gap=5e-4).replace("[0.0, 0.2]]\nC", "[0.0]]\nC"), ":4: model.M",
     "square matrix"),
    ('[model]\nname = "System"\nM = [[1.0]]\n', ":1: model", "needs K"),
])
def test_a_bad_model_is_named_by_file_line_and_key(tmp_path, text, where, what):
    p = write_scene(tmp_path, text)
    with pytest.raises(SceneError) as err:
        load_scene(p)
    msg = str(err.value)
    assert f"{p}{where}" in msg and what in msg, msg


def test_a_changed_element_parameter_changes_the_cache_key(tmp_path):
    def keys(gap, k="2e4"):
        p = write_scene(tmp_path, RIG_TOML.format(gap=gap).replace("2e4", k) + ANALYSES)
        return {j.kind: j.key for j in plan(load_scene(p), tmp_path / "out")}

    k0 = keys(5e-4)
    assert keys(5e-4) == k0  # the same file, the same keys
    assert keys(6e-4)["periodic"] != k0["periodic"]
    assert keys(6e-4)["stochastic"] != k0["stochastic"]
    assert keys(5e-4, k="3e4")["periodic"] != k0["periodic"]


def test_a_sweep_of_an_element_parameter_overlays_its_diagrams(tmp_path):
    text = RIG_TOML.format(gap=5e-4) + ANALYSES.split("[stochastic]")[0] + """
[[figure]]
kind = "frc"
file = "frc.png"

[[table]]
kind = "bifurcations"
file = "bifurcations.csv"

[sweep]
parameter = "elements[1].gap"
values = [4e-4, 6e-4]
"""
    scene = write_scene(tmp_path, text)
    sc = load_scene(scene)
    gaps = [float(m["elements"][1]["gap"]) for _, m, _, _ in sc.variants()]
    assert gaps == [4e-4, 6e-4]
    rep = run_scene(scene, tmp_path / "out", quiet=True, workers=1)
    assert sorted(os.path.basename(f) for f in rep.files) == ["bifurcations.csv", "frc.png"]
    with open(tmp_path / "out" / "bifurcations.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:2] == ["variant", "elements[1].gap"]
    folds = {}
    for r in rows:
        if r["kind"] == "fold":
            folds.setdefault(float(r["elements[1].gap"]), []).append(float(r["frequency_hz"]))
    assert sorted(folds) == [4e-4, 6e-4]
    # a wider gap: the stop is met later, the fold of the jump down moves to lower frequency
    assert max(folds[6e-4]) < max(folds[4e-4])
    from nlbeam.app.plots.scene import variant_label
    assert variant_label("elements[1].gap=0.0004") == "elements[1].gap = 0.4 mm"
    assert variant_label("elements[0].k3=2") == "elements[0].k3 = 2 N/m^3"


def test_a_bad_sweep_name_lists_the_names_that_exist(tmp_path):
    p = write_scene(tmp_path, RIG_TOML.format(gap=5e-4) + ANALYSES
               + '[sweep]\nparameter = "gap"\nvalues = [1e-3]\n')
    with pytest.raises(SceneError) as err:
        load_scene(p)
    msg = str(err.value)
    assert "sweep.parameter" in msg and "elements[1].gap" in msg and "elements[1].k" in msg
    assert "amplitude" in msg and "band[1]" in msg and "duration" in msg


def _doc_sections():
    """{heading: text} of docs/usage.md's '#### `[section]`' headings."""
    text = open(DOCS, encoding="utf-8").read()
    parts = re.split(r"^#### `([^`]+)`\s*$", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def test_every_key_of_every_section_is_documented():
    docs = _doc_sections()
    sections = {"[model]": models.MODEL_KEYS, "[periodic]": schema.PERIODIC_KEYS,
                "[stochastic]": schema.STOCHASTIC_KEYS, "[[figure]]": schema.FIGURE_KEYS,
                "[[table]]": schema.TABLE_KEYS, "[sweep]": schema.SWEEP_KEYS,
                "[model.args]": {}, "[measured]": schema.MEASURED_KEYS,
                "[chart]": schema.CHART_KEYS,
                "(top level)": {"title": None}}
    for t, keys in models.ELEMENT_KEYS.items():
        sections.setdefault("[[model.elements]]", {}).update(keys)
    missing = []
    for sec, keys in sections.items():
        assert sec in docs, f"docs/usage.md has no '#### `{sec}`' heading"
        for k in keys:
            if f"`{k}`" not in docs[sec]:
                missing.append(f"{sec} {k}")
    words = {"[[figure]]": schema.FIGURE_KINDS, "[[table]]": schema.TABLE_KINDS,
             "[[model.elements]]": tuple(models.ELEMENT_TYPES), "[model]": models.MODEL_NAMES,
             "[sweep]": tuple(PARAMETERS) + tuple(BAND_EDGES)}
    for sec, names in words.items():
        missing += [f"{sec} {w}" for w in names if f"`{w}`" not in docs[sec]]
    assert not missing, f"keys not documented in docs/usage.md: {missing}"


def test_every_analysis_key_is_a_command_line_option_with_the_same_default():
    parser = _parser()
    frc = vars(parser.parse_args(["frc"]))
    sim = vars(parser.parse_args(["simulate"]))
    for table, args in ((PERIODIC, frc), (STOCHASTIC, sim)):
        for k, v in table.items():
            assert k in args, k
            assert args[k] == v, (k, args[k], v)


def test_the_command_line_takes_a_scene_model_and_sets_parameters_by_name(tmp_path, capsys):
    scene = write_scene(tmp_path, RIG_TOML.format(gap=5e-4))
    out = tmp_path / "frc.h5"
    rc = main(["frc", "--model", str(scene), "--set", "elements[1].gap=6e-4", "--f-range",
               "8", "11", "--orders", "1", "--n-grid", "3", "--accuracy", "off", "--out",
               str(out), "--quiet"])
    assert rc == 0
    import continuation
    frc = continuation.load(out)
    assert float(frc.model_parameters["element1.gap"]) == 6e-4
    assert float(frc.model_parameters["n_dof"]) == 2
    rc = main(["frc", "--model", str(scene), "--set", "gap=1e-3", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and "elements[1].gap" in err and "'gap' is not a parameter" in err
    # refinement of the diagram's folds, with the model it was computed for
    ref = tmp_path / "refined.h5"
    rc = main(["refine", str(out), "--model", str(scene), "--set", "elements[1].gap=6e-4",
               "--out", str(ref), "--quiet"])
    assert rc == 0
    folds = sorted(b.frequency for b in frc.bifurcations if b.kind == "fold")
    refined = continuation.load(ref)
    rf = sorted((b.frequency, b.error) for b in refined.bifurcations if b.kind == "fold")
    assert len(rf) == len(folds) == 2
    for f, (g, e) in zip(folds, rf):
        # the default step's fold is off by its integration error (4e-6 of f measured);
        # the refined one states 1e-9 of f or better
        assert abs(g - f) < 1e-4 * f and e < 1e-8 * g, (f, g, e)
    rc = main(["refine", str(out), "--model", str(scene), "--out", str(ref)])
    err = capsys.readouterr().err
    assert rc == 2 and "computed for another model (differs in element1.gap)" in err


def test_simulate_keeps_a_history_window_of_the_model_set_by_name(tmp_path):
    out = tmp_path / "sto.h5"
    rc = main(["simulate", "--duration", "0.5", "--transient", "0.2", "--psd-resolution", "8",
               "--history", "0.1", "0.3", "--set", "gap=1e-5", "--band", "0", "100",
               "--out", str(out), "--quiet"])
    assert rc == 0
    import stochastic
    res = stochastic.load(out)
    t = res.history["t"]
    dt = t[1] - t[0]
    assert abs(t[0] - 0.3) <= dt and abs(t[-1] - 0.5) <= dt  # transient + window
    assert float(res.model_parameters["gap"]) == 1e-5
    # delta = x - y - gap, sample by sample
    h = res.history
    assert np.allclose(h["delta"], h["x"] - h["y"] - 1e-5, rtol=0, atol=1e-12)


SDOF_TOML = """
[model]
name = "System"
M = [[1.0]]
C = [[0.1]]
K = [[1.0]]
excitation_kind = "force"

[[model.elements]]
type = "PiecewiseLinearStop"
dof = 0
k = 4.0
gap = 0.1
on_base = false
"""


def test_nlbeam_continue_follows_an_element_parameter_as_the_python_api(tmp_path, capsys):
    """x'' + 0.1 x' + x + 4 max(x - gap, 0) = 0.1 cos(2 pi 0.12 t) continued in the gap: the
    command gives the branch and period doublings of continuation.continue_parameter, and
    shares its defaults with [periodic] and continue_parameter's signature."""
    import inspect

    import continuation
    from nlbeam.app.cli import _CONTINUE_KNOBS
    from nlbeam.app.scenes.models import build_model

    sig = {k: p.default for k, p in
           inspect.signature(continuation.continue_parameter).parameters.items()}
    args = vars(_parser().parse_args(["continue", "gap", "0", "1", "--frequency", "1"]))
    for k in _CONTINUE_KNOBS:
        assert args[k] == PERIODIC[k], k
        if k in sig:
            assert sig[k] == PERIODIC[k], k
    scene = write_scene(tmp_path, SDOF_TOML)
    out = tmp_path / "c.h5"
    rc = main(["continue", "elements[0].gap", "0.02", "0.3", "--frequency", "0.12",
               "--amplitude", "0.1", "--model", str(scene), "--accuracy", "off", "--out",
               str(out), "--quiet"])
    assert rc == 0
    frc = continuation.load(out)
    model = build_model(load_scene(scene).model)
    sol = continuation.periodic_solution(model, 0.1, 0.12, error=False)
    ref = continuation.continue_parameter(sol, "elements[0].gap", (0.02, 0.3), model=model,
                                          accuracy="off")
    pd = sorted(b.value for b in frc.bifurcations if b.kind == "period-doubling")
    pd_ref = sorted(b.value for b in ref.bifurcations if b.kind == "period-doubling")
    assert len(pd) == len(pd_ref) == 2
    assert np.allclose(pd, pd_ref, rtol=1e-7, atol=0)  # located to bif_tol 1e-8 both
    assert frc.parameter == "elements[0].gap"
    rc = main(["continue", "gap", "0.02", "0.3", "--frequency", "0.12", "--model", str(scene)])
    err = capsys.readouterr().err
    assert rc == 2 and "frequency, amplitude, elements[0].k, elements[0].gap" in err


@pytest.mark.parametrize("argv, message", [
    (["frc", "--ds-max", "-1"], "--ds-max: must be > 0, got -1"),
    (["frc", "--max-points", "1"], "--max-points: must be >= 2, got 1"),
    (["continue", "e", "0.2", "0.9", "--frequency", "40", "--accuracy", "99"],
     "--accuracy: must be 'default', 'high', 'off' or a number"),
    (["continue", "e", "0.9", "0.2", "--frequency", "40"], "range: must satisfy LO < HI"),
    (["simulate", "--band", "10", "5"], "--band: must satisfy 0 <= lo < hi (Hz), got 10 5"),
    (["simulate", "--dt", "0"], "--dt: must be > 0 s, got 0"),
    (["frc", "--set", "gap"], "--set: must be NAME=NUMBER"),
    (["frc", "--set", "elements[0].gap=1e-3"], "'elements[0].gap' is not a parameter of this "
     "BeamImpact; the names that exist: m, k, b, K_hertz, e, gap"),
])
def test_the_command_line_checks_its_options_as_the_scene_checks_its_keys(argv, message,
                                                                           capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_a_moments_table_of_a_sweep_has_a_column_of_the_swept_value(tmp_path):
    from types import SimpleNamespace

    from nlbeam.app.scenes.outputs import write_table

    def sto(std):
        return SimpleNamespace(moments=lambda ch: {"mean": 0.0, "std": std, "skewness": 0.1,
                                                   "kurtosis": 3.0})
    variants = [(f"band={b}", {}, None, {}, None, sto(s), {"stochastic": f"{b}.h5"})
                for b, s in (("0-100", 1e-4), ("50-100", 2e-4))]
    values = {"band=0-100": [0.0, 100.0], "band=50-100": [50.0, 100.0]}
    path = write_table({"kind": "moments", "file": "m.csv", "channel": "x"}, variants,
                       str(tmp_path), swept=("band", "Hz", values))
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:3] == ["variant", "band", "channel"]
    assert [(r["band"], float(r["std"])) for r in rows] == [("0-100", 1e-4), ("50-100", 2e-4)]


def test_nlbeam_run_sets_scene_parameters_by_the_sweeps_names(tmp_path, capsys):
    """`nlbeam run SCENE --set NAME=VALUE` plans exactly the analyses of the scene with the
    value written in (same cache keys)."""
    base = write_scene(tmp_path, RIG_TOML.format(gap=5e-4) + ANALYSES, "base.toml")
    written = write_scene(tmp_path, (RIG_TOML.format(gap=6e-4) + ANALYSES).replace(
        "band = [0.0, 40.0]", "band = [0.0, 30.0]"), "written.toml")
    out = tmp_path / "out"
    keys = {j.kind: j.key for j in plan(load_scene(written), out)}
    assert main(["run", str(base), "--out", str(out), "--dry-run", "--set",
                 "elements[1].gap=6e-4", "--set", "band=[0.0, 30.0]"]) == 0
    text = capsys.readouterr().out
    assert all(f"{k}-{v}.h5" in text for k, v in keys.items()), (keys, text)
    assert main(["run", str(base), "--dry-run", "--set", "gap=1e-3"]) == 2
    err = capsys.readouterr().err
    assert "gap: not a parameter of this scene" in err and "elements[1].gap" in err
    assert main(["run", str(base), "--dry-run", "--set", "elements[1].k=-1"]) == 2
    assert "elements[1].k: must be finite and >= 0" in capsys.readouterr().err


def test_the_bundled_general_system_scene_runs_end_to_end(tmp_path):
    """figures/extra/rig_2dof_stop.toml (documented in docs/usage.md, not run by `nlbeam
    figures`): diagram, noise record and comparison, cached. Measured 3.4 s CPU."""
    scene = os.path.join(os.path.dirname(DOCS), "..", "figures", "extra", "rig_2dof_stop.toml")
    rep = run_scene(scene, tmp_path, quiet=True, workers=1)
    assert rep.computed == 2
    assert sorted(os.path.basename(f) for f in rep.files) == [
        "rig_2dof_compare.png", "rig_2dof_frc.png", "table_rig_2dof_bifurcations.csv",
        "table_rig_2dof_moments.csv"]
    with open(tmp_path / "table_rig_2dof_bifurcations.csv") as fh:
        kinds = [r["kind"] for r in csv.DictReader(fh)]
    assert kinds.count("fold") == 2 and "grazing" in kinds, kinds
    with open(DOCS) as fh:
        assert "figures/extra/rig_2dof_stop.toml" in fh.read()
    assert run_scene(scene, tmp_path, quiet=True, workers=1).computed == 0
