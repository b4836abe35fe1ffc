"""The bifurcation list (issue 16): sorted by frequency, with branch, order and error; reports
of one point merged (grazing + a bifurcation 'at grazing' on one branch; the fold of order 2n
where a branch switched at a period doubling of order n starts); points apart kept apart; the
CSV table names the error column for what it is and has a header when empty."""
import csv
import math

import numpy as np

from continuation.diagram import Bifurcation, Branch, FrequencyResponse
from nlbeam.app.scenes.bifurcation_list import bifurcation_rows, list_bifurcations
from nlbeam.app.scenes.outputs import write_table


def _bif(kind, f, order, branch, tol, note="", error=float("nan")):
    return Bifurcation(kind=kind, frequency=f, value=f, xmax=1e-3 * order, order=order,
                       branch=branch, tolerance=tol, multipliers=None, note=note, error=error)


def _frc(bifs):
    f = np.linspace(10.0, 80.0, 8)
    br = [Branch(order=o, parameter="frequency", values=f, frequency=f, amplitude=np.ones(8),
                 xmax=np.full(8, 1e-3), stable=np.ones(8, bool), multipliers=None,
                 state0=np.zeros((8, 2)), states=np.zeros((8, 1, 2)),
                 boundaries=np.zeros((8, 1))) for o in (1, 1, 2)]
    return FrequencyResponse(model_parameters={}, amplitude=1e-4, parameter="frequency",
                             p_range=(10.0, 80.0), branches=br, bifurcations=bifs,
                             settings={"bif_tol": 1e-8})


def test_sorted_merged_and_kept_apart():
    bifs = [_bif("fold", 67.8357, 1, 1, 1e-9),                      # three reports of one
            _bif("grazing", 67.83575, 1, 1, 2e-4),                  # point on branch 1
            _bif("period-doubling", 67.8356, 1, 1, 3e-4, note="at grazing: multiplier "
                 "jumps from -0.9 to -1.2 (non-smooth)"),
            _bif("period-doubling", 16.19942, 1, 0, 1e-9, error=2e-6),  # PD of order 1 ...
            _bif("fold", 16.199421, 2, 2, 1e-9),                    # ... its order-2 fold
            _bif("fold", 16.3, 2, 2, 1e-9),                         # a real fold nearby
            _bif("grazing", 67.8357, 1, 0, 1e-5),                   # other branch: apart
            _bif("fold", 12.0, 1, 0, 1e-9, error=5e-6)]
    rows = list_bifurcations(_frc(bifs))
    freqs = [r.frequency for r in rows]
    assert freqs == sorted(freqs)
    assert [(r.kind, r.order, r.branch) for r in rows] == [
        ("fold", 1, 0), ("period-doubling", 1, 0), ("fold", 2, 2),
        ("grazing", 1, 0), ("fold+period-doubling+grazing", 1, 1)]
    pd = rows[1]
    assert "order-2 branch 2 starts here" in pd.note and len(pd.merged) == 2
    assert pd.frequency_error == 2e-6  # its own error estimate, not the bracket 1e-9
    merged = rows[-1]
    assert merged.frequency == 67.8357  # the best-located report (bracket 1e-9)
    # the error covers the spread of the merged reports and their largest bracket
    assert merged.frequency_error >= 3e-4 and merged.frequency_error >= 67.83575 - 67.8356
    assert "at grazing" in merged.note
    assert rows[0].frequency_error == 5e-6


def test_table_columns(tmp_path):
    frc = _frc([_bif("fold", 42.123456789, 1, 0, 1e-9, error=3e-5)])
    (row,) = bifurcation_rows(frc, "v")
    assert row["frequency_hz"] == "42.12346" and row["frequency_error_hz"] == "3e-05"
    assert row["branch"] == 0 and row["order"] == 1 and "tolerance" not in row
    # an error that rounds up to the next decade: the frequency to the printed error's digit
    # (main printed 9.1685387 +- 1e-06: a digit the error does not support)
    (row,) = bifurcation_rows(_frc([_bif("fold", 9.16853874, 1, 0, 1e-9, error=9.5e-7)]))
    assert (row["frequency_hz"], row["frequency_error_hz"]) == ("9.168539", "1e-06")
    path = write_table({"kind": "bifurcations", "file": "b.csv"},
                       [("v", None, None, None, frc, None, {"periodic": 1})], str(tmp_path))
    with open(path) as fh:
        got = list(csv.DictReader(fh))
    assert got[0]["frequency_error_hz"] == "3e-05" and math.isclose(
        float(got[0]["frequency_hz"]), 42.12346)
    empty = write_table({"kind": "bifurcations", "file": "e.csv"},
                        [("v", None, None, None, _frc([]), None, {"periodic": 2})], str(tmp_path))
    with open(empty) as fh:
        header = fh.readline().strip().split(",")
    assert header[:5] == ["variant", "branch", "order", "kind", "frequency_hz"]
