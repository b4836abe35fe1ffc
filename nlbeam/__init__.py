"""nlbeam: periodic and stochastic dynamics of strongly nonlinear mechanical systems with impact.

Front door of the bottom layer: models (``BeamImpact``, ``Duffing``, ``ModalBeam``, the general
``System`` with ``Contact``, ``PiecewiseLinearStop``, ``CubicSpring`` elements), excitations
(``Harmonic``, ``Sampled``, ``CosineSum``) and the event-exact integrators (``integrate``,
``flow``). The analyses live in the sibling packages ``continuation`` and ``stochastic``; the
application floor (command line, scenes, comparison, sweeps, files, plots) in ``nlbeam.app``.

The names are loaded on first use (``__getattr__``, PEP 562): ``import nlbeam`` alone, or a
light module such as ``nlbeam.vocabulary`` or ``nlbeam.io``, loads neither numba nor the
kernels; ``nlbeam.BeamImpact`` (or ``from nlbeam import BeamImpact``) loads its module.
"""
import importlib
import sys
import types

__version__ = "0.1.0"

#: public name -> the module of the package that defines it
_HOME = {
    "BeamImpact": "systems", "Duffing": "systems", "System": "systems", "Contact": "systems",
    "PiecewiseLinearStop": "systems", "CubicSpring": "systems", "hertz_stiffness": "systems",
    "mu_from_e": "systems", "e_from_mu": "systems",
    "ModalBeam": "modal",
    "Excitation": "excitation", "Harmonic": "excitation", "Sampled": "excitation",
    "CosineSum": "excitation",
    "integrate": "integrate", "flow": "integrate", "Trajectory": "integrate", "Flow": "integrate",
    "IntegrationError": "integrate", "default_dt": "integrate",
    "identify_contact": "identify", "ContactFit": "identify",
}
#: the modules ``import nlbeam`` used to load, reachable as attributes as before
_CORE = ("systems", "modal", "excitation", "custom", "_kernels", "_validate")

__all__ = ["__version__", *_HOME]


def __getattr__(name):
    if name in _HOME:
        value = getattr(importlib.import_module(f"{__name__}.{_HOME[name]}"), name)
        globals()[name] = value
        return value
    if name in _CORE:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_HOME))


class _Package(types.ModuleType):
    """The package object, with one property: ``nlbeam.integrate`` is the function although
    a module of the package has the same name. Importing that module (``from
    nlbeam.integrate import FlowMap``) makes Python set the package attribute to the module;
    the setter ignores that, so the attribute stays the function (the module is
    ``sys.modules["nlbeam.integrate"]``). Setting a function (a test's monkeypatch) works."""

    @property
    def integrate(self):
        function = self.__dict__.get("_integrate_function")
        if function is None:
            function = importlib.import_module(f"{__name__}.integrate").integrate
        return function

    @integrate.setter
    def integrate(self, value):
        if not isinstance(value, types.ModuleType):
            self.__dict__["_integrate_function"] = value


sys.modules[__name__].__class__ = _Package
