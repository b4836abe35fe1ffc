"""Running a scene: compute the analyses the plan marks missing (sweep points in parallel,
see nlbeam.app.sweeps.run_jobs), store each in the cache (HDF5, atomically), load the cached
ones, and write the figures and tables (``run_scene``).
"""
from __future__ import annotations

import functools
import json
import os
import time
import warnings
from dataclasses import dataclass, field

import continuation
import stochastic

from ..files import remove_stale_temporaries, write_text_atomic
from ..progress import Progress
from ..sweeps import run_jobs
from ..warmup import prepare_kernels
from .empty import SweepEmpties
from .outputs import write_outputs
from .plan import CACHE_DIR, entry_record, plan
from .schema import Scene, build_model, build_noise, load_scene

__all__ = ["RunReport", "run_scene", "check_outputs", "compute", "compute_recorded",
           "load_result", "store_result", "cached_warnings", "AnalysisWarning",
           "CachedResultWarning", "STALE_AGE"]

STALE_AGE = 3600.0  # s: older .tmp-* files in the output and cache folders are removed


def compute(job_inputs):
    """Run one analysis from its inputs (module level: runs in pool or Dask workers).
    Progress goes to ``job_inputs["_progress"]`` if given, or as (label, message) or (label,
    (done, total)) to the queue ``job_inputs["_queue"]`` (a worker's channel to the parent)."""
    queue = job_inputs.get("_queue")
    if queue is not None:
        label = job_inputs.get("_label", "")
        job_inputs = dict(job_inputs)
        if job_inputs["analysis"] in ("periodic", "chart"):  # lines of text
            job_inputs["_progress"] = lambda msg: queue.put((label, str(msg)))
        else:
            job_inputs["_progress"] = lambda done, total: queue.put((label, (done, total)))
    kind = job_inputs["analysis"]
    model = build_model(job_inputs["model"])
    if kind == "periodic":
        p = job_inputs["periodic"]
        kw = {k: v for k, v in p.items() if k not in ("amplitude", "f_range", "orders")}
        kw.setdefault("stability", True)
        if job_inputs.get("_progress") is not None:
            kw["progress"] = job_inputs["_progress"]
        if job_inputs.get("_parallel") is not None:  # (workers, scheduler): the same diagram
            kw["workers"], kw["scheduler"] = job_inputs["_parallel"]
        return continuation.frequency_response(
            model, p["amplitude"], tuple(p["f_range"]), orders=tuple(p["orders"]), **kw)
    if kind == "chart":
        c = job_inputs["chart"]
        return continuation.stability_chart(
            model, tuple(c["p_range"]), tuple(c["f_range"]), orders=tuple(c["orders"]),
            amplitude=c["amplitude"], label_grid=tuple(c["label_grid"]),
            max_points=c["max_points"], max_evaluations=c["max_evaluations"],
            progress=job_inputs.get("_progress"))
    s = job_inputs["stochastic"]
    hist = job_inputs["history"]
    keep = None if hist is None else tuple(hist)  # s after the transient, as in simulate
    return stochastic.simulate(model, build_noise(s), s["duration"], s["transient"],
                               outputs=tuple(job_inputs["outputs"]),
                               channels=tuple(job_inputs["channels"]), method=s["method"],
                               psd_resolution=s["psd_resolution"], keep_history=keep,
                               pdf_bins=s["pdf_bins"], progress=job_inputs.get("_progress"),
                               **{k: s[k] for k in ("rtol", "atol", "dt", "steps_per_contact")
                                  if k in s})


