"""Round-off does not decide the diagram: a stability change at (or within round-off of) a
grazing point is listed once whichever side of the grazing point round-off puts it on, and a
diagram computed with round-off perturbed on purpose has the same structure (branches: count,
order, covered ranges; bifurcations: kind, count, frequency within the stated tolerance)."""
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation import pathfollow as PF
from continuation.pathfollow import Point, Tracer


def _pt(p, mu, n_impacts):
    return Point(u=np.zeros(2), p=p, xmax=1.0, multipliers=np.asarray(mu, dtype=complex),
                 problem=None, n_impacts=n_impacts)


def _grazing_step(mus, ps=(1.0, 1.4, 1.5, 2.0), impacts=(6, 6, 7, 7)):
    """A jump from prev to pt across a grazing point bracketed by g_near, g_far."""
    prev, g_near, g_far, pt = (_pt(p, mu, n) for p, mu, n in zip(ps, mus, impacts))
    tr = Tracer()
    located = []
    tr.locate_chord = lambda prob, a, b, k, ga, gb: (located.append((a.p, b.p, k)) or
                                                      (b, 1e-9))
    out = tr._detect_step(None, None, None, 0.1, prev, pt, PF.test_functions(prev.multipliers),
                          PF.test_functions(pt.multipliers), True,
                          (g_far, g_far.p - g_near.p, g_near, None), 0)
    return out, located


def test_multiplier_jump_across_grazing_point_is_reported_there():
    """The lead's case: the leading multiplier jumps from -1.21 to 0.53 at the grazing point."""
    out, located = _grazing_step([[-1.10, 0.01], [-1.21, 0.01], [0.53, 0.02], [0.50, 0.02]])
    assert [L.kind for L in out] == ["period-doubling"]
    assert out[0].point.p == 1.5 and out[0].tolerance == pytest.approx(0.1)
    assert "at grazing" in out[0].note and "-1.21" in out[0].note and "0.53" in out[0].note
    assert located == []  # nothing to locate on the smooth sides


@pytest.mark.parametrize("mus, where", [
    # the multiplier crosses -1 on the near side, then jumps back at the grazing point: two
    ([[-0.9, 0.0], [-3.4, 0.0], [-0.01, 0.0], [-0.02, 0.0]], ["near", "across"]),
    # it crosses on the far side only (the whole step shows the change too)
    ([[0.87, 0.0], [0.87, 0.0], [0.80, 0.0], [-1.38, 0.0]], ["far"]),
    # it jumps from +0.9 to -1.3 and crosses back on the far side: a pair the ends hide
    ([[0.9, 0.0], [0.9, 0.0], [-1.3, 0.0], [-0.5, 0.0]], ["across", "far"]),
    # a complex pair jumps out of the unit circle: Neimark-Sacker at the grazing point
    ([[0.5 + 0.5j, 0.5 - 0.5j], [0.6 + 0.6j, 0.6 - 0.6j], [0.8 + 0.9j, 0.8 - 0.9j],
      [0.8 + 0.95j, 0.8 - 0.95j]], ["across"]),
])
def test_grazing_step_is_split_at_the_grazing_point(mus, where):
    out, located = _grazing_step(mus)
    side = {(1.0, 1.4): "near", (1.5, 2.0): "far"}
    got = []
    for L in out:
        got.append("across" if L.note else side[[s for s in side if L.point.p == s[1]][0]])
    assert sorted(got) == sorted(where)
    assert len(located) == sum(w != "across" for w in where)


# --- a diagram under round-off perturbed on purpose ---------------------------------------------
def _coverage(frc, order, tol):
    """Union of the frequency intervals the branches of ``order`` cover, clipped to the range
    (intervals closer than tol merged)."""
    lo, hi = frc.p_range
    iv = sorted((max(lo, b.frequency.min()), min(hi, b.frequency.max()))
                for b in frc.branches if b.order == order)
    out = []
    for a, b in iv:
        if out and a <= out[-1][1] + tol:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return out


def _both_unresolved(a, b, order):
    """The parts of the range that both diagrams declare unresolved for this order
    (FrequencyResponse.unresolved: what their warnings tell the user), as (lo, hi)."""
    out = []
    for _, lo, hi, _ in a.unresolved(order):
        for _, lo2, hi2, _ in b.unresolved(order):
            if max(lo, lo2) <= min(hi, hi2):
                out.append((max(lo, lo2), min(hi, hi2)))
    return out


