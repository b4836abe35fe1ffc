"""The streaming simulation loop, its result object, HDF5 files and ensembles.

``simulate`` alternates between Python and the compiled integrator one chunk at a time:
the excitation of the chunk is synthesized (a ``nlbeam.Sampled`` table), ``nlbeam.integrate``
continues from the previous chunk's end state and contact memory, and the stored samples
feed the streaming estimators. Memory is one chunk, whatever the duration.
"""
from __future__ import annotations

import math
import os
import re
import sys
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from nlbeam._validate import (ArgumentTypeError, callable_or_none, check_count, check_memory,
                              choice, choices, integer, nonnegative, positive, real_array)
from nlbeam.summary import Summary, describe_value
from nlbeam.vocabulary import METHODS
from nlbeam.vocabulary import CHANNELS

from .assemble import feed, make_estimators, store_results

__all__ = ["simulate", "StochasticResult", "load", "ensemble", "EnsembleResult",
           "default_transient"]

OUTPUTS = ("psd", "pdf", "moments")
#: default limit of the integration samples (transient + duration) / dt of one simulate call
#: (``max_samples``): 1e8 samples are 4.3 h of a 200 Hz band at the default 6.4 kHz, tens of
#: minutes of CPU
MAX_SAMPLES = 100_000_000
#: a block noise may synthesize this many table samples per allowed integration sample (its
#: step h is finer than dt, and an FFT sample is cheap: 1e9 samples of a 200 Hz band: 3 h)
SYNTHESIS_PER_SAMPLE = 10


def _parse_channel(name, model):
    m = re.fullmatch(rf"({'|'.join(CHANNELS)})(?:\[(\d+)\])?", str(name))
    if m is None:
        raise ValueError(f"channels: unknown channel {name!r}; use one of {', '.join(CHANNELS)}, "
                         "optionally indexed like 'x[1]' or 'delta[0]'")
    kind, idx = m.group(1), m.group(2)
    if kind in ("x", "v"):
        i = model.output_dof if idx is None else int(idx)
        if not 0 <= i < model.n_dof:
            raise ValueError(f"channels: {name!r} indexes DOF {i}, the model has {model.n_dof}")
    elif kind in ("delta", "force"):
        i = 0 if idx is None else int(idx)
        if not 0 <= i < model.n_elements:
            raise ValueError(f"channels: {name!r} indexes element {i}, the model has "
                             f"{model.n_elements}")
    else:
        if idx is not None:
            raise ValueError(f"channels: {name!r}: the excitation channel takes no index")
        i = 0
    return kind, i


def _extract(tr, kind, i, sel):
    if kind == "x":
        return tr.x[sel, i]
    if kind == "v":
        return tr.v[sel, i]
    if kind == "delta":
        return tr.delta[sel, i]
    if kind == "force":
        return tr.force[sel, i]
    y, yd = tr.excitation.evaluate(tr.t[sel])
    return y if kind == "y" else yd


def _chunk_excitation(excitation, t_a, t_b):
    from nlbeam.excitation import CosineSum

    if isinstance(excitation, CosineSum) and excitation.tab.shape[0] <= 64:
        return excitation  # a few cosines: the kernel evaluates them directly
    if hasattr(excitation, "sampled") and not _is_plain_table(excitation):
        return excitation.sampled(t_b, t_start=t_a)
    return excitation


def _is_plain_table(excitation):
    from nlbeam.excitation import Sampled

    return isinstance(excitation, Sampled)


