"""Committed tables under round-off: the same rows within their stated errors.

An impacting record amplifies round-off into another realization of the same process, so
the moments and the PSD of two runs that differ by round-off differ like those of two
records. The tables must not: the same peaks (kind, order, frequency within the errors
printed beside it), each moment within its printed standard errors, and every number
printed to the digit its error supports. The 2-mode beam (ModalBeam.paper(n_modes=2)), 40 s
under 0-200 Hz base noise, the excitation scaled by 1 + 1e-13 (a round-off-sized change on
purpose): delta's std moves by 3 % within 8 s (the paper's 1-DOF beam amplifies it only
to 4e-11 in 30 s).
"""
import csv
import math
from decimal import Decimal
from types import SimpleNamespace

import numpy as np

import nlbeam
import stochastic
from nlbeam.app.scenes.numbers import moment_cells
from nlbeam.app.scenes.outputs import write_table
from nlbeam.app.scenes.schema import build_noise

F1 = np.linspace(5.0, 150.0, 581)
# an order-1 branch resonating at 43.5 Hz (the paper model's impacting resonance)
DIAGRAM = SimpleNamespace(branches=[SimpleNamespace(
    order=1, frequency=F1, xmax=1e-4 + 1e-3 / (1 + ((F1 - 43.5) / 3.0) ** 2),
    stable=np.ones(F1.size, bool))], bifurcations=[], superharmonics=[])


def _last_digit(cell):
    """The decade of a printed number's last digit ('-0.00060' and '2e-05': -5)."""
    return Decimal(cell).as_tuple().exponent


def _tables(tmp_path, factor):
    s = {"band": [0.0, 200.0], "rms": 1e-4 * factor, "seed": 1}
    res = stochastic.simulate(nlbeam.ModalBeam.paper(n_modes=2), build_noise(s), 40.0, 1.0,
                              method="rk4", psd_resolution=0.5, outputs=("psd", "moments"))
    variants = [("", None, {"f_range": [5.0, 150.0]}, s, DIAGRAM, res,
                 {"periodic": "p.h5", "stochastic": "s.h5"})]
    out = {}
    for kind in ("moments", "peaks"):
        d = {"kind": kind, "file": f"{kind}_{factor!r}.csv", "f_max": 200.0}
        with open(write_table(d, variants, tmp_path), newline="") as fh:
            out[kind] = list(csv.DictReader(fh))
    return res, out


def test_tables_agree_within_their_errors_under_round_off(tmp_path):
    res_a, a = _tables(tmp_path, 1.0)
    res_b, b = _tables(tmp_path, 1.0 + 1e-13)
    # the realization did change (else the test says nothing)
    std_a, std_b = res_a.moments("delta")["std"], res_b.moments("delta")["std"]
    assert abs(std_a - std_b) > 1e-9 * std_a
    (ma,), (mb,) = a["moments"], b["moments"]
    for key in ("mean", "std", "skewness", "kurtosis"):
        for m in (ma, mb):  # the value's last digit is the error's one significant digit
            assert _last_digit(m[key]) == _last_digit(m[f"se_{key}"]), m
        err = math.hypot(float(ma[f"se_{key}"]), float(mb[f"se_{key}"]))
        assert abs(float(ma[key]) - float(mb[key])) <= 2.5 * err, (key, ma, mb)
    # every clearly significant peak (6 standard errors over min_prominence) of either
    # table is in the other, of the same kind, within the errors printed beside it; a
    # marginal one may be missing from the other record (five 40 s records under 1 +- 1e-13,
    # 1 +- 2e-13: the resonance at 30-32 Hz has significance 6.3-6.7 in each, the 62-64 Hz
    # hump 3.3-6.4: the stated prominence error is about half the spread between records)
    for pa_, pb_ in ((a["peaks"], b["peaks"]), (b["peaks"], a["peaks"])):
        strong = [p for p in pa_ if int(p["significance"]) >= 6]
        assert strong, pa_
        for p in strong:
            fp, ep = float(p["frequency_hz"]), float(p["frequency_error_hz"])
            q = min(pb_, key=lambda q: abs(float(q["frequency_hz"]) - fp))
            assert abs(float(q["frequency_hz"]) - fp) <= 2 * math.hypot(
                ep, float(q["frequency_error_hz"])), (p, q)
            assert (p["kind"], p["order"], p["note"]) == (q["kind"], q["order"], q["note"])
            err = math.hypot(float(p["prominence_error_dec"]), float(q["prominence_error_dec"]))
            assert abs(float(p["prominence_dec"]) - float(q["prominence_dec"])) <= 3 * err


def test_the_digits_rule():
    """A statistic prints to the decade of its standard error's one significant digit."""
    assert moment_cells(-1.03317, 0.0374) == ("-1.03", "0.04")
    assert moment_cells(4.0991, 0.19) == ("4.1", "0.2")
    assert moment_cells(5.1113e-4, 7.3e-6) == ("0.000511", "7e-06")
    assert moment_cells(2.0, 0.0096) == ("2.00", "0.01")  # the error rounds up a decade
    assert moment_cells(0.5, math.nan) == ("0.5", None)
