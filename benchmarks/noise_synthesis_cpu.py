"""CPU time of the noise synthesis and of stochastic.simulate (paper beam, 0-200 Hz, rms 1e-4);
run with PYTHONPATH set to each checkout, alternating, to compare two versions side by side.
Usage: python benchmarks/noise_synthesis_cpu.py [duration_s]"""
import sys
import time

import nlbeam
import stochastic as st
dur = float(sys.argv[1]) if len(sys.argv) > 1 else 20.0
noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
noise.block(0)
t = time.process_time(); n = 0
for b in noise.blocks(0.0, dur):
    n += b.tab.shape[0]
syn = time.process_time() - t
noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
model = nlbeam.BeamImpact()
st.simulate(model, noise, 0.5, transient=0.0)
noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
t = time.process_time()
res = st.simulate(model, noise, dur, transient=1.0, channels=("delta", "x", "y"))
cpu = time.process_time() - t
mo = res.moments("delta")
print(f"{nlbeam.__file__.split('/nlbeam/')[0]}: synthesis {dur/syn:.0f} s/CPU s; simulate "
      f"{(dur+1)/cpu:.1f} sim s/CPU s; impacts {res.n_impacts}; skew {mo['skewness']:.4f} "
      f"kurt {mo['kurtosis']:.4f}", flush=True)
