"""nlbeam's RK4 step next to a plain compiled C loop of the same scheme (not a test).

Builds benchmarks/c_reference/rk4_contact.c with cc or gcc (-O2) into a temporary
directory, runs it and nlbeam.integrate(method='rk4') on the same problems, side by side in
one run, and prints CPU ns per step (best of 5, time.process_time for nlbeam, clock() inside
the C program). Problems (paper beam: m = 37.75e-3 kg, k = 736.3 N/m, b = 0.16 kg/s,
Lankarani-Nikravesh stop K = 2.1e8 N/m^1.5, e = 0.5; base motion a 0-200 Hz noise table on
the 1e-10 Hermite grid):
  free flight: the stop 1 m away (never met), dt = 1e-5 s, 2 s;
  in contact : the stop preloaded (gap -1 mm), a 1e-7 m rms base motion, 0.2 s, the C step
               set to nlbeam's mean step so both take the same steps.
nlbeam is also timed with graded=True, with every sample stored (store_every=1) and with
events=False, which splits its cost into bookkeeping, storing and event checks; each of these
with the lean loop for routine steps (nlbeam/_kernels/routine.py, the default) and with the
general loop alone (nlbeam.integrate.ROUTINE_STEPS = False), all variants timed in turn
(alternating rounds, best of 5), and their trajectories compared bit for bit.
Skipped with a message when no C compiler is found.
Run: python benchmarks/c_reference.py
"""
import os
import shutil
import subprocess
import tempfile
import time

import importlib

import numpy as np

import nlbeam
import stochastic as st

integ = importlib.import_module("nlbeam.integrate")

M, K_SPRING, B = 37.75e-3, 736.3, 0.16
K_HERTZ, E = 2.1e8, 0.5
SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "c_reference", "rk4_contact.c")


def build(workdir):
    """Path of the compiled reference, or None (and a message) without a compiler."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        print("c_reference: skipped, no C compiler (cc or gcc) on PATH")
        return None
    exe = os.path.join(workdir, "rk4_contact")
    subprocess.run([cc, "-O2", "-o", exe, SRC, "-lm"], check=True)
    return exe


def system(gap):
    stop = nlbeam.Contact(0, "lankarani-nikravesh", K_HERTZ, e=E, gap=gap)
    return nlbeam.System([[M]], [[B]], [[K_SPRING]], (stop,), "base", y_load=[K_SPRING],
                         yd_load=[B])


def write_table(tab, path):
    np.concatenate([[tab.tab.shape[0], tab.t_start, tab.h], tab.tab[:, 0], tab.tab[:, 1],
                    tab.tab[:, 2]]).astype(np.float64).tofile(path)


def run_c(exe, table, t_end, dt, dt_c, gap, x0, v0, v_imp0, repeats=5):
    out = subprocess.run([exe, table] + [repr(float(a)) for a in
                                         (t_end, dt, dt_c, K_HERTZ, E, gap, x0, v0, v_imp0)]
                         + [str(repeats)], check=True, capture_output=True, text=True).stdout
    ns, nr, ne, xe, ve, cpu = out.split()
    return int(ns), int(ne), float(xe), float(cpu)


def best_of_alternating(fns, repeat=5):
    """Best CPU time of each of fns, timed in turn (one call of each per round), and its last
    result: the variants see the same load."""
    best, outs = [np.inf] * len(fns), [None] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t = time.process_time()
            outs[i] = fn()
            best[i] = min(best[i], time.process_time() - t)
    return best, outs


def _run_nlbeam(model, tab, t_end, dt, x0, routine, kw):
    integ.ROUTINE_STEPS = routine
    try:
        return nlbeam.integrate(model, tab, t_end, method="rk4", dt=dt, x0=[x0, 0.0], **kw)
    finally:
        integ.ROUTINE_STEPS = True


def case(name, exe, workdir, gap, rms, t_end, dt, x0):
    # the C loop interpolates cubic Hermite tables: the noise on the cubic 1e-10 grid, and
    # nlbeam given the same (cubic) table
    noise = st.BandLimitedNoise((0.0, 200.0), rms=rms, seed=3, h=st.hermite_step(200.0))
    q = noise.sampled(t_end + 0.01)
    tab = nlbeam.Sampled(q.t_start, q.h, q.y, q.yd, q.ydd, max_freq=q.max_freq)
    path = os.path.join(workdir, f"{name}.bin")
    write_table(tab, path)
    model = system(gap)
    variants = (("rk4 graded=False", dict(graded=False, store_every=0)),
                ("rk4 graded=True", dict(graded=True, store_every=0)),
                ("rk4 graded=False store_every=1", dict(graded=False, store_every=1)),
                ("rk4 graded=False events=False", dict(graded=False, store_every=0,
                                                       events=False)))
    nlbeam.integrate(model, tab, 0.01, method="rk4", dt=dt, x0=[x0, 0.0])  # compile
    runs = [(f"{label}{'' if routine else ' general loop'}", routine, kw)
            for label, kw in variants for routine in (True, False)]
    cpus, trs = best_of_alternating([
        (lambda routine=routine, kw=kw: _run_nlbeam(model, tab, t_end, dt, x0, routine, kw))
        for label, routine, kw in runs])
    rows = [(label, cpu / tr.n_steps * 1e9, tr.n_steps, tr.state_end[0])
            for (label, routine, kw), cpu, tr in zip(runs, cpus, trs)]
    for (label, _, _), fast, general in zip(runs[::2], trs[::2], trs[1::2]):
        if not all(np.array_equal(getattr(fast, k), getattr(general, k))
                   for k in ("t", "x", "v", "state_end", "xmax", "events")):
            print(f"  ({label}: the routine loop's trajectory differs from the general loop's)")
    ref = trs[0]
    dt_c = t_end / ref.n_steps if gap < 0 else dt / 8
    ns, ne, xe, cpu = run_c(exe, path, t_end, dt, dt_c, gap, x0, 0.0, 1e-3)
    c_ns = cpu / ns * 1e9
    print(f"{name}: C {c_ns:.1f} ns/step ({ns} steps, {ne} events, x_end {xe:.12g} m)")
    for label, nsps, n, xend in rows:
        print(f"  nlbeam {label:45s} {nsps:7.1f} ns/step  {nsps / c_ns:5.1f} x C  "
              f"({n} steps, x_end {xend:.12g} m)")


def main():
    with tempfile.TemporaryDirectory() as workdir:
        exe = build(workdir)
        if exe is None:
            return
        case("free flight", exe, workdir, gap=1.0, rms=1e-4, t_end=2.0, dt=1e-5, x0=0.0)
        case("in contact", exe, workdir, gap=-1e-3, rms=1e-7, t_end=0.2, dt=1e-5,
             x0=-1e-3 + 2.3e-6)


if __name__ == "__main__":
    main()
