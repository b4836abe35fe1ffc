"""Planning a scene: which analyses its figures and tables need (``plan``: one Job per
analysis and sweep value, each keyed by exactly its inputs and marked cached or not) and the
plan as text (``format_plan``).

What each output needs: ``frc`` and table ``bifurcations`` the diagram; ``stability_chart``
and table ``curves`` the stability chart of the [chart] section; ``psd`` the PSD of
its channel; ``excitation_psd`` the PSD of ``y``; ``pdf`` the histogram and moments of its
channel; ``history`` a stored time window of its channels; ``compare`` and table ``peaks``
the diagram and the PSD. A scene without them runs neither analysis; a stochastic run keeps
only the channels, estimators and history the outputs read.

Cache: ``OUT/.nlbeam-cache/<analysis>-<key>.h5`` where key = SHA-256 of the canonical JSON
of the analysis' inputs (model, its section with defaults filled in, the channels / outputs
/ history it must produce) and the code fingerprint (SHA-256 of the source the analysis
depends on, ``files.keys.analysis_fingerprint``: results of other code are never reused;
an edit of the drawing code or of the other analysis' package keeps them). A sidecar ``.json``
records the inputs and the SHA-256 of the result file; ``check_entry`` verifies both and
the file's own checksums, so an entry that is corrupted, truncated, empty or another
result swapped in is marked for recomputation (``Job.problem`` says why).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

from .. import defaults
from ..files import canonical_json, content_key, file_sha256
from ..files.keys import analysis_fingerprint
from .models import model_inputs
from .schema import CHART_OUTPUTS, history_channels, history_window

__all__ = ["CACHE_DIR", "Job", "plan", "format_plan", "check_entry", "entry_record"]

CACHE_DIR = ".nlbeam-cache"


@dataclass
class Job:
    """One analysis of one variant: kind 'periodic' or 'stochastic'; inputs: the exact
    inputs (hashed into key); path: the cache file; cached: a verified entry exists;
    problem: why an existing entry will be recomputed ("" if none)."""

    kind: str
    variant: str
    inputs: dict
    key: str
    path: str
    cached: bool = False
    description: str = ""
    problem: str = ""


def _model_inputs(spec):
    """The model as keyed (models.model_inputs): the paper beam with the constructor's
    defaults filled in, a factory with the digest of the system it returns."""
    return model_inputs(spec, defaults.MODEL)


def needs(scene):
    """What the outputs read: (periodic?, stability?, channels -> set of outputs, history
    window, history channels)."""
    need_p = need_stab = False
    chans = {}
    hist = None
    hist_ch = []

    def want(ch, *what):
        chans.setdefault(ch, set()).update(what)

    for d in scene.figures + scene.tables:
        k = d["kind"]
        ch = d.get("channel", defaults.CHANNEL)
        if k in ("frc", "bifurcations", "compare", "peaks"):
            need_stab = need_stab or d.get("stability", True)
        if k in ("frc", "bifurcations"):
            need_p = True
        elif k == "psd":
            want(ch, "psd")
        elif k == "excitation_psd":
            want("y", "psd")
        elif k == "pdf":
            want(ch, "pdf", "moments")
        elif k == "moments":
            want(ch, "moments")
        elif k in ("compare", "peaks"):
            need_p = True
            want(ch, "psd")
        elif k == "history":
            w = history_window(d, scene.stochastic["duration"])
            hist = list(w) if hist is None else [min(hist[0], w[0]), max(hist[1], w[1])]
            for c in history_channels(d):
                if c not in hist_ch:
                    hist_ch.append(c)
    return need_p, need_stab, chans, hist, hist_ch


def plan(scene, out_dir):
    """The jobs the scene's outputs need, each marked cached or not. Returns a list of Job."""
    need_p, need_stab, chans, hist, hist_ch = needs(scene)
    need_chart = any(d["kind"] in CHART_OUTPUTS for d in scene.figures + scene.tables)
    stability = bool(need_stab)  # what is computed is what is keyed
    cache = os.path.join(os.fspath(out_dir), CACHE_DIR)
    jobs = []
    for label, m, p, s in scene.variants():
        m = _model_inputs(m)
        if need_p:
            p = dict(p, stability=stability)
            inputs = {"analysis": "periodic", "model": m, "periodic": p,
                      "code": analysis_fingerprint("periodic")}
            jobs.append(_job("periodic", label, inputs, cache,
                             f"frequency response {p['f_range'][0]:g}-{p['f_range'][1]:g} Hz, "
                             f"A = {p['amplitude']:g} m, orders {p['orders']}"
                             f"{'' if stability else ', no stability'}"))
        if need_chart:
            c = scene.chart
            inputs = {"analysis": "chart", "model": m, "chart": c,
                      "code": analysis_fingerprint("chart")}
            jobs.append(_job("chart", label, inputs, cache,
                             f"stability chart {c['f_range'][0]:g}-{c['f_range'][1]:g} Hz, "
                             f"A = {c['p_range'][0]:g}-{c['p_range'][1]:g} m, orders "
                             f"{c['orders']}"))
        if chans or hist is not None:
            channels = sorted(set(chans) | set(hist_ch))
            outputs = sorted(set().union(*chans.values())) if chans else []
            inputs = {"analysis": "stochastic", "model": m, "stochastic": s,
                      "channels": channels, "outputs": outputs, "history": hist,
                      "code": analysis_fingerprint("stochastic")}
            under = (f"the record {os.path.basename(s['record'])} ({s['record_column']})"
                     if "record" in s else f"band {s['band'][0]:g}-{s['band'][1]:g} Hz")
            jobs.append(_job("stochastic", label, inputs, cache,
                             f"{s['duration']:g} s under {under}"
                             f"{', low-pass %g Hz' % s['lowpass'] if s.get('lowpass') else ''}, "
                             f"seed {s['seed']}, channels {channels}, outputs {outputs}"
                             f"{', history %s s' % hist if hist else ''}"))
    return jobs


