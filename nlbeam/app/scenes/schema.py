"""The scene file: its schema (sections, keys, allowed values, defaults), ``load_scene`` that
validates it and names the file, line and key of the first problem, and the model and noise
objects it describes.

Scenes: a TOML file that names a model, the periodic and stochastic analyses, and the
figures and tables wanted; ``run_scene`` computes only what those outputs need, caches each
analysis in HDF5 under a key made of exactly its inputs, and reuses it.

Scene file (every section and key optional; units SI, Hz)::

    title = "Fig. 9"
    [model]        # the paper's BeamImpact; m, k, b, K_hertz, e, contact, mu, clamp, gap
    e = 0.5        # (or ModalBeam, a System written out, a factory: scenes.models)
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
    [chart]        # continuation.stability_chart: bifurcation curves in (f, amplitude)
    p_range = [2e-5, 5e-4]    # m, the amplitude range of the curves
    f_range = [5.0, 150.0]    # Hz
    [[figure]]     # kind: frc | excitation_psd | pdf | history | psd | compare |
                   #       stability_chart
    kind = "psd"
    file = "fig9.png"
    channel = "delta"         # x | v | y | yd | delta | force
    [[table]]      # kind: moments | peaks | bifurcations | curves (CSV)
    kind = "moments"
    file = "moments.csv"
    [sweep]        # one run per value; any name of sweep_parameters
    parameter = "rms"
    values = [5e-5, 1e-4]

Every key with its meaning: docs/usage.md ("Scene keys, section by section"; a test walks
the schema against it). What each output needs and how the analyses are cached:
``nlbeam.app.scenes.plan``.
"""
from __future__ import annotations

import copy
import os
import re
import tomllib
from dataclasses import dataclass

import stochastic
from nlbeam.parameters import element_parameter
from nlbeam.vocabulary import CHANNELS, METHODS

from .. import defaults
from ..files import canonical_json
from .checks import (_accuracy, _bool, _channels, _choice, _file, _int, _int_list, _pair,
                     _pair_int, _real, _str)
from ..sweeps import BAND_EDGES, PARAMETERS
from .models import MODEL_KEYS, PARAMETER_UNITS, build_model, check_model, model_parameters

__all__ = ["SceneError", "Scene", "load_scene", "build_model", "build_noise", "default_f_max",
           "history_window", "history_channels", "excitation_for_peaks", "FIGURE_KINDS",
           "TABLE_KINDS", "sweep_parameters", "SECTIONS", "with_settings"]

FIGURE_KINDS = ("frc", "excitation_psd", "pdf", "history", "psd", "compare", "stability_chart")
TABLE_KINDS = ("moments", "peaks", "bifurcations", "curves")
#: the outputs that read the [chart] section's stability chart
CHART_OUTPUTS = ("stability_chart", "curves")


class SceneError(ValueError):
    """A scene file that cannot run: the message names the file, line and key."""


# -- schema --------------------------------------------------------------------------------
PERIODIC_KEYS = {"amplitude": _real(0, lo_open=True, unit="m"),
                 "f_range": _pair(0.0, strict_lo=True), "orders": _int_list(1, 8),
                 "n_grid": _int(2, 2000), "segments": _int(1, 64),
                 "dt_scale": _real(0, lo_open=True), "method": _choice(METHODS),
                 "steps_per_contact": _real(0, lo_open=True), "rtol": _real(0, lo_open=True),
                 "atol": _real(0, lo_open=True, unit="m"), "ds": _real(0, lo_open=True),
                 "ds_max": _real(0, lo_open=True), "max_angle": _real(0, 3.2, lo_open=True),
                 "max_points": _int(2), "tol": _real(0, lo_open=True),
                 "bif_tol": _real(0, lo_open=True), "accuracy": _accuracy, "switch": _bool,
                 "brute_force_grid": _bool}
