"""nlbeam: periodic and stochastic dynamics of strongly nonlinear mechanical systems with impact.

Front door of the bottom layer: models (``BeamImpact``, ``Duffing``, ``ModalBeam``, the general ``System`` with
``Contact``, ``PiecewiseLinearStop``, ``CubicSpring`` elements), excitations (``Harmonic``,
``Sampled``, ``CosineSum``) and the event-exact integrators (``integrate``, ``flow``).
The analyses live in the sibling packages ``continuation`` and ``stochastic``.
"""
__version__ = "0.1.0"

from .excitation import CosineSum, Excitation, Harmonic, Sampled
from .modal import ModalBeam
from .integrate import Flow, IntegrationError, Trajectory, default_dt, flow, integrate
from .systems import (BeamImpact, Contact, CubicSpring, Duffing, PiecewiseLinearStop, System,
                      e_from_mu, hertz_stiffness, mu_from_e)

__all__ = [
    "__version__", "BeamImpact", "Duffing", "ModalBeam", "System", "Contact", "PiecewiseLinearStop",
    "CubicSpring", "hertz_stiffness", "mu_from_e", "e_from_mu", "Excitation", "Harmonic",
    "Sampled", "CosineSum", "integrate", "flow", "Trajectory", "Flow", "IntegrationError",
    "default_dt",
]
