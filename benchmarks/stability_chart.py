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
    python benchmarks/stability_chart.py --curves   (the curves only, nothing saved: where
                                                     their shooting evaluations and CPU go,
                                                     by trace end and by use; the codim-2
                                                     points; with --traces also one line per
                                                     trace direction)
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


def diagram_and_curves(m):
    """The reference diagram at A_REF (no error estimates) and the chart's curves from it
    (no labels), ContinuationWarnings silenced: (diagram, chart, CPU s of each)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        C.periodic_solution(m, A_REF, 40.0, error=False)  # warm the JIT cache
        t = time.process_time()
        frc = C.frequency_response(m, A_REF, F_RANGE, (1, 2, 3), accuracy="off")
        t_diag = time.process_time() - t
        t = time.process_time()
        chart = C.stability_chart(m, P_RANGE, F_RANGE, (1, 2, 3), diagram=frc,
                                  label_grid=(0, 0))
        return frc, chart, t_diag, time.process_time() - t


def main():
    m = nlbeam.BeamImpact()
    frc, chart, t_diag, t_curves = diagram_and_curves(m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
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


def curves_only():
    """The curves of the chart (diagram given, no labels), with the shooting evaluations of
    each trace direction tallied by use: the start, corrector calls of accepted steps and of
    failed ones (a ConvergenceError: the step is halved), codimension-2 location (_locate),
    the rest (Jacobians after a fallback, rephasing, border renewals, error estimates)."""
    import collections

    from continuation import curve as CU

    uses = collections.Counter()
    traces = []  # (end, evaluations, impacts-per-period values on the points, kind, order,
    #               CPU s, start (Hz, m), last point (Hz, m), points)
    corr, trace, locate = CU._Tracer.correct, CU._Tracer.trace, CU._locate
    where = []  # the innermost tallied caller

    def t_correct(self, *a, **k):
        n0 = self.s.n_evaluations
        ok = False
        try:
            out = corr(self, *a, **k)
            ok = True
            return out
        finally:
            use = where[-1] if where else "other"
            if use == "trace":
                use = "step accepted" if ok else "step failed"
            uses[use] += self.s.n_evaluations - n0

    def t_trace(self, p0, on_step):
        n0, c0 = self.s.n_evaluations, time.process_time()
        where.append("trace")
        try:
            pts, why = trace(self, p0, on_step)
        finally:
            where.pop()
        last = ([p0] + pts)[-1]
        traces.append((why, self.s.n_evaluations - n0,
                       sorted({int(p.st.n_impacts) for p in [p0] + pts}), self.s.kind,
                       self.s.order, time.process_time() - c0, (p0.frequency, p0.value),
                       (last.frequency, last.value), len(pts)))
        return pts, why

    def t_locate(tr, *a, **k):
        where.append("codim-2 location")
        try:
            return locate(tr, *a, **k)
        finally:
            where.pop()

    CU._Tracer.correct, CU._Tracer.trace, CU._locate = t_correct, t_trace, t_locate
    m = nlbeam.BeamImpact()
    frc, chart, t_diag, t_curves = diagram_and_curves(m)
    n_ev = chart.n_evaluations
    print(f"reference diagram: {len(frc.bifurcations)} bifurcations, {t_diag:.1f} s CPU")
    print(f"curves: {len(chart.curves)}, {sum(len(c.frequency) for c in chart.curves)} points, "
          f"{n_ev} shooting evaluations, {t_curves:.1f} s CPU; not traced or in part: "
          f"{len(chart.skipped)}")
    ends = collections.defaultdict(lambda: [0, 0, 0.0])
    for why, ev, _, _, _, cpu, *_ in traces:
        ends[why.split(":")[0]][0] += 1  # 'corrector-limited: where' by its kind
        ends[why.split(":")[0]][1] += ev
        ends[why.split(":")[0]][2] += cpu
    print("trace directions by end (directions, evaluations, CPU s):")
    for why, (k, ev, cpu) in sorted(ends.items(), key=lambda kv: -kv[1][1]):
        print(f"  {why:28s} {k:4d} {ev:7d} ({100 * ev / max(n_ev, 1):.0f} %) {cpu:6.1f} s")
    budget = [t for t in traces if t[0] == "max_evaluations"]
    for label, sel in (("one impacts-per-period value", [t for t in budget if len(t[2]) == 1]),
                       ("several values", [t for t in budget if len(t[2]) > 1])):
        kinds = collections.Counter(t[3] for t in sel)
        print(f"  at the budget, {label}: {len(sel)} directions, "
              f"{sum(t[1] for t in sel)} evaluations ({dict(kinds)})")
    uses["outside corrector calls"] = n_ev - sum(uses.values())
    print("evaluations by use: " + ", ".join(
        f"{k} {v} ({100 * v / max(n_ev, 1):.0f} %)" for k, v in uses.most_common()))
    sp = sorted(((s.kind, s.frequency, s.value, c.kind, c.order) for c in chart.curves
                 for s in c.special), key=lambda s: (s[1], s[2]))
    print(f"codimension-2 points: {len(sp)} "
          f"{dict(collections.Counter(s[0] for s in sp))}")
    for kind, f, v, ck, co in sp:
        print(f"  {kind:14s} {f:10.5f} Hz {v * 1e3:8.5f} mm   on the {ck} curve, order {co}")
    if "--traces" in sys.argv:
        print("trace directions (kind, order, start, last point, end, evaluations, CPU, "
              "points, impacts per period):")
        for why, ev, imp, kind, order, cpu, (f0, v0), (f1, v1), n in traces:
            print(f"  {kind:15s} {order} {f0:9.4f} Hz {v0 * 1e3:7.4f} mm -> {f1:9.4f} Hz "
                  f"{v1 * 1e3:8.5f} mm  {why.split(':')[0]:24s} {ev:5d} ev {cpu:5.2f} s "
                  f"{n:4d} pts {imp}")


if __name__ == "__main__":
    if "--curves" in sys.argv:
        curves_only()
    elif "--plot" in sys.argv:
        figure(C.load_curves(H5))
    else:
        main()
