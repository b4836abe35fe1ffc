"""Drop numba's on-disk kernel caches when any kernel source changed.

numba keys a cached kernel by the timestamp and size of the file that defines it, not of the
files whose functions it inlines: after ``excite.py`` changes, ``loop.py``'s cached
``integrate_kernel`` would still run the old excitation code. Before any kernel is compiled or
loaded, the SHA-256 of every kernel source (and the Python and numba versions) is compared with
the stamp left in ``__pycache__``; if they differ, the cached ``*.nbi``/``*.nbc`` files there
are removed, so every kernel compiles again from the sources it is built from.
Standard library only; a read-only install (nothing can be removed or stamped) is left as is.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

STAMP = "kernel_sources.sha256"


def sources_digest(sources, extra=()):
    """SHA-256 (hex) of the files ``sources`` (their names and bytes, sorted by name) and the
    strings ``extra``."""
    h = hashlib.sha256()
    for path in sorted(map(Path, sources), key=lambda p: p.name):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    for s in extra:
        h.update(str(s).encode() + b"\0")
    return h.hexdigest()


def drop_stale(cache_dir, sources, extra=()):
    """Remove numba's cache files in ``cache_dir`` unless its stamp equals the digest of
    ``sources``; then write the stamp. Returns the number of files removed."""
    cache_dir = Path(cache_dir)
    digest = sources_digest(sources, extra)
    stamp = cache_dir / STAMP
    try:
        if stamp.read_text().strip() == digest:
            return 0
    except OSError:
        pass
    removed = 0
    try:
        cache_dir.mkdir(exist_ok=True)
        for f in cache_dir.iterdir():
            if f.suffix in (".nbi", ".nbc"):
                f.unlink()
                removed += 1
        tmp = cache_dir / f".{STAMP}.{os.getpid()}"
        tmp.write_text(digest + "\n")
        os.replace(tmp, stamp)
    except OSError:  # read-only install, or another process is doing the same
        pass
    return removed


def check_package():
    """The check for this package's kernels (called once, when ``nlbeam._kernels`` loads)."""
    here = Path(__file__).resolve().parent
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:  # pragma: no cover - numba is a dependency
        numba_version = "?"
    return drop_stale(here / "__pycache__", sorted(here.glob("*.py")),
                      extra=(sys.version, numba_version))