def entry_record(inputs, path, warned=()):
    """The sidecar text of a cache entry: its inputs, the SHA-256 of its result file and the
    warnings its computation gave (repeated when the entry is reused)."""
    return canonical_json({"inputs": inputs, "result_sha256": file_sha256(path),
                           "warnings": [str(w) for w in warned]}) + "\n"


def check_entry(path, inputs, kind):
    """Why the cache entry at ``path`` cannot be reused for ``inputs`` ("" when it can):
    no sidecar, other inputs recorded, file bytes not those recorded, or the result file
    itself refused (format, checksums)."""
    from ..files.stamped_hdf5 import ResultFileError, read_result

    side = path[:-3] + ".json"
    try:
        with open(side, encoding="utf-8") as fh:
            rec = json.loads(fh.read())
        recorded, sha = rec["inputs"], rec["result_sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return f"no valid record of its inputs ({os.path.basename(side)})"
    if canonical_json(recorded) != canonical_json(inputs):
        return "it records other inputs (a different result under this key)"
    try:
        if file_sha256(path) != sha:
            return "its bytes differ from the recorded checksum (changed or swapped)"
        name = {"periodic": "nlbeam.frequency_response", "chart": "nlbeam.bifurcation_curves"
                }.get(kind, "nlbeam.stochastic.result")
        with read_result(path, name):
            pass
    except (OSError, ResultFileError) as err:
        return str(err).replace(path + ": ", "")
    return ""


def _job(kind, label, inputs, cache, desc):
    key = content_key(inputs)
    path = os.path.join(cache, f"{kind}-{key}.h5")
    problem = check_entry(path, inputs, kind) if os.path.exists(path) else ""
    return Job(kind, label, inputs, key, path, os.path.exists(path) and not problem, desc,
               problem)


def format_plan(scene, jobs, out_dir):
    """Human-readable plan: what will be computed, what is reused, what is written."""
    lines = [f"scene {scene.path}: {scene.title}"]
    first = {}
    for j in jobs:
        var = f" [{j.variant}]" if j.variant else ""
        if j.path in first:  # a sweep value this analysis does not depend on
            lines.append(f"  shared  {j.kind}{var}: the same as{first[j.path]}")
            continue
        first[j.path] = var or " above"
        state = "cached " if j.cached else "compute"
        lines.append(f"  {state} {j.kind}{var}: {j.description}")
        if j.problem:
            lines.append(f"          (cached entry refused, recomputed: {j.problem})")
        lines.append(f"          -> {j.path}")
    if not jobs:
        lines.append("  (no analysis needed)")
    from .outputs import planned_files  # (the names a run writes, suffixes included)

    for what, path in planned_files(scene, jobs, out_dir):
        lines.append(f"  write   {what}: {path}")
    return "\n".join(lines)
