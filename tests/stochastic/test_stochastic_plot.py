"""Each figure function writes an image, and plotting stays out of ``import stochastic``."""
import subprocess
import sys

import matplotlib
import pytest

import nlbeam
import stochastic as st

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def result():
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=2)
    res = st.simulate(nlbeam.BeamImpact.paper(), noise, 2.0, transient=0.5,
                      channels=("delta", "x", "y"), psd_resolution=2.0, keep_history=(1.0, 1.3))
    return noise, res


@pytest.mark.parametrize("name", ["excitation_psd", "response_psd", "pdf", "time_history"])
def test_each_plot_writes_a_png(result, name, tmp_path):
    import matplotlib.pyplot as plt
    from stochastic import plot

    noise, res = result
    path = tmp_path / f"{name}.png"
    if name == "excitation_psd":
        fig = plot.excitation_psd(res, noise, path=path)
    elif name == "response_psd":
        fig = plot.response_psd(res, "delta", path=path, reference=res)
    elif name == "pdf":
        fig = plot.pdf(res, "delta", path=path, log=True)
    else:
        fig = plot.time_history(res, ("y", "x"), path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 5000
    assert fig.axes
    plt.close(fig)


def test_time_history_needs_a_kept_window(result):
    from stochastic import plot

    noise, res = result
    short = st.simulate(nlbeam.BeamImpact.paper(), noise, 0.5, transient=0.0, psd_resolution=4.0)
    with pytest.raises(ValueError, match="^result"):
        plot.time_history(short)
    with pytest.raises(ValueError, match="^channels"):
        plot.time_history(res, ("v",))


def test_importing_the_plot_module_defers_matplotlib():
    code = "import sys, stochastic.plot; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False"]
