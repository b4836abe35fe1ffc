"""A 10^4 s stochastic record of the paper's beam: energy balance, moments and memory per batch.

python benchmarks/long_record.py [--duration 10000] [--batch 250] [--method rk4]

The paper model under 0-200 Hz band-limited noise (rms 0.1 mm) is integrated chunk by chunk
exactly as ``stochastic.simulate`` does (same chunk excitation, same ``nlbeam.integrate`` calls,
state and contact memory carried across chunks). For every batch it prints

- the moments of delta (std, skewness, kurtosis),
- the power balance of eq. 1, m x'' + b x' + k x + f = b y' + k y: with the stored energy
  E = m v^2/2 + k (x - y)^2/2 + V(delta), dE/dt = P_in - b (v - y')^2 - (f - f_el) delta', where
  P_in = y' (k (y - x) + b (y' - v) - f) is the power the frame puts in. Over a batch the
  elastic part f_el delta' and dE/dt average to (almost) zero, so mean P_in must equal the mean
  dissipated power b (v - y')^2 + f delta' up to E(end) - E(start) / batch length and the
  sampling error of the 20 kHz grid (contacts last ~1 ms). The residual is reported relative
  to P_in; drift would show as a trend over the batches (fitted slope with its standard error).
- the resident set size (current, from /proc/self/statm) after the batch.

No assertions: this is a report. The quick check of the same balance lives in the tests.
"""
import argparse
import os
import time

import numpy as np

import nlbeam
import stochastic as st
from stochastic.estimators import StreamingMoments
from stochastic.simulate import _chunk_excitation


def rss_mib():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def energy(model, x, v, y, delta):
    """Stored energy (J): kinetic + beam spring + elastic Hertz energy of the stop."""
    K = model.K_hertz
    return (0.5 * model.m * v ** 2 + 0.5 * model.k * (x - y) ** 2
            + 0.4 * K * np.clip(delta, 0, None) ** 2.5)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.0e4, help="s (after a 10 s transient)")
    ap.add_argument("--batch", type=float, default=250.0, help="s per reported batch")
    ap.add_argument("--method", default="rk4")
    ap.add_argument("--rms", type=float, default=1e-4, help="m")
    args = ap.parse_args(argv)

    model = nlbeam.BeamImpact.paper()
    noise = st.BandLimitedNoise((0.0, 200.0), rms=args.rms, seed=2026)
    dt = nlbeam.default_dt(model, noise, args.method)
    transient = 10.0
    chunk = noise.block_duration
    b, k = model.b, model.k

    nlbeam.integrate(model, _chunk_excitation(noise, 0.0, 0.1), 0.1, method=args.method, dt=dt)
    rss0 = rss_mib()
    print(f"paper beam, 0-200 Hz, rms {args.rms * 1e3:g} mm, {args.method} dt = {dt:.3g} s, "
          f"{args.duration:g} s after a {transient:g} s transient, batches of {args.batch:g} s, "
          f"chunks of {chunk:g} s; RSS after compile {rss0:.0f} MiB")
    print(f"{'t_end s':>9} {'std(delta) m':>13} {'skew':>7} {'kurt':>6} {'P_in W':>10} "
          f"{'P_diss W':>10} {'dE/T W':>9} {'resid':>9} {'impacts':>8} {'RSS MiB':>8}")

    state, disc, t = None, None, 0.0
    t_wall = time.perf_counter()
    rows, total = [], StreamingMoments()
    batch_end = transient + args.batch
    acc = None
    E_start = None
    t_stop = transient + args.duration
    while t < t_stop - 1e-9:
        t_b = min(t + chunk, batch_end if t >= transient else transient, t_stop)
        tr = nlbeam.integrate(model, _chunk_excitation(noise, t, t_b), t_b, method=args.method,
                              dt=dt, x0=state, t0=t, disc0=disc)
        state, disc = tr.state_end, tr.disc_end
        if t >= transient:
            sel = slice(0, -1)  # [t, t_b): the chunk end is the next chunk's start
            x, v = tr.x[sel, 0], tr.v[sel, 0]
            d, f = tr.delta[sel, 0], tr.force[sel, 0]
            y, yd = tr.excitation.evaluate(tr.t[sel])
            if acc is None:
                acc = dict(n=0, pin=0.0, pdiss=0.0, imp=0, mom=StreamingMoments())
                E_start = float(energy(model, x[:1], v[:1], y[:1], d[:1])[0])
            acc["n"] += x.size
            acc["pin"] += float(np.sum(yd * (k * (y - x) + b * (yd - v) - f)))
            acc["pdiss"] += float(np.sum(b * (v - yd) ** 2 + f * (v - yd)))
            acc["imp"] += tr.n_impacts
            acc["mom"].update(d)
            total.update(d)
        t = t_b
        at_end = abs(t - batch_end) < 1e-9 or abs(t - t_stop) < 1e-9
        if t >= transient and acc is not None and at_end:
            y1, _ = tr.excitation.evaluate([t])
            E_end = float(energy(model, state[:1], state[1:2], y1, np.array([state[0] - y1[0]]))[0])
            T = acc["n"] * dt
            mo = acc["mom"].result()
            pin, pdiss = acc["pin"] / acc["n"], acc["pdiss"] / acc["n"]
            dEdt = (E_end - E_start) / T
            resid = (pin - pdiss - dEdt) / pin
            rows.append((t, mo["std"], mo["skewness"], mo["kurtosis"], pin, pdiss, dEdt, resid,
                         rss_mib()))
            print(f"{t:9.0f} {mo['std']:13.5e} {mo['skewness']:7.3f} {mo['kurtosis']:6.3f} "
                  f"{pin:10.4e} {pdiss:10.4e} {dEdt:9.1e} {resid:9.2e} {acc['imp']:8d} "
                  f"{rows[-1][-1]:8.0f}", flush=True)
            acc = None
            batch_end = t + args.batch
    wall = time.perf_counter() - t_wall
    r = np.array(rows)
    tt, res = r[:, 0], r[:, 7]
    A = np.vstack([tt - tt.mean(), np.ones_like(tt)]).T
    coef, ssr, *_ = np.linalg.lstsq(A, res, rcond=None)
    n = len(tt)
    se = (np.sqrt(ssr[0] / (n - 2) / np.sum((tt - tt.mean()) ** 2)) if n > 2 and ssr.size
          else float("nan"))
    mo = total.result()
    print()
    print(f"wall {wall:.0f} s for {transient + args.duration:g} simulated s "
          f"({(transient + args.duration) / wall:.1f} simulated s per wall s)")
    print(f"power-balance residual: mean {res.mean():.2e}, batch std {res.std(ddof=1):.2e}, "
          f"trend {coef[0] * 1e3:.2e} +- {se * 1e3:.2e} per 1000 s")
    for j, name in ((1, "std"), (2, "skewness"), (3, "kurtosis")):
        half = n // 2
        print(f"{name} of delta: whole {mo[name]:.5g}; batches mean {r[:, j].mean():.5g}, "
              f"batch std {r[:, j].std(ddof=1):.3g}; first half {r[:half, j].mean():.5g}, "
              f"second half {r[half:, j].mean():.5g}")
    print(f"RSS: after compile {rss0:.0f} MiB, after first batch {r[0, -1]:.0f} MiB, "
          f"after last {r[-1, -1]:.0f} MiB, max {r[:, -1].max():.0f} MiB")


if __name__ == "__main__":
    main()
