"""The scene file: its schema (sections, keys, allowed values, defaults), ``load_scene`` that
validates it and names the file, line and key of the first problem, and the model and noise
objects it describes.

Scenes: a TOML file that names a model, the periodic and stochastic analyses, and the
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
    # record = "base.csv"     # instead of the noise: a measured base motion (CSV or HDF5 with
    # record_time = "t"       # named columns, relative to the scene) as stochastic.Recorded
    # record_column = "y"     # (band then only says where to look for peaks)
    [measured]     # a measured response overlaid on psd, pdf, excitation_psd and compare
    file = "rig.csv"          # figures and added to moments and peaks tables (stochastic.analyze)
    channels = ["delta", "y"] # its columns, named like the channels (SI units)
    time_column = "t"         # default "t"; label (default "measured"), band, psd_resolution,
                              # pdf_bins optional
    [[figure]]     # kind: frc | excitation_psd | pdf | history | psd | compare
    kind = "psd"
    file = "fig9.png"
    channel = "delta"         # x | v | y | yd | delta | force
    [[table]]      # kind: moments | peaks | bifurcations (CSV)
    kind = "moments"
    file = "moments.csv"
    [sweep]        # one run per value; see nlbeam.app.sweeps.PARAMETERS
    parameter = "rms"
    values = [5e-5, 1e-4]

What each output needs and how the analyses are cached: ``nlbeam.app.scenes.plan``.
"""
from __future__ import annotations

import copy
import math
import os
import re
import tomllib
from dataclasses import dataclass

import nlbeam
import stochastic
from nlbeam.vocabulary import BOUNDARY_CONDITIONS, CHANNELS, CONTACT_LAWS, METHODS

from .. import defaults
from ..files import canonical_json
from ..sweeps import PARAMETERS

__all__ = ["SceneError", "Scene", "load_scene", "build_model", "build_noise", "default_f_max",
           "history_window", "history_channels", "excitation_for_peaks", "FIGURE_KINDS",
           "TABLE_KINDS"]

FIGURE_KINDS = ("frc", "excitation_psd", "pdf", "history", "psd", "compare")
TABLE_KINDS = ("moments", "peaks", "bifurcations")


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
              "contact": _choice(CONTACT_LAWS), "mu": _real(0, unit="N s/m^2.5"), "clamp": _bool,
              # name = "ModalBeam": ModalBeam.paper(...) (docs/modal_beam.md), m, k, b not taken
              "n_modes": _int(1, 20), "bc": _choice(BOUNDARY_CONDITIONS),
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
                   "method": _choice(METHODS), "pdf_bins": _int(10, 100000),
                   "record": _file((".csv", ".h5", ".hdf5")), "record_time": _str,
                   "record_column": _str}
#: [measured]: a measured response record, analysed by stochastic.analyze and overlaid
MEASURED_KEYS = {"file": _file((".csv", ".h5", ".hdf5")), "time_column": _str,
                 "channels": _channels, "label": _str, "band": _pair(0.0),
                 "psd_resolution": _real(0, lo_open=True, unit="Hz"),
                 "pdf_bins": _int(10, 100000)}
MEASURED_DEFAULTS = {"time_column": "t", "label": "measured"}
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

#: what a section leaves out (nlbeam.app.defaults: the analyses' own defaults and the paper's
#: study); transient and psd_resolution None: stochastic.simulate derives them
PERIODIC_DEFAULTS = defaults.PERIODIC
STOCHASTIC_DEFAULTS = defaults.STOCHASTIC


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
    measured: dict | None = None  # [measured] with the file's absolute path

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
    text = text[1:] if text.startswith("\ufeff") else text  # a UTF-8 BOM (some editors)
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

    allowed_top = ("title", "model", "periodic", "stochastic", "figure", "table", "sweep",
                   "measured")
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
        periodic = copy.deepcopy(PERIODIC_DEFAULTS)
        periodic.update(section("periodic", PERIODIC_KEYS, doc["periodic"], ("periodic",)))
    if "stochastic" in doc:
        s = section("stochastic", STOCHASTIC_KEYS, doc["stochastic"], ("stochastic",))
        if "rms" in s and "psd_level" in s:
            fail(("stochastic", "psd_level"), "give either rms (m) or psd_level (m^2/Hz), not both")
        stoch = copy.deepcopy(STOCHASTIC_DEFAULTS)
        if "psd_level" in s:
            del stoch["rms"]
        stoch.update(s)
        if "record" in stoch:
            stoch.update(_record(path, stoch, fail))
        if stoch["psd_resolution"] is not None and stoch["psd_resolution"] * stoch["duration"] < 1:
            fail(("stochastic", "psd_resolution"),
                 f"needs Welch segments of {1 / stoch['psd_resolution']:g} s, longer than "
                 f"duration {stoch['duration']:g} s", stoch["psd_resolution"])
    measured = None
    if "measured" in doc:
        measured = dict(MEASURED_DEFAULTS)
        measured.update(section("measured", MEASURED_KEYS, doc["measured"], ("measured",)))
        for req in ("file", "channels"):
            if req not in measured:
                fail(("measured",), f"missing key {req!r}")
        measured["file"] = _columns_file(path, measured["file"], ("measured", "file"),
                                         (measured["time_column"], *measured["channels"]), fail)
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
                w = history_window(d, stoch["duration"])
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
                  figures=[d for _, d in figures], tables=[d for _, d in tables], sweep=sweep,
                  measured=measured)
    # the objects validate the values together (e.g. hunt-crossley needs mu, Nyquist)
    for label, m, p, s in scene.variants():
        try:
            build_model(m)
            if s is not None:
                build_noise(s)
        except ValueError as exc:
            key = str(exc).split(":", 1)[0].strip()
            sec = "model" if key in MODEL_KEYS else "stochastic"
            line = _line_of(text, (sec, key)) or _line_of(text, ("sweep", "values"))
            where = f"{path}:{line}" if line else path
            raise SceneError(f"{where}: {sec}.{exc}" + (f" ({label})" if label else "")) from None
    return scene


