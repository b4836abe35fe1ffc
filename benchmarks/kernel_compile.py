"""CPU time of the integration kernels' first compile, as on a fresh machine.

python benchmarks/kernel_compile.py [plain var | var plain | ...]

Runs one fresh interpreter with numba's cache in an empty temporary folder (NUMBA_CACHE_DIR:
the kernels cached in this checkout are not read) and compiles the kernels in the order given
(``nlbeam.integrate.compile_kernels``: plain = without, var = with the variational equations),
printing the CPU seconds of each and the number of compiled signatures of each kernel. The
second kernel reuses the step functions the first compiled, so 'plain var' prints the plain
kernel alone and what the variational one adds (a diagram needs both, a record only the plain
one). Times vary with load; CPU seconds are steadier than wall seconds on a shared machine.
"""
import os
import subprocess
import sys
import tempfile

CODE = """
import sys, time
import nlbeam
from nlbeam.integrate import compile_kernels
m = nlbeam.BeamImpact.paper()
for what in sys.argv[1:]:
    t = time.perf_counter()
    cpu = compile_kernels(m, what == "var")
    print(f"{what}: {cpu:.1f} s CPU, {time.perf_counter() - t:.1f} s wall", flush=True)
k = m.kernels()
print(f"signatures: integrate_plain {len(k.integrate_plain.signatures)}, "
      f"integrate_var {len(k.integrate_var.signatures)}")
"""


def main(order):
    for what in order:
        if what not in ("plain", "var"):
            raise SystemExit(f"kernel_compile: give plain and/or var, got {what!r}")
    with tempfile.TemporaryDirectory(prefix="nlbeam-numba-cache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        subprocess.run([sys.executable, "-c", CODE, *order], env=env, check=True)


if __name__ == "__main__":
    main(sys.argv[1:] or ["plain", "var"])
