"""Short reprs and HTML tables of every result (issue 16): a few hundred characters whatever
the data (the diagram's repr was 277,719 characters), with the shape, ranges, counts and
success a reader looks for, and a table Jupyter shows."""
import numpy as np
import pytest

from continuation.diagram import Bifurcation, Branch, FrequencyResponse, Superharmonic
from continuation.refine import Refined
from continuation.shooting import PeriodicSolution
from nlbeam.app.compare import PeakMatch
from nlbeam.identify import ContactFit
from nlbeam.summary import describe_value
from stochastic.simulate import EnsembleResult, StochasticResult

N = 20_000  # points of a big branch


def _branch(order, f0, f1):
    f = np.linspace(f0, f1, N)
    return Branch(order=order, parameter="frequency", values=f, frequency=f,
                  amplitude=np.full(N, 1e-4), xmax=np.linspace(1e-4, 2e-3, N),
                  stable=np.arange(N) % 4 != 0, multipliers=np.ones((N, 2), complex),
                  state0=np.zeros((N, 2)), states=np.zeros((N, 3, 2)),
                  boundaries=np.zeros((N, 3)))


def _diagram():
    bifs = [Bifurcation("fold", 42.123456789, 42.123456789, 1e-3, 1, 0, 1e-9,
                        np.array([1.0 + 0j, 0.3j]), error=2e-6, refine_status="refined"),
            Bifurcation("period-doubling", 60.0, 60.0, 1e-3, 1, 0, 1e-9, None,
                        refine_status="failed: no convergence"),
            Bifurcation("grazing", 61.0, 61.0, 1e-3, 2, 1, 1e-5, None)]
    return FrequencyResponse({"model": "BeamImpact"}, 1e-4, "frequency", (5.0, 150.0),
                             branches=[_branch(1, 5.0, 150.0), _branch(2, 50.0, 70.0)],
                             bifurcations=bifs, superharmonics=[Superharmonic(20.0, 1e-3, 2, 0)],
                             wall_time=12.5, n_points=2 * N)


def _stochastic(n=50_001):
    f = np.linspace(0.0, 1000.0, n)
    mo = {"mean": 0.0, "std": 7.5e-4, "kurtosis": 3.9, "se_std": 2e-5}
    return StochasticResult(("delta",), ("psd", "moments"), 2000.0, 5e-4, 0.0, 1.0, 10.0,
                            "adaptive", 7, {}, {}, "0.1.0",
                            psd_data={"delta": {"frequencies": f, "psd": np.ones(n),
                                                "n_segments": 31}},
                            moment_data={"delta": mo}, n_impacts=514,
                            history={"t": np.linspace(1.0, 11.0, n)})


def _check(obj, must, limit=1200):
    text = repr(obj)
    assert len(text) < limit, (len(text), text)
    for m in must:
        assert m in text, (m, text)
    page = obj._repr_html_()
    assert page.startswith("<table>") and page.endswith("</table>")
    assert len(page) < 3 * limit
    return text


def test_diagram_and_its_parts():
    frc = _diagram()
    _check(frc, ["5 .. 150 Hz", "0.0001 m", "branches          : 2: order 1: 1, order 2: 1",
                 "fold 1, grazing 1, period-doubling 1", "1 refined, 1 failed",
                 "points            : 40000"])
    _check(frc.branches[0], ["points         : 20000", "float64 (20000,), 5 .. 150",
                             "15000 of 20000 points"])
    b = _check(frc.bifurcations[0], ["42.12345679", "error [Hz]", "2e-06",
                                     "bracket (tolerance) [Hz] : 1e-09", "refined"])
    assert "not refined" not in b
    assert "failed: no convergence" in repr(frc.bifurcations[1])
    _check(frc.superharmonics[0], ["harmonic"])


def test_periodic_solution_and_refined():
    sol = PeriodicSolution(np.zeros(4), None, 2, 40.0, 1e-4, 0.05, 1.2e-3,
                           np.array([0.5, -0.2 + 0.1j]), True, 1e-12, 3, np.zeros(8),
                           np.zeros((8, 4)), np.eye(4))
    _check(sol, ["order", "float64 (8, 4), 0 .. 0", "complex128 (2,)", "stable"])
    r = Refined("fold", 1, np.array([1.0, 1.5, 1.75]), np.array([2.0]), 2.0, 1e-9, 9.0,
                np.array([2.0]), np.array([0.1, 0.2, 0.4]), (), np.zeros(2))
    _check(r, ["value", "tolerance    : 1e-09"])


def test_stochastic_results():
    res = _stochastic()
    _check(res, ["10 s kept after a 1 s transient, fs 2000 Hz", "514 (51.4 /s)",
                 "std 0.00075 +- 2e-05", "31 averages", "50001 bins of 0.02 Hz",
                 "history       : float64 (50001,), 1 .. 11", "success"])
    ens = EnsembleResult([1, 2, 3], [res, res, res])
    _check(ens, ["members  : 3", "3 of 3"])


def test_comparison_and_contact_fit():
    pk = PeakMatch(87.0, 1.2, "subharmonic", 2, 174.0, True, 0.1, 2.0,
                   alternatives=tuple(PeakMatch(87.0, 1.0, "harmonic", 1, 87.0, None, 0.0)
                                      for _ in range(50)))
    text = _check(pk, ["subharmonic", "50 PeakMatch"])
    assert text.count("PeakMatch") == 2  # the title and the count: alternatives not expanded
    fit = ContactFit("hertz", "least-squares", 2.1e8, None, None, 1e6, None, None, 0.3, 40,
                     12_000, np.linspace(0.1, 0.5, 40))
    _check(fit, ["K_hertz", "2.1e+08", "float64 (40,), 0.1 .. 0.5"])


@pytest.mark.parametrize("value, text", [
    (np.array([1.0, np.nan, 3.0]), "float64 (3,), 1 .. 3, 1 NaN"),
    (np.array([True, False, True]), "bool (3,), 2 True"),
    (np.zeros((0, 2)), "float64 (0, 2), empty"),
    ([1, 2.5, "a"], "[1, 2.5, 'a']"),
    ("x" * 200, "x" * 67 + "..."),
    ({"a": 1}, "a=1"),
])
def test_describe_value(value, text):
    assert describe_value(value) == text
