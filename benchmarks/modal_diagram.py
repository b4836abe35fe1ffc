"""Where the 4-mode beam's diagram spends its time, and what its step size buys (not a test).

The diagram of the scene figures/modal_beam.toml: ModalBeam.paper(n_modes=4) (Lankarani-Nikravesh,
K = 2.1e8 N/m^1.5, e = 0.5), A = 0.1 mm, 5-150 Hz, orders 1 and 2, n_grid 20. Units: s, Hz.

    python benchmarks/modal_diagram.py steps [--freqs 5.5,8,12.5,27,40,48] [--scales 1,2,4,8]
    python benchmarks/modal_diagram.py flows
    python benchmarks/modal_diagram.py diagram [--out modal4.h5] [--accuracy off]
    python benchmarks/modal_diagram.py branch [--freq 5.9] [--debug] [--scene] [--range 5,8]

- ``steps``: periodic orbits (order 1, found by integration to the steady state) solved at the
  default free-flight step times dt_scale (steps_per_contact 32 throughout) against the orbit at
  dt_scale 1/4: relative error of xmax, largest multiplier error, CPU per solve. Also printed:
  how much the contact steps alone change the reference (steps_per_contact 128).
- ``flows``: CPU of one period's flow with and without the variational equations (monodromy)
  at dt_scale 1, 2, 4, with the steps taken and the impacts per period.
- ``branch``: the order-1 branch through the steady state at --freq, traced alone both
  ways (with --debug: every corrector iterate and step; with --scene: the scene's
  path-follower options, else frequency_response's defaults).
- ``diagram``: the whole diagram, with the path-follower options the scene's [periodic] sets
  (ds, ds_max, max_angle, max_points, tol, bif_tol), with a progress line per branch (CPU
  seconds of this process in brackets); at the end the CPU per stage (brute-force grid,
  branches, error estimates), the CPU of the branches by how they ended, the flows the tracer
  asked for (per half-branch end reason, with those spent after the half's last point: what
  giving up cost), and the diagram's warnings. --accuracy: as the scene says
  (figures/modal_beam.toml: "off", no error estimates; "default" for the estimates as well).

Measured on main 97c7b7d (2026-11-24, 2 cores at load ~10, one run under cProfile, fresh
kernel cache): 854 s CPU: brute-force grid 257 s, all but <= 10 s of it compiling the kernels;
69 branches 389 s, of which the 36 with an end where the tracer gave up 296 s (far-side solves
29 % and bifurcation location 18 % of the branches' time); error estimates 207 s (locating
the 792 bifurcations again at finer steps 90 % of it). A flow with the variational equations
costs 3-6 times one without; below 15 Hz most steps are inside the long contacts.
"""
import argparse
import re
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

import continuation
import nlbeam
from continuation.accuracy import match_multipliers

AMPLITUDE, F_RANGE, ORDERS, N_GRID = 1e-4, (5.0, 150.0), (1, 2), 20
GAVE_UP = ("stuck at a corner", "step underflow", "no progress", "max_points",
           "could not move the segment boundaries")  # (continuation.diagram._GAVE_UP)
JUMP = "discontinuous map"


SCENE = Path(__file__).resolve().parents[1] / "figures" / "modal_beam.toml"
TRACE_KEYS = ("ds", "ds_max", "max_angle", "max_points", "tol", "bif_tol")


def scene_trace_options():
    """The path follower's options the scene's [periodic] sets (figures/modal_beam.toml), so
    that ``diagram`` measures what ``nlbeam figures`` runs."""
    with open(SCENE, "rb") as fh:
        periodic = tomllib.load(fh)["periodic"]
    return {k: periodic[k] for k in TRACE_KEYS if k in periodic}


def model():
    return nlbeam.ModalBeam.paper(n_modes=4, K_hertz=2.1e8, e=0.5, contact="lankarani-nikravesh")


