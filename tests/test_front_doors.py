"""Every front door refuses bad input with a ValueError or TypeError that names the argument,
raised by nlbeam's own code (never a traceback from numpy, scipy, h5py or Python below), before
any long work: each case runs under an alarm (CASE_SECONDS) and fails if it hangs.

The table lists (front door, argument, bad value): wrong types (numeric strings, bools,
lists, None), NaN, inf, zero, negative, out of range, wrong shape, misspelt options.
"""
import math
import os
import signal
import time
import traceback

import numpy as np
import pytest

import continuation
import nlbeam
import stochastic
from continuation.diagram import FrequencyResponse
from nlbeam._validate import ArgumentTypeError, BudgetError
from nlbeam.app.compare import map_peaks
from nlbeam.app.plots import stochastic as stochastic_plots
from nlbeam.app.plots.frequency_response import plot_frequency_response

CASE_SECONDS = 60  # generous: a case that reaches an integration loop would run much longer
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OWN = tuple(os.path.join(ROOT, d) + os.sep for d in ("nlbeam", "continuation", "stochastic"))

M = nlbeam.BeamImpact()
EX = nlbeam.Harmonic(1e-4, 40.0)
NOISE = stochastic.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=1, block_duration=1.0)
F = np.linspace(0.5, 200.0, 400)
PSD = (F, 1e-9 / (1.0 + ((F - 40.0) / 2.0) ** 2) + 1e-12)


def _frc():
    return FrequencyResponse(model_parameters=M.parameters(), amplitude=1e-4,
                             parameter="frequency", p_range=(5.0, 150.0))


def _res():
    t = np.arange(4000) * 1e-3
    return stochastic.analyze(t, {"x": np.sin(2 * np.pi * 40.0 * t)}, psd_resolution=2.0)


def _bif():
    return continuation.Bifurcation(kind="fold", frequency=40.0, value=40.0, xmax=1e-4,
                                    order=1, branch=0, tolerance=1e-8, multipliers=None,
                                    state0=np.zeros(2))


def _sol():
    return continuation.PeriodicSolution(
        state0=np.zeros(2), disc0=None, order=1, frequency=40.0, amplitude=1e-4, period=0.025,
        xmax=1e-4, multipliers=None, stable=None, residual=0.0, iterations=0,
        boundaries=np.zeros(1), states=np.zeros((1, 2)), monodromy=None)


# front door name -> callable(**overrides): the call with valid defaults
DOORS = {
    "BeamImpact": lambda **k: nlbeam.BeamImpact(**k),
    "Duffing": lambda **k: nlbeam.Duffing(**k),
    "ModalBeam": lambda **k: nlbeam.ModalBeam(**k),
    "Contact": lambda **k: nlbeam.Contact(**k),
    "PiecewiseLinearStop": lambda **k: nlbeam.PiecewiseLinearStop(**k),
    "CubicSpring": lambda **k: nlbeam.CubicSpring(**k),
    "System": lambda **k: nlbeam.System(**{"M": [[1.0]], "C": [[0.1]], "K": [[1.0]], **k}),
    "Harmonic": lambda **k: nlbeam.Harmonic(**{"amplitude": 1e-4, "frequency": 40.0, **k}),
    "Sampled": lambda **k: nlbeam.Sampled(**{"t_start": 0.0, "h": 1e-3, "y": [0.0, 1.0, 0.0],
                                             "yd": [0.0, 0.0, 0.0], **k}),
    "CosineSum": lambda **k: nlbeam.CosineSum(**{"frequencies": [10.0], "amplitudes": [1.0],
                                                 "phases": [0.0], **k}),
    "integrate": lambda **k: nlbeam.integrate(**{"model": M, "excitation": EX, "t_end": 0.1,
                                                 **k}),
    "flow": lambda **k: nlbeam.flow(**{"model": M, "excitation": EX, "state0": None,
                                       "t0": 0.0, "duration": 0.025, **k}),
    "periodic_solution": lambda **k: continuation.periodic_solution(
        **{"model": M, "amplitude": 1e-4, "frequency": 40.0, **k}),
    "frequency_response": lambda **k: continuation.frequency_response(
        **{"model": M, "amplitude": 1e-4, "f_range": (40.0, 45.0), **k}),
    "continue_parameter": lambda **k: continuation.continue_parameter(
        **{"solution": _sol(), "parameter": "frequency", "p_range": (30.0, 50.0), "model": M,
           **k}),
    "refine_bifurcations": lambda **k: continuation.refine_bifurcations(
        **{"frc": _frc(), "model": M, **k}),
    "refine": lambda **k: continuation.refine(
        **{"model": M, "bifurcation": _bif(), "amplitude": 1e-4, **k}),
    "BandLimitedNoise": lambda **k: stochastic.BandLimitedNoise(
        **{"band": (0.0, 100.0), "rms": 1e-4, "seed": 1, **k}),
    "SpectralNoise": lambda **k: stochastic.SpectralNoise(
        **{"psd": lambda f: np.ones_like(f), "band": (0.0, 100.0), "seed": 1, **k}),
    "Recorded": lambda **k: stochastic.Recorded(
        **{"t": np.arange(10) * 1e-3, "y": np.sin(np.arange(10.0)), **k}),
    "simulate": lambda **k: stochastic.simulate(
        **{"model": M, "excitation": NOISE, "duration": 1.0, "transient": 0.1, **k}),
    "ensemble": lambda **k: stochastic.ensemble(
        **{"model": M, "make_excitation": _noise_factory, "seeds": [1, 2], "duration": 1.0,
           **k}),
    "map_peaks": lambda **k: map_peaks(**{"psd": PSD, "frc": _frc(), **k}),
    "plot_frequency_response": lambda **k: plot_frequency_response(
        **{"frc": _frc(), **k}),
    "response_psd": lambda **k: stochastic_plots.response_psd(
        **{"result": _res(), "ch": "x", **k}),
    "pdf": lambda **k: stochastic_plots.pdf(**{"result": _res(), "ch": "x", **k}),
    "continuation.load": lambda **k: continuation.load(**k),
    "stochastic.load": lambda **k: stochastic.load(**k),
}


