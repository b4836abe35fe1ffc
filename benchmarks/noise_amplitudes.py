"""Kurtosis and skewness bias of a linear response against CPU time, per amplitude law and
line spacing of the block noise (how the default amplitude law was chosen, issue 19).

The paper's beam without its stop (K_hertz = 0; f_n = 22.2 Hz, half-power bandwidth 0.675 Hz)
under flat 0-200 Hz noise of rms 0.1 mm, rk4 at dt = 2.5e-4 s; for each configuration
``--seeds`` independent records of ``--duration`` s. The bias is the mean over the records
of kurtosis - 3 (and of the skewness), its error the scatter over records / sqrt(records);
CPU is process time per simulated second. ``predicted`` is ``noise.kurtosis_bias``.

    python benchmarks/noise_amplitudes.py --duration 300 --seeds 6
    python benchmarks/noise_amplitudes.py --configs random:1 --first-seed 7 --seeds 14
"""
import argparse
import math
import time
import warnings

import numpy as np

import nlbeam
import stochastic as st


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=300.0, help="kept record per seed, s")
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--configs", default="deterministic:1,deterministic:4,random:1",
                    help="amplitudes:block multiple (of the default block), comma separated")
    a = ap.parse_args()
    model = nlbeam.BeamImpact.paper(K_hertz=0.0)
    zeta = model.b / (2 * math.sqrt(model.k * model.m))
    B0 = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=0).block_duration
    seeds = range(a.first_seed, a.first_seed + a.seeds)
    for cfg in a.configs.split(","):
        amp, mult = cfg.split(":")
        sk, ku, cpu = [], [], 0.0
        for s in seeds:
            n = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=s, amplitudes=amp,
                                    block_duration=int(mult) * B0)
            t = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the line-spacing warning, expected here
                r = st.simulate(model, n, a.duration, transient=5.0, dt=2.5e-4, method="rk4",
                                outputs=("moments",))
            cpu += time.process_time() - t
            mo = r.moments("delta")
            sk.append(mo["skewness"])
            ku.append(mo["kurtosis"])
        sk, ku = np.array(sk), np.array(ku)
        k = sk.size
        print(f"{amp:13s} block x{mult} df={n.df:.4f} Hz predicted kurtosis bias "
              f"{n.kurtosis_bias(model.natural_frequency, zeta):+.3f}: kurtosis-3 "
              f"{ku.mean() - 3:+.3f} +- {ku.std(ddof=1) / math.sqrt(k):.3f}, skewness "
              f"{sk.mean():+.3f} +- {sk.std(ddof=1) / math.sqrt(k):.3f} ({k} x {a.duration:g} s), "
              f"CPU {cpu / (k * (a.duration + 5.0)):.4f} s per simulated s", flush=True)


if __name__ == "__main__":
    main()
