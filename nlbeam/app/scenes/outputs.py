"""The outputs of a scene: its figures (drawn by nlbeam.app.plots.scene) and its CSV tables
(moments, peaks, bifurcations), one per distinct set of the analyses each reads.

An output is drawn again only when something it shows may have changed: each is stamped
(``OUT/.nlbeam-cache/outputs.json``) with the SHA-256 of its [[figure]] / [[table]] entry,
the scene title, the variants it shows with the checksums of the analysis results it reads,
the source of the code and the matplotlib version, and with the checksum of each file
written; an output whose stamp and files are unchanged is kept as it is (a scene with a
measured record, and a stability chart, are always drawn).
"""
from __future__ import annotations

import csv
import io
import json
import math
import os

from .. import defaults
from ..compare import map_peaks, welch_dof_of
from ..files import code_fingerprint, content_key, file_sha256, write_text_atomic
from ..plots.scene import scene_figure
from .bifurcation_list import bifurcation_rows
from .chart_outputs import chart_figure, chart_table, chart_variants
from .numbers import error_digit, moment_cells, with_error
from .plan import CACHE_DIR
from .schema import CHART_OUTPUTS, build_model, default_f_max, excitation_for_peaks

__all__ = ["write_outputs", "write_table", "distinct"]


def _by_variant(scene, jobs, results):
    """[(label, model, periodic, stochastic, diagram, stochastic result, job paths)]; job
    paths: {'periodic': cache file or None, 'stochastic': ...}."""
    out = []
    for label, m, p, s in scene.variants():
        paths = {k: next((j.path for j in jobs if j.kind == k and j.variant == label), None)
                 for k in ("periodic", "stochastic")}
        per = results[paths["periodic"]] if paths["periodic"] and results else None
        sto = results[paths["stochastic"]] if paths["stochastic"] and results else None
        out.append((label, m, p, s, per, sto, paths))
    return out


# the header of a table with no rows (e.g. a diagram without bifurcations)
_EMPTY_COLUMNS = {
    "moments": ["variant", "channel", "mean", "std", "skewness", "kurtosis", "se_mean",
                "se_std", "se_skewness", "se_kurtosis", "se_dof"],
    "peaks": ["variant", "channel", "frequency_hz", "frequency_error_hz", "prominence_dec",
              "prominence_error_dec", "significance", "kind", "order",
              "branch_frequency_hz", "stable", "distance_hz", "tolerance_hz", "xmax_m", "note",
              "explained_by_hz"],
    "bifurcations": ["variant", "branch", "order", "kind", "frequency_hz", "frequency_error_hz",
                     "xmax_m", "note"]}

#: which analyses each output reads
_READS = {"frc": ("periodic",), "bifurcations": ("periodic",), "history": ("stochastic",),
          "psd": ("stochastic",), "pdf": ("stochastic",), "excitation_psd": ("stochastic",),
          "moments": ("stochastic",), "compare": ("periodic", "stochastic"),
          "peaks": ("periodic", "stochastic")}


def distinct(kind, variants):
    """The variants an output must show: one per distinct set of the analyses it reads (a
    sweep of a parameter the output does not depend on gives one). Labels are dropped when
    only one is left."""
    seen, out = set(), []
    for v in variants:
        key = tuple(v[6][a] for a in _READS[kind])
        if key not in seen:
            seen.add(key)
            out.append(v)
    if len(out) == 1:
        out = [("",) + tuple(out[0][1:])]
    return out


def planned_files(scene, jobs, out_dir):
    """[(kind, path)] of every figure and table file ``write_outputs`` will write (a
    per-variant figure of several variants: one file each, ``name_1.png``, ...)."""
    from ..plots.scene import PER_VARIANT, suffixed

    variants = _by_variant(scene, jobs, None)
    out = []
    for d in scene.figures:
        path = os.path.join(out_dir, d["file"])
        n = len(distinct(d["kind"], variants)) if d["kind"] in PER_VARIANT else 1
        out += [(f"figure {d['kind']}", suffixed(path, i, n)) for i in range(n)]
    out += [(f"table {d['kind']}", os.path.join(out_dir, d["file"])) for d in scene.tables]
    return out


