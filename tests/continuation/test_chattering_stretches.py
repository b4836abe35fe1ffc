"""Deterministic answers where the number of impacts changes often (issue 13 item 4): a grazing
point's error estimate never lands on another change of the number of impacts, and the
stretches where the tracer gave up are declared by the diagram (and only those may differ
between two runs)."""
from types import SimpleNamespace

import numpy as np
import pytest

from continuation.accuracy import _grazing_bisect, _locate
from continuation.shooting import ConvergenceError


class Steps:
    """A stand-in for a shooting problem whose orbits have ``counts[i]`` impacts per period
    between breaks[i - 1] and breaks[i] (solves counted)."""

    def __init__(self, breaks, counts):
        self.breaks, self.counts, self.calls = list(breaks), list(counts), 0

    def solve(self, u, p, tol=1e-10, max_iter=12):
        self.calls += 1
        n = self.counts[int(np.searchsorted(self.breaks, p, side="right"))]
        return np.asarray(u, dtype=float), SimpleNamespace(n_impacts=n), 0.0, 1


def test_the_nearest_change_is_bisected_not_any_in_the_wide_bracket():
    """Changes at 1.0005 (5 -> 6), 1.0007 (6 -> 5), 1.0012 (5 -> 6): from 1.0 the search
    first sees another count at 1.0016 (widened 1e-4, 4e-4, 1.6e-3); bisecting [1.0, 1.0016]
    lands on 1.0012, the scan outward finds 1.0005."""
    prob = Steps([1.0005, 1.0007, 1.0012], [5, 6, 5, 6])
    p, u, half, pair = _grazing_bisect(prob, np.zeros(2), 1.0, 1e-4, 1e-9)
    assert abs(p - 1.0005) <= 2e-9 and half <= 1e-9 and pair == (5, 6)
    # mirrored: the nearest below
    prob = Steps([0.9988, 0.9993, 0.9995], [6, 5, 6, 5])
    p, u, half, pair = _grazing_bisect(prob, np.zeros(2), 1.0, 1e-4, 1e-9)
    assert abs(p - 0.9995) <= 2e-9 and pair == (6, 5)


def test_a_change_between_other_impact_counts_is_another_event():
    """The level before located a change 5 -> 6; the nearest change at this level is 6 -> 7:
    not this grazing point's estimate."""
    prob = Steps([1.0003, 1.0009], [5, 6, 7])
    p, *_ = _grazing_bisect(prob, np.zeros(2), 1.0004, 1e-4, 1e-9, expect=(5, 6))
    assert abs(p - 1.0003) < 2e-9  # the 5 -> 6 change, 1e-4 away
    with pytest.raises(ConvergenceError, match="another change"):
        _grazing_bisect(prob, np.zeros(2), 1.00085, 1e-4, 1e-9, expect=(5, 6))


def test_the_diagrams_own_bracket_is_not_widened_at_level_0():
    """Relocated at the diagram's step, a grazing point is searched inside the diagram's
    bracket only: a change 3 bracket widths away is another event."""
    prob = Steps([1.0003], [5, 6])
    with pytest.raises(ConvergenceError, match="no change"):
        _grazing_bisect(prob, np.zeros(2), 1.0, 1e-4, 1e-9, widen=False)
    assert prob.calls == 3  # p0 and its two sides
    hint = {"level0": True}
    with pytest.raises(ConvergenceError):
        _locate("grazing", prob, np.zeros(2), 1.0, 1e-4, 1e-9, hint)
    hint = {"level0": True}
    p, u, half = _locate("grazing", Steps([0.99995], [5, 6]), np.zeros(2), 1.0, 1e-4, 1e-9,
                         hint)
    # (the far side: the diagram's point, 6 impacts; -1: another number)
    assert abs(p - 0.99995) < 2e-9 and hint == {"level0": False, "impacts": (-1, 6), "far": 6}
    # the next level (the change moved by 2e-4, beyond the bracket): found by widening, and
    # the same event; a level whose nearest change is between other counts raises
    p, u, half = _locate("grazing", Steps([1.00015], [5, 6]), np.zeros(2), p, 1e-4, 1e-9,
                         hint)
    assert abs(p - 1.00015) < 2e-9
    with pytest.raises(ConvergenceError, match="another change"):
        _locate("grazing", Steps([1.0002], [6, 5]), np.zeros(2), p, 1e-4, 1e-9, hint)


# --- stretches the diagram declares unresolved -------------------------------------------------
def _branch(f0, f1, ends, order=2):
    f = np.linspace(f0, f1, 5)
    return SimpleNamespace(order=order, values=f, frequency=f, ends=ends, multipliers_error=None,
                           error_sampled=None)


def _diagram(end, grazing, order=2, reason="step underflow"):
    """A branch of this order from 58 Hz to ``end`` (where the tracer gave up: ``reason``) with
    grazing points at ``grazing``."""
    from continuation.diagram import Bifurcation, FrequencyResponse
    bifs = [Bifurcation("grazing", f, f, 1e-4, order, 0, 1e-6, None) for f in grazing]
    return FrequencyResponse({}, 1e-4, "frequency", (50.0, 70.0),
                             branches=[_branch(58.0, end, ("left the parameter range", reason),
                                               order)], bifurcations=bifs)


