"""Custom forces: the escape hatch for what the element table cannot say.

A custom force is a numba-jitted function ``force(t, x, v, y, yd, params, out)`` that *adds*
the generalised force (N, acting like the elements' restoring forces are subtracted, i.e. on the
right-hand side) of every DOF to ``out`` (length N): t in s, x (m) and v (m/s) length-N arrays,
y and yd the excitation and its rate, params the float array given as ``custom_params``.
It must be smooth in (x, v) (no contact events are attached to it); the variational equations
use a forward-difference Jacobian of it (relative step 1e-7).

Compiling. The kernels are compiled once per custom function into a copy of the package
``nlbeam._kernels`` that calls it (30-70 s CPU). That copy is cached on disk, so this is paid
once per machine, not in every process or Dask worker: the package's files are copied to
``$NLBEAM_CACHE_DIR/kernels/<key>/`` (default ``~/.cache/nlbeam/kernels/<key>/``) with a
generated ``force.py`` that imports the force by its module and qualified name, and numba
caches the compiled kernels there. The key hashes the force's source and the values of the
globals it reads (numba freezes them; followed into the jitted functions it calls), the kernel
package's source and the Python, numpy, numba and nlbeam versions, so an edited force or kernel
gets a new folder (delete old ones to reclaim space). A force that cannot be imported by name
(defined in ``__main__`` - a script or an interactive session - or inside a function), or an
unwritable cache folder, falls back to an uncached copy compiled in every process, with a
warning that says why. A jitted helper in another module that the force calls is hashed too,
but a change of the global values such helpers read is not seen: delete the folder then.
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import os
import shutil
import sys
import tempfile
import types
import warnings

import numpy as np

from . import _kernels

_MODULES: dict[int, tuple[object, object]] = {}
_FORMAT = b"nlbeam custom-force kernels 1"


def kernels_for(force):
    """The kernel package compiled with ``force`` as the custom-force hook (one per function and
    process; on disk per machine where the force is importable by name)."""
    if force is None:
        return _kernels
    hit = _MODULES.get(id(force))
    if hit is not None and hit[0] is force:
        return hit[1]
    folder, why = cached_folder(force)
    if folder is None:
        warnings.warn(f"custom_force {_name(force)}: {why}; its kernels are compiled in this "
                      "process without a disk cache (30-70 s, again in every process). Define "
                      "it at module level of an importable module to compile it once per "
                      "machine (see nlbeam.custom)", RuntimeWarning, stacklevel=4)
        mod = _load(f"nlbeam._kernels_custom_{len(_MODULES)}",
                    os.path.dirname(_kernels.__file__), force)
    else:
        mod = _load(f"nlbeam._kernels_cached_{os.path.basename(folder)}", folder, None)
    _MODULES[id(force)] = (force, mod)
    return mod


def cache_root():
    """The folder of the cached kernel copies: $NLBEAM_CACHE_DIR/kernels, else
    $XDG_CACHE_HOME/nlbeam/kernels, else ~/.cache/nlbeam/kernels."""
    base = os.environ.get("NLBEAM_CACHE_DIR")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        base = os.path.join(xdg, "nlbeam")
    return os.path.join(base, "kernels")


def import_path(force):
    """(module, qualified name) by which ``force`` can be imported, or (None, why not)."""
    py = getattr(force, "py_func", force)
    module = getattr(py, "__module__", None)
    qualname = getattr(py, "__qualname__", "")
    if module in (None, "__main__", "__mp_main__"):
        return None, "it is defined in __main__ (a script or an interactive session)"
    if "<locals>" in qualname or "<lambda>" in qualname:
        return None, "it is defined inside a function"
    try:
        obj = importlib.import_module(module)
        for part in qualname.split("."):
            obj = getattr(obj, part)
    except Exception as exc:  # any failure means: not importable by name
        return None, f"{module}.{qualname} cannot be imported ({type(exc).__name__}: {exc})"
    if obj is not force and _fingerprint(obj) != _fingerprint(force):
        # (a force unpickled in a worker process is a copy of the one its module defines)
        return None, f"{module}.{qualname} is another function than the force given"
    return (module, qualname), None


def cache_key(force, module, qualname):
    """Hex key of the cached copy for ``force`` (see the module docstring for what it hashes)."""
    import numba

    from . import __version__ as nlbeam_version
    h = hashlib.sha256(_FORMAT)
    for part in (sys.version, np.__version__, numba.__version__, nlbeam_version, module,
                 qualname):
        h.update(str(part).encode() + b"\0")
    folder = os.path.dirname(_kernels.__file__)
    for fname in _package_files():
        with open(os.path.join(folder, fname), "rb") as f:
            h.update(fname.encode() + b"\0" + f.read() + b"\0")
    _hash_function(force, h, set())
    return h.hexdigest()[:24]


def cached_folder(force):
    """The folder of the cached kernel copy for ``force``, written (atomically) if missing;
    (folder, None), or (None, why not)."""
    where, why = import_path(force)
    if where is None:
        return None, why
    module, qualname = where
    try:
        key = cache_key(force, module, qualname)
    except Exception as exc:  # a global numba cannot freeze either: let the fallback say so
        return None, f"its source could not be hashed ({type(exc).__name__}: {exc})"
    root = cache_root()
    final = os.path.join(root, key)
    if os.path.isfile(os.path.join(final, "__init__.py")):
        return final, None
    try:
        os.makedirs(root, exist_ok=True)
        tmp = tempfile.mkdtemp(prefix=f".{key}-", dir=root)
        src = os.path.dirname(_kernels.__file__)
        for fname in _package_files():
            if fname != "force.py":
                shutil.copyfile(os.path.join(src, fname), os.path.join(tmp, fname))
        with open(os.path.join(tmp, "force.py"), "w") as f:
            f.write(_FORCE_TEMPLATE.format(module=module, qualname=qualname))
        try:
            os.rename(tmp, final)   # atomic: another process may have won the race
        except OSError:
            shutil.rmtree(tmp, ignore_errors=True)
    except OSError as exc:
        return None, f"the cache folder {root} is not writable ({exc})"
    if not os.path.isfile(os.path.join(final, "__init__.py")):
        return None, f"the cache folder {final} is incomplete"
    return final, None


_FORCE_TEMPLATE = '''"""Generated by nlbeam.custom: the custom force {module}.{qualname}, imported
by name. The files beside this one are a copy of nlbeam._kernels; numba caches them here."""
import importlib

USER_FORCE = importlib.import_module({module!r})
for _part in {qualname!r}.split("."):
    USER_FORCE = getattr(USER_FORCE, _part)
CACHE = True
'''


def _package_files():
    folder = os.path.dirname(_kernels.__file__)
    return sorted(f for f in os.listdir(folder) if f.endswith(".py"))


def _load(name, folder, force):
    """Import the kernel package in ``folder`` as module ``name``; ``force``: the hook of an
    uncached copy (read by its force.py), None for a generated copy."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, os.path.join(folder, "__init__.py"),
                                                  submodule_search_locations=[folder])
    mod = importlib.util.module_from_spec(spec)
    if force is not None:
        mod._USER_FORCE_OVERRIDE = force
    sys.modules[name] = mod            # its modules import each other relatively
    try:
        spec.loader.exec_module(mod)
    except BaseException:
        del sys.modules[name]
        raise
    return mod