def steps(freqs, scales):
    m = model()
    print(f"natural frequencies (Hz): {np.round(m.system.natural_frequencies(), 2)}")
    for f in freqs:
        try:
            ref = continuation.periodic_solution(m, AMPLITUDE, f, error=False, dt_scale=0.25)
            ref2 = continuation.periodic_solution(m, AMPLITUDE, f, guess=ref, error=False,
                                                  dt_scale=0.25, steps_per_contact=128)
        except continuation.ConvergenceError as exc:
            print(f"{f:6.2f} Hz: no reference orbit ({str(exc)[:60]}...)")
            continue
        d_mu = np.max(np.abs(match_multipliers(ref.multipliers, ref2.multipliers)
                             - ref.multipliers))
        print(f"{f:6.2f} Hz: xmax {ref.xmax:.6e} m, |mu|max {abs(ref.multipliers[0]):.4f}; "
              f"steps_per_contact 32 -> 128 at dt_scale 1/4 changes xmax by "
              f"{abs(ref2.xmax - ref.xmax) / ref.xmax:.1e} (rel), the multipliers by {d_mu:.1e}")
        for s in scales:
            t = time.process_time()
            for _ in range(3):
                sol = continuation.periodic_solution(m, AMPLITUDE, f, guess=ref, error=False,
                                                     dt_scale=s)
            cpu = (time.process_time() - t) / 3
            err = np.max(np.abs(match_multipliers(ref.multipliers, sol.multipliers)
                                - ref.multipliers))
            spp = continuation.Integrator(dt_scale=s).steps_per_period(m, f)
            print(f"    dt_scale {s:4g}: {spp:5d} free-flight steps per period, xmax error "
                  f"{abs(sol.xmax - ref.xmax) / ref.xmax:.1e} (rel), multipliers {err:.1e}, "
                  f"{1e3 * cpu:.1f} ms per solve")


def flows(freqs=(8.0, 27.0, 48.0)):
    from continuation.shooting import Integrator, ShootingProblem

    m = model()
    for f in freqs:
        sol = continuation.periodic_solution(m, AMPLITUDE, f, error=False)
        for s in (1, 2, 4):
            prob = ShootingProblem(m, AMPLITUDE, f, 1, [0.0], Integrator(dt_scale=s))
            cost = {}
            for mono in (False, True):
                n, t = 0, time.process_time()
                while time.process_time() - t < 0.5:
                    fl = prob.flow_phases(*prob.forcing(f), sol.state0, 0.0, 1.0,
                                          monodromy=mono)
                    n += 1
                cost[mono] = (time.process_time() - t) / n
            print(f"{f:5.1f} Hz dt_scale {s}: {prob.steps_per_period:5d} free-flight steps per "
                  f"period, {fl.n_steps} steps taken, {fl.n_impacts} impacts; one period "
                  f"{1e3 * cost[False]:.2f} ms, with monodromy {1e3 * cost[True]:.2f} ms "
                  f"({cost[True] / cost[False]:.1f}x)")


def diagram(out=None, accuracy="off"):
    from continuation.pathfollow import Tracer

    tracers = []
    init = Tracer.__init__

    def counting_init(self, *a, **k):  # (to report the flows every tracer asked for)
        init(self, *a, **k)
        tracers.append(self)

    Tracer.__init__ = counting_init
    trace, halves = Tracer.trace, {}

    def counting_trace(self, *a, **k):  # (flows per half-branch, and after its last point)
        n0 = self.n_evaluations
        pts, located, reason = trace(self, *a, **k)
        n, fl, end = halves.get(reason, (0, 0, 0))
        halves[reason] = (n + 1, fl + self.n_evaluations - n0, end + self.end_evaluations)
        return pts, located, reason

    Tracer.trace = counting_trace
    t0 = time.process_time()
    log = []

    def progress(msg):
        line = f"[{time.process_time() - t0:7.1f}] {msg}"
        log.append(line)
        print(line, flush=True)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frc = continuation.frequency_response(model(), AMPLITUDE, F_RANGE, orders=ORDERS,
                                              n_grid=N_GRID, progress=progress,
                                              accuracy=accuracy, **scene_trace_options())
    total = time.process_time() - t0
    Tracer.__init__, Tracer.trace = init, trace
    stamps = [(float(re.match(r"\[\s*([\d.]+)\]", s).group(1)), s) for s in log]
    grid = next(t for t, s in stamps if "brute-force grid" in s)
    last_branch = max(t for t, s in stamps if "] branch " in s)
    by_end, prev = {}, grid
    for t, s in stamps:
        if "] branch " not in s:
            prev = t if "brute-force grid" in s else prev
            continue
        ends = re.search(r"ends: (.*) / (.*) \(", s).groups()
        key = ("gave up at an end" if any(e in GAVE_UP for e in ends) else
               "ended at a discontinuous map" if JUMP in ends else "ended cleanly")
        n, c = by_end.get(key, (0, 0.0))
        by_end[key] = (n + 1, c + t - prev)
        prev = t
    print(f"scene options (figures/modal_beam.toml): {scene_trace_options()}")
    print(f"CPU {total:.1f} s: brute-force grid {grid:.1f} s (with any kernel compile), "
          f"branches {last_branch - grid:.1f} s, error estimates {total - last_branch:.1f} s")
    for key, (n, c) in by_end.items():
        print(f"  {n} branches {key}: {c:.1f} s")
    for reason, (n, fl, end) in sorted(halves.items(), key=lambda kv: -kv[1][1]):
        print(f"  {n} half-branches ending '{reason}': {fl} flows, {end} of them after the "
              "last point")
    print(f"{len(frc.branches)} branches, {frc.n_points} points, {len(frc.bifurcations)} "
          f"bifurcations; the tracer asked for {sum(t.n_evaluations for t in tracers)} flows")
    ends = [e for b in frc.branches for e, v in zip(b.ends, (b.values[0], b.values[-1]))
            if F_RANGE[0] < v < F_RANGE[1]]
    print(f"ends inside the range: {sum(e in GAVE_UP for e in ends)} where the tracer gave up, "
          f"{ends.count(JUMP)} at a 'discontinuous map'; "
          f"order 1 uncovered: {len(frc.uncovered(1))} intervals")
    for w in caught:
        print(f"{w.category.__name__}: {str(w.message)[:400]}")
    if out:
        frc.save(out)