def compute_recorded(job_inputs, reissue=True):
    """(result of ``compute``, the distinct texts of the warnings it gave): the warnings are
    issued again here, once each (``reissue``; a pool's parent issues them itself), and stored
    with the cache entry so that a cached re-run repeats them."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = compute(job_inputs)
    seen = {}
    for w in caught:
        seen.setdefault(str(w.message).strip(), w)
    if reissue:
        for w in seen.values():
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return result, list(seen)


def cached_warnings(job):
    """The warnings the original computation of a cached ``job`` gave (from its record)."""
    try:
        with open(job.path[:-3] + ".json", encoding="utf-8") as fh:
            return [str(w) for w in json.loads(fh.read()).get("warnings", [])]
    except (OSError, ValueError, AttributeError):
        return []


def load_result(job):
    """The cached result of ``job`` (its HDF5 file)."""
    if job.kind == "periodic":
        return continuation.load(job.path)
    if job.kind == "chart":
        return continuation.load_curves(job.path)
    return stochastic.load(job.path)


def store_result(job, result, log=None, warned=()):
    """Write ``result`` to the cache file of ``job`` and, beside it (``.json``), its inputs,
    the SHA-256 of the file and the warnings ``warned`` of its computation; log a warning when
    the analysis reports failure."""
    if log is not None and getattr(result, "success", True) is False:
        log(f"nlbeam: warning: {job.kind}{' ' + job.variant if job.variant else ''}: "
            f"{getattr(result, 'message', 'failed')}")
    os.makedirs(os.path.dirname(job.path), exist_ok=True)
    result.save(job.path)  # atomic (temporary name, then os.replace)
    write_text_atomic(job.path[:-3] + ".json", entry_record(job.inputs, job.path, warned))


@dataclass
class RunReport:
    """What ``run_scene`` did: jobs (with cached flags as found; one per analysis and sweep
    value, so a shared analysis appears more than once), computed count (distinct analyses),
    files."""

    jobs: list
    computed: int
    files: list = field(default_factory=list)
    wall_time: float = 0.0

    @property
    def reused(self):
        """Distinct analyses taken from the cache."""
        return len({j.path for j in self.jobs if j.cached})


class AnalysisWarning(UserWarning):
    """A warning an analysis gave in a worker process, issued again in the parent."""


class CachedResultWarning(UserWarning):
    """A warning of the computation of a result now taken from the cache, repeated."""


def _reissued(outs, names):
    """Issue here the warnings the workers recorded (once each, naming the analysis)."""
    for (_, warned), name in zip(outs, names):
        for text in warned:
            warnings.warn(f"({name}) {text}", AnalysisWarning, stacklevel=3)
    return outs


def _run_parallel(todo, workers, scheduler, show, quiet, name_of):
    """[(result, warnings)] of the jobs ``todo`` on a process pool or Dask (run_jobs), the
    workers' progress (per branch, per simulated block) relayed to ``show`` through a
    manager queue (local pool only: a Dask worker reports per analysis)."""
    items = [dict(j.inputs) for j in todo]
    names = [f"[{k}/{len(todo)}] {name_of(j)}" for k, j in enumerate(todo, start=1)]

    def prog(done, total):
        show.bar("nlbeam: analyses done", done, total)

    func = functools.partial(compute_recorded, reissue=False)
    if scheduler is not None or quiet:
        return _reissued(run_jobs(func, items, workers=workers, scheduler=scheduler,
                                  progress=prog), names)
    import multiprocessing
    import threading

    lines = Progress(write=show)  # plain, throttled lines per analysis
    with multiprocessing.Manager() as manager:
        queue = manager.Queue()
        for item, name in zip(items, names):
            item["_queue"], item["_label"] = queue, name

        def relay():
            while True:
                msg = queue.get()
                if msg is None:
                    return
                label, what = msg
                if isinstance(what, tuple):
                    lines.bar(f"nlbeam:   {label}: simulated", what[0], what[1], "s")
                else:
                    show(f"nlbeam:   {label}: {what}")

        thread = threading.Thread(target=relay, daemon=True)
        thread.start()
        try:
            return _reissued(run_jobs(func, items, workers=workers, progress=prog), names)
        finally:
            queue.put(None)
            thread.join(timeout=5.0)


def check_outputs(scene, out_dir):
    """Before any analysis: the output folder and its cache folder can be written (created
    if missing), no figure or table file is a folder or a read-only file, and every figure
    title renders (matplotlib math text). Raises ValueError naming what is wrong."""
    from nlbeam._validate import output_file, writable_folder

    from ..plots.files import check_figure_text

    writable_folder("out", out_dir, create=True)
    cache = os.path.join(out_dir, CACHE_DIR)
    if os.path.exists(cache):
        writable_folder("out (cache folder)", cache)
    check_figure_text("title", scene.title)
    for d in list(scene.figures) + list(scene.tables):
        output_file(f"{'figure' if d in scene.figures else 'table'} {d['kind']} file",
                    os.path.join(out_dir, d["file"]))
        if "title" in d:
            check_figure_text(f"figure {d['kind']} title", d["title"])


def run_scene(path_or_scene, out_dir=".", *, dry_run=False, workers=None, scheduler=None,
              quiet=False, log=None, computed=(), planned=None):
    """Validate, plan, compute what is missing (sweep points in parallel, see
    nlbeam.app.sweeps.run_jobs), cache it, and write the figures and tables atomically.
    A diagram that came out empty (every solve failed) raises EmptyDiagramError naming the
    scene, uncached and undrawn (``empty.check_not_empty``); in a sweep, after the other
    values are computed and cached (``empty.SweepEmpties``). Returns a RunReport. ``log``:
    callable(str) for progress lines (default stderr); ``computed``: cache paths of analyses
    the caller computed (and cached) in this run (``batch.run_scenes``): their warnings, given
    then, are not repeated as those of cached results; ``planned``: this scene's plan as the
    caller just made it (``plan(scene, out_dir)``; None: planned here)."""
    t0 = time.perf_counter()
    scene = path_or_scene if isinstance(path_or_scene, Scene) else load_scene(path_or_scene)
    out_dir = os.fspath(out_dir)
    if log is None:
        log = Progress(quiet=quiet)  # lines; a bar for what advances, on a terminal
    jobs = plan(scene, out_dir) if planned is None else planned
    if dry_run:
        return RunReport(jobs=jobs, computed=0, wall_time=time.perf_counter() - t0)
    check_outputs(scene, out_dir)
    for folder in (out_dir, os.path.join(out_dir, CACHE_DIR)):  # left by killed runs
        for p in remove_stale_temporaries(folder, max_age=STALE_AGE):
            log(f"nlbeam: removed a stale temporary file {p}")
    for j in {j.path: j for j in jobs if j.problem}.values():
        log(f"nlbeam: warning: cache entry {j.path}: {j.problem}; recomputing it")
    todo = list({j.path: j for j in jobs if not j.cached}.values())  # equal keys: once
    sharing = {}
    for j in jobs:
        sharing[j.path] = sharing.get(j.path, 0) + 1

    def name_of(j):  # an analysis several variants share names no variant
        return j.kind + (f" {j.variant}" if j.variant and sharing[j.path] == 1 else "")

    for j in {j.path: j for j in jobs if j.cached and j.path not in computed}.values():
        name = name_of(j)
        for text in cached_warnings(j):
            warnings.warn(f"(cached {name}, as first computed) {text}", CachedResultWarning,
                          stacklevel=2)
    if todo:
        title = scene.title if scene.title.startswith("nlbeam") else f"nlbeam: {scene.title}"
        log(f"{title}: computing {len(todo)} of {len(jobs)} analyses")
    results = {}
    show = log if isinstance(log, Progress) else Progress(write=log)
    w = workers if workers is not None else (scene.sweep or {}).get("workers")
    parallel = scheduler is not None or (
        scene.sweep is not None and len(todo) > 1 and min(w or os.cpu_count() or 1,
                                                          len(todo)) > 1)
    empties = SweepEmpties(scene)   # a sweep goes on past an empty diagram
    if todo and scheduler is None:  # the kernels here (before a pool forks its workers)
        prepare_kernels([j.inputs for j in todo])
    if parallel:
        outs = _run_parallel(todo, w, scheduler, show, quiet, name_of)
        for j, (r, warned) in zip(todo, outs):
            if empties.check(j, r, warned):
                store_result(j, r, log, warned)
                results[j.path] = r
    else:
        for n, j in enumerate(todo, start=1):
            log(f"nlbeam: [{n}/{len(todo)}] {name_of(j)}: {j.description}")
            inputs = dict(j.inputs)
            if j.kind == "stochastic" and not quiet:
                inputs["_progress"] = (lambda done, total, n=n: show.bar(
                    f"nlbeam:   [{n}/{len(todo)}] simulated", done, total, "s"))
            elif j.kind in ("periodic", "chart") and not quiet:
                inputs["_progress"] = lambda msg: show(f"nlbeam:   {msg}")
            if j.kind == "periodic":  # its branches on the workers (not sweep points)
                inputs["_parallel"] = (workers, scheduler)
            t = time.perf_counter()
            r, warned = compute_recorded(inputs)
            show.close()
            if empties.check(j, r, warned):
                store_result(j, r, log, warned)
                results[j.path] = r
            log(f"nlbeam:   done in {time.perf_counter() - t:.1f} s")
    empties.raise_any()
    files = write_outputs(scene, jobs, results, out_dir, log, load_result)
    return RunReport(jobs=jobs, computed=len(todo), files=files,
                     wall_time=time.perf_counter() - t0)
