"""The outputs of a scene's [chart] section: the stability-chart figure (one per variant) and
the CSV table of its curves and codimension-2 points."""
from __future__ import annotations

import csv
import io
import math
import os

from ..files import write_text_atomic
from .numbers import with_error

__all__ = ["chart_variants", "chart_figure", "chart_table"]


def chart_variants(scene, jobs, results):
    """[(label, StabilityChart)] one per distinct chart job (a sweep of a parameter the chart
    does not depend on gives one, unlabelled)."""
    out, seen = [], set()
    for label, *_ in scene.variants():
        path = next((j.path for j in jobs if j.kind == "chart" and j.variant == label), None)
        if path is not None and path not in seen:
            seen.add(path)
            out.append((label, results[path]))
    if len(out) == 1:
        out = [("", out[0][1])]
    return out


def chart_figure(scene_title, d, variants, out_dir):
    """Write the stability chart(s) of one [[figure]] entry; ``name_1.png``, ... for several
    variants. Returns the files written."""
    from ..plots.files import files_backend, save_figure
    from ..plots.stability_chart import plot_stability_chart

    files_backend()
    import matplotlib.pyplot as plt

    target = os.path.join(out_dir, d["file"])
    stem, ext = os.path.splitext(target)
    written = []
    for i, (label, chart) in enumerate(variants):
        path = target if len(variants) == 1 else f"{stem}_{i + 1}{ext}"
        fig, ax = plt.subplots(figsize=(10, 6.5))
        plot_stability_chart(chart, ax)
        ax.set_title(d.get("title", scene_title) + (f" ({label})" if label else ""))
        fig.tight_layout()
        written.append(save_figure(fig, path))
    return written


def chart_table(d, variants, out_dir):
    """Write the CSV table of one [[table]] entry of kind 'curves': one row per curve point
    (kind, order, frequency_hz, amplitude_m or the parameter's value, the frequency's error
    where estimated, exact: placed at a requested value), then one per codimension-2 point
    (point = its kind; frequency and value with their bracket errors). Returns its path."""
    rows = []
    for label, chart in variants:
        for ci, c in enumerate(chart.curves):
            for i in range(len(c.frequency)):
                e = float(c.error[i]) if c.error is not None else math.nan
                rows.append({"variant": label, "curve": ci, "kind": c.kind, "order": c.order,
                             "point": "curve", "frequency_hz": with_error(
                                 float(c.frequency[i]), e) if math.isfinite(e) and e > 0
                             else float(c.frequency[i]),
                             "parameter": c.parameter, "value": float(c.values[i]),
                             "frequency_error_hz": f"{e:.2g}" if math.isfinite(e) else "",
                             "exact": bool(c.exact[i]), "n_impacts": int(c.n_impacts[i])})
            for s in c.special:
                rows.append({"variant": label, "curve": ci, "kind": c.kind, "order": c.order,
                             "point": s.kind, "frequency_hz": float(s.frequency),
                             "parameter": c.parameter, "value": float(s.value),
                             "frequency_error_hz": f"{s.error_frequency:.2g}",
                             "value_error": f"{s.error_value:.2g}", "note": s.note})
    buf = io.StringIO()
    cols = list(dict.fromkeys(k for r in rows for k in r)) or ["variant"]
    wr = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    wr.writeheader()
    for r in rows:
        wr.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    path = os.path.join(out_dir, d["file"])
    write_text_atomic(path, buf.getvalue())
    return path
