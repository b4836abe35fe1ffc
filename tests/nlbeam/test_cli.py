"""nlbeam command line on tiny problems: each subcommand runs, --quiet prints nothing,
--help states units, a failure gives exit status 2 and a one-line cause."""
import os

import numpy as np
import pytest

from helpers import MOMENTS_TABLE, PSD_FIGURE, TINY_STOCHASTIC
from nlbeam.cli import main

SCENE = '\ntitle = "tiny"' + TINY_STOCHASTIC + PSD_FIGURE + MOMENTS_TABLE


DEMO_FILES = ["demo.toml", "demo_bifurcations.csv", "demo_compare_1.png", "demo_compare_2.png",
              "demo_excitation_psd.png", "demo_frequency_response.png", "demo_moments.csv",
              "demo_pdf_delta.png", "demo_peaks.csv", "demo_psd_delta.png",
              "demo_time_history_1.png", "demo_time_history_2.png"]


@pytest.mark.slow
def test_demo_is_a_short_nlbeam_figures(tmp_path, capsys):
    """nlbeam demo writes its scene and every kind of figure and table of nlbeam figures:
    the diagram once (the band sweep does not touch it), the comparison and the history
    once per band; the broad band's delta is skewed like the paper's (-1.02), and the
    narrow band around twice the harmonic resonance answers at half its frequencies."""
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--dry-run"]) == 0
    plan_text = capsys.readouterr().out
    assert "compute periodic" in plan_text and "shared  periodic" in plan_text
    assert not out.exists()
    assert main(["demo", "--out", str(out), "--quiet"]) == 0
    cap = capsys.readouterr()
    # --quiet: no progress, no results; warnings (one line each) still reach stderr
    assert cap.out == "" and all(ln.startswith("nlbeam demo: warning: ")
                                 for ln in cap.err.splitlines()), cap.err
    assert sorted(f for f in os.listdir(out) if not f.startswith(".")) == DEMO_FILES
    for f in DEMO_FILES:
        if f.endswith(".png"):
            assert (out / f).stat().st_size > 5000, f
    import csv

    mom = {r["variant"]: r for r in csv.DictReader(open(out / "demo_moments.csv"))}
    assert float(mom["band=0-200"]["skewness"]) < -0.5
    peaks = list(csv.DictReader(open(out / "demo_peaks.csv")))
    sub = [r for r in peaks if r["variant"] == "band=78-98" and r["kind"] == "subharmonic"]
    assert sub and all(35.0 < float(r["frequency_hz"]) < 50.0 for r in sub)
    assert all(float(r["frequency_hz"]) <= 200.0 for r in peaks)
    # everything is cached now: the plan computes nothing
    assert main(["demo", "--out", str(out), "--dry-run"]) == 0
    assert "compute" not in capsys.readouterr().out
    # bad input: one line naming the option, nothing written
    assert main(["demo", "--out", str(tmp_path / "bad"), "--workers", "0"]) == 2
    assert "--workers: must be an integer >= 1" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


@pytest.mark.parametrize("cmd", [[], ["frc"], ["simulate"], ["run"], ["figures"], ["compare"],
                                 ["analyze"], ["continue"], ["refine"]])
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


