"""frequency_response on several processes or a Dask cluster gives the serial diagram: the same
branches (order, origin, ends, points), bifurcations and arrays (continuation.parallel: a
branch traced ahead is taken only where the serial stop rule would not have stopped it)."""
import dataclasses
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam

A = 1e-4


def _diagram(f_range, orders, n_grid, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frc = C.frequency_response(nlbeam.BeamImpact.paper(), A, f_range, orders=orders,
                                   n_grid=n_grid, **kw)
    return frc, sorted(str(w.message) for w in caught
                       if issubclass(w.category, C.ContinuationWarning))


def _same(a, b, rtol=1e-12):
    """The two diagrams agree: the same structure exactly, the numbers to rtol (relative to
    each array's largest magnitude; NaN where the other has NaN)."""
    assert len(a.branches) == len(b.branches)
    assert [(x.kind, x.order, x.branch, x.note) for x in a.bifurcations] == \
        [(y.kind, y.order, y.branch, y.note) for y in b.bifurcations]
    pairs = list(zip(a.branches, b.branches)) + list(zip(a.bifurcations, b.bifurcations))
    for x, y in pairs:
        for f in dataclasses.fields(x):
            u, v = getattr(x, f.name), getattr(y, f.name)
            if f.name == "refined":
                continue
            if isinstance(u, np.ndarray) or isinstance(v, np.ndarray):
                assert u is not None and v is not None and u.shape == v.shape, f.name
                if u.dtype == bool:
                    assert np.array_equal(u, v), f.name
                    continue
                assert np.array_equal(np.isnan(u), np.isnan(v)), f.name
                scale = max(float(np.nanmax(np.abs(u), initial=0.0)), 1e-300)
                assert np.nanmax(np.abs(u - v), initial=0.0) <= rtol * scale, f.name
            elif isinstance(u, float):
                assert (np.isnan(u) and np.isnan(v)) or abs(u - v) <= rtol * abs(u), f.name
            else:
                assert u == v, f.name
    assert [(s.harmonic, s.branch) for s in a.superharmonics] == \
        [(s.harmonic, s.branch) for s in b.superharmonics]


def test_two_processes_give_the_serial_diagram():
    # orders 1 and 2: starts skipped on traced branches, branches that run onto others,
    # period doublings switched to order 2; error estimates of every point
    serial, w1 = _diagram((15.0, 19.0), (1, 2), 5)
    par, w2 = _diagram((15.0, 19.0), (1, 2), 5, workers=2)
    assert any(b.origin == "period-doubling" for b in serial.branches)
    _same(serial, par)
    assert w1 == w2  # the same warnings, issued again from the processes


def test_dask_cluster_gives_the_serial_diagram():
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    serial, _ = _diagram((15.0, 17.0), (1, 2), 3)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        there, _ = _diagram((15.0, 17.0), (1, 2), 3, scheduler=cluster.scheduler_address)
    _same(serial, there)


def test_bad_workers_is_a_clear_error():
    with pytest.raises(ValueError, match="^workers"):
        C.frequency_response(nlbeam.BeamImpact.paper(), A, (15.0, 17.0), workers=0)


def test_serial_estimates_during_the_trace_equal_estimates_afterwards():
    # the serial run estimates each branch right after its trace (its level-0 flows still
    # kept, continuation._flowcache): the numbers of estimate_diagram on the finished diagram
    from continuation.accuracy import estimate_diagram

    during, _ = _diagram((15.0, 19.0), (1, 2), 5)
    after, _ = _diagram((15.0, 19.0), (1, 2), 5, accuracy="off")
    estimate_diagram(after, nlbeam.BeamImpact.paper(), C.Integrator())
    assert all(b.error_sampled.any() for b in during.branches)
    assert any(np.isfinite(bf.error) for bf in during.bifurcations)
    _same(during, after)
