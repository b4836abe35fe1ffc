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

__all__ = ["prepare_kernels", "KernelWarmup", "warm_linalg", "needs_variational", "adopt_cached",
           "OVERLAP"]

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
    warm = KernelWarmup(todo)
    try:
        warm.plain()
        return warm.finish()
    finally:
        warm.stop()


class KernelWarmup:
    """``prepare_kernels`` in two halves, so that work needing only the plain kernels runs
    while a second process compiles a variational one: construction starts that process
    (where it saves time), ``plain()`` compiles or loads the plain kernels here (and the
    dense linear algebra of the continuation where a diagram or chart follows,
    ``warm_linalg``), ``pending()`` says whether the second process is still compiling,
    ``finish()`` adopts its kernel and loads the variational kernels here; ``stop()`` ends
    the second process (in a ``finally``)."""

    def __init__(self, todo):
        from .scenes.schema import build_model

        self.needed = {}   # kernel package -> [model, its scene inputs, variational needed]
        for inputs in todo:
            model = build_model(inputs["model"])
            entry = self.needed.setdefault(model.kernels().__name__,
                                           [model, inputs["model"], False])
            entry[2] = entry[2] or needs_variational(inputs)
        self.second = {}
        try:
            for name, (model, spec, var) in self.needed.items():
                kern = model.kernels()
                if var and OVERLAP and not self.second and _cores() >= 2 \
                        and not _cached(kern.integrate_plain) \
                        and not _cached(kern.integrate_var):
                    self.second[name] = _SecondProcess(spec, kern.integrate_var)   # (one)
        except BaseException:
            self.stop()
            raise

    @property
    def variational(self):
        """Whether any analysis needs a variational kernel."""
        return any(var for _, _, var in self.needed.values())

    def plain(self):
        """Compile or load the plain kernels here (and the linear algebra of a diagram)."""
        from nlbeam.integrate import compile_kernels

        for model, _, _ in self.needed.values():
            compile_kernels(model, False)
        if self.variational:
            warm_linalg()

    def pending(self):
        """Whether a second process is still compiling a variational kernel."""
        return any(proc.proc.poll() is None for proc in self.second.values())

    def finish(self):
        """Load the variational kernels here (adopting the second process's); returns the
        number of kernels made ready."""
        from nlbeam.integrate import compile_kernels

        for name, (model, _, var) in self.needed.items():
            if var:
                if name in self.second:
                    self.second.pop(name).adopt()
                compile_kernels(model, True)   # loads what the second process compiled
        return len(self.needed) + sum(var for _, _, var in self.needed.values())

    def stop(self):
        """End a second process still running (and remove its folder)."""
        for proc in self.second.values():
            proc.stop()
        self.second = {}


def warm_linalg():
    """Compile (or load from numba's disk cache) here every routine of ``nlbeam._linalg`` for
    the argument types the continuation passes (float arrays, complex eigenvalues), before a
    pool forks its workers: otherwise the first diagram compiles them on its way (about 20 s
    CPU on a fresh machine), in every worker that meets them first. Returns the CPU
    seconds it took."""
    import numpy as np

    from nlbeam import _linalg as la

    t = time.process_time()
    A = np.array([[2.0, -1.0, 0.5], [1.0, 2.0, 0.0], [0.0, 0.25, 1.0]])   # a complex pair
    b = np.array([1.0, 2.0, 3.0])
    la.solve(A, b)
    la.solve(A, A)
    la.det_sign(A)
    la.det(A)
    la.inv(A)
    la.matmul(A, A)
    la.matmul(A, b)
    la.matmul(b, A)
    la.matmul(b, b)
    la.dot(b, b)
    la.norm(b)
    la.norm(A)
    la.eig(A)
    la.qr(A)
    la.qr(A[:, :2])
    la.null_vector(A[:2, :])
    la.smallest_singular_vectors(A)
    return time.process_time() - t


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
