"""A scene whose diagram comes out empty (every shooting solve failed) stops `nlbeam run` and
`nlbeam figures` with a non-zero exit and a message naming the scene; nothing is cached, so a
re-run computes the diagram again.

The failure is the one of session 11's reverted parallel compile: a variational kernel that
runs the plain loop (the monodromy is never integrated), reproduced by pointing the kernel
dispatch at the plain kernel; every solve of the brute-force grid then fails."""
import os

import pytest

import continuation
import nlbeam._kernels as kernels
from helpers import TINY_DIAGRAM, write_scene
from nlbeam.app.cli import main
from nlbeam.app.scenes.empty import EmptyDiagramError
from nlbeam.scenes import run_scene

SCENE = 'title = "an empty diagram"\n' + TINY_DIAGRAM + """
[[figure]]
kind = "frc"
file = "frc.png"
"""


@pytest.fixture
def plain_as_var(monkeypatch):
    # the variational kernel replaced by the plain one: what the adopted cache entry ran
    monkeypatch.setattr(kernels, "integrate_var", kernels.integrate_plain)


def _cache_files(out):
    return [f for _, _, fs in os.walk(out) for f in fs if f.endswith(".h5")]


def test_a_diagram_with_every_solve_failed_stops_the_run(tmp_path, plain_as_var):
    scene = write_scene(tmp_path, SCENE, "empty.toml")
    out = tmp_path / "out"
    with pytest.warns(continuation.ContinuationWarning), \
            pytest.raises(EmptyDiagramError) as err:
        run_scene(scene, out, quiet=True)
    msg = str(err.value)
    assert "empty.toml" in msg and "an empty diagram" in msg and "every solve failed" in msg
    assert len(msg.splitlines()) == 1
    assert not (out / "frc.png").exists() and _cache_files(out) == []


def test_the_same_scene_with_the_real_kernel_draws_its_diagram(tmp_path):
    # (the check does not fire on a good diagram: 42-45 Hz has a stable order-1 branch)
    scene = write_scene(tmp_path, SCENE, "good.toml")
    rep = run_scene(scene, tmp_path / "out", quiet=True)
    assert rep.computed == 1 and (tmp_path / "out" / "frc.png").exists()


def test_nlbeam_run_exits_non_zero_naming_the_scene(tmp_path, capsys, plain_as_var):
    scene = write_scene(tmp_path, SCENE, "empty.toml")
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "error: scene empty.toml (an empty diagram)" in err[-1]


def test_nlbeam_figures_exits_non_zero_naming_the_bundled_scene(tmp_path, capsys,
                                                                 monkeypatch):
    # a bundled scene's diagram, empty; its analyses come before its records, so nothing else
    # runs first
    def empty(model, amplitude, f_range, orders=(1,), **kw):
        return continuation.FrequencyResponse(model_parameters=model.parameters(),
                                              amplitude=amplitude, parameter="frequency",
                                              p_range=tuple(f_range))

    monkeypatch.setattr(continuation, "frequency_response", empty)
    out = tmp_path / "figs"
    assert main(["figures", "--only", "paper_broadband", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "error: scene paper_broadband.toml (" in err[-1] and "empty" in err[-1]
    assert _cache_files(out) == []


SWEPT = SCENE + """
[sweep]
parameter = "amplitude"
values = [2e-4, 1e-4]
"""


def test_a_sweep_goes_on_past_an_empty_diagram_and_exits_non_zero(tmp_path, capsys,
                                                                   monkeypatch):
    # a user's sweep: the diagram at the first value comes out empty, the second is traced
    # and cached; the empty one is reported at once and named again at the end (exit 2),
    # nothing is drawn; a re-run computes only the value that came out empty
    real = continuation.frequency_response

    def empty_at_2e4(model, amplitude, f_range, orders=(1,), **kw):
        if amplitude == 2e-4:
            return continuation.FrequencyResponse(model_parameters=model.parameters(),
                                                  amplitude=amplitude, parameter="frequency",
                                                  p_range=tuple(f_range))
        return real(model, amplitude, f_range, orders=orders, **kw)

    monkeypatch.setattr(continuation, "frequency_response", empty_at_2e4)
    scene = write_scene(tmp_path, SWEPT, "swept.toml")
    out = tmp_path / "o"
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--workers", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert sum("came out empty" in line for line in err) == 2   # at once, and at the end
    assert "error: scene swept.toml (an empty diagram): 1 diagram(s) of the sweep" in err[-1]
    assert "amplitude=0.0002" in err[-1] or "2e-04" in err[-1] or "0.0002" in err[-1], err[-1]
    assert len(_cache_files(out)) == 1 and not (out / "frc.png").exists()
    monkeypatch.setattr(continuation, "frequency_response", real)
    rep = run_scene(scene, out, quiet=True, workers=1)
    assert rep.computed == 1 and rep.reused == 1 and (out / "frc.png").exists()
