"""Where independent pieces of one analysis run: here, on a local process pool, or on a Dask
distributed cluster (``Pool``; used by continuation.frequency_response and
stochastic.ensemble).

``workers``: None (the CPU count) or an integer >= 1 of local processes; 1 runs everything in
this process. ``scheduler``: the address of a running Dask scheduler (``tcp://host:8786``) or
a ``distributed.Client`` (then ``workers`` is ignored); needs the optional extra
``nlbeam[distributed]``. Functions sent away must be module-level and their arguments
picklable.
"""
from __future__ import annotations

import os

__all__ = ["Pool", "check_workers"]


def check_workers(workers):
    """ValueError unless workers is None or an integer >= 1."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ValueError(f"workers: must be an integer >= 1 (processes), got {workers!r}")


class _Done:
    """A finished result with the interface of a future (result, cancel, done)."""

    def __init__(self, value=None, error=None):
        self.value, self.error = value, error

    def result(self):
        if self.error is not None:
            raise self.error
        return self.value

    def cancel(self):
        return False

    def done(self):
        return True


class Pool:
    """Runs ``func(*args)`` here, in local processes or on Dask (module doc). Use as a context
    manager; ``serial`` is True when everything runs in this process. ``submit`` returns an
    object with ``result()`` and ``cancel()``; ``map`` keeps the order of the items."""

    def __init__(self, workers=None, scheduler=None, connect_timeout=10.0):
        check_workers(workers)
        self.scheduler = scheduler
        self.workers = workers
        self._client = self._own = self._pool = None
        if scheduler is not None:  # Dask lives on the application floor (tests/test_floors)
            from nlbeam.app.sweeps import dask_client

            self._client, self._own = dask_client(scheduler, connect_timeout)
        self.size = (len(self._client.scheduler_info().get("workers", {})) or 1
                     if self._client is not None else (workers or os.cpu_count() or 1))

    @property
    def serial(self):
        return self._client is None and self.size <= 1

    def submit(self, func, *args):
        if self._client is not None:
            return self._client.submit(func, *args, pure=False)
        if self.serial:
            try:
                return _Done(func(*args))
            except Exception as exc:  # raised again by result(), as a future would
                return _Done(error=exc)
        if self._pool is None:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.size)
        return self._pool.submit(func, *args)

    def map(self, func, items):
        """[func(x) for x in items], in order."""
        items = list(items)
        if self.serial or len(items) <= 1:
            return [func(x) for x in items]
        futures = [self.submit(func, x) for x in items]
        return [f.result() for f in futures]

    def close(self):
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._own:
            self._client.close()
            self._own = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
