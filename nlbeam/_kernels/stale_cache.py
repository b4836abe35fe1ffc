"""Drop numba's on-disk kernel caches when any kernel source changed.

numba keys a cached kernel by the timestamp and size of the file that defines it, not of the
files whose functions it inlines: after ``excite.py`` changes, ``loop.py``'s cached
``integrate_kernel`` would still run the old excitation code. Before any kernel is compiled or
loaded, the SHA-256 of every kernel source (and the Python and numba versions) is compared with
the stamp left in the folder where numba keeps this package's cache; if they differ, the cached
``*.nbi``/``*.nbc`` files there are removed, so every kernel compiles again from the sources it
is built from. That folder is the one numba's own cache locator picks for a file of this
package: ``$NUMBA_CACHE_DIR/<package folder>_<hash>`` when NUMBA_CACHE_DIR is set, else the
package's ``__pycache__`` if writable, else numba's per-user cache folder. A folder where
nothing can be removed or stamped is left as is (numba then cannot write there either).
"""
from __future__ import annotations

import hashlib
import inspect
import os
import sys
import warnings
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


def numba_cache_dir(func):
    """The folder in which numba caches the kernels of ``func``'s source file, found by numba's
    own cache locator (it honours NUMBA_CACHE_DIR and NUMBA_CACHE_LOCATOR_CLASSES, and creates
    the folder, as numba does for every cached kernel). A RuntimeWarning and the in-tree
    ``__pycache__`` if this numba has no such locator (a renamed internal)."""
    try:
        from numba.core import caching
        return Path(caching.CompileResultCacheImpl(func).locator.get_cache_path())
    except Exception as exc:  # an internal API: a numba that moved it must not stop the import
        fallback = Path(inspect.getfile(func)).resolve().parent / "__pycache__"
        warnings.warn(f"nlbeam: numba's cache locator is not available ({exc!r}); the stale-"
                      f"kernel check covers only {fallback}. If kernels misbehave after an "
                      "update, delete numba's cache folder (NUMBA_CACHE_DIR if set)",
                      RuntimeWarning, stacklevel=2)
        return fallback


def check_package():
    """The check for this package's kernels (called once, when ``nlbeam._kernels`` loads), in
    the folder numba caches them in (``numba_cache_dir``)."""
    here = Path(__file__).resolve().parent
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:  # pragma: no cover - numba is a dependency
        numba_version = "?"
    return drop_stale(numba_cache_dir(check_package), sorted(here.glob("*.py")),
                      extra=(sys.version, numba_version))
