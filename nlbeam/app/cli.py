"""Command line: ``nlbeam demo | frc | continue | refine | simulate | compare | analyze |
identify | run | figures``.

Units everywhere: SI (m, s, kg, N), frequencies in Hz. Progress goes to stderr; ``--quiet``
silences it. A warning is one line on stderr (``nlbeam CMD: warning: ...``), --quiet or not. On
failure: a one-line cause on stderr and exit status 2 (130 if interrupted).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

_UNITS = ("Units: displacements and amplitudes in m (1e-4 = 0.1 mm), frequencies in Hz, "
          "times in s, K_hertz in N/m^1.5.")


def _log(args):
    """Progress lines on stderr (a bar for what advances, on a terminal); none with --quiet."""
    from .progress import Progress

    return Progress(quiet=args.quiet)


#: the paper beam's parameters the command line sets (--m, --K-hertz, ...): BeamImpact's
_BEAM_OPTIONS = ("m", "k", "b", "K_hertz", "e", "gap", "contact", "mu")


def _model(args):
    """The model of --model SCENE (its [model]: any kind a scene takes) or of the paper beam's
    options, with each --set NAME=VALUE applied (nlbeam.parameters names)."""
    import nlbeam
    from nlbeam.parameters import with_parameter

    kw = {k: getattr(args, k) for k in _BEAM_OPTIONS if getattr(args, k, None) is not None}
    if getattr(args, "model", None):
        from .scenes.models import build_model
        from .scenes.schema import load_scene

        if kw:
            raise ValueError(f"--model: give the model's parameters with --set NAME=VALUE, "
                             f"not --{next(iter(kw)).replace('_', '-')}")
        model = build_model(load_scene(args.model).model)
    else:
        model = nlbeam.BeamImpact.paper(**kw)
    for item in getattr(args, "set", None) or []:
        name, sep, value = item.partition("=")
        try:
            v = float(value)
        except ValueError:
            v = None
        if not sep or v is None:
            raise ValueError(f"--set: must be NAME=NUMBER (e.g. elements[1].gap=1e-3), "
                             f"got {item!r}")
        model = with_parameter(model, name.strip(), v)
    return model


def _check_knobs(args, section):
    """Check the options that are keys of the scene section ``section`` ('periodic' or
    'stochastic') with the scene's own checks: one line naming the option and the range."""
    from .scenes.schema import SECTIONS

    for name, check in SECTIONS[section].items():
        v = getattr(args, name, None)
        if v is None or check is None:
            continue
        _, err = check(list(v) if isinstance(v, tuple) else v)
        if err:
            raise ValueError(f"--{name.replace('_', '-')}: {err}, got {_shown(v)}")


def _check_workers(args):
    w = getattr(args, "workers", None)
    if w is not None and w < 1:
        raise ValueError(f"--workers: must be an integer >= 1, got {w}")


def _demo(args):
    from .defaults import DEMO_WORKERS
    from .demo import DEMO_SCENE
    from .files import write_text_atomic
    from .scenes import format_plan, load_scene, plan, run_scene

    _check_workers(args)
    out = args.out
    path = os.path.join(out, "demo.toml")
    if args.dry_run:  # nothing written: validate the text from a temporary copy
        import tempfile

        with tempfile.TemporaryDirectory() as d:
            tmp = os.path.join(d, "demo.toml")
            with open(tmp, "w", encoding="utf-8") as fh:
                fh.write(DEMO_SCENE)
            scene = load_scene(tmp)
            scene.path = path
            print(format_plan(scene, plan(scene, out), out))
        return 0
    write_text_atomic(path, DEMO_SCENE)
    # small analyses: in this process unless asked (a pool's workers would each load the
    # compiled kernels, which costs more than the analyses here)
    rep = run_scene(path, out, workers=DEMO_WORKERS if args.workers is None else args.workers,
                    scheduler=args.scheduler, quiet=args.quiet)
    _log(args)(f"nlbeam demo: {rep.computed} computed, {rep.reused} reused, "
               f"{len(rep.files)} files in {rep.wall_time:.1f} s -> {out} (scene: {path})")
    return 0


def _accuracy(text):
    """--accuracy: a name ('default', 'high', 'off') or a number of digits."""
    try:
        return float(text)
    except ValueError:
        return text


def _check_out(args, *names):
    """Before any work: each output file named in args (--out, --plot) can be written."""
    from nlbeam._validate import output_file

    for n in names:
        if getattr(args, n, None):
            output_file(f"--{n}", getattr(args, n))