def structure_differences(a, b, f_rel=2e-3, rel=1e-7):
    """What differs between the structures of diagrams a and b: branches (count per order,
    covered ranges, their ends within f_rel relative: a switched branch starts at its period
    doubling's first point, one step away) and bifurcations (per kind and order the same count,
    matched in order of frequency within the sum of their stated errors, the errors the
    bifurcation table prints them with (``numbers.bifurcation_error``: the bracket, the
    estimated integration error, bif_tol, and 1e-5 of f at grazing points and at bifurcations
    reported at one), plus ``rel`` relative: the round-off of the located point). Bifurcations
    of an order inside a stretch that BOTH diagrams declare unresolved for that order
    (``FrequencyResponse.unresolved``, named in each diagram's warning) are left out of the
    comparison; a stretch only one of them declares is compared like any other."""
    from nlbeam.app.scenes.numbers import bifurcation_error
    diff = []
    skip = {o: _both_unresolved(a, b, o)
            for o in {x.order for x in a.bifurcations + b.bifurcations}}

    def compared(x):
        return not any(lo <= x.frequency <= hi for lo, hi in skip[x.order])
    orders = sorted({br.order for br in a.branches} | {br.order for br in b.branches})
    for o in orders:
        na = sum(br.order == o for br in a.branches)
        nb = sum(br.order == o for br in b.branches)
        if na != nb:
            diff.append(f"order {o}: {na} against {nb} branches")
        ca, cb = _coverage(a, o, 1e-9), _coverage(b, o, 1e-9)
        if len(ca) != len(cb) or not np.allclose(ca, cb, rtol=f_rel, atol=0):
            diff.append(f"order {o}: covers {ca} against {cb}")
    keys = sorted({(x.kind, x.order) for x in a.bifurcations + b.bifurcations})
    for key in keys:
        xa = sorted((x for x in a.bifurcations if (x.kind, x.order) == key and compared(x)),
                    key=lambda x: x.frequency)
        xb = sorted((x for x in b.bifurcations if (x.kind, x.order) == key and compared(x)),
                    key=lambda x: x.frequency)
        if len(xa) != len(xb):
            diff.append(f"{key}: {[round(x.frequency, 6) for x in xa]} against "
                        f"{[round(x.frequency, 6) for x in xb]}")
            continue
        for x, y in zip(xa, xb):
            ex, ey = bifurcation_error(x, a), bifurcation_error(y, b)
            if abs(x.frequency - y.frequency) > ex + ey + rel * x.frequency:
                diff.append(f"{key}: {x.frequency:.10g} (+- {ex:.1e}) against "
                            f"{y.frequency:.10g} (+- {ey:.1e})")
    return diff


def _window(model, dt_scale=1.0, amplitude=1e-4):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return C.frequency_response(model, amplitude, (12.3, 14.2), orders=(1, 2), n_grid=4,
                                    dt_scale=dt_scale)


def _scaled(s):
    """The paper model with m, k, b, K_hertz all scaled by s (the same dynamics)."""
    p = nlbeam.BeamImpact.paper()
    return p.replace(m=p.m * s, k=p.k * s, b=p.b * s, K_hertz=p.K_hertz * s)


@pytest.fixture(scope="module")
def reference_window():
    return _window(nlbeam.BeamImpact.paper())


def test_reference_window_lists_both_period_doublings_of_the_switched_branch(reference_window):
    """12.3-14.2 Hz at A = 0.1 mm: the order-2 branch between the harmonic branch's period
    doublings (12.68, 13.79 Hz) loses and regains stability by a period doubling next to each
    of its two grazing points (12.742, 13.317 Hz; the multiplier changes fastest there), which
    round-off used to put on either side of the grazing point: one of them went unlisted."""
    frc = reference_window
    pd2 = sorted(b.frequency for b in frc.bifurcations
                 if b.order == 2 and b.kind == "period-doubling")
    graz = sorted(b.frequency for b in frc.bifurcations if b.order == 2 and b.kind == "grazing")
    assert len(pd2) == 2 and len(graz) == 2
    # each period doubling lies between a grazing point and the far end of its smooth stretch
    assert abs(pd2[0] - graz[0]) < 5e-3 and abs(pd2[1] - graz[1]) < 5e-3
    main = max((b for b in frc.branches if b.order == 2), key=lambda b: len(b.values))
    for f in pd2:  # the branch's stability changes there
        i = np.argmin(np.abs(main.frequency - f))
        lo, hi = max(i - 3, 0), min(i + 3, len(main.frequency) - 1)
        assert main.stable[lo] != main.stable[hi] or f in (main.frequency[0], main.frequency[-1])


