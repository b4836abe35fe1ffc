"""Benchmark (not a test): the frequency-response diagram of the paper model.

A = 0.1 mm, 5-150 Hz, orders 1-3. Reports the wall and CPU time (JIT cache warm), the points,
branches, bifurcations (grazing points included), superharmonic resonances and the coverage of
the harmonic branch; then refines every fold and period doubling (continuation.refine: extended
system, graded RK4 at dt_scale 1/4 .. 1/32 with steps_per_contact 32 / dt_scale, Richardson
extrapolation) and prints a table: the value at each level, the extrapolants, the digits and the
cost. Saves figures/frc_paper.png and figures/frc_paper.h5.

    python benchmarks/continuation_diagram.py [--quick]   (--quick: refine order 1 only)
    python benchmarks/continuation_diagram.py --plot      (redraw the figure from the .h5)
    python benchmarks/continuation_diagram.py --stability (harmonic branch 15-150 Hz with and
                                                           without stability: cost)
"""
import os
import sys
import time
import warnings


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402

A = 1e-4


def harmonic_coverage(frc):
    """One line: the frequency span the order-1 branches cover, and the gaps between them
    inside f_range (FrequencyResponse.uncovered: a branch that ran onto another joins it)."""
    iv = [(b.frequency.min(), b.frequency.max()) for b in frc.branches if b.order == 1]
    gaps = frc.uncovered(1)
    return (f"harmonic branch covers {min(a for a, _ in iv):.3f}-{max(b for _, b in iv):.3f} Hz;"
            " gaps: " + (", ".join(f"{a:.4f}-{b:.4f} Hz" for a, b in gaps) or "none"))


def figure(frc):
    """figures/frc_paper.png: the whole diagram (log |x|max) above, 5-30 Hz below."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from continuation.plot import plot_frequency_response
    fig, (ax, az) = plt.subplots(2, 1, figsize=(11, 11), height_ratios=(1.1, 1))
    plot_frequency_response(frc, ax=ax)
    ax.set_yscale("log")
    plot_frequency_response(frc, ax=az)
    az.set_xlim(5.0, 30.0)
    az.set_ylim(0.1, 0.3)
    az.set_title("detail 5-30 Hz (grazing points x: an impact appears or disappears)")
    az.get_legend().remove()
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "figures", "frc_paper.png"), dpi=110)
    print("saved figures/frc_paper.png")


def main(quick=False):
    warnings.simplefilter("ignore", RuntimeWarning)
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    t, c = time.perf_counter(), time.process_time()
    frc = C.frequency_response(model, A, (5.0, 150.0), orders=(1, 2, 3))
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    print(f"nlbeam from {os.path.dirname(nlbeam.__file__)}")
    print(f"diagram: {wall:.1f} s wall, {cpu:.1f} s CPU, {frc.n_points} points, "
          f"{len(frc.branches)} branches, {len(frc.bifurcations)} bifurcations "
          f"({sum(b.kind == 'grazing' for b in frc.bifurcations)} grazing)")
    for i, b in enumerate(frc.branches):
        print(f"  branch {i}: order {b.order} ({b.origin}), {len(b.values)} points, "
              f"{b.frequency.min():.3f}-{b.frequency.max():.3f} Hz, "
              f"max |x|max {b.xmax.max() * 1e3:.4f} mm")
    for bf in frc.bifurcations:
        if bf.kind != "grazing":
            print(f"  {bf.kind:16s} order {bf.order} branch {bf.branch:2d} at "
                  f"{bf.frequency:.10f} Hz (bracket {bf.tolerance:.1e}), "
                  f"|x|max {bf.xmax * 1e3:.5f} mm")
    for s in frc.superharmonics:
        print(f"  superharmonic resonance of order {s.harmonic} at {s.frequency:.4f} Hz "
              f"(+- {s.tolerance:.1e}), {s.xmax * 1e3:.5f} mm, harmonic {s.harmonic} / first "
              f"= {s.ratio:.2f}")
    print(harmonic_coverage(frc))
    graz = [b for b in frc.bifurcations if b.kind == "grazing" and b.order == 1]
    print("grazing points on the harmonic branch (Hz, bracket): "
          + ", ".join(f"{g.frequency:.5f} ({g.tolerance:.0e})" for g in graz))

    os.makedirs(os.path.join(ROOT, "figures"), exist_ok=True)
    frc.save(os.path.join(ROOT, "figures", "frc_paper.h5"))
    figure(frc)

    # accuracy: refine folds and period doublings
    coarse = {id(b): b.frequency for b in frc.bifurcations}
    t = time.perf_counter()
    res = C.refine_bifurcations(frc, model, orders=(1,) if quick else None)
    print(f"refinement: {time.perf_counter() - t:.1f} s for {len(res)} bifurcations; levels "
          "dt_scale 1/4, 1/8, 1/16, 1/32 (steps_per_contact 128 .. 1024)")
    print("| kind | order | diagram (Hz) | dt/4 | dt/8 | dt/16 | dt/32 | ratios | "
          "extrapolated (Hz) | +- | digits | cost (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for bf, r in res:
        if isinstance(r, Exception):
            print(f"| {bf.kind} | {bf.order} | {coarse[id(bf)]:.8f} | failed: "
                  f"{str(r).split(';')[0]} |")
            continue
        print(f"| {bf.kind} | {bf.order} | {coarse[id(bf)]:.8f} | "
              + " | ".join(f"{v:.10f}" for v in r.values) + " | "
              + ", ".join(f"{q:.1f}" for q in r.ratios) + f" | {r.value:.10f} | "
              f"{r.tolerance:.1e} | {r.digits:.1f} | {r.seconds.sum():.2f} |")
    frc.save(os.path.join(ROOT, "figures", "frc_paper.h5"))


def stability_cost():
    """The harmonic branch 15-150 Hz with stability=True and stability=False."""
    warnings.simplefilter("ignore", RuntimeWarning)
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    for st in (True, False):
        t, c = time.perf_counter(), time.process_time()
        frc = C.frequency_response(model, A, (15.0, 150.0), orders=(1,), stability=st)
        print(f"stability={st}: {time.perf_counter() - t:.2f} s wall, "
              f"{time.process_time() - c:.2f} s CPU, {frc.n_points} points, "
              f"{sum(b.kind == 'fold' for b in frc.bifurcations)} folds, "
              f"{len(frc.bifurcations)} bifurcations")


if __name__ == "__main__":
    if "--stability" in sys.argv:
        stability_cost()
    elif "--plot" in sys.argv:  # redraw the figure from figures/frc_paper.h5
        figure(C.load(os.path.join(ROOT, "figures", "frc_paper.h5")))
    else:
        main(quick="--quick" in sys.argv)
