"""Work-precision of nlbeam's integrators against scipy's on one noise realization (not a test).

Problem: the paper model (Lankarani-Nikravesh, e = 0.5) under one realization of flat
0-200 Hz base noise, rms 0.1 mm, seed 11, over T seconds (default 2 s), starting at rest
0.2 mm off the stop. Both integrators see the identical y(t), y'(t): the realization is
tabulated once (``noise.sampled(T)``, a ``nlbeam.Sampled`` table) and scipy's right-hand side
evaluates that table with nlbeam's own compiled interpolation (``nlbeam._kernels.excite``)
inside a numba-compiled right-hand side, so scipy is not slowed by Python arithmetic.

scipy is restarted at every contact event (the vector field changes form and the
Lankarani-Nikravesh law needs delta'_minus at the onset). The stepping loop drives the
``OdeSolver`` objects directly so that every step is inspected:
  * a sign change of delta between the step ends is located by brentq on the dense output;
  * a brief contact (or a brief exit) between two step ends is caught by checking, when
    delta' changes sign inside the step, the extremum of delta on the dense output;
  * after a restart on the boundary the sign of delta at the segment start is forced to
    its side (free flight: negative, contact: positive), so a new crossing within the first
    step is not lost to a root at the start point.
The reference is DOP853 at rtol 1e-13 with this loop; it is confirmed by nlbeam's adaptive
integrator at rtol 1e-12 (independent code). Error = max over a 0.5 ms grid of |x - x_ref|,
relative to max |x_ref|. Time: CPU time of the process (time.process_time, so that other
load on the machine does not count; on an idle core it equals the wall time), best of 3 for
nlbeam (compiled, warm), one run for scipy.

Also measures the peak RSS of stochastic.simulate for 60 s and 3600 s records (each in a
fresh subprocess, resource.getrusage ru_maxrss).

Run: python benchmarks/stochastic_work_precision.py [--T 2] [--no-rss]
Writes benchmarks/stochastic_work_precision.png and prints the tables.
"""
import argparse
import math
import os
import platform
import subprocess
import sys
import time

import numpy as np
import scipy.integrate as si
import scipy.optimize as so
from numba import njit

import nlbeam
import stochastic as st
from nlbeam._kernels import excite

HERE = os.path.dirname(os.path.abspath(__file__))
GRID = 5e-4  # s, common output grid


@njit(cache=False)
def _rhs(t, s, contact, vminus, par, code, p, tab):
    """[x', v'] of m x'' + b x' + k x + f = b y' + k y; f Lankarani-Nikravesh when contact."""
    m, b, k, K, e = par[0], par[1], par[2], par[3], par[4]
    y, yd, ydd, status = excite(t, code, p, tab)
    x, v = s[0], s[1]
    f = 0.0
    if contact:
        d = x - y
        if d > 0.0:
            f = K * d * math.sqrt(d) * (1.0 + 0.75 * (1.0 - e * e) * (v - yd) / vminus)
            if f < 0.0:
                f = 0.0
    out = np.empty(2)
    out[0] = v
    out[1] = (b * (yd - v) + k * (y - x) - f) / m
    return out


@njit(cache=False)
def _delta(t, x, v, code, p, tab):
    y, yd, ydd, status = excite(t, code, p, tab)
    return x - y, v - yd


SOLVERS = {"RK45": si.RK45, "DOP853": si.DOP853, "LSODA": si.LSODA, "Radau": si.Radau}


def scipy_restarted(method, rtol, exc, par, x0, T, grid):
    """Integrate with scipy's ``method``, restarted at every contact event. Returns x on
    ``grid``, the end state, the number of impacts and the wall time."""
    code, p, tab = exc.kernel_args()
    atol = rtol * np.array([1e-4, 1e-2])  # x ~ 0.1 mm, v ~ 10 mm/s
    t_start = time.process_time()
    xs = np.full(grid.size, np.nan)
    t, s = 0.0, np.array(x0, dtype=float)
    contact = _delta(t, s[0], s[1], code, p, tab)[0] > 0
    vminus = max(_delta(t, s[0], s[1], code, p, tab)[1], 1e-12)
    n_imp = 0
    gi = 0
    while t < T:
        side = 1.0 if contact else -1.0   # sign of delta inside this segment
        cflag, vm = bool(contact), vminus
        solver = SOLVERS[method](lambda tt, ss: _rhs(tt, ss, cflag, vm, par, code, p, tab),
                                 t, s, T, rtol=rtol, atol=atol)
        seg_t0 = t
        event = None
        while solver.status == "running":
            solver.step()
            if solver.status == "failed":
                raise RuntimeError(f"{method} failed at t = {solver.t}")
            t_old, t_new = solver.t_old, solver.t
            sol = solver.dense_output()

            def g(tt):
                if tt == seg_t0:
                    return -1e-300  # forced: the segment starts on its own side (g < 0)
                xv = sol(tt)
                return -side * _delta(tt, xv[0], xv[1], code, p, tab)[0]

            # g < 0 inside the segment's region; an event is g crossing to >= 0
            g_new = g(t_new)
            t_hit = None
            if g_new >= 0.0:
                t_hit = so.brentq(g, t_old, t_new, xtol=1e-15, rtol=1e-15)
            else:
                xa, xb = sol(t_old), sol(t_new)
                da = _delta(t_old, xa[0], xa[1], code, p, tab)[1]
                db = _delta(t_new, xb[0], xb[1], code, p, tab)[1]
                if side * da < 0 < side * db:
                    # delta has an extremum towards the boundary inside the step
                    r = so.minimize_scalar(lambda tt: -g(tt), bounds=(t_old, t_new),
                                           method="bounded", options={"xatol": 1e-14})
                    if g(r.x) >= 0.0:
                        t_hit = so.brentq(g, t_old, r.x, xtol=1e-15, rtol=1e-15)
            t_end = t_new if t_hit is None else t_hit
            gj = gi + int(np.searchsorted(grid[gi:], t_end, side="right"))
            if gj > gi:
                xs[gi:gj] = sol(grid[gi:gj])[0]
                gi = gj
            if t_hit is not None:
                event = t_hit
                break
        if event is None:
            t, s = solver.t, solver.y.copy()
            break
        s = sol(event).copy()
        y, yd, _, _ = excite(event, code, p, tab)
        s[0] = y  # onto the boundary (delta = 0)
        t = event
        contact = not contact
        if contact:
            n_imp += 1
            vminus = max(s[1] - yd, 1e-12)
    while gi < grid.size:  # grid points at T exactly
        xs[gi] = s[0]
        gi += 1
    return xs, s, n_imp, time.process_time() - t_start


