"""How cost grows (not a test): with record length, number of spectral components, contact
stiffness and number of degrees of freedom, each fitted as a power law on a log-log plot; and the
profile of the hot path (one right-hand-side evaluation times the number needed, against what a
run spends). Run: python benchmarks/scaling.py [--out DIR]. Timings vary by machine; the slopes
and ratios are what carry over.
"""
import argparse
import math
import time
from pathlib import Path

import numpy as np
from numba import njit

import nlbeam
import stochastic as st
from nlbeam import _kernels as K


def wall(fn, repeat=3):
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def fit(x, y):
    return np.polyfit(np.log(x), np.log(y), 1)[0]


def loglog(path, title, xlabel, series):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5, 3.6))
    for label, x, y in series:
        ax.loglog(x, y, "o-", label=f"{label} (slope {fit(x, y):.2f})")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("wall time (s)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def record_length(out):
    model = nlbeam.BeamImpact.paper()
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    st.simulate(model, noise, 1.0, transient=0.1)
    T = np.array([5.0, 10.0, 20.0, 40.0])
    w = np.array([wall(lambda d=d: st.simulate(model, noise, d, transient=0.1), 1) for d in T])
    loglog(out / "scaling_record_length.png", "stochastic.simulate, paper model, 0-200 Hz",
           "record length (s)", [("simulate", T, w)])
    return [("record length (s)", T, w, "simulate, paper model, 0-200 Hz, rms 0.1 mm")]


def spectral_components(out):
    model = nlbeam.BeamImpact.paper()
    rng = np.random.default_rng(0)
    Ks = np.array([10, 100, 1000, 4000])
    direct = []
    for n in Ks:
        f = np.linspace(0.5, 200.0, n)
        ex = nlbeam.CosineSum(f, np.full(n, 1e-4 / math.sqrt(n)), rng.uniform(0, 2 * np.pi, n))
        nlbeam.integrate(model, ex, 0.01)
        direct.append(wall(lambda ex=ex: nlbeam.integrate(model, ex, 1.0, store_every=0), 1))
    table = []
    for n in Ks:
        f = np.linspace(0.5, 200.0, n)
        ex = nlbeam.CosineSum(f, np.full(n, 1e-4 / math.sqrt(n)), rng.uniform(0, 2 * np.pi, n))
        t = np.arange(0.0, 1.0 + 1e-5, 1e-5)
        y, yd = ex.evaluate(t)
        w = 2 * np.pi * f
        ydd = (-(np.cos(np.outer(t, w) + ex.tab[:, 2]) @ (ex.tab[:, 1] * w * w)) if n <= 1000
               else None)
        if ydd is None:
            ydd = np.gradient(yd, t)
        tab = nlbeam.Sampled(0.0, 1e-5, y, yd, ydd, max_freq=200.0)
        table.append(wall(lambda tab=tab: nlbeam.integrate(model, tab, 1.0, store_every=0), 1))
    direct, table = np.array(direct), np.array(table)
    loglog(out / "scaling_components.png", "1 s of the paper model under a sum of K cosines",
           "number of spectral components K",
           [("direct cosine sum", Ks, direct), ("tabulated (FFT synthesis)", Ks, table)])
    return [("spectral components", Ks, direct, "direct cosine sum, 1 s"),
            ("spectral components", Ks, table, "tabulated excitation (Hermite), 1 s")]


def contact_stiffness(out):
    ex = nlbeam.Harmonic(1e-4, 40.0)
    Ks = np.array([1e4, 1e6, 1e8, 1e10, 1e12])
    w = []
    for k in Ks:
        m = nlbeam.BeamImpact.paper(K_hertz=k)
        nlbeam.integrate(m, ex, 0.01)
        w.append(wall(lambda m=m: nlbeam.integrate(m, ex, 2.0, store_every=0)))
    w = np.array(w)
    loglog(out / "scaling_stiffness.png", "2 s at A = 0.1 mm, 40 Hz, rk4 defaults",
           "K_hertz (N/m^1.5)", [("integrate", Ks, w)])
    return [("K_hertz (N/m^1.5)", Ks, w, "integrate, 2 s harmonic, rk4 defaults")]


def chain(n):
    """n equal masses in a chain tied to the base, a Hertz stop on the last one."""
    m = 37.75e-3 / n
    k = 736.3 * n
    Kmat = np.zeros((n, n))
    for i in range(n):
        Kmat[i, i] += k
        if i + 1 < n:
            Kmat[i, i] += k
            Kmat[i, i + 1] -= k
            Kmat[i + 1, i] -= k
    M = np.eye(n) * m
    C = 1e-4 * Kmat
    load = np.zeros(n)
    load[0] = k
    return nlbeam.System(M, C, Kmat, (nlbeam.Contact(n - 1, "hertz", 2.1e8),), "base",
                         y_load=load, yd_load=1e-4 * load)


def dofs(out):
    ex = nlbeam.Harmonic(1e-4, 40.0)
    Ns = np.array([1, 2, 4, 8, 16, 32])
    w = []
    for n in Ns:
        s = chain(int(n))
        nlbeam.integrate(s, ex, 0.01, dt=2.5e-5)
        tr = nlbeam.integrate(s, ex, 0.5, dt=2.5e-5, store_every=0)
        w.append(wall(lambda s=s: nlbeam.integrate(s, ex, 0.5, dt=2.5e-5, store_every=0), 1)
                 / tr.n_steps * 1e5)
    w = np.array(w)
    loglog(out / "scaling_dofs.png", "chain of N masses with a stop: cost of 1e5 steps",
           "degrees of freedom N", [("integrate", Ns, w)])
    return [("degrees of freedom", Ns, w, "integrate, wall time per 1e5 steps (rk4)")]


@njit
def _rhs_loop(n, sysa, xc, xp, xtab, want_var):
    s = np.zeros(2)
    P = np.eye(2)
    dvm = np.zeros((1, 2))
    disc = np.zeros((1, 2))
    disc[0, 0] = 1.0  # in contact: the element's force and its derivatives are evaluated
    disc[0, 1] = 0.1
    ks = np.zeros(2)
    kP = np.zeros((2, 2))
    fel = np.zeros(1)
    acc = 0.0
    for i in range(n):
        s[0] = 1e-6 + 1e-12 * i  # penetrating the stop (delta = x - y > 0 near t = 0)
        s[1] = 0.05
        K.deriv(1e-7 * (i % 1000), s, P, dvm, disc, want_var, sysa, xc, xp, xtab, ks, kP, fel)
        acc += ks[1] + kP[1, 0]
    return acc


@njit
def _excite_loop(n, code, p, tab, t_span):
    acc = 0.0
    for i in range(n):
        y, yd, ydd, st = K.excite(t_span * (i / n), code, p, tab)  # forward, as an integrator
        acc += y + yd
    return acc


def profile():
    """Costs of the hot-path pieces (ns), each measured in a compiled loop, and what a run
    spends: rk4 in contact and free flight, a flow over one period with and without the
    variational equations (monodromy), the excitation evaluated from a Hermite table, by
    formula and as a direct cosine sum."""
    model = nlbeam.BeamImpact.paper()
    ex = nlbeam.Harmonic(1e-4, 40.0)
    sysa = model.kernel_arrays()
    xc, xp, xtab = ex.kernel_args()
    n = 2_000_000
    rhs = {}
    for var in (False, True):
        _rhs_loop(10, sysa, xc, xp, xtab, var)
        rhs[var] = wall(lambda var=var: _rhs_loop(n, sysa, xc, xp, xtab, var)) / n
    tr = nlbeam.integrate(model, ex, 10.0, store_every=0)
    t_run = wall(lambda: nlbeam.integrate(model, ex, 10.0, store_every=0))
    noise = st.BandLimitedNoise((0.0, 200.0), rms=1e-4, seed=1)
    tab_ex = noise.sampled(10.0)
    cos_ex = nlbeam.CosineSum(np.linspace(1.0, 200.0, 100), np.full(100, 1e-5), np.zeros(100))
    exc = {}
    for name, e in (("Hermite table (noise)", tab_ex), ("harmonic formula", ex),
                    ("direct sum of 100 cosines", cos_ex)):
        c, p_, tb = e.kernel_args()
        _excite_loop(10, c, p_, tb, 1.0)
        m = n if name != "direct sum of 100 cosines" else n // 50
        exc[name] = wall(lambda c=c, p_=p_, tb=tb, m=m: _excite_loop(m, c, p_, tb, 9.0)) / m
    s0 = np.array([0.0, 0.0])
    fl = {}
    for mono in (False, True):
        nlbeam.flow(model, ex, s0, 0.0, 0.025, monodromy=mono)
        fl[mono] = wall(lambda mono=mono: nlbeam.flow(model, ex, s0, 0.0, 0.025,
                                                      monodromy=mono), 20)
    return dict(rhs=rhs, n_rhs=tr.n_rhs, t_run=t_run, n_steps=tr.n_steps, exc=exc, flow=fl)


def main(out="benchmarks"):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for fn in (contact_stiffness, dofs, spectral_components, record_length):
        rows += fn(out)
    lines = ["| what varies | values | wall time (s) | fitted slope | case |",
             "|---|---|---|---|---|"]
    for name, x, y, case in rows:
        lines.append(f"| {name} | {', '.join(f'{v:g}' for v in x)} | "
                     f"{', '.join(f'{v:.3g}' for v in y)} | {fit(x, y):.2f} | {case} |")
    pr = profile()
    t_rhs, n_rhs, t_run, n_steps = pr["rhs"][False], pr["n_rhs"], pr["t_run"], pr["n_steps"]
    lines += ["", "Hot path (paper model, 10 s at A = 0.1 mm, 40 Hz, rk4 defaults):", "",
              f"- one right-hand-side evaluation (in contact, all element derivatives): "
              f"{t_rhs * 1e9:.0f} ns (numba loop calling the kernel's `deriv`); the run needs "
              f"{n_rhs} of them: {t_rhs * n_rhs:.4f} s",
              f"- the run takes {t_run:.4f} s for {n_steps} steps "
              f"({t_run / n_steps * 1e9:.0f} ns per step): right-hand sides are "
              f"{100 * t_rhs * n_rhs / t_run:.0f} % of it; the rest is "
              "event checks, dense output and bookkeeping.",
              f"- with the variational equations (2x2 sensitivity, 1 DOF): "
              f"{pr['rhs'][True] * 1e9:.0f} ns per right-hand side "
              f"({pr['rhs'][True] / t_rhs:.2f}x); a flow over one period (25 ms, 1 impact) costs "
              f"{pr['flow'][False] * 1e6:.0f} us without and {pr['flow'][True] * 1e6:.0f} us with "
              f"the monodromy ({pr['flow'][True] / pr['flow'][False]:.2f}x; includes the Python "
              "set-up of each call)",
              "- excitation evaluation (y, y', y'' at one time): " + ", ".join(
                  f"{k} {v * 1e9:.0f} ns" for k, v in pr["exc"].items())]
    text = "\n".join(lines)
    print(text)
    return text


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="benchmarks")
    main(ap.parse_args().out)
