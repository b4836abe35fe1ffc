"""Scenes: a TOML file that names a model, the periodic and stochastic analyses, and the
figures and tables wanted; ``run_scene`` computes only what those outputs need, caches each
analysis in HDF5 under a key made of exactly its inputs, and reuses it.

Scene file (every section and key optional; units SI, Hz)::

    title = "Fig. 9"
    [model]        # the paper's BeamImpact; m, k, b, K_hertz, e, contact, mu, clamp
    e = 0.5
    [periodic]     # continuation.frequency_response
    amplitude = 1e-4          # m
    f_range = [5.0, 150.0]    # Hz
    orders = [1, 2, 3]
    n_grid = 30
    [stochastic]   # stochastic.simulate under stochastic.BandLimitedNoise
    band = [0.0, 200.0]       # Hz
    rms = 1e-4                # m (or psd_level, m^2/Hz)
    lowpass = 30.0            # Hz, first-order low-pass corner (actuator shape), optional
    seed = 1
    duration = 60.0           # s kept, after `transient` s
    transient = 2.0
    psd_resolution = 0.25     # Hz
    [[figure]]     # kind: frc | excitation_psd | pdf | history | psd | compare
    kind = "psd"
    file = "fig9.png"
    channel = "delta"         # x | v | y | yd | delta | force
    [[table]]      # kind: moments | peaks | bifurcations (CSV)
    kind = "moments"
    file = "moments.csv"
    [sweep]        # one run per value; see nlbeam.sweeps.PARAMETERS
    parameter = "rms"
    values = [5e-5, 1e-4]

What each output needs: ``frc`` and table ``bifurcations`` the diagram; ``psd`` the PSD of
its channel; ``excitation_psd`` the PSD of ``y``; ``pdf`` the histogram and moments of its
channel; ``history`` a stored time window of its channels; ``compare`` and table ``peaks``
the diagram and the PSD. A scene without them runs neither analysis; a stochastic run keeps
only the channels, estimators and history the outputs read.

Cache: ``OUT/.nlbeam-cache/<analysis>-<key>.h5`` where key = SHA-256 of the canonical JSON
of the analysis' inputs (model, its section with defaults filled in, the channels / outputs
/ history it must produce) and the package version. A sidecar ``.json`` holds that text.
"""
from __future__ import annotations

import copy
import csv
import io
import math
import os
import re
import sys
import time
import tomllib
from dataclasses import dataclass, field

import numpy as np

from . import __version__
from .io import atomic_path, canonical_json, content_key, write_text_atomic
from .sweeps import PARAMETERS, run_jobs

__all__ = ["SceneError", "Scene", "Job", "load_scene", "plan", "run_scene", "format_plan",
           "CACHE_DIR"]

CACHE_DIR = ".nlbeam-cache"
CHANNELS = ("x", "v", "y", "yd", "delta", "force")
FIGURE_KINDS = ("frc", "excitation_psd", "pdf", "history", "psd", "compare")
TABLE_KINDS = ("moments", "peaks", "bifurcations")
CONTACTS = ("hertz", "lankarani-nikravesh", "hunt-crossley")
METHODS = ("rk2", "rk4", "adaptive")


class SceneError(ValueError):
    """A scene file that cannot run: the message names the file, line and key."""


# -- schema --------------------------------------------------------------------------------
def _real(lo=None, hi=None, lo_open=False, unit=""):
    def check(v):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            return None, "must be a number" + (f" ({unit})" if unit else "")
        v = float(v)
        if not math.isfinite(v):
            return None, "must be finite"
        if lo is not None and (v <= lo if lo_open else v < lo):
            return None, f"must be {'>' if lo_open else '>='} {lo:g}" + (f" {unit}" if unit else "")
        if hi is not None and v > hi:
            return None, f"must be <= {hi:g}" + (f" {unit}" if unit else "")
        return v, None
    return check


def _int(lo=None, hi=None):
    def check(v):
        if isinstance(v, bool) or not isinstance(v, int):
            return None, "must be an integer"
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            return None, f"must lie in [{lo}, {hi}]" if hi is not None else f"must be >= {lo}"
        return int(v), None
    return check


def _choice(options):
    def check(v):
        if v not in options:
            return None, f"must be one of {', '.join(map(repr, options))}"
        return v, None
    return check


def _bool(v):
    return (v, None) if isinstance(v, bool) else (None, "must be true or false")


def _str(v):
    return (v, None) if isinstance(v, str) else (None, "must be a string")