PERTURBATIONS = ("parameters x (1 + 1e-13)", "parameters x (1 - 1e-13)",
                 "amplitude x (1 + 1e-13)", "dt_scale 1 - 1e-9")


@pytest.fixture(scope="module")
def perturbed_windows():
    """dt_scale 1 - 1e-9 rounds the steps per period up (101 instead of 100): a 1 % change of
    the step, more than round-off."""
    out = {}
    for what in PERTURBATIONS:
        if what.startswith("parameters"):
            out[what] = _window(_scaled(1 + (1e-13 if "+" in what else -1e-13)))
        elif what.startswith("amplitude"):
            out[what] = _window(nlbeam.BeamImpact.paper(), amplitude=1e-4 * (1 + 1e-13))
        else:
            out[what] = _window(nlbeam.BeamImpact.paper(), dt_scale=1 - 1e-9)
    return out


@pytest.mark.parametrize("what", PERTURBATIONS)
def test_round_off_perturbed_on_purpose_keeps_the_structure(reference_window,
                                                            perturbed_windows, what):
    assert structure_differences(reference_window, perturbed_windows[what]) == []


def _table_rows(frc):
    from nlbeam.app.scenes.numbers import bifurcation_error, error_bound, with_error, xmax_error
    rows = []
    for b in sorted(frc.bifurcations, key=lambda b: (b.kind, b.order, b.frequency)):
        e = bifurcation_error(b, frc)
        rows.append((b.kind, b.order, with_error(b.frequency, e),
                     with_error(b.xmax, xmax_error(b, frc, e)), error_bound(e)))
    return rows


@pytest.mark.parametrize("what", PERTURBATIONS[:3])
def test_bifurcation_table_prints_the_same_under_round_off(reference_window,
                                                           perturbed_windows, what):
    """The committed table's numbers (nlbeam.app.scenes.numbers: each to the digits its
    error supports) do not change when round-off does."""
    assert _table_rows(perturbed_windows[what]) == _table_rows(reference_window)


def test_structure_differences_sees_a_missing_bifurcation(reference_window):
    """The comparison used above can fail: drop one period doubling, shift another."""
    import copy
    frc = copy.deepcopy(reference_window)
    pds = [b for b in frc.bifurcations if b.kind == "period-doubling" and b.order == 2]
    frc.bifurcations.remove(pds[0])
    assert structure_differences(reference_window, frc)
    frc = copy.deepcopy(reference_window)
    b = [b for b in frc.bifurcations if b.kind == "period-doubling" and b.order == 1][0]
    from nlbeam.app.scenes.numbers import bifurcation_error
    e = bifurcation_error(b, frc)  # its stated error (the table's), shifted 3 times that
    b.frequency += 3 * e + 1e-6 * b.frequency
    assert structure_differences(reference_window, frc)
    b.frequency -= 2.6 * e + 1e-6 * b.frequency  # 0.4 of it: the same
    assert structure_differences(reference_window, frc) == []


def test_numbers_are_printed_to_the_decade_of_their_error():
    from nlbeam.app.scenes.numbers import error_bound, with_error
    rng = np.random.default_rng(3)
    for _ in range(2000):
        v = rng.choice([-1, 1]) * 10 ** rng.uniform(-5, 3)
        e = 10 ** rng.uniform(-12, 1) * abs(v)
        txt = with_error(v, e)
        k = np.floor(np.log10(e))
        assert abs(float(txt) - v) <= 0.5 * 10 ** k * (1 + 1e-9) + 1e-15 * abs(v), (v, e, txt)
        # no digit below the error's decade: dropping one more digit changes the value
        assert float(error_bound(e)) >= e * (1 - 1e-12)
        assert float(error_bound(e)) < 10 ** (k + 1) * (1 + 1e-12)
    assert with_error(6.648660903, 1.4e-3) == "6.649"
    assert with_error(12.74368194, 1.3e-7) == "12.7436819"
    assert with_error(1.12215e-4, 3e-9) == "0.000112215"
    assert with_error(0.01, 0.5) == "0"
    assert with_error(3.0, float("nan")) == "3"
    # round-off far below the error does not change the text (away from a rounding boundary)
    assert with_error(13.31385961 * (1 + 3e-12), 1.3e-7) == with_error(13.31385961, 1.3e-7)