def test_a_give_up_end_declares_the_stretch_of_its_chained_events():
    """Around a give-up end: CHATTER_REACH of f on either side, widened over the branch's
    grazing points that follow each other within that reach (66.42 -> 66.47 -> 66.53 Hz: each
    within 1e-3 of f of the next; 66.2 Hz is not); an end that left the range, or ran onto
    another branch, declares nothing."""
    from continuation.diagram import CHATTER_REACH
    frc = _diagram(66.561, [66.2, 66.42, 66.47, 66.53])
    ((o, lo, hi, what),) = frc.unresolved()
    assert o == 2 and "66.561 (step underflow)" in what and "3 of its" in what
    assert lo == pytest.approx(66.42 * (1 - CHATTER_REACH)) and lo > 66.2
    assert hi == pytest.approx(66.561 * (1 + CHATTER_REACH))
    assert frc.unresolved(1) == [] and frc.unresolved(2)
    for reason in ("left the parameter range", "stop", "closed (isola)"):
        assert _diagram(66.561, [66.53], reason=reason).unresolved() == []
    for reason in ("discontinuous map", "stuck at a corner", "no progress"):
        assert _diagram(66.561, [66.53], reason=reason).unresolved()
    # the point budget: where it ends a branch is the count's doing, not the contacts'
    assert _diagram(66.561, [66.53], reason="max_points").unresolved() == []
    assert "unresolved" in dict(frc._summary_rows())


def test_the_warning_names_the_unresolved_stretch():
    import warnings

    from continuation import ContinuationWarning
    from continuation.diagram import _warn_coverage
    frc = _diagram(66.561, [66.53])
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        _warn_coverage(frc.branches, frc.p_range, (2,), "frequency", "Hz", "try this.",
                       frc.bifurcations)
    msg = [str(x.message) for x in w if issubclass(x.category, ContinuationWarning)]
    assert len(msg) == 1 and "unresolved" in msg[0] and "order 2: 66.4" in msg[0]


def test_comparison_skips_only_stretches_both_diagrams_declare():
    """Two runs that end the branch at 66.561 / 66.568 Hz with 0 against 2 grazing points on
    the last 0.03 Hz: matched, since both declare the stretch; the same events where one run's
    branch ran on (no declaration there) or outside the stretch: a difference."""
    import sys
    sys.path.insert(0, __file__.rsplit("/", 1)[0])
    from test_continuation_roundoff import structure_differences
    a = _diagram(66.561, [])
    b = _diagram(66.568, [66.545, 66.559])
    assert structure_differences(a, b) == []
    c = _diagram(66.568, [66.545, 66.559], reason="left the parameter range")
    assert structure_differences(a, c)  # c declares nothing: compared
    d = _diagram(66.568, [66.40, 66.559])  # 66.40 lies outside a's stretch
    assert structure_differences(a, d)


def test_a_flickering_count_beside_the_grazing_point_is_one_side():
    """The paper model's order-1 grazing point near 6.648 Hz: 3 impacts above it, below it the
    count flickers between 4 and 5 (a tiny impact comes and goes). Located from the far side
    (3), the level-0 bracket is no cluster and the finer level finds the edge of the 3-impact
    stretch 1.4e-3 Hz away, not a 4 / 5 flicker next to the level-0 value."""
    breaks0 = [6.6472, 6.64725, 6.64755, 6.64762]
    level0 = Steps(breaks0, [4, 5, 4, 5, 3])
    hint = {"level0": True}
    p, u, half = _locate("grazing", level0, np.zeros(2), 6.64785, 2.8e-4, 1e-9, hint)
    assert abs(p - 6.64762) < 1e-8 and hint["far"] == 3 and hint["impacts"] == (-1, 3)
    level1 = Steps([6.64735, 6.6474, 6.64805, 6.6481, 6.64915], [4, 5, 4, 5, 4, 3])
    p, u, half = _locate("grazing", level1, np.zeros(2), p, 2.8e-4, 1e-9, hint)
    assert abs(p - 6.64915) < 1e-8
    # without the far side's count the nearest change is a flicker (another event)
    with pytest.raises(ConvergenceError, match="another change"):
        _grazing_bisect(level1, np.zeros(2), 6.64762, 2.8e-4, 1e-9, expect=(5, 3))


def test_a_branch_that_runs_onto_another_inside_a_stretch_widens_it():
    """Two branches of order 3 meet where one gave up (110.717, step underflow) and the other
    ran onto it (110.6965, 'stop'): which of the two traces gives up there and which goes on
    is up to round-off (the paper model, parameters x (1 + 1e-13): the second one stuck at a
    corner at 110.896 Hz instead). The stretch then grows over the stopped branch's events
    chained from its edges (110.834 -> 110.877 -> 110.900 -> 110.9585 Hz: each within 1e-3 of
    f of the next; 111.2 Hz is not), so that both runs declare 110.83-110.96 Hz; a 'stop' end
    outside every stretch declares nothing."""
    from continuation.diagram import CHATTER_REACH, Bifurcation, FrequencyResponse
    ev = [110.8342, 110.8768, 110.9001, 110.9585, 111.2]
    bifs = [Bifurcation("fold", f, f, 1e-4, 3, 1, 1e-9, None) for f in ev]
    frc = FrequencyResponse({}, 1e-4, "frequency", (100.0, 150.0),
                            branches=[_branch(105.0, 110.717, ("left the parameter range",
                                                               "step underflow"), 3),
                                      _branch(110.6965, 150.0, ("stop",
                                                                "left the parameter range"), 3)],
                            bifurcations=bifs)
    ((o, lo, hi, what),) = frc.unresolved()
    assert o == 3 and lo == pytest.approx(110.717 * (1 - CHATTER_REACH))
    assert hi == pytest.approx(110.9585 * (1 + CHATTER_REACH)) and hi < 111.2
    assert "branch 2 runs onto another at 110.697 inside it; 4 of its" in what
    # the same 'stop' end away from the give-up end (outside its stretch): nothing more
    frc.branches[1] = _branch(110.5, 150.0, ("stop", "left the parameter range"), 3)
    ((o, lo, hi, what),) = frc.unresolved()
    assert hi == pytest.approx(110.717 * (1 + CHATTER_REACH)) and "runs onto" not in what