def _attr(v):
    """``v`` as a plain HDF5 attribute value (None -> "none", integers beyond int64 -> str), so
    a result compares equal to itself saved and loaded (the seed)."""
    if v is None:
        return "none"
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v) if abs(int(v)) < 2 ** 63 else str(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    return str(v)


@dataclass(repr=False)
class StochasticResult(Summary):
    """Statistics of one simulated record (the kept ``duration`` after the ``transient``).

    Per channel (``channels``): Welch PSD ``psd(ch) -> (f Hz, P units^2/Hz)`` with its
    chi-square 95 % interval ``psd_interval(ch)`` and ``n_averages`` segments; histogram
    PDF ``pdf(ch) -> (centres, density)`` with ``density_se`` and under/overflow counts in
    ``pdf_details(ch)``; ``moments(ch)`` -> dict(mean, std, variance, skewness, kurtosis
    (non-excess), p_positive = P(channel > 0), their standard errors se_*, se_dof, n_eff_*).
    Every standard error is one standard deviation of the estimate over independent records
    of the same length, from the record's own correlation and without a Gaussian
    assumption (overlapping batch means of the linearized statistic over windows of 10
    measured correlation times; see ``StreamingMoments.result``, ``stochastic.errors``).

    Counters, all over the kept record: ``n_impacts`` (contact onsets, every element),
    ``contact_fraction`` (per element, in ``model.contact_elements`` order: the fraction of
    the kept time spent in contact, from the located onset and end times), so
    ``n_impacts / duration`` is the impact rate. ``n_impacts_transient``: onsets in the
    discarded transient. ``n_steps``, ``n_chunks``, ``n_samples``: work over the whole run.
    ``history``: kept time samples (``t`` and channels) or None.
    """

    channels: tuple
    outputs: tuple
    fs: float
    dt: float
    t_start: float
    transient: float
    duration: float
    method: str
    seed: object
    model_parameters: dict
    excitation_description: dict
    nlbeam_version: str
    psd_data: dict = field(default_factory=dict)
    pdf_data: dict = field(default_factory=dict)
    moment_data: dict = field(default_factory=dict)
    history: dict | None = None
    n_impacts: int = 0
    n_impacts_transient: int = 0
    contact_fraction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n_steps: int = 0
    n_chunks: int = 0
    n_samples: int = 0
    min_steps_per_contact: int = 0
    wall_time: float = 0.0
    success: bool = True
    message: str = "completed"

    def _summary_rows(self):
        rows = [("channels", ", ".join(self.channels)), ("outputs", ", ".join(self.outputs)),
                ("record", f"{self.duration:.6g} s kept after a {self.transient:.6g} s "
                           f"transient, fs {self.fs:.6g} Hz"),
                ("method", str(self.method)), ("seed", describe_value(self.seed)),
                ("impacts", f"{self.n_impacts} ({self.n_impacts / self.duration:.4g} /s)"
                 if self.duration > 0 else str(self.n_impacts))]
        for ch in self.channels:
            parts = []
            if ch in self.moment_data:
                mo = self.moment_data[ch]
                se = float(mo.get("se_std", float("nan")))
                parts.append(f"std {mo['std']:.4g}" + (f" +- {se:.2g}" if se == se else ""))
                parts.append(f"kurtosis {mo['kurtosis']:.3g}")
            if ch in self.psd_data:
                d = self.psd_data[ch]
                f = np.asarray(d.get("frequencies", ()))
                if f.size > 1:
                    parts.append(f"PSD {f.size} bins of {f[1] - f[0]:.3g} Hz")
                if "n_segments" in d:
                    parts.append(f"{int(d['n_segments'])} averages")
            if ch in self.pdf_data:
                parts.append(f"PDF {len(self.pdf_data[ch].get('centres', ()))} bins")
            rows.append((f"  {ch}", ", ".join(parts) or "-"))
        if self.history is not None and "t" in self.history:
            rows.append(("history", describe_value(np.asarray(self.history["t"]))))
        rows += [("success", f"{self.success} ({describe_value(self.message)})"),
                 ("wall_time [s]", f"{self.wall_time:.3g}")]
        return rows

    def _get(self, store, ch, what):
        if ch not in self.channels:
            raise ValueError(f"ch: {ch!r} was not recorded; channels are {self.channels}")
        if ch not in store:
            raise ValueError(f"ch: {what} was not computed (outputs={self.outputs})")
        return store[ch]

    def psd(self, ch="delta"):
        """(frequencies Hz, one-sided PSD units^2/Hz) of channel ``ch``."""
        d = self._get(self.psd_data, ch, "psd")
        return d["frequencies"], d["psd"]

    def psd_interval(self, ch="delta"):
        """(lower, upper) chi-square 95 % bounds of the PSD of ``ch`` (Welch dof)."""
        d = self._get(self.psd_data, ch, "psd")
        return d["ci95_low"], d["ci95_high"]

    def n_averages(self, ch="delta"):
        """Number of Welch segments averaged for ``ch``."""
        return int(self._get(self.psd_data, ch, "psd")["n_segments"])

    def psd_relative_std(self, ch="delta"):
        """Relative standard deviation of each PSD bin of ``ch``, sqrt(2/nu)."""
        return self._get(self.psd_data, ch, "psd")["relative_std"]

    def pdf(self, ch="delta"):
        """(bin centres, probability density 1/units) of ``ch``; see ``pdf_details``."""
        d = self._get(self.pdf_data, ch, "pdf")
        return d["centres"], d["density"]

    def pdf_details(self, ch="delta"):
        """Full histogram record: edges, counts, n_below, n_above, n_total, density_se."""
        return dict(self._get(self.pdf_data, ch, "pdf"))

    def moments(self, ch="delta"):
        """dict(mean, std, variance, skewness, kurtosis, p_positive, se_mean, se_std,
        se_variance, se_skewness, se_kurtosis, se_p_positive, se_dof, n, n_eff_*) of ``ch``.

        se_x: one standard deviation of x over independent records of this length (about
        68 % of such records fall within +-se, 95 % within +-2 se when se_dof >= 20), from
        overlapping batch means of x's influence function over windows of 10 integrated
        correlation times measured on this record, and at least two realization spans of a
        block noise (8.8 s for a 200 Hz band: its random line amplitudes hold that long):
        valid for non-Gaussian, correlated responses. se_dof: approximate degrees of
        freedom of the errors themselves (about 1.5 (duration / window - 1); below ~10 the
        errors are rough, use Student's t)."""
        return dict(self._get(self.moment_data, ch, "moments"))

    # -- files ------------------------------------------------------------------------
    def save(self, path):
        """Write to HDF5 (temporary file in the same directory, then renamed; the usual
        file mode under the umask). Returns ``path``. The file format lives on the
        application floor (nlbeam.app.files.stochastic_hdf5), which imports h5py."""
        from nlbeam.app.files.stochastic_hdf5 import save_stochastic_result

        return save_stochastic_result(self, path)


def load(path) -> StochasticResult:
    """Read a :class:`StochasticResult` written by ``save`` (the format:
    nlbeam.app.files.stochastic_hdf5)."""
    from nlbeam._validate import path_like
    from nlbeam.app.files.stochastic_hdf5 import load_stochastic_result

    return load_stochastic_result(path_like("path", path))


def _history_window(window, t_kept, duration):
    """keep_history (s after the transient) -> the absolute window [h0, h1] s; raises when it
    is not a window inside the kept record [0, duration]."""
    try:
        w0, w1 = (float(v) for v in window)
    except (TypeError, ValueError):
        raise ValueError(f"keep_history: must be (t0, t1) in s after the transient or None, "
                         f"got {window!r}") from None
    if not w1 > w0:
        raise ValueError(f"keep_history: must satisfy t0 < t1, got {window!r}")
    slack = 1e-9 * max(duration, 1.0)
    if w0 < -slack or w1 > duration + slack:
        raise ValueError(f"keep_history: {window!r} s lies outside the kept record [0, "
                         f"{duration:.6g}] s (times count from the end of the transient)")
    return t_kept + w0, t_kept + w1


def _check_nyquist(excitation, dt, store_every):
    """Raise ValueError naming dt when the excitation's highest frequency (Hz) is above the
    Nyquist frequency 1/(2 dt store_every) of the samples (its PSD peak would alias)."""
    f_max = float(excitation.max_frequency())
    nyq = 0.5 / (dt * store_every)
    if f_max > nyq * (1 + 1e-9):
        raise ValueError(f"dt: samples every {dt * store_every:.6g} s (dt {dt:.6g} s x "
                         f"store_every {store_every}) have Nyquist frequency {nyq:.6g} Hz, below "
                         f"the excitation's highest frequency {f_max:.6g} Hz (it would show at an "
                         f"aliased frequency); use dt * store_every < {0.5 / f_max:.6g} s")


def _warn_short_record(excitation, duration):
    """RuntimeWarning when the record (duration, s) is shorter than the correlation time of a
    noise, 1 / its band's width (s): its statistics then describe one quasi-static stretch of
    the noise (a band of (0, 1e-3) Hz over 10 s: a nearly constant input), not its
    distribution."""
    band = getattr(excitation, "band", None)
    if band is None:
        return
    width = float(band[1]) - float(band[0])
    if width > 0 and width * duration < 1.0:  # (a single line, width 0, is no noise)
        tc = 1.0 / width
        warnings.warn(f"duration: {duration:.6g} s is shorter than the excitation's correlation "
                      f"time 1 / band width = {tc:.6g} s: the statistics describe one "
                      f"quasi-static stretch of the noise, not its distribution; give "
                      f"duration >= {tc:.6g} s (a mean square then errs by about "
                      "1 / sqrt(band width x duration)) or a wider band", RuntimeWarning,
                      stacklevel=3)


def _default_resolution(duration):
    # >= ~31 Welch averages (50 % overlap), never finer than 0.05 Hz
    return max(0.05, 16.0 / duration)


def simulate(model, excitation, duration, transient=None, outputs=OUTPUTS, channels=("delta",),
             method="adaptive", dt=None, rtol=1e-8, atol=1e-12, seed=None, psd_resolution=None,
             keep_history=None, *, x0=None, store_every=1, steps_per_contact=None,
             chunk_duration=None, pdf_bins=200, pdf_edges=None, batch_duration=None,
             progress=None, max_samples=MAX_SAMPLES) -> StochasticResult:
    """Simulate ``model`` under ``excitation`` for ``transient + duration`` seconds and
    return the statistics of the last ``duration`` seconds.

    excitation: a stochastic excitation (``BandLimitedNoise``, ``SpectralNoise``,
    ``Realization``, ``Recorded``), any ``nlbeam.Excitation``, or a callable
    ``seed -> excitation`` (then ``seed`` is required).
    duration, transient: s (transient default: 10 / (damping ratio * 2 pi f_n) of the
    slowest mode, i.e. ~10 decay times). outputs: any of "psd", "pdf", "moments".
    channels: "x", "v" (output DOF, or "x[i]"), "y", "yd", "delta", "force" ("delta[e]").
    method, dt, rtol, atol, steps_per_contact, x0: as ``nlbeam.integrate``; the samples are
    every ``store_every`` steps of ``dt`` (sampling frequency fs = 1/(dt store_every));
    the band of a noise must lie below fs/2 (checked). The default, adaptive DP5 at rtol
    1e-8 / atol 1e-12 m with samples every dt = 1/(32 f_max) (6.4 kHz for a 200 Hz band), gives
    a max|x| error of ~5e-7 of the record's max|x| on the paper's beam (2 s, 95 impacts, against
    a DOP853 rtol 1e-13 reference; benchmarks/stochastic_work_precision.py) at ~0.4 the CPU of
    rk4 with dt = 5e-5 s and 32 steps per contact, whose error there is 5.6e-4.
    psd_resolution: Welch bin spacing (Hz), default max(0.05, 16/duration).
    keep_history: (t0, t1) s after the transient (0 <= t0 < t1 <= duration: a window
    outside the kept record raises), keep the samples in that window (memory ~ its length);
    ``history["t"]`` holds their times from the excitation's start (t_start + transient + t0
    onwards).
    chunk_duration: s per call to the integrator (default: the noise's block or 1 s).
    pdf_bins / pdf_edges: histogram (edges chosen from the first kept chunk if not given).
    batch_duration: s per fine batch of the standard errors (default 64 samples); the
    batches the errors use are chosen from the measured correlation time (see
    ``StochasticResult.moments``).
    progress: callable(t_done_s, t_total_s) called after every chunk, or True to print.
    max_samples: refuse a run of more integration samples (transient + duration) / dt than
    this before it starts (default MAX_SAMPLES = 1e8), or a block noise that would synthesize
    more than SYNTHESIS_PER_SAMPLE (10) times as many table samples.
    Every excitation's highest frequency must lie below the sampling Nyquist frequency
    fs/2 (checked: a harmonic input above it would show at an aliased frequency).

    A noise whose line spacing is too coarse for the damping of the model's linear modes
    (predicted kurtosis bias of a mode's response above 0.01, ``noise.kurtosis_bias``) is
    reported by a RuntimeWarning and in ``message``. Contact onsets with a non-positive
    rate and runaways fail the result only inside the kept record; inside the discarded
    transient they are noted in ``message``.
    """
    import nlbeam

    t_wall = time.perf_counter()
    if callable(excitation) and not hasattr(excitation, "kernel_args"):
        if seed is None:
            raise ValueError("seed: required when excitation is a factory seed -> excitation")
        excitation = excitation(seed)
    elif seed is not None and getattr(excitation, "seed", seed) != seed:
        raise ValueError(f"seed: {seed!r} differs from the excitation's own seed "
                         f"{excitation.seed!r}; pass a factory seed -> excitation to set it")
    if not hasattr(excitation, "kernel_args"):
        raise ValueError("excitation: must be an nlbeam.Excitation or a stochastic excitation")
    if not hasattr(model, "kernel_arrays"):
        raise ValueError("model: must be an nlbeam model (BeamImpact, Duffing, System, ...)")
    duration = positive("duration", duration, unit="s")
    if isinstance(outputs, str):
        outputs = (outputs,)
    outputs = choices("outputs", outputs, OUTPUTS)
    if not outputs:
        raise ValueError(f"outputs: give at least one of {OUTPUTS}, got ()")
    if isinstance(channels, str):
        channels = (channels,)
    if not hasattr(channels, "__iter__"):
        raise ArgumentTypeError(f"channels: must be a tuple of channel names, got {channels!r}")
    channels = tuple(channels)
    if not channels:
        raise ValueError("channels: give at least one channel")
    for ch in channels:
        if not isinstance(ch, str):
            raise ArgumentTypeError(f"channels: must be names such as 'x' or 'delta[0]', got "
                                    f"{ch!r}")
    choice("method", method, METHODS)
    positive("rtol", rtol)
    positive("atol", atol)
    max_samples = positive("max_samples", max_samples)
    pdf_bins = integer("pdf_bins", pdf_bins, 1, 10_000_000)
    if pdf_edges is not None:
        real_array("pdf_edges", pdf_edges, ndim=1, min_size=2)
    if progress is not True:
        callable_or_none("progress", progress, "a callable(t_done, t_total), True")
    parsed = {ch: _parse_channel(ch, model) for ch in channels}
    if transient is None:
        transient = default_transient(model)
    transient = nonnegative("transient", transient, unit="s")
    if (isinstance(store_every, bool) or not isinstance(store_every, (int, np.integer))
            or store_every < 1):
        raise ValueError(f"store_every: must be an integer >= 1, got {store_every!r}")
    if dt is None:
        dt = nlbeam.default_dt(model, excitation, method)
    dt = positive("dt", dt, unit="s")
    fs = 1.0 / (dt * store_every)
    if hasattr(excitation, "check_band_vs_step"):
        excitation.check_band_vs_step(dt * store_every)
    else:
        _check_nyquist(excitation, dt, store_every)
    check_count(f"simulate: integration samples of dt = {dt:.4g} s over transient + duration "
                f"= {transient + duration:.6g} s", (transient + duration) / dt, max_samples,
                "give a larger dt (or store_every), a shorter duration or transient, a "
                "narrower band, or raise max_samples")
    if getattr(excitation, "n_block", None) is not None:  # a block noise: its synthesis
        check_count(f"simulate: noise samples of h = {excitation.h:.4g} s synthesized over "
                    f"transient + duration = {transient + duration:.6g} s",
                    (transient + duration) / excitation.h, SYNTHESIS_PER_SAMPLE * max_samples,
                    "give a narrower band (h follows its upper edge), a shorter duration or "
                    "transient, or raise max_samples")
    t0 = float(excitation.time_span()[0]) if math.isfinite(excitation.time_span()[0]) else 0.0
    n_tr = int(round(transient / (dt * store_every))) * store_every  # steps, on the sample grid
    n_keep = int(round(duration / (dt * store_every))) * store_every
    if n_keep < 2 * store_every:
        raise ValueError(f"duration: must span at least 2 samples "
                         f"(>= {2 * dt * store_every:.3g} s)")
    _warn_short_record(excitation, duration)
    n_total = n_tr + n_keep
    t_total_end = t0 + n_total * dt
    hi = excitation.time_span()[1]
    if t_total_end > hi + 1e-9 * max(abs(hi), 1.0):
        raise ValueError(f"duration: transient + duration = {n_total * dt:.6g} s exceeds the "
                         f"excitation's span, which ends at {hi:.6g} s")
    if chunk_duration is None:
        chunk_duration = getattr(excitation, "block_duration", 1.0)
    chunk_duration = positive("chunk_duration", chunk_duration, unit="s")
    if chunk_duration < 2 * dt * store_every:
        raise ValueError(f"chunk_duration: must span at least 2 samples (>= "
                         f"{2 * dt * store_every:.3g} s), got {chunk_duration!r}")
    m = max(int(round(chunk_duration / (dt * store_every))), 2) * store_every  # steps per chunk
    if psd_resolution is None:
        psd_resolution = _default_resolution(n_keep * dt)
    psd_resolution = positive("psd_resolution", psd_resolution, unit="Hz")
    if "psd" in outputs:
        check_memory(f"psd_resolution: Welch segments of {fs / psd_resolution:.3g} samples for "
                     f"{len(channels)} channel(s)", 48.0 * fs / psd_resolution * len(channels),
                     "give a coarser psd_resolution (Hz), or a larger dt or store_every")
    if "psd" in outputs and psd_resolution * n_keep * dt < 1.0:
        raise ValueError(f"psd_resolution: {psd_resolution} Hz needs segments of "
                         f"{1 / psd_resolution:.3g} s, longer than duration {n_keep * dt:.3g} s")
    batch = 64 if batch_duration is None else max(
        int(round(positive("batch_duration", batch_duration, unit="s") * fs)), 1)
    if keep_history is not None:
        h0, h1 = _history_window(keep_history, t0 + n_tr * dt, n_keep * dt)
        h_tol = 1e-6 * dt * store_every  # the ends are samples: round-off of the grid times
        n_hist = (h1 - h0) * fs + 1
        check_memory(f"keep_history: {n_hist:.3g} samples of {len(channels) + 1} series",
                     8.0 * n_hist * (len(channels) + 1), "give a shorter keep_history window")
    if progress is True:
        def progress(done, total):  # noqa: F811 - the printing default
            print(f"stochastic.simulate: {done:.4g} / {total:.4g} s", file=sys.stderr)

    est = make_estimators(channels, outputs, fs, psd_resolution, pdf_edges, pdf_bins, batch)
    hist_parts = {"t": []}
    hist_parts.update({ch: [] for ch in channels})

    spacing_note = _check_line_spacing(model, excitation)
    state, disc = x0, None
    chunk_warnings = {}
    n_impacts = n_impacts_tr = n_steps = n_chunks = n_samples = 0
    min_spc = 0
    bad = {"kept": [0, None], "transient": [0, None]}  # onsets with rate <= 0: count, first t
    chunk_std, t_runaway, t_runaway_tr = [], None, None
    contact_el = [int(e) for e in model.contact_elements]
    contact_time = np.zeros(len(contact_el))
    k0 = 0
    while k0 < n_total:
        # chunks never straddle the end of the transient: counters split exactly there
        k1 = min(k0 + m, n_total, n_tr if k0 < n_tr else n_total)
        kept = k0 >= n_tr
        t_a, t_b = t0 + k0 * dt, t0 + k1 * dt
        exc = _chunk_excitation(excitation, t_a, t_b)
        disc_a = disc if disc is not None or not kept else _contact_at_start(model, exc, state, t_a)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                tr = nlbeam.integrate(model, exc, t_b, method=method, dt=dt, x0=state, t0=t_a,
                                      disc0=disc, store_every=store_every,
                                      steps_per_contact=steps_per_contact, rtol=rtol, atol=atol)
        except nlbeam.IntegrationError as err:
            raise nlbeam.IntegrationError(f"chunk [{t_a:.6g}, {t_b:.6g}] s: {err}") from err
        for w in caught:  # gathered, and reported once at the end
            key = (w.category, re.sub(r"\d+", "#", str(w.message)))
            if key not in chunk_warnings:
                chunk_warnings[key] = [w, 0]
            chunk_warnings[key][1] += 1
        state, disc = tr.state_end, tr.disc_end
        if tr.events is not None and tr.n_events:
            ev = tr.events[:min(tr.n_events, tr.events.shape[0])]
            # an onset with delta' <= 0 that starts a contact of nonzero duration (a
            # zero-length onset/end pair at one instant is a harmless grazing touch)
            for e in np.unique(ev[:, 1]).astype(int):
                ee = ev[ev[:, 1] == e]
                t_next = np.append(ee[1:, 0], np.inf if tr.disc_end[e, 0] else ee[-1, 0])
                lasts = t_next - ee[:, 0] > 1e-12 * np.maximum(np.abs(ee[:, 0]), 1.0)
                is_bad = (ee[:, 2] == 1) & ~(ee[:, 3] > 0) & lasts
                if np.any(is_bad):
                    b = bad["kept" if kept else "transient"]
                    b[0] += int(np.sum(is_bad))
                    t1 = float(ee[np.argmax(is_bad), 0])
                    b[1] = t1 if b[1] is None else min(b[1], t1)
        # runaway guard: a chunk whose largest excursion of x from its mean exceeds 50 times
        # the median std of the chunks so far has gained energy numerically
        xo = tr.x[:, model.output_dof]
        if xo.size > 1:
            sd = float(np.std(xo))
            if len(chunk_std) >= 3:
                ref = float(np.median(chunk_std))
                if not (np.max(np.abs(xo - np.mean(xo))) <= 50.0 * ref):
                    if kept and t_runaway is None:
                        t_runaway = t_a
                    elif not kept and t_runaway_tr is None:
                        t_runaway_tr = t_a
            chunk_std.append(sd)
        if kept:
            n_impacts += tr.n_impacts
            contact_time += _contact_time(tr, contact_el, disc_a, t_a, t_b)
        else:
            n_impacts_tr += tr.n_impacts
        n_steps += tr.n_steps
        n_chunks += 1
        if tr.min_steps_per_contact > 0:
            spc = tr.min_steps_per_contact
            min_spc = spc if min_spc == 0 else min(min_spc, spc)
        # samples on the global grid t0 + j store_every dt, [t_a, t_b): drop the chunk end
        j = np.rint((tr.t - t0) / (dt * store_every))
        on_grid = np.abs((tr.t - t0) / (dt * store_every) - j) < 1e-6
        keep = on_grid & (j * store_every >= max(k0, n_tr)) & (j * store_every < k1)
        sel = np.nonzero(keep)[0]
        expected = (k1 - max(k0, n_tr)) // store_every if k1 > n_tr else 0
        if sel.size != max(expected, 0):
            raise RuntimeError(f"internal: chunk [{t_a}, {t_b}] s gave {sel.size} samples on the "
                               f"grid, expected {expected}; nlbeam.integrate's sampling changed?")
        if sel.size:
            n_samples += sel.size
            for ch, (kind, i) in parsed.items():
                data = np.ascontiguousarray(_extract(tr, kind, i, sel))
                feed(est[ch], data)
                if keep_history is not None:
                    hsel = (tr.t[sel] >= h0 - h_tol) & (tr.t[sel] <= h1 + h_tol)
                    if np.any(hsel):
                        hist_parts[ch].append(data[hsel])
            if keep_history is not None:
                hsel = (tr.t[sel] >= h0 - h_tol) & (tr.t[sel] <= h1 + h_tol)
                if np.any(hsel):
                    hist_parts["t"].append(tr.t[sel][hsel])
        k0 = k1
        if progress is not None:
            progress(k0 * dt, n_total * dt)

    res = StochasticResult(
        channels=channels, outputs=outputs, fs=fs, dt=dt, t_start=t0, transient=n_tr * dt,
        duration=n_keep * dt, method=method,
        seed=_attr(seed if seed is not None else getattr(excitation, "seed", None)),
        model_parameters=dict(model.parameters()),
        excitation_description=dict(excitation.describe()),
        nlbeam_version=str(getattr(nlbeam, "__version__", "unknown")))
    # the line amplitudes of a block noise hold for one realization span: the errors'
    # windows cover at least two of them (stochastic.errors)
    span = getattr(excitation, "realization_duration", None)
    min_window = None if span is None else int(math.ceil(2.0 * span * fs))
    store_results(res, est, min_window)
    if keep_history is not None:
        res.history = {k: (np.concatenate(v) if v else np.zeros(0)) for k, v in hist_parts.items()}
    res.n_impacts, res.n_steps = n_impacts, n_steps
    res.n_chunks, res.n_samples = n_chunks, n_samples
    res.n_impacts_transient = n_impacts_tr
    res.contact_fraction = contact_time / (n_keep * dt)
    res.min_steps_per_contact = min_spc
    notes = []
    if spacing_note:
        notes.append(spacing_note)
    n_tr_bad, t_tr_bad = bad["transient"]
    if n_tr_bad:
        notes.append(f"{n_tr_bad} contact onset(s) with penetration rate <= 0 in the discarded "
                     f"transient (first at t = {t_tr_bad:.9g} s), not in the kept record")
    if t_runaway_tr is not None:
        notes.append(f"a large excursion of x in the discarded transient (chunk starting at "
                     f"t = {t_runaway_tr:.6g} s), not in the kept record")
    if chunk_warnings:
        msgs = [f"{str(w.message)} (in {n} of {n_chunks} chunks; fewest steps in a contact "
                f"over the run: {min_spc})" for w, n in chunk_warnings.values()]
        res.message = "completed with warnings: " + "; ".join(msgs)
        for (w, n), text in zip(chunk_warnings.values(), msgs):
            warnings.warn(text, w.category, stacklevel=2)
    if notes:
        res.message += ("; " if res.message != "completed" else " (") + "; ".join(notes) + (
            "" if res.message != "completed" else ")")
    if t_runaway is not None:
        text = (f"the response ran away in the chunk starting at t = {t_runaway:.6g} s (an "
                "excursion of x above 50 times the typical chunk std: energy gained numerically, "
                "e.g. in a stiff contact); the statistics are unreliable; raise "
                "steps_per_contact or reduce dt")
        res.success = False
        res.message = "failed: " + text + ("; " + res.message if res.message != "completed" else "")
        warnings.warn(text, RuntimeWarning, stacklevel=2)
    n_bad_onsets, t_bad_onset = bad["kept"]
    if n_bad_onsets:
        # a contact onset with delta' <= 0 (a grazing re-entry just after a contact end) makes
        # the Lankarani-Nikravesh damping term change sign and feed energy in: the record is
        # not trustworthy from there on
        text = (f"{n_bad_onsets} contact onset(s) with penetration rate <= 0 (first at t = "
                f"{t_bad_onset:.9g} s): a grazing re-contact the integrator did not resolve; the "
                "statistics after it are unreliable; change dt or the seed")
        res.success = False
        earlier = "; " + res.message if res.message != "completed" else ""
        res.message = "failed: " + text + earlier
        warnings.warn(text, RuntimeWarning, stacklevel=2)
    res.wall_time = time.perf_counter() - t_wall
    return res


def default_transient(model):
    """The transient ``simulate`` discards when given none (s): 10 decay times of the
    slowest mode, 10 / (damping ratio * 2 pi f_n), at most 1e4 s."""
    wn = 2 * np.pi * np.min(model.system.natural_frequencies())
    zeta = _min_damping_ratio(model)
    return 10.0 / max(zeta * wn, 1e-3)


def _contact_at_start(model, excitation, state, t):
    """disc rows [in contact, 0] at time t of ``state`` (None: at rest), as integrate's
    start-in-contact rule (only the in-contact flag is used here)."""
    N = model.n_dof
    s0 = np.zeros(2 * N) if state is None else np.asarray(state, dtype=float).ravel()
    y, yd = excitation.evaluate([t])
    d, _ = model.penetration(s0, y[0], yd[0])
    disc = np.zeros((model.n_elements, 2))
    disc[:, 0] = np.asarray(d, dtype=float).ravel() > 0
    return disc


def _contact_time(tr, elements, disc_a, t_a, t_b):
    """Time (s) each of ``elements`` spends in contact over the chunk [t_a, t_b] of the
    trajectory ``tr``, from the located onset/end events (the chunk starts in contact where
    disc_a[e, 0] != 0). If the event log overflowed, from the stored samples (delta > 0)."""
    out = np.zeros(len(elements))
    if not elements:
        return out
    n_ev = int(tr.n_events)
    ev = tr.events[:n_ev] if tr.events is not None else np.zeros((0, 4))
    if tr.events is None or n_ev > tr.events.shape[0]:
        inside = tr.delta[:-1, elements] > 0 if tr.delta.shape[0] > 1 else tr.delta[:, elements] > 0
        return np.mean(inside, axis=0) * (t_b - t_a)
    for j, e in enumerate(elements):
        ee = ev[ev[:, 1] == e]
        start = t_a if disc_a[e, 0] != 0 else None
        total = 0.0
        for t, kind in zip(ee[:, 0], ee[:, 2]):
            if kind == 1:
                start = t
            elif start is not None:
                total += t - start
                start = None
        if start is not None and tr.disc_end[e, 0] != 0:
            total += t_b - start
        out[j] = total
    return out


def _damped_modes(model):
    """(f_n Hz, zeta) of the underdamped modes of the linear structure M x'' + C x' + K x
    (state-space eigenvalues lambda = -zeta w_n +- i w_n sqrt(1 - zeta^2), any damping)."""
    s = model.system
    M, C, K = (np.asarray(a, dtype=float) for a in (s.M, s.C, s.K))
    N = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((N, N)), np.eye(N)], [-Mi @ K, -Mi @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 1e-9 * np.maximum(np.abs(lam), 1e-300)]
    wn = np.abs(lam)
    keep = wn > 0
    return wn[keep] / (2 * np.pi), -lam.real[keep] / wn[keep]


