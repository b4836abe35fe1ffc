"""Several scenes as one job (``nlbeam figures``): the analyses all of them miss, computed on
two cores while the kernels compile, then each scene's figures and tables (``run_scenes``).

One scene after the other leaves a core idle most of the time: the plain kernel compiles
here in about half the time the variational one takes in the second process
(``warmup.KernelWarmup``), a diagram's branch pool does not keep two cores busy, and each
scene's records and drawing wait for its diagram. Here, on two or more cores:

1. a second process compiles the variational kernel; this one compiles the plain kernel and
   the continuation's linear algebra (``warmup.warm_linalg``), then computes the records
   (they need the plain kernel only) while the second process still compiles, and draws
   each scene whose analyses are then all done;
2. with the variational kernel loaded, this process computes the costliest analysis left
   (the diagram of the model with the most degrees of freedom) on its branch pool, and one
   process forked now (it inherits the kernels) computes the others meanwhile, the cheapest
   first; whichever is free first takes the next one;
3. each scene is drawn (``run_scene``, its analyses all cached).

An analysis gives the same result wherever it runs (a diagram traced on a pool is exactly
the serial one, continuation.parallel; a record depends on its seed only), so the figures,
tables and cache entries are those of one scene after the other. Each result is checked as
it arrives (an empty diagram raises EmptyDiagramError naming its scene; what is done by
then stays cached) and cached at once. One core, ``workers=1`` or a Dask scheduler: one
scene after the other (``run_scene``).
"""
from __future__ import annotations

import os
import time
import warnings

from ..progress import Progress
from ..warmup import KernelWarmup
from .empty import check_not_empty
from .plan import plan
from .run import AnalysisWarning, check_outputs, compute_recorded, run_scene, store_result
from .schema import build_model

__all__ = ["run_scenes"]


def _cost(job):
    """Sort key, costliest first: diagrams and charts before records, more degrees of
    freedom first."""
    return (job.kind in ("periodic", "chart"), build_model(job.inputs["model"]).n_dof)


class _Batch:
    """The distinct analyses the scenes miss, who needs them, and what is done."""

    def __init__(self, scenes, out_dir, workers, quiet, log):
        self.scenes, self.out_dir, self.workers, self.quiet = scenes, out_dir, workers, quiet
        self.log = log
        self.show = log if isinstance(log, Progress) else Progress(write=log)
        self.todo = {}    # path -> (job, the first scene that needs it)
        self.needs = []   # per scene: the paths of its analyses to compute
        self.plans = []
        for sc in scenes:
            check_outputs(sc, out_dir)   # every scene's outputs writable before any work
            mine = []
            self.plans.append(plan(sc, out_dir))
            for j in self.plans[-1]:
                if not j.cached:
                    self.todo.setdefault(j.path, (j, sc))
                    mine.append(j.path)
            self.needs.append(set(mine))
        self.done = set()
        self.drawn = set()
        self.n = 0

    def label(self, job, scene):
        self.n += 1
        stem = os.path.splitext(os.path.basename(scene.path or "scene"))[0]
        return (f"[{self.n}/{len(self.todo)}] {stem}: {job.kind}"
                f"{' ' + job.variant if job.variant else ''}")

    def inputs_here(self, job, label):
        inputs = dict(job.inputs)
        if not self.quiet:
            if job.kind == "stochastic":
                inputs["_progress"] = (lambda done, total: self.show.bar(
                    f"nlbeam:   {label}: simulated", done, total, "s"))
            else:
                inputs["_progress"] = lambda msg: self.show(f"nlbeam:   {msg}")
        if job.kind == "periodic":   # its branches on the pool (None: every core)
            inputs["_parallel"] = (self.workers, None)
        return inputs

    def run_here(self, job, scene, label=None):
        label = label or self.label(job, scene)
        self.log(f"nlbeam: {label}: {job.description}")
        t = time.perf_counter()
        r, warned = compute_recorded(self.inputs_here(job, label))
        self.show.close()
        self.keep(job, scene, r, warned)
        self.log(f"nlbeam:   {label}: done in {time.perf_counter() - t:.1f} s")

    def keep(self, job, scene, result, warned):
        """Check and cache one result (EmptyDiagramError for an empty diagram)."""
        check_not_empty(scene, job, result, warned)
        store_result(job, result, self.log, warned)
        self.done.add(job.path)

    def draw_ready(self, computed):
        """Draw every scene whose analyses are all done (once)."""
        for k, sc in enumerate(self.scenes):
            if k not in self.drawn and self.needs[k] <= self.done:
                self.drawn.add(k)
                run_scene(sc, self.out_dir, workers=self.workers, quiet=self.quiet,
                          log=self.log, computed=computed)