def _pair(lo=0.0, strict_lo=False, unit="Hz"):
    def check(v):
        if not isinstance(v, list) or len(v) != 2 or any(
                isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
            return None, f"must be a pair [lo, hi] of numbers ({unit})"
        a, b = float(v[0]), float(v[1])
        if not (math.isfinite(a) and math.isfinite(b)) or not (a > lo if strict_lo else a >= lo) \
                or not b > a:
            return None, f"must satisfy {lo:g} {'<' if strict_lo else '<='} lo < hi ({unit})"
        return [a, b], None
    return check


def _int_list(lo, hi):
    def check(v):
        if not isinstance(v, list) or not v or any(
                isinstance(x, bool) or not isinstance(x, int) or not lo <= x <= hi for x in v):
            return None, f"must be a non-empty list of integers in [{lo}, {hi}]"
        return sorted(set(v)), None
    return check


def _channels(v):
    if not isinstance(v, list) or not v or any(c not in CHANNELS for c in v):
        return None, f"must be a non-empty list of channels from {', '.join(CHANNELS)}"
    return list(dict.fromkeys(v)), None


def _file(exts):
    def check(v):
        if not isinstance(v, str) or not v or os.path.isabs(v) or ".." in v.split("/"):
            return None, "must be a relative file name"
        if not v.lower().endswith(exts):
            return None, f"must end with {' or '.join(exts)}"
        return v, None
    return check


MODEL_KEYS = {"name": _choice(("BeamImpact", "ModalBeam")), "m": _real(0, lo_open=True, unit="kg"),
              "k": _real(0, unit="N/m"), "b": _real(0, unit="kg/s"),
              "K_hertz": _real(0, unit="N/m^1.5"), "e": _real(0, 1, lo_open=True),
              "contact": _choice(CONTACTS), "mu": _real(0, unit="N s/m^2.5"), "clamp": _bool,
              # name = "ModalBeam": ModalBeam.paper(...) (docs/modal_beam.md), m, k, b not taken
              "n_modes": _int(1, 20), "bc": _choice(("clamped-free", "clamped-clamped")),
              "stop_ratio": _real(0, 1, lo_open=True), "zeta": _real(0), "gap": _real(unit="m")}
MODAL_KEYS = ("n_modes", "bc", "stop_ratio", "zeta", "gap")
PERIODIC_KEYS = {"amplitude": _real(0, lo_open=True, unit="m"),
                 "f_range": _pair(0.0, strict_lo=True), "orders": _int_list(1, 8),
                 "n_grid": _int(3, 2000), "segments": _int(1, 64),
                 "dt_scale": _real(0, lo_open=True)}
STOCHASTIC_KEYS = {"band": _pair(0.0), "rms": _real(0, lo_open=True, unit="m"),
                   "psd_level": _real(0, lo_open=True, unit="m^2/Hz"),
                   "lowpass": _real(0, lo_open=True, unit="Hz"), "seed": _int(0),
                   "duration": _real(0, lo_open=True, unit="s"),
                   "transient": _real(0, unit="s"),
                   "psd_resolution": _real(0, lo_open=True, unit="Hz"),
                   "method": _choice(METHODS), "pdf_bins": _int(10, 100000)}
FIGURE_KEYS = {"kind": _choice(FIGURE_KINDS), "file": _file((".png", ".pdf", ".svg")),
               "title": _str, "channel": _choice(CHANNELS), "channels": _channels,
               "f_max": _real(0, lo_open=True, unit="Hz"), "window": _pair(0.0, unit="s"),
               "stability": _bool}
TABLE_KEYS = {"kind": _choice(TABLE_KINDS), "file": _file((".csv",)),
              "channel": _choice(CHANNELS), "f_max": _real(0, lo_open=True, unit="Hz"),
              "stability": _bool}
#: outputs that may set ``stability = false`` (all others that read the diagram need it)
STABILITY_OPTIONAL = ("compare", "peaks")
SWEEP_KEYS = {"parameter": _choice(tuple(PARAMETERS)), "values": None,
              "workers": _int(1, 1024)}
SECTIONS = {"model": MODEL_KEYS, "periodic": PERIODIC_KEYS, "stochastic": STOCHASTIC_KEYS,
            "sweep": SWEEP_KEYS}

PERIODIC_DEFAULTS = {"amplitude": 1e-4, "f_range": [5.0, 150.0], "orders": [1, 2, 3],
                     "n_grid": 30, "segments": 1, "dt_scale": 1.0}
STOCHASTIC_DEFAULTS = {"band": [0.0, 200.0], "seed": 1, "duration": 60.0, "transient": 2.0,
                       "psd_resolution": 0.25, "method": "rk4", "pdf_bins": 200,
                       "lowpass": None}


# -- locating keys in the text (tomllib gives no line numbers) -----------------------------
_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-\"' ]+?)\s*\]\]?\s*(#.*)?$")
_KEYLINE = re.compile(r"^\s*([A-Za-z0-9_\-\"']+)\s*=")


