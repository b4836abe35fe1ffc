"""The one layer of argument checks every front door uses.

Each check raises an exception whose message names the argument, the value it got and what is
allowed (``name: must be ..., got ...``), like the scene errors. A value of the wrong type
raises ``ArgumentTypeError``, which is both a ``TypeError`` and a ``ValueError`` (callers
that caught ValueError keep working); a value of the right type outside its range raises
``ValueError``. Numbers must be real numbers: a numeric string ('0.5'), a bool or a complex
number is refused with the value it got, never converted quietly.

Resource guards (``check_count``, ``check_memory``) refuse work whose estimate (steps,
samples, bytes) exceeds a stated budget, naming the estimate and the knob that changes it.
This module is a leaf of the package: it imports numpy only.
"""
from __future__ import annotations

import difflib
import math
import numbers
import os

import numpy as np


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a TypeError, and a ValueError for older callers)."""


class BudgetError(ValueError):
    """A request whose estimated work or memory exceeds the stated budget."""


# --- numbers -------------------------------------------------------------------------------------
def _is_real_type(value):
    t = type(value)
    if t is float or t is int:  # the common case, fast
        return True
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, (numbers.Real, np.integer, np.floating)):
        return True
    return isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"


def _num(name, value):
    """``value`` as a float when it is a real number (int, float, numpy real scalar)."""
    if not _is_real_type(value):
        what = f"a {type(value).__name__}"
        if isinstance(value, str):
            try:
                float(value)
                what = "a numeric string"
            except ValueError:
                what = "a string"
        raise ArgumentTypeError(f"{name}: must be a real number, got {what} {value!r}")
    return float(value)


def _unit(unit):
    return f" {unit}" if unit else ""


def real(name, value, unit=""):
    """A real number (inf and NaN allowed: the caller checks its range)."""
    return _num(name, value)


def finite(name, value, unit=""):
    v = _num(name, value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be a finite number{' in ' + unit if unit else ''}, got "
                         f"{value!r}")
    return v


def positive(name, value, unit=""):
    v = _num(name, value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name}: must be finite and > 0{_unit(unit)}, got {value!r}")
    return v


def nonnegative(name, value, unit=""):
    v = _num(name, value)
    if not (math.isfinite(v) and v >= 0):
        raise ValueError(f"{name}: must be finite and >= 0{_unit(unit)}, got {value!r}")
    return v


def in_range(name, value, lo, hi, lo_open=False, hi_open=False, unit=""):
    v = _num(name, value)
    ok = math.isfinite(v)
    ok = ok and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ValueError(f"{name}: must lie in {lb}{lo}, {hi}{rb}{_unit(unit)}, got {value!r}")
    return v


def integer(name, value, lo=None, hi=None):
    """An integer (int or numpy integer; an integral float such as 64.0 is taken too) in
    [lo, hi] (None: no bound). A bool, a string or a non-integral number is refused."""
    if isinstance(value, (bool, np.bool_)) or not _is_real_type(value):
        raise ArgumentTypeError(f"{name}: must be an integer, got {type(value).__name__} "
                                f"{value!r}")
    if not isinstance(value, (numbers.Integral, np.integer)):
        v = float(value)
        if not (math.isfinite(v) and v == int(v)):
            raise ArgumentTypeError(f"{name}: must be an integer, got {value!r}")
    i = int(value)
    if (lo is not None and i < lo) or (hi is not None and i > hi):
        rng = (f">= {lo}" if hi is None else f"<= {hi}" if lo is None else f"in [{lo}, {hi}]")
        raise ValueError(f"{name}: must be an integer {rng}, got {value!r}")
    return i


def flag(name, value):
    """A bool (True/False, numpy bool); 'no', 0 or None are refused."""
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name}: must be True or False, got {type(value).__name__} "
                                f"{value!r}")
    return bool(value)


def _suggest(value, allowed):
    if not isinstance(value, str):
        return ""
    close = difflib.get_close_matches(value, [str(a) for a in allowed], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def choice(name, value, allowed):
    """One of ``allowed``; a misspelt string gets a 'did you mean'."""
    try:
        ok = value in allowed
    except TypeError:  # an unhashable value against a set
        ok = False
    if not ok or isinstance(value, (bool, np.bool_)) != any(isinstance(a, bool) for a in allowed
                                                             if a == value):
        raise ValueError(f"{name}: must be one of {', '.join(repr(a) for a in allowed)}, got "
                         f"{value!r}{_suggest(value, allowed)}")
    return value


def choices(name, values, allowed):
    """A tuple of members of ``allowed`` (a single string is refused: give a tuple)."""
    if isinstance(values, str) or not _iterable(values):
        raise ArgumentTypeError(f"{name}: must be a tuple of names from "
                                f"{', '.join(repr(a) for a in allowed)}, got {values!r}")
    values = tuple(values)
    for v in values:
        choice(name, v, allowed)
    return values


def keywords(where, given, allowed):
    """Raise TypeError naming every keyword of ``given`` not in ``allowed`` (with a 'did you
    mean'); where: the function's name."""
    allowed = tuple(allowed)
    for k in given:
        if k not in allowed:
            raise ArgumentTypeError(f"{where}: unknown keyword {k!r}{_suggest(k, allowed)}; the "
                                    f"keywords are {', '.join(sorted(allowed))}")


def callable_or_none(name, value, what="a callable"):
    if value is not None and not callable(value):
        raise ArgumentTypeError(f"{name}: must be {what} or None, got {type(value).__name__} "
                                f"{value!r}")
    return value


# --- sequences and arrays ------------------------------------------------------------------------
def _iterable(value):
    try:
        iter(value)
    except TypeError:
        return False
    return True


def real_array(name, value, *, ndim=None, shape=None, min_size=0, finite_values=True,
               unit=""):
    """``value`` as a float array: real numbers only (no strings, no bools, no objects), of
    ``ndim`` dimensions / ``shape`` (None entries: any length), at least ``min_size`` values,
    all finite when ``finite_values``."""
    if isinstance(value, (str, bytes)):
        raise ArgumentTypeError(f"{name}: must be an array of real numbers, got a string "
                                f"{value!r}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):  # ragged nested sequences
        raise ArgumentTypeError(f"{name}: must be an array of real numbers, got "
                                f"{_short(value)}") from None
    if arr.dtype.kind not in "iuf" or arr.dtype == object:
        raise ArgumentTypeError(f"{name}: must be an array of real numbers, got "
                                f"{_short(value)} (dtype {arr.dtype})")
    arr = arr.astype(float, copy=False)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name}: must be a {ndim}-D array, got shape {arr.shape}")
    if shape is not None and (arr.ndim != len(shape) or any(
            s is not None and s != a for s, a in zip(shape, arr.shape))):
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: must have shape {want}, got {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name}: must hold at least {min_size} values, got {arr.size}")
    if finite_values and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite{_unit(unit)}, got {_short(value)}")
    return arr


def interval(name, value, lo=-math.inf, lo_open=False, unit=""):
    """A pair (a, b) of finite real numbers with lo <= a < b (lo < a if lo_open)."""
    if isinstance(value, (str, bytes)) or not _iterable(value):
        raise ArgumentTypeError(f"{name}: must be a pair (low, high){_unit(unit)}, got "
                                f"{value!r}")
    items = tuple(value)
    if len(items) != 2:
        raise ValueError(f"{name}: must be a pair (low, high){_unit(unit)}, got {value!r} "
                         f"({len(items)} values)")
    a = finite(f"{name}[0]", items[0], unit)
    b = finite(f"{name}[1]", items[1], unit)
    if not (a > lo if lo_open else a >= lo) or not b > a:
        lim = f"{lo} {'<' if lo_open else '<='} " if math.isfinite(lo) else ""
        raise ValueError(f"{name}: must be (low, high) with {lim}low < high{_unit(unit)}, got "
                         f"{value!r}")
    return a, b


def integers(name, values, lo=None, hi=None):
    """A non-empty tuple of integers in [lo, hi] (a single int is refused: give a tuple)."""
    if isinstance(values, (str, bytes)) or not _iterable(values):
        raise ArgumentTypeError(f"{name}: must be a tuple of integers such as (1, 2), got "
                                f"{values!r}")
    values = tuple(values)
    if not values:
        raise ValueError(f"{name}: must hold at least one integer, got {values!r}")
    return tuple(integer(name, v, lo, hi) for v in values)


def _short(value, n=60):
    r = repr(value)
    return r if len(r) <= n else r[:n] + "..."


# --- resource guards -----------------------------------------------------------------------------
#: environment variable: the memory budget in bytes (default: half the available memory)
MEMORY_ENV = "NLBEAM_MEMORY_BUDGET"
#: bytes every machine this runs on can allocate: not checked against the available memory
_ALWAYS_AFFORDABLE = 64 * 2 ** 20


def _available_memory():
    """Bytes of memory available now (MemAvailable of /proc/meminfo, else the free physical
    pages; 8 GiB when neither is known)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 * 2 ** 30


def memory_budget():
    """The memory budget (bytes) of one allocation: $NLBEAM_MEMORY_BUDGET, else half the
    memory available now."""
    env = os.environ.get(MEMORY_ENV)
    if env:
        try:
            return float(env)
        except ValueError:
            raise ValueError(f"{MEMORY_ENV}: must be a number of bytes, got {env!r}") from None
    return 0.5 * _available_memory()


def format_bytes(n):
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} EiB"  # pragma: no cover


