"""Whole diagrams that pass corners: each range covered once (a branch reverses in the
parameter only at a fold it reports), the branch that the old tracer lost at a corner is there,
and what no branch covers is named in one ContinuationWarning.

The systems of issue 13: the paper model at A = 0.2 mm (10-120 Hz), a Duffing oscillator with a
one-sided linear stop, and a 2-DOF system with a gapped Lankarani-Nikravesh stop on its second
mass in amplitude continuation. Before corners were checked, each traced a stretch twice: the
paper model's harmonic branch ran 120.7 -> 11.66 -> 120.2 Hz (10-11.66 Hz never computed), the
Duffing branch turned back at its non-smooth fold at 1.0675 Hz onto the stretch it came from
(the non-impacting branch up to 3 Hz missing), the 2-DOF branch turned at the grazing corner at
A = 3.596e-5 and never went below 2.14e-5."""
import re
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation.diagram import _polish
from continuation.pathfollow import Tracer
from continuation.shooting import Integrator, _problem_from_state
from continuation.turns import turn_indices, turns


def test_turns_are_the_extrema_left_by_more_than_the_noise():
    # 2 and 1.5 are left by 0.5 and 1.5; the last step back (1e-7) is below noise * 3
    assert turns([0.0, 1.0, 2.0, 1.5, 3.0, 2.9999999]) == [2.0, 1.5]
    assert turns([5.0, 4.0, 4.0000001, 3.0]) == []
    assert turns([1.0, 2.0, 1.0], noise=2.0) == []
    # the same turns by index, +1 at a maximum and -1 at a minimum
    assert turn_indices([0.0, 1.0, 2.0, 1.5, 3.0, 2.9999999]) == [(2, 1), (3, -1)]


def _assert_turns_at_folds(values, folds, rel):
    """Every reversal of the parameter along a branch lies at a distinct fold of it (within rel
    of the fold's value, or of the branch's steps there): no stretch is traced twice except
    through folds."""
    free = sorted(folds)
    for x in turns(values):
        near = [f for f in free if abs(f - x) <= rel * abs(x)]
        assert near, f"the branch turns back at {x:.9g} without a fold (folds: {free})"
        free.remove(min(near, key=lambda f: abs(f - x)))


def _branch_folds(frc, i):
    return [b.value for b in frc.bifurcations if b.branch == i and b.kind == "fold"]


def _no_bifurcation_twice(frc):
    seen = []
    for b in frc.bifurcations:
        for o in seen:
            assert not (o.kind == b.kind and o.order == b.order and
                        abs(o.value - b.value) <= 1e-7 * abs(b.value) and
                        abs(o.xmax - b.xmax) <= 1e-5 * abs(b.xmax)), (b.kind, b.value)
        seen.append(b)


def _covers(frc, order, lo, hi):
    iv = sorted((b.values.min(), b.values.max()) for b in frc.branches if b.order == order)
    assert iv and iv[0][0] <= lo, iv
    reach = iv[0][1]
    for a, c in iv[1:]:
        assert a <= reach, f"order {order} not covered between {reach} and {a}"
        reach = max(reach, c)
    assert reach >= hi, iv


@pytest.fixture(scope="module")
def paper_2e4():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        frc = C.frequency_response(nlbeam.BeamImpact.paper(), 2e-4, (10.0, 120.0), orders=(1,),
                                   n_grid=12)
    return frc, [str(x.message) for x in w if issubclass(x.category, C.ContinuationWarning)]


def test_paper_model_at_02mm_covers_10_to_120_hz_once(paper_2e4):
    frc, msgs = paper_2e4
    _covers(frc, 1, 10.0, 120.0)
    for i, b in enumerate(frc.branches):
        _assert_turns_at_folds(b.values, _branch_folds(frc, i), 5e-3)
    _no_bifurcation_twice(frc)
    # at the corner at 11.683-11.687 Hz (3 -> 4 impacts, a multiplier from |0.31| to 3-6) the
    # branch turns back onto the unstable 4-impact orbits: a fold reported there (at the
    # corner, or the smooth one of the 4-impact orbits just past it, 11.70 Hz with the map's
    # exact derivative), and the branch's turn near the corner is at it (checked above)
    assert any(b.kind == "fold" and abs(b.frequency - 11.69) < 3e-2 for b in frc.bifurcations)
    assert any(turns(b.values) and any(abs(t - 11.69) < 3e-2 for t in turns(b.values))
               for b in frc.branches)
    assert not any("not covered" in m for m in msgs), msgs


@pytest.mark.slow
def test_paper_model_at_02mm_orders_1_and_2():
    """The issue's command: `nlbeam frc --amplitude 2e-4 --f-range 10 120 --orders 1 2`."""
    frc = C.frequency_response(nlbeam.BeamImpact.paper(), 2e-4, (10.0, 120.0), orders=(1, 2))
    _covers(frc, 1, 10.0, 120.0)
    for i, b in enumerate(frc.branches):
        if b.order == 1:  # (a branch switched at a period doubling may pass its pitchfork)
            _assert_turns_at_folds(b.values, _branch_folds(frc, i), 5e-3)
    _no_bifurcation_twice(frc)


def _duffing_with_stop():
    return nlbeam.System([[1.0]], [[0.2513]], [[39.48]],
                         elements=(nlbeam.CubicSpring(0, k3=10.0),
                                   nlbeam.PiecewiseLinearStop(0, k=789.6, gap=0.5,
                                                              on_base=False)),
                         excitation_kind="force", y_load=[1.0])


