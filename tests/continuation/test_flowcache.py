"""The shooting problems' kept flows (continuation._flowcache) are the flows themselves: a hit
equals a fresh integration bit for bit (with and without the variational equations, a plain
request answered by a kept variational flow included), nothing else is ever answered (other
model, excitation, start, contact state or settings), a caller cannot change a kept flow, the
memory stays bounded, and a diagram is the same with and without them."""
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation import _flowcache
from continuation.shooting import Integrator, ShootingProblem, forcing
from nlbeam.parameters import with_parameter

A = 1e-4
FIELDS = ("state", "disc", "xmax", "monodromy")


@pytest.fixture(autouse=True)
def fresh_cache():
    _flowcache.clear()
    _flowcache.hits.update(plain=0, var=0)
    was = _flowcache.enabled
    _flowcache.enabled = True
    yield
    _flowcache.enabled = was
    _flowcache.clear()


def _problem(model, f, **kw):
    return ShootingProblem(model, A, f, 1, [0.0], Integrator(**kw))


def _fresh(prob, model, ex, state, phase0, dphi, **kw):
    """The same flow computed with the kept flows switched off."""
    _flowcache.enabled = False
    try:
        return prob.flow_phases(model, ex, state, phase0, dphi, **kw)
    finally:
        _flowcache.enabled = True


def _equal(a, b, fields=FIELDS):
    for name in fields:
        u, v = getattr(a, name), getattr(b, name)
        if u is None or v is None:
            assert u is None and v is None, name
        else:
            assert u.tobytes() == v.tobytes(), name
    assert a.n_impacts == b.n_impacts


def _starts(model, f, n=6, seed=3):
    rng = np.random.default_rng(seed)
    N = model.n_dof
    scale = np.r_[np.full(N, 3e-4), np.full(N, 3e-4 * 2 * np.pi * f)]
    return [rng.normal(size=2 * N) * scale for _ in range(n)]


@pytest.mark.parametrize("f", [9.3, 44.0, 130.0])
def test_hits_equal_fresh_flows_bit_for_bit(f):
    model = nlbeam.BeamImpact.paper()
    prob = _problem(model, f)
    ex = forcing(A, f)
    for s in _starts(model, f):
        first = prob.flow_phases(model, ex, s, 0.25, 1.0, monodromy=True, newton=True)
        again = prob.flow_phases(model, ex, s, 0.25, 1.0, monodromy=True, newton=True)
        plain = prob.flow_phases(model, ex, s, 0.25, 1.0, newton=True)  # from the var flow
        fresh_var = _fresh(prob, model, ex, s, 0.25, 1.0, monodromy=True, newton=True)
        fresh_plain = _fresh(prob, model, ex, s, 0.25, 1.0, newton=True)
        _equal(first, fresh_var)
        _equal(again, fresh_var)
        _equal(plain, fresh_plain, FIELDS[:3])
    assert _flowcache.hits["var"] >= len(_starts(model, f))


@pytest.mark.parametrize("method", ["rk4", "adaptive"])
def test_plain_from_variational_on_a_modal_beam(method):
    """A plain request answered by a kept variational flow equals a fresh plain flow also for
    several modes and the adaptive method (whose steps must not depend on the variational
    equations)."""
    model = nlbeam.ModalBeam.paper(n_modes=2)
    f = 44.0
    prob, ex = _problem(model, f, method=method), forcing(A, f)
    for s in _starts(model, f, n=4, seed=11):
        prob.flow_phases(model, ex, s, 0.1, 1.0, monodromy=True)
        plain = prob.flow_phases(model, ex, s, 0.1, 1.0)
        _equal(plain, _fresh(prob, model, ex, s, 0.1, 1.0), FIELDS[:3])
    assert _flowcache.hits["plain"] == 4


def test_no_answer_for_another_flow():
    """Requests that differ in any input get their own flow (compared with fresh ones)."""
    model = nlbeam.BeamImpact.paper()
    other = with_parameter(model, "e", 0.5 * model.parameters()["e"])
    f = 22.0
    s = _starts(model, f, n=1)[0]
    prob = _problem(model, f)
    prob_o = _problem(other, f)
    prob_fine = _problem(model, f, dt_scale=0.5)
    disc = np.zeros((model.n_elements, 2))
    cases = [(prob, model, forcing(A, f), s, 0.0, 1.0, {}),
             (prob_o, other, forcing(A, f), s, 0.0, 1.0, {}),  # another model
             (prob, model, forcing(1.1 * A, f), s, 0.0, 1.0, {}),  # another excitation
             (prob, model, forcing(A, f), s * (1 + 1e-12), 0.0, 1.0, {}),  # another start
             (prob, model, forcing(A, f), s, 0.5, 1.0, {}),  # another phase
             (prob, model, forcing(A, f), s, 0.0, 0.5, {}),  # another duration
             (prob_fine, model, forcing(A, f), s, 0.0, 1.0, {}),  # another step
             (prob, model, forcing(A, f), s, 0.0, 1.0, {"disc0": disc})]
    for q, m, ex, st, ph, d, kw in cases:
        _equal(q.flow_phases(m, ex, st, ph, d, **kw), _fresh(q, m, ex, st, ph, d, **kw),
               FIELDS[:3])
    assert _flowcache.hits["plain"] == 0 and _flowcache.hits["var"] == 0


