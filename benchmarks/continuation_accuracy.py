"""Benchmark (not a test): the paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) at accuracy
'off', default (6 significant digits) and 'high' (8): CPU time, and the fold / period-doubling
frequencies against continuation.refine_bifurcations (extended system at dt/4..dt/32,
Richardson; ~90 s CPU, computed first on the diagram without estimates).

    python benchmarks/continuation_accuracy.py [off default high 7 ...]

Folds / PDs reported at a grazing point (Bifurcation.smooth False: a multiplier jumps there)
are counted apart: refine_bifurcations does not refine them.
"""
import sys
import time
import warnings

import numpy as np

import nlbeam

import continuation as C

A = 1e-4


def reference(model):
    """(kind, order, value, tolerance) of refine_bifurcations on the diagram without
    estimates."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frc = C.frequency_response(model, A, (5.0, 150.0), orders=(1, 2, 3), accuracy="off")
        C.refine_bifurcations(frc, model)
    return [(b.kind, b.order, b.refined.value, b.refined.tolerance)
            for b in frc.bifurcations if getattr(b, "refined", None) is not None]


def main(levels):
    model = nlbeam.BeamImpact.paper()
    C.periodic_solution(model, A, 44.0)  # JIT warm-up
    t = time.process_time()
    ref = reference(model)
    print(f"reference: {len(ref)} folds / PDs refined ({time.process_time() - t:.0f} s CPU)")
    for acc in levels:
        a = acc if acc in ("off", "default", "high") else float(acc)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t = time.process_time()
            frc = C.frequency_response(model, A, (5.0, 150.0), orders=(1, 2, 3), accuracy=a)
            cpu = time.process_time() - t
        true_d, stated_d, under, nan, at_grazing = [], [], 0, 0, 0
        for bf in frc.bifurcations:
            if bf.kind not in ("fold", "period-doubling"):
                continue
            if not bf.smooth:  # reported at a grazing point: refine skips those
                at_grazing += 1
                continue
            if np.isfinite(bf.error):
                stated_d.append(-np.log10(bf.error / bf.frequency))
            elif acc != "off":
                nan += 1
                continue
            cands = [r for r in ref if r[0] == bf.kind and r[1] == bf.order]
            if not cands:
                continue
            _, _, v, tol = min(cands, key=lambda r: abs(r[2] - bf.frequency))
            e = abs(v - bf.frequency)
            if e > 1e-3 * bf.frequency:
                continue  # not the same point
            true_d.append(-np.log10(max(e, tol) / bf.frequency))
            under += bool(np.isfinite(bf.error) and e > bf.error + tol)
        st = np.array(stated_d)
        print(f"accuracy={acc}: {cpu:.1f} s CPU, {frc.n_points} points; folds/PDs matched "
              f"{len(true_d)}: true digits {min(true_d):.1f}-{max(true_d):.1f} median "
              f"{np.median(true_d):.1f}; stated digits "
              + (f"{st.min():.1f}-{st.max():.1f} median {np.median(st):.1f} (>= 6: "
                 f"{int(np.sum(st >= 6))}, >= 8: {int(np.sum(st >= 8))})" if st.size else "-")
              + f"; not confirmed (error NaN) {nan}; true error > stated {under}; "
              f"{at_grazing} more at grazing points (not compared)")
        for w in caught:
            if "accuracy below" in str(w.message):
                print("   warning:", str(w.message)[:300], "...")


if __name__ == "__main__":
    main(sys.argv[1:] or ["off", "default", "high"])
