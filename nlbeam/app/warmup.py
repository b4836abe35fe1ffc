"""The integration kernels of a run, compiled (or loaded from numba's disk cache) in this
process before the analyses start (and before a process pool forks its workers).

numba compiles a kernel in the process that first calls it; the workers of a pool forked
before that each compile it again, at once (twice the CPU on two cores, for the same code).
Forked after ``prepare_kernels``, they inherit the compiled kernels. Only the kernels the
analyses need: the plain one (records, brute-force integrations) always, the variational
one for a diagram with stability or a stability chart.

On a fresh machine with two or more cores, the variational kernel compiles in a second
process (``python -m nlbeam.app.warmup``, numba's cache in a folder of its own) while the
plain one compiles here; its cache entry is then copied into this process's numba cache
(``adopt_cached``) and loaded from there. Two processes never write one cache folder: the
two kernels share step functions whose cache index numba rewrites without a lock. Wall time
of the two first compiles: the longer of them instead of their sum
(``python benchmarks/kernel_compile.py --overlap``).
"""
from __future__ import annotations

import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import time
import warnings

__all__ = ["prepare_kernels", "needs_variational", "adopt_cached", "OVERLAP"]

#: compile the variational kernel in a second process beside the plain one here, where both
#: are missing from the cache and two cores are available (False: both here, one after the
#: other; tests and benchmarks)
OVERLAP = True


def needs_variational(inputs):
    """Whether the analysis of these job inputs integrates the variational equations (a
    diagram with stability, a stability chart)."""
    kind = inputs["analysis"]
    if kind == "chart":
        return True
    return kind == "periodic" and bool(inputs["periodic"].get("stability", True))


def prepare_kernels(todo):
    """Compile or load here the kernels the analyses ``todo`` (job inputs) need, once per
    kernel package (a custom force has its own); a missing variational kernel in a second
    process meanwhile where that saves time (module docstring). Returns the number of
    kernels made ready."""
    from nlbeam.integrate import compile_kernels

    from .scenes.schema import build_model

    needed = {}   # kernel package -> [model, its scene inputs, variational kernel needed]
    for inputs in todo:
        model = build_model(inputs["model"])
        entry = needed.setdefault(model.kernels().__name__, [model, inputs["model"], False])
        entry[2] = entry[2] or needs_variational(inputs)
    second = {}
    try:
        for name, (model, spec, var) in needed.items():
            kern = model.kernels()
            if var and OVERLAP and not second and _cores() >= 2 \
                    and not _cached(kern.integrate_plain) and not _cached(kern.integrate_var):
                second[name] = _SecondProcess(spec, kern.integrate_var)   # (one at most)
        for model, _, _ in needed.values():
            compile_kernels(model, False)
        for name, (model, _, var) in needed.items():
            if var:
                if name in second:
                    second[name].adopt()
                compile_kernels(model, True)   # loads what the second process compiled
    finally:
        for proc in second.values():
            proc.stop()
    return len(needed) + sum(var for _, _, var in needed.values())


def adopt_cached(dispatcher, folder):
    """Copy the disk-cache entries of the numba function ``dispatcher`` that another process
    compiled with NUMBA_CACHE_DIR pointing elsewhere (its cache folder for this function:
    ``folder``) into the cache folder this process uses, through numba's own index and data
    files (written atomically); entries of another source stamp are ignored. Returns the
    number of entries copied (0 if the dispatcher has no disk cache)."""
    from numba.core.caching import IndexDataCacheFile

    mine = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if mine is None:   # not cached on disk (an uncached custom-force copy)
        return 0
    base = mine._index_name[:-len(".nbi")]
    theirs = IndexDataCacheFile(os.fspath(folder), base, mine._source_stamp)
    n = 0
    for key, data_name in theirs._load_index().items():
        mine.save(key, theirs._load_data(data_name))
        n += 1
    return n


def _cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _cached(dispatcher):
    """Whether ``dispatcher`` is compiled in this process or has an entry in its disk cache
    (True where that cannot be read: then nothing is compiled in a second process)."""
    if dispatcher.signatures:
        return True
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except Exception:  # no disk cache (NullCache), or numba moved its internals
        return True


class _SecondProcess:
    """The variational kernel of a model compiled in another Python process into a numba
    cache folder of its own (started on construction)."""

    def __init__(self, model_inputs, dispatcher):
        self.dispatcher = dispatcher
        self.folder = tempfile.mkdtemp(prefix="nlbeam-numba-var-")
        spec = os.path.join(self.folder, "model.pkl")
        with open(spec, "wb") as f:
            pickle.dump(model_inputs, f)
        # (this process's import path: a model factory the scene names imports there too)
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(self.folder, "cache"),
                   PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
        self.proc = subprocess.Popen([sys.executable, "-m", __name__, spec], env=env,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def adopt(self):
        """Wait for the second process and copy its kernel into this process's numba cache;
        a RuntimeWarning if it failed (the kernel then compiles here). Returns the number of
        cache entries copied."""
        out, err = self.proc.communicate()
        try:
            if self.proc.returncode != 0:
                raise RuntimeError(f"exit status {self.proc.returncode}: {err[-2000:]}")
            report = json.loads(out.splitlines()[-1])
            n = adopt_cached(self.dispatcher, report["cache_path"])
            if n == 0:
                raise RuntimeError(f"no cache entry in {report['cache_path']}")
            return n
        except (RuntimeError, OSError, ValueError, IndexError, KeyError) as exc:
            warnings.warn(f"nlbeam: the variational kernel compiled in a second process could "
                          f"not be used ({exc}); it compiles here instead (about a minute). "
                          "Set nlbeam.app.warmup.OVERLAP = False to skip the second process",
                          RuntimeWarning, stacklevel=3)
            return 0
        finally:
            self.stop()

    def stop(self):
        """End the second process (if still running) and remove its folder."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()
        shutil.rmtree(self.folder, ignore_errors=True)


def _main(spec):
    """The second process: compile the variational kernel of the model in ``spec`` (a pickle
    of scene model inputs) and print its cache folder and CPU seconds (JSON)."""
    from nlbeam.integrate import compile_kernels

    from .scenes.schema import build_model

    with open(spec, "rb") as f:
        model = build_model(pickle.load(f))
    t = time.perf_counter()
    cpu = compile_kernels(model, True)
    disp = model.kernels().integrate_var
    print(json.dumps({"cache_path": disp._cache._cache_path, "cpu": cpu,
                      "wall": time.perf_counter() - t}))


if __name__ == "__main__":
    _main(sys.argv[1])
