"""Skewness and kurtosis of delta against the excitation level (not a test).

The paper gives skewness -1.02 and kurtosis 3.96 of delta for flat 0-200 Hz base noise but
not the excitation rms. This script simulates the paper model (law 2, rk4 at the default
step) at a range of rms levels of y, all with the same seed (common random numbers: the
excitation records differ only by their scale, so differences between levels are the
effect of the scale, not of sampling), and prints per level: skewness and kurtosis of delta
with batch-means standard errors, the PSD peaks of delta (scipy.signal.find_peaks on
log10 PSD, prominence 0.5 decade), the share of the variance of delta below 15 Hz, impacts
per second and the speed (simulated s per wall s). The linear model (K_hertz = 0) is run
once for comparison.

Run:  python benchmarks/stochastic_paper_sweep.py [--duration 200] [--processes 2]
"""
import argparse
import os
import platform
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import scipy.signal

import nlbeam
import stochastic as st

LEVELS_MM = (0.001, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0)
PAPER = {"skewness": -1.02, "kurtosis": 3.96}
BAND = (0.0, 200.0)


def psd_peaks(f, P, f_min=2.0, f_max=195.0, prominence=0.5):
    """Frequencies (Hz) of the peaks of log10 P in (f_min, f_max), prominence in decades."""
    sel = (f > f_min) & (f < f_max) & (P > 0)
    idx, props = scipy.signal.find_peaks(np.log10(P[sel]), prominence=prominence)
    return f[sel][idx], props["prominences"]


def run_level(args):
    rms_m, linear, duration, seed, psd_resolution, spc = args
    model = nlbeam.BeamImpact.paper(K_hertz=0.0) if linear else nlbeam.BeamImpact.paper()
    noise = st.BandLimitedNoise(BAND, rms=rms_m, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # reported through res.message
        res = st.simulate(model, noise, duration, transient=5.0, channels=("delta",),
                          psd_resolution=psd_resolution, steps_per_contact=spc)
    f, P = res.psd("delta")
    df = f[1] - f[0]
    var_psd = float(np.sum(P) * df)
    low = float(np.sum(P[f <= 15.0]) * df) / var_psd
    pk, prom = psd_peaks(f, P)
    mo = res.moments("delta")
    return {"rms_mm": rms_m * 1e3, "linear": linear, "skewness": mo["skewness"],
            "se_skewness": mo["se_skewness"],
            "kurtosis": mo["kurtosis"],
            "se_kurtosis": mo["se_kurtosis"],
            "std_over_rms": mo["std"] / rms_m, "mean_over_rms": mo["mean"] / rms_m,
            "low_share": low, "peaks": pk, "prominences": prom,
            "impacts_per_s": res.n_impacts / res.duration,  # both over the kept record
            "sim_per_wall": (res.duration + res.transient) / res.wall_time,
            "min_spc": res.min_steps_per_contact, "message": res.message, "dt": res.dt,
            "wall": res.wall_time, "n_steps": res.n_steps, "success": res.success}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=200.0, help="kept record per level, s")
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--psd-resolution", type=float, default=0.5, help="Hz")
    ap.add_argument("--steps-per-contact", type=int, default=96,
                    help="rk4 steps per contact (nlbeam default 32)")
    a = ap.parse_args()
    # compile once in this process before forking the pool
    st.simulate(nlbeam.BeamImpact.paper(), st.BandLimitedNoise(BAND, rms=1e-4, seed=1), 0.2,
                transient=0.0)
    jobs = [(lvl * 1e-3, False, a.duration, a.seed, a.psd_resolution, a.steps_per_contact)
            for lvl in LEVELS_MM]
    jobs.append((1e-4, True, a.duration, a.seed, a.psd_resolution, a.steps_per_contact))
    # a second seed
    jobs.append((1e-4, False, a.duration, a.seed + 1, a.psd_resolution, a.steps_per_contact))
    t = time.perf_counter()
    with ProcessPoolExecutor(max_workers=a.processes) as pool:
        rows = list(pool.map(run_level, jobs))
    wall = time.perf_counter() - t
    print(f"# stochastic_paper_sweep: paper model (law 2, e = 0.5), "
          f"flat {BAND[0]:g}-{BAND[1]:g} Hz, rk4 dt = {rows[0]['dt']:.3g} s, "
          f"{a.steps_per_contact} steps per contact, transient 5 s + {a.duration:g} s per level, "
          f"seed {a.seed}, "
          f"PSD resolution {a.psd_resolution} Hz")
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"{a.processes} processes, total wall {wall:.0f} s")
    print()
    print("| rms y (mm) | skewness | kurtosis | std(delta)/rms y | mean(delta)/rms y "
          "| var share < 15 Hz | PSD peaks (Hz) | impacts/s | sim s / wall s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        name = f"{r['rms_mm']:g}" + (" (linear)" if r["linear"] else "")
        if not r["linear"] and r is rows[-1]:
            name += f" (seed {a.seed + 1})"
        if not r["success"]:
            name += " FAILED"
        peaks = ", ".join(f"{p:.1f}" for p in r["peaks"])
        print(f"| {name} | {r['skewness']:.3f} +- {r['se_skewness']:.3f} | {r['kurtosis']:.3f} +- "
              f"{r['se_kurtosis']:.3f} | {r['std_over_rms']:.4f} | {r['mean_over_rms']:+.4f} | "
              f"{r['low_share']:.3f} | {peaks} | {r['impacts_per_s']:.1f} | "
              f"{r['sim_per_wall']:.1f} |")
    print(f"| paper | {PAPER['skewness']} | {PAPER['kurtosis']} | | | | | | |")
    msgs = {r["message"] for r in rows if r["message"] != "completed"}
    print()
    print("fewest steps in a contact per level:", [r["min_spc"] for r in rows])
    for m in msgs:
        print("note:", m)
    ok = [r for r in rows if not r["linear"]]
    s = np.array([r["skewness"] for r in ok[:-1]])
    k = np.array([r["kurtosis"] for r in ok[:-1]])
    print(f"over {LEVELS_MM[0]:g}-{LEVELS_MM[-1]:g} mm: skewness {s.min():.3f} .. {s.max():.3f}, "
          f"kurtosis {k.min():.3f} .. {k.max():.3f}")


if __name__ == "__main__":
    main()