def _check_line_spacing(model, excitation, limit=0.01):
    """Warn (and return the text) when a block noise's lines are too coarse for the damping
    of a linear mode of the model: |predicted kurtosis bias of that mode's response| > limit
    (``excitation.kurtosis_bias``). Returns None when fine or not applicable."""
    if not hasattr(excitation, "kurtosis_bias"):
        return None
    worst = None
    for f_n, zeta in zip(*_damped_modes(model)):
        if not zeta > 0:
            continue
        b = excitation.kurtosis_bias(f_n, zeta)
        if math.isfinite(b) and abs(b) > limit and (worst is None or abs(b) > abs(worst[0])):
            worst = (b, f_n, zeta)
    if worst is None:
        return None
    b, f_n, zeta = worst
    bw = 2 * zeta * f_n
    fix = ("use amplitudes='random' (the default) or " if not excitation.random_amplitudes
           else "")
    text = (f"noise lines too coarse for the model's damping: line spacing df = "
            f"{excitation.df:.4g} Hz against the half-power bandwidth {bw:.4g} Hz of the mode at "
            f"{f_n:.4g} Hz (amplitudes={excitation.amplitudes!r}): the kurtosis of a linear "
            f"response there is biased by about {b:+.3f}; {fix}give a longer block_duration "
            f"(df is about 1/(1.5 block_duration)) so that df is well below {bw:.4g} Hz")
    warnings.warn(text, RuntimeWarning, stacklevel=3)
    return text


