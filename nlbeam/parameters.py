"""The names of a model's parameters, one scheme for every front door (continuation's
``continue_parameter``, the scene sweeps, the command line's ``--set``).

- a model built by a constructor (``BeamImpact``, ``Duffing``, ``ModalBeam``, any frozen
  dataclass of numbers): its numeric fields by name (``m``, ``k``, ``b``, ``K_hertz``, ``e``,
  ``gap``, ``mu``, ...);
- a general ``System``: the numeric fields of its elements as ``elements[i].name``
  (``elements[1].gap``, ``elements[0].K``, ``elements[0].k3``), i counting from 0.

``parameter_names(model)`` lists them; ``get_parameter`` reads one; ``with_parameter`` returns
the model with one changed (the model's own checks apply); a name that does not exist raises a
ValueError listing those that do. Units: those of the field (SI).
"""
from __future__ import annotations

import dataclasses
import math
import re

__all__ = ["parameter_names", "get_parameter", "with_parameter", "check_parameter",
           "element_parameter"]

_ELEMENT = re.compile(r"^elements\[(\d+)\]\.([A-Za-z_][A-Za-z0-9_]*)$")
#: element fields that are not parameters (where, which way, the law's name)
_NOT_PARAMETERS = ("dof", "side", "on_base", "clamp", "law")


def _numeric(v):
    return (isinstance(v, (int, float)) and not isinstance(v, bool)
            and math.isfinite(float(v)))


def _is_system(model):
    from .systems import System
    return isinstance(model, System)


def _fields(obj):
    """The init fields of a dataclass instance holding a finite number."""
    if not dataclasses.is_dataclass(obj):
        return []
    return [f.name for f in dataclasses.fields(obj)
            if f.init and f.name not in _NOT_PARAMETERS and _numeric(getattr(obj, f.name))]


def _element_fields(el):
    """The numeric parameters of an element (None-valued optional ones such as ``mu`` of a
    Hertz contact are left out: they do not act)."""
    return _fields(el)


def parameter_names(model) -> list:
    """Every parameter name of ``model`` the scheme knows (module doc)."""
    if _is_system(model):
        return [f"elements[{i}].{n}" for i, el in enumerate(model.elements)
                for n in _element_fields(el)]
    return _fields(model)


def element_parameter(name):
    """(element index, field) of an ``elements[i].field`` name, else None."""
    m = _ELEMENT.match(str(name))
    return (int(m.group(1)), m.group(2)) if m else None


def check_parameter(model, name, extra=()):
    """Raise ValueError naming ``name`` and listing the names that exist (``extra`` first:
    e.g. the excitation's 'frequency', 'amplitude') unless ``name`` is one of them."""
    names = list(extra) + parameter_names(model)
    if name not in names:
        kind = type(model).__name__
        raise ValueError(f"parameter: {name!r} is not a parameter of this {kind}; "
                         f"the names that exist: {', '.join(names) or 'none'}")


def get_parameter(model, name) -> float:
    """The value of parameter ``name`` of ``model`` (SI units of the field)."""
    check_parameter(model, name)
    el = element_parameter(name)
    if el is not None:
        return float(getattr(model.elements[el[0]], el[1]))
    return float(getattr(model, name))


def with_parameter(model, name, value):
    """``model`` with parameter ``name`` set to ``value`` (a new object; the model's and the
    element's own checks apply and raise ValueError naming the field)."""
    check_parameter(model, name)
    el = element_parameter(name)
    if el is None:
        if hasattr(model, "replace"):  # BeamImpact, ModalBeam: fields recomputed from inputs
            return model.replace(**{name: value})
        return dataclasses.replace(model, **{name: value})
    i, field = el
    elements = list(model.elements)
    elements[i] = dataclasses.replace(elements[i], **{field: value})
    return dataclasses.replace(model, elements=tuple(elements))
