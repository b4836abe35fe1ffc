"""The [measured] record of a scene: its columns read (CSV or HDF5), analysed by the
estimators of a simulation (``stochastic.analyze``), to be overlaid on the stochastic figures
and added to the moments and peaks tables. Not cached: reading and analysing a record takes
about as long as checking a cache entry."""
from __future__ import annotations

import os

import stochastic

from ..files.columns import read_columns
from ..plots.units import excitation_kind

__all__ = ["measured_result"]


def measured_result(spec, model_parameters=None):
    """The StochasticResult of the [measured] section ``spec`` (file: absolute path,
    time_column, channels; band, psd_resolution, pdf_bins optional); y is a force when the
    model (``model_parameters``) is force-excited."""
    cols = read_columns(spec["file"], required=(spec["time_column"], *spec["channels"]))
    kw = {k: spec[k] for k in ("band", "psd_resolution", "pdf_bins") if k in spec}
    return stochastic.analyze(cols[spec["time_column"]], {c: cols[c] for c in spec["channels"]},
                              excitation_kind=excitation_kind(model_parameters or {}),
                              description={"source": os.path.basename(spec["file"])}, **kw)
