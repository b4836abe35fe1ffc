"""Argument checks that raise ``ValueError`` naming the parameter and the allowed range."""
from __future__ import annotations

import math


def _num(name, value):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a real number, got {value!r}") from None
    return v


def finite(name, value):
    v = _num(name, value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    return v


def positive(name, value, unit=""):
    v = _num(name, value)
    if not (math.isfinite(v) and v > 0):
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name}: must be finite and > 0{u}, got {value!r}")
    return v


def nonnegative(name, value, unit=""):
    v = _num(name, value)
    if not (math.isfinite(v) and v >= 0):
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name}: must be finite and >= 0{u}, got {value!r}")
    return v


def in_range(name, value, lo, hi, lo_open=False, hi_open=False):
    v = _num(name, value)
    ok = math.isfinite(v)
    ok = ok and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ValueError(f"{name}: must lie in {lb}{lo}, {hi}{rb}, got {value!r}")
    return v


def choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name}: must be one of {', '.join(repr(a) for a in allowed)}, got "
                         f"{value!r}")
    return value
