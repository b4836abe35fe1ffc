"""Running a scene: compute the analyses the plan marks missing (sweep points in parallel,
see nlbeam.app.sweeps.run_jobs), store each in the cache (HDF5, atomically), load the cached
ones, and write the figures and tables (``run_scene``).
"""
from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

import continuation
import stochastic

from ..files import remove_stale_temporaries, write_text_atomic
from ..sweeps import run_jobs
from .outputs import write_outputs
from .plan import CACHE_DIR, entry_record, plan
from .schema import Scene, build_model, build_noise, load_scene

__all__ = ["RunReport", "run_scene", "compute", "load_result", "store_result", "STALE_AGE"]

STALE_AGE = 3600.0  # s: older .tmp-* files in the output and cache folders are removed


def compute(job_inputs):
    """Run one analysis from its inputs (module level: runs in pool or Dask workers)."""
    kind = job_inputs["analysis"]
    model = build_model(job_inputs["model"])
    if kind == "periodic":
        p = job_inputs["periodic"]
        kw = {"stability": p.get("stability", True)}
        if job_inputs.get("_progress") is not None:
            kw["progress"] = job_inputs["_progress"]
        return continuation.frequency_response(
            model, p["amplitude"], tuple(p["f_range"]), orders=tuple(p["orders"]),
            n_grid=p["n_grid"], segments=p["segments"], dt_scale=p["dt_scale"], **kw)
    s = job_inputs["stochastic"]
    hist = job_inputs["history"]
    keep = None if hist is None else tuple(hist)  # s after the transient, as in simulate
    return stochastic.simulate(model, build_noise(s), s["duration"], s["transient"],
                               outputs=tuple(job_inputs["outputs"]),
                               channels=tuple(job_inputs["channels"]), method=s["method"],
                               psd_resolution=s["psd_resolution"], keep_history=keep,
                               pdf_bins=s["pdf_bins"], progress=job_inputs.get("_progress"))


def load_result(job):
    """The cached result of ``job`` (its HDF5 file)."""
    if job.kind == "periodic":
        return continuation.load(job.path)
    return stochastic.load(job.path)


def store_result(job, result, log=None):
    """Write ``result`` to the cache file of ``job`` and, beside it (``.json``), its inputs
    and the SHA-256 of the file; log a warning when the analysis reports failure."""
    if log is not None and getattr(result, "success", True) is False:
        log(f"nlbeam: warning: {job.kind}{' ' + job.variant if job.variant else ''}: "
            f"{getattr(result, 'message', 'failed')}")
    os.makedirs(os.path.dirname(job.path), exist_ok=True)
    result.save(job.path)  # atomic (temporary name, then os.replace)
    write_text_atomic(job.path[:-3] + ".json", entry_record(job.inputs, job.path))


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


def run_scene(path_or_scene, out_dir=".", *, dry_run=False, workers=None, scheduler=None,
              quiet=False, log=None):
    """Validate, plan, compute what is missing (sweep points in parallel, see
    nlbeam.app.sweeps.run_jobs), cache it, and write the figures and tables atomically.
    Returns a RunReport. ``log``: callable(str) for progress lines (default stderr)."""
    t0 = time.perf_counter()
    scene = path_or_scene if isinstance(path_or_scene, Scene) else load_scene(path_or_scene)
    out_dir = os.fspath(out_dir)
    if log is None:
        def log(msg):
            if not quiet:
                print(msg, file=sys.stderr, flush=True)
    jobs = plan(scene, out_dir)
    if dry_run:
        return RunReport(jobs=jobs, computed=0, wall_time=time.perf_counter() - t0)
    for folder in (out_dir, os.path.join(out_dir, CACHE_DIR)):  # left by killed runs
        for p in remove_stale_temporaries(folder, max_age=STALE_AGE):
            log(f"nlbeam: removed a stale temporary file {p}")
    for j in {j.path: j for j in jobs if j.problem}.values():
        log(f"nlbeam: warning: cache entry {j.path}: {j.problem}; recomputing it")
    todo = list({j.path: j for j in jobs if not j.cached}.values())  # equal keys: once
    if todo:
        log(f"nlbeam: {scene.title}: computing {len(todo)} of {len(jobs)} analyses")
    results = {}
    if todo:
        if scene.sweep is not None and len(todo) > 1 or scheduler is not None:
            w = workers if workers is not None else (scene.sweep or {}).get("workers")

            def prog(done, total):
                log(f"nlbeam: {done}/{total} analyses done")

            outs = run_jobs(compute, [j.inputs for j in todo], workers=w, scheduler=scheduler,
                            progress=prog)
            for j, r in zip(todo, outs):
                store_result(j, r, log)
                results[j.path] = r
        else:
            for n, j in enumerate(todo, start=1):
                log(f"nlbeam: [{n}/{len(todo)}] {j.kind}{' ' + j.variant if j.variant else ''}: "
                    f"{j.description}")
                inputs = dict(j.inputs)
                if j.kind == "stochastic" and not quiet:
                    last = [0.0]

                    def progress(done, total, last=last):
                        if done >= total or time.perf_counter() - last[0] > 5.0:
                            last[0] = time.perf_counter()
                            log(f"nlbeam:   simulated {done:.4g} / {total:.4g} s")
                    inputs["_progress"] = progress
                elif j.kind == "periodic" and not quiet:
                    inputs["_progress"] = lambda msg: log(f"nlbeam:   {msg}")
                t = time.perf_counter()
                r = compute(inputs)
                store_result(j, r, log)
                results[j.path] = r
                log(f"nlbeam:   done in {time.perf_counter() - t:.1f} s")
    for j in jobs:
        if j.path not in results:
            results[j.path] = load_result(j)
    files = write_outputs(scene, jobs, results, out_dir, log)
    return RunReport(jobs=jobs, computed=len(todo), files=files,
                     wall_time=time.perf_counter() - t0)
