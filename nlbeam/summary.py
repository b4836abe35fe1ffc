"""Short text and HTML views of results (for a terminal and a notebook): each field on one
line, arrays as their shape and range, lists and dicts as counts, never the whole data.

A result class inherits ``Summary`` (its dataclass declared with ``repr=False``) and may
override ``_summary_rows()`` to put computed lines (counts by kind, ranges in units) before
or instead of the field lines. ``repr(obj)`` is then a few hundred characters whatever the
data, and ``obj._repr_html_()`` a two-column table Jupyter shows.
"""
from __future__ import annotations

import dataclasses
import html

import numpy as np

__all__ = ["Summary", "describe_value", "field_rows", "MAX_TEXT"]

MAX_TEXT = 70  # characters of a string or a nested repr shown before '...'


def _num(v):
    v = float(v)
    return f"{v:.6g}"


def _clip(text):
    text = str(text).replace("\n", " ")
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 3] + "..."


def describe_value(v):
    """One short line for ``v``: an array as 'float64 (n, m), min .. max' (complex by modulus,
    bool as a count of True, NaN counted), a list or tuple of objects as 'n Name', a dict as
    'n entries', a number to 6 digits, anything else its repr clipped to MAX_TEXT."""
    if v is None:
        return "None"
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return _num(v)
    if isinstance(v, (complex, np.complexfloating)):
        return f"{complex(v):.4g}"
    if isinstance(v, str):
        return _clip(v)
    if isinstance(v, np.ndarray):
        return _describe_array(v)
    if isinstance(v, (list, tuple)):
        if len(v) <= 6 and all(isinstance(x, (int, float, str, np.integer, np.floating))
                               for x in v):
            inner = ", ".join(repr(x) if isinstance(x, str) else describe_value(x) for x in v)
            return _clip(f"[{inner}]" if isinstance(v, list) else f"({inner})")
        names = sorted({type(x).__name__ for x in v})
        return f"{len(v)} {'/'.join(names) if names else 'items'}"
    if isinstance(v, dict):
        if len(v) <= 4 and all(isinstance(x, (int, float, str, bool)) for x in v.values()):
            return _clip(", ".join(f"{k}={x!r}" for k, x in v.items()))
        return f"{len(v)} entries"
    return _clip(repr(v))


def _describe_array(a):
    head = f"{a.dtype} {a.shape}"
    if a.size == 0:
        return f"{head}, empty"
    if a.dtype == bool:
        return f"{head}, {int(np.count_nonzero(a))} True"
    if np.issubdtype(a.dtype, np.complexfloating):
        m = np.abs(a)
        fin = m[np.isfinite(m)]
        rng = f"|.| {_num(fin.min())} .. {_num(fin.max())}" if fin.size else "all NaN"
    elif np.issubdtype(a.dtype, np.number):
        fin = a[np.isfinite(a)]
        rng = f"{_num(fin.min())} .. {_num(fin.max())}" if fin.size else "all NaN"
        if a.size == 1 and fin.size:
            rng = _num(fin[0])
    else:
        return head
    n_nan = a.size - int(np.count_nonzero(np.isfinite(a)))
    return f"{head}, {rng}" + (f", {n_nan} NaN" if n_nan else "")


def field_rows(obj, skip=()):
    """(name, short text) of every dataclass field of ``obj`` not in ``skip``."""
    return [(f.name, describe_value(getattr(obj, f.name)))
            for f in dataclasses.fields(obj) if f.name not in skip]


class Summary:
    """Mixin: a short ``__repr__`` and a ``_repr_html_`` table from ``_summary_rows()``."""

    def _summary_rows(self):
        return field_rows(self)

    def _summary_title(self):
        return type(self).__name__

    def __repr__(self):
        rows = self._summary_rows()
        width = max((len(k) for k, _ in rows), default=0)
        lines = [f"  {k:<{width}} : {v}" for k, v in rows]
        return "\n".join([f"{self._summary_title()}("] + lines + [")"])

    def _repr_html_(self):
        cells = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                        f"<td style='text-align:left'>{html.escape(v)}</td></tr>"
                        for k, v in self._summary_rows())
        return (f"<table><caption style='text-align:left'><b>"
                f"{html.escape(self._summary_title())}</b></caption>{cells}</table>")
