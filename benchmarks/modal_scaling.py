"""Cost and convergence of the multi-mode beam against the number of modes N (not a test).

Two parts, for ModalBeam.paper(n_modes=N), A = 0.1 mm:

1. The convergence study (default; --no-study skips it). On the harmonic resonance near 28 Hz
   (N >= 2; N = 1, the SDOF model, has its resonance at 43.5 Hz instead):
   - the periodic orbit at F_START = 27.2 Hz (the stable resonant response, found by
     integration from rest and shooting): contacts per period, the excursion away from the stop
     min u(a) (mm) and the largest penetration (um), for N up to 20 (--amp-modes);
   - the first fold or period doubling met when the branch through that orbit is followed up
     in frequency (frequency_response on WINDOW = 27.0-28.8 Hz, started from the orbit, no
     brute-force grid): where the resonant response first loses stability in a sweep up. It is
     refined (continuation.refine: extended system at dt_scale 1, 1/2, 1/4 of the default step,
     Richardson), so its tolerance is the integrator's error and the differences between
     successive N are the truncation's; for N up to 8 (--modes).
   Prints the tables, the differences between successive N and the fitted decay exponent p of
   |q(N) - q(N_max)| ~ N^-p, and the diagram's CPU per branch point against N. CPU time of
   this process (time.process_time): about 4 min for the defaults on a shared 2-core machine
   (N = 7's refinement, which falls back to 4 shooting segments, and N = 8's trace dominate);
   --quick about 10 s. N = 10 in (b) takes about 4 min more (trace only: larger N than 8 are not
   refined, see study(refine_max=...)).
2. The cost of a 400 s stochastic record (0-200 Hz, rms 0.1 mm; --duration to shorten) and its
   PSD peaks and moments of delta, for N = 1, 2, 4, 8 (--record-modes), each cost fitted as a
   power law in N (--no-records skips it; about 1.5 min CPU).

Run: python benchmarks/modal_scaling.py [--quick] [--no-study] [--no-records] [--duration S]
(--quick: N = 1..4 in the study, 100 s records of N = 1, 2, 4). Timings vary with the machine
and its load; slopes carry over. Cost per simulated second grows with the highest mode (the
step is a fixed fraction of its period: dt = 1 / (100 f_N) for rk4), f_N ~ N^2; the shooting's
variational equations add a factor ~N^2 per step.
"""
import argparse
import time
import warnings

import numpy as np

import continuation
import nlbeam
import stochastic
from continuation.refine import refine
from continuation.shooting import Integrator
from nlbeam.compare import find_peaks

AMPLITUDE = 1e-4                 # m
F_START = 27.2                   # Hz, on the stable resonant response for every N >= 2
WINDOW = (27.0, 28.8)            # Hz, the resonance's top
REFINE_SCALES = (1.0, 0.5, 0.25)  # dt_scale of the refinement levels (contact steps 32 / s)


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def slope(n, t):
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def orbit_at(n, f=F_START):
    """The periodic orbit at f (Hz) reached from rest (shooting, default rk4 step), and what it
    looks like over one period integrated from its state with at least 20000 steps:
    (solution, contacts per period, min u(a) m, max delta m, CPU s)."""
    c = time.process_time()
    mb = nlbeam.ModalBeam.paper(n_modes=n)
    sol = continuation.periodic_solution(mb, AMPLITUDE, f)
    spp = max(Integrator().steps_per_period(mb, f), 20000)  # samples fine enough for delta
    tr = nlbeam.integrate(mb, nlbeam.Harmonic(AMPLITUDE, f), 1.0 / f, dt=1.0 / (f * spp),
                          x0=sol.state0, disc0=sol.disc0, warn=False)
    u = mb.deflection(tr.x, tr.y)
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(tr.delta))):
        raise FloatingPointError(f"N = {n}: non-finite orbit at {f} Hz")
    return sol, tr.n_impacts, float(u.min()), float(tr.delta[:, 0].max()), time.process_time() - c