def _noise_factory(seed):
    return stochastic.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=seed)


def _psd_negative_between_probes(f):
    """A PSD (m^2/Hz) on (0, 100) Hz positive at the 1001 points 0.1 Hz apart that a PSD
    callable is first probed at, negative (down to -5e-10) between them."""
    return 1e-9 * (1.0 - 1.5 * np.sin(np.pi * np.asarray(f) / 0.1) ** 2)


NAN, INF = math.nan, math.inf
# (front door, argument named in the message, keyword overrides)
CASES = [
    # models and elements
    ("BeamImpact", "e", {"e": "0.5"}), ("BeamImpact", "e", {"e": NAN}),
    ("BeamImpact", "e", {"e": 0.0}), ("BeamImpact", "e", {"e": 1.5}),
    ("BeamImpact", "m", {"m": -1.0}), ("BeamImpact", "m", {"m": 0.0}),
    ("BeamImpact", "m", {"m": INF}), ("BeamImpact", "k", {"k": "abc"}),
    ("BeamImpact", "K_hertz", {"K_hertz": "2e8"}), ("BeamImpact", "b", {"b": -0.1}),
    ("BeamImpact", "clamp", {"clamp": "no"}), ("BeamImpact", "contact", {"contact": "herz"}),
    ("BeamImpact", "mu", {"contact": "hunt-crossley"}), ("BeamImpact", "e", {"e": True}),
    ("BeamImpact", "m", {"m": 1 + 2j}), ("BeamImpact", "k", {"k": [736.0]}),
    ("Duffing", "k3", {"k3": NAN}), ("Duffing", "m", {"m": "1"}),
    ("ModalBeam", "n_modes", {"n_modes": 2.5}), ("ModalBeam", "n_modes", {"n_modes": 0}),
    ("ModalBeam", "bc", {"bc": "clamped"}), ("ModalBeam", "zeta", {"zeta": "0.01"}),
    ("ModalBeam", "stop_position", {"stop_position": 1.0}),
    ("Contact", "dof", {"dof": 1.7}), ("Contact", "dof", {"dof": "x"}),
    ("Contact", "dof", {"dof": -1}), ("Contact", "K", {"K": -1.0}),
    ("Contact", "law", {"law": "lankarani"}), ("Contact", "side", {"side": 2}),
    ("Contact", "on_base", {"on_base": "yes"}), ("Contact", "gap", {"gap": NAN}),
    ("PiecewiseLinearStop", "k", {"k": "5"}), ("CubicSpring", "k3", {"k3": INF}),
    ("System", "M", {"M": "abc"}), ("System", "M", {"M": [[1.0, 0.0]]}),
    ("System", "M", {"M": [[-1.0]]}), ("System", "K", {"K": [[NAN]]}),
    ("System", "elements", {"elements": nlbeam.Contact()}),
    ("System", "elements", {"elements": (1.0,)}),
    ("System", "output_dof", {"output_dof": "a"}), ("System", "output_dof", {"output_dof": 3}),
    ("System", "excitation_kind", {"excitation_kind": "bse"}),
    ("System", "y_load", {"y_load": [1.0, 2.0]}),
    # excitations
    ("Harmonic", "frequency", {"frequency": "40"}), ("Harmonic", "frequency", {"frequency": 0}),
    ("Harmonic", "frequency", {"frequency": -5.0}), ("Harmonic", "amplitude",
                                                     {"amplitude": NAN}),
    ("Harmonic", "phase", {"phase": INF}),
    ("Sampled", "max_freq", {"max_freq": -5.0}), ("Sampled", "h", {"h": 0.0}),
    ("Sampled", "y", {"y": "abc"}), ("Sampled", "y", {"y": [0.0, NAN, 1.0]}),
    ("CosineSum", "frequencies", {"frequencies": "abc"}),
    ("CosineSum", "frequencies", {"frequencies": [-1.0]}),
    # integrate and flow
    ("integrate", "t_end", {"t_end": "1.0"}), ("integrate", "t_end", {"t_end": NAN}),
    ("integrate", "t_end", {"t_end": -1.0}), ("integrate", "dt", {"dt": "1e-4"}),
    ("integrate", "dt", {"dt": 0.0}), ("integrate", "dt", {"dt": -1e-4}),
    ("integrate", "t0", {"t0": "0"}), ("integrate", "store_every", {"store_every": "a"}),
    ("integrate", "store_every", {"store_every": 0.5}),
    ("integrate", "store_every", {"store_every": -1}),
    ("integrate", "steps_per_contact", {"steps_per_contact": 0.5}),
    ("integrate", "steps_per_contact", {"steps_per_contact": 1e9}),
    ("integrate", "method", {"method": "euler"}), ("integrate", "method", {"method": "rk5"}),
    ("integrate", "x0", {"x0": [0.0]}), ("integrate", "x0", {"x0": "ab"}),
    ("integrate", "disc0", {"disc0": [[1.0, NAN]]}), ("integrate", "disc0",
                                                      {"disc0": [[1.0, -1.0]]}),
    ("integrate", "model", {"model": "beam"}), ("integrate", "excitation", {"excitation": 40.0}),
    ("integrate", "rtol", {"method": "adaptive", "rtol": 0.0}),
    ("integrate", "events", {"events": "yes"}), ("integrate", "max_steps", {"max_steps": 0}),
    ("integrate", "max_steps", {"t_end": 1e6}),  # 4e9 steps at the default dt
    ("integrate", "max_steps", {"dt": 1e-15}),
    ("integrate", "max_steps", {"excitation": nlbeam.Harmonic(1e-4, 1e12)}),
    ("flow", "duration", {"duration": 0.0}), ("flow", "duration", {"duration": NAN}),
    ("flow", "max_steps", {"duration": 1e7}),
    ("flow", "max_steps", {"dt": 1e-12, "monodromy": True}),
    ("flow", "state0", {"state0": [1.0, 2.0, 3.0]}), ("flow", "monodromy",
                                                      {"monodromy": "yes"}),
    ("flow", "t0", {"t0": INF}),
    # continuation
    ("periodic_solution", "amplitude", {"amplitude": "1e-4"}),
    ("periodic_solution", "frequency", {"frequency": 0.0}),
    ("periodic_solution", "frequency", {"frequency": NAN}),
    ("periodic_solution", "order", {"order": 1.5}), ("periodic_solution", "order", {"order": 0}),
    ("periodic_solution", "segments", {"segments": 0}),
    ("periodic_solution", "tol", {"tol": NAN}), ("periodic_solution", "max_iter",
                                                 {"max_iter": 0}),
    ("periodic_solution", "guess", {"guess": "abc"}),
    ("periodic_solution", "dt_scale", {"dt_scale": "1"}),
    ("periodic_solution", "dt_scale", {"dt_scale": -1.0}),
    ("periodic_solution", "method", {"method": "rk3"}),
    ("periodic_solution", "stabilty", {"stabilty": False}),
    ("periodic_solution", "accuracy", {"accuracy": "hihg"}),
    ("periodic_solution", "model", {"model": None}),
    ("frequency_response", "f_range", {"f_range": (5.0,)}),
    ("frequency_response", "f_range", {"f_range": "5-150"}),
    ("frequency_response", "f_range", {"f_range": (150.0, 5.0)}),
    ("frequency_response", "f_range", {"f_range": (0.0, 5.0)}),
    ("frequency_response", "f_range", {"f_range": (5.0, INF)}),
    ("frequency_response", "orders", {"orders": 1}),
    ("frequency_response", "orders", {"orders": (0,)}),
    ("frequency_response", "orders", {"orders": (-1,)}),
    ("frequency_response", "orders", {"orders": (1.5,)}),
    ("frequency_response", "orders", {"orders": ()}),
    ("frequency_response", "n_grid", {"n_grid": 0}),
    ("frequency_response", "n_grid", {"n_grid": -5}),
    ("frequency_response", "n_grid", {"n_grid": 2.5}),
    ("frequency_response", "ds", {"ds": 0.0}), ("frequency_response", "ds", {"ds": -0.02}),
    ("frequency_response", "ds", {"ds": NAN}), ("frequency_response", "ds_max",
                                                {"ds_max": NAN}),
    ("frequency_response", "max_points", {"max_points": 0}),
    ("frequency_response", "tol", {"tol": NAN}),
    ("frequency_response", "max_angle", {"max_angle": 0.0}),
    ("frequency_response", "bif_tol", {"bif_tol": NAN}),
    ("frequency_response", "amplitude", {"amplitude": 0.0}),
    ("frequency_response", "amplitude", {"amplitude": "1e-4"}),
    ("frequency_response", "progress", {"progress": "yes"}),
    ("frequency_response", "stabilty", {"stabilty": False}),
    ("frequency_response", "stability", {"stability": "no"}),
    ("frequency_response", "segments", {"segments": 0}),
    ("frequency_response", "integrator", {"integrator": "rk4"}),
    ("frequency_response", "starts", {"starts": [(40.0, 1)]}),
    ("frequency_response", "accuracy", {"accuracy": NAN}),
    ("continue_parameter", "p_range", {"p_range": (50.0, 30.0)}),
    ("continue_parameter", "parameter", {"parameter": "frequncy"}),
    ("continue_parameter", "solution", {"solution": None}),
    ("continue_parameter", "p_range", {"p_range": (50.0, 60.0)}),
    ("continue_parameter", "p_range", {"parameter": "e", "p_range": (0.6, 0.9)}),
    ("continue_parameter", "ds", {"ds": NAN}),
    ("refine_bifurcations", "kinds", {"kinds": ("flod",)}),
    ("refine_bifurcations", "kinds", {"kinds": "fold"}),
    ("refine_bifurcations", "target_digits", {"target_digits": NAN}),
    ("refine_bifurcations", "max_levels", {"max_levels": 0}),
    ("refine_bifurcations", "levels", {"levels": ()}),
    ("refine_bifurcations", "model", {"model": nlbeam.BeamImpact(e=0.52)}),
    ("refine_bifurcations", "frc", {"frc": None}),
    ("refine", "bifurcation", {"bifurcation": None}), ("refine", "model", {"model": "beam"}),
    ("refine", "target_digits", {"target_digits": INF}),
    ("refine", "levels", {"levels": [1.0]}),
    # stochastic
    ("BandLimitedNoise", "rms", {"rms": "1e-4"}), ("BandLimitedNoise", "rms", {"rms": -1.0}),
    ("BandLimitedNoise", "band", {"band": "0-100"}),
    ("BandLimitedNoise", "band", {"band": (100.0, 0.0)}),
    ("BandLimitedNoise", "seed", {"seed": -1}), ("BandLimitedNoise", "seed", {"seed": 1.5}),
    ("BandLimitedNoise", "block_duration", {"block_duration": 1e12}),
    ("BandLimitedNoise", "amplitudes", {"amplitudes": "randm"}),
    ("SpectralNoise", "psd", {"psd": {"f": [0, 100], "G": [1, 1]}}),
    ("SpectralNoise", "psd", {"psd": lambda f: 1 / 0}),
    ("SpectralNoise", "psd", {"psd": lambda f: np.cos(f)}),
    ("SpectralNoise", "psd", {"psd": _psd_negative_between_probes}),
    ("Recorded", "h", {"h": 0.5}), ("Recorded", "bc_type", {"bc_type": "bogus"}),
    ("Recorded", "t", {"t": "abc"}),
    ("simulate", "duration", {"duration": "10"}), ("simulate", "duration", {"duration": -1.0}),
    ("simulate", "outputs", {"outputs": ()}), ("simulate", "outputs", {"outputs": ("pds",)}),
    ("simulate", "channels", {"channels": ("dleta",)}),
    ("simulate", "method", {"method": "euler"}),
    ("simulate", "chunk_duration", {"chunk_duration": 1e-9}),
    ("simulate", "keep_history", {"keep_history": (100.0, 200.0)}),
    ("simulate", "keep_history", {"keep_history": "all"}),
    ("simulate", "dt", {"excitation": nlbeam.Harmonic(1e-4, 40.0), "dt": 0.02}),
    ("simulate", "max_samples", {"excitation": stochastic.BandLimitedNoise(
        (0.0, 1e6), rms=1e-4, seed=1, block_duration=1e-3), "duration": 10.0}),
    ("simulate", "psd_resolution", {"psd_resolution": 0.0}),
    ("simulate", "psd_resolution", {"psd_resolution": 1e-6}),  # 48 GB of Welch segments
    ("simulate", "store_every", {"store_every": 0}),
    ("simulate", "pdf_bins", {"pdf_bins": 0}),
    ("simulate", "progress", {"progress": "yes"}),
    ("ensemble", "processes", {"processes": 0}),
    ("ensemble", "make_excitation", {"make_excitation": lambda s: NOISE}),
    ("ensemble", "make_excitation", {"make_excitation": lambda s: _noise_factory(s),
                                     "workers": 2}),
    ("ensemble", "stabilty", {"stabilty": 1}),
    ("ensemble", "seeds", {"seeds": ["a"]}),
    # comparison, plots, loaders
    ("map_peaks", "min_prominence", {"min_prominence": NAN}),
    ("map_peaks", "min_prominence", {"min_prominence": -1.0}),
    ("map_peaks", "background_hz", {"background_hz": 0.0}),
    ("map_peaks", "background_hz", {"background_hz": -5.0}),
    ("map_peaks", "background_hz", {"background_hz": NAN}),
    ("map_peaks", "tol_bins", {"tol_bins": -2.0}),
    ("map_peaks", "max_superharmonic", {"max_superharmonic": -1}),
    ("map_peaks", "psd", {"psd": (F[::-1], PSD[1])}),
    ("map_peaks", "psd", {"psd": {"f": F}}),
    ("map_peaks", "f_range", {"f_range": (10.0,)}),
    ("map_peaks", "frc", {"frc": None}), ("map_peaks", "tolerance", {"tolerance": 0.0}),
    ("map_peaks", "max_multiple", {"max_multiple": 1.5}),
    ("plot_frequency_response", "scale", {"scale": "1e3"}),
    ("plot_frequency_response", "grazing", {"grazing": "no"}),
    ("plot_frequency_response", "path", {"path": ROOT}),
    ("response_psd", "path", {"path": ROOT}), ("response_psd", "f_max", {"f_max": -1.0}),
    ("response_psd", "ax", {"ax": "a"}), ("pdf", "log", {"log": "yes"}),
    ("continuation.load", "path", {"path": 5}),
    ("stochastic.load", "path", {"path": None}),
]