def _frc(args):
    import continuation

    _check_out(args, "out", "plot")
    _check_workers(args)
    log = _log(args)
    _check_knobs(args, "periodic")
    model = _model(args)
    log(f"nlbeam frc: A = {args.amplitude:g} m, {args.f_range[0]:g}-{args.f_range[1]:g} Hz, "
        f"orders {args.orders}, {args.n_grid} grid frequencies (this can take minutes)")
    from .defaults import PERIODIC

    kw = {k: getattr(args, k) for k in PERIODIC if k not in ("amplitude", "f_range", "orders")}
    frc = continuation.frequency_response(model, args.amplitude, tuple(args.f_range),
                                          orders=tuple(args.orders), stability=args.stability,
                                          progress=lambda msg: log(f"nlbeam frc:   {msg}"),
                                          workers=args.workers, scheduler=args.scheduler,
                                          **kw)
    frc.save(args.out)
    log(f"nlbeam frc: {len(frc.branches)} branches, {frc.n_points} points, "
        f"{len(frc.bifurcations)} bifurcations in {frc.wall_time:.1f} s -> {args.out}")
    if not args.quiet:
        from .scenes.bifurcation_list import list_bifurcations
        from .scenes.numbers import error_bound, with_error

        rows = list_bifurcations(frc)
        if rows:
            print(f"{'f [Hz]':>14s}  {'error [Hz]':>10s}  {'kind':24s} order branch  "
                  f"|x|max [mm]  (sorted; reports of one point merged)")
        for r in rows:
            print(f"{with_error(r.frequency, r.frequency_error):>14s}  "
                  f"{error_bound(r.frequency_error):>10s}  {r.kind:24s} {r.order:5d} "
                  f"{r.branch:6d}  {r.xmax * 1e3:11.4f}" + (f"  ({r.note})" if r.note else ""))
    if args.plot:
        from .plots.files import files_backend, save_figure
        from .plots.frequency_response import plot_frequency_response

        files_backend()
        save_figure(plot_frequency_response(frc), args.plot)
    return 0


#: the [periodic] keys that continue_parameter takes as well
_CONTINUE_KNOBS = ("segments", "dt_scale", "method", "steps_per_contact", "rtol", "atol", "ds",
                   "ds_max", "max_angle", "max_points", "tol", "bif_tol", "accuracy")


def _continue(args):
    import continuation

    log = _log(args)
    _check_knobs(args, "periodic")
    model = _model(args)
    lo, hi = args.lo, args.hi
    if not lo < hi:
        raise ValueError(f"range: must satisfy LO < HI, got {lo:g} {hi:g}")
    log(f"nlbeam continue: the order-{args.order} orbit at {args.frequency:g} Hz, amplitude "
        f"{args.amplitude:g}, continued in {args.parameter} over [{lo:g}, {hi:g}]")
    kw = {k: getattr(args, k) for k in _CONTINUE_KNOBS}
    integ = {k: kw.pop(k) for k in ("dt_scale", "method", "steps_per_contact", "rtol", "atol")}
    sol = continuation.periodic_solution(model, args.amplitude, args.frequency, args.order,
                                         segments=kw["segments"], error=False, **integ)
    frc = continuation.continue_parameter(sol, args.parameter, (lo, hi), model=model,
                                          **kw, **integ)
    frc.save(args.out)
    log(f"nlbeam continue: {frc.n_points} points, {len(frc.bifurcations)} bifurcations in "
        f"{frc.wall_time:.1f} s -> {args.out}")
    if not args.quiet:
        for b in frc.bifurcations:
            err = b.error if b.error is not None else float("nan")
            print(f"{b.kind:16s} order {b.order}  {args.parameter} = {b.value:.9g} +- "
                  f"{err:.1e}  |x|max = {b.xmax:.6g}")
    if args.plot:
        from .plots.files import files_backend, save_figure
        from .plots.frequency_response import plot_frequency_response

        files_backend()
        save_figure(plot_frequency_response(frc), args.plot)
    return 0


def _refine(args):
    import continuation

    log = _log(args)
    frc = continuation.load(args.diagram)
    model = _model(args)
    want = {k: str(v) for k, v in model.parameters().items()}
    have = {k: str(v) for k, v in frc.model_parameters.items()}
    if want != have:
        diff = sorted(k for k in set(want) | set(have) if want.get(k) != have.get(k))
        raise ValueError(f"{args.diagram}: computed for another model (differs in "
                         f"{', '.join(diff)}); give the model options of its nlbeam frc")
    log(f"nlbeam refine: {args.diagram}: refining {' and '.join(args.kinds)} "
        f"(target {args.target_digits:g} digits; this can take minutes)")
    out = continuation.refine_bifurcations(
        frc, model, kinds=tuple(args.kinds), orders=args.orders, segments=args.segments,
        target_digits=args.target_digits)
    frc.save(args.out)
    if not args.quiet:
        for b, r in out:
            if isinstance(r, Exception):
                print(f"{b.kind:16s} order {b.order}  f = {b.frequency:.9g} Hz  not refined: "
                      f"{str(r).strip().splitlines()[0]}")
            else:
                print(f"{b.kind:16s} order {b.order}  f = {r.value:.10g} +- {r.tolerance:.1e} Hz"
                      f"  ({r.digits:.1f} digits, {len(r.values)} levels)")
    log(f"nlbeam refine: {sum(not isinstance(r, Exception) for _, r in out)} of {len(out)} "
        f"refined -> {args.out}")
    return 0


