"""Flip-grazing points (issue 14: where a period-doubling curve meets a grazing curve) against
the closed form of tests/exact_pwl.py.

The oscillator of test_fold_grazing_exact.py (f_n = 1 Hz, damping ratio 0.02, a stop 100 k
after 0.1 m) with a second, equally stiff stop below, 0.2062 m from rest. At 4 N the order-1
orbit impacts the upper stop deeply (x up to 0.208 m) and period-doubles at 0.62336 Hz, where
its lowest point is -0.20825 m: just past the lower stop's gap. The grazing curve of the lower
stop in (f, amplitude) therefore crosses the period-doubling curve of the one-stop orbits:
there a multiplier of the grazing orbit (from the free side: the lower stop not touched) passes
-1. The exact answer: the orbit of the one-stop closed form (the lower stop never acts on the
free side) with det(M + I) = 0 and its lowest point at the lower stop, by Newton on the exact
period map."""
import warnings

import numpy as np

import continuation
import nlbeam
from exact_pwl import StopOscillator, damped_newton, period_map, turning_points

GAP2 = 0.2062  # m, the lower stop


def _osc(amplitude):
    return StopOscillator.tuned(ratio=100.0, gap=0.1, amplitude=amplitude)


def _two_stops(amplitude):
    """The oscillator with the lower stop too, as an nlbeam System."""
    o = _osc(amplitude)
    up = nlbeam.PiecewiseLinearStop(0, k=o.ks, gap=0.1, on_base=o.on_base)
    down = nlbeam.PiecewiseLinearStop(0, k=o.ks, gap=GAP2, side=-1, on_base=o.on_base)
    return nlbeam.System([[o.m]], [[o.c]], [[o.k]], elements=(up, down),
                         excitation_kind="force", y_load=[1.0])


def _lowest(o, f, z0):
    """The minimum of x (m) over the exact one-stop orbit through z0 at t = 0."""
    return min(turning_points(o, f, z0, maxima=False))


def _exact_flip_grazing(f, A, z0):
    """(f, A) where the exact one-stop orbit has a multiplier -1 and its lowest point at
    -GAP2: Newton on (P(z0) - z0, det(M + I), (lowest + GAP2) / 0.1) in (z0, f, A), scaled,
    Jacobian by forward differences."""
    S = np.r_[np.abs(z0).max(), np.abs(z0).max(), f, A]

    def eqs(u):
        z, ff, aa = u[:2] * S[:2], u[2] * S[2], u[3] * S[3]
        o = _osc(aa)
        zT, M, _, _ = period_map(o, ff, z)
        return np.r_[(zT - z) / S[:2], np.linalg.det(M + np.eye(2)),
                     (_lowest(o, ff, z) + GAP2) / 0.1]

    u = damped_newton(eqs, np.r_[z0, f, A] / S)
    return u[2] * S[2], u[3] * S[3]


def test_flip_grazing_points_on_a_grazing_curve_against_the_closed_form():
    """The lower stop's grazing curve from the diagram's grazing point near 0.6193 Hz at 4 N,
    traced in amplitude over 2-8 N, reports two flip-grazing points and no other special
    point; each agrees with the exact one (Newton on the closed form) within its stated errors
    (bracket + integration error). Measured: (0.6218621 Hz, 3.746941 N) off by -1.2e-7 Hz,
    -1.1e-6 N (stated 2.3e-7 Hz, 2.0e-6 N); (0.6162902 Hz, 5.456039 N) off by -1.1e-7 Hz,
    -9.2e-6 N (stated 2.0e-7 Hz, 1.8e-5 N). 70 s wall on a loaded machine."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", continuation.ContinuationWarning)
        d = continuation.frequency_response(_two_stops(4.0), 4.0, (0.5, 0.75), orders=(1,),
                                            accuracy="off")
        g = min((b for b in d.bifurcations if b.kind == "grazing"),
                key=lambda b: abs(b.frequency - 0.6193))
        c = continuation.bifurcation_curve(_two_stops(4.0), g, (2.0, 8.0), amplitude=4.0,
                                           f_range=(0.4, 1.0), max_points=100, element=1)
    fg = [p for p in c.special if p.kind == "flip-grazing"]
    assert len(fg) == 2 and len(c.special) == 2, c.special
    for p in fg:
        j = p.index
        f_ex, A_ex = _exact_flip_grazing(c.frequency[j], c.values[j], c.state0[j])
        assert abs(p.frequency - f_ex) <= p.error_frequency, (p, f_ex)
        assert abs(p.value - A_ex) <= p.error_value, (p, A_ex)
