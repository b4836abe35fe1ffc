"""Do the stated standard errors cover the scatter over seeds? (issue 19)

The paper's impacting beam under flat 0-200 Hz noise of rms 0.1 mm, ``--seeds`` records of
``--duration`` s kept after a 2 s transient, default settings. For mean, std, skewness,
kurtosis and P(delta > 0) of delta: the scatter of the estimates over the seeds against the
mean stated standard error (ratio; 1 is ideal) and the fraction of records with
|x - mean over seeds| <= 2 se (nominal ~ 95 %).

    python benchmarks/stochastic_coverage.py --duration 20 --seeds 40
"""
import argparse
import time
import warnings

import numpy as np

import nlbeam
import stochastic as st

KEYS = ("mean", "std", "skewness", "kurtosis", "p_positive")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=20.0, help="kept record per seed, s")
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--amplitudes", default="random", choices=st.noise.AMPLITUDES)
    ap.add_argument("--method", default="adaptive", choices=("adaptive", "rk4", "rk2"))
    a = ap.parse_args()
    model = nlbeam.BeamImpact.paper()
    vals = {k: [] for k in KEYS}
    ses = {k: [] for k in KEYS}
    dof, failed = [], 0
    t = time.process_time()
    for seed in range(1, a.seeds + 1):
        n = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=seed, amplitudes=a.amplitudes)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = st.simulate(model, n, a.duration, transient=2.0, outputs=("moments",),
                            method=a.method)
        if not r.success:
            failed += 1
            print(f"seed {seed} failed: {r.message}")
            continue
        mo = r.moments("delta")
        for k in KEYS:
            vals[k].append(mo[k])
            ses[k].append(mo["se_" + k])
        dof.append(mo["se_dof"])
    print(f"{a.seeds} seeds x {a.duration:g} s ({a.amplitudes} amplitudes, {a.method}), CPU "
          f"{time.process_time() - t:.1f} s, failed {failed}, median se_dof {np.median(dof):.0f}")
    for k in KEYS:
        v, s = np.array(vals[k]), np.array(ses[k])
        cover = np.mean(np.abs(v - v.mean()) <= 2 * s)
        print(f"  {k:10s} mean {v.mean():+.4g} +- {v.std(ddof=1) / np.sqrt(v.size):.2g}  "
              f"scatter {v.std(ddof=1):.3g}  mean se "
              f"{s.mean():.3g}  ratio {v.std(ddof=1) / s.mean():.2f}  |z| <= 2: {cover:.3f}")


if __name__ == "__main__":
    main()
