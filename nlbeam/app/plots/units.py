"""One table of units for every figure: what a channel is measured in, how it is drawn, and
the label style (``quantity [unit]``, square brackets everywhere)."""
from __future__ import annotations

import re

import numpy as np

__all__ = ["excitation_kind", "channel_unit", "axis_label", "psd_label", "log_limits",
           "legend_outside"]

#: channel kind -> (SI unit, drawn unit, factor SI -> drawn) for base excitation
_BASE = {"x": ("m", "mm", 1e3), "delta": ("m", "mm", 1e3), "y": ("m", "mm", 1e3),
         "v": ("m/s", "m/s", 1.0), "yd": ("m/s", "m/s", 1.0), "force": ("N", "N", 1.0)}
#: under force excitation the excitation channels are a force and its rate
_FORCE = dict(_BASE, y=("N", "N", 1.0), yd=("N/s", "N/s", 1.0))


def excitation_kind(parameters):
    """'base' or 'force' from a result's ``model_parameters`` (base unless it says force;
    ``Duffing`` is force-excited)."""
    p = parameters or {}
    if p.get("excitation_kind") == "force" or p.get("model") == "Duffing":
        return "force"
    return "base"


def channel_unit(ch, kind="base"):
    """(SI unit, drawn unit, factor) of channel ``ch`` ('x', 'x[1]', 'delta[0]', ...)."""
    m = re.fullmatch(r"(x|v|y|yd|delta|force)(?:\[\d+\])?", str(ch))
    if m is None:
        raise ValueError(f"ch: unknown channel {ch!r}")
    return (_FORCE if kind == "force" else _BASE)[m.group(1)]


def axis_label(quantity, unit):
    return f"{quantity} [{unit}]"


def psd_label(ch, kind="base"):
    """Axis label of a one-sided PSD of ``ch``, in SI units (unit^2/Hz)."""
    si = channel_unit(ch, kind)[0]
    unit = f"({si})$^2$/Hz" if "/" in si else f"{si}$^2$/Hz"
    return f"PSD of {ch} [{unit}]"


def log_limits(values, decades=8.0):
    """(bottom, top) of a log axis for the positive ``values`` drawn: from a factor 3 above the
    largest down to the smallest, but at most ``decades`` below the largest (a leakage floor
    or a band-edge roll-off would otherwise stretch the axis over 20 decades)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size == 0:
        return None
    top = float(v.max()) * 3.0
    return max(float(v.min()) / 2.0, top * 10.0 ** -decades), top


def legend_outside(ax, **kw):
    """The legend of ``ax`` to the right of the axes, its top at theirs (font size 8; kw: more
    options of ``ax.legend``)."""
    return ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), **kw)