def test_pickled_problems_keep_their_meaning():
    """A problem sent to another process (pickled with its FlowMap) asks for its own model's
    flows: the same flow is a hit, another model's problem at the same inputs is not."""
    import pickle

    model = nlbeam.BeamImpact.paper()
    other = with_parameter(model, "K_hertz", 2.0 * model.parameters()["K_hertz"])
    f = 9.3
    ex = forcing(A, f)
    s = _starts(model, f, n=1)[0]
    p_m, p_o = _problem(model, f), _problem(other, f)
    p_m.flow_phases(model, ex, s, 0.0, 1.0)
    p_o.flow_phases(other, ex, s, 0.0, 1.0)
    q_m, q_o = pickle.loads(pickle.dumps(p_m)), pickle.loads(pickle.dumps(p_o))
    m2, o2 = q_m.base_model, q_o.base_model  # (unpickled models: other objects)
    _equal(q_o.flow_phases(o2, ex, s, 0.0, 1.0), _fresh(p_o, other, ex, s, 0.0, 1.0),
           FIELDS[:3])
    _equal(q_m.flow_phases(m2, ex, s, 0.0, 1.0), _fresh(p_m, model, ex, s, 0.0, 1.0),
           FIELDS[:3])


def test_a_caller_cannot_change_a_kept_flow():
    model = nlbeam.BeamImpact.paper()
    f = 44.0
    prob, ex = _problem(model, f), forcing(A, f)
    s = _starts(model, f, n=1)[0]
    a = prob.flow_phases(model, ex, s, 0.0, 1.0, monodromy=True)
    ref = _fresh(prob, model, ex, s, 0.0, 1.0, monodromy=True)
    a.state[:] = 0.0
    a.monodromy[:] = 0.0
    b = prob.flow_phases(model, ex, s, 0.0, 1.0, monodromy=True)
    b.xmax[:] = 0.0
    _equal(prob.flow_phases(model, ex, s, 0.0, 1.0, monodromy=True), ref)


def test_memory_is_bounded(monkeypatch):
    monkeypatch.setattr(_flowcache, "MAX_BYTES", 20_000)
    model = nlbeam.BeamImpact.paper()
    f = 60.0
    prob, ex = _problem(model, f), forcing(A, f)
    starts = _starts(model, f, n=40, seed=5)
    for s in starts:
        prob.flow_phases(model, ex, s, 0.0, 0.2, monodromy=True)
    assert 0 < _flowcache._bytes <= 20_000
    assert len(_flowcache._flows) < len(starts)
    # the most recent ones are kept, the first ones dropped (computed again: no hit)
    prob.flow_phases(model, ex, starts[-1], 0.0, 0.2, monodromy=True)
    assert _flowcache.hits["var"] == 1
    prob.flow_phases(model, ex, starts[0], 0.0, 0.2, monodromy=True)
    assert _flowcache.hits["var"] == 1


def test_diagram_same_with_and_without_kept_flows():
    model = nlbeam.BeamImpact.paper()
    out = []
    for on in (False, True):
        _flowcache.clear()
        _flowcache.enabled = on
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out.append(C.frequency_response(model, A, (12.0, 16.0), orders=(1, 2), n_grid=4))
    a, b = out
    assert _flowcache.hits["var"] + _flowcache.hits["plain"] > 0
    assert len(a.branches) == len(b.branches) and a.n_points == b.n_points
    for x, y in zip(a.branches, b.branches):
        for name in ("frequency", "xmax", "multipliers", "xmax_error", "multipliers_error"):
            u, v = getattr(x, name), getattr(y, name)
            assert (u is None and v is None) or np.array_equal(u, v, equal_nan=True), name
    assert [(q.kind, q.frequency, q.tolerance) for q in a.bifurcations] == \
        [(q.kind, q.frequency, q.tolerance) for q in b.bifurcations]
    assert np.array_equal([q.error for q in a.bifurcations], [q.error for q in b.bifurcations],
                          equal_nan=True)
