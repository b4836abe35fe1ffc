"""A measured record against the simulation, in the style of the paper's section 7.

The 'rig' is the toolkit itself: the paper's beam under actuator-shaped base noise (0-200 Hz
through a 40 Hz first-order low-pass, rms 0.1 mm, Fig. 12) with one seed, sampled at 5 kHz
with 1 % measurement noise added, written to CSV as a rig would write it. That record is read
back and analysed as measured data (``stochastic.analyze``); the model is simulated under
another realization of the same excitation; the PSD and PDF of delta are overlaid.

Not run by ``nlbeam figures``. Usage (m, s, Hz):
    python figures/measured_example.py [--duration 60] [--out DIR]
Writes DIR/measured_record.csv, measured_stats.h5, measured_psd_delta.png,
measured_pdf_delta.png.
"""
import argparse
import os

import numpy as np

import nlbeam
import stochastic
from nlbeam.app.files.columns import read_columns
from nlbeam.app.plots.files import files_backend, save_figure
from nlbeam.app.plots.stochastic import pdf, response_psd

BAND, LOWPASS, RMS = (0.0, 200.0), 40.0, 1e-4  # Hz, Hz, m
FS_RIG = 5000.0  # Hz, the rig's sampling
NOISE = 0.01  # measurement noise, of each channel's std


def _rig_record(model, duration, transient, path):
    """The 'measured' record: delta and y at FS_RIG with measurement noise, written to CSV."""
    noise = stochastic.BandLimitedNoise(BAND, rms=RMS, seed=101, lowpass=LOWPASS)
    res = stochastic.simulate(model, noise, duration, transient, channels=("delta", "y"),
                              outputs=("moments",), dt=1.0 / FS_RIG,
                              keep_history=(0.0, duration))
    h = res.history
    rng = np.random.default_rng(7)
    cols = {"t": h["t"]}
    for c in ("delta", "y"):
        cols[c] = h[c] + NOISE * np.std(h[c]) * rng.standard_normal(h[c].size)
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",",
               header=",".join(cols), comments="", fmt="%.10g")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="record (s), default 60")
    ap.add_argument("--out", default=".", help="output directory, default .")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    model = nlbeam.BeamImpact()
    transient, resolution = 2.0, 0.5
    csv = os.path.join(args.out, "measured_record.csv")
    _rig_record(model, args.duration, transient, csv)
    cols = read_columns(csv, required=("t", "delta", "y"))
    measured = stochastic.analyze(cols["t"], {"delta": cols["delta"], "y": cols["y"]},
                                  psd_resolution=resolution, band=BAND)
    measured.save(os.path.join(args.out, "measured_stats.h5"))
    sim = stochastic.simulate(model, stochastic.BandLimitedNoise(BAND, rms=RMS, seed=202,
                                                                 lowpass=LOWPASS),
                              args.duration, transient, channels=("delta", "y"),
                              psd_resolution=resolution)
    files_backend()
    fig = response_psd(measured, "delta", reference=sim, reference_label="simulation",
                       mark_peaks=None, f_max=250.0)
    save_figure(fig, os.path.join(args.out, "measured_psd_delta.png"))
    fig = pdf(measured, "delta")
    c, d = sim.pdf("delta")
    fig.axes[0].step(c * 1e3, d / 1e3, where="mid", color="C1", lw=1.0, label="simulation")
    fig.axes[0].legend(frameon=False)
    save_figure(fig, os.path.join(args.out, "measured_pdf_delta.png"))
    for name, r in (("measured", measured), ("simulation", sim)):
        m = r.moments("delta")
        print(f"{name:10s} delta std {m['std']:.4e} +- {m['se_std']:.1e} m  skewness "
              f"{m['skewness']:+.3f} +- {m['se_skewness']:.3f}  kurtosis {m['kurtosis']:.3f} "
              f"+- {m['se_kurtosis']:.3f}")


if __name__ == "__main__":
    main()