def _fingerprint(func):
    h = hashlib.sha256()
    try:
        _hash_function(func, h, set())
    except Exception:  # not a function whose source and globals can be read
        return None
    return h.hexdigest()


def _hash_function(func, h, seen):
    """Hash a (jitted) function's source, numba options and the globals it reads, recursively
    into the jitted functions among them."""
    py = getattr(func, "py_func", func)
    if id(py) in seen:
        return
    seen.add(id(py))
    code = py.__code__
    try:
        h.update(inspect.getsource(py).encode())
    except (OSError, TypeError):
        h.update(code.co_code + repr(code.co_consts).encode())
    h.update(repr(sorted(getattr(func, "targetoptions", {}).items())).encode())
    for name in sorted(_global_names(code)):
        if name not in py.__globals__:
            continue
        value = py.__globals__[name]
        h.update(name.encode() + b"=")
        if hasattr(value, "py_func"):
            _hash_function(value, h, seen)
        elif isinstance(value, types.ModuleType):
            h.update(value.__name__.encode())
        elif isinstance(value, np.ndarray):
            h.update(repr((value.dtype.str, value.shape)).encode() + value.tobytes())
        elif isinstance(value, (bool, int, float, complex, str, bytes, tuple, type(None),
                                np.generic)):
            h.update(repr(value).encode())
        else:
            h.update(repr(type(value)).encode())
        h.update(b"\0")


def _global_names(code):
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _global_names(const)
    return names


def _name(force):
    py = getattr(force, "py_func", force)
    return f"{getattr(py, '__module__', '?')}.{getattr(py, '__qualname__', repr(force))}"
