"""Custom forces: the escape hatch for what the element table cannot say.

A custom force is a numba-jitted function ``force(t, x, v, y, yd, params, out)`` that *adds*
the generalised force (N, acting like the elements' restoring forces are subtracted, i.e. on the
right-hand side) of every DOF to ``out`` (length N): t in s, x (m) and v (m/s) length-N arrays,
y and yd the excitation and its rate, params the float array given as ``custom_params``.
It must be smooth in (x, v) (no contact events are attached to it). The kernels are compiled
once per custom function into a private copy of the package ``nlbeam._kernels`` (not cached
on disk, so the first call in a process compiles for ~20-40 s); the variational equations use
a forward-difference Jacobian of it (relative step 1e-7).
"""
from __future__ import annotations

import importlib.util
import os
import sys

from . import _kernels

_MODULES: dict[int, tuple[object, object]] = {}


def kernels_for(force):
    """The kernel module compiled with ``force`` as the custom-force hook (cached per function)."""
    if force is None:
        return _kernels
    hit = _MODULES.get(id(force))
    if hit is not None and hit[0] is force:
        return hit[1]
    name = f"nlbeam._kernels_custom_{len(_MODULES)}"
    folder = os.path.dirname(_kernels.__file__)
    spec = importlib.util.spec_from_file_location(name, _kernels.__file__,
                                                  submodule_search_locations=[folder])
    mod = importlib.util.module_from_spec(spec)
    mod._USER_FORCE_OVERRIDE = force   # read by its force.py
    sys.modules[name] = mod            # its modules import each other relatively
    spec.loader.exec_module(mod)
    _MODULES[id(force)] = (force, mod)
    return mod
