"""Where stochastic.simulate's integration CPU goes (issue 15; not a test, timings vary).

python benchmarks/simulate_steps.py [--simulate] [--errors] [--repeat N]

One noise block (paper beam, 0-200 Hz, rms 0.1 mm, seed 1, block 1: 2.94 s), integrated as
simulate integrates it (adaptive DP5, rtol 1e-8, atol 1e-12 m, samples every 1/6400 s): DP5
step attempts and rejections, impacts, and the kernel's CPU time (time.process_time, best of
N, default 7) with the samples stored (store_every=1, as simulate) and not (store_every=0), for the
paper beam and for the same beam without its stop (K_hertz = 0: free flight only). The
differences give the cost of storing a sample and of the steps a contact adds. With
--simulate also stochastic.simulate itself (1 s + 30 s, channels delta, x, y; best of 3):
simulated seconds per CPU second and the moments of delta.
With --errors also the work-precision problem of benchmarks/stochastic_work_precision.py
(paper beam, 0-200 Hz, rms 0.1 mm, seed 11, 2 s from x = -0.2 mm at rest, samples every
0.5 ms) at rtol 1e-6 .. 1e-10 (atol 1e-12 m): DP5 attempts, rejections and max|x - x_ref| /
max|x_ref| against nlbeam's own DP5 at rtol 1e-12, atol 1e-18 (what a change of the step
control does to steps and errors; scipy's reference is that benchmark's).
To compare two checkouts run it with PYTHONPATH set to each, alternating.
"""
import sys
import time

import numpy as np

import nlbeam
import stochastic as st

DT = 1.0 / 6400.0


def best_cpu(fn, repeat):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def block_rows(repeat):
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    B = noise.block_duration
    exc = noise.sampled(2.0 * B, t_start=B)
    paper = nlbeam.BeamImpact()
    nlbeam.integrate(paper, exc, B + 0.05, t0=B, method="adaptive", dt=DT)  # compile / load
    n_samples = None
    for name, model in (("paper", paper), ("no stop", paper.replace(K_hertz=0.0))):
        cpu = {}
        for se in (1, 0):
            cpu[se], tr = best_cpu(lambda: nlbeam.integrate(
                model, exc, 2.0 * B, t0=B, method="adaptive", dt=DT, rtol=1e-8, atol=1e-12,
                store_every=se), repeat)
            if se == 1:
                n_samples = tr.t.size
        print(f"{name:8s}: {tr.n_steps} DP5 attempts ({tr.n_rejected} rejected), "
              f"{tr.n_impacts} impacts; CPU {cpu[1] * 1e3:.2f} ms stored, {cpu[0] * 1e3:.2f} ms "
              f"not: {cpu[0] / tr.n_steps * 1e9:.0f} ns an attempt, "
              f"{(cpu[1] - cpu[0]) / n_samples * 1e9:.0f} ns a stored sample; "
              f"{B / cpu[1]:.0f} simulated s per CPU s")


def error_rows(repeat):
    model = nlbeam.BeamImpact.paper()
    exc = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=11).sampled(2.0)

    def run(rtol, atol=1e-12):
        return nlbeam.integrate(model, exc, 2.0, x0=[-2e-4, 0.0], method="adaptive", dt=5e-4,
                                rtol=rtol, atol=atol)

    xr = run(1e-12, 1e-18).x[:, 0]
    for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        cpu, tr = best_cpu(lambda: run(rtol), repeat)
        err = np.max(np.abs(tr.x[:, 0] - xr)) / np.max(np.abs(xr))
        print(f"rtol {rtol:g}: {tr.n_steps} DP5 attempts ({tr.n_rejected} rejected), "
              f"{tr.n_impacts} impacts, error {err:.2e}, CPU {cpu * 1e3:.2f} ms")


def simulate_row():
    model = nlbeam.BeamImpact()
    st.simulate(model, st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1), 0.5, transient=0.0)
    cpu, res = best_cpu(lambda: st.simulate(
        model, st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1), 30.0, transient=1.0,
        channels=("delta", "x", "y")), 3)
    mo = res.moments("delta")
    print(f"simulate 1 s + 30 s: {cpu:.3f} s CPU, {31.0 / cpu:.0f} simulated s per CPU s; "
          f"{res.n_steps} steps, {res.n_impacts} impacts; delta std {mo['std']:.6e}, skewness "
          f"{mo['skewness']:.4f} +- {mo['se_skewness']:.4f}, kurtosis {mo['kurtosis']:.4f} +- "
          f"{mo['se_kurtosis']:.4f}")


if __name__ == "__main__":
    args = sys.argv[1:]
    block_rows(int(args[args.index("--repeat") + 1]) if "--repeat" in args else 7)
    if "--errors" in args:
        error_rows(5)
    if "--simulate" in args:
        simulate_row()
