"""Command line: ``nlbeam demo | frc | simulate | compare | analyze | identify | run | figures``.

Units everywhere: SI (m, s, kg, N), frequencies in Hz. Progress goes to stderr; ``--quiet``
silences it. A warning is one line on stderr (``nlbeam CMD: warning: ...``), --quiet or not. On
failure: a one-line cause on stderr and exit status 2 (130 if interrupted).
"""
from __future__ import annotations

import argparse
import os
import sys
import warnings

_UNITS = ("Units: displacements and amplitudes in m (1e-4 = 0.1 mm), frequencies in Hz, "
          "times in s, K_hertz in N/m^1.5.")


def _log(args):
    """Progress lines on stderr (a bar for what advances, on a terminal); none with --quiet."""
    from .progress import Progress

    return Progress(quiet=args.quiet)


def _model(args):
    import nlbeam

    kw = {}
    if getattr(args, "e", None) is not None:
        kw["e"] = args.e
    if getattr(args, "K_hertz", None) is not None:
        kw["K_hertz"] = args.K_hertz
    return nlbeam.BeamImpact.paper(**kw)


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


def _frc(args):
    import continuation

    log = _log(args)
    model = _model(args)
    log(f"nlbeam frc: A = {args.amplitude:g} m, {args.f_range[0]:g}-{args.f_range[1]:g} Hz, "
        f"orders {args.orders}, {args.n_grid} grid frequencies (this can take minutes)")
    frc = continuation.frequency_response(model, args.amplitude, tuple(args.f_range),
                                          orders=tuple(args.orders), n_grid=args.n_grid,
                                          accuracy=_accuracy(args.accuracy),
                                          progress=lambda msg: log(f"nlbeam frc:   {msg}"))
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


def _simulate(args):
    import stochastic

    log = _log(args)
    model = _model(args)
    noise = stochastic.BandLimitedNoise(band=tuple(args.band), rms=args.rms, seed=args.seed,
                                        lowpass=args.lowpass)
    def progress(done, total):
        log.bar("nlbeam simulate: simulated", done, total, "s")

    res = stochastic.simulate(model, noise, args.duration, args.transient,
                              channels=tuple(args.channels), method=args.method,
                              psd_resolution=args.psd_resolution,
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
    import continuation
    import stochastic

    from .compare import map_peaks

    res = stochastic.load(args.stochastic)
    frc = continuation.load(args.diagram)
    d = res.excitation_description
    band = (float(d["band_lo"]), float(d["band_hi"])) if "band_lo" in d else None
    if args.f_max is not None and not args.f_max > 0:
        raise ValueError(f"--f-max: must be > 0 Hz, got {args.f_max:g}")
    f_range = None if args.f_max is None else (0.0, args.f_max)
    matches = map_peaks(res.psd(args.channel), frc, band, min_prominence=args.min_prominence,
                        f_range=f_range)
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
    out = args.out or "."
    if args.dry_run:
        print(format_plan(scene, plan(scene, out), out))
        return 0
    rep = run_scene(scene, out, workers=args.workers, scheduler=args.scheduler,
                    quiet=args.quiet)
    _log(args)(f"nlbeam run: {rep.computed} computed, {rep.reused} reused, "
               f"{len(rep.files)} files in {rep.wall_time:.1f} s")
    return 0


def bundled_scenes():
    """The scene files shipped in the repository's figures/ folder (sorted)."""
    here = os.path.abspath(__file__)  # <checkout>/nlbeam/app/cli.py
    folder = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(here))), "figures")
    if not os.path.isdir(folder):
        raise RuntimeError(f"figures: no bundled scenes at {folder} (run from a source checkout)")
    return folder, sorted(os.path.join(folder, f) for f in os.listdir(folder)
                          if f.endswith(".toml"))


def _figures(args):
    from .scenes import format_plan, load_scene, plan, run_scene

    _check_workers(args)
    folder, paths = bundled_scenes()
    if args.only:
        paths = [p for p in paths if os.path.splitext(os.path.basename(p))[0] in args.only]
        if not paths:
            raise ValueError(f"--only: no bundled scene named {args.only}")
    out = args.out or folder
    scenes = [load_scene(p) for p in paths]  # all validated before any work
    for sc in scenes:
        if args.dry_run:
            print(format_plan(sc, plan(sc, out), out))
        else:
            run_scene(sc, out, workers=args.workers, scheduler=args.scheduler, quiet=args.quiet)
    return 0