class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang(f"no answer within {CASE_SECONDS} s")


@pytest.mark.parametrize("door, name, kw", CASES,
                         ids=[f"{d}-{n}-{i}" for i, (d, n, _) in enumerate(CASES)])
def test_bad_input_is_refused_naming_the_argument(door, name, kw):
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(CASE_SECONDS)
    t = time.perf_counter()
    try:
        with pytest.raises((ValueError, TypeError)) as err:
            DOORS[door](**kw)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    msg = str(err.value)
    assert name in msg, f"{door}({kw}): the message does not name {name!r}: {msg}"
    last = traceback.extract_tb(err.value.__traceback__)[-1].filename
    assert last.startswith(OWN), f"{door}({kw}) raised from {last}, below nlbeam: {msg}"
    assert time.perf_counter() - t < CASE_SECONDS


def test_numeric_strings_are_refused_with_their_value_not_converted():
    with pytest.raises(TypeError, match=r"e: must be a real number, got a numeric string '0.5'"):
        nlbeam.BeamImpact(e="0.5")
    # the type error is a ValueError too, for callers that caught ValueError before
    with pytest.raises(ValueError):
        nlbeam.Harmonic(1e-4, "40")


def test_misspelt_options_get_a_did_you_mean():
    with pytest.raises(ValueError, match=r"did you mean 'hertz'"):
        nlbeam.BeamImpact(contact="herz")
    with pytest.raises(TypeError, match=r"did you mean 'stability'"):
        continuation.frequency_response(M, 1e-4, (40.0, 45.0), stabilty=False)
    with pytest.raises(ValueError, match=r"did you mean 'fold'"):
        continuation.refine_bifurcations(_frc(), M, kinds=("flod",))