def test_grazing_points_within_each_others_bracket_are_merged():
    from continuation.diagram import Bifurcation, _merged_grazing

    def g(f, tol, branch=0, kind="grazing"):
        return Bifurcation(kind, f, f, 1e-4, 2, branch, tol, None)

    bifs = [g(7.78976, 1.1e-3)]
    assert _merged_grazing(g(7.79126, 3.1e-3), bifs)
    assert bifs[0].frequency == 7.78976 and bifs[0].tolerance == pytest.approx(1.5e-3 + 3.1e-3)
    assert bifs[0].note.startswith("2 changes")
    assert _merged_grazing(g(7.7930, 1e-4), bifs) and bifs[0].note.startswith("3 changes")
    assert not _merged_grazing(g(7.80, 1e-4), bifs)  # outside the brackets
    assert not _merged_grazing(g(7.7898, 1e-4, branch=1), bifs)  # another branch
    assert not _merged_grazing(g(7.7898, 1e-4, kind="fold"), bifs)
    # brackets far below the grazing resolution (1e-5 of f): merged within it, not beyond
    f0 = 67.5012
    bifs = [g(f0, 2e-6)]
    assert _merged_grazing(g(f0 + 0.9e-5 * f0, 3e-6), bifs)
    assert bifs[0].tolerance == pytest.approx(0.9e-5 * f0 + 3e-6)
    assert not _merged_grazing(g(f0 + 1.1e-5 * f0 + 2e-5 + bifs[0].tolerance, 1e-6), bifs)
    # a bifurcation reported at a grazing point (a multiplier jumps across the unit circle)
    # next to one of its kind: one event; a smooth one is never merged
    jump = "at grazing: multiplier jumps from -2.554 to 4.003 (non-smooth)"
    bifs = [g(f0, 5e-5, kind="period-doubling")]
    bifs[0].note = jump
    nxt = g(f0 + 4e-5, 9e-5, kind="period-doubling")
    nxt.note = jump
    assert _merged_grazing(nxt, bifs) and bifs[0].tolerance == pytest.approx(1.3e-4)
    assert bifs[0].note == jump + " (2 such jumps within the bracket)" and not bifs[0].smooth
    assert _merged_grazing(nxt, bifs) and bifs[0].note.endswith("(3 such jumps within the bracket)")
    assert not _merged_grazing(g(f0 + 1e-5, 1e-6, kind="period-doubling"), bifs)  # smooth


@pytest.mark.slow
def test_paper_diagram_keeps_its_structure_under_round_off():
    """The whole paper diagram (A = 0.1 mm, 5-150 Hz, orders 1-3) with m, k, b, K_hertz x
    (1 + 1e-13): the same structure. (On 0312b23, outside those intervals the bifurcation
    tables print the same; inside them 40 of 129 rows differ.) Passes since session 13
    (continuation.pathfollow.at_grazing_points: the fold pair at the order-2 grazing point
    9.66425 Hz is one event in both runs); measured with benchmarks/roundoff_structure.py:
    0 unmatched bifurcations (main 6b2e8f3: 1, the order-2 fold 9.663664)."""
    def diagram(model):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return C.frequency_response(model, 1e-4, (5.0, 150.0), orders=(1, 2, 3))
    a, b = diagram(nlbeam.BeamImpact.paper()), diagram(_scaled(1 + 1e-13))
    assert structure_differences(a, b) == []


def test_refine_skips_bifurcations_at_grazing_points():
    """A multiplier that jumps across -1 at a grazing point is no regular root of the extended
    system: refine_bifurcations leaves it (its grazing bracket stays the tolerance)."""
    from continuation.diagram import Bifurcation, FrequencyResponse
    from continuation.refine import refine_bifurcations
    bf = Bifurcation("period-doubling", 13.3171, 13.3171, 1e-4, 2, 1, 4.8e-5, None,
                     note="at grazing: multiplier jumps from -1.21 to 0.534 (non-smooth)")
    assert not bf.smooth
    frc = FrequencyResponse({}, 1e-4, "frequency", (12.3, 14.2), bifurcations=[bf])
    ((b, res),) = refine_bifurcations(frc, nlbeam.BeamImpact.paper())
    assert b is bf and isinstance(res, C.ConvergenceError) and "at grazing" in str(res)
    assert bf.refined is None and bf.frequency == 13.3171 and bf.tolerance == 4.8e-5
    assert bf.refine_status.startswith("failed: at a grazing point")