def branch(f, debug=False, scene=False, f_range=F_RANGE):
    """The order-1 branch through the steady state at f (Hz), traced alone both ways as the
    diagram's gap seeds are: points, flows (after each half's last point), end reasons, CPU.
    scene: with the path follower's options of the scene's [periodic] (else
    frequency_response's defaults)."""
    from continuation import diagram as D
    from continuation.pathfollow import Tracer

    m, integ = model(), continuation.Integrator()
    opts = dict(ds=0.02, ds_max=0.5, max_angle=0.2, max_points=1000, tol=1e-10, bif_tol=1e-8)
    if scene:
        opts.update(scene_trace_options())
    tr = Tracer(p_min=f_range[0], p_max=f_range[1], **opts)
    tr.debug = debug
    s0 = D.steady_state(m, AMPLITUDE, f, integrator=integ)
    t0 = time.process_time()
    for (_, _, prob, u, p, _) in D._polished_starts(m, AMPLITUDE, None, "frequency", (1,),
                                                   [(f, 1, s0, False)], 1, integ, True,
                                                   tr.tol, []):
        ends, prior = [], None
        for direction in (1, -1):  # (as diagram._both_ways: the second half knows the first)
            pts, _, reason = tr.trace(prob, u, p, direction=direction, prior=prior)
            ends.append(f"{pts[-1].p:.6f} Hz {reason} ({len(pts)} points, "
                        f"{tr.end_evaluations} flows after the last)")
            if reason.startswith("closed"):
                break
            prior = tr.retrace.export()
        print(f"from {p:.6g} Hz: {'; '.join(ends)}; {tr.n_evaluations} flows, "
              f"{time.process_time() - t0:.1f} s CPU")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("steps", "flows", "diagram", "branch"))
    ap.add_argument("--freq", type=float, default=5.9, help="branch: its start (Hz)")
    ap.add_argument("--debug", action="store_true", help="branch: Tracer.debug")
    ap.add_argument("--range", default=None, help="branch: lo,hi (Hz; default the scene's)")
    ap.add_argument("--scene", action="store_true",
                    help="branch: the scene's path-follower options (figures/modal_beam.toml)")
    ap.add_argument("--freqs", default="5.5,8,12.5,27,40,48")
    ap.add_argument("--scales", default="1,2,4,8")
    ap.add_argument("--out", default=None)
    ap.add_argument("--accuracy", default="off")
    a = ap.parse_args()
    if a.what != "diagram":
        warnings.simplefilter("ignore")  # (the diagram's warnings are printed at its end)
    if a.what == "steps":
        steps([float(x) for x in a.freqs.split(",")], [float(x) for x in a.scales.split(",")])
    elif a.what == "flows":
        flows()
    elif a.what == "branch":
        branch(a.freq, a.debug, a.scene,
               tuple(map(float, a.range.split(","))) if a.range else F_RANGE)
    else:
        diagram(a.out, a.accuracy)


if __name__ == "__main__":
    main()
