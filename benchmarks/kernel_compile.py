"""CPU time of the integration kernels' first compile, as on a fresh machine.

python benchmarks/kernel_compile.py [--by-function | --by-phase] [plain var | var plain | ...]
python benchmarks/kernel_compile.py --overlap [off | on] [--repeat N]

Runs one fresh interpreter with numba's cache in an empty temporary folder (NUMBA_CACHE_DIR:
the kernels cached in this checkout are not read) and compiles the kernels in the order given
(``nlbeam.integrate.compile_kernels``: plain = without, var = with the variational equations),
printing the CPU seconds of each and the number of compiled signatures of each kernel. The
second kernel reuses the step functions the first compiled, so 'plain var' prints the plain
kernel alone and what the variational one adds (a diagram needs both, a record only the plain
one). Times vary with load; CPU seconds are steadier than wall seconds on a shared machine.
``--by-function``: also every numba function compiled on the way, indented by call depth, with
the CPU seconds of its compile including what it called (what numba compiled twice shows up
as two lines of one name).
``--by-phase``: the CPU seconds of each kernel split by what numba does (its exclusive time in
type inference, lowering to LLVM IR, LLVM's function passes, LLVM's module passes over a
function's module with every callee's code linked in, machine code of that module, cache
writes, the rest of numba's pipeline), with the number of calls: every dispatcher level
optimizes and emits again the code of all it calls.
``--overlap``: both kernels of the paper model as a scene run prepares them
(``nlbeam.app.warmup.prepare_kernels`` of a diagram's inputs), in a fresh cache each: once
with ``OVERLAP = False`` (plain then variational here) and once with the variational kernel
in a second process beside the plain one (``off`` / ``on`` alone: only that one); prints wall
seconds and the CPU seconds of this process and of its children, alternating the two
``--repeat`` times (default 1).
"""
import os
import subprocess
import sys
import tempfile

TRACE = """
import time
from numba.core import dispatcher
_compile = dispatcher.Dispatcher.compile
_log, _depth = [], [0]
def _traced(self, sig):
    t, n0 = time.process_time(), len(self.overloads)
    _depth[0] += 1
    try:
        return _compile(self, sig)
    finally:
        _depth[0] -= 1
        if len(self.overloads) > n0:
            _log.append((_depth[0], self.py_func.__module__ + '.' + self.py_func.__qualname__,
                         time.process_time() - t, str(sig)))
dispatcher.Dispatcher.compile = _traced
"""

PHASES = """
import collections
from numba.core import codegen, lowering, typeinfer
_stack, _excl, _calls = [], collections.defaultdict(float), collections.Counter()
def _timed(cls, name, what):
    orig = getattr(cls, name)
    def timed(*a, **k):
        t = time.process_time()
        _stack.append(0.0)
        try:
            return orig(*a, **k)
        finally:
            inner, dt = _stack.pop(), time.process_time() - t
            _excl[what] += dt - inner
            _calls[what] += 1
            if _stack:
                _stack[-1] += dt
    setattr(cls, name, timed)
_timed(dispatcher.Dispatcher, "compile", "rest of numba's pipeline")
_timed(typeinfer.TypeInferer, "propagate", "type inference")
_timed(lowering.Lower, "lower", "lowering to LLVM IR")
_timed(codegen.CPUCodeLibrary, "_optimize_functions", "LLVM function passes")
_timed(codegen.CPUCodeLibrary, "_optimize_final_module", "LLVM module passes, callees linked")
_timed(codegen.CPUCodeLibrary, "_finalize_final_module", "machine code, callees linked")
_timed(codegen.CPUCodeLibrary, "serialize_using_object_code", "cache writes")
def _phases(what):
    print(f"--- {what} by phase (exclusive CPU s, calls)")
    for name, cpu in sorted(_excl.items(), key=lambda kv: -kv[1]):
        print(f"  {cpu:6.1f}  {_calls[name]:4d}  {name}")
    _excl.clear()
    _calls.clear()
"""

CODE = """
import sys, time
import nlbeam
from nlbeam.integrate import compile_kernels
m = nlbeam.BeamImpact.paper()
for what in sys.argv[1:]:
    t = time.perf_counter()
    if TRACED:
        _log.append((-1, what, 0.0, ''))
    if PHASED:
        _excl.clear()
        _calls.clear()
    cpu = compile_kernels(m, what == "var")
    print(f"{what}: {cpu:.1f} s CPU, {time.perf_counter() - t:.1f} s wall", flush=True)
    if PHASED:
        _phases(what)
k = m.kernels()
print(f"signatures: integrate_plain {len(k.integrate_plain.signatures)}, "
      f"integrate_var {len(k.integrate_var.signatures)}")
if TRACED:
    for depth, name, cpu, sig in _log:
        if depth < 0:
            print(f"--- {name}")
        elif cpu >= 0.3:
            print(f"{'  ' * depth}{cpu:6.1f}  {name}  {sig[:60]}")
"""


OVERLAP = """
import resource, sys, time
from nlbeam.app import warmup
warmup.OVERLAP = sys.argv[1] == "on"
t, c = time.perf_counter(), time.process_time()
n = warmup.prepare_kernels([{"analysis": "periodic", "model": {"name": "BeamImpact"},
                             "periodic": {"stability": True}}])
wall, cpu = time.perf_counter() - t, time.process_time() - c
child = resource.getrusage(resource.RUSAGE_CHILDREN)
import nlbeam
k = nlbeam.BeamImpact.paper().kernels()
hits = sum(k.integrate_var.stats.cache_hits.values())
print(f"overlap {sys.argv[1]:>3}: {n} kernels, {wall:6.1f} s wall, {cpu:6.1f} s CPU here, "
      f"{child.ru_utime + child.ru_stime:6.1f} s CPU in a second process; variational kernel "
      f"{'loaded from the cache' if hits else 'compiled here'}", flush=True)
"""


def overlap(args):
    repeat = int(args[args.index("--repeat") + 1]) if "--repeat" in args else 1
    modes = [a for a in ("off", "on") if a in args] or ["off", "on"]
    for _ in range(repeat):
        for mode in modes:
            with tempfile.TemporaryDirectory(prefix="nlbeam-numba-cache-") as cache:
                env = dict(os.environ, NUMBA_CACHE_DIR=cache)
                subprocess.run([sys.executable, "-c", OVERLAP, mode], env=env, check=True)


def main(args):
    if "--overlap" in args:
        return overlap(args)
    traced = "--by-function" in args
    phased = "--by-phase" in args
    if traced and phased:
        raise SystemExit("kernel_compile: --by-function or --by-phase, not both")
    order = [a for a in args if a not in ("--by-function", "--by-phase")] or ["plain", "var"]
    for what in order:
        if what not in ("plain", "var"):
            raise SystemExit(f"kernel_compile: give plain and/or var, got {what!r}")
    code = ("import time\nfrom numba.core import dispatcher\n" + PHASES if phased else "") \
        + (TRACE if traced else "") + f"TRACED = {traced}\nPHASED = {phased}\n" + CODE
    with tempfile.TemporaryDirectory(prefix="nlbeam-numba-cache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        subprocess.run([sys.executable, "-c", code, *order], env=env, check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
