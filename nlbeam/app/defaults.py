"""The defaults of the application floor, one place for the scene files and the command line.

Where an analysis has a default, it is read from the function's signature, where it is
defined once: ``continuation.frequency_response`` (orders, n_grid, segments; dt_scale from
``continuation.Integrator``), ``stochastic.simulate`` (method, transient, psd_resolution,
pdf_bins; None means the function derives the value: the transient from the model's slowest
decay, the PSD bin from the duration), ``StochasticResult.psd`` (the channel),
``nlbeam.app.compare.map_peaks`` (min_prominence), ``nlbeam.BeamImpact`` (the paper's model).
What an analysis needs but does not default is the paper's study, set here: the base
amplitude and frequency range of the diagram, the noise band, rms and seed (a fixed seed, so
that a scene is reproducible and cacheable) and the record's duration.
"""
from __future__ import annotations

import inspect

import continuation
import nlbeam
import stochastic

from .compare import map_peaks

__all__ = ["signature_defaults", "HELP", "DERIVED", "PERIODIC", "STOCHASTIC", "CHART",
           "MODEL", "CHANNEL", "MIN_PROMINENCE", "HISTORY_SECONDS", "HISTORY_CHANNELS",
           "SIMULATE_CHANNELS", "DEMO_WORKERS", "DEMO_DURATION"]


def signature_defaults(func) -> dict:
    """{parameter: default} of ``func`` (a function or a dataclass), parameters without a
    default left out."""
    return {k: p.default for k, p in inspect.signature(func).parameters.items()
            if p.default is not inspect.Parameter.empty}


_FREQUENCY_RESPONSE = signature_defaults(continuation.frequency_response)
_INTEGRATOR = signature_defaults(continuation.Integrator)
_SIMULATE = signature_defaults(stochastic.simulate)

#: [periodic] of a scene and ``nlbeam frc``: amplitude (m), f_range (Hz), the rest as
#: continuation.frequency_response and continuation.Integrator
PERIODIC = {"amplitude": 1e-4, "f_range": [5.0, 150.0],
            "orders": list(_FREQUENCY_RESPONSE["orders"]),
            "n_grid": _FREQUENCY_RESPONSE["n_grid"],
            "segments": _FREQUENCY_RESPONSE["segments"],
            "dt_scale": _INTEGRATOR["dt_scale"],
            **{k: _INTEGRATOR[k] for k in ("method", "steps_per_contact", "rtol", "atol")},
            **{k: _FREQUENCY_RESPONSE[k] for k in ("ds", "ds_max", "max_angle", "max_points",
                                                   "tol", "bif_tol", "accuracy", "switch",
                                                   "brute_force_grid")}}
#: [stochastic] of a scene and ``nlbeam simulate``: the noise (band Hz, rms m, lowpass Hz,
#: seed) and the record (duration s), the rest as stochastic.simulate
STOCHASTIC = {"band": [0.0, 200.0], "rms": 1e-4, "lowpass": None, "seed": 1, "duration": 60.0,
              "transient": _SIMULATE["transient"],
              "psd_resolution": _SIMULATE["psd_resolution"],
              "method": _SIMULATE["method"], "pdf_bins": _SIMULATE["pdf_bins"],
              **{k: _SIMULATE[k] for k in ("rtol", "atol", "dt", "steps_per_contact")},
              "amplitudes": "random"}
#: what each key of [periodic] / [stochastic] (and the option of ``nlbeam frc`` / ``simulate``
#: of the same name, dashes for underscores) means, with its unit: one text for the
#: command line's --help; docs/usage.md says the same
HELP = {
    "amplitude": "excitation amplitude (m; N for a force-excited model)",
    "f_range": "excitation frequency range (Hz)",
    "orders": "orders n (period n/f) of the branches",
    "n_grid": "brute-force start frequencies",
    "segments": "shooting segments per period (multiple shooting)",
    "dt_scale": "fixed step as a fraction of the default (0.5: half the step)",
    "method": "integrator",
    "steps_per_contact": "steps per contact duration",
    "rtol": "relative tolerance of the adaptive method",
    "atol": "absolute tolerance of the adaptive method (m)",
    "ds": "first arclength step (scaled units)",
    "ds_max": "largest arclength step (scaled units)",
    "max_angle": "largest angle between successive tangents (rad)",
    "max_points": "points per branch at most",
    "tol": "Newton tolerance of a branch point",
    "bif_tol": "relative bracket of a located bifurcation",
    "accuracy": "significant digits of the fold / period-doubling frequencies: 'default' (6), "
                "'high' (8), a number, or 'off' (no error estimates)",
    "switch": "branch switching at period doublings",
    "brute_force_grid": "start branches from integrations on the n_grid frequencies",
    "band": "excitation band (Hz)",
    "rms": "excitation rms (m; N for a force-excited model)",
    "psd_level": "flat PSD level before the low-pass (m^2/Hz), instead of rms",
    "lowpass": "first-order low-pass corner (Hz) shaping the band (actuator)",
    "seed": "random seed (integer >= 0)",
    "duration": "record kept (s)",
    "transient": "discarded start (s)",
    "psd_resolution": "Welch bin (Hz)",
    "pdf_bins": "histogram bins of the PDF",
    "dt": "sample step (s)",
    "amplitudes": "the noise's line amplitudes: random (Rayleigh: a Gaussian process) or "
                  "deterministic (the paper's method)",
}
#: what a default of None means (the analysis derives the value)
DERIVED = {"steps_per_contact": "the solver's", "accuracy": "'default'",
           "lowpass": "none", "transient": "10 decay times of the slowest mode "
           "(stochastic.simulate)", "psd_resolution": "max(0.05, 16 / duration) "
           "(stochastic.simulate)", "dt": "1 / (32 f_max of the noise)"}
_CHART = signature_defaults(continuation.stability_chart)
#: [chart] of a scene: the paper's study (amplitudes 0.02-0.5 mm, 5-150 Hz), the rest as
#: continuation.stability_chart (amplitude None: the geometric mean of p_range)
CHART = {"p_range": [2e-5, 5e-4], "f_range": [5.0, 150.0],
         "orders": list(_CHART["orders"]), "amplitude": _CHART["amplitude"],
         "label_grid": list(_CHART["label_grid"]), "max_points": _CHART["max_points"],
         "max_evaluations": _CHART["max_evaluations"]}
#: the paper's model (nlbeam.BeamImpact's defaults: m, k, b, K_hertz, e, contact, mu, clamp)
MODEL = signature_defaults(nlbeam.BeamImpact)
#: the channel of a figure, table or comparison that names none
CHANNEL = signature_defaults(stochastic.StochasticResult.psd)["ch"]
#: least peak prominence (decades) of ``nlbeam compare``
MIN_PROMINENCE = signature_defaults(map_peaks)["min_prominence"]
#: a history figure without ``window`` shows the first HISTORY_SECONDS s of the kept record
HISTORY_SECONDS = 0.5
#: ... of these channels
HISTORY_CHANNELS = ["y", "x"]
#: the channels ``nlbeam simulate`` records and summarizes
SIMULATE_CHANNELS = ["delta", "x", "y"]
#: processes of ``nlbeam demo`` (its analyses are small: a pool's workers would each load the
#: compiled kernels, which costs more than the analyses); ``nlbeam run`` defaults to the CPU
#: count (nlbeam.app.sweeps.run_jobs)
DEMO_WORKERS = 1
#: how long ``nlbeam demo`` takes once the kernels are compiled (measured; README and --help)
DEMO_DURATION = "about 20 s"