def _line_of(text, path):
    """1-based line of ``path`` (e.g. ('stochastic', 'rms') or ('figure', 1, 'kind')), or of
    its table header, or None."""
    counts = {}
    table, idx = None, None
    header_line = {}
    for no, line in enumerate(text.splitlines(), start=1):
        m = _HEADER.match(line)
        if m:
            table = m.group(2).strip().strip("\"'")
            if m.group(1) == "[[":
                counts[table] = counts.get(table, -1) + 1
                idx = counts[table]
            else:
                idx = None
            header_line[(table, idx)] = no
            continue
        m = _KEYLINE.match(line)
        if not m:
            continue
        key = m.group(1).strip("\"'")
        if len(path) == 1 and table is None and key == path[0]:
            return no
        if len(path) == 2 and (table, idx) == (path[0], None) and key == path[1]:
            return no
        if len(path) == 3 and (table, idx) == (path[0], path[1]) and key == path[2]:
            return no
    if len(path) >= 2:
        return header_line.get((path[0], path[1] if len(path) == 3 else None))
    return header_line.get((path[0], None))


def _name(path):
    out = str(path[0])
    for p in path[1:]:
        out += f"[{p}]" if isinstance(p, int) else f".{p}"
    return out


# -- the scene -----------------------------------------------------------------------------
@dataclass
class Scene:
    """A validated scene: sections with defaults filled, outputs, sweep."""

    path: str
    title: str
    model: dict
    periodic: dict | None
    stochastic: dict | None
    figures: list
    tables: list
    sweep: dict | None

    def variants(self):
        """[(label, model, periodic, stochastic)] one per sweep value (one if no sweep)."""
        if self.sweep is None:
            return [("", self.model, self.periodic, self.stochastic)]
        sec, key = PARAMETERS[self.sweep["parameter"]]
        out = []
        for v in self.sweep["values"]:
            parts = {"model": copy.deepcopy(self.model),
                     "periodic": copy.deepcopy(self.periodic),
                     "stochastic": copy.deepcopy(self.stochastic)}
            if parts[sec] is not None:
                parts[sec][key] = v
                if key == "rms" and sec == "stochastic":
                    parts[sec].pop("psd_level", None)
            label = f"{self.sweep['parameter']}={_fmt(v)}"
            out.append((label, parts["model"], parts["periodic"], parts["stochastic"]))
        return out


def _fmt(v):
    if isinstance(v, list):
        return "-".join(_fmt(x) for x in v)
    return f"{v:g}" if isinstance(v, float) else str(v)