def nlbeam_run(model, exc, x0, T, method, **kw):
    if method == "adaptive":
        kw.setdefault("dt", GRID)
    store = max(int(round(GRID / kw["dt"])), 1) if method != "adaptive" else 1
    best = math.inf
    for _ in range(3):
        t0 = time.process_time()
        tr = nlbeam.integrate(model, exc, T, method=method, x0=x0, store_every=store, warn=False,
                              **kw)
        best = min(best, time.process_time() - t0)
    grid_t = np.arange(0, int(round(T / GRID)) + 1) * GRID
    # fixed-step grids are t0 + j*store*dt; adaptive interpolates onto dt
    assert np.allclose(tr.t[: grid_t.size], grid_t, atol=1e-9), "grid mismatch"
    return tr.x[: grid_t.size, 0], tr.state_end, tr.n_impacts, best


def rss_of_simulate(duration):
    code = (
        "import resource, nlbeam, stochastic as st, warnings\n"
        "warnings.simplefilter('ignore')\n"
        "n = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=3)\n"
        f"r = st.simulate(nlbeam.BeamImpact.paper(), n, {duration}, transient=1.0, "
        "channels=('delta', 'x', 'y'))\n"
        "u = resource.getrusage(resource.RUSAGE_SELF)\n"
        "print(u.ru_maxrss, u.ru_utime + u.ru_stime, r.n_impacts)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    kb, cpu, imp = out.stdout.split()
    return int(kb) / 1024.0, float(cpu), int(imp)


def rss_table():
    print()
    print("| record | peak RSS (MiB) | CPU time (s) | simulated s per CPU s | impacts |")
    print("|---|---|---|---|---|")
    for d in (60.0, 3600.0):
        mib, cpu, imp = rss_of_simulate(d)
        print(f"| {d:g} s | {mib:.0f} | {cpu:.0f} | {(d + 1.0) / cpu:.1f} | {imp} |", flush=True)


def pareto(errs, times):
    """(errors ascending, times) of the non-dominated points of one curve."""
    o = np.argsort(times)
    e_best, pts = np.inf, []
    for i in o:
        if errs[i] < e_best:
            e_best = errs[i]
            pts.append((errs[i], times[i]))
    pts.sort()
    return np.array([a for a, _ in pts]), np.array([b for _, b in pts])


def time_at_error(errs, times, err):
    """Wall time a scipy curve needs for ``err``: log-log interpolation on its Pareto front
    (None when the curve never reaches it)."""
    e, w = pareto(np.asarray(errs), np.asarray(times))
    if err < e[0]:
        return None
    if err >= e[-1]:
        return float(w[-1])
    return float(10 ** np.interp(np.log10(err), np.log10(e), np.log10(w)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--T", type=float, default=2.0)
    ap.add_argument("--no-rss", action="store_true")
    ap.add_argument("--rss-only", action="store_true")
    a = ap.parse_args()
    T = a.T
    if a.rss_only:
        return rss_table()
    model = nlbeam.BeamImpact.paper()
    par = np.array([model.m, model.b, model.k, model.K_hertz, model.e])
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=11)
    exc = noise.sampled(T + 0.01)
    y0, yd0 = exc.evaluate(0.0)
    x0 = np.array([y0[0] - 2e-4, 0.0])  # at rest, 0.2 mm off the stop
    grid = np.arange(0, int(round(T / GRID)) + 1) * GRID
    # compile
    _rhs(0.0, x0, True, 1.0, par, *exc.kernel_args())
    _delta(0.0, 0.0, 0.0, *exc.kernel_args())
    nlbeam.integrate(model, exc, 0.05, x0=x0, warn=False)

    t0 = time.perf_counter()
    x_ref, s_ref, imp_ref, w_ref = scipy_restarted("DOP853", 1e-13, exc, par, x0, T, grid)
    print(f"reference DOP853 rtol 1e-13 (event-restarted): {imp_ref} impacts, {w_ref:.1f} s")
    x_chk, s_chk, imp_chk, _ = nlbeam_run(model, exc, x0, T, "adaptive", rtol=1e-12, atol=1e-16)
    scale = np.max(np.abs(x_ref))
    ref_gap = np.max(np.abs(x_chk - x_ref)) / scale
    print(f"check nlbeam adaptive rtol 1e-12: {imp_chk} impacts, max |x - x_ref| / max|x_ref| = "
          f"{ref_gap:.2e}, end state {s_chk} vs {s_ref}")

    rows = []
    # nlbeam: fixed step (steps_per_contact scaled with dt) and adaptive
    for method, settings in (
            ("rk2", [dict(dt=d, steps_per_contact=spc) for d, spc in
                     ((5e-5, 48), (2.5e-5, 96), (1.25e-5, 192), (6.25e-6, 384))]),
            ("rk4", [dict(dt=d, steps_per_contact=spc) for d, spc in
                     ((1e-4, 16), (5e-5, 32), (2.5e-5, 64), (1.25e-5, 128), (6.25e-6, 256))]),
            ("adaptive", [dict(rtol=r, atol=r * 1e-4)
                          for r in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)])):
        for kw in settings:
            x, s, imp, w = nlbeam_run(model, exc, x0, T, method, **dict(kw))
            err = np.max(np.abs(x - x_ref)) / scale
            rows.append(("nlbeam", method, kw, err, w, imp))
            print(f"nlbeam {method:8s} {str(kw):45s} err {err:.2e} cpu {w * 1e3:8.2f} ms impacts "
                  f"{imp}",
                  flush=True)
    for method, rtols in (("RK45", (1e-5, 1e-6, 1e-7, 1e-8, 1e-9)),
                          ("DOP853", (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)),
                          ("LSODA", (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)),
                          ("Radau", (1e-5, 1e-6, 1e-7, 1e-8))):
        for r in rtols:
            x, s, imp, w = scipy_restarted(method, r, exc, par, x0, T, grid)
            err = np.max(np.abs(x - x_ref)) / scale
            rows.append(("scipy", method, {"rtol": r}, err, w, imp))
            print(f"scipy  {method:8s} rtol {r:.0e} err {err:.2e} cpu {w * 1e3:9.1f} ms impacts "
                  f"{imp}",
                  flush=True)
    print(f"(total {time.perf_counter() - t0:.0f} s)")

    # speed ratio at equal error: each nlbeam point against the best scipy method at its error
    sc = {}
    for r in rows:
        if r[0] == "scipy":
            sc.setdefault(r[1], ([], []))
            sc[r[1]][0].append(r[3])
            sc[r[1]][1].append(r[4])
    print()
    print("| nlbeam | settings | error | CPU (ms) | best scipy at that error | scipy CPU (ms) | "
          "ratio |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        if r[0] != "nlbeam":
            continue
        cands = [(time_at_error(*sc[m], r[3]), m) for m in sc]
        cands = [(w, m) for w, m in cands if w is not None]
        kw = ", ".join(f"{k}={v:g}" for k, v in r[2].items())
        if not cands:
            print(f"| {r[1]} | {kw} | {r[3]:.1e} | {r[4] * 1e3:.2f} | none reaches it | | |")
            continue
        w, m = min(cands)
        print(f"| {r[1]} | {kw} | {r[3]:.1e} | {r[4] * 1e3:.2f} | {m} | {w * 1e3:.0f} | "
              f"{w / r[4]:.0f}x |")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5), layout="constrained")
    styles = {"rk2": "o-", "rk4": "s-", "adaptive": "D-", "RK45": "o--", "DOP853": "s--",
              "LSODA": "^--", "Radau": "v--"}
    for lib, meth in [("nlbeam", m) for m in ("rk2", "rk4", "adaptive")] + \
                     [("scipy", m) for m in SOLVERS]:
        pts = [(r[3], r[4]) for r in rows if r[0] == lib and r[1] == meth]
        e, w = np.array(pts).T
        ax.loglog(w, e, styles[meth], ms=4, label=f"{lib} {meth}")
    ax.axhline(ref_gap, color="0.6", lw=0.8, ls=":", label="reference vs nlbeam adaptive 1e-12")
    ax.set_xlabel("CPU time (s)")
    ax.set_ylabel("max |x - x_ref| / max |x_ref|")
    ax.set_title(f"paper beam, 0-200 Hz noise, rms 0.1 mm, {T:g} s, {imp_ref} impacts", fontsize=9)
    ax.legend(fontsize=7, ncols=2)
    out = os.path.join(HERE, "stochastic_work_precision.png")
    fig.savefig(out, dpi=130)
    print("wrote", out)

    if not a.no_rss:
        rss_table()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}")


if __name__ == "__main__":
    main()
