"""CPU time of the noise synthesis and of stochastic.simulate (paper beam, 0-200 Hz, rms 1e-4);
run with PYTHONPATH set to each checkout, alternating, to compare two versions side by side.
With --breakdown, also where simulate's CPU goes (cProfile with time.process_time, cumulative
per part): synthesis (the chunk tables), integration (nlbeam.integrate), estimators (feeding
Welch / histogram / moments per chunk), results (standard errors, intervals at the end).
With --tables, the integration of one noise block (2.94 s, default adaptive method) with the
quintic table handed to the kernels as nodes (code 3) and as per-cell coefficients (code 4),
alternating in this process, best of 7 CPU times.
Usage: python benchmarks/noise_synthesis_cpu.py [duration_s] [--breakdown] [--tables]"""
import cProfile
import pstats
import sys
import time

import nlbeam
import stochastic as st

args = [a for a in sys.argv[1:] if not a.startswith("--")]
dur = float(args[0]) if args else 20.0
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
print(f"{nlbeam.__file__.split('/nlbeam/')[0]}: synthesis {dur/syn:.0f} s/CPU s (h {noise.h:.3g} "
      f"s); simulate {(dur+1)/cpu:.1f} sim s/CPU s; impacts {res.n_impacts}; skew "
      f"{mo['skewness']:.4f} kurt {mo['kurtosis']:.4f}", flush=True)
if "--breakdown" in sys.argv:
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    prof = cProfile.Profile(time.process_time)
    prof.enable()
    st.simulate(model, noise, dur, transient=1.0, channels=("delta", "x", "y"))
    prof.disable()
    stats = pstats.Stats(prof).stats
    total = max(v[3] for v in stats.values())
    parts = {"synthesis": "_chunk_excitation", "integration": "integrate",
             "estimators": "feed", "results": "store_results"}
    cum = {k: sum(v[3] for (f, _, name), v in stats.items()
                  if name == fn and ("stochastic" in f or "nlbeam" in f))
           for k, fn in parts.items()}
    print("  breakdown (ms CPU of %.1f): " % (1e3 * total) + ", ".join(
        f"{k} {1e3 * v:.1f}" for k, v in cum.items())
        + f", other {1e3 * (total - sum(cum.values())):.1f}", flush=True)
if "--tables" in sys.argv:
    import numpy as np
    from nlbeam import excitation as ex

    blk = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1).block(1)
    ta, tb = blk.time_span()

    def run(limit):
        ex.COEF_MAX_NODES = limit  # 0: every quintic table as nodes (code 3)
        e = nlbeam.Sampled.from_table(blk.t_start, blk.h, blk.tab, max_freq=200.0)
        code = e.kernel_args()[0]
        t = time.process_time()
        tr = nlbeam.integrate(model, e, tb, method="adaptive", dt=res.dt, t0=ta)
        return time.process_time() - t, code, tr

    best, trs = {}, {}
    for r in range(8):
        for limit in (0, 1 << 20):
            cpu, code, trs[code] = run(limit)
            if r:
                best[code] = min(best.get(code, np.inf), cpu)
    n = trs[4].n_steps
    print(f"  one block ({tb - ta:.3g} s, {n} steps): " + ", ".join(
        f"code {c} {1e3 * v:.2f} ms ({1e9 * v / n:.0f} ns/step)" for c, v in sorted(best.items()))
        + f"; the same trajectory: {np.array_equal(trs[3].x, trs[4].x)}", flush=True)
if "--taylor" in sys.argv:
    import numpy as np
    from stochastic import _kernels

    calls = []
    real = _kernels.taylor_nodes

    def spy(D, T, scale, out):
        calls.append((D.copy(), T.copy(), scale.copy(), out.shape))
        return real(D, T, scale, out)

    _kernels.taylor_nodes = spy
    st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1).block(0)
    _kernels.taylor_nodes = real
    D, T, scale, shape = calls[-1]
    out = np.empty(shape)
    best = np.inf
    for _ in range(30):
        t = time.process_time()
        real(D, T, scale, out)
        best = min(best, time.process_time() - t)
    print(f"  taylor_nodes of one block ({D.shape[0]} coarse nodes, order {T.shape[0] - 1}, "
          f"R {T.shape[1]}, {shape[0]} table nodes): {1e3 * best:.3f} ms", flush=True)
