"""Response statistics of the paper beam under 0-200 Hz noise (rms 1e-4 m), 60 s records of
seeds 1 and 2, each with its standard errors: run with PYTHONPATH set to two checkouts to see
whether a change of the noise synthesis moved a statistic beyond its errors (not a test).
Usage: python benchmarks/noise_statistics.py"""
import time

import nlbeam
import stochastic as st

model = nlbeam.BeamImpact()
for seed in (1, 2):
    n = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=seed)
    t = time.process_time()
    r = st.simulate(model, n, 60.0, transient=1.0, channels=("delta", "y"))
    c = time.process_time() - t
    m = r.moments("delta")
    my = r.moments("y")
    print(f"{nlbeam.__file__.split('/nlbeam/')[0]} seed {seed}: {61 / c:.0f} sim s/CPU s, impacts "
          f"{r.n_impacts}, delta std {m['std']:.4e}+-{m['se_std']:.1e} skew {m['skewness']:.3f}"
          f"+-{m['se_skewness']:.3f} kurt {m['kurtosis']:.3f}+-{m['se_kurtosis']:.3f}; y std "
          f"{my['std']:.4e}+-{my['se_std']:.1e} kurt {my['kurtosis']:.3f}+-{my['se_kurtosis']:.3f}",
          flush=True)
