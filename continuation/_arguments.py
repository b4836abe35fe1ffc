"""Checks of the arguments of continuation's front doors (periodic_solution,
frequency_response, continue_parameter, refine_bifurcations), on nlbeam._validate: each raises
before any work starts, naming the argument, its value and what is allowed."""
from __future__ import annotations

import math
import numbers

import numpy as np

from nlbeam._validate import (ArgumentTypeError, callable_or_none, choices, finite, flag,
                              in_range, integer, integers, interval, keywords, positive, real)

#: the Integrator options a front door takes as keywords
INTEGRATOR_OPTIONS = ("method", "dt_scale", "steps_per_contact", "rtol", "atol")
#: upper bounds of the counts (beyond them a diagram runs for days)
MAX_ORDER = 64
MAX_SEGMENTS = 256
MAX_GRID = 100_000
MAX_POINTS = 1_000_000
MAX_ITER = 1000


def check_model(model):
    if not hasattr(model, "kernel_arrays"):
        raise ArgumentTypeError(f"model: must be an nlbeam model (BeamImpact, Duffing, System, "
                                f"...), got {type(model).__name__}")


def check_integrator(where, integrator, integrator_kw, signature_names):
    """integrator: an Integrator or None; integrator_kw: only Integrator options (an unknown
    keyword is named, with a 'did you mean' among every keyword of the function)."""
    from .shooting import Integrator

    for k in integrator_kw:
        if k not in INTEGRATOR_OPTIONS:
            names = tuple(n for n, par in signature_names.items() if par.kind != par.VAR_KEYWORD)
            keywords(where, {k: None}, names + INTEGRATOR_OPTIONS)
    if integrator is not None:
        if not isinstance(integrator, Integrator):
            raise ArgumentTypeError(f"integrator: must be a continuation.Integrator or None, "
                                    f"got {type(integrator).__name__}")
        if integrator_kw:
            raise ArgumentTypeError(f"{where}: give either integrator= or the options "
                                    f"{', '.join(sorted(integrator_kw))}, not both")


def check_trace(ds, ds_max, max_angle, max_points, tol, bif_tol):
    """The path follower's options."""
    positive("ds", ds)
    positive("ds_max", ds_max)
    if ds > ds_max:
        raise ValueError(f"ds: must be <= ds_max = {ds_max!r}, got {ds!r}")
    in_range("max_angle", max_angle, 0.0, math.pi, lo_open=True, unit="rad")
    integer("max_points", max_points, 1, MAX_POINTS)
    in_range("tol", tol, 0.0, 1e-2, lo_open=True)
    in_range("bif_tol", bif_tol, 0.0, 1e-1, lo_open=True)


def check_accuracy(accuracy):
    """None, 'off', 'default', 'high' or a number of significant digits in [3, 12]."""
    if accuracy is None or (isinstance(accuracy, str) and accuracy == "off"):
        return
    if not isinstance(accuracy, str):
        real("accuracy", accuracy)
    from .accuracy import target_digits

    target_digits(accuracy)


def check_amplitude(amplitude, nonzero=False):
    a = finite("amplitude", amplitude, unit="m (N for force excitation)")
    if nonzero and a == 0:
        raise ValueError("amplitude: must be finite and nonzero m (N for force excitation), "
                         "got 0: the diagram of the rest state is empty")
    return a


def check_frequency_response(model, amplitude, f_range, orders, n_grid, segments, switch,
                             brute_force_grid, starts, stability, progress):
    check_model(model)
    check_amplitude(amplitude, nonzero=True)
    interval("f_range", f_range, lo=0.0, lo_open=True, unit="Hz")
    integers("orders", orders, 1, MAX_ORDER)
    integer("n_grid", n_grid, 2 if brute_force_grid else 0, MAX_GRID)
    integer("segments", segments, 1, MAX_SEGMENTS)
    flag("switch", switch)
    flag("brute_force_grid", brute_force_grid)
    flag("stability", stability)
    callable_or_none("progress", progress, "a callable(str)")
    if isinstance(starts, (str, bytes)) or not hasattr(starts, "__iter__"):
        raise ArgumentTypeError(f"starts: must be a list of (frequency, order, state0), got "
                                f"{starts!r}")
    for i, st in enumerate(starts):
        if isinstance(st, (str, bytes)) or not hasattr(st, "__len__") or len(st) != 3:
            raise ArgumentTypeError(f"starts[{i}]: must be (frequency Hz, order, state0), got "
                                    f"{st!r}")
        positive(f"starts[{i}] frequency", st[0], unit="Hz")
        integer(f"starts[{i}] order", st[1], 1, MAX_ORDER)


