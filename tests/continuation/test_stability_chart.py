"""Stability charts (continuation.stability_chart): the attractor order against known regions of
the paper model, the chart's curves through the diagram's bifurcations, HDF5 round trip, the
CSV table and figure of a scene's [chart] section, cached on a rerun."""
import csv
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from nlbeam.scenes import SceneError, load_scene, run_scene


def test_attractor_order_in_the_paper_models_regions():
    """PHYSICS.md section 2 (A = 0.1 mm): harmonic response at 40 Hz, the 1/2 subharmonic
    region 86-98 Hz; a 1/3 subharmonic at 120 Hz (order-3 branches from 105 Hz, README);
    a Duffing orbit after a slow transient (decay 0.05 1/s) is of order 1."""
    m = nlbeam.BeamImpact()
    assert [C.attractor_order(m, 1e-4, f) for f in (40.0, 90.0, 120.0)] == [1, 2, 3]
    assert C.attractor_order(nlbeam.Duffing(), 0.1, 0.15) == 1


@pytest.fixture(scope="module")
def small_chart():
    m = nlbeam.BeamImpact()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        ch = C.stability_chart(m, (5e-5, 2e-4), (55.0, 62.0), orders=(1,), amplitude=1e-4,
                               label_grid=(2, 2))
    return m, ch


def test_chart_curve_passes_the_diagrams_period_doubling(small_chart):
    m, ch = small_chart
    pds = [c for c in ch.curves if c.kind == "period-doubling"]
    assert len(pds) == 1
    c = pds[0]
    assert c.ends == ("left the parameter range", "left the parameter range")
    assert c.values.min() == pytest.approx(5e-5, rel=1e-9)
    assert c.values.max() == pytest.approx(2e-4, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        frc = C.frequency_response(m, 2e-4, (55.0, 62.0), orders=(1,), accuracy="off")
    f_pd = [b.frequency for b in frc.bifurcations if b.kind == "period-doubling"]
    f_end = c.frequency[np.argmax(c.values)]  # the curve's point placed at A = 0.2 mm
    assert min(abs(f - f_end) for f in f_pd) < 1e-6 * f_end
    # labels: the attractor order at the log-spaced grid points inside the ranges
    assert len(ch.label_order) == 4 and np.all((ch.label_order >= 0) & (ch.label_order <= 6))
    np.testing.assert_allclose(np.unique(ch.label_value), np.geomspace(5e-5, 2e-4, 4)[1:3])


def test_chart_and_curve_hdf5_round_trip(small_chart, tmp_path):
    m, ch = small_chart
    ch.save(tmp_path / "chart.h5")
    back = C.load_curves(tmp_path / "chart.h5")
    assert isinstance(back, C.StabilityChart)
    assert len(back.curves) == len(ch.curves)
    for a, b in zip(ch.curves, back.curves):
        assert (a.kind, a.order, a.ends) == (b.kind, b.order, b.ends)
        for name in ("frequency", "values", "xmax", "state0", "n_impacts", "exact"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert [s.kind for s in a.special] == [s.kind for s in b.special]
    np.testing.assert_array_equal(back.label_order, ch.label_order)
    c = ch.curves[0]
    c.save(tmp_path / "curve.h5")
    one = C.load_curves(tmp_path / "curve.h5")
    assert isinstance(one, C.BifurcationCurve)
    np.testing.assert_array_equal(one.frequency, c.frequency)
    # a diagram file is not a curves file: refused in one line
    with pytest.raises(ValueError, match="frequency-response"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", C.ContinuationWarning)
            C.frequency_response(m, 1e-4, (57.0, 59.0), orders=(1,), accuracy="off",
                                 n_grid=3).save(tmp_path / "frc.h5")
        C.load_curves(tmp_path / "frc.h5")


CHART_SCENE = """
title = "chart"
[chart]
p_range = [5e-5, 2e-4]
f_range = [55.0, 62.0]
orders = [1]
amplitude = 1e-4
label_grid = [2, 2]

[[figure]]
kind = "stability_chart"
file = "chart.png"

[[table]]
kind = "curves"
file = "curves.csv"
"""


def test_scene_chart_figure_and_table_cached(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(CHART_SCENE)
    rep = run_scene(p, tmp_path, quiet=True)
    assert rep.computed == 1
    assert (tmp_path / "chart.png").stat().st_size > 1000
    rows = list(csv.DictReader(open(tmp_path / "curves.csv")))
    pd = [r for r in rows if r["kind"] == "period-doubling" and r["point"] == "curve"]
    f = np.array([float(r["frequency_hz"]) for r in pd])
    a = np.array([float(r["value"]) for r in pd])
    assert np.all((f > 55.0) & (f < 62.0)) and np.all((a >= 5e-5 * (1 - 1e-9))
                                                      & (a <= 2e-4 * (1 + 1e-9)))
    rep2 = run_scene(p, tmp_path, quiet=True)
    assert rep2.computed == 0 and rep2.reused == 1


@pytest.mark.parametrize("text, match", [
    (CHART_SCENE.replace("amplitude = 1e-4", "amplitude = 1e-3"), r"chart\.amplitude"),
    (CHART_SCENE.replace("label_grid = [2, 2]", "label_grid = [2]"), r"chart\.label_grid"),
    (CHART_SCENE.replace("[chart]", "[chart]\nds = 1"), r"chart\.ds: unknown key"),
    (CHART_SCENE.split("[[figure]]")[0].replace("[chart]", "[periodic]").replace(
        "p_range = [5e-5, 2e-4]\n", "").replace("label_grid = [2, 2]\n", "")
     + '[[figure]]\nkind = "stability_chart"\nfile = "c.png"\n', "needs a \\[chart\\] section"),
])
def test_chart_section_checked_before_work(tmp_path, text, match):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(SceneError, match=match):
        load_scene(p)


def test_chart_front_door_checks_its_input():
    m = nlbeam.BeamImpact()
    with pytest.raises(ValueError, match="p_range: must be"):
        C.stability_chart(m, (0.0, 1e-4), (5.0, 150.0))
    with pytest.raises(ValueError, match="f_range: must be"):
        C.stability_chart(m, (1e-5, 1e-4), (150.0, 5.0))
    with pytest.raises(ValueError, match="kinds: must be among"):
        C.stability_chart(m, (1e-5, 1e-4), (5.0, 150.0), kinds=("hopf",))
    with pytest.raises(ValueError, match="amplitude: the reference amplitude"):
        C.stability_chart(m, (1e-5, 1e-4), (5.0, 150.0), amplitude=1e-3)
    with pytest.raises(ValueError, match="label_grid"):
        C.stability_chart(m, (1e-5, 1e-4), (5.0, 150.0), label_grid=(-1, 2))


def test_bundled_chart_scene_is_valid_and_outside_nlbeam_figures():
    import os

    from nlbeam.app.cli import bundled_scenes

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sc = load_scene(os.path.join(root, "figures", "extra", "paper_stability_chart.toml"))
    assert sc.chart["p_range"] == [2e-5, 5e-4] and sc.chart["f_range"] == [5.0, 150.0]
    assert [d["kind"] for d in sc.figures] == ["stability_chart"]
    assert not any("stability_chart" in p for p in bundled_scenes()[1])
