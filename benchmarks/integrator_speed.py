"""Cost of the compiled integrator on the paper model (not a test; timings vary by machine).
Times are CPU times of this process (time.process_time), best of 5 (3 for the accuracy rows),
so that other load on a shared machine counts as little as possible.

Prints ns per RK4 step in free flight and in contact, steps per second over a 10 s harmonic run,
the accuracy of the default settings, and the table of achieved vs nominal restitution.
Run: python benchmarks/integrator_speed.py
"""
import time

import numpy as np

import nlbeam


def best_of(fn, repeat=5):
    best = np.inf
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def main():
    paper = nlbeam.BeamImpact.paper()
    ex = nlbeam.Harmonic(1e-4, 40.0)
    nlbeam.integrate(paper, ex, 0.05)  # warm the JIT cache

    free = paper.replace(K_hertz=0.0)
    tf, tr = best_of(lambda: nlbeam.integrate(free, ex, 10.0, dt=2.5e-4, store_every=0))
    print(f"RK4 free flight: {tf / tr.n_steps * 1e9:.0f} ns/step "
          f"({tr.n_steps} steps, {tr.n_rhs} rhs)")

    # permanently in contact: a preloaded stop (gap -1 mm) and small oscillation
    pre = nlbeam.System([[paper.m]], [[paper.b]], [[paper.k]],
                        (nlbeam.Contact(0, "hertz", paper.K_hertz, gap=-1e-3),), "base",
                        y_load=[paper.k], yd_load=[paper.b])
    tc, tr = best_of(lambda: nlbeam.integrate(pre, nlbeam.Harmonic(1e-7, 40.0), 0.2, dt=2e-6,
                                              x0=[-1e-3 + 7e-6, 0.0], store_every=0))
    print(f"RK4 in contact: {tc / tr.n_steps * 1e9:.0f} ns/step ({tr.n_steps} steps, "
          f"{tr.n_impacts} impacts)")

    th, tr = best_of(lambda: nlbeam.integrate(paper, ex, 10.0, store_every=0))
    print(f"10 s at A = 0.1 mm, 40 Hz (defaults dt = {tr.dt:.3g} s, {tr.steps_per_contact:g} "
          f"steps/contact): {th:.3f} s CPU, {tr.n_steps / th:.3g} steps/s, "
          f"{10.0 / th:.0f} simulated s per CPU s, {tr.n_impacts} impacts")

    ref = nlbeam.integrate(paper, ex, 1.0, method="adaptive", rtol=1e-13, atol=1e-19,
                           dt=1 / 400, store_every=0).state_end
    print("accuracy after 1 s (40 impacts), |x(1 s) - x_ref| / |x_ref|:")
    for meth, kw in (("rk4", {}), ("rk4", {"dt": 1.25e-4, "steps_per_contact": 64}),
                     ("rk4", {"dt": 6.25e-5, "steps_per_contact": 128}), ("rk2", {}),
                     ("adaptive", {"rtol": 1e-8}), ("adaptive", {"rtol": 1e-10, "atol": 1e-16})):
        t, tr = best_of(lambda: nlbeam.integrate(paper, ex, 1.0, method=meth, store_every=0,
                                                 **kw), 3)
        err = abs(tr.state_end[0] - ref[0]) / abs(ref[0])
        print(f"  {meth:8s} {str(kw):45s} error {err:.2e}  CPU {t * 1e3:.1f} ms")

    print("restitution of an isolated impact, Lankarani-Nikravesh (free mass, v0 = 0.1 m/s):")
    print("| nominal e | achieved e |")
    print("|---|---|")
    for e in (0.05, 0.1, 0.3, 0.5, 0.7, 0.9, 0.95, 0.99, 1.0):
        el = nlbeam.Contact(0, "lankarani-nikravesh", 1e8, e=e, on_base=False)
        sysm = nlbeam.System([[1e-2]], [[0.0]], [[0.0]], (el,), "force")
        tr = nlbeam.integrate(sysm, nlbeam.Harmonic(0.0, 1.0), 5e-3, x0=[-1e-8, 0.1], dt=1e-4,
                              steps_per_contact=512)
        print(f"| {e:g} | {-tr.events[1, 3] / tr.events[0, 3]:.4f} |")


if __name__ == "__main__":
    main()
