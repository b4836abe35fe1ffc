"""CPU time of the integration kernels' first compile, as on a fresh machine.

python benchmarks/kernel_compile.py [--by-function] [plain var | var plain | ...]

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

CODE = """
import sys, time
import nlbeam
from nlbeam.integrate import compile_kernels
m = nlbeam.BeamImpact.paper()
for what in sys.argv[1:]:
    t = time.perf_counter()
    if TRACED:
        _log.append((-1, what, 0.0, ''))
    cpu = compile_kernels(m, what == "var")
    print(f"{what}: {cpu:.1f} s CPU, {time.perf_counter() - t:.1f} s wall", flush=True)
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


def main(args):
    traced = "--by-function" in args
    order = [a for a in args if a != "--by-function"] or ["plain", "var"]
    for what in order:
        if what not in ("plain", "var"):
            raise SystemExit(f"kernel_compile: give plain and/or var, got {what!r}")
    code = (TRACE if traced else "") + f"TRACED = {traced}\n" + CODE
    with tempfile.TemporaryDirectory(prefix="nlbeam-numba-cache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        subprocess.run([sys.executable, "-c", code, *order], env=env, check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
