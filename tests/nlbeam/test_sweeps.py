"""nlbeam.sweeps and scene sweeps: one analysis per value, run in this process, on a local
process pool, or on a Dask cluster (a LocalCluster on loopback here), with identical results
and one cache."""
import os

import numpy as np
import pytest

import stochastic
from helpers import MOMENTS_TABLE, PSD_FIGURE, TINY_STOCHASTIC
from nlbeam.scenes import SceneError, load_scene, run_scene
from nlbeam.sweeps import run_jobs

SWEEP = TINY_STOCHASTIC + """
[sweep]
parameter = "seed"
values = [1, 2]
""" + PSD_FIGURE + MOMENTS_TABLE


def _square(x):
    return x * x


def test_run_jobs_keeps_order_here_and_on_a_pool():
    xs = list(range(7))
    assert run_jobs(_square, xs, workers=1) == [x * x for x in xs]
    assert run_jobs(_square, xs, workers=2) == [x * x for x in xs]
    assert run_jobs(_square, []) == []
    with pytest.raises(ValueError, match="workers"):
        run_jobs(_square, xs, workers=0)


def test_sweep_values_are_validated_like_the_key(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(SWEEP.replace("values = [1, 2]", "values = [1, -2]"))
    with pytest.raises(SceneError, match=r"s.toml:12: sweep.values: each value: must be >= 0"):
        load_scene(p)
    p.write_text(SWEEP.replace('parameter = "seed"', 'parameter = "amplitude"'))
    with pytest.raises(SceneError, match="no \\[periodic\\]"):
        load_scene(p)


def _psds(report):
    return [stochastic.load(j.path).psd("delta") for j in report.jobs]


@pytest.fixture(scope="module")
def pool_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("pool")
    (d / "s.toml").write_text(SWEEP)
    rep = run_scene(d / "s.toml", d / "out", workers=2, quiet=True)
    return d, rep


def test_sweep_on_local_pool_makes_one_result_per_value(pool_run):
    d, rep = pool_run
    assert rep.computed == 2 and [j.variant for j in rep.jobs] == ["seed=1", "seed=2"]
    assert [stochastic.load(j.path).seed for j in rep.jobs] == [1, 2]
    a, b = _psds(rep)
    assert not np.array_equal(a[1], b[1])  # different seeds, different records
    rows = (d / "out" / "moments.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[1].startswith("seed=1")
    # the same sweep again: all cached
    again = run_scene(d / "s.toml", d / "out", workers=2, quiet=True)
    assert again.computed == 0


def test_dask_cluster_gives_the_same_results_as_the_pool(pool_run, tmp_path):
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    d, rep = pool_run
    (tmp_path / "s.toml").write_text(SWEEP)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        drep = run_scene(tmp_path / "s.toml", tmp_path / "out", scheduler=cluster.scheduler_address,
                         quiet=True)
    assert drep.computed == 2
    # same keys (cache file names) and bit-identical PSDs
    names = [os.path.basename(j.path) for j in rep.jobs]
    assert [os.path.basename(j.path) for j in drep.jobs] == names
    for (f1, p1), (f2, p2) in zip(_psds(rep), _psds(drep)):
        assert np.array_equal(f1, f2) and np.array_equal(p1, p2)
    m1 = [stochastic.load(j.path).moments("delta")["kurtosis"] for j in rep.jobs]
    m2 = [stochastic.load(j.path).moments("delta")["kurtosis"] for j in drep.jobs]
    assert m1 == m2


def test_unreachable_scheduler_is_a_clear_error(tmp_path):
    pytest.importorskip("distributed")
    with pytest.raises(RuntimeError, match="scheduler"):
        run_jobs(_square, [1, 2], scheduler="tcp://127.0.0.1:9", connect_timeout=1.0)


def test_output_that_does_not_depend_on_the_swept_parameter_is_written_once(tmp_path):
    """A seed sweep: the diagram (and its figure and table) is the same for every value, so
    it is computed and written once; the comparison reads the stochastic run and comes once
    per value."""
    text = SWEEP.replace("[sweep]", """
[periodic]
amplitude = 1e-4
f_range = [42.0, 45.0]
orders = [1]
n_grid = 3

[sweep]""") + """
[[figure]]
kind = "frc"
file = "frc.png"

[[figure]]
kind = "compare"
file = "cmp.png"

[[table]]
kind = "bifurcations"
file = "bif.csv"
"""
    (tmp_path / "s.toml").write_text(text)
    from nlbeam.scenes import format_plan, plan

    sc = load_scene(tmp_path / "s.toml")
    lines = format_plan(sc, plan(sc, tmp_path / "out"), str(tmp_path / "out")).splitlines()
    assert sum("compute periodic" in x for x in lines) == 1
    assert sum("shared  periodic [seed=2]" in x for x in lines) == 1
    rep = run_scene(tmp_path / "s.toml", tmp_path / "out", workers=1, quiet=True)
    assert rep.computed == 3 and rep.reused == 0
    names = sorted(os.path.basename(f) for f in rep.files)
    assert names == ["bif.csv", "cmp_1.png", "cmp_2.png", "frc.png", "moments.csv", "psd.png"]
    moments = (tmp_path / "out" / "moments.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in moments[1:]] == ["seed=1", "seed=2"]


def test_a_pool_relays_each_analysis_progress(tmp_path):
    """With workers, each analysis still reports its own progress (relayed from the worker
    processes), not only 'k/n analyses done' (issue 16)."""
    import io

    from nlbeam.app.progress import Progress
    (tmp_path / "s.toml").write_text(SWEEP.replace("values = [1, 2]", "values = [3, 4]"))
    buf = io.StringIO()
    run_scene(tmp_path / "s.toml", tmp_path / "out", workers=2, log=Progress(stream=buf))
    text = buf.getvalue()
    for k in (1, 2):
        assert f"[{k}/2] stochastic" in text and f"[{k}/2] stochastic seed=" in text, text
    assert "simulated:" in text and "analyses done: 2 / 2" in text, text


def test_dry_run_lists_the_files_a_run_writes(tmp_path):
    """A per-variant figure of a sweep is written as name_1.png, name_2.png: the plan lists
    those names, not name.png (issue 16)."""
    from nlbeam.scenes import format_plan, plan

    (tmp_path / "s.toml").write_text(SWEEP + '\n[[figure]]\nkind = "history"\nfile = "h.png"\n'
                                     'window = [0.0, 0.2]\n')
    scene = load_scene(tmp_path / "s.toml")
    out = str(tmp_path / "out")
    listed = {line.split(": ", 1)[1] for line in format_plan(scene, plan(scene, out), out)
              .splitlines() if line.strip().startswith("write")}
    rep = run_scene(scene, out, workers=1, quiet=True)
    assert listed == set(rep.files)
    assert {os.path.basename(f) for f in listed} == {"psd.png", "moments.csv", "h_1.png",
                                                     "h_2.png"}