STOCHASTIC_KEYS = {"band": _pair(0.0), "rms": _real(0, lo_open=True, unit="m"),
                   "psd_level": _real(0, lo_open=True, unit="m^2/Hz"),
                   "lowpass": _real(0, lo_open=True, unit="Hz"), "seed": _int(0),
                   "duration": _real(0, lo_open=True, unit="s"),
                   "transient": _real(0, unit="s"),
                   "psd_resolution": _real(0, lo_open=True, unit="Hz"),
                   "method": _choice(METHODS), "pdf_bins": _int(10, 100000),
                   "record": _file((".csv", ".h5", ".hdf5")), "record_time": _str,
                   "record_column": _str,
                   "rtol": _real(0, lo_open=True), "atol": _real(0, lo_open=True, unit="m"),
                   "dt": _real(0, lo_open=True, unit="s"),
                   "steps_per_contact": _real(0, lo_open=True),
                   "amplitudes": _choice(("random", "deterministic"))}
#: [measured]: a measured response record, analysed by stochastic.analyze and overlaid
MEASURED_KEYS = {"file": _file((".csv", ".h5", ".hdf5")), "time_column": _str,
                 "channels": _channels, "label": _str, "band": _pair(0.0),
                 "psd_resolution": _real(0, lo_open=True, unit="Hz"),
                 "pdf_bins": _int(10, 100000)}
MEASURED_DEFAULTS = {"time_column": "t", "label": "measured"}
FIGURE_KEYS = {"kind": _choice(FIGURE_KINDS), "file": _file((".png", ".pdf", ".svg")),
               "title": _str, "channel": _choice(CHANNELS), "channels": _channels,
               "f_max": _real(0, lo_open=True, unit="Hz"), "window": _pair(0.0, unit="s"),
               "stability": _bool, "min_prominence": _real(0, lo_open=True)}
TABLE_KEYS = {"kind": _choice(TABLE_KINDS), "file": _file((".csv",)),
              "channel": _choice(CHANNELS), "f_max": _real(0, lo_open=True, unit="Hz"),
              "stability": _bool, "min_prominence": _real(0, lo_open=True)}
#: outputs that may set ``stability = false`` (all others that read the diagram need it)
STABILITY_OPTIONAL = ("compare", "peaks")
SWEEP_KEYS = {"parameter": _str, "values": None,
              "workers": _int(1, 1024)}
CHART_KEYS = {"p_range": _pair(0.0, strict_lo=True, unit="m"),
              "f_range": _pair(0.0, strict_lo=True), "orders": _int_list(1, 8),
              "amplitude": _real(0, lo_open=True, unit="m"),
              "label_grid": _pair_int(0, 200), "max_points": _int(1, 100000),
              "max_evaluations": _int(1, 10 ** 8)}
SECTIONS = {"model": MODEL_KEYS, "periodic": PERIODIC_KEYS, "stochastic": STOCHASTIC_KEYS,
            "sweep": SWEEP_KEYS}

#: what a section leaves out (nlbeam.app.defaults: the analyses' own defaults and the paper's
#: study); transient and psd_resolution None: stochastic.simulate derives them
PERIODIC_DEFAULTS = defaults.PERIODIC
CHART_DEFAULTS = defaults.CHART
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
    chart: dict | None = None  # [chart] with defaults filled in (continuation.stability_chart)

    def variants(self):
        """[(label, model, periodic, stochastic)] one per sweep value (one if no sweep)."""
        if self.sweep is None:
            return [("", self.model, self.periodic, self.stochastic)]
        sec, keys, _ = sweep_parameters(self.model)[self.sweep["parameter"]]
        out = []
        for v in self.sweep["values"]:
            parts = {"model": copy.deepcopy(self.model),
                     "periodic": copy.deepcopy(self.periodic),
                     "stochastic": copy.deepcopy(self.stochastic)}
            if parts[sec] is not None:
                _set(parts[sec], keys, v)
                other = {"rms": "psd_level", "psd_level": "rms"}.get(keys[0])
                if sec == "stochastic" and other:
                    parts[sec].pop(other, None)
            label = f"{self.sweep['parameter']}={_fmt(v)}"
            out.append((label, parts["model"], parts["periodic"], parts["stochastic"]))
        return out

    @property
    def swept(self):
        """(name, unit) of the swept parameter, or None without a sweep: a factory's
        arguments have no known unit; the excitation's are N (N^2/Hz) for a force-excited
        model."""
        if self.sweep is None:
            return None
        name = self.sweep["parameter"]
        if "factory" in self.model and name in self.model.get("args", {}):
            return name, ""
        field = name.rsplit(".", 1)[-1]
        unit = PARAMETER_UNITS.get(name, PARAMETER_UNITS.get(field, ""))
        if name in ("amplitude", "rms", "psd_level") and \
                build_model(self.model).excitation_kind == "force":
            unit = unit.replace("m", "N")
        return name, unit