def _min_damping_ratio(model):
    """Smallest modal damping ratio of the linear structure (for the default transient)."""
    s = model.system
    M, C, K = (np.asarray(a, dtype=float) for a in (s.M, s.C, s.K))
    w2, V = np.linalg.eig(np.linalg.solve(M, K))
    z = []
    for k in range(w2.size):
        v = np.real(V[:, k])
        mk, ck, kk = v @ M @ v, v @ C @ v, v @ K @ v
        if kk > 0 and mk > 0:
            z.append(ck / (2 * math.sqrt(kk * mk)))
    return max(min(z), 1e-4) if z else 1.0


# -- ensembles ----------------------------------------------------------------------------
@dataclass(repr=False)
class EnsembleResult(Summary):
    """Members of an ensemble and their combination.

    ``psd(ch) -> (f, mean P, lower, upper)``: mean over members with a Student-t 95 %
    interval from the member scatter. ``moments(ch)``: for each of mean, std, skewness,
    kurtosis the mean over members, its standard error (member scatter / sqrt(M)) and a
    95 % interval; plus the pooled estimate from merging all samples.
    """

    seeds: list
    members: list

    def _summary_rows(self):
        first = self.members[0] if self.members else None
        rows = [("members", str(len(self.members))), ("seeds", describe_value(self.seeds))]
        if first is not None:
            rows += [("channels", ", ".join(first.channels)),
                     ("record", f"{first.duration:.6g} s each, fs {first.fs:.6g} Hz"),
                     ("success", f"{sum(bool(m.success) for m in self.members)} of "
                                 f"{len(self.members)}")]
        return rows

    def _check(self):
        if len(self.members) < 2:
            raise ValueError("seeds: an ensemble needs at least 2 members for an interval")

    def psd(self, ch="delta"):
        from scipy.stats import t as student

        self._check()
        P = np.array([m.psd(ch)[1] for m in self.members])
        M = P.shape[0]
        mean = P.mean(axis=0)
        se = P.std(axis=0, ddof=1) / math.sqrt(M)
        q = student.ppf(0.975, M - 1)
        return self.members[0].psd(ch)[0], mean, mean - q * se, mean + q * se

    def moments(self, ch="delta"):
        from scipy.stats import t as student

        self._check()
        M = len(self.members)
        q = student.ppf(0.975, M - 1)
        out = {"n_members": M}
        for key in ("mean", "std", "skewness", "kurtosis"):
            v = np.array([m.moments(ch)[key] for m in self.members])
            se = float(v.std(ddof=1) / math.sqrt(M))
            out[key] = float(v.mean())
            out[f"se_{key}"] = se
            out[f"ci95_{key}"] = (float(v.mean() - q * se), float(v.mean() + q * se))
        return out