def test_refine_bifurcations_refuses_another_model_naming_the_parameter():
    with pytest.raises(ValueError, match=r"e = 0.52 here, 0.5 in the diagram"):
        continuation.refine_bifurcations(_frc(), nlbeam.BeamImpact(e=0.52))
    # the diagram's own model passes the check (no bifurcation to refine: an empty list)
    assert continuation.refine_bifurcations(_frc(), nlbeam.BeamImpact()) == []


def test_budgets_state_the_estimate_and_the_knob():
    with pytest.raises(BudgetError, match=r"about 1e\+15.*limit 1e\+08.*max_steps"):
        nlbeam.integrate(M, EX, 1.0, dt=1e-15)
    # the memory budget is stated by $NLBEAM_MEMORY_BUDGET: 1 kB refuses 0.1 s of samples
    os.environ["NLBEAM_MEMORY_BUDGET"] = "1000"
    try:
        with pytest.raises(BudgetError, match=r"store_every"):
            nlbeam.integrate(M, EX, 0.1)
    finally:
        del os.environ["NLBEAM_MEMORY_BUDGET"]
    tr = nlbeam.integrate(M, EX, 0.1)  # within the default budget
    assert tr.t[-1] == pytest.approx(0.1)


def test_argument_type_error_is_both_kinds():
    assert issubclass(ArgumentTypeError, TypeError) and issubclass(ArgumentTypeError, ValueError)


