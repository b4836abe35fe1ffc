"""Measured data as named columns: a CSV file with a header line (comma-separated; ``#``
starts a comment) or an HDF5 file whose root holds one 1-D dataset per column."""
from __future__ import annotations

import os

import numpy as np

__all__ = ["read_columns"]


def _csv(path):
    with open(path, encoding="utf-8-sig") as fh:
        lines = [ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"{path}: no header line (the column names, comma-separated)")
    names = [n.strip() for n in lines[0].split(",")]
    if len(set(names)) != len(names) or not all(names):
        raise ValueError(f"{path}: line 1: the header must name every column once, got {names}")
    rows = []
    for k, ln in enumerate(lines[1:], start=2):
        cells = ln.split(",")
        if len(cells) != len(names):
            raise ValueError(f"{path}: data line {k}: {len(cells)} values, the header names "
                             f"{len(names)} columns")
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            raise ValueError(f"{path}: data line {k}: a value is not a number: "
                             f"{ln.strip()[:80]!r}") from None
    data = np.array(rows, dtype=float).reshape(-1, len(names))
    return {n: data[:, i].copy() for i, n in enumerate(names)}


def _hdf5(path):
    import h5py

    try:
        with h5py.File(path, "r") as fh:
            return {k: np.asarray(v[()], dtype=float) for k, v in fh.items()
                    if isinstance(v, h5py.Dataset) and v.ndim == 1}
    except OSError as err:
        raise ValueError(f"{path}: not a readable HDF5 file ({err})") from None


def read_columns(path, required=()):
    """{name: 1-D float array} of the file at ``path`` (.csv, or .h5/.hdf5). Every name in
    ``required`` must be present; the error lists the columns the file has."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    ext = os.path.splitext(path)[1].lower()
    cols = _hdf5(path) if ext in (".h5", ".hdf5") else _csv(path)
    missing = [n for n in required if n not in cols]
    if missing:
        raise ValueError(f"{path}: no column {missing[0]!r}; the file has "
                         f"{', '.join(repr(c) for c in cols) or 'none'}")
    if cols and len({len(v) for v in cols.values()}) > 1:
        raise ValueError(f"{path}: the columns have different lengths")
    return cols
