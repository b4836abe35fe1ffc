"""Fold-grazing points on a grazing curve (issue 14: codimension-2 points) against the closed
form of tests/exact_pwl.py.

The oscillator: f_n = 1 Hz, damping ratio 0.02, a stop 100 k after 0.1 m, force 4 N. Between
0.5 and 0.7 Hz the order-1 orbit already impacts once per period and a second, lower peak of
x grazes the stop: the grazing curve of that peak in (f, amplitude) carries orbits whose
monodromy is not the free one, and a real multiplier crosses +1 on it (fold-grazing). There
the exact orbit solves det(M - I) = 0 and (its second peak) = gap together: solved here by
Newton on the exact period map."""
import warnings

import numpy as np

import continuation
from exact_pwl import StopOscillator, damped_newton, period_map, turning_points

A0 = 4.0


def _osc(amplitude, gap=0.1):
    return StopOscillator.tuned(ratio=100.0, gap=gap, amplitude=amplitude)


def _peak(o, f, z0):
    """The maximum of x (m) of the exact orbit through z0 at t = 0 closest to 0.1 m, the
    grazing peak (the deep contact's maximum lies far above 0.1 m)."""
    return min(turning_points(o, f, z0), key=lambda x: abs(x - 0.1))


def _exact_fold_grazing(f, A, z0, lift):
    """(f, A) where the exact orbit has a multiplier +1 and its highest free peak touches the gap
    0.1 m, for a flow whose stop sits ``lift`` (relative) above that gap (so the touching
    peak stays free: the grazing orbit's monodromy is the limit from the free side; the
    shallow contact's square-root term would spoil the Jacobian): Newton on
    (P(z0) - z0, det(M - I), peak - 0.1) in (z0, f, A), scaled (at the fold the orbit at
    fixed (f, A) is degenerate, so z0 is an unknown, not a Newton solve)."""
    S = np.r_[np.abs(z0).max(), np.abs(z0).max(), f, A]

    def eqs(u):
        z, ff, aa = u[:2] * S[:2], u[2] * S[2], u[3] * S[3]
        o = _osc(aa, 0.1 * (1 + lift))
        zT, M, _, _ = period_map(o, ff, z)
        return np.r_[(zT - z) / S[:2], np.linalg.det(M - np.eye(2)),
                     (_peak(o, ff, z) - 0.1) / 0.1]

    u = damped_newton(eqs, np.r_[z0, f, A] / S)
    return np.array([u[2] * S[2], u[3] * S[3]])


def test_fold_grazing_points_on_a_grazing_curve_against_the_closed_form():
    """The grazing curve from the diagram's grazing point near 0.505 Hz at 4 N, traced in
    amplitude over 0.3-12 N, reports two fold-grazing points; each agrees with the exact one
    (Newton on the closed form) within its stated errors (bracket + integration error).
    The curve's multipliers are those of the free side (continuation.extended: the stop's
    gap lifted by 1e-6 and 2e-6 of the orbit's size, extrapolated to no lift); with the
    integrator's multipliers of the touching orbit the first point was 6.9e-5 Hz off
    against a stated 3.1e-5 Hz. Measured (exact: 0.5570604 Hz, 1.2585253 N and 0.6380301
    Hz, 2.2254968 N): off by 5.0e-8 Hz, 1.6e-6 N (stated 1.0e-7 Hz, 3.2e-6 N) and by
    -1.5e-7 Hz, -8.7e-7 N (stated 2.9e-7 Hz, 1.7e-6 N). 8 s CPU."""
    osc = _osc(A0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", continuation.ContinuationWarning)
        d = continuation.frequency_response(osc.system(), A0, (0.3, 1.0), orders=(1,),
                                            accuracy="off")
        g = min((b for b in d.bifurcations if b.kind == "grazing"),
                key=lambda b: abs(b.frequency - 0.505))
        c = continuation.bifurcation_curve(osc.system(), g, (0.3, 12.0), amplitude=A0,
                                           f_range=(0.2, 1.5), max_points=200)
    fg = [p for p in c.special if p.kind == "fold-grazing"]
    assert len(fg) == 2, c.special
    out = []
    for p in fg:
        j = p.index
        # extrapolated to a lift of 0 from 1e-6 and 2e-6 (linear in the lift)
        e1, e2 = (_exact_fold_grazing(c.frequency[j], c.values[j], c.state0[j], lift)
                  for lift in (1e-6, 2e-6))
        f_ex, A_ex = 2 * e1 - e2
        out.append((p, f_ex, A_ex))
    for p, f_ex, A_ex in out:
        assert abs(p.frequency - f_ex) <= p.error_frequency, (p, f_ex)
        assert abs(p.value - A_ex) <= p.error_value, (p, A_ex)