def first_instability(n, sol, f=F_START, window=WINDOW, scales=REFINE_SCALES):
    """Follow the branch through ``sol`` (at f) over ``window`` and return the first fold or
    period doubling above f in the forward trace (the diagram's bifurcations list the backward
    trace first, then the forward one in the order met), refined. Returns a dict."""
    mb = nlbeam.ModalBeam.paper(n_modes=n)
    c = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frc = continuation.frequency_response(mb, AMPLITUDE, window, orders=(1,),
                                              brute_force_grid=False, starts=[(f, 1, sol.state0)])
    ct = time.process_time() - c
    top = max(float(np.max(b.values)) for b in frc.branches)
    out = dict(n=n, trace_cpu=ct, points=frc.n_points, top=top, kind=None, f_diagram=np.nan,
               value=np.nan, tol=np.nan, values=(), refine_cpu=0.0, note="",
               warnings=[str(w.message).split(".")[0] for w in caught])
    if not sol.stable:
        out["note"] = f"the orbit at {f} Hz is unstable: not a loss of stability; "
    cand = [b for b in frc.bifurcations if b.kind in ("fold", "period-doubling")
            and b.frequency > f]
    if not cand:
        out["note"] += ("none in the window" if top >= window[1]
                        else f"none: the branch ends at {top:.4f} Hz")
        return out
    bf = cand[0]
    out.update(kind=bf.kind, f_diagram=bf.frequency, xmax=bf.xmax)
    if not scales:
        out["note"] += "not refined (cost); diagram bracket"
        out["value"], out["tol"] = bf.frequency, bf.tolerance
        return out
    levels = tuple(Integrator(dt_scale=s, steps_per_contact=32 / s) for s in scales)
    c = time.process_time()
    err = None
    for segs in (1, 4):
        try:
            r = refine(mb, bf, AMPLITUDE, levels=levels, max_levels=len(levels), segments=segs)
            break
        except continuation.ConvergenceError as exc:
            err = exc
    else:
        out["refine_cpu"] = time.process_time() - c
        out["note"] += f"not refined ({str(err)[:60]}...); diagram bracket"
        out["value"], out["tol"] = bf.frequency, bf.tolerance
        return out
    out["refine_cpu"] = time.process_time() - c
    if segs > 1:
        out["note"] += f"refined with {segs} shooting segments (1 did not converge)"
    out.update(value=r.value, tol=max(r.tolerance, 0.0), values=tuple(r.values))
    return out


def decay_exponent(ns, q):
    """p of |q(N) - q(N_last)| ~ N^-p, fitted over all N but the last (log-log least squares)."""
    ns, q = np.asarray(ns, float), np.asarray(q, float)
    e = np.abs(q[:-1] - q[-1])
    keep = e > 0
    return float(-np.polyfit(np.log(ns[:-1][keep]), np.log(e[keep]), 1)[0])


