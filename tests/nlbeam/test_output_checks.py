"""Output paths and figure titles are checked before any analysis starts (CLI, scenes), and
simulate checks the Nyquist frequency for every excitation."""
import time

import numpy as np
import pytest

import continuation
import nlbeam
import stochastic
from helpers import read_only_folder
from nlbeam._validate import output_file
from nlbeam.app.cli import main
from nlbeam.scenes import run_scene


def _no_analysis(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("an analysis started")
    monkeypatch.setattr(continuation, "frequency_response", boom)
    monkeypatch.setattr(stochastic, "simulate", boom)


def test_frc_onto_a_folder_fails_before_the_diagram(tmp_path, monkeypatch, capsys):
    _no_analysis(monkeypatch)
    t = time.perf_counter()
    assert main(["frc", "--out", str(tmp_path)]) == 2
    assert time.perf_counter() - t < 30
    err = capsys.readouterr().err
    assert "--out" in err and "is a folder" in err


def test_output_file_under_a_file_is_refused(tmp_path):
    f = tmp_path / "plain"
    f.write_text("x")
    with pytest.raises(ValueError, match="is not a folder"):
        output_file("out", str(f / "sub" / "r.h5"))
    # a missing folder under a writable one is fine (the save creates it)
    assert output_file("out", str(tmp_path / "new" / "r.h5")).endswith("r.h5")


def test_read_only_folder_is_refused(tmp_path):
    with read_only_folder(tmp_path / "ro") as ro:
        with pytest.raises(ValueError, match="not writable"):
            output_file("out", str(ro / "r.h5"))


def test_scene_with_bad_math_title_fails_before_any_analysis(tmp_path, monkeypatch):
    _no_analysis(monkeypatch)
    scene = tmp_path / "s.toml"
    scene.write_text('title = "$\\\\frac{a}{$"\n[periodic]\namplitude = 1e-4\n'
                     'f_range = [42.0, 45.0]\norders = [1]\nn_grid = 3\n'
                     '[[figure]]\nkind = "frc"\nfile = "frc.png"\n')
    with pytest.raises(ValueError, match=r"title: matplotlib cannot render"):
        run_scene(scene, tmp_path / "out", quiet=True)


def test_scene_figure_file_that_is_a_folder_fails_before_any_analysis(tmp_path, monkeypatch):
    _no_analysis(monkeypatch)
    (tmp_path / "out" / "frc.png").mkdir(parents=True)
    scene = tmp_path / "s.toml"
    scene.write_text('title = "t"\n[periodic]\namplitude = 1e-4\nf_range = [42.0, 45.0]\n'
                     'orders = [1]\nn_grid = 3\n[[figure]]\nkind = "frc"\nfile = "frc.png"\n')
    with pytest.raises(ValueError, match=r"figure frc file: .* is a folder"):
        run_scene(scene, tmp_path / "out", quiet=True)


def test_harmonic_input_above_nyquist_is_refused_and_below_it_peaks_where_it_is():
    m, ex = nlbeam.BeamImpact(K_hertz=0.0), nlbeam.Harmonic(1e-4, 40.0)
    with pytest.raises(ValueError, match=r"dt: .*Nyquist frequency 25 Hz.*40 Hz"):
        stochastic.simulate(m, ex, 4.0, 0.1, outputs=("psd",), channels=("y",), dt=0.02,
                            method="rk4")
    res = stochastic.simulate(m, ex, 4.0, 0.1, outputs=("psd",), channels=("y",), dt=0.005,
                              method="rk4", psd_resolution=1.0)
    f, P = res.psd("y")
    assert abs(f[np.argmax(P)] - 40.0) <= 1.0
