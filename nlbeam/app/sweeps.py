"""Run independent jobs (the points of a parameter sweep) here, on a local process pool, or
on a Dask distributed cluster.

``run_jobs(func, items, workers=None, scheduler=None)`` returns ``[func(item) for item in
items]`` in order. ``func`` must be a module-level function and the items picklable when
they leave this process. ``scheduler``: address of a running Dask scheduler
(``tcp://host:8786``), or a ``distributed.Client``; needs the optional extra
``nlbeam[distributed]``. Without it, more than one job and ``workers != 1`` use a
``ProcessPoolExecutor`` of ``workers`` processes (default: the CPU count, at most the
number of jobs); otherwise the jobs run in this process, one after another.
The sweepable scene parameters are listed in ``PARAMETERS`` and ``BAND_EDGES``; those of a
general system or a factory depend on the scene's [model] (``nlbeam.app.scenes.models``).
"""
from __future__ import annotations

import os

__all__ = ["run_jobs", "dask_client", "PARAMETERS", "BAND_EDGES"]

#: sweepable scene parameters -> (section, key): the excitation's and the record's, and the
#: paper beam's; the model's of other kinds come from the scene's [model]
#: (nlbeam.app.scenes.models.model_parameters: ``elements[i].field`` of a System, a factory's
#: keyword arguments), named as nlbeam.parameters names them
PARAMETERS = {
    "amplitude": ("periodic", "amplitude"),
    "rms": ("stochastic", "rms"),
    "psd_level": ("stochastic", "psd_level"),
    "band": ("stochastic", "band"),
    "seed": ("stochastic", "seed"),
    "lowpass": ("stochastic", "lowpass"),
    "duration": ("stochastic", "duration"),
    "e": ("model", "e"),
    "K_hertz": ("model", "K_hertz"),
    "m": ("model", "m"),
    "k": ("model", "k"),
    "b": ("model", "b"),
    "mu": ("model", "mu"),
    "gap": ("model", "gap"),
}
#: the band's edges -> (section, key, index)
BAND_EDGES = {"band[0]": ("stochastic", "band", 0), "band[1]": ("stochastic", "band", 1)}


def dask_client(scheduler, timeout):
    """(client, owned): a distributed.Client for ``scheduler`` (an address, or a Client
    given, then owned False); RuntimeError naming ``scheduler`` when Dask is missing or the
    scheduler cannot be reached in ``timeout`` s (also used by nlbeam.pool)."""
    try:
        from distributed import Client
    except ImportError:
        raise RuntimeError("scheduler: Dask is not installed; "
                           "pip install 'nlbeam[distributed]'") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    try:
        return Client(str(scheduler), timeout=f"{timeout}s"), True
    except (OSError, TimeoutError) as exc:
        raise RuntimeError(f"scheduler: cannot reach the Dask scheduler at {scheduler!r}: "
                           f"{exc}") from None


def run_jobs(func, items, *, workers=None, scheduler=None, progress=None, connect_timeout=10.0):
    """``[func(x) for x in items]``, in order, here / on a process pool / on Dask (module doc).
    progress: callable(done, total) called as results arrive; connect_timeout: s to reach
    the scheduler."""
    items = list(items)
    n = len(items)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ValueError(f"workers: must be an integer >= 1, got {workers!r}")
    if n == 0:
        return []
    if scheduler is not None:
        client, own = dask_client(scheduler, connect_timeout)
        try:
            from distributed import as_completed

            futures = client.map(func, items, pure=False)
            index = {f.key: i for i, f in enumerate(futures)}
            out = [None] * n
            for done, fut in enumerate(as_completed(futures), start=1):
                out[index[fut.key]] = fut.result()
                if progress is not None:
                    progress(done, n)
            return out
        finally:
            if own:
                client.close()
    w = min(workers or os.cpu_count() or 1, n)
    if w <= 1:
        out = []
        for i, x in enumerate(items):
            out.append(func(x))
            if progress is not None:
                progress(i + 1, n)
        return out
    from concurrent.futures import ProcessPoolExecutor, as_completed

    out = [None] * n
    with ProcessPoolExecutor(max_workers=w) as pool:
        futs = {pool.submit(func, x): i for i, x in enumerate(items)}
        for done, fut in enumerate(as_completed(futs), start=1):
            out[futs[fut]] = fut.result()
            if progress is not None:
                progress(done, n)
    return out
