"""Atomic writes (standard library only): every output file of the application floor (HDF5
results, figures, tables, cache sidecars) is written to a temporary name in its own folder
and renamed over the target (``os.replace``), so a reader never sees half a file and a
failure leaves none.
"""
from __future__ import annotations

import contextlib
import os
import secrets

__all__ = ["atomic_path", "write_text_atomic"]


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