def load_scene(path) -> Scene:
    """Read and validate a scene file. Raises SceneError naming the file, line and key of the
    first problem (unknown key, wrong type, value out of range, missing section)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise SceneError(f"{path}: cannot read: {exc.strerror}") from None
    text = raw.decode("utf-8", errors="replace")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None

    def fail(p, msg, value=None):
        line = _line_of(text, p)
        where = f"{path}:{line}" if line else path
        got = "" if value is None else f", got {value!r}"
        raise SceneError(f"{where}: {_name(p)}: {msg}{got}")

    def section(name, keys, data, prefix):
        if not isinstance(data, dict):
            fail(prefix, "must be a table")
        out = {}
        for k, v in data.items():
            if k not in keys:
                fail(prefix + (k,), f"unknown key; allowed: {', '.join(keys)}")
            chk = keys[k]
            if chk is None:
                out[k] = v
                continue
            val, err = chk(v)
            if err:
                fail(prefix + (k,), err, v)
            out[k] = val
        return out

    allowed_top = ("title", "model", "periodic", "stochastic", "figure", "table", "sweep")
    for k in doc:
        if k not in allowed_top:
            fail((k,), f"unknown key or section; allowed: {', '.join(allowed_top)}")
    title = doc.get("title", os.path.splitext(os.path.basename(path))[0])
    if not isinstance(title, str):
        fail(("title",), "must be a string", title)
    model = section("model", MODEL_KEYS, doc.get("model", {}), ("model",))
    if model.get("name") != "ModalBeam":
        model.pop("name", None)
    periodic = stoch = None
    if "periodic" in doc:
        periodic = dict(PERIODIC_DEFAULTS)
        periodic.update(section("periodic", PERIODIC_KEYS, doc["periodic"], ("periodic",)))
    if "stochastic" in doc:
        s = section("stochastic", STOCHASTIC_KEYS, doc["stochastic"], ("stochastic",))
        if "rms" in s and "psd_level" in s:
            fail(("stochastic", "psd_level"), "give either rms (m) or psd_level (m^2/Hz), not both")
        stoch = dict(STOCHASTIC_DEFAULTS)
        if "psd_level" not in s:
            stoch["rms"] = 1e-4
        stoch.update(s)
        if stoch["psd_resolution"] * stoch["duration"] < 1.0:
            fail(("stochastic", "psd_resolution"),
                 f"needs Welch segments of {1 / stoch['psd_resolution']:g} s, longer than "
                 f"duration {stoch['duration']:g} s", stoch["psd_resolution"])
    figures, tables = [], []
    for name, keys, store in (("figure", FIGURE_KEYS, figures), ("table", TABLE_KEYS, tables)):
        items = doc.get(name, [])
        if not isinstance(items, list):
            fail((name,), f"must be an array of tables: write [[{name}]]")
        for i, it in enumerate(items):
            d = section(name, keys, it, (name, i))
            for req in ("kind", "file"):
                if req not in d:
                    fail((name, i), f"missing key {req!r}")
            store.append((i, d))
    files = {}
    for name, store in (("figure", figures), ("table", tables)):
        for i, d in store:
            if d["file"] in files:
                fail((name, i, "file"), f"also written by {files[d['file']]}", d["file"])
            files[d["file"]] = _name((name, i))
            if "stability" in d and d["kind"] not in STABILITY_OPTIONAL:
                fail((name, i, "stability"), f"only {' and '.join(STABILITY_OPTIONAL)} outputs "
                     f"can do without stability ({d['kind']!r} shows it)", d["stability"])
            if name == "table" and "f_max" in d and d["kind"] != "peaks":
                fail((name, i, "f_max"), "only a peaks table has a frequency range", d["f_max"])
            needs_p = d["kind"] in ("frc", "compare", "peaks", "bifurcations")
            needs_s = d["kind"] in ("excitation_psd", "pdf", "history", "psd", "compare",
                                    "moments", "peaks")
            if needs_p and periodic is None:
                fail((name, i, "kind"), f"{d['kind']!r} needs a [periodic] section")
            if needs_s and stoch is None:
                fail((name, i, "kind"), f"{d['kind']!r} needs a [stochastic] section")
            if d["kind"] == "history" and stoch is not None:
                w = d.get("window", [0.0, min(0.5, stoch["duration"])])
                if w[1] > stoch["duration"]:
                    fail((name, i, "window"), f"must lie within the kept record [0, "
                         f"{stoch['duration']:g}] s", w)
    sweep = None
    if "sweep" in doc:
        sweep = section("sweep", SWEEP_KEYS, doc["sweep"], ("sweep",))
        if "parameter" not in sweep or "values" not in sweep:
            fail(("sweep",), "needs parameter and values")
        sec, key = PARAMETERS[sweep["parameter"]]
        target = {"model": model, "periodic": periodic, "stochastic": stoch}[sec]
        if sec != "model" and target is None:
            fail(("sweep", "parameter"), f"sweeps {sec}.{key} but the scene has no [{sec}]",
                 sweep["parameter"])
        vals = sweep["values"]
        if not isinstance(vals, list) or not vals:
            fail(("sweep", "values"), "must be a non-empty list", vals)
        chk = SECTIONS[sec][key]
        clean = []
        for v in vals:
            c, err = chk(v)
            if err:
                fail(("sweep", "values"), f"each value: {err}", v)
            clean.append(c)
        if len({canonical_json(c) for c in clean}) != len(clean):
            fail(("sweep", "values"), "must be distinct", vals)
        sweep["values"] = clean
    scene = Scene(path=path, title=title, model=model, periodic=periodic, stochastic=stoch,
                  figures=[d for _, d in figures], tables=[d for _, d in tables], sweep=sweep)
    # the objects validate the values together (e.g. hunt-crossley needs mu, Nyquist)
    for label, m, p, s in scene.variants():
        try:
            _model(m)
            if s is not None:
                _noise(s)
        except ValueError as exc:
            key = str(exc).split(":", 1)[0].strip()
            sec = "model" if key in MODEL_KEYS else "stochastic"
            line = _line_of(text, (sec, key)) or _line_of(text, ("sweep", "values"))
            where = f"{path}:{line}" if line else path
            raise SceneError(f"{where}: {sec}.{exc}" + (f" ({label})" if label else "")) from None
    return scene


# -- analyses ------------------------------------------------------------------------------
def _model(spec):
    import nlbeam

    kw = {k: v for k, v in spec.items() if k != "name"}
    if spec.get("name") == "ModalBeam":
        for k in ("m", "k", "b"):
            if k in kw:
                raise ValueError(f"{k}: not a parameter of ModalBeam (calibrated to m, k, b)")
        return nlbeam.ModalBeam.paper(**kw)
    for k in MODAL_KEYS:
        if k in kw:
            raise ValueError(f"{k}: a ModalBeam parameter (set name = 'ModalBeam')")
    return nlbeam.BeamImpact(**kw)


def _model_inputs(spec):
    """The model as keyed: a BeamImpact spec with the constructor's defaults filled in, so
    a scene that writes a default out and one that leaves it share a cache entry."""
    if spec.get("name", "BeamImpact") != "BeamImpact":
        return spec
    import inspect

    import nlbeam

    full = {k: p.default for k, p in inspect.signature(nlbeam.BeamImpact).parameters.items()
            if p.default is not inspect.Parameter.empty and p.default is not None}
    full.update((k, v) for k, v in spec.items() if k != "name")
    return full


def _noise(s):
    import stochastic

    kw = {"rms": s["rms"]} if "rms" in s else {"psd_level": s["psd_level"]}
    return stochastic.BandLimitedNoise(band=tuple(s["band"]), seed=s["seed"],
                                       lowpass=s.get("lowpass"), **kw)


@dataclass
class Job:
    """One analysis of one variant: kind 'periodic' or 'stochastic'; inputs: the exact
    inputs (hashed into key); path: the cache file; cached: the file exists."""

    kind: str
    variant: str
    inputs: dict
    key: str
    path: str
    cached: bool = False
    description: str = ""


def _compute(job_inputs):
    """Run one analysis from its inputs (module level: runs in pool or Dask workers)."""
    kind = job_inputs["analysis"]
    model = _model(job_inputs["model"])
    if kind == "periodic":
        import continuation

        p = job_inputs["periodic"]
        kw = {} if p.get("stability", True) else {"stability": False}  # planned only if supported
        if job_inputs.get("_progress") is not None:
            kw["progress"] = job_inputs["_progress"]
        return continuation.frequency_response(
            model, p["amplitude"], tuple(p["f_range"]), orders=tuple(p["orders"]),
            n_grid=p["n_grid"], segments=p["segments"], dt_scale=p["dt_scale"], **kw)
    import stochastic

    s = job_inputs["stochastic"]
    hist = job_inputs["history"]
    keep = None if hist is None else (s["transient"] + hist[0], s["transient"] + hist[1])
    return stochastic.simulate(model, _noise(s), s["duration"], s["transient"],
                               outputs=tuple(job_inputs["outputs"]),
                               channels=tuple(job_inputs["channels"]), method=s["method"],
                               psd_resolution=s["psd_resolution"], keep_history=keep,
                               pdf_bins=s["pdf_bins"], progress=job_inputs.get("_progress"))


def _stability_optional():
    """True when continuation.frequency_response takes ``stability`` (can skip Floquet
    multipliers); older versions always compute them."""
    import inspect

    import continuation

    try:
        return "stability" in inspect.signature(continuation.frequency_response).parameters
    except (TypeError, ValueError):
        return False


def _needs(scene):
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
        ch = d.get("channel", "delta")
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
            w = d.get("window", [0.0, min(0.5, scene.stochastic["duration"])])
            hist = list(w) if hist is None else [min(hist[0], w[0]), max(hist[1], w[1])]
            for c in d.get("channels", ["y", "x"]):
                if c not in hist_ch:
                    hist_ch.append(c)
    return need_p, need_stab, chans, hist, hist_ch


def plan(scene, out_dir):
    """The jobs the scene's outputs need, each marked cached or not. Returns a list of Job."""
    need_p, need_stab, chans, hist, hist_ch = _needs(scene)
    # what is computed is what is keyed: without the keyword, stability comes anyway
    stability = bool(need_stab) or (need_p and not _stability_optional())
    cache = os.path.join(os.fspath(out_dir), CACHE_DIR)
    jobs = []
    for label, m, p, s in scene.variants():
        m = _model_inputs(m)
        if need_p:
            p = dict(p, stability=stability)
            inputs = {"analysis": "periodic", "model": m, "periodic": p, "version": __version__}
            jobs.append(_job("periodic", label, inputs, cache,
                             f"frequency response {p['f_range'][0]:g}-{p['f_range'][1]:g} Hz, "
                             f"A = {p['amplitude']:g} m, orders {p['orders']}"
                             f"{'' if stability else ', no stability'}"))
        if chans or hist is not None:
            channels = sorted(set(chans) | set(hist_ch))
            outputs = sorted(set().union(*chans.values())) if chans else []
            inputs = {"analysis": "stochastic", "model": m, "stochastic": s,
                      "channels": channels, "outputs": outputs, "history": hist,
                      "version": __version__}
            jobs.append(_job("stochastic", label, inputs, cache,
                             f"{s['duration']:g} s under band {s['band'][0]:g}-{s['band'][1]:g} Hz"
                             f"{', low-pass %g Hz' % s['lowpass'] if s.get('lowpass') else ''}, "
                             f"seed {s['seed']}, channels {channels}, outputs {outputs}"
                             f"{', history %s s' % hist if hist else ''}"))
    return jobs