def test_memory_budgets_name_block_duration_and_psd_resolution(monkeypatch):
    # the issue's 2.2 GiB block synthesis (block_duration=1e6 s) and 47.7 GiB of Welch
    # segments (psd_resolution=1e-6 Hz) under a stated budget of 1 GB
    monkeypatch.setenv("NLBEAM_MEMORY_BUDGET", "1e9")
    with pytest.raises(BudgetError,
                       match=r"^block synthesis: .*needs about [0-9.]+ [GT]iB.*block_duration"):
        stochastic.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=1, block_duration=1e6)
    with pytest.raises(BudgetError, match=r"^psd_resolution: .*needs about [0-9.]+ [GT]iB"):
        stochastic.simulate(M, NOISE, duration=1.0, transient=0.1, psd_resolution=1e-6)


def test_a_record_shorter_than_the_noise_correlation_time_warns():
    # a band of (0, 1e-3) Hz varies over 1000 s: 1 s of it is one quasi-static stretch
    slow = stochastic.BandLimitedNoise((0.0, 1e-3), rms=1e-4, seed=1)
    with pytest.warns(RuntimeWarning, match=r"duration: 1 s is shorter than the excitation's "
                                            r"correlation time 1 / band width = 1000 s"):
        stochastic.simulate(M, slow, duration=1.0, transient=0.1, outputs=("moments",))
    import warnings

    with warnings.catch_warnings():
        warnings.filterwarnings("error", message=".*correlation time")
        stochastic.simulate(M, NOISE, duration=1.0, transient=0.1, outputs=("moments",))