def test_refinement_status_and_record_are_saved(tmp_path):
    """A refined record (value, error, levels' values), a failure with its reason and a
    bifurcation never refined come back from the file as they were (issue 16)."""
    from continuation.diagram import Bifurcation, FrequencyResponse
    from continuation.refine import Refined
    mu = np.array([1.0 + 0j, 0.2 + 0j])
    a, b, c = (Bifurcation(k, f, f, 1e-4, 1, 0, 1e-9, mu, state0=np.array([1e-4, 0.0]))
               for k, f in (("fold", 12.5), ("period-doubling", 13.0), ("fold", 14.0)))
    a.refined = Refined("fold", 1, np.array([12.51, 12.502, 12.5005]), np.array([12.50001]),
                        12.50001, 3e-9, 9.6, np.array([4.0]), np.array([1.0, 2.0, 4.0]), (),
                        a.state0)
    a.refine_status, a.error = "refined", 3e-9
    b.refine_status = "failed: extended system: no convergence after 20 iterations"
    frc = FrequencyResponse({}, 1e-4, "frequency", (12.0, 15.0), bifurcations=[a, b, c])
    frc.save(tmp_path / "d.h5")
    la, lb, lc = C.load(tmp_path / "d.h5").bifurcations
    assert la.refine_status == "refined" and la.error == 3e-9
    assert (la.refined.value, la.refined.tolerance, la.refined.digits) == (12.50001, 3e-9, 9.6)
    assert np.array_equal(la.refined.values, a.refined.values)
    assert np.array_equal(la.refined.seconds, a.refined.seconds)
    assert lb.refined is None and lb.refine_status == b.refine_status
    assert lc.refined is None and lc.refine_status == ""


# --- the overlap check: decided by re-solving the traced branch, not by where a point falls ---
def test_overlap_check_is_confirmed_by_a_re_solve_of_the_branch():
    """A point within the geometric allowances of a traced branch (2e-3 relative plus a
    twentieth of the segment; state within 5 % of the orbit's size) is on it only when the
    branch re-solved there (same_orbit) lands on the point's orbit: two different orbits can
    lie that close (the paper model's order-3 branches near 111-113 Hz), and which point of a
    trace first falls inside the allowances is up to round-off. At most two segments per
    branch are re-solved; outside the allowances nothing is."""
    from types import SimpleNamespace

    from continuation.diagram import _on_branch
    st = np.array([[1e-4, 0.0], [1.06e-4, 0.0]])
    br = SimpleNamespace(order=1, frequency=np.array([10.0, 11.0]),
                         xmax=np.array([1e-4, 1.06e-4]), state0=st, ends=("", ""))
    calls = []

    def said(answer):
        return lambda b, i, lam: calls.append((b, i, lam)) or answer
    f, x_chord = 10.5, 1.03e-4
    for off, inside in ((1.001, True), (1.05, False)):
        x = x_chord * off
        shifts = np.array([[x, 0.0]])
        assert _on_branch([br], 1, f, x, shifts) == (0 if inside else None)
        calls.clear()
        assert _on_branch([br], 1, f, x, shifts, same_orbit=said(True)) == (0 if inside
                                                                             else None)
        assert len(calls) == (1 if inside else 0)
        if calls:  # segment 0, where the point projects onto it
            assert calls[0][0] is br and calls[0][1] == 0 and 0.4 < calls[0][2] < 0.6
        assert _on_branch([br], 1, f, x, shifts, same_orbit=said(False)) is None


