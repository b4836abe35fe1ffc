"""The kernels' compile settings and the custom-force hook (``nlbeam.custom``).

In the package itself the hook is a compile-time False and costs nothing; in a copy made for a
custom force (``force.py`` says which and whether it is cached on disk), the right-hand sides
call ``_USER_FORCE`` and the unrolled steps are pruned at compile time.
"""
from numba import njit as _njit

from .force import CACHE as _CACHE
from .force import USER_FORCE

_HAS_USER = USER_FORCE is not None


def njit(*args, **kw):
    """numba.njit with the package's cache setting and, unless ``_nrt=True`` is given, without
    numba's reference counting (NRT). The kernels allocate nothing: they work on arrays
    the caller owns for the whole call, so the atomic increments and decrements NRT would do
    for every array passed at every call (about 2/3 of a right-hand side's cost) buy nothing.
    Only ``integrate_kernel``, which allocates the work arrays, runs with NRT; a kernel without
    NRT that tried to allocate would fail to compile (loudly). Nor may one return an array to
    Python: ``tableau`` called from Python crashes the interpreter (tests/helpers.py avoids it)."""
    kw["cache"] = _CACHE
    kw.setdefault("_nrt", False)
    return _njit(*args, **kw)


if _HAS_USER:
    _USER_FORCE = USER_FORCE
else:
    @_njit(cache=True)
    def _USER_FORCE(t, x, v, y, yd, params, out):
        return