def _result_sha(path):
    """The checksum of a cached result recorded beside it (its .json), or None."""
    try:
        with open(path[:-3] + ".json", encoding="utf-8") as fh:
            return json.loads(fh.read())["result_sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _stamp(scene, d, jobs):
    """The content key of everything output ``d`` shows (module doc); None when a result's
    checksum is unknown (then it is drawn)."""
    import matplotlib

    light = [(label, m, p, s, None, None, {
        k: next((j.path for j in jobs if j.kind == k and j.variant == label), None)
        for k in ("periodic", "stochastic")}) for label, m, p, s in scene.variants()]
    shown = []
    for label, m, p, s, _, _, paths in distinct(d["kind"], light):
        sums = {a: _result_sha(paths[a]) for a in _READS[d["kind"]] if paths[a]}
        if any(v is None for v in sums.values()):
            return None
        shown.append([label, m, p, s, sums])
    return content_key({"output": d, "title": scene.title, "shown": shown,
                        "code": code_fingerprint(), "matplotlib": matplotlib.__version__},
                       length=32)


def _record_path(out_dir):
    return os.path.join(out_dir, CACHE_DIR, "outputs.json")


def _read_record(out_dir):
    try:
        with open(_record_path(out_dir), encoding="utf-8") as fh:
            rec = json.loads(fh.read())
        return rec if isinstance(rec, dict) else {}
    except (OSError, ValueError):
        return {}


def _up_to_date(entry, stamp, out_dir):
    """The files of an output recorded with this stamp, all present and unchanged (else
    None)."""
    if stamp is None or not isinstance(entry, dict) or entry.get("stamp") != stamp:
        return None
    files = entry.get("files")
    if not isinstance(files, dict) or not files:
        return None
    paths = []
    for name, sha in files.items():
        path = os.path.join(out_dir, name)
        try:
            if file_sha256(path) != sha:
                return None
        except OSError:
            return None
        paths.append(path)
    return paths


def write_outputs(scene, jobs, results, out_dir, log, load=None):
    """Write the figures and tables of ``scene`` to ``out_dir`` from ``results`` (cache path
    -> result; a result missing there is read with ``load(job)``), except those whose files
    are up to date (module doc); log each file written. Returns all the scene's output files
    (written or kept)."""
    out_dir = os.fspath(out_dir)
    record = _read_record(out_dir)
    todo, files, kept = [], [], 0
    for kind, d in [("figure", d) for d in scene.figures] + [("table", d) for d in scene.tables]:
        stamp = (None if scene.measured is not None or d["kind"] in CHART_OUTPUTS
                 else _stamp(scene, d, jobs))
        have = _up_to_date(record.get(d["file"]), stamp, out_dir)
        if have is None:
            todo.append((kind, d, stamp))
        else:
            files += have
            kept += len(have)
    if todo:
        for j in jobs:
            if j.path not in results:
                results[j.path] = load(j)
        variants = _by_variant(scene, jobs, results)
        measured = None
        if scene.measured is not None:
            from .measured import measured_result

            measured = (scene.measured["label"], measured_result(
                scene.measured, dict(build_model(scene.model).parameters())))
        swept = None
        if scene.sweep is not None:
            values = dict(zip((v[0] for v in variants), scene.sweep["values"]))
            swept = (*scene.swept, values)
        for kind, d, stamp in todo:
            if d["kind"] in CHART_OUTPUTS:
                cv = chart_variants(scene, jobs, results)
                new = (chart_figure(scene.title, d, cv, out_dir) if kind == "figure"
                       else [chart_table(d, cv, out_dir)])
            elif kind == "figure":
                new = scene_figure(scene.title, d, distinct(d["kind"], variants), out_dir,
                                   measured=measured)
            else:
                new = [write_table(d, variants, out_dir, measured=measured, swept=swept)]
            for f in new:
                log(f"nlbeam: wrote {f}")
            files += new
            record[d["file"]] = {"stamp": stamp, "files": {
                os.path.relpath(f, out_dir): file_sha256(f) for f in new}}
        os.makedirs(os.path.dirname(_record_path(out_dir)), exist_ok=True)
        write_text_atomic(_record_path(out_dir), json.dumps(record, indent=1, sort_keys=True))
    if kept:
        log(f"nlbeam: {kept} file(s) up to date, kept")
    return files


def write_table(d, variants, out_dir, measured=None, swept=None):
    """Write the CSV table of one [[table]] entry ``d`` (moments, peaks or bifurcations) over
    the variants it distinguishes, and for moments and peaks the ``measured`` record (label,
    StochasticResult) if it has the channel (its peaks mapped to the first variant's diagram).
    ``swept``: (name, unit, {label: value}) of a sweep: each row of a variant gets a column
    named as the parameter with its value (SI units; a band as 'lo-hi' Hz). Returns its
    path."""
    kind = d["kind"]
    ch = d.get("channel", defaults.CHANNEL)
    rows = []
    todo = distinct(kind, variants)
    if measured is not None and kind in ("moments", "peaks") and ch in measured[1].channels:
        label0, m0, p0, s0, per0 = todo[0][:5]
        todo = todo + [(measured[0], m0, p0, s0, per0, measured[1], None)]
    for label, m, p, s, per, sto, _ in todo:
        if kind == "moments":
            mo = sto.moments(ch)
            row = {"variant": label, "channel": ch,
                   **{k: mo[k] for k in ("mean", "std", "skewness", "kurtosis",
                                         "se_mean", "se_std", "se_skewness",
                                         "se_kurtosis") if k in mo}}
            for key in ("mean", "std", "skewness", "kurtosis"):
                if key in row:
                    row[key], se = moment_cells(row[key], row.get(f"se_{key}"))
                    if se is not None:
                        row[f"se_{key}"] = se
            # how rough the errors themselves are (about +-1/sqrt(2 dof) relative)
            dof = mo.get("se_dof", math.nan)
            row["se_dof"] = f"{dof:.2g}" if math.isfinite(dof) else ""
            rows.append(row)
        elif kind == "peaks":
            f_max = d.get("f_max", default_f_max(p, s))
            for pk in map_peaks(sto.psd(ch), per, excitation_for_peaks(s),
                                f_range=(0.0, f_max), dof=welch_dof_of(sto, ch),
                                min_prominence=d.get("min_prominence",
                                                     defaults.MIN_PROMINENCE)):
                row = pk.as_row()
                if not d.get("stability", True):
                    row["stable"] = ""  # not asked for (and not computed when supported)
                rows.append({"variant": label, "channel": ch, **row})
        else:
            rows += bifurcation_rows(per, label)
    if swept is not None:
        name, _, values = swept
        for r in rows:
            if r.get("variant") in values:
                v = values[r["variant"]]
                r[name] = "-".join(f"{x:.10g}" for x in v) if isinstance(v, list) else v
        rows = [{"variant": r["variant"], **({name: r[name]} if name in r else {}), **r}
                if "variant" in r else r for r in rows]
    buf = io.StringIO()
    cols = list(dict.fromkeys(k for r in rows for k in r)) or _EMPTY_COLUMNS[kind]
    wr = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    wr.writeheader()
    for r in (map(_peak_row, rows) if kind == "peaks" else rows):
        wr.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    path = os.path.join(out_dir, d["file"])
    write_text_atomic(path, buf.getvalue())
    return path


def _peak_row(row):
    """A peaks-table row with every number to the digits it supports: the peak's frequency
    and prominence to the decade of their (one-digit) errors from the PSD estimate, its
    significance (standard errors) as a whole number, the distance to the diagram point, the
    match's tolerance and the parent peak of a multiple (which move with the peak) to the
    peak frequency's digit; the
    branch frequency to a hundredth of the tolerance (the branch point matched moves with
    the tracer's steps), xmax to 1e-3 of itself (the matched point's)."""
    out = dict(row)
    for key, err in (("frequency_hz", "frequency_error_hz"),
                     ("prominence_dec", "prominence_error_dec")):
        e = row.get(err, math.nan)
        if isinstance(e, float) and math.isfinite(e) and e > 0:
            out[err] = error_digit(e)
            out[key] = with_error(row[key], float(out[err]))
        elif key == "prominence_dec":
            out[key] = with_error(row[key], 0.01)
    z = row.get("significance", math.nan)
    if isinstance(z, float) and math.isfinite(z):
        out["significance"] = f"{z:.0f}"  # standard errors: uncertain by about one
    tol = row.get("tolerance_hz", math.nan)
    if isinstance(tol, float) and math.isfinite(tol) and tol > 0:
        for key in ("branch_frequency_hz", "distance_hz", "tolerance_hz"):
            out[key] = with_error(row[key], tol / 100)
    e = row.get("frequency_error_hz", math.nan)
    if isinstance(e, float) and math.isfinite(e) and e > 0:  # they move with the peak
        for key in ("distance_hz", "tolerance_hz", "explained_by_hz"):
            v = row.get(key, math.nan)
            if isinstance(v, float) and math.isfinite(v):
                out[key] = with_error(v, float(error_digit(e)))
    x = row["xmax_m"]
    if isinstance(x, float) and math.isfinite(x) and x != 0:
        out["xmax_m"] = with_error(x, 1e-3 * abs(x))
    return out