def test_same_orbit_test_recognises_the_orbit_and_rejects_another():
    """The re-solve (paper model, order 1): the branch through 39.8 and 40.2 Hz re-solved at 40
    Hz from its interpolated state lands on the orbit at 40 Hz (True); judged against a state
    5 % off that orbit (not an orbit of the map) it says False."""
    from types import SimpleNamespace

    from continuation.diagram import _same_orbit_test
    from continuation.shooting import Integrator, _problem_from_state
    m = nlbeam.BeamImpact.paper()
    sols = [C.periodic_solution(m, 1e-4, f, error=False) for f in (39.8, 40.0, 40.2)]
    br = SimpleNamespace(order=1, frequency=np.array([39.8, 40.2]),
                         xmax=np.array([sols[0].xmax, sols[2].xmax]),
                         state0=np.array([sols[0].state0, sols[2].state0]), ends=("", ""))
    s0 = np.asarray(sols[1].state0, dtype=float)
    prob, u = _problem_from_state(m, 1e-4, 40.0, 1, s0, 1, Integrator())
    u, ev, res, it = prob.solve(u, 40.0)
    assert _same_orbit_test(prob, u, 40.0)(br, 0, 0.5)
    assert not _same_orbit_test(prob, u * 1.05, 40.0)(br, 0, 0.5)


def test_clusters_within_their_stated_errors_are_one_event():
    """diagram._merged_clusters: grazing points of one branch whose error intervals (value +-
    max(bracket, estimated error, 1e-5 of f)) overlap one after the other are one event, kept
    at the member nearest the cluster's middle with a tolerance covering every member; which
    members a run resolved does not change the event or its interval."""
    from continuation.diagram import Bifurcation, _merged_clusters, _stated_error

    def g(f, tol=1e-6, err=float("nan"), branch=3, kind="grazing", note=""):
        b = Bifurcation(kind, f, f, 1e-4, 2, branch, tol, None, note=note)
        b.error = err
        return b
    f0 = 67.5
    r = 1e-5 * f0  # the resolution: each stated error at least this
    # 67.4999-67.5037 Hz: changes 1.3e-3 Hz apart (more than one resolution, less than two)
    fs = [f0, f0 + 1.3e-3, f0 + 2.5e-3, f0 + 3.7e-3]
    out = _merged_clusters([g(f) for f in fs])
    assert len(out) == 1 and out[0].note == "4 changes of the number of impacts within the bracket"
    assert out[0].value in (fs[1], fs[2])  # the member nearest the middle
    assert out[0].value - _stated_error(out[0]) <= fs[0] and out[0].value + out[0].tolerance \
        >= fs[-1]
    # any subset a perturbed run may have resolved: one event, its interval overlapping the
    # reference's, both covering all the changes they saw
    # (one that missed a change bridging two others sees two events: [fs[0], fs[2]])
    assert len(_merged_clusters([g(fs[0]), g(fs[2])])) == 2
    for sub in ([fs[0], fs[1]], [fs[1]], [fs[0], fs[1], fs[2]], [fs[2], fs[3]]):
        o = _merged_clusters([g(f) for f in sub])
        assert len(o) == 1
        assert abs(o[0].value - out[0].value) <= _stated_error(o[0]) + _stated_error(out[0])
    # farther apart than the two errors: two events; an estimated error larger than the
    # resolution widens the interval
    assert len(_merged_clusters([g(f0), g(f0 + 2.1 * r)])) == 2
    assert len(_merged_clusters([g(f0), g(f0 + 2.1 * r, err=1.2 * r)])) == 1
    assert len(_merged_clusters([g(f0), g(f0 + 3 * r, tol=2.1 * r)])) == 1  # the bracket
    # another branch, a smooth bifurcation: never merged
    assert len(_merged_clusters([g(f0), g(f0 + 1e-4, branch=4)])) == 2
    assert len(_merged_clusters([g(f0, kind="fold"), g(f0 + 1e-4, kind="fold")])) == 2
    # jumps of a multiplier at grazing points: counted in the note
    jump = "at grazing: multiplier jumps from -1.2 to 0.5 (non-smooth)"
    o = _merged_clusters([g(f0, kind="period-doubling", note=jump),
                          g(f0 + r, kind="period-doubling", note=jump + " (2 such jumps within "
                            "the bracket)")])
    assert len(o) == 1 and o[0].note == jump + " (3 such jumps within the bracket)"
    assert not o[0].smooth
    # a chain decided on either side the same: values moved by 1e-13 keep the clusters
    rng = np.random.default_rng(5)
    for _ in range(200):
        v = np.sort(f0 + rng.uniform(0, 40 * r, 8))
        a = len(_merged_clusters([g(f) for f in v]))
        b = len(_merged_clusters([g(f * (1 + 1e-13)) for f in v]))
        assert a == b

