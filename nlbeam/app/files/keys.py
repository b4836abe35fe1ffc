"""Content keys (standard library only): a canonical JSON text of a dict of inputs and its
SHA-256, so that equal inputs name the same cache file (scenes).
"""
from __future__ import annotations

import hashlib
import json
import math

__all__ = ["canonical_json", "content_key"]


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
