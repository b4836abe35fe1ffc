"""Result files you can trust: every HDF5 result carries its format (name and version, one
attribute ``format`` = "<name>/<version>"), the nlbeam that wrote it (``written_by``) and a
SHA-256 of every dataset (name, dtype, shape, bytes) and of all attributes (``checksums``,
JSON). ``write_result`` has the file built in memory (HDF5 never writes to the disk, so a full
or read-only disk fails in Python, cleanly) and hands the bytes to ``write_bytes_atomic``.
``read_result`` refuses, in one line each: a missing, empty, non-HDF5 or truncated file, a
result of the other kind, a newer format, a changed dataset or attribute, and a file that
lacks what its format holds. Files written before this stamp (format 1: no checksums) load
with a ``LegacyResultWarning``; one whose nlbeam version is newer than this one is refused.
A stamped file of a known format written by a newer nlbeam loads with a
``NewerWriterWarning`` (the format version is the contract; the warning says so).
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import re
import warnings

import h5py
import numpy as np

from .atomic import write_bytes_atomic

__all__ = ["ResultFileError", "LegacyResultWarning", "NewerWriterWarning", "FORMATS",
           "write_result", "read_result", "verify_result"]

# format name -> (current version, what the user calls to load it)
FORMATS = {"nlbeam.frequency_response": (2, "continuation.load"),
           "nlbeam.stochastic.result": (2, "stochastic.load"),
           # first written stamped: version 2 (version 1 means unstamped, legacy)
           "nlbeam.bifurcation_curves": (2, "continuation.load_curves")}
_KIND = {"nlbeam.frequency_response": "a frequency-response result",
         "nlbeam.stochastic.result": "a stochastic result",
         "nlbeam.bifurcation_curves": "a bifurcation-curve result"}
_STAMP = ("format", "written_by", "checksums")  # attributes the checksum does not cover
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class ResultFileError(ValueError):
    """A result file that cannot be trusted or read; ``reason`` is one of 'empty',
    'not-hdf5', 'truncated', 'wrong-kind', 'newer-format', 'corrupted', 'incomplete',
    'unknown'."""

    def __init__(self, message, reason):
        super().__init__(message)
        self.reason = reason


class NewerWriterWarning(UserWarning):
    """A result file of a format this nlbeam reads, written by a newer nlbeam."""


class LegacyResultWarning(UserWarning):
    """A result file written before files carried checksums: read, but not verified."""


def _version_tuple(text):
    return tuple(int(x) for x in re.findall(r"\d+", str(text))[:3])


def _value_bytes(v):
    """Canonical bytes of a dataset's or attribute's value (dtype, shape, contents)."""
    if isinstance(v, (bytes, str)):
        return b"s:" + (v.encode() if isinstance(v, str) else v)
    a = np.asarray(v)
    head = f"{a.dtype.str}:{a.shape}:".encode()
    if a.dtype.kind == "O":  # variable-length strings
        return head + b"\0".join(x.encode() if isinstance(x, str) else bytes(x)
                                 for x in a.ravel())
    return head + np.ascontiguousarray(a).tobytes()


def _checksums(h):
    """{"datasets": {name: sha256}, "attributes": sha256 of every attribute but the stamp}."""
    sums = {}
    attrs = hashlib.sha256()
    objs = [("/", h)]
    h.visititems(lambda name, obj: objs.append((name, obj)))
    for name, obj in sorted(objs, key=lambda t: t[0]):
        if isinstance(obj, h5py.Dataset):
            try:
                sums[name] = hashlib.sha256(_value_bytes(obj[()])).hexdigest()
            except (OSError, ValueError, TypeError) as err:  # damaged beyond reading
                sums[name] = f"unreadable: {err}"
        for k in sorted(obj.attrs):
            if name == "/" and k in _STAMP:
                continue
            attrs.update(f"{name}@{k}=".encode() + _value_bytes(obj.attrs[k]) + b"\n")
    return {"datasets": sums, "attributes": attrs.hexdigest()}


@contextlib.contextmanager
def write_result(path, name):
    """Yield an in-memory file object for ``h5py.File(obj, "w")`` that receives a result of
    format ``name``; on leaving, stamp it (format, writer, checksums) and write its bytes to
    ``path`` atomically. On any failure nothing is left at ``path``, no temporary either."""
    import nlbeam

    version = FORMATS[name][0]
    buf = io.BytesIO()
    yield buf
    with h5py.File(buf, "r+") as h:
        h.attrs["checksums"] = json.dumps(_checksums(h), sort_keys=True)
        h.attrs["format"] = f"{name}/{version}"
        h.attrs["written_by"] = f"nlbeam {nlbeam.__version__}"
    write_bytes_atomic(path, buf.getbuffer())


def _text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def _open(path):
    """h5py.File of ``path`` for reading, or one line saying why it cannot be."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(2, f"{path}: no such file")
    if os.path.isdir(path):
        raise ResultFileError(f"{path}: is a folder, not a result file", "not-hdf5")
    size = os.path.getsize(path)
    if size == 0:
        raise ResultFileError(f"{path}: empty file (0 bytes), not a result", "empty")
    try:
        return h5py.File(path, "r")
    except OSError:
        with open(path, "rb") as fh:
            head = fh.read(8)
        if head == _HDF5_SIGNATURE:
            raise ResultFileError(f"{path}: truncated or damaged HDF5 file ({size} bytes): "
                                  "recompute or copy it again", "truncated") from None
        hint = (": a measured record (CSV) is read by stochastic.analyze (nlbeam analyze)"
                if head[:1].isalpha() or head[:1] in (b"#", b'"') else "")
        raise ResultFileError(f"{path}: not an HDF5 file (first bytes {head[:8]!r}), not a "
                              f"result{hint}", "not-hdf5") from None


