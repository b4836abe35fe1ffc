"""Small file helpers: atomic writes and content keys (standard library only, so every layer
may use them: the analyses' save functions, scenes, the command line).

Every output file is written to a temporary name in its own folder and renamed over the
target (``os.replace``), so a reader never sees half a file and a failure leaves none.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import secrets

__all__ = ["atomic_path", "write_text_atomic", "canonical_json", "content_key"]


@contextlib.contextmanager
def atomic_path(path, suffix=""):
    """Yield a temporary path beside ``path``; on success rename it to ``path``, on any
    exception remove it (and re-raise). ``suffix`` helps writers that look at the extension
    (matplotlib). The temporary file is created with mode 0666 minus the umask, like any
    new file (``tempfile.mkstemp`` would make it 0600, and the rename would keep that)."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    suffix = suffix or os.path.splitext(path)[1]
    for _ in range(100):
        tmp = os.path.join(folder, f".tmp-{secrets.token_hex(6)}{suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        break
    else:  # pragma: no cover - 100 collisions of 48 random bits
        raise FileExistsError(f"{path}: no free temporary name in {folder}")
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