def _beside(job):
    """The inputs of ``job`` for the forked process: no progress, the diagram serial."""
    inputs = dict(job.inputs)
    if job.kind == "periodic":
        inputs["_parallel"] = (1, None)
    return inputs


def _compute_beside(inputs):
    return compute_recorded(inputs, reissue=False)


def run_scenes(scenes, out_dir=".", *, workers=None, scheduler=None, quiet=False, log=None):
    """Run the scenes (validated ``Scene`` objects) into ``out_dir`` as one job (module
    docstring); returns the RunReport of each scene's drawing."""
    out_dir = os.fspath(out_dir)
    if log is None:
        log = Progress(quiet=quiet)
    cores = os.cpu_count() or 1
    if scheduler is not None or workers == 1 or cores < 2:
        return [run_scene(sc, out_dir, workers=workers, scheduler=scheduler, quiet=quiet,
                          log=log) for sc in scenes]
    b = _Batch(scenes, out_dir, workers, quiet, log)
    computed = set(b.todo)
    if b.todo:
        log(f"nlbeam: computing {len(b.todo)} analyses of {len(scenes)} scenes")
        _compute(b)
    reports = []
    for k, sc in enumerate(scenes):
        if k not in b.drawn:   # (nothing computed: the plan made above still holds)
            reports.append(run_scene(sc, out_dir, workers=workers, quiet=quiet, log=log,
                                     computed=computed,
                                     planned=None if computed else b.plans[k]))
    return reports


def _compute(b):
    jobs = sorted(b.todo.values(), key=lambda js: _cost(js[0]), reverse=True)
    warm = KernelWarmup([j.inputs for j, _ in jobs])
    try:
        warm.plain()
        if warm.pending():   # records here while the variational kernel compiles there
            for j, sc in [js for js in reversed(jobs) if js[0].kind == "stochastic"]:
                if not warm.pending():
                    break
                b.run_here(j, sc)
            jobs = [js for js in jobs if js[0].path not in b.done]
            if warm.pending():
                b.draw_ready(set(b.todo))
        warm.finish()
    finally:
        warm.stop()
    if not jobs:
        return
    if len(jobs) == 1:
        b.run_here(*jobs[0])
        return
    from concurrent.futures import ProcessPoolExecutor

    # forked now: the kernels compiled or loaded above are inherited
    with ProcessPoolExecutor(max_workers=1) as pool:
        beside = [(pool.submit(_compute_beside, _beside(j)), j, sc, b.label(j, sc))
                  for j, sc in reversed(jobs[1:])]   # the cheapest first
        for _, j, _, label in beside:
            b.log(f"nlbeam: {label}: {j.description} (in a second process)")
        try:
            b.run_here(*jobs[0])
            for fut, j, sc, label in reversed(beside):   # the costliest not started: here
                if fut.cancel():
                    b.run_here(j, sc, label)
            for fut, j, sc, label in beside:
                if fut.cancelled():
                    continue
                r, warned = fut.result()
                for text in warned:
                    warnings.warn(f"({label}) {text}", AnalysisWarning, stacklevel=3)
                b.keep(j, sc, r, warned)
                b.log(f"nlbeam:   {label}: done (in a second process)")
        except BaseException:
            for fut, _, _, _ in beside:
                fut.cancel()
            for proc in list((getattr(pool, "_processes", None) or {}).values()):
                proc.terminate()   # (an error here: not waiting for the analysis there)
            raise
