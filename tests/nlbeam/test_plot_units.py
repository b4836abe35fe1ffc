"""Every figure kind, for a base- and a force-excited system: the labels carry the units of
the one units table, the axes end where the data and the requested range end."""
import warnings

import matplotlib
import pytest

import continuation
import nlbeam
import stochastic

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from nlbeam.app.plots import stochastic as splot  # noqa: E402
from nlbeam.app.plots.frequency_response import plot_frequency_response  # noqa: E402
from nlbeam.app.plots.units import channel_unit, log_limits  # noqa: E402

BAND = (30.0, 60.0)


def _force_system():
    return nlbeam.System([[1.0]], [[0.5]], [[4.0e4]], elements=(
        nlbeam.PiecewiseLinearStop(0, k=4.0e5, gap=1e-5, on_base=False),),
        excitation_kind="force", y_load=[1.0])


@pytest.fixture(scope="module", params=["base", "force"])
def result(request):
    if request.param == "base":
        model, rms = nlbeam.BeamImpact.paper(), 1e-4
    else:
        model, rms = _force_system(), 0.5
    noise = stochastic.BandLimitedNoise(band=BAND, rms=rms, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = stochastic.simulate(model, noise, duration=8.0, transient=1.0,
                                  channels=("delta", "x", "y", "force"), psd_resolution=1.0,
                                  keep_history=(1.0, 1.5), method="rk4")
    return request.param, res


def test_units_table():
    assert channel_unit("x[1]") == ("m", "mm", 1e3)
    assert channel_unit("y", "force") == ("N", "N", 1.0)
    assert channel_unit("yd", "force") == ("N/s", "N/s", 1.0)
    assert channel_unit("force") == ("N", "N", 1.0)
    with pytest.raises(ValueError, match="ch: unknown channel 'q'"):
        channel_unit("q")
    lo, hi = log_limits([1e-30, 1e-12, 1e-6])
    assert hi == pytest.approx(3e-6) and lo == pytest.approx(3e-14)


def test_response_psd_labels_and_limits(result):
    kind, res = result
    for ch, unit in (("delta", "m$^2$/Hz"), ("force", "N$^2$/Hz")):
        fig = splot.response_psd(res, ch)
        ax = fig.axes[0]
        assert ax.get_ylabel() == f"PSD of {ch} [{unit}]"
        assert ax.get_xlabel() == "frequency [Hz]"
        assert ax.get_xlim() == (0.0, 2 * BAND[1])  # twice the band's upper edge
        f, P = res.psd(ch)
        shown = P[(f <= 2 * BAND[1]) & (P > 0)]
        lo, hi = ax.get_ylim()
        assert hi == pytest.approx(3 * shown.max())
        assert lo >= hi * 1e-8 * 0.999  # at most 8 decades, not the leakage floor
        plt.close(fig)
    fig = splot.response_psd(res, "delta", f_max=45.0)
    assert fig.axes[0].get_xlim() == (0.0, 45.0)
    plt.close(fig)
    with pytest.raises(ValueError, match="f_max"):
        splot.response_psd(res, "delta", f_max=-1.0)


def test_excitation_psd_in_the_excitation_unit(result):
    kind, res = result
    fig = splot.excitation_psd(res, f_max=80.0)
    ax = fig.axes[0]
    assert ax.get_ylabel() == ("PSD of y [m$^2$/Hz]" if kind == "base" else "PSD of y [N$^2$/Hz]")
    assert ax.get_xlim() == (0.0, 80.0)
    plt.close(fig)


def test_pdf_and_history_units(result, tmp_path):
    kind, res = result
    fig = splot.pdf(res, "force")
    assert fig.axes[0].get_xlabel() == "force [N]"
    assert fig.axes[0].get_ylabel() == "probability density [1/N]"
    plt.close(fig)
    fig = splot.pdf(res, "x")
    assert fig.axes[0].get_xlabel() == "x [mm]"
    c, d = res.pdf("x")
    assert fig.axes[0].get_ylim()[1] >= d.max() / 1e3  # the peak is inside the axes
    plt.close(fig)
    path = tmp_path / "h.png"
    fig = splot.time_history(res, ("y", "x"), path=path)
    assert path.stat().st_size > 5000
    labels = sorted(a.get_ylabel() for a in fig.axes)
    assert labels == (["y, x [mm]"] if kind == "base" else ["x [mm]", "y [N]"])
    assert not plt.fignum_exists(fig.number)  # a figure it opened and saved is closed


def test_channel_psds_one_panel_per_channel(result):
    kind, res = result
    fig = splot.channel_psds(res)
    assert len(fig.axes) == len(res.channels)
    assert [a.get_ylabel().split(" [")[0] for a in fig.axes] == [
        f"PSD of {ch}" for ch in res.channels]
    assert all(a.get_xlim() == (0.0, 2 * BAND[1]) for a in fig.axes)
    plt.close(fig)


def test_diagram_titles_name_the_excitation_and_the_legend_the_line_styles():
    m = nlbeam.BeamImpact.paper()
    frc = continuation.frequency_response(m, 1e-4, (40.0, 46.0), orders=(1,), n_grid=4)
    fig = plot_frequency_response(frc)
    ax = fig.axes[0]
    assert "base amplitude 0.1 mm" in ax.get_title()
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "stable (solid)" in texts and "unstable (dashed)" in texts
    # the legend stands right of the axes: it covers no data
    fig.canvas.draw()
    leg = ax.get_legend().get_window_extent()
    assert leg.x0 >= ax.get_window_extent().x1
    plt.close(fig)
    s = _force_system()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = continuation.frequency_response(s, 2.0, (25.0, 40.0), orders=(1,), n_grid=4)
    ax = plot_frequency_response(frc).axes[0]
    assert "force amplitude 2 N" in ax.get_title()
    assert ax.get_xlabel() == "excitation frequency [Hz]"
    plt.close(ax.figure)


def _small_diagram(kind):
    """A diagram of two branches (no computation): enough for the figure kinds."""
    import numpy as np

    from continuation.diagram import Bifurcation, Branch, FrequencyResponse
    model = nlbeam.BeamImpact.paper() if kind == "base" else _force_system()
    f = np.linspace(30.0, 60.0, 40)
    xm = 1e-4 * (1.0 + 1.0 / (1.0 + ((f - 44.0) / 2.0) ** 2))
    br = Branch(order=1, parameter="frequency", values=f, frequency=f, amplitude=np.ones(40),
                xmax=xm, stable=f < 50.0, multipliers=None, state0=np.zeros((40, 2)),
                states=np.zeros((40, 1, 2)), boundaries=np.zeros((40, 1)))
    bif = Bifurcation("period-doubling", 50.0, 50.0, float(np.interp(50.0, f, xm)), 1, 0, 1e-6,
                      None)
    return FrequencyResponse(dict(model.parameters()), 1e-4 if kind == "base" else 2.0,
                             "frequency", (30.0, 60.0), branches=[br], bifurcations=[bif])


def _every_kind(kind, res):
    """(name, function of (ax, path) drawing that figure kind) for every figure of the toolkit."""
    import numpy as np

    from nlbeam.app.plots.compare import plot_comparison
    from nlbeam.app.plots.identify import plot_contact_fit
    from nlbeam.identify import identify_contact

    frc = _small_diagram(kind)
    t = np.linspace(0.0, 1e-3, 200)
    d = 1e-5 * np.sin(np.pi * t / 1e-3)
    r = 1e-5 * np.pi / 1e-3 * np.cos(np.pi * t / 1e-3)
    F = 2e8 * d ** 1.5
    fit = identify_contact([d, d], [r, r], [F, F], law="hertz")
    return [
        ("frc", lambda ax, p: plot_frequency_response(frc, ax, path=p)),
        ("compare", lambda ax, p: plot_comparison(res.psd("delta"), frc, ax=ax, path=p,
                                                  f_max=120.0)),
        ("excitation_psd", lambda ax, p: splot.excitation_psd(res, ax=ax, path=p)),
        ("response_psd", lambda ax, p: splot.response_psd(res, "delta", ax=ax, path=p)),
        ("pdf", lambda ax, p: splot.pdf(res, "x", ax=ax, path=p)),
        ("history", lambda ax, p: splot.time_history(res, ("x",), ax=ax, path=p)),
        ("channel_psds", lambda ax, p: splot.channel_psds(res, ax=ax, path=p)),
        ("contact_fit", lambda ax, p: plot_contact_fit(fit, [d, d], [r, r], [F, F], ax=ax,
                                                       path=p)),
    ]


def test_every_figure_kind_draws_into_ax_and_closes_what_it_saves(result, tmp_path):
    """Each figure function returns the Figure, draws into the axes it is given (opening no
    figure) and, when it saves a figure it opened, closes it (issue 16)."""
    kind, res = result
    plt.close("all")
    for name, draw in _every_kind(kind, res):
        fig0, ax0 = plt.subplots()
        axes = (ax0, fig0.add_subplot(212)) if name == "compare" else ax0
        got = draw(axes, None)
        assert got is fig0, name
        assert plt.get_fignums() == [fig0.number], name  # nothing else opened
        assert ax0.has_data() and ax0.get_ylabel(), name  # drew into the given axes
        got = draw(axes, tmp_path / f"{name}_given.png")
        assert plt.fignum_exists(fig0.number), name  # the caller's figure stays open
        plt.close(fig0)
        fig = draw(None, None)
        _promised(name, kind, fig)
        plt.close(fig)
        path = tmp_path / f"{name}.png"
        fig = draw(None, path)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert not plt.fignum_exists(fig.number) and plt.get_fignums() == [], name


def _promised(name, kind, fig):
    """The labels, units and limits each figure kind promises, read back from matplotlib."""
    ax = fig.axes[0]
    y_unit = "m" if kind == "base" else "N"
    if name == "frc":
        assert ax.get_xlabel() == "excitation frequency [Hz]"
        assert ax.get_ylabel().endswith("[mm]") and ax.get_xlim() == (30.0, 60.0)
        assert ("base amplitude 0.1 mm" if kind == "base" else "force amplitude 2 N") \
            in ax.get_title()
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "stable (solid)" in texts and "unstable (dashed)" in texts
    elif name == "compare":
        assert ax.get_ylabel() == "PSD of delta [m$^2$/Hz]" and ax.get_xlim() == (0.0, 120.0)
        assert fig.axes[1].get_xlabel() == "response frequency [Hz]"
        assert fig.axes[1].get_ylabel() == "|x|max [mm]"
    elif name == "excitation_psd":
        assert ax.get_ylabel() == f"PSD of y [{y_unit}$^2$/Hz]"
        assert ax.get_xlabel() == "frequency [Hz]" and ax.get_xlim() == (0.0, 2 * BAND[1])
    elif name == "response_psd":
        assert ax.get_ylabel() == "PSD of delta [m$^2$/Hz]"
        assert ax.get_xlim() == (0.0, 2 * BAND[1])
        lo, hi = ax.get_ylim()
        assert 0 < lo and hi / lo <= 3e8  # at most 8 decades and a half: no leakage floor
    elif name == "pdf":
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [mm]", "probability density [1/mm]")
    elif name == "history":
        assert ax.get_xlabel() == "t after the transient [s]" and ax.get_ylabel() == "x [mm]"
        assert ax.get_xlim() == pytest.approx((1.0, 1.5))  # keep_history=(1.0, 1.5)
    elif name == "channel_psds":
        assert fig.axes[-1].get_xlabel() == "frequency [Hz]"
        assert [a.get_ylabel() for a in fig.axes] == [
            f"PSD of {c} [{u}$^2$/Hz]" for c, u in (("delta", "m"), ("x", "m"), ("y", y_unit),
                                                    ("force", "N"))]
    else:
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("indentation delta [um]",
                                                      "contact force F [N]")
        assert ax.get_xlim()[0] == 0.0


def test_sweep_labels_in_the_units_of_the_axes():
    """A sweep's legend says 'rms = 0.025 mm' on mm axes, not 'rms=2.5e-05' (issue 16)."""
    import importlib

    importlib.import_module("nlbeam.app.scenes")  # (the scene figures import the schema)
    from nlbeam.app.plots.scene import variant_label

    assert variant_label("rms=2.5e-05") == "rms = 0.025 mm"
    assert variant_label("amplitude=0.0001") == "amplitude = 0.1 mm"
    assert variant_label("rms=0.5", "force") == "rms = 0.5 N"
    assert variant_label("band=78-98") == "band = 78-98 Hz"
    assert variant_label("seed=3") == "seed=3" and variant_label("") == ""


def test_comparison_legend_lists_only_drawn_peaks_and_labels_stay_inside(result):
    """A peak beyond f_max gets no legend entry; a label at the low-frequency edge does not
    cross the y axis (issue 16)."""
    from nlbeam.app.compare import PeakMatch
    from nlbeam.app.plots.compare import plot_comparison

    kind, res = result
    f, P = res.psd("delta")
    far = PeakMatch(1016.0, 1.0, "unexplained", 0, float("nan"), None, float("nan"),
                    psd=float(P.max()))
    low = PeakMatch(1.0, 1.0, "asymmetry", 0, float("nan"), None, float("nan"),
                    psd=float(P.max()))
    fig = plot_comparison((f, P), _small_diagram(kind), [far, low], f_max=120.0)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "unexplained" not in labels and "asymmetry" in labels
    fig.canvas.draw()
    (text,) = [t for t in ax.texts if t.get_text() == "asym"]
    assert text.get_window_extent().x0 >= ax.get_window_extent().x0
    plt.close(fig)