def _job(kind, label, inputs, cache, desc):
    key = content_key(inputs)
    path = os.path.join(cache, f"{kind}-{key}.h5")
    return Job(kind, label, inputs, key, path, os.path.exists(path), desc)


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
        lines.append(f"          -> {j.path}")
    if not jobs:
        lines.append("  (no analysis needed)")
    for d in scene.figures:
        lines.append(f"  write   figure {d['kind']}: {os.path.join(out_dir, d['file'])}")
    for d in scene.tables:
        lines.append(f"  write   table {d['kind']}: {os.path.join(out_dir, d['file'])}")
    return "\n".join(lines)


def _load(job):
    if job.kind == "periodic":
        import continuation

        return continuation.load(job.path)
    import stochastic

    return stochastic.load(job.path)


def _store(job, result, log=None):
    if log is not None and getattr(result, "success", True) is False:
        log(f"nlbeam: warning: {job.kind}{' ' + job.variant if job.variant else ''}: "
            f"{getattr(result, 'message', 'failed')}")
    os.makedirs(os.path.dirname(job.path), exist_ok=True)
    result.save(job.path)  # atomic (temporary name, then os.replace)
    write_text_atomic(job.path[:-3] + ".json", canonical_json(job.inputs) + "\n")


@dataclass
class RunReport:
    """What ``run_scene`` did: jobs (with cached flags as found; one per analysis and sweep
    value, so a shared analysis appears more than once), computed count (distinct analyses),
    files."""

    jobs: list
    computed: int
    files: list = field(default_factory=list)
    wall_time: float = 0.0

    @property
    def reused(self):
        """Distinct analyses taken from the cache."""
        return len({j.path for j in self.jobs if j.cached})


