"""A branch switched at a period doubling ends where it meets the parent branch again (at its
other period doubling) instead of passing onto the other half of the pitchfork and tracing
the same orbits, shifted by one excitation period, a second time."""
import warnings

import numpy as np

import continuation as C
import nlbeam


def test_switched_branch_is_traced_once_between_two_period_doublings():
    model = nlbeam.BeamImpact.paper()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        frc = C.frequency_response(model, 1e-4, (12.3, 14.2), orders=(1, 2), n_grid=4)
    pds = sorted(b.frequency for b in frc.bifurcations
                 if b.kind == "period-doubling" and b.order == 1)
    assert len(pds) == 2  # 12.68 and 13.79 Hz on the harmonic branch
    main = max((b for b in frc.branches if b.order == 2 and b.origin == "period-doubling"),
               key=lambda b: len(b.values))
    # it joins the two period doublings (their diagram values are off by up to 1.2e-3)...
    assert main.frequency.min() < pds[0] * (1 + 2e-3)
    assert main.frequency.max() > pds[1] * (1 - 2e-3)
    # ...once: before, it went on through the pitchfork and came back (81 points, and each
    # bifurcation on it twice)
    assert len(main.values) < 60
    on_main = [b for b in frc.bifurcations if b.order == 2 and b.kind != "grazing"]
    f = np.array([b.frequency for b in on_main])
    assert len(on_main) >= 2
    assert np.all(np.abs(np.diff(np.sort(f))) > 1e-4 * f.max())
    graz = np.sort([b.frequency for b in frc.bifurcations
                    if b.order == 2 and b.kind == "grazing"])
    assert np.all(np.diff(graz) > 1e-4 * graz.max())
