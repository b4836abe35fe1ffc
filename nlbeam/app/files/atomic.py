"""Atomic writes (standard library only): every output file of the application floor (HDF5
results, figures, tables, cache sidecars) is written to a temporary name in its own folder
and renamed over the target (``os.replace``), so a reader never sees half a file and a
failure leaves none: the temporary is removed on any exception, and on SIGTERM while it is
open (the process then ends by SIGTERM as before, after one line on stderr).
``remove_stale_temporaries`` clears ``.tmp-*`` files that a killed process left behind.
"""
from __future__ import annotations

import contextlib
import os
import secrets
import signal
import sys
import threading
import time

__all__ = ["atomic_path", "write_bytes_atomic", "write_text_atomic",
           "remove_stale_temporaries", "TMP_PREFIX"]

TMP_PREFIX = ".tmp-"
_open_temporaries = set()  # temporaries of this process, removed on SIGTERM


def _on_sigterm(signum, frame):
    """Remove this process' open temporaries, say so, and end by SIGTERM."""
    for tmp in list(_open_temporaries):
        with contextlib.suppress(OSError):
            os.remove(tmp)
    print(f"nlbeam: terminated (SIGTERM) while writing; removed {len(_open_temporaries)} "
          "temporary file(s)", file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    os.kill(os.getpid(), signal.SIGTERM)


@contextlib.contextmanager
def _sigterm_guard():
    """While inside: SIGTERM removes the temporaries first (main thread, default handler
    only: a handler the program installed is left alone)."""
    ours = (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None))
    if ours:
        signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        if ours and not _open_temporaries:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)


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
        tmp = os.path.join(folder, f"{TMP_PREFIX}{secrets.token_hex(6)}{suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        break
    else:  # pragma: no cover - 100 collisions of 48 random bits
        raise FileExistsError(f"{path}: no free temporary name in {folder}")
    with _sigterm_guard():
        _open_temporaries.add(tmp)
        try:
            yield tmp
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                os.remove(tmp)
            raise
        finally:
            _open_temporaries.discard(tmp)


def write_bytes_atomic(path, data):
    """Write ``data`` (bytes) to ``path`` atomically and durably (flushed, fsync'ed, closed
    before the rename). Any failure (full disk, read-only folder, quota) removes the
    temporary and raises one OSError line naming ``path`` and the cause."""
    path = os.fspath(path)
    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                view = memoryview(data)
                while view:  # a short write on a nearly full disk: go on or fail
                    n = fh.write(view)
                    view = view[n:]
                fh.flush()
                os.fsync(fh.fileno())
    except OSError as err:
        why = err.strerror or str(err)
        clean = OSError(f"{path}: cannot save ({why}, {len(data)} bytes to write); nothing "
                        "was written")
        clean.errno = err.errno  # str(clean) stays the one line above
        raise clean from None
    return path


def write_text_atomic(path, text):
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def remove_stale_temporaries(folder, max_age=3600.0, dry_run=False):
    """Remove ``.tmp-*`` files in ``folder`` older than ``max_age`` seconds (left by a
    killed process; younger ones may belong to a run in progress). Returns their paths."""
    folder = os.fspath(folder)
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    now = time.time()
    stale = []
    for name in names:
        p = os.path.join(folder, name)
        if not name.startswith(TMP_PREFIX):
            continue
        with contextlib.suppress(OSError):
            if os.path.isfile(p) and now - os.path.getmtime(p) > max_age:
                if not dry_run:
                    os.remove(p)
                stale.append(p)
    return stale