def check_periodic_solution(model, amplitude, frequency, order, segments, tol, max_iter,
                            stability, error):
    check_model(model)
    check_amplitude(amplitude)
    positive("frequency", frequency, unit="Hz")
    integer("order", order, 1, MAX_ORDER)
    integer("segments", segments, 1, MAX_SEGMENTS)
    in_range("tol", tol, 0.0, 1e-2, lo_open=True)
    integer("max_iter", max_iter, 1, MAX_ITER)
    flag("stability", stability)
    flag("error", error)


def check_p_range(parameter, model, p_range, solution=None):
    """p_range of a continuation in ``parameter`` (checked by nlbeam.parameters): a pair low <
    high, containing the solution's value of the parameter when a solution is given."""
    lo, hi = interval("p_range", p_range)
    if solution is not None:
        if parameter in ("amplitude", "frequency"):
            v = getattr(solution, parameter)
        else:
            from nlbeam.parameters import get_parameter

            v = get_parameter(model, parameter)
        if not lo <= float(v) <= hi:
            raise ValueError(f"p_range: {p_range!r} does not contain the solution's {parameter} "
                             f"= {float(v):.9g}, where the continuation starts")


def _same(a, b):
    """Two recorded parameter values are the same (numbers to 1e-12 relative, else as text)."""
    if isinstance(a, bytes):
        a = a.decode()
    if isinstance(b, bytes):
        b = b.decode()
    num = (numbers.Real, np.integer, np.floating, np.bool_)
    if isinstance(a, num) and isinstance(b, num):
        a, b = float(a), float(b)
        return a == b or abs(a - b) <= 1e-12 * max(abs(a), abs(b))
    return str(a) == str(b)


def check_same_model(frc, model, name="model"):
    """Raise ValueError unless ``model`` is the model the diagram ``frc`` was computed for
    (its recorded ``model_parameters``), naming the first parameter that differs."""
    check_model(model)
    recorded = getattr(frc, "model_parameters", None) or {}
    if not recorded:
        return
    mine = model.parameters()
    for k in sorted(set(recorded) | set(mine)):
        if k not in recorded or k not in mine or not _same(recorded[k], mine[k]):
            raise ValueError(
                f"{name}: is not the diagram's model: {k} = {mine.get(k, '(absent)')!r} here, "
                f"{recorded.get(k, '(absent)')!r} in the diagram; pass the model the diagram "
                "was computed with")


def check_refine(frc, model, kinds, orders, levels, segments, tol, target_digits, max_levels):
    from .diagram import FrequencyResponse

    if not isinstance(frc, FrequencyResponse):
        raise ArgumentTypeError(f"frc: must be a continuation.FrequencyResponse, got "
                                f"{type(frc).__name__}")
    check_same_model(frc, model)
    choices("kinds", kinds, ("fold", "period-doubling"))
    if orders is not None:
        integers("orders", orders, 1, MAX_ORDER)
    _check_levels(levels, segments, tol, target_digits, max_levels)


def check_refine_one(model, bifurcation, levels, segments, tol, target_digits, max_levels):
    """refine: the model, a fold or period doubling with its state, and the levels."""
    check_model(model)
    kind = getattr(bifurcation, "kind", None)
    if kind not in ("fold", "period-doubling") or getattr(bifurcation, "state0", None) is None:
        raise ArgumentTypeError(f"bifurcation: must be a fold or period-doubling "
                                f"continuation.Bifurcation with its state0, got "
                                f"{type(bifurcation).__name__} {kind!r}")
    _check_levels(levels, segments, tol, target_digits, max_levels)


def _check_levels(levels, segments, tol, target_digits, max_levels):
    from .shooting import Integrator

    if isinstance(levels, (str, bytes)) or not hasattr(levels, "__iter__"):
        raise ArgumentTypeError(f"levels: must be a non-empty sequence of Integrator, got "
                                f"{levels!r}")
    levels = tuple(levels)
    if not levels:
        raise ValueError("levels: must hold at least one Integrator, got ()")
    for i, lv in enumerate(levels):
        if not isinstance(lv, Integrator):
            raise ArgumentTypeError(f"levels[{i}]: must be a continuation.Integrator, got "
                                    f"{type(lv).__name__}")
    integer("segments", segments, 1, MAX_SEGMENTS)
    in_range("tol", tol, 0.0, 1e-2, lo_open=True)
    in_range("target_digits", target_digits, 1.0, 15.0)
    integer("max_levels", max_levels, 1, 12)
