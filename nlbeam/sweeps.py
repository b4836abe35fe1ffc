"""Alias of ``nlbeam.app.sweeps`` (``run_jobs``: here, on a process pool or on Dask), kept
for the names users import."""
from nlbeam.app.sweeps import PARAMETERS, run_jobs

__all__ = ["run_jobs", "PARAMETERS"]