def _member(args):
    model, make_excitation, seed, kwargs = args
    return simulate(model, make_excitation, seed=seed, **kwargs)


def ensemble(model, make_excitation, seeds, duration, *, workers=None, scheduler=None,
             processes=None, **kwargs) -> EnsembleResult:
    """Run ``simulate`` once per seed (excitation ``make_excitation(seed)``) and combine:
    in ``workers`` local processes (None: the CPU count, at most one per seed; 1: in this
    process) or on the Dask scheduler ``scheduler`` (an address or distributed.Client; see
    nlbeam.pool). The members are the same wherever they run. make_excitation must be
    picklable (a module-level function) unless everything runs here. ``processes``: the
    former name of ``workers`` (deprecated). Other keywords go to :func:`simulate`."""
    import inspect
    import pickle

    from nlbeam.pool import Pool

    if processes is not None:
        processes = integer("processes", processes, 1, 4096)
        warnings.warn("ensemble: processes= is deprecated; use workers= (the same meaning)",
                      DeprecationWarning, stacklevel=2)
        if workers is not None and workers != processes:
            raise ValueError(f"workers: {workers!r} and processes: {processes!r} disagree; "
                             "give workers only")
        workers = processes
    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__iter__"):
        raise ArgumentTypeError(f"seeds: must be a list of non-negative integers, got {seeds!r}")
    seeds = [integer("seeds", s, 0) for s in seeds]
    if workers is not None:
        workers = integer("workers", workers, 1, 4096)
    if not callable(make_excitation):
        raise ArgumentTypeError(f"make_excitation: must be a callable seed -> excitation, got "
                                f"{type(make_excitation).__name__}")
    names = [n for n in inspect.signature(simulate).parameters
             if n not in ("model", "excitation", "seed", "duration")]
    for k in kwargs:
        if k not in names:
            from nlbeam._validate import keywords

            keywords("ensemble", {k: None}, names + ["workers", "scheduler", "processes"])
    if (workers != 1 or scheduler is not None) and len(seeds) > 1:
        try:
            pickle.dumps(make_excitation)
        except Exception as exc:
            raise ArgumentTypeError(f"make_excitation: cannot be sent to the worker processes "
                                    f"({type(exc).__name__}: {exc}); define it at module level "
                                    "(not a lambda or a local function), or pass workers=1") \
                from None
    if len(seeds) < 1:
        raise ValueError("seeds: give at least one seed")
    if len(set(seeds)) != len(seeds):
        raise ValueError("seeds: must be distinct")
    kwargs["duration"] = duration
    jobs = [(model, make_excitation, s, kwargs) for s in seeds]
    if scheduler is None and len(seeds) == 1:
        workers = 1
    elif scheduler is None and workers is None:
        workers = min(len(seeds), os.cpu_count() or 1)
    with Pool(workers, scheduler) as pool:
        if not pool.serial and scheduler is None:  # compiled (or loaded) once, here: the
            from nlbeam.integrate import compile_kernels  # forked workers inherit it

            compile_kernels(model, False)
        members = pool.map(_member, jobs)
    return EnsembleResult(seeds=seeds, members=members)