def test_duffing_with_stop_diagram_has_its_non_impacting_branch_to_3_hz():
    m = _duffing_with_stop()
    frc = C.frequency_response(m, 2.0, (0.3, 3.0), orders=(1, 2))
    _covers(frc, 1, 0.3, 3.0)
    for i, b in enumerate(frc.branches):
        _assert_turns_at_folds(b.values, _branch_folds(frc, i), 5e-3)
    # the non-impacting branch (|x| < gap) from the non-smooth fold at 1.0675 Hz to 3 Hz
    ones = [b for b in frc.branches if b.order == 1]
    assert any(np.any((b.frequency >= 3.0) & (b.xmax < 0.5)) and
               np.any((b.frequency < 1.1) & (b.xmax < 0.5) & (b.frequency > 1.06))
               for b in ones)
    assert any(b.kind == "fold" and abs(b.frequency - 1.0675) < 2e-3 for b in frc.bifurcations)


@pytest.mark.parametrize("f0", [0.3, 0.5, 0.8])
@pytest.mark.parametrize("ds", [0.01, 0.05, 0.1])
def test_duffing_with_stop_branch_from_any_start_passes_its_corner(f0, ds):
    """The branch traced up from f0 with first step ds: through the fold at 1.4267 Hz, back to
    the corner at 1.0675 Hz, and on along the non-impacting branch to 3 Hz, whatever the step
    sizes (before, most of these traces turned back at the corner and ran down to 0.3 Hz)."""
    m = _duffing_with_stop()
    integ = Integrator()
    sol = C.periodic_solution(m, 2.0, f0)
    prob, u0 = _problem_from_state(m, 2.0, f0, 1, sol.state0, 1, integ)
    prob, u, p = _polish(prob, u0, f0, 1e-10)
    tr = Tracer(p_min=0.3, p_max=3.0, ds=ds, ds_max=0.1, max_angle=0.2, bif_tol=1e-8)
    pts, loc, reason = tr.trace(prob, u, p, direction=1)
    assert reason == "left the parameter range" and pts[-1].p > 3.0 and pts[-1].xmax < 0.5
    _assert_turns_at_folds(np.array([q.p for q in pts]),
                           [L.point.p for L in loc if L.kind == "fold"], 5e-3)
    assert len(turns([q.p for q in pts])) == 2


def test_two_dof_amplitude_continuation_reaches_the_lower_limit():
    """2-DOF system with a stop on the second mass (gap 0.1 mm, on the base) at 25 Hz: the
    branch from A = 0.1 mm passes the fold at 2.14e-5 and the non-smooth fold at the grazing
    corner at 3.60e-5 (impacting orbits with a multiplier of 5 meet the stable non-impacting
    ones) and goes on down the non-impacting branch below 2e-5."""
    K = np.array([[1200.0, -400.0], [-400.0, 400.0]])
    m = nlbeam.System(np.diag([0.04, 0.02]), 1e-4 * K, K, elements=(
        nlbeam.Contact(dof=1, law="lankarani-nikravesh", K=1e8, e=0.7, gap=1e-4),),
        excitation_kind="base")
    sol = C.periodic_solution(m, 1e-4, 25.0)
    frc = C.continue_parameter(sol, "amplitude", (2e-5, 3e-4), model=m)
    (b,) = frc.branches
    assert b.values.min() < 2e-5 and b.values.max() > 3e-4
    assert sorted(b.ends) == ["left the parameter range"] * 2
    _assert_turns_at_folds(b.values, _branch_folds(frc, 0), 5e-3)
    assert len(turns(b.values)) == 2
    assert any(g.kind == "grazing" and abs(g.value - 3.6e-5) < 1e-7 for g in frc.bifurcations)


def test_uncovered_range_is_named_in_one_warning():
    """A diagram whose only branch stops early (the point budget) leaves parts of the range
    uncovered: one ContinuationWarning names them with the branch's own end values; a diagram
    with no branch at all says so."""
    m = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    kw = dict(orders=(1,), dt_scale=0.2, switch=False, brute_force_grid=False)
    sol = C.periodic_solution(m, 0.05, 0.3, dt_scale=0.2)
    with pytest.warns(C.ContinuationWarning) as rec:
        frc = C.frequency_response(m, 0.05, (0.1, 0.5), max_points=6,
                                   starts=[(0.3, 1, sol.state0)], **kw)
    msgs = [str(r.message) for r in rec if "not covered" in str(r.message)]
    assert len(msgs) == 1
    (b,) = frc.branches
    lo, hi = b.values.min(), b.values.max()
    got = [(float(a), float(c)) for a, c in re.findall(r"order 1: ([0-9.e-]+)-([0-9.e-]+) Hz",
                                                       msgs[0])]
    assert got == [pytest.approx((0.1, lo), rel=1e-5), pytest.approx((hi, 0.5), rel=1e-5)]
    assert frc.uncovered(1) == [pytest.approx(g, rel=1e-5) for g in got]
    assert "max_points" in msgs[0]
    with pytest.warns(C.ContinuationWarning, match=r"no branch of order\(s\) 1 was found"):
        empty = C.frequency_response(m, 0.05, (0.1, 0.5), **kw)
    assert empty.branches == []
