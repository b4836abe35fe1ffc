"""continuation: periodic solutions, their stability and frequency-response diagrams.

Front door: ``periodic_solution`` (shooting), ``frequency_response`` and ``continue_parameter``
(pseudo-arclength path following with bifurcation detection), ``refine_bifurcations``
(folds and period doublings to 7-9 digits by an extended system, step refinement and Richardson
extrapolation), ``load``; ``bifurcation_curve`` (the locus of a fold, period doubling,
Neimark-Sacker or grazing point in (frequency, amplitude or a model parameter), with the
codimension-2 points met) and ``stability_chart`` (all curves of a diagram, and the attractor
orders on a grid), saved and read by ``load_curves``. Every periodic solution, branch point
and bifurcation carries an error estimate from a solve with the step halved
(``continuation.accuracy``; ``accuracy=`` asks for more digits). The figures
(``continuation.plot``) and the HDF5 files (``save``, ``load``, ``load_curves``) live on the
application floor, nlbeam.app; importing this package loads neither matplotlib nor h5py.
Units: Hz, m (N for force excitation), s.
"""
from ._newton import ContinuationWarning, ConvergenceError
from .diagram import (Bifurcation, Branch, FrequencyResponse, Superharmonic,
                      continue_parameter, frequency_response, load)
from .refine import Refined, refine, refine_bifurcations
from .shooting import Integrator, PeriodicSolution, periodic_solution

__all__ = ["periodic_solution", "frequency_response", "continue_parameter", "load",
           "PeriodicSolution", "FrequencyResponse", "Branch", "Bifurcation", "Superharmonic",
           "Integrator", "ConvergenceError", "ContinuationWarning", "refine", "refine_bifurcations",
           "Refined"]
from .curve import BifurcationCurve, Codim2, bifurcation_curve, load_curves  # noqa: E402

__all__ += ["bifurcation_curve", "BifurcationCurve", "Codim2", "load_curves"]
from .chart import StabilityChart, attractor_order, stability_chart  # noqa: E402

__all__ += ["stability_chart", "StabilityChart", "attractor_order"]
