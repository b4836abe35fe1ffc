"""Content keys (standard library only): a canonical JSON text of a dict of inputs and its
SHA-256, so that equal inputs name the same cache file (scenes).
"""
from __future__ import annotations

import hashlib
import json
import math

__all__ = ["canonical_json", "content_key", "file_sha256", "code_fingerprint",
           "analysis_fingerprint", "ANALYSIS_CODE"]


def _plain(v):
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, bool) or v is None or isinstance(v, str):
        return v
    if isinstance(v, int):
        return int(v)
    if hasattr(v, "item"):
        return _plain(v.item())
    if isinstance(v, float):
        if not math.isfinite(v):
            return repr(v)
        return float(repr(v)) if v != int(v) or abs(v) >= 2 ** 53 else float(v)
    return str(v)


def canonical_json(obj) -> str:
    """JSON with sorted keys, no spaces, tuples as lists and floats by repr: equal inputs
    give equal text."""
    return json.dumps(_plain(obj), sort_keys=True, separators=(",", ":"))


def content_key(obj, length=16) -> str:
    """Hex SHA-256 (first ``length`` digits) of ``canonical_json(obj)``."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:length]


def file_sha256(path) -> str:
    """Hex SHA-256 of the bytes of the file at ``path`` (read in 1 MiB blocks)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


_CODE = {}


def code_fingerprint(packages=("nlbeam", "continuation", "stochastic"), exclude=()) -> str:
    """Hex SHA-256 (16 digits) of the source of ``packages``: every ``.py`` file's path
    (relative) and bytes, sorted, except those under ``exclude`` (paths such as
    'nlbeam/app/plots' or 'nlbeam/app/cli.py'). Changes whenever the code that computes a
    result changes, unlike a hand-kept version string (cache keys use it). Packages are
    located, not imported."""
    import importlib.util
    import os

    key = (tuple(packages), tuple(exclude))
    if key in _CODE:
        return _CODE[key]
    h = hashlib.sha256()
    for pkg in packages:
        spec = importlib.util.find_spec(pkg)
        for root in (spec.submodule_search_locations or []) if spec else []:
            files = []
            for d, dirs, names in os.walk(root):
                dirs[:] = sorted(x for x in dirs if x != "__pycache__")
                files += [os.path.join(d, n) for n in names if n.endswith(".py")]
            for p in sorted(files):
                rel = f"{pkg}/{os.path.relpath(p, root)}".replace(os.sep, "/")
                if any(rel == x or rel.startswith(x.rstrip("/") + "/") for x in exclude):
                    continue
                h.update(f"{rel}\0".encode())
                with open(p, "rb") as fh:
                    h.update(fh.read())
                h.update(b"\0")
    _CODE[key] = h.hexdigest()[:16]
    return _CODE[key]


# the application floor's code that reads results but never computes them: the drawing, the
# tables, the comparison of peaks, the command line, the scene outputs, the kernels' warm-up
_READERS = ("nlbeam/app/plots", "nlbeam/app/cli.py", "nlbeam/app/demo.py",
            "nlbeam/app/compare.py", "nlbeam/app/scenes/outputs.py",
            "nlbeam/app/scenes/numbers.py", "nlbeam/app/warmup.py",
            "nlbeam/app/scenes/batch.py", "nlbeam/app/scenes/empty.py")   # (order, checks)

#: the source each analysis of a scene depends on: (packages, paths left out): an edit of
#: the stochastic package keeps the cached diagrams, one of the plots keeps every result
ANALYSIS_CODE = {
    "periodic": (("nlbeam", "continuation"), _READERS),
    "stochastic": (("nlbeam", "stochastic"), _READERS),
    "chart": (("nlbeam", "continuation"), _READERS),
}


def analysis_fingerprint(kind) -> str:
    """``code_fingerprint`` of the source the analysis ``kind`` ('periodic', 'stochastic')
    depends on (``ANALYSIS_CODE``; 'chart' too)."""
    return code_fingerprint(*ANALYSIS_CODE[kind])