def check_memory(what, nbytes, knob):
    """Raise BudgetError when ``nbytes`` (an estimate) exceeds the memory budget; what: what
    would be allocated, knob: the arguments that change it."""
    if nbytes <= _ALWAYS_AFFORDABLE and MEMORY_ENV not in os.environ:
        return nbytes  # no need to read /proc/meminfo (tens of microseconds) for a small one
    budget = memory_budget()
    if not nbytes <= budget:
        raise BudgetError(f"{what}: needs about {format_bytes(nbytes)}, more than the memory "
                          f"budget {format_bytes(budget)} (half the available memory, or "
                          f"${MEMORY_ENV}); {knob}")
    return nbytes


def check_count(what, count, limit, knob):
    """Raise BudgetError when ``count`` (an estimated number of steps, samples, points)
    exceeds ``limit``; knob: the arguments that change it."""
    if not count <= limit:
        raise BudgetError(f"{what}: about {count:.3g}, more than the limit {limit:.3g}; {knob}")
    return count


# --- output paths --------------------------------------------------------------------------------
def path_like(name, value):
    """A file path: a str or os.PathLike (not empty). Returns it as a str."""
    if not isinstance(value, (str, os.PathLike)):
        raise ArgumentTypeError(f"{name}: must be a path (str or os.PathLike), got "
                                f"{type(value).__name__} {value!r}")
    p = os.fspath(value)
    if not isinstance(p, str) or not p:
        raise ValueError(f"{name}: must be a non-empty path, got {value!r}")
    return p


