"""The [model] section of a scene: which model, checked key by key, the object it builds, the
names of its parameters (what a sweep may vary) and its inputs as the cache keys them.

Four kinds (docs/usage.md, "Models"):

- the paper beam ``nlbeam.BeamImpact`` (the default; keys m, k, b, K_hertz, e, contact, mu,
  clamp, gap);
- ``name = "ModalBeam"``: ``nlbeam.ModalBeam.paper`` (n_modes, bc, stop_ratio, zeta, gap and
  the stop's keys);
- ``name = "System"``: a general ``nlbeam.System`` written out: M, C, K (kg, kg/s, N/m; lists
  of rows), excitation_kind ('base' or 'force'), y_load, yd_load, output_dof and elements
  ([[model.elements]] tables with ``type`` = Contact | PiecewiseLinearStop | CubicSpring and
  the fields of that class);
- ``factory = "module:function"``: the model a Python function returns when called with the
  keyword arguments of [model.args] (the module must be importable where the scene runs:
  on the path, or installed).
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import inspect

import numpy as np

import nlbeam
from nlbeam.vocabulary import BOUNDARY_CONDITIONS, CONTACT_LAWS

from .checks import _bool, _choice, _dof, _int, _matrix, _real, _vector

__all__ = ["MODEL_KEYS", "BEAM_KEYS", "MODAL_KEYS", "SYSTEM_KEYS", "FACTORY_KEYS",
           "ELEMENT_TYPES", "ELEMENT_KEYS", "MODEL_NAMES", "check_model", "build_model",
           "model_parameters", "model_inputs", "system_digest", "PARAMETER_UNITS"]

MODEL_NAMES = ("BeamImpact", "ModalBeam", "System")
#: the paper beam's keys (BeamImpact) and those only the modal beam takes
BEAM_KEYS = {"name": _choice(MODEL_NAMES), "m": _real(0, lo_open=True, unit="kg"),
             "k": _real(0, unit="N/m"), "b": _real(0, unit="kg/s"),
             "K_hertz": _real(0, unit="N/m^1.5"), "e": _real(0, 1, lo_open=True),
             "contact": _choice(CONTACT_LAWS), "mu": _real(0, unit="N s/m^2.5"), "clamp": _bool,
             "gap": _real(unit="m"),
             # name = "ModalBeam": ModalBeam.paper(...) (docs/modal_beam.md), m, k, b not taken
             "n_modes": _int(1, 20), "bc": _choice(BOUNDARY_CONDITIONS),
             "stop_ratio": _real(0, 1, lo_open=True), "zeta": _real(0)}
MODAL_KEYS = ("n_modes", "bc", "stop_ratio", "zeta")
#: name = "System": a general System
SYSTEM_KEYS = {"name": _choice(MODEL_NAMES), "M": _matrix, "C": _matrix, "K": _matrix,
               "excitation_kind": _choice(("base", "force")), "y_load": _vector,
               "yd_load": _vector, "output_dof": _int(0), "elements": None}
#: factory = "module:function" and its keyword arguments
FACTORY_KEYS = {"factory": None, "args": None}
#: the element classes a [[model.elements]] table may name (``type``)
ELEMENT_TYPES = {"Contact": nlbeam.Contact, "PiecewiseLinearStop": nlbeam.PiecewiseLinearStop,
                 "CubicSpring": nlbeam.CubicSpring}
#: units of the parameters (sweep legends and table columns; element fields by field name)
PARAMETER_UNITS = {"m": "kg", "k": "N/m", "b": "kg/s", "K_hertz": "N/m^1.5", "e": "",
                   "mu": "N s/m^2.5", "gap": "m", "K": "N/m^1.5", "k3": "N/m^3",
                   "zeta": "", "stop_ratio": "", "n_modes": "", "amplitude": "m", "rms": "m",
                   "psd_level": "m^2/Hz", "band": "Hz", "band[0]": "Hz", "band[1]": "Hz",
                   "lowpass": "Hz", "seed": "", "duration": "s"}


def _field_check(name):
    return {"dof": _dof, "law": _choice(CONTACT_LAWS), "side": _choice((1, -1)),
            "on_base": _bool, "clamp": _bool}.get(
        name, _real(unit=PARAMETER_UNITS.get(name, "")))


#: the keys of each element type: ``type`` and the fields of its class (one definition)
ELEMENT_KEYS = {t: {"type": _choice(tuple(ELEMENT_TYPES)),
                    **{f.name: _field_check(f.name) for f in dataclasses.fields(cls) if f.init}}
                for t, cls in ELEMENT_TYPES.items()}
#: every key the [model] section takes, of any kind (documented in docs/usage.md)
MODEL_KEYS = {**BEAM_KEYS, **SYSTEM_KEYS, **FACTORY_KEYS}


def _kind(data):
    if "factory" in data:
        return "factory"
    return data.get("name", "BeamImpact")


def check_model(data, fail):
    """The [model] table ``data`` checked key by key; ``fail(path, message, value=None)``
    raises (path: ('model', key), ('model.elements', i, key), ('model.args', key)).
    Returns the clean spec (name dropped for the paper beam, as before)."""
    if not isinstance(data, dict):
        fail(("model",), "must be a table")
    kind = _kind(data)
    keys = {"factory": FACTORY_KEYS, "System": SYSTEM_KEYS}.get(kind, BEAM_KEYS)
    out = {}
    for k, v in data.items():
        if k not in keys:
            what = {"factory": "a factory model (factory, args)",
                    "System": "name = 'System'"}.get(kind, "the beam models")
            fail(("model", k), f"unknown key for {what}; allowed: {', '.join(keys)}")
        chk = keys[k]
        if chk is None:
            out[k] = v
            continue
        val, err = chk(v)
        if err:
            fail(("model", k), err, v)
        out[k] = val
    if kind == "factory":
        _check_factory(out, fail)
    elif kind == "System":
        _check_system(out, fail)
    elif out.get("name") != "ModalBeam":
        out.pop("name", None)
    return out


def _check_factory(out, fail):
    ref = out["factory"]
    if not isinstance(ref, str) or ref.count(":") != 1 or not all(ref.split(":")):
        fail(("model", "factory"), "must be 'module:function' (e.g. 'mypkg.rigs:two_dof')", ref)
    args = out.setdefault("args", {})
    if not isinstance(args, dict):
        fail(("model", "args"), "must be a table of keyword arguments: write [model.args]")
    try:
        _factory(ref)
    except ValueError as exc:
        fail(("model", "factory"), str(exc), ref)


def _factory(ref):
    mod, fn = ref.split(":")
    try:
        module = importlib.import_module(mod)
    except ImportError as exc:
        raise ValueError(f"cannot import module {mod!r} ({exc}); put it on the Python path "
                         "(PYTHONPATH) or install it") from None
    func = getattr(module, fn, None)
    if not callable(func):
        raise ValueError(f"module {mod!r} has no function {fn!r}")
    return func


def _check_system(out, fail):
    for req in ("M", "K"):
        if req not in out:
            fail(("model",), f"name = 'System' needs {req} (a square matrix, list of rows)")
    els = out.get("elements", [])
    if not isinstance(els, list):
        fail(("model", "elements"), "must be an array of tables: write [[model.elements]]")
    clean = []
    for i, el in enumerate(els):
        if not isinstance(el, dict):
            fail(("model.elements", i), "must be a table")
        t = el.get("type")
        if t not in ELEMENT_TYPES:
            fail(("model.elements", i, "type"),
                 f"must be one of {', '.join(map(repr, ELEMENT_TYPES))}", t)
        d = {}
        for k, v in el.items():
            keys = ELEMENT_KEYS[t]
            if k not in keys:
                fail(("model.elements", i, k), f"unknown key for a {t}; allowed: "
                     f"{', '.join(keys)}")
            val, err = keys[k](v)
            if err:
                fail(("model.elements", i, k), err, v)
            d[k] = val
        clean.append(d)
    out["elements"] = clean


def _element(d):
    kw = {k: v for k, v in d.items() if k != "type"}
    return ELEMENT_TYPES[d["type"]](**kw)


def build_model(spec):
    """The model of a [model] spec (module doc); the objects' own checks raise ValueError
    naming the key ('key: ...'; an element's as 'elements[i].key: ...')."""
    kind = _kind(spec)
    if kind == "factory":
        model = _factory(spec["factory"])(**spec.get("args", {}))
        sysm = getattr(model, "system", None)
        if not isinstance(sysm, nlbeam.System):
            raise ValueError(f"factory: {spec['factory']} returned a {type(model).__name__}, "
                             "not an nlbeam.System or a model with a .system (BeamImpact, ...)")
        return model
    if kind == "System":
        elements = []
        for i, d in enumerate(spec.get("elements", [])):
            try:
                elements.append(_element(d))
            except ValueError as exc:
                raise ValueError(f"elements[{i}].{exc}") from None
        n = len(spec["M"])
        return nlbeam.System(spec["M"], spec.get("C", np.zeros((n, n))), spec["K"],
                             tuple(elements), spec.get("excitation_kind", "base"),
                             y_load=spec.get("y_load"), yd_load=spec.get("yd_load"),
                             output_dof=spec.get("output_dof"))
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


def model_parameters(spec):
    """{name: (path in the spec, check)} of the parameters a sweep may vary: the paper beam's
    numeric keys (m, k, b, K_hertz, e, mu, gap), the modal beam's (n_modes, stop_ratio, zeta,
    gap, K_hertz, e, mu), a System's element fields ``elements[i].field`` (as
    nlbeam.parameters names them), a factory's keyword arguments by name."""
    kind = _kind(spec)
    if kind == "factory":
        return {k: (("args", k), None) for k in spec.get("args", {})}
    if kind == "System":
        out = {}
        for i, d in enumerate(spec.get("elements", [])):
            for f in dataclasses.fields(ELEMENT_TYPES[d["type"]]):
                if f.init and f.name not in ("dof", "side", "on_base", "clamp", "law"):
                    out[f"elements[{i}].{f.name}"] = (("elements", i, f.name),
                                                      ELEMENT_KEYS[d["type"]][f.name])
        return out
    names = ("n_modes", "stop_ratio", "zeta", "gap", "K_hertz", "e", "mu") \
        if spec.get("name") == "ModalBeam" else ("m", "k", "b", "K_hertz", "e", "mu", "gap")
    return {k: ((k,), BEAM_KEYS[k]) for k in names}


def system_digest(model) -> str:
    """SHA-256 of the arrays that define ``model``'s system (M, C, K, loads, element table,
    output DOF, excitation kind, a custom force's source): what a factory's result is keyed by."""
    s = model.system
    h = hashlib.sha256()
    et, ew, ewy, eg = s.element_geometry()
    a = s.kernel_arrays()
    for arr in (s.M, s.C, s.K, s.y_load, s.yd_load, et, ew, ewy, eg, a.epar, a.upar):
        arr = np.ascontiguousarray(arr)
        h.update(str((arr.dtype.str, arr.shape)).encode())
        h.update(arr.tobytes())
    h.update(f"{s.excitation_kind}|{s.output_dof}|{s.name}".encode())
    if s.custom_force is not None:
        f = getattr(s.custom_force, "py_func", s.custom_force)
        try:
            h.update(inspect.getsource(f).encode())
        except (OSError, TypeError):
            h.update(f"{f.__module__}.{f.__qualname__}".encode())
    return h.hexdigest()


def model_inputs(spec, defaults_model):
    """The model as the cache keys it: the paper beam with the constructor's defaults filled
    in (a default written out and one left out share an entry); a factory with the digest of
    the system it returns (``system_sha256``); the other kinds as written."""
    kind = _kind(spec)
    if kind == "factory":
        return dict(spec, system_sha256=system_digest(build_model(spec)))
    if kind != "BeamImpact":
        return spec
    full = {k: v for k, v in defaults_model.items() if v is not None}
    full.update((k, v) for k, v in spec.items() if k != "name")
    return full
