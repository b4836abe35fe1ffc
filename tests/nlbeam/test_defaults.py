"""One vocabulary and one set of defaults: the scene files and the command line take theirs
from the analyses' signatures (and the paper's study in nlbeam.app.defaults), so a scene
and the command with the same settings run the same analysis."""
import importlib
import inspect

import pytest

import continuation
import nlbeam
import stochastic
from nlbeam import vocabulary
from nlbeam.app import defaults
from nlbeam.app.cli import _parser
from nlbeam.app.compare import map_peaks
from nlbeam.scenes import SceneError, load_scene

MINIMAL = "[periodic]\n[stochastic]\n"


def _signature(func):
    return {k: p.default for k, p in inspect.signature(func).parameters.items()}


@pytest.fixture
def scene(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(MINIMAL)
    return load_scene(p)


def test_a_scene_leaving_keys_out_gets_the_analyses_defaults(scene):
    fr = _signature(continuation.frequency_response)
    assert scene.periodic["orders"] == list(fr["orders"])
    for key in ("n_grid", "segments"):
        assert scene.periodic[key] == fr[key]
    assert scene.periodic["dt_scale"] == _signature(continuation.Integrator)["dt_scale"]
    sim = _signature(stochastic.simulate)
    for key in ("method", "transient", "psd_resolution", "pdf_bins"):
        assert scene.stochastic[key] == sim[key], key
    assert scene.stochastic["method"] == "adaptive"  # as `nlbeam simulate` and the library


def test_the_command_line_defaults_are_the_scene_defaults(scene):
    parser = _parser()
    frc = parser.parse_args(["frc"])
    for key in ("amplitude", "f_range", "orders", "n_grid"):
        assert getattr(frc, key) == scene.periodic[key], key
    sim = parser.parse_args(["simulate"])
    for key in ("band", "rms", "lowpass", "seed", "duration", "transient", "psd_resolution",
                "method"):
        assert getattr(sim, key) == scene.stochastic[key], key
    cmp_ = parser.parse_args(["compare", "a.h5", "b.h5"])
    assert cmp_.channel == _signature(stochastic.StochasticResult.psd)["ch"] == "delta"
    assert cmp_.min_prominence == _signature(map_peaks)["min_prominence"]
    model = nlbeam.BeamImpact()
    assert frc.e is None and frc.K_hertz is None  # None: the model's own (paper) values
    assert defaults.MODEL["e"] == model.e and defaults.MODEL["K_hertz"] == model.K_hertz


def test_help_prints_the_shared_defaults(capsys):
    with pytest.raises(SystemExit):
        _parser().parse_args(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"integrator, default {defaults.STOCHASTIC['method']}" in text
    assert "default 10 decay times of the slowest mode" in text
    assert f"default {defaults.STOCHASTIC['duration']:g}" in text
    assert ", ".join(vocabulary.CHANNELS) in text
    with pytest.raises(SystemExit):
        _parser().parse_args(["frc", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"default {defaults.PERIODIC['n_grid']}" in text
    assert "default " + " ".join(map(str, defaults.PERIODIC["orders"])) in text


def test_the_demo_help_readme_and_scene_agree(capsys):
    """demo --help reads its workers default, its time and what it computes from one place
    each (defaults.py, the demo scene), and the README and docs/usage.md say the same time."""
    import os
    import tomllib

    from nlbeam.app.demo import DEMO_SCENE
    with pytest.raises(SystemExit):
        _parser().parse_args(["demo", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"default {defaults.DEMO_WORKERS}: this process" in text and "--scheduler" in text
    sc = tomllib.loads(DEMO_SCENE)
    lo, hi = sc["periodic"]["f_range"]
    assert f"diagram {lo:g}-{hi:g} Hz" in text
    assert all(f"{a:g}-{b:g} Hz" in text for a, b in sc["sweep"]["values"])
    with pytest.raises(SystemExit):
        _parser().parse_args(["--help"])
    top = " ".join(capsys.readouterr().out.split())
    assert f"({defaults.DEMO_DURATION} once the kernels are compiled)" in top
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    for doc in ("README.md", os.path.join("docs", "usage.md")):
        with open(os.path.join(root, doc), encoding="utf-8") as fh:
            words = " ".join(fh.read().split())
        assert f"{defaults.DEMO_DURATION} once the kernels are compiled" in words.replace(
            "About", "about"), doc


def test_the_vocabulary_is_the_one_the_core_accepts(tmp_path):
    integrate_module = importlib.import_module("nlbeam.integrate")  # the module, not the function
    assert tuple(integrate_module.METHODS) == vocabulary.METHODS
    from nlbeam import modal, systems
    assert systems.CONTACT_LAWS is vocabulary.CONTACT_LAWS
    assert modal.BOUNDARY_CONDITIONS is vocabulary.BOUNDARY_CONDITIONS
    for law in vocabulary.CONTACT_LAWS:
        mu = 1.0 if law == "hunt-crossley" else None
        nlbeam.BeamImpact(contact=law, mu=mu)
    from stochastic.simulate import _parse_channel
    model = nlbeam.BeamImpact()
    parsed = [_parse_channel(ch, model)[0] for ch in vocabulary.CHANNELS]
    assert parsed == list(vocabulary.CHANNELS)
    # the scene schema accepts exactly these words
    p = tmp_path / "s.toml"
    for method in vocabulary.METHODS:
        p.write_text(f'[stochastic]\nmethod = "{method}"\n')
        assert load_scene(p).stochastic["method"] == method
    p.write_text('[stochastic]\nmethod = "euler"\n')
    with pytest.raises(SceneError, match="stochastic.method: must be one of 'rk2', 'rk4'"):
        load_scene(p)
    p.write_text('[model]\ncontact = "kelvin"\n')
    with pytest.raises(SceneError, match="'hertz', 'lankarani-nikravesh', 'hunt-crossley'"):
        load_scene(p)