def _noise(band, lowpass, amplitudes, level, seed):
    """The command line's excitation for one seed (module level: sent to workers)."""
    import stochastic

    return stochastic.BandLimitedNoise(band=band, seed=seed, lowpass=lowpass,
                                       amplitudes=amplitudes, **level)


def _member_path(out, seed):
    """OUT with '-seed<N>' before its extension: the file of one member of --seeds."""
    stem, ext = os.path.splitext(out)
    return f"{stem}-seed{seed}{ext or '.h5'}"


def _ensemble(args, model, log, level, sim_kw):
    """simulate --seeds: one record per seed (in parallel), each saved beside OUT, and the
    moments over the members with their standard errors."""
    import functools

    import stochastic

    if any(s < 0 for s in args.seeds) or len(set(args.seeds)) != len(args.seeds):
        raise ValueError(f"--seeds: must be distinct integers >= 0, got {args.seeds}")
    if args.plot:
        raise ValueError("--plot: not available with --seeds (plot a member file with "
                         "nlbeam compare, or run one seed)")
    make = functools.partial(_noise, tuple(args.band), args.lowpass, args.amplitudes, level)
    t = time.perf_counter()
    ens = stochastic.ensemble(model, make, args.seeds, args.duration, workers=args.workers,
                              scheduler=args.scheduler, **sim_kw)
    for seed, res in zip(args.seeds, ens.members):
        res.save(_member_path(args.out, seed))
    log(f"nlbeam simulate: {len(ens.members)} seeds in {time.perf_counter() - t:.1f} s -> "
        f"{_member_path(args.out, '<N>')}")
    if not args.quiet and len(ens.members) > 1:
        from .plots.units import channel_unit, excitation_kind

        kind = excitation_kind(ens.members[0].model_parameters)
        for ch in ens.members[0].channels:
            mo = ens.moments(ch)
            u = channel_unit(ch, kind)[0]
            print(f"{ch:6s} over {mo['n_members']} seeds: mean {mo['mean']:+.4e} +- "
                  f"{mo['se_mean']:.1e} {u}  std {mo['std']:.4e} +- {mo['se_std']:.1e} {u}  "
                  f"skewness {mo['skewness']:+.3f} +- {mo['se_skewness']:.3f}  kurtosis "
                  f"{mo['kurtosis']:.3f} +- {mo['se_kurtosis']:.3f}")
    return 0


def _simulate(args):
    _check_out(args, "out", "plot")
    import stochastic

    _check_workers(args)
    log = _log(args)
    _check_knobs(args, "stochastic")
    model = _model(args)
    level = {"rms": args.rms} if args.psd_level is None else {"psd_level": args.psd_level}
    if args.seeds is not None:
        keep = None if args.history is None else tuple(args.history)
        return _ensemble(args, model, log, level, dict(
            transient=args.transient, keep_history=keep, channels=tuple(args.channels),
            method=args.method, psd_resolution=args.psd_resolution, pdf_bins=args.pdf_bins,
            rtol=args.rtol, atol=args.atol, dt=args.dt,
            steps_per_contact=args.steps_per_contact))
    if args.workers is not None or args.scheduler is not None:
        raise ValueError("--workers/--scheduler: one record runs in one process; give --seeds "
                         "for several records in parallel")
    noise = stochastic.BandLimitedNoise(band=tuple(args.band), seed=args.seed,
                                        lowpass=args.lowpass, amplitudes=args.amplitudes,
                                        **level)

    def progress(done, total):
        log.bar("nlbeam simulate: simulated", done, total, "s")

    keep = None if args.history is None else tuple(args.history)  # s after the transient
    res = stochastic.simulate(model, noise, args.duration, args.transient, keep_history=keep,
                              channels=tuple(args.channels), method=args.method,
                              psd_resolution=args.psd_resolution, pdf_bins=args.pdf_bins,
                              rtol=args.rtol, atol=args.atol, dt=args.dt,
                              steps_per_contact=args.steps_per_contact,
                              progress=None if args.quiet else progress)
    res.save(args.out)
    log(f"nlbeam simulate: {res.n_impacts} impacts in {res.wall_time:.1f} s -> {args.out}")
    if not args.quiet:
        from .plots.units import channel_unit, excitation_kind

        kind = excitation_kind(res.model_parameters)
        for ch in res.channels:
            mo = res.moments(ch)
            u = channel_unit(ch, kind)[0]
            print(f"{ch:6s} mean {mo['mean']:+.4e} {u}  std {mo['std']:.4e} {u}  "
                  f"skewness {mo['skewness']:+.3f}  kurtosis {mo['kurtosis']:.3f}")
    if args.plot:
        from .plots.files import files_backend, save_figure
        from .plots.stochastic import channel_psds

        files_backend()
        save_figure(channel_psds(res, f_max=args.f_max), args.plot)
    return 0