def _set(d, keys, v):
    for k in keys[:-1]:
        d = d[k]
    d[keys[-1]] = v


def sweep_parameters(model):
    """{name: (section, path of keys, check)} of what a [sweep] may vary in a scene whose
    [model] spec is ``model``: the model's parameters (models.model_parameters) and the
    excitation's and record's (nlbeam.app.sweeps.PARAMETERS)."""
    out = {n: ("model", keys, chk) for n, (keys, chk) in model_parameters(model).items()}
    for n, (sec, key) in PARAMETERS.items():
        if sec != "model":
            out[n] = (sec, (key,), SECTIONS[sec][key])
    for n, (sec, key, i) in BAND_EDGES.items():
        out[n] = (sec, (key, i), _real(0, unit="Hz"))
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

    allowed_top = ("title", "model", "periodic", "stochastic", "chart", "figure", "table",
                   "sweep", "measured")
    for k in doc:
        if k not in allowed_top:
            fail((k,), f"unknown key or section; allowed: {', '.join(allowed_top)}")
    title = doc.get("title", os.path.splitext(os.path.basename(path))[0])
    if not isinstance(title, str):
        fail(("title",), "must be a string", title)
    model = check_model(doc.get("model", {}), fail)
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
    chart = None
    if "chart" in doc:
        chart = copy.deepcopy(CHART_DEFAULTS)
        chart.update(section("chart", CHART_KEYS, doc["chart"], ("chart",)))
        a = chart["amplitude"]
        if a is not None and not chart["p_range"][0] <= a <= chart["p_range"][1]:
            fail(("chart", "amplitude"), f"must lie in p_range {chart['p_range']} (m)", a)
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
            if "min_prominence" in d and d["kind"] not in ("peaks", "compare"):
                fail((name, i, "min_prominence"), "only a peaks table and a compare figure "
                     "find peaks", d["min_prominence"])
            needs_p = d["kind"] in ("frc", "compare", "peaks", "bifurcations")
            needs_s = d["kind"] in ("excitation_psd", "pdf", "history", "psd", "compare",
                                    "moments", "peaks")
            if d["kind"] in CHART_OUTPUTS and chart is None:
                fail((name, i, "kind"), f"{d['kind']!r} needs a [chart] section")
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
        names = sweep_parameters(model)
        if sweep["parameter"] not in names:
            fail(("sweep", "parameter"), "not a parameter of this scene; the names that exist: "
                 + ", ".join(names), sweep["parameter"])
        sec, keys, chk = names[sweep["parameter"]]
        target = {"model": model, "periodic": periodic, "stochastic": stoch}[sec]
        if sec != "model" and target is None:
            fail(("sweep", "parameter"), f"sweeps {sec}.{keys[0]} but the scene has no [{sec}]",
                 sweep["parameter"])
        vals = sweep["values"]
        if not isinstance(vals, list) or not vals:
            fail(("sweep", "values"), "must be a non-empty list", vals)
        clean = []
        for v in vals:
            c, err = chk(v) if chk is not None else (v, None)
            if err:
                fail(("sweep", "values"), f"each value: {err}", v)
            clean.append(c)
        if len({canonical_json(c) for c in clean}) != len(clean):
            fail(("sweep", "values"), "must be distinct", vals)
        sweep["values"] = clean
    scene = Scene(path=path, title=title, model=model, periodic=periodic, stochastic=stoch,
                  figures=[d for _, d in figures], tables=[d for _, d in tables], sweep=sweep,
                  measured=measured, chart=chart)
    # the objects validate the values together (e.g. hunt-crossley needs mu, Nyquist)
    for label, m, p, s in scene.variants():
        try:
            build_model(m)
            if s is not None:
                build_noise(s)
        except (ValueError, TypeError) as exc:
            key = str(exc).split(":", 1)[0].strip()
            el = element_parameter(key)
            if el is not None:
                sec, at = "model", ("model.elements", el[0], el[1])
            elif "factory" in m:
                sec, at = "model", ("model", "factory")
                exc = f"factory: {m['factory']}(**args) failed: {exc}" \
                    if not str(exc).startswith("factory:") else exc
            else:
                sec = "model" if key in MODEL_KEYS else "stochastic"
                at = (sec, key)
            line = _line_of(text, at) or _line_of(text, ("sweep", "values"))
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
    out = {"record_time": s.get("record_time", "t"), "record_column": s.get("record_column",
                                                                             "y")}
    out["record"] = _columns_file(scene_path, s["record"], ("stochastic", "record"),
                                  (out["record_time"], out["record_column"]), fail)
    from ..files.columns import read_columns
    from ..files.keys import file_sha256

    t = read_columns(out["record"])[out["record_time"]]
    need = s["duration"] + (s["transient"] or 0.0)  # (a default transient: checked by simulate)
    if t.size < 2 or t[-1] - t[0] < need * (1 - 1e-9):
        fail(("stochastic", "duration"), f"transient + duration = {need:g} s exceed the record "
             f"{s['record']} ({t[-1] - t[0] if t.size else 0:g} s long)", s["duration"])
    out["record_sha256"] = file_sha256(out["record"])
    return out


