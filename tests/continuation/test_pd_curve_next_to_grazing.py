"""A period-doubling curve next to a grazing curve (issue 14: codimension-2 points on a curve).

With a continuous piecewise-linear stop (the force ks max(delta, 0) vanishes at contact), the
monodromy of an orbit that just grazes is that of the free orbit (complex multipliers of
modulus exp(-zeta w T) < 1), so a period-doubling curve of order-1 orbits cannot cross the
grazing curve of their only contact: where the contact is shallow the multipliers move like
the square root of its depth, and a stiff stop's period-doubling curve runs along the grazing
curve at a contact depth of a few micrometres without meeting it. bifurcation_curve must then
report no flip-grazing point and its points must be those of the closed form
(tests/exact_pwl.py). (A flip-grazing point needs a second contact grazing while the first one
is deep: test_flip_grazing_exact.py.)"""
import warnings

import numpy as np
import pytest
import scipy.optimize

import continuation
from exact_pwl import StopOscillator, orbit, turning_points

# f_n = 1 Hz, damping ratio 0.02, stop 100 k after 0.1 m, 1 N: the period doubling of the
# harmonic branch at 0.8655634 Hz lies next to its lower grazing point (test_exact_pwl.py)
F_PD = 0.865563379652703
AT = (0.8, 1.2, 1.5)


def _osc(amplitude):
    return StopOscillator.tuned(ratio=100.0, gap=0.1, amplitude=amplitude)


def test_period_doubling_curve_along_the_grazing_curve_against_the_closed_form():
    """The curve in (f, amplitude) from the period doubling at 1 N, with points placed at
    0.8, 1.2 and 1.5 N: there each frequency is the closed-form period doubling (Brent on
    det(M + I) of the exact orbit) within the point's stated error; the exact orbit there
    impacts (xmax > gap, one contact per period) and no flip-grazing point is reported.
    Measured: |curve - exact| 1.0e-8, 1.2e-8, 1.4e-8 Hz against stated 2.0e-8, 2.3e-8,
    2.6e-8 Hz; contact depths 3.1e-5, 7.3e-6, 2.6e-6 m (0.5 s CPU for the curve)."""
    osc = _osc(1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", continuation.ContinuationWarning)
        sol = continuation.periodic_solution(osc.system(), 1.0, F_PD, error=False)
        bf = {"kind": "period-doubling", "frequency": F_PD, "order": 1, "state0": sol.state0}
        c = continuation.bifurcation_curve(osc.system(), bf, (0.5, 2.0), amplitude=1.0,
                                           f_range=(0.5, 3.0), at=AT, max_points=60)
    assert not [p for p in c.special if p.kind == "flip-grazing"], c.special
    assert np.all(c.n_impacts == 1)
    for A in AT:
        f_curve, err = c.at(A), c.error_at(A)
        assert len(f_curve) == 1 and np.isfinite(err[0]), (A, f_curve, err)
        f, e = float(f_curve[0]), float(err[0])
        j = int(np.argmin(np.abs(c.frequency - f) + np.abs(c.values - A)))
        o = _osc(A)

        def det(ff):
            return np.linalg.det(orbit(o, ff, c.state0[j]).monodromy + np.eye(2))

        f_ex = scipy.optimize.brentq(det, f * (1 - 1e-5), f * (1 + 1e-5), xtol=1e-14)
        assert abs(f - f_ex) <= e, (A, f, f_ex, e)
        ex = orbit(o, f_ex, c.state0[j])
        assert ex.n_impacts == 1 and ex.xmax > o.gap, (A, ex.n_impacts, ex.xmax)


def _free_peak(o, f, z0, gap=0.1):
    """The maximum of x (m) of the exact orbit through z0 at t = 0 closest to the gap."""
    return min(turning_points(o, f, z0), key=lambda x: abs(x - gap))


def test_period_doubling_at_a_grazing_point_is_refused_with_the_way_out():
    """At 4 N the diagram's period doubling at 0.33571164 Hz (reported smooth) lies 5.8e-7 Hz
    from a grazing point of a second, lower peak (0.33571106 Hz): its extended system does not
    converge. The refusal names the grazing contact (the start orbit's peak 1.5e-5 of its size
    from the stop) and says to trace the grazing curve instead; doing what it says works: the
    grazing curve from the diagram's grazing point next to it starts, and its point at 4 N
    is the closed-form grazing frequency (Brent on the exact orbit's peak - gap) within its
    stated error. Measured: 9.8e-9 Hz off, stated 1.8e-8 Hz (16 s wall on a loaded machine)."""
    # the diagram's PD and grazing point (frequency_response, 0.3-1 Hz, 4 N, order 1)
    f_pd, f_g = 0.33571164020813954, 0.33571105976018567
    osc = _osc(4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", continuation.ContinuationWarning)
        sol = continuation.periodic_solution(osc.system(), 4.0, f_pd, error=False)
        bf = {"kind": "period-doubling", "frequency": f_pd, "order": 1, "state0": sol.state0}
        with pytest.raises(continuation.ConvergenceError,
                           match=r"grazes stop 0 .*Trace the grazing curve instead"):
            continuation.bifurcation_curve(osc.system(), bf, (3.9, 4.1), amplitude=4.0,
                                           f_range=(0.3, 0.4), max_points=5)
        sol = continuation.periodic_solution(osc.system(), 4.0, f_g, error=False)
        g = {"kind": "grazing", "frequency": f_g, "order": 1, "state0": sol.state0}
        c = continuation.bifurcation_curve(osc.system(), g, (3.99, 4.01), amplitude=4.0,
                                           f_range=(0.3, 0.4), at=(4.0,), max_points=5)
    f, err = float(c.at(4.0)[0]), float(c.error_at(4.0)[0])
    j = int(np.argmin(np.abs(c.values - 4.0) + np.abs(c.frequency - f)))

    def peak_minus_gap(ff):
        return _free_peak(osc, ff, orbit(osc, ff, c.state0[j]).state0) - 0.1

    f_ex = scipy.optimize.brentq(peak_minus_gap, f * (1 - 1e-5), f * (1 + 1e-5), xtol=1e-14)
    assert abs(f - f_ex) <= err, (f, f_ex, err)