def _identify(args):
    _check_out(args, "out", "plot")
    from nlbeam.identify import identify_contact

    from .files.columns import read_columns

    names = (args.delta_column, args.rate_column, args.force_column)
    cols = read_columns(args.file, required=names)
    d, r, f = (cols[n] for n in names)
    fit = identify_contact(d, r, f, law=args.law, method=args.method)
    if not args.quiet:
        print(fit)
    if args.plot:
        from .plots.files import files_backend, save_figure
        from .plots.identify import plot_contact_fit

        files_backend()
        save_figure(plot_contact_fit(fit, d, r, f), args.plot)
    return 0


def _analyze(args):
    _check_out(args, "out", "plot")
    import stochastic

    from .files.columns import read_columns

    cols = read_columns(args.file, required=(args.time_column, *args.channels))
    res = stochastic.analyze(cols[args.time_column], {c: cols[c] for c in args.channels},
                             psd_resolution=args.psd_resolution, pdf_bins=args.pdf_bins,
                             resample=args.resample, band=args.band,
                             description={"source": os.path.basename(args.file)})
    res.save(args.out)
    _log(args)(f"nlbeam analyze: {res.n_samples} samples at {res.fs:.6g} Hz (resampled: "
               f"{res.excitation_description['resample']}) -> {args.out}")
    if not args.quiet:
        from .plots.units import channel_unit

        for ch in res.channels:
            mo = res.moments(ch)
            u = channel_unit(ch)[0]
            print(f"{ch:6s} mean {mo['mean']:+.4e} +- {mo['se_mean']:.1e} {u}  std "
                  f"{mo['std']:.4e} +- {mo['se_std']:.1e} {u}  skewness {mo['skewness']:+.3f} "
                  f"+- {mo['se_skewness']:.3f}  kurtosis {mo['kurtosis']:.3f} "
                  f"+- {mo['se_kurtosis']:.3f}")
    return 0


def _compare(args):
    _check_out(args, "out", "plot")
    import continuation
    import stochastic

    from .compare import map_peaks, welch_dof_of

    res = stochastic.load(args.stochastic)
    frc = continuation.load(args.diagram)
    d = res.excitation_description
    band = (float(d["band_lo"]), float(d["band_hi"])) if "band_lo" in d else None
    if args.f_max is not None and not args.f_max > 0:
        raise ValueError(f"--f-max: must be > 0 Hz, got {args.f_max:g}")
    f_range = None if args.f_max is None else (0.0, args.f_max)
    matches = map_peaks(res.psd(args.channel), frc, band, min_prominence=args.min_prominence,
                        f_range=f_range, dof=welch_dof_of(res, args.channel))
    if not args.quiet:
        print(f"{'peak Hz':>9s} {'prom dec':>8s} {'kind':14s} {'order':>5s} "
              f"{'branch f Hz':>11s} {'stable':>6s} {'dist Hz':>7s}  note")
        for m in matches:
            note = m.note + (f" of {m.explained_by:.4g} Hz" if m.note == "multiple" else "")
            print(f"{m.frequency:9.3f} {m.prominence:8.2f} {m.kind:14s} {m.order:5d} "
                  f"{m.branch_frequency:11.3f} {str(m.stable):>6s} {m.distance:7.3f}  {note}")
    if args.plot:
        from .plots.compare import plot_comparison
        from .plots.files import files_backend, save_figure

        files_backend()
        fig = plot_comparison(res.psd(args.channel), frc, matches, excitation=band,
                              label=args.channel, f_max=args.f_max)
        save_figure(fig, args.plot)
    return 0


def _run(args):
    from .scenes import format_plan, load_scene, plan, run_scene

    _check_workers(args)
    scene = load_scene(args.scene)
    if args.set:
        from .scenes.schema import with_settings

        scene = with_settings(scene, [_setting(item) for item in args.set])
    out = args.out or "."
    if args.dry_run:
        print(format_plan(scene, plan(scene, out), out))
        return 0
    rep = run_scene(scene, out, workers=args.workers, scheduler=args.scheduler,
                    quiet=args.quiet)
    _log(args)(f"nlbeam run: {rep.computed} computed, {rep.reused} reused, "
               f"{len(rep.files)} files in {rep.wall_time:.1f} s")
    return 0