def writable_folder(name, folder, create=False):
    """A folder files can be written into (created when ``create`` and missing)."""
    folder = path_like(name, folder)
    if create and not os.path.exists(folder):
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"{name}: cannot create the folder {folder!r} "
                             f"({exc.strerror or exc})") from None
    if not os.path.isdir(folder):
        what = "does not exist" if not os.path.exists(folder) else "is not a folder"
        raise ValueError(f"{name}: the folder {folder!r} {what}")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{name}: the folder {folder!r} is not writable")
    return folder


def output_file(name, path):
    """A file path that can be written: not a folder, not a read-only file, in a writable
    folder (or under a writable folder where the missing ones will be created). Checked
    before any work starts. Returns it as a str."""
    p = path_like(name, path)
    if p.endswith(os.sep) or os.path.isdir(p):
        raise ValueError(f"{name}: {p!r} is a folder; give a file name (e.g. "
                         f"{os.path.join(p, 'result.h5')!r})")
    folder = os.path.dirname(os.path.abspath(p))
    while not os.path.exists(folder):  # a missing folder is created by the save: its parent
        parent = os.path.dirname(folder)
        if parent == folder:
            break
        folder = parent
    if not os.path.isdir(folder):
        raise ValueError(f"{name}: {folder!r} in the path {p!r} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{name}: the folder {folder!r} is not writable (for {p!r})")
    if os.path.exists(p) and not os.access(p, os.W_OK):
        raise ValueError(f"{name}: the file {p!r} exists and is not writable")
    return p
