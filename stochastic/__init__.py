"""Stochastic dynamics: Gaussian excitations synthesized block by block, streaming
estimators (Welch PSD, histogram PDF, moments) and the simulation loop.

Importing this package loads neither matplotlib nor h5py: the figures (`stochastic.plot`) and
the HDF5 files (`StochasticResult.save`, `load`) live on the application floor, nlbeam.app.
"""
from . import errors  # standard errors of correlated records
from .estimators import (StreamingHistogram, StreamingMoments, WelchPSD, correlation_from_psd,
                         welch_dof)
from .noise import (BandLimitedNoise, Realization, Recorded, SpectralNoise, hermite_step,
                    quintic_step)

__all__ = ["BandLimitedNoise", "SpectralNoise", "Realization", "Recorded", "hermite_step",
           "quintic_step",
           "WelchPSD", "StreamingHistogram", "StreamingMoments", "correlation_from_psd",
           "welch_dof", "errors"]
from .simulate import EnsembleResult, StochasticResult, ensemble, load, simulate  # noqa: E402

__all__ += ["simulate", "StochasticResult", "load", "ensemble", "EnsembleResult"]
from .analyze import analyze  # noqa: E402

__all__ += ["analyze"]
