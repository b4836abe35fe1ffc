"""The checks of a scene file's values: each ``check(value) -> (clean value, None)`` or
``(None, what the value must be)``; the schema (``schema``, ``models``) names them per key.
"""
from __future__ import annotations

import math
import os

from nlbeam.vocabulary import CHANNELS

__all__ = ["_real", "_int", "_choice", "_bool", "_str", "_pair", "_pair_int", "_int_list",
           "_channels", "_file", "_matrix", "_vector", "_dof", "_accuracy"]


# -- value checks --------------------------------------------------------------------------------
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


def _pair_int(lo, hi):
    def check(v):
        if not isinstance(v, list) or len(v) != 2 or any(
                isinstance(x, bool) or not isinstance(x, int) or not lo <= x <= hi for x in v):
            return None, f"must be a pair [a, b] of integers in [{lo}, {hi}]"
        return [int(v[0]), int(v[1])], None
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


def _vector(v, n=None):
    """A finite vector (list of numbers), of length n when given."""
    if not isinstance(v, list) or not v or any(
            isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x)
            for x in v):
        return None, "must be a non-empty list of finite numbers"
    if n is not None and len(v) != n:
        return None, f"must have {n} entries (the number of DOFs)"
    return [float(x) for x in v], None


def _matrix(v):
    """A square matrix of finite numbers, as a list of rows."""
    if not isinstance(v, list) or not v or any(not isinstance(r, list) for r in v):
        return None, "must be a square matrix: a list of rows, e.g. [[1.0, 0.0], [0.0, 2.0]]"
    rows = []
    for r in v:
        row, err = _vector(r, len(v))
        if err:
            return None, "must be a square matrix of finite numbers (each row " + err[5:] + ")"
        rows.append(row)
    return rows, None


def _dof(v):
    """A DOF index (integer >= 0) or a location vector of numbers."""
    if isinstance(v, int) and not isinstance(v, bool):
        return (int(v), None) if v >= 0 else (None, "must be a DOF index >= 0 or a vector")
    vec, err = _vector(v)
    return (vec, None) if not err else (None, "must be a DOF index >= 0 or a vector of numbers")


def _accuracy(v):
    """continuation's accuracy: 'default', 'high', 'off' or a number of digits in [3, 12]."""
    if isinstance(v, str) and v in ("default", "high", "off"):
        return v, None
    if not isinstance(v, bool) and isinstance(v, (int, float)) and 3 <= v <= 12:
        return float(v), None
    return None, "must be 'default', 'high', 'off' or a number of significant digits in [3, 12]"
