"""Bifurcation curves (``continuation.BifurcationCurve``) and stability charts
(``continuation.StabilityChart``) as HDF5 files.

Attribute ``what``: 'curve' (one curve) or 'chart'. A chart's attributes: version, parameter,
amplitude, f_range, p_range, wall_time, n_evaluations, ``model.<name>``, ``settings.<name>``;
datasets label_frequency, label_value, label_order, skipped (strings). Group
``curves/NNNN`` per curve: attributes kind, order, parameter, ends, f_range, p_range,
n_evaluations, wall_time, version, ``model.<name>``, ``settings.<name>``; datasets frequency,
values, amplitude, xmax, multipliers (absent without), state0, phase, n_impacts, exact, error;
group ``special`` with datasets kind, note, frequency, value, error_frequency, error_value,
index (one row per codimension-2 point).
"""
from __future__ import annotations

import h5py
import numpy as np

from continuation.chart import StabilityChart
from continuation.curve import BifurcationCurve, Codim2

from .stamped_hdf5 import read_result, write_result

__all__ = ["save_curves", "load_curves"]

FORMAT = "nlbeam.bifurcation_curves"  # and version: see stamped_hdf5.FORMATS
_ARRAYS = ("frequency", "values", "amplitude", "xmax", "multipliers", "state0", "phase",
           "n_impacts", "exact", "error")
_SPECIAL = ("frequency", "value", "error_frequency", "error_value", "index")


def _attrs(h, params, settings):
    for k, v in params.items():
        h.attrs[f"model.{k}"] = "None" if v is None else v
    for k, v in settings.items():
        h.attrs[f"settings.{k}"] = "None" if v is None else v


def _write_curve(g, c):
    g.attrs["kind"] = c.kind
    g.attrs["order"] = c.order
    g.attrs["parameter"] = c.parameter
    g.attrs["ends"] = np.array([str(e) for e in c.ends], dtype="S")  # no limit: ends name stretches
    g.attrs["f_range"] = np.asarray(c.f_range, dtype=float)
    g.attrs["p_range"] = np.asarray(c.p_range, dtype=float)
    g.attrs["n_evaluations"] = c.n_evaluations
    g.attrs["wall_time"] = c.wall_time
    g.attrs["version"] = c.version
    _attrs(g, c.model_parameters, c.settings)
    for name in _ARRAYS:
        v = getattr(c, name)
        if v is not None:
            g.create_dataset(name, data=np.asarray(v))
    gs = g.create_group("special")
    gs.create_dataset("kind", data=np.array([s.kind for s in c.special], dtype="S32"))
    gs.create_dataset("note", data=np.array([s.note.encode() for s in c.special],
                                            dtype=h5py.string_dtype()))
    for name in _SPECIAL:
        gs.create_dataset(name, data=np.array([getattr(s, name) for s in c.special],
                                              dtype=float))


def save_curves(obj, path):
    """Write a BifurcationCurve or a StabilityChart to HDF5 at ``path`` (stamped with format
    and checksums, written atomically; stamped_hdf5.write_result)."""
    with write_result(path, FORMAT) as tmp:
        with h5py.File(tmp, "w") as h:
            if isinstance(obj, BifurcationCurve):
                h.attrs["what"] = "curve"
                _write_curve(h.create_group("curves").create_group("0000"), obj)
                return
            h.attrs["what"] = "chart"
            h.attrs["version"] = obj.version
            h.attrs["parameter"] = obj.parameter
            h.attrs["amplitude"] = obj.amplitude
            h.attrs["f_range"] = np.asarray(obj.f_range, dtype=float)
            h.attrs["p_range"] = np.asarray(obj.p_range, dtype=float)
            h.attrs["wall_time"] = obj.wall_time
            h.attrs["n_evaluations"] = obj.n_evaluations
            _attrs(h, obj.model_parameters, obj.settings)
            h.create_dataset("label_frequency", data=np.asarray(obj.label_frequency, float))
            h.create_dataset("label_value", data=np.asarray(obj.label_value, float))
            h.create_dataset("label_order", data=np.asarray(obj.label_order, int))
            h.create_dataset("skipped", data=np.array([s.encode() for s in obj.skipped],
                                                      dtype=h5py.string_dtype()))
            g = h.create_group("curves")
            for i, c in enumerate(obj.curves):
                _write_curve(g.create_group(f"{i:04d}"), c)


def _s(v):
    return v.decode() if isinstance(v, bytes) else (v.item() if hasattr(v, "item") else v)


def _read_prefixed(a, prefix):
    out = {k[len(prefix):]: _s(a[k]) for k in a if k.startswith(prefix)}
    return {k: None if v == "None" else v for k, v in out.items()}


def _read_curve(g):
    a = g.attrs
    gs = g["special"]
    special = [Codim2(kind=gs["kind"][i].decode(), note=_s(gs["note"][i]),
                      frequency=float(gs["frequency"][i]), value=float(gs["value"][i]),
                      error_frequency=float(gs["error_frequency"][i]),
                      error_value=float(gs["error_value"][i]), index=int(gs["index"][i]))
               for i in range(len(gs["kind"]))]
    return BifurcationCurve(
        kind=_s(a["kind"]), order=int(a["order"]), parameter=_s(a["parameter"]),
        ends=tuple(e.decode() for e in a["ends"]), f_range=tuple(a["f_range"]),
        p_range=tuple(a["p_range"]), n_evaluations=int(a["n_evaluations"]),
        wall_time=float(a["wall_time"]), version=_s(a["version"]),
        model_parameters=_read_prefixed(a, "model."),
        settings=_read_prefixed(a, "settings."), special=special,
        **{n: g[n][()] if n in g else None for n in _ARRAYS})


def load_curves(path):
    """Read what ``save_curves`` wrote (a BifurcationCurve or a StabilityChart), after
    checking format and checksums (stamped_hdf5.read_result)."""
    with read_result(path, FORMAT) as h:
        curves = [_read_curve(h["curves"][k]) for k in sorted(h["curves"])]
        if _s(h.attrs["what"]) == "curve":
            return curves[0]
        a = h.attrs
        return StabilityChart(
            curves=curves, parameter=_s(a["parameter"]), amplitude=float(a["amplitude"]),
            f_range=tuple(a["f_range"]), p_range=tuple(a["p_range"]),
            label_frequency=h["label_frequency"][()], label_value=h["label_value"][()],
            label_order=h["label_order"][()],
            skipped=[_s(s) for s in h["skipped"][()]],
            model_parameters=_read_prefixed(a, "model."),
            settings=_read_prefixed(a, "settings."), n_evaluations=int(a["n_evaluations"]),
            wall_time=float(a["wall_time"]), version=_s(a["version"]))