def study(modes, amp_modes, refine_max=8):
    print(f"\nConvergence in N: ModalBeam.paper(n_modes=N), A = {AMPLITUDE * 1e3:g} mm\n")
    print(f"(a) the periodic orbit at {F_START} Hz (shooting from the state reached from rest, "
          "default rk4 step; u(a) and delta sampled at >= 20000 steps per period)\n")
    print("| N | highest mode (Hz) | stable | contacts per period | min u(a) (mm) | difference "
          "to N-1 row (mm) | max delta (um) | CPU (s) |")
    print("|---|---|---|---|---|---|---|---|")
    amp, orbits = [], {}
    for n in amp_modes:
        sol, nimp, umin, dmax, cpu = orbit_at(n)
        orbits[n] = sol
        d = "" if not amp else f"{umin * 1e3 - amp[-1][1] * 1e3:+.4f}"
        amp.append((n, umin))
        fN = nlbeam.ModalBeam.paper(n_modes=n).modal_frequencies[-1]
        print(f"| {n} | {fN:.1f} | {sol.stable} | {nimp} | {umin * 1e3:.4f} | {d} | "
              f"{dmax * 1e6:.2f} | {cpu:.1f} |", flush=True)
    big = [(n, u) for n, u in amp if n >= 2]
    if len(big) >= 3:
        ns, us = zip(*big)
        print(f"\nmin u(a): |q(N) - q({ns[-1]})| ~ N^-p with p = {decay_exponent(ns, us):.2f} "
              f"(N = {ns[0]}..{ns[-2]})")
    print(f"\n(b) the first fold or period doubling above {F_START} Hz on the branch through "
          f"that orbit ({WINDOW[0]}-{WINDOW[1]} Hz), refined at dt_scale "
          f"{', '.join(f'{s:g}' for s in REFINE_SCALES)}\n")
    print("| N | kind | diagram (Hz) | refined (Hz) | tolerance (Hz) | difference to N-1 row "
          "(Hz) | branch's highest f (Hz) | points | trace CPU (s) | refine CPU (s) | note |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    rows, prev = [], None
    for n in modes:
        if n not in orbits:
            orbits[n] = orbit_at(n)[0]
        r = first_instability(n, orbits[n], scales=REFINE_SCALES if n <= refine_max else ())
        rows.append(r)
        d = "" if (prev is None or not np.isfinite(prev) or not np.isfinite(r["value"])) \
            else f"{r['value'] - prev:+.4f}"
        prev = r["value"]
        def fmt(v, spec):
            return "-" if not np.isfinite(v) else format(v, spec)
        print(f"| {n} | {r['kind'] or '-'} | {fmt(r['f_diagram'], '.6f')} | "
              f"{fmt(r['value'], '.6f')} | {fmt(r['tol'], '.1e')} | {d} | {r['top']:.4f} | "
              f"{r['points']} | {r['trace_cpu']:.1f} | {r['refine_cpu']:.1f} | {r['note']} |",
              flush=True)
        for w in r["warnings"]:
            print(f"  (N = {n}: {w})")
    cost = [(r["n"], r["trace_cpu"] / r["points"]) for r in rows if r["n"] >= 2 and r["points"]]
    if len(cost) >= 2:
        ns, c = zip(*cost)
        print(f"\ndiagram cost: CPU per branch point ~ N^{slope(ns, c):.2f} (N = "
              f"{ns[0]}..{ns[-1]}; "
              + ", ".join(f"N = {n}: {x * 1e3:.0f} ms" for n, x in cost) + ")")
    return amp, rows


def records(modes, dur, method):
    """Cost, moments and PSD peaks of delta of a stochastic record against N."""
    stochastic.simulate(nlbeam.ModalBeam.paper(n_modes=1),     # compile outside the timings
                        stochastic.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=2), 1.0, 0.1,
                        method=method)
    rows, peaks = [], {}
    for n in modes:
        mb = nlbeam.ModalBeam.paper(n_modes=n)
        noise = stochastic.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
        r, ws, cs = timed(lambda: stochastic.simulate(mb, noise, dur, 2.0,
                                                      outputs=("psd", "moments"),
                                                      channels=("delta",), psd_resolution=0.25,
                                                      method=method))
        f, P = r.psd("delta")
        idx, prom, _, _ = find_peaks((f, P), f_range=(5.0, 200.0))
        peaks[n] = [(float(f[i]), float(p)) for i, p in zip(idx, prom)]
        mo = r.moments("delta")
        rows.append((n, mb.modal_frequencies[-1], ws, cs, mo["skewness"], mo["kurtosis"]))
        print(f"N = {n}: record {cs:.1f} s CPU", flush=True)
    n = np.array([r[0] for r in rows], dtype=float)
    print(f"\nrecords: {dur:g} s (+2 s transient), 0-200 Hz, rms 0.1 mm, {method} default step, "
          "seed 1\n")
    print("| N | highest mode (Hz) | record wall (s) | CPU (s) | skewness delta | kurtosis delta "
          "| PSD peaks of delta (Hz, prominence in decades) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        pk = ", ".join(f"{fq:.1f} ({p:.1f})" for fq, p in peaks[r[0]])
        print(f"| {r[0]} | {r[1]:.1f} | {r[2]:.1f} | {r[3]:.1f} | {r[4]:.3f} | {r[5]:.3f} | {pk} |")
    if len(rows) > 1:
        print(f"\nfitted log-log slope in N: record {slope(n, [r[3] for r in rows]):.2f} (CPU "
              f"time; highest mode frequency {slope(n, [r[1] for r in rows]):.2f})")
    return rows, peaks


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=None, help="s of record (default 400)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--modes", type=int, nargs="+", default=None,
                    help="N of the bifurcation study (default 1..8)")
    ap.add_argument("--amp-modes", type=int, nargs="+", default=None,
                    help="N of the orbit table (default 1..8, 10, 12, 16, 20)")
    ap.add_argument("--record-modes", type=int, nargs="+", default=None,
                    help="N of the records (default 1, 2, 4, 8)")
    ap.add_argument("--method", default="rk4", help="integrator of the records (default rk4)")
    ap.add_argument("--no-study", action="store_true", help="records only")
    ap.add_argument("--no-records", action="store_true", help="convergence study only")
    ap.add_argument("--no-diagram", action="store_true", help="same as --no-study (old name)")
    a = ap.parse_args(argv)
    modes = a.modes or ([1, 2, 3, 4] if a.quick else [1, 2, 3, 4, 5, 6, 7, 8])
    amp_modes = a.amp_modes or ([1, 2, 3, 4] if a.quick
                                else [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 16, 20])
    rec_modes = a.record_modes or ([1, 2, 4] if a.quick else [1, 2, 4, 8])
    dur = a.duration or (100.0 if a.quick else 400.0)
    # compile outside the timings
    nlbeam.integrate(nlbeam.ModalBeam.paper(n_modes=2), nlbeam.Harmonic(1e-4, 40.0), 0.05)
    continuation.periodic_solution(nlbeam.ModalBeam.paper(n_modes=2), AMPLITUDE, 30.0)
    if not (a.no_study or a.no_diagram):
        c = time.process_time()
        study(modes, amp_modes)
        print(f"\nstudy: {time.process_time() - c:.0f} s CPU")
    if not a.no_records:
        records(rec_modes, dur, a.method)


if __name__ == "__main__":
    main()