def _shown(v):
    """A default as the command line spells it: lists as space-separated values."""
    if isinstance(v, (list, tuple)):
        return " ".join(_shown(x) for x in v)
    return f"{v:g}" if isinstance(v, float) else str(v)


def _parser():
    # the defaults shared with the scene files (nlbeam.app.defaults: the analyses' own, read
    # from their signatures, and the paper's study); importing them loads the analyses
    from nlbeam.vocabulary import CHANNELS, METHODS

    from .defaults import (CHANNEL, DEMO_DURATION, DEMO_WORKERS, MIN_PROMINENCE, MODEL,
                           PERIODIC, SIMULATE_CHANNELS, STOCHASTIC)
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
        p.add_argument("--e", type=float, default=None,
                       help=f"coefficient of restitution (-), default {MODEL['e']:g}")
        p.add_argument("--K-hertz", dest="K_hertz", type=float, default=None,
                       help=f"Hertz contact stiffness (N/m^1.5), default {MODEL['K_hertz']:g}")

    p = sub.add_parser("frc", parents=[common], help="periodic frequency-response diagram "
                       "(|x|max vs excitation frequency, orders 1..n) to HDF5",
                       description="Continuation of periodic solutions under y = A cos(2 pi f t): "
                       "branches of period n/f, stability, folds and period doublings. " + _UNITS)
    p.add_argument("--amplitude", type=float, default=per["amplitude"],
                   help=f"base amplitude A (m), default {_shown(per['amplitude'])}")
    p.add_argument("--f-range", type=float, nargs=2, default=list(per["f_range"]),
                   metavar=("LO", "HI"),
                   help=f"excitation frequency range (Hz), default {_shown(per['f_range'])}")
    p.add_argument("--orders", type=int, nargs="+", default=list(per["orders"]),
                   help=f"orders n (period n/f), default {_shown(per['orders'])}")
    p.add_argument("--n-grid", type=int, default=per["n_grid"],
                   help=f"brute-force start frequencies, default {per['n_grid']}")
    p.add_argument("--accuracy", default="default",
                   help="significant digits of the fold / period-doubling frequencies: 'default' "
                   "(6), 'high' (8), a number, or 'off' (no error estimates)")
    model_opts(p)
    p.add_argument("--out", default="frc.h5", help="HDF5 result file, default frc.h5")
    p.add_argument("--plot", default=None, help="also write the diagram (PNG/PDF/SVG)")
    p.set_defaults(func=_frc)

    p = sub.add_parser("simulate", parents=[common], help="stochastic response to band-limited "
                       "Gaussian base excitation (PSD, PDF, moments) to HDF5",
                       description="Long-record simulation under band-limited Gaussian base "
                       "excitation with a flat (optionally low-passed) PSD. " + _UNITS)
    p.add_argument("--band", type=float, nargs=2, default=list(sto["band"]),
                   metavar=("LO", "HI"),
                   help=f"excitation band (Hz), default {_shown(sto['band'])}")
    p.add_argument("--rms", type=float, default=sto["rms"],
                   help=f"excitation rms (m), default {_shown(sto['rms'])}")
    p.add_argument("--lowpass", type=float, default=sto["lowpass"],
                   help="first-order low-pass corner (Hz) shaping the band (actuator), default "
                   + ("none" if sto["lowpass"] is None else _shown(sto["lowpass"])))
    p.add_argument("--seed", type=int, default=sto["seed"],
                   help=f"random seed (integer >= 0), default {sto['seed']}")
    p.add_argument("--duration", type=float, default=sto["duration"],
                   help=f"record kept (s), default {_shown(sto['duration'])}")
    p.add_argument("--transient", type=float, default=sto["transient"],
                   help="discarded start (s), default " + (
                       "10 decay times of the slowest mode (stochastic.simulate)"
                       if sto["transient"] is None else _shown(sto["transient"])))
    p.add_argument("--psd-resolution", type=float, default=sto["psd_resolution"],
                   help="Welch bin (Hz), default " + (
                       "max(0.05, 16 / duration) (stochastic.simulate)"
                       if sto["psd_resolution"] is None else _shown(sto["psd_resolution"])))
    p.add_argument("--method", choices=METHODS, default=sto["method"],
                   help=f"integrator, default {sto['method']}")
    p.add_argument("--channels", nargs="+", default=list(SIMULATE_CHANNELS),
                   help=f"any of {', '.join(CHANNELS)} (delta: penetration x - y, m; force: N); "
                   f"default {_shown(SIMULATE_CHANNELS)}")
    model_opts(p)
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