def test_frc_without_a_grid_is_refused_before_any_work(tmp_path, capsys):
    # issue 18: `nlbeam frc --n-grid 0` exited 0 with a diagram of no branch
    out = tmp_path / "frc.h5"
    assert main(["frc", "--f-range", "40", "41", "--n-grid", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--n-grid" in err[0] and "got 0" in err[0]
    assert not out.exists()


def test_frc_simulate_compare(tmp_path, capsys):
    frc, sto, png = (str(tmp_path / n) for n in ("frc.h5", "sto.h5", "cmp.png"))
    assert main(["frc", "--amplitude", "1e-4", "--f-range", "42", "45", "--orders", "1",
                 "--n-grid", "3", "--out", frc]) == 0
    # progress on stderr: the brute-force grid, then one line per branch with its points
    cap = capsys.readouterr()
    err = cap.err.splitlines()
    import continuation
    diagram = continuation.load(frc)
    # stdout: the bifurcations sorted by frequency, with error, branch and order, merged
    from nlbeam.app.scenes.bifurcation_list import list_bifurcations
    rows = [ln.split() for ln in cap.out.splitlines()[1:]]
    listed = list_bifurcations(diagram)
    assert len(rows) == len(listed)
    assert [float(r[0]) for r in rows] == sorted(float(r[0]) for r in rows)
    assert [(r[2], int(r[3]), int(r[4])) for r in rows] == [(b.kind, b.order, b.branch)
                                                            for b in listed]
    branch_lines = [ln for ln in err if ln.startswith("nlbeam frc:   branch ")]
    assert any(ln.startswith("nlbeam frc:   brute-force grid: ") for ln in err), err
    assert len(branch_lines) == len(diagram.branches) >= 1
    assert [int(ln.split(" points")[0].split()[-1]) for ln in branch_lines] == \
        [len(b.values) for b in diagram.branches]
    assert main(["simulate", "--band", "0", "100", "--duration", "10", "--transient", "0.1",
                 "--psd-resolution", "1", "--channels", "delta", "--out", sto, "--quiet"]) == 0
    capsys.readouterr()
    assert main(["compare", sto, frc, "--plot", png, "--f-max", "150"]) == 0
    out = capsys.readouterr().out
    lines = out.strip().splitlines()
    assert lines[0].split()[:2] == ["peak", "Hz"] and lines[0].split()[-1] == "note"
    rows = [ln.split() for ln in lines[1:]]
    # the harmonic resonance of the 42-45 Hz diagram explains the strongest peak
    assert any(r[2] == "harmonic" and r[-1] == "resonance" and 40 < float(r[0]) < 46
               for r in rows), out
    assert all(float(r[0]) <= 150.0 for r in rows)  # --f-max limits the peaks
    assert os.path.getsize(png) > 1000
    assert main(["compare", sto, frc, "--f-max", "0"]) == 2
    assert "--f-max: must be > 0 Hz" in capsys.readouterr().err


def test_a_warning_is_one_line_naming_the_command(tmp_path, capsys, monkeypatch):
    import warnings

    import continuation

    frc0 = continuation.frequency_response

    def frc(*a, **k):
        warnings.warn("continuation: a branch ended early; try segments=4",
                      continuation.ContinuationWarning)
        return frc0(*a, **k)

    monkeypatch.setattr(continuation, "frequency_response", frc)
    out = str(tmp_path / "frc.h5")
    assert main(["frc", "--amplitude", "1e-4", "--f-range", "42", "44", "--orders", "1",
                 "--n-grid", "2", "--out", out, "--quiet", "--accuracy", "off"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == ["nlbeam frc: warning: continuation: a branch ended early; try segments=4"]


def test_workers_and_seeds_give_what_one_process_gives(tmp_path, capsys):
    """frc --workers 2: the diagram of one process; simulate --seeds on 2 workers: each member
    is the record of --seed with that seed; --workers without --seeds is refused."""
    import continuation
    import stochastic

    one, two = str(tmp_path / "one.h5"), str(tmp_path / "two.h5")
    args = ["frc", "--amplitude", "1e-4", "--f-range", "42", "45", "--orders", "1",
            "--n-grid", "3", "--accuracy", "off", "--quiet"]
    assert main(args + ["--out", one]) == 0
    assert main(args + ["--out", two, "--workers", "2"]) == 0
    a, b = continuation.load(one), continuation.load(two)
    assert [len(x.values) for x in a.branches] == [len(x.values) for x in b.branches]
    for x, y in zip(a.branches, b.branches):
        assert np.allclose(x.xmax, y.xmax, rtol=1e-12, atol=0)
    sim = ["simulate", "--band", "0", "100", "--duration", "2", "--transient", "0.1",
           "--psd-resolution", "2", "--channels", "delta"]
    assert main(sim + ["--seeds", "3", "4", "--workers", "2", "--out",
                       str(tmp_path / "s.h5")]) == 0
    out = capsys.readouterr().out
    assert "delta  over 2 seeds: mean" in out and "+-" in out
    assert main(sim + ["--seed", "4", "--quiet", "--out", str(tmp_path / "single.h5")]) == 0
    member = stochastic.load(str(tmp_path / "s-seed4.h5"))
    single = stochastic.load(str(tmp_path / "single.h5"))
    assert np.array_equal(member.psd("delta")[1], single.psd("delta")[1])
    assert (tmp_path / "s-seed3.h5").exists()
    capsys.readouterr()
    assert main(sim + ["--workers", "2", "--out", str(tmp_path / "x.h5")]) == 2
    assert "--workers/--scheduler" in capsys.readouterr().err
    assert main(sim + ["--seeds", "1", "1", "--out", str(tmp_path / "x.h5")]) == 2
    assert "--seeds: must be distinct" in capsys.readouterr().err
