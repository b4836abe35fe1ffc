"""Flows of the shooting problems already computed, kept for when the same flow is asked for
again (a diagram asks for about 7 % of its flows twice: accepted branch points evaluated
again by the error estimates, states at phase zero, trial points re-solved from the same
start, forward differences at a point already differenced).

A flow is a deterministic function of its arguments, so a kept one is the same result bit for
bit: the key holds everything the kernel reads (the model's kernel arrays, the excitation's,
the method and its settings, the start state and contact state, start time, duration, step
and step limit). A flow with the variational equations also answers a request without them
(the trajectory is the same: the variational equations do not steer the steps). A flow is
kept as a copy and a hit returns a copy (arrays included): what a caller does with its flow
never changes what a later caller gets.

Memory is bounded (``MAX_BYTES`` per process, least recently used flows dropped first); ``clear()``
empties it, ``enabled = False`` turns it off (every flow computed).
"""
from __future__ import annotations

import copy
import threading
from collections import OrderedDict

import numpy as np

#: the most bytes kept (least recently used flows are dropped first): about 23 000 flows of a
#: 1-DOF model (the paper diagram computes about 51 000)
MAX_BYTES = 48 * 2 ** 20
#: per kept flow, for the objects around the arrays (measured with tracemalloc: 2.2 kB per
#: flow of the paper model with monodromy, of which 0.1 kB its arrays and key bytes)
OVERHEAD = 2000

enabled = True
_flows = OrderedDict()  # key -> (model, Flow, bytes)
_bytes = 0
hits = {"plain": 0, "var": 0}
_lock = threading.Lock()  # (a Dask worker may run tasks in threads)


_interned = {}  # kernel arrays' contents -> one object of them, shared by every key


def _bytes_of(*arrays):
    """The contents of the arrays (numbers too), shapes and types included."""
    out = []
    for a in arrays:
        a = np.ascontiguousarray(a)
        out.append((a.dtype.str, a.shape, a.tobytes()))
    return tuple(out)


def key(fm, state, t0, duration, disc0, dt, max_steps):
    """The key of the flow of FlowMap ``fm`` from ``state`` at t0 (s) over duration (s) with
    contact state disc0 (None: the start-in-contact rule), step dt (s) and step limit."""
    sys_key = getattr(fm, "_cache_sys", None)
    if sys_key is None or sys_key[0] is not fm.sysa:
        # the contents themselves (one object shared by the keys of this map, which a pickled
        # map carries to another process with the same meaning)
        contents = _bytes_of(*fm.sysa)
        if len(_interned) >= 256:
            _interned.clear()  # (only the sharing is lost)
        sys_key = (fm.sysa, _interned.setdefault(contents, contents))
        fm._cache_sys = sys_key
    ex_key = getattr(fm, "_cache_ex", None)
    if ex_key is None or not (ex_key[0] is fm.xc and ex_key[1] is fm.xp
                              and ex_key[2] is fm.xtab):
        ex_key = (fm.xc, fm.xp, fm.xtab, _bytes_of(fm.xc, fm.xp, fm.xtab))
        fm._cache_ex = ex_key  # (FlowMap.retarget gives new arrays: computed again)
    return (sys_key[1], ex_key[3], fm.meth, fm.spc, fm.rtol, fm.atol,
            fm.events, fm.graded, np.asarray(state, dtype=float).tobytes(), float(t0),
            float(duration), None if disc0 is None else _bytes_of(disc0), float(dt),
            int(max_steps))


def get(k, model, monodromy):
    """A kept flow for key k of model (with the variational equations if ``monodromy``), or
    None."""
    if not enabled:
        return None
    with _lock:
        for mono in ((True,) if monodromy else (False, True)):
            hit = _flows.get((k, mono))
            if hit is not None and hit[0] is model:
                _flows.move_to_end((k, mono))
                hits["var" if monodromy else "plain"] += 1
                return _copy(hit[1])
    return None


_ARRAYS = ("state", "disc", "xmax", "monodromy", "dstate_dvminus0", "dvminus_dstate0",
           "dvminus_dvminus0")


def _copy(flow):
    """A copy of an nlbeam.Flow with copies of its arrays (its fields copied directly: a
    Flow is a plain dataclass, and copy.copy's generic path costs more than the copies)."""
    cls = type(flow)
    if (cls.__reduce_ex__ is not object.__reduce_ex__ or hasattr(cls, "__copy__")
            or getattr(cls, "__getstate__", None) is not getattr(object, "__getstate__", None)
            or not hasattr(flow, "__dict__")):
        out = copy.copy(flow)
    else:
        out = object.__new__(cls)
        out.__dict__.update(flow.__dict__)
    d = out.__dict__
    for name in _ARRAYS:
        a = d.get(name)
        if type(a) is np.ndarray:
            d[name] = a.copy()
        elif isinstance(a, np.ndarray):
            setattr(out, name, a.copy())
    return out


def put(k, model, monodromy, flow):
    """Keep a copy of ``flow`` (of model, with the variational equations if ``monodromy``)
    under key k."""
    global _bytes
    if not enabled:
        return
    flow = _copy(flow)
    size = OVERHEAD + len(k[8]) + (0 if k[11] is None else len(k[11][0][2]))
    size += sum(a.nbytes for a in map(flow.__dict__.get, _ARRAYS) if isinstance(a, np.ndarray))
    with _lock:
        old = _flows.pop((k, bool(monodromy)), None)
        if old is not None:
            _bytes -= old[2]
        _flows[(k, bool(monodromy))] = (model, flow, size)
        _bytes += size
        while _bytes > MAX_BYTES and _flows:
            _bytes -= _flows.popitem(last=False)[1][2]


def clear():
    """Drop every kept flow."""
    global _bytes
    with _lock:
        _flows.clear()
        _bytes = 0
