"""Cost and convergence of the multi-mode beam against the number of modes (not a test).

For ModalBeam.paper(n_modes=N), N = 1, 2, 4, 8: the wall and CPU time of a frequency-response
diagram (harmonic branch, A = 0.1 mm, 20-70 Hz, n_grid 10: a reduced diagram, the full one is
figures/modal_beam.py) and of a stochastic record (0-200 Hz, rms 0.1 mm, 400 s; --duration to
shorten), each fitted as a power law in N; and what converges: the diagram's folds and the PSD
peaks of delta (find_peaks). Run: python benchmarks/modal_scaling.py [--duration S] [--quick]
(--quick: 100 s records, N = 1, 2, 4). Timings vary with the machine and its load; slopes
carry over. Cost per simulated second grows with the highest mode (the step is a fixed fraction
of its period: dt = 1 / (100 f_N) for rk4), f_N ~ N^2.
"""
import argparse
import time

import numpy as np

import continuation
import nlbeam
import stochastic
from nlbeam.compare import find_peaks


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def slope(n, t):
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--duration", type=float, default=None, help="s of record (default 400)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--modes", type=int, nargs="+", default=None)
    ap.add_argument("--method", default="rk4", help="integrator of the records (default rk4)")
    ap.add_argument("--no-diagram", action="store_true", help="records only")
    a = ap.parse_args(argv)
    modes = a.modes or ([1, 2, 4] if a.quick else [1, 2, 4, 8])
    dur = a.duration or (100.0 if a.quick else 400.0)
    # compile outside the timings
    nlbeam.integrate(nlbeam.ModalBeam.paper(n_modes=2), nlbeam.Harmonic(1e-4, 40.0), 0.05)
    stochastic.simulate(nlbeam.ModalBeam.paper(n_modes=1),
                        stochastic.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=2), 1.0, 0.1,
                        method=a.method)
    rows, folds, peaks = [], {}, {}
    for n in modes:
        mb = nlbeam.ModalBeam.paper(n_modes=n)
        if a.no_diagram:
            frc, wd, cd = continuation.FrequencyResponse({}, 1e-4, "frequency", (20.0, 70.0)), 0.0, 0.0
        else:
            frc, wd, cd = timed(lambda: continuation.frequency_response(
                mb, 1e-4, (20.0, 70.0), orders=(1,), n_grid=10))
        folds[n] = sorted((b.frequency, "F" if b.kind == "fold" else "PD") for b in frc.bifurcations
                          if b.kind in ("fold", "period-doubling"))
        noise = stochastic.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
        r, ws, cs = timed(lambda: stochastic.simulate(mb, noise, dur, 2.0, outputs=("psd", "moments"),
                                                      channels=("delta",), psd_resolution=0.25,
                                                      method=a.method))
        f, P = r.psd("delta")
        idx, prom, _, _ = find_peaks((f, P), f_range=(5.0, 200.0))
        peaks[n] = [(float(f[i]), float(p)) for i, p in zip(idx, prom)]
        mo = r.moments("delta")
        rows.append((n, mb.modal_frequencies[-1], wd, cd, frc.n_points, ws, cs,
                     mo["skewness"], mo["kurtosis"]))
        print(f"N = {n}: diagram {wd:.1f} s, record {ws:.1f} s", flush=True)
    n = np.array([r[0] for r in rows], dtype=float)
    print(f"\nModalBeam.paper(n_modes=N); diagram: harmonic branch 20-70 Hz, A = 0.1 mm, n_grid 10; "
          f"record: {dur:g} s (+2 s transient), 0-200 Hz, rms 0.1 mm, {a.method} default step\n")
    print("| N | highest mode (Hz) | diagram wall (s) | CPU (s) | points | record wall (s) | CPU (s) "
          "| skewness delta | kurtosis delta |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.1f} | {r[2]:.1f} | {r[3]:.1f} | {r[4]} | {r[5]:.1f} | {r[6]:.1f} "
              f"| {r[7]:.3f} | {r[8]:.3f} |")
    if len(rows) > 1:
        dia = "" if a.no_diagram else f"diagram {slope(n, [r[3] for r in rows]):.2f}, "
        print(f"\nfitted log-log slope in N: {dia}"
              f"record {slope(n, [r[6] for r in rows]):.2f} (CPU time; "
              f"highest mode frequency {slope(n, [r[1] for r in rows]):.2f})")
    print("\nconvergence: folds (F) and period doublings (PD) of the harmonic branch (Hz) and PSD "
          "peaks of delta (Hz, prominence in decades)")
    for r in rows:
        k = r[0]
        pk = ", ".join(f"{fq:.1f} ({p:.1f})" for fq, p in peaks[k])
        bif = ", ".join(f"{x:.3f} {kind}" for x, kind in folds[k]) or "none"
        print(f"- N = {k}: bifurcations {bif}; peaks {pk}")


if __name__ == "__main__":
    main()
