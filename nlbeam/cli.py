"""Command line: ``nlbeam demo`` (more subcommands arrive with the scenes)."""
from __future__ import annotations

import argparse
import sys
import time


def _demo(args):
    import numpy as np

    import nlbeam

    model = nlbeam.BeamImpact.paper()
    ex = nlbeam.Harmonic(args.amplitude, args.frequency)
    t0 = time.perf_counter()
    nlbeam.integrate(model, ex, 0.01)  # compile or load the cached kernels
    t1 = time.perf_counter()
    tr = nlbeam.integrate(model, ex, args.duration, store_every=0)
    t2 = time.perf_counter()
    last = nlbeam.integrate(model, ex, args.duration + 10.0 / args.frequency, x0=tr.state_end,
                            disc0=tr.disc_end, t0=args.duration, store_every=1)
    if not args.quiet:
        print("nlbeam demo: the paper's beam with elastic stop (m = 37.75 g, k = 736.3 N/m, "
              "b = 0.16 kg/s, K_hertz = 2.1e8 N/m^1.5, e = 0.5, Lankarani-Nikravesh)")
        print(f"  base excitation y = {args.amplitude:g} m * cos(2 pi {args.frequency:g} Hz t), "
              f"RK4, dt = {tr.dt:.3g} s, {tr.steps_per_contact:g} steps per contact")
        print(f"  simulated {args.duration:g} s in {t2 - t1:.3f} s "
              f"({tr.n_steps / (t2 - t1):.3g} steps/s; kernel load/compile {t1 - t0:.1f} s)")
        print(f"  impacts: {tr.n_impacts} ({tr.n_impacts / args.duration:.4g} per s)")
        print(f"  steady state over the last 10 periods: max|x| = {last.xmax[0] * 1e3:.6f} mm, "
              f"max penetration = {np.max(last.delta) * 1e6:.4f} um, "
              f"{last.n_impacts} impacts")
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(prog="nlbeam", description="Periodic and stochastic "
                                     "dynamics of a beam with an elastic stop. SI units, Hz.")
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="integrate the paper's model under harmonic base excitation "
                       "and print a summary")
    p.add_argument("--amplitude", type=float, default=1e-4, help="base amplitude A (m), default 1e-4")
    p.add_argument("--frequency", type=float, default=40.0, help="excitation frequency (Hz), default 40")
    p.add_argument("--duration", type=float, default=10.0, help="simulated time (s), default 10")
    p.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, RuntimeError) as exc:
        print(f"nlbeam {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