def run_scene(path_or_scene, out_dir=".", *, dry_run=False, workers=None, scheduler=None,
              quiet=False, log=None):
    """Validate, plan, compute what is missing (sweep points in parallel, see
    nlbeam.sweeps.run_jobs), cache it, and write the figures and tables atomically.
    Returns a RunReport. ``log``: callable(str) for progress lines (default stderr)."""
    t0 = time.perf_counter()
    scene = path_or_scene if isinstance(path_or_scene, Scene) else load_scene(path_or_scene)
    out_dir = os.fspath(out_dir)
    if log is None:
        def log(msg):
            if not quiet:
                print(msg, file=sys.stderr, flush=True)
    jobs = plan(scene, out_dir)
    if dry_run:
        return RunReport(jobs=jobs, computed=0, wall_time=time.perf_counter() - t0)
    todo = list({j.path: j for j in jobs if not j.cached}.values())  # equal keys: once
    if todo:
        log(f"nlbeam: {scene.title}: computing {len(todo)} of {len(jobs)} analyses")
    results = {}
    if todo:
        if scene.sweep is not None and len(todo) > 1 or scheduler is not None:
            w = workers if workers is not None else (scene.sweep or {}).get("workers")

            def prog(done, total):
                log(f"nlbeam: {done}/{total} analyses done")

            outs = run_jobs(_compute, [j.inputs for j in todo], workers=w, scheduler=scheduler,
                            progress=prog)
            for j, r in zip(todo, outs):
                _store(j, r, log)
                results[j.path] = r
        else:
            for n, j in enumerate(todo, start=1):
                log(f"nlbeam: [{n}/{len(todo)}] {j.kind}{' ' + j.variant if j.variant else ''}: "
                    f"{j.description}")
                inputs = dict(j.inputs)
                if j.kind == "stochastic" and not quiet:
                    last = [0.0]

                    def progress(done, total, last=last):
                        if done >= total or time.perf_counter() - last[0] > 5.0:
                            last[0] = time.perf_counter()
                            log(f"nlbeam:   simulated {done:.4g} / {total:.4g} s")
                    inputs["_progress"] = progress
                elif j.kind == "periodic" and not quiet:
                    inputs["_progress"] = lambda msg: log(f"nlbeam:   {msg}")
                t = time.perf_counter()
                r = _compute(inputs)
                _store(j, r, log)
                results[j.path] = r
                log(f"nlbeam:   done in {time.perf_counter() - t:.1f} s")
    for j in jobs:
        if j.path not in results:
            results[j.path] = _load(j)
    files = _write_outputs(scene, jobs, results, out_dir, log)
    return RunReport(jobs=jobs, computed=len(todo), files=files,
                     wall_time=time.perf_counter() - t0)