def _columns_file(scene_path, name, key, required, fail):
    """The absolute path of a data file named in a scene (relative to the scene's folder),
    checked to hold the ``required`` columns (SceneError naming ``key`` otherwise)."""
    from ..files.columns import read_columns

    full = os.path.join(os.path.dirname(os.path.abspath(scene_path)), name)
    try:
        read_columns(full, required=required)
    except ValueError as exc:
        fail(key, str(exc).replace(full, name))
    return full


def _record(scene_path, s, fail):
    """record, record_time, record_column of a [stochastic] with a measured excitation: the
    absolute path and the SHA-256 of its bytes (so that the cache key follows the data)."""
    import hashlib

    out = {"record_time": s.get("record_time", "t"), "record_column": s.get("record_column",
                                                                             "y")}
    out["record"] = _columns_file(scene_path, s["record"], ("stochastic", "record"),
                                  (out["record_time"], out["record_column"]), fail)
    from ..files.columns import read_columns

    t = read_columns(out["record"])[out["record_time"]]
    need = s["duration"] + (s["transient"] or 0.0)  # (a default transient: checked by simulate)
    if t.size < 2 or t[-1] - t[0] < need * (1 - 1e-9):
        fail(("stochastic", "duration"), f"transient + duration = {need:g} s exceed the record "
             f"{s['record']} ({t[-1] - t[0] if t.size else 0:g} s long)", s["duration"])
    with open(out["record"], "rb") as fh:
        out["record_sha256"] = hashlib.sha256(fh.read()).hexdigest()
    return out


def excitation_for_peaks(s):
    """What map_peaks and the comparison figure take as the excitation of a [stochastic]:
    the noise, or for a measured record its ``band`` (Hz)."""
    return tuple(s["band"]) if "record" in s else build_noise(s)


# -- the objects the scene describes -------------------------------------------------
def build_model(spec):
    """The model of a [model] section (a BeamImpact, or ModalBeam.paper for name =
    "ModalBeam"); the model's own checks raise ValueError naming the key."""
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


def build_noise(s):
    """The excitation of a [stochastic] section: stochastic.BandLimitedNoise, or
    stochastic.Recorded of its ``record`` file's columns (time in s, y in m)."""
    if "record" in s:
        from ..files.columns import read_columns

        cols = read_columns(s["record"], required=(s["record_time"], s["record_column"]))
        return stochastic.Recorded(cols[s["record_time"]], cols[s["record_column"]])
    kw = {"rms": s["rms"]} if "rms" in s else {"psd_level": s["psd_level"]}
    return stochastic.BandLimitedNoise(band=tuple(s["band"]), seed=s["seed"],
                                       lowpass=s.get("lowpass"), **kw)


def default_f_max(p, s):
    """Peaks and comparisons look up to the excitation band's or the diagram's upper end
    (whichever is higher), not to the Nyquist frequency of the record."""
    return max(float(s["band"][1]), float(p["f_range"][1]))


def history_window(d, duration):
    """The window [t0, t1] (s after the transient) of a history figure ``d``: its ``window``,
    else the first defaults.HISTORY_SECONDS s of a record of ``duration`` s."""
    return d.get("window", [0.0, min(defaults.HISTORY_SECONDS, duration)])


def history_channels(d):
    """The channels of a history figure ``d``: its ``channels``, else
    defaults.HISTORY_CHANNELS."""
    return d.get("channels", list(defaults.HISTORY_CHANNELS))