def _format_of(h):
    """(name, version) of an open file; files before the stamp get version 1."""
    fmt = _text(h.attrs.get("format", ""))
    if "/" in fmt:
        name, _, ver = fmt.rpartition("/")
        if ver.isdigit():
            return name, int(ver)
    if not fmt and "branches" in h and "version" in h.attrs:
        return "nlbeam.frequency_response", 1  # written before the stamp
    return fmt or None, None


def verify_result(h, path, name):
    """Check the open file ``h`` is a ``name`` result this nlbeam can read, unchanged since
    written. Returns the root attributes of the stamp (dict); raises ResultFileError."""
    import nlbeam

    path = os.fspath(path)
    have, version = _format_of(h)
    if have != name:
        if have in FORMATS:
            raise ResultFileError(f"{path}: this is {_KIND[have]}, use "
                                  f"{FORMATS[have][1]}", "wrong-kind")
        raise ResultFileError(f"{path}: not an nlbeam result file (format "
                              f"{have!r}); {FORMATS[name][1]} reads {_KIND[name]} file; a "
                              "measured record in HDF5 is read by stochastic.analyze",
                              "unknown")
    newest = FORMATS[name][0]
    if version > newest:
        raise ResultFileError(f"{path}: written by format {version} "
                              f"({_text(h.attrs.get('written_by', '?'))}), this nlbeam "
                              f"{nlbeam.__version__} reads up to {newest}: update nlbeam",
                              "newer-format")
    if version < 2 or "checksums" not in h.attrs:
        wrote = _text(h.attrs.get("version", h.attrs.get("nlbeam_version", "?")))
        if _version_tuple(wrote) > _version_tuple(nlbeam.__version__):
            raise ResultFileError(f"{path}: written by nlbeam {wrote} without a format "
                                  f"stamp; this is nlbeam {nlbeam.__version__}: update "
                                  "nlbeam", "newer-format")
        warnings.warn(f"{path}: written before result files carried checksums (nlbeam "
                      f"{wrote}): read without verification; save it again to add them",
                      LegacyResultWarning, stacklevel=4)
        return {}
    try:
        want = json.loads(_text(h.attrs["checksums"]))
        have_sums = _checksums(h)
    except (ValueError, KeyError, TypeError, OSError) as err:
        raise ResultFileError(f"{path}: corrupted: cannot read its checksums or data "
                              f"({err})", "corrupted") from None
    for ds in sorted(set(want["datasets"]) | set(have_sums["datasets"])):
        if ds not in have_sums["datasets"]:
            raise ResultFileError(f"{path}: corrupted: dataset {ds!r} is missing",
                                  "corrupted")
        if ds not in want["datasets"]:
            raise ResultFileError(f"{path}: corrupted: dataset {ds!r} was added after "
                                  "writing", "corrupted")
        if want["datasets"][ds] != have_sums["datasets"][ds]:
            why = have_sums["datasets"][ds]
            why = why if why.startswith("unreadable") else "does not match its checksum"
            raise ResultFileError(f"{path}: corrupted: dataset {ds!r} {why} (changed after "
                                  "writing)", "corrupted")
    if want["attributes"] != have_sums["attributes"]:
        raise ResultFileError(f"{path}: corrupted: its attributes (metadata) do not match "
                              "their checksum (changed after writing)", "corrupted")
    wrote = _text(h.attrs.get("written_by", ""))
    if _version_tuple(wrote) > _version_tuple(nlbeam.__version__):
        warnings.warn(f"{path}: written by {wrote}, this is nlbeam {nlbeam.__version__}: "
                      f"read as format {version}, which this version knows; update nlbeam "
                      "for anything the newer one adds", NewerWriterWarning, stacklevel=4)
    return {k: h.attrs[k] for k in h.attrs}


@contextlib.contextmanager
def read_result(path, name):
    """Yield the open, verified h5py.File of a ``name`` result at ``path`` (see
    ``verify_result``); a reader that misses a dataset or attribute inside raises
    ResultFileError naming the file instead of h5py's KeyError."""
    h = _open(path)
    with h:
        verify_result(h, path, name)
        try:
            yield h
        except (KeyError, TypeError, IndexError, AttributeError) as err:
            raise ResultFileError(f"{os.fspath(path)}: incomplete {_KIND[name]} file: "
                                  f"{type(err).__name__}: {err}", "incomplete") from None