# -- outputs -------------------------------------------------------------------------------
def _by_variant(scene, jobs, results):
    """[(label, model, periodic, stochastic, diagram, stochastic result, job paths)]; job
    paths: {'periodic': cache file or None, 'stochastic': ...}."""
    out = []
    for label, m, p, s in scene.variants():
        paths = {k: next((j.path for j in jobs if j.kind == k and j.variant == label), None)
                 for k in ("periodic", "stochastic")}
        per = results[paths["periodic"]] if paths["periodic"] else None
        sto = results[paths["stochastic"]] if paths["stochastic"] else None
        out.append((label, m, p, s, per, sto, paths))
    return out


#: which analyses each output reads
_READS = {"frc": ("periodic",), "bifurcations": ("periodic",), "history": ("stochastic",),
          "psd": ("stochastic",), "pdf": ("stochastic",), "excitation_psd": ("stochastic",),
          "moments": ("stochastic",), "compare": ("periodic", "stochastic"),
          "peaks": ("periodic", "stochastic")}


def _distinct(kind, variants):
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


def _write_outputs(scene, jobs, results, out_dir, log):
    variants = _by_variant(scene, jobs, results)
    files = []
    for d in scene.figures:
        files += _figure(scene, d, variants, out_dir)
    for d in scene.tables:
        files.append(_table(d, variants, out_dir))
    for f in files:
        log(f"nlbeam: wrote {f}")
    return files


def _suffixed(path, i, n):
    if n == 1:
        return path
    stem, ext = os.path.splitext(path)
    return f"{stem}_{i + 1}{ext}"


def _save_fig(fig, path):
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format=os.path.splitext(path)[1][1:])
    finally:
        plt.close(fig)
    return path


