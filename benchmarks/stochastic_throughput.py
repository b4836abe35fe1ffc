"""Throughput of the stochastic layer (run by hand: python benchmarks/stochastic_throughput.py).

Prints the synthesis rate of BandLimitedNoise (table samples per second, with the default
grid step that meets the 1e-10 Hermite bound) and the speed of stochastic.simulate on the
paper's beam under 0-200 Hz noise (simulated seconds per wall-clock second), so that a
regression in either shows up as a number. No assertions: timing depends on the machine.
"""
import time

import nlbeam
import stochastic as st


def main(duration=20.0):
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    noise.block(0)  # warm caches / compile
    t = time.perf_counter()
    n = 0
    for b in noise.blocks(0.0, duration):
        n += b.tab.shape[0]
    dt_syn = time.perf_counter() - t
    print(f"synthesis: {n} samples (h = {noise.h:.3g} s) in {dt_syn:.2f} s "
          f"-> {n / dt_syn:.3g} samples/s, {duration / dt_syn:.1f} s of excitation per s")
    model = nlbeam.BeamImpact()
    st.simulate(model, noise, 0.5, transient=0.0)  # compile
    t = time.perf_counter()
    res = st.simulate(model, noise, duration, transient=1.0, channels=("delta", "x", "y"))
    wall = time.perf_counter() - t
    mo = res.moments("delta")
    print(f"simulate (paper beam, rk4, dt = {res.dt:.3g} s): {duration + 1.0:.0f} s simulated in "
          f"{wall:.2f} s -> {(duration + 1.0) / wall:.1f} simulated s per s; "
          f"{res.n_impacts} impacts, {res.n_chunks} chunks")
    print(f"  delta: skewness {mo['skewness']:.3f} +- {mo['se_skewness']:.3f}, "
          f"kurtosis {mo['kurtosis']:.3f} +- {mo['se_kurtosis']:.3f} (paper: -1.02, 3.96)")


if __name__ == "__main__":
    main()
