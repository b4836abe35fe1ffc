"""nlbeam command line on tiny problems: each subcommand runs, --quiet prints nothing,
--help states units, a failure gives exit status 2 and a one-line cause."""
import os

import pytest

from nlbeam.cli import main

SCENE = """
title = "tiny"
[stochastic]
band = [0.0, 100.0]
rms = 1e-4
seed = 1
duration = 1.5
transient = 0.1
psd_resolution = 2.0

[[figure]]
kind = "psd"
file = "psd.png"

[[table]]
kind = "moments"
file = "moments.csv"
"""


def test_demo_still_runs(capsys):
    assert main(["demo", "--duration", "0.5"]) == 0
    assert "impacts" in capsys.readouterr().out
    assert main(["demo", "--duration", "0.5", "--quiet"]) == 0
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("cmd", [[], ["frc"], ["simulate"], ["run"], ["figures"], ["compare"]])
def test_help_explains_units(cmd, capsys):
    with pytest.raises(SystemExit) as e:
        main(cmd + ["--help"])
    assert e.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "Units: displacements and amplitudes in m" in out and "frequencies in Hz" in out


def test_run_dry_run_then_run_then_cached(tmp_path, capsys):
    scene = tmp_path / "tiny.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "compute stochastic" in text and "psd.png" in text
    assert not out.exists()
    assert main(["run", str(scene), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "1 computed" in err and "simulated" in err  # progress on stderr
    assert (out / "psd.png").exists() and (out / "moments.csv").exists()
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""
    assert main(["run", str(scene), "--out", str(out), "--dry-run"]) == 0
    assert "cached  stochastic" in capsys.readouterr().out


def test_failure_is_one_line_and_exit_2(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(SCENE.replace("seed = 1", "seed = -1"))
    assert main(["run", str(scene), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "stochastic.seed" in err[0] and "bad.toml:6" in err[0]
    assert not (tmp_path / "o").exists()
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_frc_simulate_compare(tmp_path, capsys):
    frc, sto, png = (str(tmp_path / n) for n in ("frc.h5", "sto.h5", "cmp.png"))
    assert main(["frc", "--amplitude", "1e-4", "--f-range", "42", "45", "--orders", "1",
                 "--n-grid", "3", "--out", frc, "--quiet"]) == 0
    assert main(["simulate", "--band", "0", "100", "--duration", "4", "--transient", "0.1",
                 "--psd-resolution", "1", "--channels", "delta", "--out", sto, "--quiet"]) == 0
    capsys.readouterr()
    assert main(["compare", sto, frc, "--plot", png]) == 0
    out = capsys.readouterr().out
    lines = out.strip().splitlines()
    assert lines[0].split()[:2] == ["peak", "Hz"] and len(lines) >= 2  # header + >= 1 peak
    assert os.path.getsize(png) > 1000
