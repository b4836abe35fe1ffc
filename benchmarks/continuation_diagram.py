"""Benchmark (not a test): the frequency-response diagram of the paper model.

A = 0.1 mm, 5-150 Hz, orders 1-3. Reports the wall time (JIT cache warm), the number of
points, and how the located fold / period-doubling frequencies of the harmonic branch change as
the step is refined (dt_scale 1, 1/2, 1/4, 1/8 of the free-flight step, with steps_per_contact
32 / dt_scale; significant digits that agree between the last two). Saves figures/frc_paper.png and figures/frc_paper.h5.

    python benchmarks/continuation_diagram.py [--quick]
"""
import os
import sys
import time
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402

A = 1e-4


def relocate(model, bif, dt_scale, half_width=0.3):
    """Locate one bifurcation of the harmonic branch again with a finer step: continue from a
    nearby solution over a narrow window and take the bifurcation of the same kind there."""
    integ = C.Integrator(dt_scale=dt_scale, steps_per_contact=32 / dt_scale)
    side = -0.5 * half_width if bif.kind == "fold" else 0.0
    f0 = bif.frequency + side
    sol = C.periodic_solution(model, A, bif.frequency, guess=bif.state0, integrator=integ) \
        if bif.kind != "fold" else None
    if sol is None:
        for s in (-1, 1):
            try:
                sol = C.periodic_solution(model, A, bif.frequency + s * 0.05 * half_width,
                                          guess=bif.state0, integrator=integ)
                break
            except C.ConvergenceError:
                continue
    frc = C.continue_parameter(sol, "frequency", (bif.frequency - half_width,
                                                  bif.frequency + half_width),
                               model=model, integrator=integ, bif_tol=1e-11)
    cands = [b for b in frc.bifurcations if b.kind == bif.kind]
    if not cands:
        return np.nan
    return min(cands, key=lambda b: abs(b.frequency - bif.frequency)).frequency


def main(quick=False):
    warnings.simplefilter("ignore", RuntimeWarning)
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    t = time.perf_counter()
    frc = C.frequency_response(model, A, (5.0, 150.0), orders=(1, 2, 3))
    wall = time.perf_counter() - t
    print(f"diagram: {wall:.1f} s wall, {frc.n_points} points, {len(frc.branches)} branches, "
          f"{len(frc.bifurcations)} bifurcations")
    for i, b in enumerate(frc.branches):
        print(f"  branch {i}: order {b.order} ({b.origin}), {len(b.values)} points, "
              f"{b.frequency.min():.3f}-{b.frequency.max():.3f} Hz, "
              f"max |x|max {b.xmax.max() * 1e3:.4f} mm")
    for bf in frc.bifurcations:
        print(f"  {bf.kind:16s} order {bf.order} at {bf.frequency:.10f} Hz "
              f"(+- {bf.tolerance:.1e}), |x|max {bf.xmax * 1e3:.5f} mm")
    for s in frc.superharmonics:
        print(f"  superharmonic resonance of order {s.harmonic} at {s.frequency:.4f} Hz "
              f"(+- {s.tolerance:.1e}), {s.xmax * 1e3:.5f} mm, harmonic {s.harmonic} / first "
              f"= {s.ratio:.2f}")
    # coverage of the harmonic branch(es): gaps in frequency between the order-1 branches
    iv = sorted((b.frequency.min(), b.frequency.max()) for b in frc.branches if b.order == 1)
    gaps, hi = [], iv[0][0]
    for lo_, hi_ in iv:
        if lo_ > hi + 1e-9:
            gaps.append((hi, lo_))
        hi = max(hi, hi_)
    print(f"harmonic branch covers {iv[0][0]:.3f}-{hi:.3f} Hz; gaps: "
          + (", ".join(f"{a:.4f}-{b:.4f} Hz" for a, b in gaps) or "none"))
    n_graz = sum(b.kind == "grazing" for b in frc.bifurcations)
    print(f"grazing points: {n_graz}")
    os.makedirs(os.path.join(ROOT, "figures"), exist_ok=True)
    frc.save(os.path.join(ROOT, "figures", "frc_paper.h5"))
    import matplotlib
    matplotlib.use("Agg")
    from continuation.plot import plot_frequency_response
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(11, 6.5))
    plot_frequency_response(frc, ax=ax)
    ax.set_yscale("log")
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "figures", "frc_paper.png"), dpi=130)
    print("saved figures/frc_paper.png")

    # convergence of fold / PD frequencies on the harmonic branch as dt is refined
    chosen = [b for b in frc.bifurcations if b.order == 1 and b.kind != "grazing"
              and b.frequency > 15.5][: (2 if quick else 4)]
    scales = (1.0, 0.5, 0.25) if quick else (1.0, 0.5, 0.25, 0.125)
    print("dt refinement (dt_scale: located frequency, Hz)")
    for bf in chosen:
        fs, cost = [], []
        for sc in scales:
            try:
                t1 = time.perf_counter()
                fs.append(relocate(model, bf, sc))
                cost.append(time.perf_counter() - t1)
            except C.ConvergenceError as exc:
                fs.append(np.nan)
                print("   ", exc)
        d = abs(fs[-1] - fs[-2])
        digits = -np.log10(d / abs(fs[-1])) if d > 0 else np.inf
        print(f"  {bf.kind:16s} near {bf.frequency:.6f}: "
              + ", ".join(f"{s:g}: {f:.10f} ({c:.1f} s)" for s, f, c in zip(scales, fs, cost))
              + f"  -> {digits:.1f} digits agree between the two finest")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