def _figure(scene, d, variants, out_dir):
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")  # files only; an interactive session keeps its backend
    import matplotlib.pyplot as plt

    kind = d["kind"]
    ch = d.get("channel", "delta")
    target = os.path.join(out_dir, d["file"])
    variants = _distinct(kind, variants)
    multi = len(variants) > 1
    title = d.get("title", scene.title)
    if kind in ("frc", "history", "compare"):
        written = []
        for i, (label, m, p, s, per, sto, _) in enumerate(variants):
            path = _suffixed(target, i, len(variants))
            t = title + (f" ({label})" if label else "")
            if kind == "frc":
                from continuation.plot import plot_frequency_response

                fig, ax = plt.subplots(figsize=(8, 5))
                plot_frequency_response(per, ax)
                ax.set_title(t)
            elif kind == "compare":
                from .compare import plot_comparison

                f_max = d.get("f_max", _default_f_max(p, s))
                fig = plot_comparison(sto.psd(ch), per, excitation=_noise(s), label=ch,
                                      f_max=f_max, f_range=(0.0, f_max),
                                      stability=d.get("stability", True))
                fig.axes[0].set_title(t)
            else:
                chans = d.get("channels", ["y", "x"])
                fig, axs = plt.subplots(len(chans), 1, sharex=True, figsize=(8, 2.2 * len(chans) + 1),
                                        squeeze=False)
                h = sto.history
                w = d.get("window", [0.0, min(0.5, s["duration"])])
                tt = h["t"] - s["transient"]
                sel = (tt >= w[0]) & (tt <= w[1])
                for ax, c in zip(axs[:, 0], chans):
                    sc = 1.0 if c == "force" else 1e3
                    ax.plot(tt[sel], h[c][sel] * sc, lw=0.8)
                    ax.set_ylabel({"force": "force [N]", "v": "v [mm/s]",
                                   "yd": "yd [mm/s]"}.get(c, f"{c} [mm]"))
                axs[-1, 0].set_xlabel("time [s]")
                axs[0, 0].set_title(t)
                fig.tight_layout()
            written.append(_save_fig(fig, path))
        return written
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, m, p, s, per, sto, _ in variants:
        lab = label or None
        if kind == "psd":
            f, P = sto.psd(ch)
            fmax = d.get("f_max", s["band"][1])
            ax.semilogy(f[P > 0], P[P > 0], lw=0.8, label=lab)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel(f"PSD of {ch} [{_unit(ch)}$^2$/Hz]")
            ax.set_xlim(0, fmax)
            shown = P[(f <= fmax) & (P > 0)]
            if shown.size:  # the band-edge roll-off would stretch the axis over decades
                lo, hi = ax.get_ylim() if ax.lines[:-1] else (np.inf, 0.0)
                ax.set_ylim(min(lo, max(shown.min(), shown.max() * 1e-7) / 2),
                            max(hi, shown.max() * 3))
        elif kind == "excitation_psd":
            f, P = sto.psd("y")
            G = _noise(s).psd(f)
            ax.plot(f, P * 1e6, lw=0.8, label=("simulated y" + (f" ({label})" if label else "")))
            ax.plot(f, G * 1e6, "k--", lw=1.0, label="target G(f)" if not multi else None)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel("PSD of y [mm$^2$/Hz]")
            ax.set_xlim(0, d.get("f_max", 1.25 * s["band"][1]))
        elif kind == "pdf":
            x, dens = sto.pdf(ch)
            mo = sto.moments(ch)
            sc = 1e3 if ch in ("x", "y", "delta") else 1.0
            ax.semilogy(x * sc, dens / sc, lw=1.0,
                        label=f"{ch}{' ' + label if label else ''}: skew {mo['skewness']:.2f}, "
                              f"kurt {mo['kurtosis']:.2f}")
            g = np.exp(-0.5 * ((x - mo["mean"]) / mo["std"]) ** 2) / (mo["std"] * math.sqrt(2 * math.pi))
            ax.semilogy(x * sc, g / sc, "k--", lw=0.8, label="Gaussian, same mean and std"
                        if label == variants[0][0] else None)
            ax.set_xlabel(f"{ch} [{'mm' if sc == 1e3 else _unit(ch)}]")
            ax.set_ylabel("probability density")
            pos = dens[dens > 0]
            if pos.size:
                ax.set_ylim(pos.min() / sc / 2, pos.max() / sc * 3)
    ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return [_save_fig(fig, target)]


def _unit(ch):
    return {"x": "m", "y": "m", "delta": "m", "v": "m/s", "yd": "m/s", "force": "N"}[ch]


def _default_f_max(p, s):
    """Peaks and comparisons look up to the excitation band's or the diagram's upper end
    (whichever is higher), not to the Nyquist frequency of the record."""
    return max(float(s["band"][1]), float(p["f_range"][1]))


def _table(d, variants, out_dir):
    from .compare import map_peaks

    kind = d["kind"]
    ch = d.get("channel", "delta")
    rows = []
    for label, m, p, s, per, sto, _ in _distinct(kind, variants):
        if kind == "moments":
            mo = sto.moments(ch)
            rows.append({"variant": label, "channel": ch,
                         **{k: mo[k] for k in ("mean", "std", "skewness", "kurtosis",
                                               "se_mean", "se_std", "se_skewness",
                                               "se_kurtosis") if k in mo}})
        elif kind == "peaks":
            f_max = d.get("f_max", _default_f_max(p, s))
            for pk in map_peaks(sto.psd(ch), per, _noise(s), f_range=(0.0, f_max)):
                row = pk.as_row()
                if not d.get("stability", True):
                    row["stable"] = ""  # not asked for (and not computed when supported)
                rows.append({"variant": label, "channel": ch, **row})
        else:
            for b in per.bifurcations:
                rows.append({"variant": label, "kind": b.kind, "order": b.order,
                             "frequency_hz": b.frequency, "xmax_m": b.xmax,
                             "tolerance": b.tolerance})
    buf = io.StringIO()
    cols = list(dict.fromkeys(k for r in rows for k in r)) or ["variant"]
    wr = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    wr.writeheader()
    for r in rows:
        wr.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    path = os.path.join(out_dir, d["file"])
    write_text_atomic(path, buf.getvalue())
    return path
