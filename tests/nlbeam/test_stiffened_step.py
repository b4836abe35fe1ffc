"""integrate warns when a hardening cubic spring stiffens the structure beyond what the step
resolves (the default step looks at the linear stiffness only), and the step it suggests is
accurate. Duffing k3 = 1e6 N/m^3, F = 100 N at 0.5 Hz, 20 periods, rk4."""
import re
import warnings


import nlbeam


def _run(dt=None):
    m, ex = nlbeam.Duffing(k3=1e6), nlbeam.Harmonic(100.0, 0.5)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tr = nlbeam.integrate(m, ex, 40.0, dt=dt, store_every=0)
    return tr, [str(w.message) for w in caught if "stiffened" in str(w.message)]


def test_a_coarse_default_step_is_warned_and_the_suggested_step_is_accurate():
    ref, _ = _run(dt=1e-4)
    coarse, notes = _run()
    assert len(notes) == 1, notes
    err = abs(coarse.xmax[0] / ref.xmax[0] - 1)
    assert err > 0.01  # the warning is deserved: percents off
    dt = float(re.search(r"use dt <= ([0-9.e-]+) s", notes[0]).group(1))
    fine, notes_fine = _run(dt=dt)
    assert notes_fine == []
    assert abs(fine.xmax[0] / ref.xmax[0] - 1) < 1e-3 < err


def test_no_warning_for_a_soft_run():
    m, ex = nlbeam.Duffing(k3=1.0), nlbeam.Harmonic(0.1, 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tr = nlbeam.integrate(m, ex, 10.0, store_every=0)
    assert tr.xmax[0] > 0
