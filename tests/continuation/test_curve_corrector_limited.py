"""The bifurcation-curve tracer's 'corrector-limited' end (continuation.curve.SLOW_STEPS): a
trace whose steps stay short with repeated corrector failures (a chattering stretch of the paper
model) ends there with the stretch named, as a truncation of the trace without the rule; a
trace that passes a cusp after short steps and failures keeps the cusp."""
import warnings

import numpy as np
import pytest

import continuation as C
import nlbeam
from continuation import curve as CU

RANGES = dict(amplitude=1e-4, f_range=(5.0, 150.0), error=False, max_points=150,
              max_evaluations=1000)


def _diagram(f_range, orders):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        return C.frequency_response(nlbeam.BeamImpact(), 1e-4, f_range, orders,
                                    accuracy="off")


def _curve(bf, directions=(1, -1)):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", C.ContinuationWarning)
        return C.bifurcation_curve(nlbeam.BeamImpact(), bf, (2e-5, 5e-4),
                                   directions=directions, **RANGES)


def test_a_chattering_stretch_ends_the_trace_as_a_truncation(monkeypatch, tmp_path):
    """The order-1 period doubling near 9.33 Hz (A = 0.1 mm, 7 impacts per period): towards
    lower amplitudes its trace crawls near 9.21-9.26 Hz; with the rule it ends there
    'corrector-limited', its points the first ones of the trace without the rule (which goes
    on, at more shooting evaluations)."""
    frc = _diagram((9.25, 9.45), (1,))
    bf = [b for b in frc.bifurcations if b.kind == "period-doubling" and b.smooth][0]
    stopped = _curve(bf, directions=(-1,))
    assert stopped.ends[1].startswith("corrector-limited: ")
    lo, hi = (float(v) for v in stopped.ends[1].split(" steps, ")[1].split(" Hz")[0].split("-"))
    # the stretch named is where the trace's last SLOW_STEPS points lie
    tail = stopped.frequency[-CU.SLOW_STEPS:]
    assert lo == pytest.approx(tail.min(), rel=1e-5) and hi == pytest.approx(tail.max(), rel=1e-5)
    stopped.save(tmp_path / "curve.h5")  # the end's text whole in the file
    assert C.load_curves(tmp_path / "curve.h5").ends == stopped.ends
    monkeypatch.setattr(CU, "SLOW_STEPS", 10 ** 9)
    full = _curve(bf, directions=(-1,))
    assert not full.ends[1].startswith("corrector-limited")
    n = len(stopped.frequency)
    assert len(full.frequency) > n
    np.testing.assert_allclose(full.frequency[:n], stopped.frequency, rtol=1e-9)
    np.testing.assert_allclose(full.values[:n], stopped.values, rtol=1e-9)
    assert stopped.n_evaluations < full.n_evaluations


def test_the_cusp_at_67_5_hz_is_kept(monkeypatch):
    """The order-2 fold curves from 67.58 and 67.64 Hz (A = 0.1 mm) meet in the cusp at
    67.5289 Hz, 0.05647 mm, reached after short steps with corrector failures: the rule leaves
    it in place (the same point as without the rule, within the bracket errors)."""
    frc = _diagram((67.4, 67.8), (1, 2))
    starts = [b for b in frc.bifurcations if b.kind == "fold" and b.order == 2 and b.smooth
              and b.frequency > 67.55]
    assert len(starts) == 2
    for bf in starts:
        with_rule = [s for s in _curve(bf).special if s.kind == "cusp"]
        with monkeypatch.context() as mp:
            mp.setattr(CU, "SLOW_STEPS", 10 ** 9)
            without = [s for s in _curve(bf).special if s.kind == "cusp"]
        assert len(with_rule) == len(without) == 1
        a, b = with_rule[0], without[0]
        assert a.frequency == pytest.approx(67.5289, abs=1e-3)
        assert a.value == pytest.approx(5.647e-5, rel=1e-3)
        assert abs(a.frequency - b.frequency) <= a.error_frequency + b.error_frequency + 1e-9
        assert abs(a.value - b.value) <= a.error_value + b.error_value + 1e-12
