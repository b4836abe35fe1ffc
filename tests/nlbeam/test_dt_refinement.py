"""Refining dt alone refines the whole solution: no step inside a contact is longer than dt
(time steps min(dt, contact step); the graded onset's steps in sigma and the exit's steps in u
n_grade * grade_multiple(dtn, dt) over spans that do not depend on dt), so with
steps_per_contact fixed the error falls at the method's order once dt is below the contact
step. Main before this change stepped a contact's exit phase the same whatever dt
was: the error of x(T) stalled (observed orders 0.05 for rk2, 0.45 for rk4)."""
import numpy as np
import pytest

import nlbeam

# the paper beam on a Hertz stop without damping and without excitation: it bounces between
# free flight and the stop with constant energy (J)
BOUNCE = nlbeam.BeamImpact.paper(contact="hertz", b=0.0)
X0 = np.array([-1e-4, 0.0])   # m, m/s: 9 impacts in 0.2 s, contact ~1 ms, dt_contact ~3e-5 s
DURATION = 0.2                # s
# dt well below the nominal contact step (spc fixed at the defaults): the asymptotic range
DTS = {"rk4": (1e-5, 5e-6, 2.5e-6, 1.25e-6), "rk2": (5e-6, 2.5e-6, 1.25e-6, 6.25e-7)}
ORDER = {"rk4": 4, "rk2": 2}


def energy(state):
    """Kinetic + spring + Hertz potential energy (J) of the bounce's state (x, v)."""
    x, v = state
    return (0.5 * BOUNCE.m * v * v + 0.5 * BOUNCE.k * x * x
            + 0.4 * BOUNCE.K_hertz * max(x, 0.0) ** 2.5)


def _runs(model, excitation, x0, method, dts, duration):
    return [nlbeam.flow(model, excitation, x0, 0.0, duration, method=method,
                        dt=duration / round(duration / dt), warn=False) for dt in dts]


@pytest.mark.parametrize("method", ["rk4", "rk2"])
def test_undamped_bounce_energy_drift_falls_at_the_methods_order(method):
    runs = _runs(BOUNCE, nlbeam.Harmonic(0.0, 40.0), X0, method, DTS[method], DURATION)
    E0 = energy(X0)
    drift = np.array([abs(energy(fl.state) - E0) / E0 for fl in runs])
    assert all(fl.n_impacts == 9 for fl in runs)
    orders = np.log2(drift[:-1] / drift[1:])
    assert np.all(orders > ORDER[method] - 0.5) and np.all(orders < ORDER[method] + 1.0), (
        orders, drift)


@pytest.mark.parametrize("method", ["rk4", "rk2"])
@pytest.mark.parametrize("case", ["bounce", "paper-40Hz"])
def test_x_end_converges_at_the_methods_order_when_dt_alone_is_halved(method, case):
    if case == "bounce":
        model, ex, x0, duration = BOUNCE, nlbeam.Harmonic(0.0, 40.0), X0, DURATION
    else:
        # the paper model (Lankarani-Nikravesh, e = 0.5) driven at 40 Hz, A = 0.1 mm, from
        # rest: 4 impacting periods
        model, ex, x0, duration = (nlbeam.BeamImpact.paper(), nlbeam.Harmonic(1e-4, 40.0),
                                   np.zeros(2), 0.1)
    x = np.array([fl.state[0] for fl in _runs(model, ex, x0, method, DTS[method], duration)])
    # observed order from successive differences (no reference solution needed)
    d = np.abs(np.diff(x))
    orders = np.log2(d[:-1] / d[1:])
    assert np.all(orders > ORDER[method] - 0.5) and np.all(orders < ORDER[method] + 1.0), (
        orders, x)


def test_grade_multiple_is_the_least_power_of_two_that_keeps_graded_steps_within_dt():
    from nlbeam._kernels.contact import grade_multiple

    for dtn, dt, m in ((1e-5, 3e-5, 1), (1e-5, 2e-5, 1), (1e-5, 1.9e-5, 2), (1e-5, 1e-5, 2),
                       (1e-5, 4.9e-6, 8), (3e-5, 1.25e-6, 64)):
        assert grade_multiple(dtn, dt) == m, (dtn, dt)
    # halving dt doubles it once dt < 2 dtn; halving both keeps it
    assert grade_multiple(1e-5, 2.5e-6) == 2 * grade_multiple(1e-5, 5e-6)
    assert grade_multiple(0.5e-5, 2.5e-6) == grade_multiple(1e-5, 5e-6)


def test_no_step_inside_a_contact_is_longer_than_dt():
    # every contact of the bounce takes at least (its duration) / dt steps. Before this change
    # (main d7fc6f0) the exit phase's n_grade steps in u were the same whatever dt was:
    # fewest steps in a contact 183 and 708 at dt 5e-6 and 1.25e-6, where the shortest contact
    # lasts 191 and 764 dt (this kernel: 383 and 1532; python /tmp/s8caps/minspc.py)
    for dt in (5e-6, 1.25e-6):
        tr = nlbeam.integrate(BOUNCE, nlbeam.Harmonic(0.0, 40.0), DURATION, method="rk4",
                              dt=DURATION / round(DURATION / dt), x0=X0, warn=False)
        ev = np.asarray(tr.events)
        on, off = ev[ev[:, 2] == 1, 0], ev[ev[:, 2] == 0, 0]
        assert len(on) == len(off) == 9
        shortest = np.min(off - on)
        assert tr.min_steps_per_contact >= shortest / tr.dt - 1, (dt, tr.min_steps_per_contact,
                                                                   shortest / tr.dt)
