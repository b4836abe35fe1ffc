"""A branch of the 4-mode beam that runs onto a jump of its flow map (the Lankarani-Nikravesh
onset-velocity memory resets where two contacts merge: 8 -> 7 impacts per period) ends there
as 'discontinuous map', and finds out after a few failed steps, not after halving the step
down to ds_min and trying multiple shooting (counted in flows, not timed)."""
import warnings

import numpy as np

import continuation as C
import nlbeam
from continuation.corners import map_jump
from continuation.diagram import _polish
from continuation.pathfollow import Tracer
from continuation.shooting import _problem_from_state

A = 1e-4


def _trace_down(f0=12.1, lo=12.0, **kw):
    """The order-1 branch of ModalBeam.paper(n_modes=4) through f0 Hz, traced downwards (it
    turns at a fold near 12.0067 Hz and runs up into the jump near 12.016 Hz)."""
    model = nlbeam.ModalBeam.paper(n_modes=4)
    sol = C.periodic_solution(model, A, f0)
    prob, u0 = _problem_from_state(model, A, f0, 1, sol.state0, 1, C.Integrator())
    prob, u, p = _polish(prob, u0, f0, 1e-10)
    tr = Tracer(p_min=lo, p_max=f0 + 0.02, ds=0.02, ds_max=0.5, max_angle=0.2,
                max_points=300, tol=1e-10, bif_tol=1e-8, **kw)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pts, loc, reason = tr.trace(prob, u, p, direction=-1)
    return tr, prob, pts, reason, caught


def test_modal_branch_ends_at_the_jump_of_its_map_without_giving_up():
    tr, prob, pts, reason, caught = _trace_down()
    assert reason == "discontinuous map"
    assert any("discontinuous just beyond" in str(w.message) for w in caught)
    last = pts[-1]
    # past the fold at 12.0067 Hz, before the jump (12.016 Hz before main a9db3e3's contact
    # step caps; there both correctors end at 12.0177-12.0178 Hz)
    assert 12.010 < last.p < 12.019
    assert min(q.p for q in pts) < 12.007
    # the map does jump ahead of the last point: from the secant into the jump, |R| rises
    # to ~1e-2 within 1e-3 (scaled) and stays there
    w, wp = prob.scale_u, prob.scale_p
    z1 = np.r_[pts[-2].u / w, pts[-2].p / wp]
    z2 = np.r_[last.u / w, last.p / wp]
    t = (z2 - z1) / np.linalg.norm(z2 - z1)
    h, r = map_jump(prob, z2, t)
    assert h <= 1e-3 and r > 1e-3
    # counted work after the last point: a few failed steps, far-side solves and one probe
    # (on main c6a4625 the same end cost 11 more halvings down to ds_min and 2- and
    # 4-segment shooting first: 615 flows for the branch both ways against 350)
    assert tr.end_evaluations <= 120, tr.end_evaluations


def test_without_the_probe_the_same_end_is_given_up_or_costs_more_work():
    """The probe is what names the end and saves the work: with probe_after=0 (the map is
    probed only once every other way has failed) the branch creeps on towards the same jump
    with ever shorter steps, each found by failed steps first, and either gives up there
    ('step underflow': which of the two round-off decides, e.g. OpenBLAS core types on main
    0a5858f) or ends at the jump after more flows; with the probe it ends at the jump, named."""
    # (both with every corrector iterate's variational equations, so that a flow counts the
    # same in both: the probe's saving alone)
    tr0, _, pts0, reason0, _ = _trace_down(probe_after=0, lazy_var=False)
    tr, _, pts, reason, _ = _trace_down(lazy_var=False)
    assert reason == "discontinuous map"
    assert reason0 in ("discontinuous map", "step underflow"), reason0
    assert abs(pts0[-1].p - pts[-1].p) < 2e-3
    print(f"flows: {tr0.n_evaluations} without the probe ({reason0}), {tr.n_evaluations} "
          f"with it; points {len(pts0)}, {len(pts)}")
    # (measured on main a9db3e3, both eager: 923 flows with the probe, 1059 without; 487
    # and 893 before its contact step caps; with nlbeam._linalg: step underflow at
    # 12.017510 Hz after 685 flows without the probe, the jump at 12.017508 Hz after 717; with
    # the modal matrices from nlbeam._linalg too (s10-roundoff): the jump after 595 flows
    # without the probe, 546 with it: how much the probe saves is round-off's, that it saves)
    if reason0 == "discontinuous map":
        assert tr.n_evaluations < tr0.n_evaluations


def test_lazy_variational_equations_trace_the_same_branch_with_fewer_of_them():
    """Tracer(lazy_var=True) (the default): the corrector's iterates after the predictor are
    flows without the variational equations unless one is expected to be the last, and an
    accepted iterate without them is evaluated again with them. The branch is the same: the
    same end at the jump, the fold at the same frequency (its bracket, bif_tol 1e-8), the
    multipliers of the points at the same frequencies the same to the corrector's tolerance;
    the flows with the variational equations per branch point (5.8 times the cost of a flow
    without them at N = 4) fall by more than 30 %."""
    tr0, _, pts0, reason0, _ = _trace_down(lazy_var=False)
    tr, _, pts, reason, _ = _trace_down(lazy_var=True)
    assert reason0 == reason == "discontinuous map"
    assert abs(pts0[-1].p - pts[-1].p) < 2e-3
    assert abs(min(q.p for q in pts0) - min(q.p for q in pts)) < 1e-6
    # the first points (before any corner) lie at the same frequencies: same multipliers
    for a, b in zip(pts0[:5], pts[:5]):
        if abs(a.p - b.p) < 1e-9 * a.p:
            assert np.max(np.abs(np.sort_complex(a.multipliers)
                                 - np.sort_complex(b.multipliers))) < 1e-6
    print(f"flows with the variational equations: {tr0.n_variational} eager, "
          f"{tr.n_variational} lazy (all flows {tr0.n_evaluations}, {tr.n_evaluations})")
    # per branch point (the lazy corrector's iterations are more, so its steps a little
    # shorter: measured 34 against 28 points, 203 against 301 such flows)
    assert tr.n_variational / len(pts) < 0.7 * tr0.n_variational / len(pts0)
    assert all(q.multipliers is not None for q in pts)
