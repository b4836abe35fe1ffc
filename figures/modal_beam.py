"""Figures of the multi-mode beam (ModalBeam.paper, docs/modal_beam.md).

    python figures/modal_beam.py [--modes 1 2 4] [--duration 60]

- figures/modal_beam_frc.png: |x|max against frequency (A = 0.1 mm, orders 1 and 2, 5-150 Hz)
  for N = 1, 2, 4 side by side;
- the 0-200 Hz response PSD of delta (N = 4) with its peaks mapped onto the N = 4 diagram by
  nlbeam.compare.map_peaks: the scene figures/modal_beam.toml (run here through nlbeam.scenes,
  so `nlbeam run figures/modal_beam.toml --out figures` gives the same files);
- figures/modal_beam_psd_map.png: the same PSD mapped with a 40 Hz background window, which
  finds the peak near 120 Hz (printed);
- figures/table_modal_bifurcations.csv: fold / period-doubling frequencies per N.
Diagrams are cached as figures/modal_frc_N<n>.h5 (delete to recompute). Units: m, s, Hz.
"""
import argparse
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
AMPLITUDE, F_RANGE, ORDERS, N_GRID = 1e-4, (5.0, 150.0), (1, 2), 20


def diagram(n, log=print):
    import continuation
    import nlbeam

    path = os.path.join(HERE, f"modal_frc_N{n}.h5")
    if os.path.exists(path):
        return continuation.load(path)
    t = time.perf_counter()
    frc = continuation.frequency_response(nlbeam.ModalBeam.paper(n_modes=n), AMPLITUDE, F_RANGE,
                                          orders=ORDERS, n_grid=N_GRID)
    frc.save(path)
    log(f"N = {n}: diagram in {time.perf_counter() - t:.0f} s, {len(frc.branches)} branches")
    return frc


def bifurcation_rows(frcs):
    """Fold and period-doubling rows, each number to the digits its error supports."""
    from nlbeam.app.scenes.numbers import bifurcation_error, error_bound, with_error, xmax_error

    rows = []
    for n, frc in frcs.items():
        for b in sorted(frc.bifurcations, key=lambda b: b.frequency):
            if b.kind in ("fold", "period-doubling"):
                e_f = max(bifurcation_error(b, frc), 1e-4)  # printed to 4 decimals at most
                e = error_bound(e_f)  # stated, and the frequency to its digit
                rows.append({"n_modes": n, "kind": b.kind, "order": b.order,
                             "frequency_hz": with_error(b.frequency, float(e)),
                             "frequency_error_hz": e,
                             "xmax_mm": with_error(b.xmax * 1e3, 1e3 * max(
                                 xmax_error(b, frc, e_f), 1e-7))})
    return rows


def psd_map(scene, plt):
    """figures/modal_beam_psd_map.png: the scene's PSD of delta (N = 4) against its diagram, peaks
    mapped with a 40 Hz background window (the scene's figure uses the default 20 Hz, which
    takes the broad hump near 120 Hz for background)."""
    import continuation
    import stochastic

    from nlbeam.app.compare import map_peaks, welch_dof_of
    from nlbeam.app.plots.compare import plot_comparison
    from nlbeam.app.scenes import plan
    from nlbeam.app.scenes.schema import build_noise

    jobs = {j.kind: j for j in plan(scene, HERE)}
    frc = continuation.load(jobs["periodic"].path)
    res = stochastic.load(jobs["stochastic"].path)
    psd = res.psd("delta")
    noise = build_noise(scene.stochastic)
    kw = dict(background_hz=40.0, f_range=(5.0, 200.0), dof=welch_dof_of(res, "delta"))
    matches = map_peaks(psd, frc, noise, **kw)
    fig = plot_comparison(psd, frc, matches, excitation=noise, f_max=200.0, **kw)
    fig.axes[0].set_title("ModalBeam (N = 4), 0-200 Hz: PSD peaks of delta mapped onto the diagram")
    fig.savefig(os.path.join(HERE, "modal_beam_psd_map.png"), dpi=110)
    for m in matches:
        print(f"peak {m.frequency:7.2f} Hz  {m.prominence:4.2f} dec  {m.kind:13s} order {m.order}  "
              f"branch point {m.branch_frequency:7.2f} Hz  stable {m.stable}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--skip-scene", action="store_true", help="diagrams only")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nlbeam.app.plots.frequency_response import plot_frequency_response

    frcs = {n: diagram(n) for n in args.modes}
    fig, axs = plt.subplots(1, len(frcs), figsize=(5 * len(frcs), 4.5), sharey=True, squeeze=False)
    for ax, (n, frc) in zip(axs[0], frcs.items()):
        plot_frequency_response(frc, ax, grazing=False, legend=ax is axs[0, -1])
        ax.set_title(f"ModalBeam.paper(n_modes={n})" + ("  = BeamImpact.paper()" if n == 1 else ""))
        if ax is not axs[0, 0]:
            ax.set_ylabel("")
    fig.suptitle(f"|x|max at the stop, A = {AMPLITUDE * 1e3:g} mm, orders {ORDERS}")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "modal_beam_frc.png"), dpi=110)
    rows = bifurcation_rows(frcs)
    with open(os.path.join(HERE, "table_modal_bifurcations.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["n_modes", "kind", "order", "frequency_hz",
                                               "frequency_error_hz", "xmax_mm"])
        w.writeheader()
        w.writerows(rows)
    print(f"wrote figures/modal_beam_frc.png, figures/table_modal_bifurcations.csv ({len(rows)} "
          "rows)")
    if not args.skip_scene:
        from nlbeam.app.scenes import load_scene, plan, run_scene
        from nlbeam.app.scenes.run import store_result

        scene = load_scene(os.path.join(HERE, "modal_beam.toml"))
        for job in plan(scene, HERE):  # the scene's diagram is the N = 4 one above: reuse it
            p = job.inputs.get("periodic") or {}
            same = (job.inputs["model"].get("n_modes") == 4 and p.get("amplitude") == AMPLITUDE
                    and tuple(p.get("f_range", ())) == F_RANGE
                    and tuple(p.get("orders", ())) == ORDERS
                    and p.get("n_grid") == N_GRID and p.get("segments") == 1
                    and p.get("dt_scale") == 1.0 and p.get("stability", True))
            if job.kind == "periodic" and not job.cached and same and 4 in frcs:
                store_result(job, frcs[4])
        rep = run_scene(scene, HERE)
        print(f"scene: {rep.computed} analyses computed, wrote {', '.join(rep.files)}")
        psd_map(scene, plt)
    return 0


if __name__ == "__main__":
    sys.exit(main())
