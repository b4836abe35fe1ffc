"""Figures of the multi-mode beam (ModalBeam.paper, docs/modal_beam.md).

    python figures/modal_beam.py [--modes 1 2 4] [--duration 60]

- figures/modal_beam_frc.png: |x|max against frequency (A = 0.1 mm, orders 1 and 2, 5-150 Hz)
  for N = 1, 2, 4 side by side;
- the 0-200 Hz response PSD of delta (N = 4) with its peaks mapped onto the N = 4 diagram by
  nlbeam.compare.map_peaks: the scene figures/modal_beam.toml (run here through nlbeam.scenes,
  so `nlbeam run figures/modal_beam.toml --out figures` gives the same files);
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
    rows = []
    for n, frc in frcs.items():
        for b in sorted(frc.bifurcations, key=lambda b: b.frequency):
            if b.kind in ("fold", "period-doubling"):
                rows.append({"n_modes": n, "kind": b.kind, "order": b.order,
                             "frequency_hz": f"{b.frequency:.4f}", "xmax_mm": f"{b.xmax * 1e3:.4f}"})
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--skip-scene", action="store_true", help="diagrams only")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from continuation.plot import plot_frequency_response

    frcs = {n: diagram(n) for n in args.modes}
    fig, axs = plt.subplots(1, len(frcs), figsize=(5 * len(frcs), 4.5), sharey=True, squeeze=False)
    for ax, (n, frc) in zip(axs[0], frcs.items()):
        plot_frequency_response(frc, ax, grazing=False)
        ax.set_title(f"ModalBeam.paper(n_modes={n})" + ("  = BeamImpact.paper()" if n == 1 else ""))
        if ax is not axs[0, 0]:
            ax.set_ylabel("")
    fig.suptitle(f"|x|max at the stop, A = {AMPLITUDE * 1e3:g} mm, orders {ORDERS}")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "modal_beam_frc.png"), dpi=110)
    rows = bifurcation_rows(frcs)
    with open(os.path.join(HERE, "table_modal_bifurcations.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["n_modes", "kind", "order", "frequency_hz", "xmax_mm"])
        w.writeheader()
        w.writerows(rows)
    print(f"wrote figures/modal_beam_frc.png, figures/table_modal_bifurcations.csv ({len(rows)} rows)")
    if not args.skip_scene:
        from nlbeam.scenes import run_scene

        run_scene(os.path.join(HERE, "modal_beam.toml"), HERE)
    return 0


if __name__ == "__main__":
    sys.exit(main())