def excitation_for_peaks(s):
    """What map_peaks and the comparison figure take as the excitation of a [stochastic]:
    the noise, or for a measured record its ``band`` (Hz)."""
    return tuple(s["band"]) if "record" in s else build_noise(s)


def with_settings(scene, settings) -> Scene:
    """``scene`` with each (name, value) of ``settings`` set: a name of the sweeps
    (sweep_parameters: the model's, the excitation's, the record's), the value checked like
    the key it sets. Raises SceneError naming the setting."""
    scene = copy.deepcopy(scene)
    names = sweep_parameters(scene.model)
    for name, value in settings:
        if name not in names:
            raise SceneError(f"{name}: not a parameter of this scene; the names that exist: "
                             + ", ".join(names))
        if scene.sweep is not None and scene.sweep["parameter"] == name:
            raise SceneError(f"{name}: the scene sweeps it; change its [sweep] values instead")
        sec, keys, chk = names[name]
        target = getattr(scene, sec)
        if target is None:
            raise SceneError(f"{name}: sets {sec}.{keys[0]} but the scene has no [{sec}]")
        v, err = chk(value) if chk is not None else (value, None)
        if err:
            raise SceneError(f"{name}: {err}, got {value!r}")
        _set(target, keys, v)
        other = {"rms": "psd_level", "psd_level": "rms"}.get(keys[0])
        if sec == "stochastic" and other:
            target.pop(other, None)
    for label, m, p, s in scene.variants():
        try:
            build_model(m)
            if s is not None:
                build_noise(s)
        except (ValueError, TypeError) as exc:
            raise SceneError(f"{exc}" + (f" ({label})" if label else "")) from None
    return scene


# -- the objects the scene describes -------------------------------------------------
def build_noise(s):
    """The excitation of a [stochastic] section: stochastic.BandLimitedNoise, or
    stochastic.Recorded of its ``record`` file's columns (time in s, y in m)."""
    if "record" in s:
        from ..files.columns import read_columns

        cols = read_columns(s["record"], required=(s["record_time"], s["record_column"]))
        return stochastic.Recorded(cols[s["record_time"]], cols[s["record_column"]])
    kw = {"rms": s["rms"]} if "rms" in s else {"psd_level": s["psd_level"]}
    return stochastic.BandLimitedNoise(band=tuple(s["band"]), seed=s["seed"],
                                       lowpass=s.get("lowpass"),
                                       amplitudes=s.get("amplitudes", "random"), **kw)


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
