"""Branches of a diagram traced ahead of their turn on other processes (an nlbeam.pool.Pool),
with exactly the serial result.

The serial diagram (diagram._run_diagram) traces its branches one after another; a branch
depends on the ones before it only through two rules: a start that lies on a traced branch
is skipped, and a trace stops where it runs onto a traced branch (the stop rule, called on
every accepted point). A ``Speculator`` traces a branch elsewhere with a stop rule that
records the points it is asked about and never stops. When the serial loop reaches that
branch it first applies its own skip check, then calls its real stop rule on the recorded
points in order: if none stops, the serial trace would have passed exactly those points (the
tracer carries no other state from branch to branch) and the recorded trace is taken, its
warnings issued again here; otherwise the branch is traced here as before. Which branches are
traced ahead is only a matter of speed, never of the result.
"""
from __future__ import annotations

import warnings

__all__ = ["Speculator", "take", "taken"]

_NONE = object()  # "no result ahead of time"


def _recorder():
    seen = []

    def stop(pt):
        seen.append(pt)
        return False
    return stop, seen


def _run(func):
    """(result, recorded points, warnings) of func(stop) with a recording stop rule."""
    stop, seen = _recorder()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = func(stop)
    return res, seen, [(w.message, w.category) for w in caught]


def _seed_job(args):
    """A branch through a polished start traced both ways (diagram._both_ways)."""
    from .diagram import _both_ways

    tracer, label, prob, u, p = args
    tracer.label = label
    return _run(lambda stop: _both_ways(tracer, prob, u, p, stop=stop))


def _switch_job(args):
    """The branch switched at a period doubling (diagram._trace_switched)."""
    from .diagram import _trace_switched

    tracer, label, pt, order, pd_values = args
    tracer.label = label
    return _run(lambda stop: _trace_switched(tracer, pt, order, (), pd_values, overlap=stop))


class Speculator:
    """Branch traces started ahead on ``pool`` (module doc), taken by key."""

    def __init__(self, pool):
        self.pool = pool
        self.futures = {}

    def seed(self, key, tracer, label, prob, u, p):
        """Start tracing the branch through (prob, u, p) (diagram.trace_from)."""
        if key not in self.futures:
            self.futures[key] = self.pool.submit(_seed_job, (tracer, label, prob, u, p))

    def switch(self, key, tracer, label, pt, order, pd_values):
        """Start the branch switched at the period doubling ``pt`` (diagram._trace_switched)."""
        if key not in self.futures:
            self.futures[key] = self.pool.submit(_switch_job,
                                                 (tracer, label, pt, order, list(pd_values)))

    def pending(self, key):
        return key in self.futures

    def cancel(self, key):
        """Drop the trace ahead of ``key`` (its start was skipped)."""
        fut = self.futures.pop(key, None)
        if fut is not None:
            fut.cancel()

    def take(self, key, stop):
        """The result traced ahead for ``key`` if the serial ``stop`` rule would not have
        stopped it at any point it saw, else ``_NONE`` (trace it here). A trace that failed
        ahead is traced here too (which raises the same error)."""
        fut = self.futures.pop(key, None)
        if fut is None:
            return _NONE
        try:
            res, seen, caught = fut.result()
        except Exception:  # noqa: BLE001 (reproduced by the serial trace)
            return _NONE
        for pt in seen:
            if stop(pt):
                return _NONE
        for message, category in caught:
            warnings.warn(message, category, stacklevel=3)
        return res

    def close(self):
        for key in list(self.futures):
            self.cancel(key)


def take(ahead, key, stop):
    """``ahead.take(key, stop)``, or no result when ahead is None (no pool)."""
    return _NONE if ahead is None else ahead.take(key, stop)


def taken(res):
    """True when ``take`` gave a result."""
    return res is not _NONE