def _setting(item):
    """(name, value) of a --set NAME=VALUE of nlbeam run; VALUE read as a TOML value
    (1e-3, [0.0, 100.0], "rk4"), else as a string."""
    import tomllib

    name, sep, text = item.partition("=")
    if not sep or not name.strip():
        raise ValueError(f"--set: must be NAME=VALUE (e.g. elements[1].gap=1e-3 or "
                         f"band=[0.0, 100.0]), got {item!r}")
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        value = text
    return name.strip(), value


def bundled_scenes():
    """The scene files shipped in the repository's figures/ folder (sorted)."""
    here = os.path.abspath(__file__)  # <checkout>/nlbeam/app/cli.py
    folder = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(here))), "figures")
    if not os.path.isdir(folder):
        raise RuntimeError(f"figures: no bundled scenes at {folder} (run from a source checkout)")
    return folder, sorted(os.path.join(folder, f) for f in os.listdir(folder)
                          if f.endswith(".toml"))


def _figures(args):
    import time

    from .scenes import format_plan, load_scene, plan
    from .scenes.batch import run_scenes

    _check_workers(args)
    folder, paths = bundled_scenes()
    if args.only:
        paths = [p for p in paths if os.path.splitext(os.path.basename(p))[0] in args.only]
        if not paths:
            raise ValueError(f"--only: no bundled scene named {args.only}")
    out = args.out or folder
    scenes = [load_scene(p) for p in paths]  # all validated before any work
    if args.dry_run:
        for sc in scenes:
            print(format_plan(sc, plan(sc, out), out))
        return 0
    t = time.perf_counter()
    run_scenes(scenes, out, workers=args.workers, scheduler=args.scheduler, quiet=args.quiet)
    _log(args)(f"nlbeam figures: {len(scenes)} scenes in {time.perf_counter() - t:.1f} s")
    return 0


def _shown(v):
    """A default as the command line spells it: lists as space-separated values."""
    if isinstance(v, (list, tuple)):
        return " ".join(_shown(x) for x in v)
    return f"{v:g}" if isinstance(v, float) else str(v)


