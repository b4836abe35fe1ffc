"""Path following: Duffing folds against harmonic balance, folds passed both ways, period
doubling and branch switching, save/load, and the import boundary."""
import subprocess
import sys

import numpy as np
import pytest

import continuation as C
import nlbeam
from helpers import DUFF, F, hb_coefficients, hb_fold


@pytest.fixture(scope="module")
def duffing_branch():
    model = nlbeam.Duffing(**DUFF)
    sol = C.periodic_solution(model, F, 0.1, dt_scale=0.2)
    frc = C.continue_parameter(sol, "frequency", (0.1, 0.5), model=model, dt_scale=0.2,
                               bif_tol=1e-11)
    return model, frc


def test_duffing_folds_match_harmonic_balance(duffing_branch):
    model, frc = duffing_branch
    folds = sorted([b for b in frc.bifurcations if b.kind == "fold"], key=lambda b: b.frequency)
    assert len(folds) == 2
    for fold in folds:
        assert fold.tolerance < 1e-9 * fold.frequency
        c = hb_coefficients(model, fold.state0, fold.frequency, 8)
        f_hb8 = hb_fold(fold.frequency, c, 8)
        f_hb10 = hb_fold(fold.frequency, np.r_[c, 0, 0, 0, 0], 10)
        assert abs(f_hb10 - f_hb8) < 1e-9  # the HB answer has converged in the harmonics
        assert abs(fold.frequency - f_hb10) < 1e-6 * f_hb10


def test_continuation_through_folds_comes_back_on_the_other_side(duffing_branch):
    model, frc = duffing_branch
    b = frc.branches[0]
    df = np.diff(b.frequency)
    turns = np.nonzero(np.sign(df[1:]) != np.sign(df[:-1]))[0]
    assert len(turns) == 2  # up to the upper fold, back to the lower fold, up again
    lo, hi = sorted(f.frequency for f in frc.bifurcations if f.kind == "fold")
    fm = 0.5 * (lo + hi)
    xs, stab = [], []
    for i in range(len(b.frequency) - 1):
        f0, f1 = b.frequency[i], b.frequency[i + 1]
        if min(f0, f1) <= fm < max(f0, f1):
            j = i if abs(fm - f0) < abs(fm - f1) else i + 1
            sol = C.periodic_solution(model, F, fm, guess=b.state0[j], dt_scale=0.2)
            xs.append(sol.xmax)
            stab.append(sol.stable)
    order = np.argsort(xs)
    xs, stab = np.array(xs)[order], np.array(stab)[order]
    assert len(xs) == 3 and np.all(np.diff(xs) > 1e-3 * xs[-1])  # three distinct solutions
    assert list(stab) == [True, False, True]  # the middle one, between the folds, unstable


@pytest.fixture(scope="module")
def pd_diagram():
    m = nlbeam.BeamImpact.paper()
    return m, C.frequency_response(m, 1e-4, (15.0, 17.0), orders=(1, 2), n_grid=3)


def test_period_doubling_switches_to_period_2T(pd_diagram):
    m, frc = pd_diagram
    pds = [b for b in frc.bifurcations if b.kind == "period-doubling" and b.order == 1]
    assert pds
    for pd in pds:
        assert np.min(np.abs(pd.multipliers + 1)) < 1e-6
    sw = [b for b in frc.branches if b.origin == "period-doubling"]
    assert sw and all(b.order == 2 for b in sw)
    b = sw[0]
    i = len(b.frequency) // 2
    f = b.frequency[i]
    ex = nlbeam.Harmonic(1e-4, f)
    n = 100 * int(np.ceil(np.max(m.natural_frequencies()) / f))
    spc = C.Integrator().steps_per_contact  # the diagram's contact steps: the same map
    one = nlbeam.flow(m, ex, b.state0[i], 0.0, 1 / f, dt=1 / (f * n), steps_per_contact=spc)
    two = nlbeam.flow(m, ex, b.state0[i], 0.0, 2 / f, dt=1 / (f * n), steps_per_contact=spc)
    scale = np.abs(b.state0[i])
    assert np.max(np.abs(two.state - b.state0[i]) / scale) < 1e-6  # period 2T
    assert np.max(np.abs(one.state - b.state0[i]) / scale) > 1e-3  # but not T
    # the switched branch starts at the PD point
    assert min(abs(b.frequency[0] - pd.frequency) for pd in pds) < 1e-2


def test_save_load_roundtrip(pd_diagram, tmp_path):
    m, frc = pd_diagram
    p = tmp_path / "frc.h5"
    frc.save(p)
    got = C.load(p)
    assert len(got.branches) == len(frc.branches)
    for a, b in zip(got.branches, frc.branches):
        assert a.order == b.order and np.array_equal(a.xmax, b.xmax)
        assert np.array_equal(a.multipliers, b.multipliers)
        assert np.array_equal(a.states, b.states)
    assert [x.kind for x in got.bifurcations] == [x.kind for x in frc.bifurcations]
    assert got.model_parameters["K_hertz"] == m.K_hertz
    assert got.amplitude == 1e-4 and got.version == nlbeam.__version__
    assert [q.name for q in tmp_path.iterdir()] == ["frc.h5"]  # no temporary left behind


def test_import_does_not_load_matplotlib_or_h5py():
    code = ("import sys, continuation; "
            "print('matplotlib' in sys.modules, 'h5py' in sys.modules)")
    import os
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=root, check=True)
    assert out.stdout.split() == ["False", "False"]


@pytest.mark.parametrize("parameter,lo,hi", [("amplitude", 0.9e-4, 1.1e-4), ("e", 0.45, 0.55)])
def test_continuation_in_other_parameters_lands_on_direct_solutions(parameter, lo, hi):
    m = nlbeam.BeamImpact.paper()
    sol = C.periodic_solution(m, 1e-4, 44.0)
    frc = C.continue_parameter(sol, parameter, (lo, hi), model=m)
    b = frc.branches[0]
    assert b.values.min() <= lo and b.values.max() >= hi
    i = len(b.values) // 3
    v = b.values[i]
    if parameter == "amplitude":
        direct = C.periodic_solution(m, v, 44.0, guess=b.state0[i])
    else:
        direct = C.periodic_solution(m.replace(e=v), 1e-4, 44.0, guess=b.state0[i])
    assert abs(direct.xmax - b.xmax[i]) < 1e-7 * direct.xmax


def test_plot_draws_branches_and_marks(pd_diagram, tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    from continuation.plot import plot_frequency_response
    m, frc = pd_diagram
    fig = plot_frequency_response(frc)
    ax = fig.axes[0]
    dashed = [l for l in ax.lines if l.get_linestyle() == "--"]
    assert dashed  # unstable parts drawn dashed
    ax.figure.savefig(tmp_path / "f.png")
