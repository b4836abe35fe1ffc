"""Small file helpers of the top layer: atomic writes and content keys.

Every output file is written to a temporary name in its own folder and renamed over the
target (``os.replace``), so a reader never sees half a file and a failure leaves none.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import tempfile

__all__ = ["atomic_path", "write_text_atomic", "canonical_json", "content_key"]


@contextlib.contextmanager
def atomic_path(path, suffix=""):
    """Yield a temporary path beside ``path``; on success rename it to ``path``, on any
    exception remove it. ``suffix`` helps writers that look at the extension (matplotlib)."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix or os.path.splitext(path)[1],
                               dir=folder)
    os.close(fd)
    mask = os.umask(0o022)
    os.umask(mask)
    os.chmod(tmp, 0o666 & ~mask)  # mkstemp makes 0600; give the file the usual mode
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(tmp)
        raise


def write_text_atomic(path, text):
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


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