def _parser():
    # the defaults shared with the scene files (nlbeam.app.defaults: the analyses' own, read
    # from their signatures, and the paper's study); importing them loads the analyses
    import continuation
    from nlbeam.vocabulary import CHANNELS, CONTACT_LAWS, METHODS

    from .defaults import (CHANNEL, DEMO_DURATION, DEMO_WORKERS, DERIVED, HELP,
                           MIN_PROMINENCE, MODEL, PERIODIC, SIMULATE_CHANNELS, STOCHASTIC,
                           signature_defaults)
    from .demo import demo_summary

    per, sto = PERIODIC, STOCHASTIC
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--quiet", action="store_true", default=argparse.SUPPRESS,
                        help="no progress and no results (for scripts); warnings and "
                        "errors still go to stderr, one line each")
    parser = argparse.ArgumentParser(
        prog="nlbeam", description="Periodic and stochastic dynamics of a beam with an elastic "
        f"stop (the paper model: m = {MODEL['m']:g} kg, k = {MODEL['k']:g} N/m, b = "
        f"{MODEL['b']:g} kg/s, K_hertz = {MODEL['K_hertz']:g} N/m^1.5, e = {MODEL['e']:g}, "
        f"{MODEL['contact']} contact). " + _UNITS,
        epilog="Exit status 0 on success, 2 on error.")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress and no results; warnings and errors still go to stderr")
    sub = parser.add_subparsers(dest="command", required=True)

    def parallel_opts(p, what, default):
        p.add_argument("--workers", type=int, default=None,
                       help=f"local processes for the {what} (default {default})")
        p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help=f"run the {what} on this Dask scheduler, e.g. tcp://host:8786 "
                       "(pip install 'nlbeam[distributed]')")

    p = sub.add_parser("demo", parents=[common], help="a short version of `nlbeam figures`: "
                       "every kind of figure and table on a small diagram and 10 s records "
                       f"({DEMO_DURATION} once the kernels are compiled)",
                       description="Write a small scene (OUT/demo.toml) and run it: "
                       f"{demo_summary()}; PSDs, PDF, time history, the comparison and the "
                       "tables. Cached like any scene: a second run takes seconds. " + _UNITS)
    p.add_argument("--out", default="nlbeam-demo",
                   help="output folder (scene, figures, tables, cache), default ./nlbeam-demo")
    p.add_argument("--dry-run", action="store_true",
                   help="print what would be computed or reused and written, do nothing")
    p.add_argument("--workers", type=int, default=None,
                   help=f"processes for the analyses (default {DEMO_WORKERS}: this process; "
                   "the demo's analyses are small and each worker loads the compiled kernels)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the analyses on this Dask scheduler, e.g. tcp://host:8786 "
                   "(pip install 'nlbeam[distributed]')")
    p.set_defaults(func=_demo)

    def model_opts(p):
        units = {"m": "kg", "k": "N/m", "b": "kg/s", "K_hertz": "N/m^1.5", "e": "-",
                 "gap": "m", "mu": "N s/m^2.5"}
        for name in _BEAM_OPTIONS:
            flag = "--" + name.replace("_", "-")
            if name == "contact":
                p.add_argument(flag, choices=CONTACT_LAWS, default=None,
                               help=f"contact law of the paper beam, default {MODEL['contact']}")
                continue
            shown = "none" if MODEL.get(name) is None else _shown(MODEL[name])
            p.add_argument(flag, dest=name, type=float, default=None,
                           help=f"paper beam: {name} ({units[name]}), default {shown}")
        p.add_argument("--model", default=None, metavar="SCENE",
                       help="take the model of this scene file's [model] (the paper beam, "
                       "ModalBeam, a System written out or a factory; docs/usage.md)")
        p.add_argument("--set", action="append", default=None, metavar="NAME=VALUE",
                       help="set a model parameter by name (repeatable): m, k, b, K_hertz, e, "
                       "gap, ... or elements[i].field of a System (e.g. elements[1].gap=1e-3)")

    def knob_opts(p, table, skip):
        """An option per key of a scene section (nlbeam.app.defaults: same names, defaults
        and help; dashes for underscores)."""
        for name, default in table.items():
            if name in skip:
                continue
            flag = "--" + name.replace("_", "-")
            shown = DERIVED[name] if default is None else _shown(default)
            kw = {"default": default, "help": f"{HELP[name]}, default {shown}"}
            if isinstance(default, bool):
                kw["action"] = argparse.BooleanOptionalAction
            elif isinstance(default, list):
                kw.update(nargs=2, type=float, metavar=("LO", "HI")) if len(default) == 2 \
                    and name != "orders" else kw.update(nargs="+", type=type(default[0]))
            elif name == "method":
                kw["choices"] = METHODS
            elif name == "amplitudes":
                kw["choices"] = ("random", "deterministic")
            elif name == "accuracy":
                kw["type"] = _accuracy
            elif isinstance(default, int):
                kw["type"] = int
            else:
                kw["type"] = float
            p.add_argument(flag, dest=name, **kw)

    p = sub.add_parser("frc", parents=[common], help="periodic frequency-response diagram "
                       "(|x|max vs excitation frequency, orders 1..n) to HDF5",
                       description="Continuation of periodic solutions under y = A cos(2 pi f t): "
                       "branches of period n/f, stability, folds and period doublings. " + _UNITS)
    knob_opts(p, per, ())
    p.add_argument("--stability", action=argparse.BooleanOptionalAction, default=True,
                   help="Floquet multipliers of every point (needed for period doublings and "
                   "solid/dashed branches); default on")
    model_opts(p)
    parallel_opts(p, "brute-force sweeps, branches and error estimates (the same diagram)",
                  "1: this process")
    p.add_argument("--out", default="frc.h5", help="HDF5 result file, default frc.h5")
    p.add_argument("--plot", default=None, help="also write the diagram (PNG/PDF/SVG)")
    p.set_defaults(func=_frc)

    p = sub.add_parser("continue", parents=[common], help="follow a periodic orbit in any "
                       "parameter (continuation.continue_parameter) to HDF5",
                       description="Solve the periodic orbit of the given order at one "
                       "frequency and amplitude, then follow it in PARAMETER over [lo, hi] both "
                       "ways: branch, stability, folds, period doublings, grazing points. "
                       "PARAMETER: frequency, amplitude, or a model parameter (m, k, b, "
                       "K_hertz, e, gap, ... or elements[i].field of a System; a name that "
                       "does not exist lists those that do). " + _UNITS)
    p.add_argument("parameter", help="the parameter to continue (see above)")
    p.add_argument("lo", type=float, help="lower end of its range (its SI unit)")
    p.add_argument("hi", type=float, help="upper end of its range")
    p.add_argument("--frequency", type=float, required=True,
                   help="excitation frequency (Hz) of the starting orbit")
    p.add_argument("--amplitude", type=float, default=per["amplitude"],
                   help=f"{HELP['amplitude']}, default {_shown(per['amplitude'])}")
    p.add_argument("--order", type=int, default=1,
                   help="order n of the starting orbit (period n/f), default 1")
    knob_opts(p, {k: per[k] for k in _CONTINUE_KNOBS}, ())
    model_opts(p)
    p.add_argument("--out", default="continuation.h5",
                   help="HDF5 result file, default continuation.h5")
    p.add_argument("--plot", default=None, help="also write the branch (PNG/PDF/SVG)")
    p.set_defaults(func=_continue)

    ref = signature_defaults(continuation.refine_bifurcations)
    p = sub.add_parser("refine", parents=[common], help="refine the folds and period "
                       "doublings of a diagram file to 7-9 digits (continuation."
                       "refine_bifurcations)",
                       description="Locate each fold / period doubling of a diagram of nlbeam "
                       "frc again by an extended system at successively halved steps, "
                       "extrapolate, and write the diagram with the refined values and their "
                       "errors. Give the model options the diagram was computed with. " + _UNITS)
    p.add_argument("diagram", help="HDF5 file of nlbeam frc")
    p.add_argument("--kinds", nargs="+", choices=("fold", "period-doubling"),
                   default=list(ref["kinds"]),
                   help=f"bifurcations to refine, default {_shown(list(ref['kinds']))}")
    p.add_argument("--orders", type=int, nargs="+", default=ref["orders"],
                   help="orders to refine, default all")
    p.add_argument("--target-digits", type=float, default=ref["target_digits"],
                   help=f"significant digits aimed at, default {_shown(ref['target_digits'])}")
    p.add_argument("--segments", type=int, default=ref["segments"],
                   help=f"shooting segments per period, default {ref['segments']}")
    model_opts(p)
    p.add_argument("--out", default="refined.h5",
                   help="HDF5 file of the refined diagram, default refined.h5")
    p.set_defaults(func=_refine)

    p = sub.add_parser("simulate", parents=[common], help="stochastic response to band-limited "
                       "Gaussian base excitation (PSD, PDF, moments) to HDF5",
                       description="Long-record simulation under band-limited Gaussian base "
                       "excitation with a flat (optionally low-passed) PSD. " + _UNITS)
    knob_opts(p, sto, ())
    p.add_argument("--history", type=float, nargs=2, default=None, metavar=("T0", "T1"),
                   help="keep the time history of the channels in this window (s after the "
                   "transient) in the result file, default none")
    p.add_argument("--psd-level", type=float, default=None,
                   help=f"{HELP['psd_level']}, default none (--rms sets the level)")
    p.add_argument("--channels", nargs="+", default=list(SIMULATE_CHANNELS),
                   help=f"any of {', '.join(CHANNELS)} (delta: penetration x - y, m; force: N); "
                   f"default {_shown(SIMULATE_CHANNELS)}")
    model_opts(p)
    p.add_argument("--seeds", type=int, nargs="+", default=None,
                   help="several records, one per seed (distinct integers >= 0; replaces "
                   "--seed), each written to OUT with -seed<N> before the extension; prints "
                   "the moments over them with standard errors")
    parallel_opts(p, "records of --seeds", "the CPU count, at most one per seed")
    p.add_argument("--out", default="stochastic.h5", help="HDF5 result file, default stochastic.h5")
    p.add_argument("--plot", default=None, help="also write the PSDs (PNG/PDF/SVG)")
    p.add_argument("--f-max", type=float, default=None,
                   help="upper frequency (Hz) of the --plot figure, default twice the band's "
                   "upper edge (at most the Nyquist frequency)")
    p.set_defaults(func=_simulate)

    p = sub.add_parser("compare", parents=[common], help="trace the peaks of a stochastic PSD "
                       "to the periodic diagram (harmonic, 1/n subharmonic, superharmonic)",
                       description="Read the files of `nlbeam simulate` and `nlbeam frc`, find the "
                       "PSD peaks and print which resonance explains each. " + _UNITS)
    p.add_argument("stochastic", help="HDF5 file of nlbeam simulate")
    p.add_argument("diagram", help="HDF5 file of nlbeam frc")
    p.add_argument("--channel", default=CHANNEL, help=f"PSD channel, default {CHANNEL}")
    p.add_argument("--min-prominence", type=float, default=MIN_PROMINENCE,
                   help="least peak height over the running-median background (decades), "
                   f"default {_shown(MIN_PROMINENCE)}")
    p.add_argument("--f-max", type=float, default=None,
                   help="upper frequency (Hz) of the peaks considered and of the plot, default all")
    p.add_argument("--plot", default=None, help="write the comparison figure (PNG/PDF/SVG)")
    p.set_defaults(func=_compare)

    p = sub.add_parser("analyze", parents=[common], help="statistics (PSD, PDF, moments) of a "
                       "measured record, as nlbeam simulate writes them",
                       description="Read a time column and channel columns from a CSV file with "
                       "a header line (or an HDF5 file with one dataset per column) and write "
                       "the statistics file of nlbeam simulate (Welch PSD, histogram PDF, "
                       "moments with standard errors), which nlbeam compare and the figures "
                       "accept. The column names are the channel names (x, v, y, yd, delta, "
                       "force, optionally indexed like x[1]). A non-uniform record is resampled "
                       "onto its median step. See stochastic.analyze. " + _UNITS)
    p.add_argument("file", help="CSV (header line with the column names) or HDF5 file")
    p.add_argument("--channels", nargs="+", required=True,
                   help=f"columns to analyse, named as channels: any of {', '.join(CHANNELS)}")
    p.add_argument("--time-column", default="t", help="time column (s), default t")
    p.add_argument("--psd-resolution", type=float, default=None,
                   help="Welch bin (Hz), default max(0.05, 16 / duration)")
    p.add_argument("--pdf-bins", type=int, default=200, help="histogram bins, default 200")
    p.add_argument("--resample", default="linear", choices=("linear", "cubic"),
                   help="interpolation of a non-uniform record onto its median step, "
                   "default linear")
    p.add_argument("--band", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="excitation band (Hz), recorded for nlbeam compare; default none")
    p.add_argument("--out", default="stats.h5", help="HDF5 statistics file, default stats.h5")
    p.set_defaults(func=_analyze)

    p = sub.add_parser("identify", parents=[common], help="estimate the contact law's "
                       "parameters (K_hertz, e or mu) from measured collisions",
                       description="Read indentation delta (m, > 0 in contact), its rate (m/s) "
                       "and the contact force (N) from a CSV file with a header line (or an "
                       "HDF5 file with one dataset per column), split the record into "
                       "collisions, and fit the contact law: by least squares over every "
                       "sample in contact (standard errors from the sandwich covariance) or "
                       "the paper's recipe (K at maximum indentation, e from the hysteresis "
                       "loop energy, eqs. 2, 5, 6). See nlbeam.identify. " + _UNITS)
    p.add_argument("file", help="CSV (header line with the column names) or HDF5 file")
    p.add_argument("--law", default="lankarani-nikravesh",
                   choices=("hertz", "lankarani-nikravesh", "hunt-crossley"),
                   help="contact law to fit, default lankarani-nikravesh")
    p.add_argument("--method", default="least-squares", choices=("least-squares", "paper"),
                   help="estimator, default least-squares")
    p.add_argument("--delta-column", default="delta", help="indentation column, default delta")
    p.add_argument("--rate-column", default="rate", help="indentation-rate column, default rate")
    p.add_argument("--force-column", default="force", help="contact-force column, default force")
    p.add_argument("--plot", default=None,
                   help="write force against indentation, measured and fitted (PNG/PDF/SVG)")
    p.set_defaults(func=_identify)

    def run_opts(p):
        p.add_argument("--dry-run", action="store_true",
                       help="print what would be computed or reused and written, do nothing")
        p.add_argument("--workers", type=int, default=None,
                       help="processes for sweep points (default: the CPU count, at most the "
                       "number of analyses)")
        p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run sweep points on this Dask scheduler, e.g. tcp://host:8786 "
                       "(pip install 'nlbeam[distributed]')")

    p = sub.add_parser("run", parents=[common], help="run a scene file (TOML): compute what its "
                       "figures and tables need, reuse cached results",
                       description="Run a scene (see docs/usage.md). Results are cached in "
                       "OUT/.nlbeam-cache by a hash of their inputs. " + _UNITS)
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--out", default=None, help="output folder (figures, tables, cache), default .")
    p.add_argument("--set", action="append", default=None, metavar="NAME=VALUE",
                   help="set a parameter of the scene by the sweeps' names (repeatable): "
                   "amplitude, rms, band, band[1], duration, seed, e, gap, elements[1].gap, "
                   "a factory's argument, ...; VALUE as in TOML (1e-3, [0.0, 100.0])")
    run_opts(p)
    p.set_defaults(func=_run)

    p = sub.add_parser("figures", parents=[common], help="run the bundled scenes in figures/ "
                       "(the paper's figures; minutes on first run, seconds when cached)",
                       description="Run every scene in the repository's figures/ folder. "
                       + _UNITS)
    p.add_argument("--out", default=None, help="output folder, default the figures/ folder")
    p.add_argument("--only", nargs="+", default=None, help="scene names (file stems) to run")
    run_opts(p)
    p.set_defaults(func=_figures)
    return parser


def main(argv=None):
    parser = _parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "quiet"):
        args.quiet = False
    def show(message, category, filename, lineno, file=None, line=None):
        # a warning (accuracy, a branch that ended early, a record that gained energy) is one
        # line on stderr, --quiet or not: it says what to change (a bar's line ended first)
        from .progress import end_bar_line

        end_bar_line()
        print(f"nlbeam {args.command}: warning: {str(message).strip()}", file=sys.stderr,
              flush=True)

    try:
        with warnings.catch_warnings():
            warnings.showwarning = show
            return args.func(args)
    except KeyboardInterrupt:
        print(f"nlbeam {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # one line for people and scripts; --debug-free by design
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"nlbeam {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
