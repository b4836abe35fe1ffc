"""Benchmark (not a test): the paper model's stability chart against a grid of diagrams.

The chart: continuation.stability_chart over A = 0.02-0.5 mm, 5-150 Hz, orders 1-3 (fold,
period-doubling, Neimark-Sacker and grazing curves from the diagram at A = 0.1 mm; the label
grid of attractor orders). Reports CPU time (process_time, one core; JIT cache warm) of the
reference diagram, of the curves and of the labels, and the curves' points and shooting
evaluations.

The grid of one-parameter diagrams that gives the same information: a diagram at amplitude A
places each curve at A exactly; between the grid's amplitudes the curve is read by
interpolation (linear in log A). For each curve that is single-valued in A, the number of
log-spaced amplitudes K for which that interpolation stays within ``TOL_HZ`` of the curve is
found; the grid needs the largest K, at the measured CPU cost of one diagram each.

    python benchmarks/stability_chart.py            (chart + grid estimate; saves
                                                     figures/stability_chart_paper.png/.h5)
    python benchmarks/stability_chart.py --plot     (redraw the figure from the .h5)
"""
import os
import sys
import time
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(ROOT)  # an installed / PYTHONPATH nlbeam takes precedence

import numpy as np  # noqa: E402

import nlbeam  # noqa: E402

import continuation as C  # noqa: E402

P_RANGE = (2e-5, 5e-4)
F_RANGE = (5.0, 150.0)
A_REF = 1e-4
TOL_HZ = 0.01  # the curves' integration error at the default step is ~7e-3 Hz (58 Hz PD)
H5 = os.path.join(ROOT, "figures", "stability_chart_paper.h5")
PNG = os.path.join(ROOT, "figures", "stability_chart_paper.png")


def grid_size(curve, tol=TOL_HZ, k_max=400):
    """Smallest number of log-spaced amplitudes over the curve's range from which linear
    interpolation in log A reproduces the curve within tol (Hz); None if the curve is not
    single-valued in A."""
    a, f = np.log(curve.values), curve.frequency
    if len(a) < 3 or not (np.all(np.diff(a) > 0) or np.all(np.diff(a) < 0)):
        return None
    order = np.argsort(a)
    a, f = a[order], f[order]
    for k in range(2, k_max):
        ak = np.linspace(a[0], a[-1], k)
        fk = np.interp(ak, a, f)
        if np.max(np.abs(np.interp(a, ak, fk) - f)) <= tol:
            return k
    return k_max


def figure(chart):
    import matplotlib
    matplotlib.use("Agg")
    from nlbeam.app.plots.stability_chart import plot_stability_chart

    plot_stability_chart(chart, path=PNG)
    print(f"saved {os.path.relpath(PNG, ROOT)}")


def main():
    m = nlbeam.BeamImpact()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        C.periodic_solution(m, A_REF, 40.0, error=False)  # warm the JIT cache
        t = time.process_time()
        frc = C.frequency_response(m, A_REF, F_RANGE, (1, 2, 3), accuracy="off")
        t_diag = time.process_time() - t
        t = time.process_time()
        chart = C.stability_chart(m, P_RANGE, F_RANGE, (1, 2, 3), diagram=frc,
                                  label_grid=(0, 0))
        t_curves = time.process_time() - t
        t = time.process_time()
        lab = C.stability_chart(m, P_RANGE, F_RANGE, (1, 2, 3), diagram=frc,
                                kinds=(), label_grid=(16, 6))
        t_labels = time.process_time() - t
    chart.label_frequency, chart.label_value, chart.label_order = (
        lab.label_frequency, lab.label_value, lab.label_order)
    n_pts = sum(len(c.frequency) for c in chart.curves)
    print(f"reference diagram A = {A_REF:g} m: {len(frc.bifurcations)} bifurcations, "
          f"{t_diag:.1f} s CPU")
    kinds = ", ".join(f"{k} {sum(c.kind == k for c in chart.curves)}"
                      for k in ("fold", "period-doubling", "neimark-sacker", "grazing"))
    print(f"curves: {len(chart.curves)} ({kinds}), {n_pts} points, {chart.n_evaluations} "
          f"shooting evaluations, {t_curves:.1f} s CPU")
    print(f"labels: {len(lab.label_order)} attractors, {t_labels:.1f} s CPU; orders found "
          f"{dict(zip(*np.unique(lab.label_order, return_counts=True)))}")
    print(f"chart total: {t_diag + t_curves + t_labels:.1f} s CPU; not traced or in part: "
          f"{len(chart.skipped)}")
    full = [c for c in chart.curves if c.ends == ("left the parameter range",) * 2]
    ks = [(grid_size(c), c) for c in full]
    ks = [(k, c) for k, c in ks if k is not None]
    if ks:
        k, c = max(ks, key=lambda kc: kc[0])
        print(f"grid of diagrams: {len(ks)} curves span the amplitude range single-valued; "
              f"to place them within {TOL_HZ} Hz by interpolation in log A needs up to {k} "
              f"diagrams ({c.kind} order {c.order} near {np.median(c.frequency):.2f} Hz); "
              f"median {int(np.median([k for k, _ in ks]))}; at {t_diag:.1f} s CPU each: "
              f"{k * t_diag:.0f} s CPU (median {np.median([k for k, _ in ks]) * t_diag:.0f} s)")
    chart.save(H5)
    print(f"saved {os.path.relpath(H5, ROOT)}")
    figure(chart)


if __name__ == "__main__":
    if "--plot" in sys.argv:
        figure(C.load_curves(H5))
    else:
        main()
