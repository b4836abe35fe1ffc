"""Render one figure of each kind into docs/gallery/ for docs/gallery.md: the paper's beam
(base excitation) and a force-excited single-DOF system with a stop. About a minute on two
loaded cores once the kernels are compiled.

    python docs/gallery.py
"""
from __future__ import annotations

import os
import warnings

import matplotlib

matplotlib.use("Agg")

import continuation  # noqa: E402
import nlbeam  # noqa: E402
import stochastic  # noqa: E402
from nlbeam.app.plots import stochastic as splot  # noqa: E402
from nlbeam.app.plots.compare import plot_comparison  # noqa: E402
from nlbeam.app.plots.frequency_response import plot_frequency_response  # noqa: E402
from nlbeam.app.plots.identify import plot_contact_fit  # noqa: E402
from nlbeam.identify import identify_contact  # noqa: E402

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "gallery")


def force_system():
    """1 kg, 0.5 kg/s, 4e4 N/m (31.8 Hz) with a one-sided stop 10 um away (4e5 N/m)."""
    return nlbeam.System([[1.0]], [[0.5]], [[4.0e4]], elements=(
        nlbeam.PiecewiseLinearStop(0, k=4.0e5, gap=1e-5, on_base=False),),
        excitation_kind="force", y_load=[1.0])


def collisions(speeds=(0.05, 0.1, 0.2, 0.3), K=2.1e8, e=0.5, m=37.75e-3, fs=50e3):
    """Collisions of a free mass with a Lankarani-Nikravesh stop, sampled at fs."""
    el = nlbeam.Contact(dof=0, law="lankarani-nikravesh", K=K, gap=0.0, e=e)
    free = nlbeam.System([[m]], [[0.0]], [[0.0]], elements=(el,), excitation_kind="base")
    out = [[], [], []]
    for v0 in speeds:
        tr = nlbeam.integrate(free, nlbeam.Harmonic(0.0, 1.0), 2e-3, method="adaptive",
                              dt=1.0 / fs, x0=[-2e-4 * v0, v0], rtol=1e-11, atol=1e-16)
        for lst, a in zip(out, (tr.delta[:, 0], tr.v[:, 0], tr.force[:, 0])):
            lst.append(a)
    return out


def main():
    os.makedirs(OUT, exist_ok=True)

    def path(name):
        return os.path.join(OUT, name)

    beam, force = nlbeam.BeamImpact.paper(), force_system()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # accuracy notes of these coarse diagrams
        frc = continuation.frequency_response(beam, 1e-4, (30.0, 100.0), orders=(1, 2),
                                              n_grid=10)
        frc_f = continuation.frequency_response(force, 2.0, (25.0, 40.0), orders=(1,),
                                                n_grid=4)
    plot_frequency_response(frc, path=path("frc_base.png"))
    plot_frequency_response(frc_f, path=path("frc_force.png"))
    noise = stochastic.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    res = stochastic.simulate(beam, noise, 10.0, 1.0, channels=("delta", "x", "y", "force"),
                              keep_history=(0.0, 0.3))
    splot.excitation_psd(res, noise, path=path("excitation_psd.png"))
    splot.response_psd(res, "delta", path=path("response_psd.png"))
    splot.pdf(res, "delta", path=path("pdf.png"), log=True)
    splot.time_history(res, ("y", "x"), path=path("time_history.png"))
    splot.channel_psds(res, path=path("channel_psds.png"))
    noise_f = stochastic.BandLimitedNoise((25.0, 40.0), rms=0.5, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res_f = stochastic.simulate(force, noise_f, 10.0, 1.0, channels=("delta", "y", "force"))
    splot.response_psd(res_f, "force", path=path("response_psd_force.png"))
    plot_comparison(res.psd("delta"), frc, excitation=noise, f_max=200.0,
                    path=path("compare.png"))
    data = collisions()
    plot_contact_fit(identify_contact(*data), *data, path=path("contact_fit.png"))
    print(f"wrote {len(os.listdir(OUT))} figures to {OUT}")


if __name__ == "__main__":
    main()
