"""A custom force paid once per machine: CPU seconds to the first result in a first and a
second fresh process.

python benchmarks/custom_force_compile.py [--monodromy]

Writes a module with a jitted custom force (a cubic spring, importable by name) into an empty
temporary folder, points NLBEAM_CACHE_DIR (the kernel copies of ``nlbeam.custom``) and
NUMBA_CACHE_DIR at empty folders, and runs the same short integration (``--monodromy``: a
flow with the variational equations, which compiles that kernel too) in two fresh
interpreters one after the other. Prints, for each, the CPU seconds of the call (compiling
or loading the kernel copy included), the kernel package's module name and how many of its
integration kernels numba compiled or loaded from the disk cache. The second process finds
the copy the first one wrote, so it loads instead of compiling.
"""
import os
import subprocess
import sys
import tempfile

FORCE = '''
from numba import njit


@njit
def cubic_force(t, x, v, y, yd, params, out):
    out[0] -= params[0] * x[0] ** 3
'''

CODE = """
import sys, time
import numpy as np
import nlbeam
from bench_force import cubic_force
monodromy = sys.argv[2] == "1"
t = time.process_time()
model = nlbeam.System([[1.0]], [[0.1]], [[1.0]], (), "force", y_load=[1.0], yd_load=[0.0],
                      custom_force=cubic_force, custom_params=[1.0])
fl = nlbeam.flow(model, nlbeam.Harmonic(0.2, 0.15), [0.3, 0.0], 0.0, 5.0, dt=0.01,
                 monodromy=monodromy)
cpu = time.process_time() - t
k = model.kernels()
made = {name: (sum(d.stats.cache_misses.values()), sum(d.stats.cache_hits.values()))
        for name, d in (("plain", k.integrate_plain), ("variational", k.integrate_var))}
print(f"process {sys.argv[1]}: {cpu:6.1f} s CPU to the first flow; {k.__name__}; "
      + ", ".join(f"{n} kernel compiled {c} / loaded {h}" for n, (c, h) in made.items())
      + f"; x(5 s) = {fl.state[0]:.15g}", flush=True)
"""


def main(args):
    monodromy = "--monodromy" in args
    with tempfile.TemporaryDirectory(prefix="nlbeam-custom-bench-") as tmp:
        with open(os.path.join(tmp, "bench_force.py"), "w") as f:
            f.write(FORCE)
        env = dict(os.environ, NLBEAM_CACHE_DIR=os.path.join(tmp, "kernel-copies"),
                   NUMBA_CACHE_DIR=os.path.join(tmp, "numba-cache"),
                   PYTHONPATH=os.pathsep.join([tmp] + sys.path))
        for n in (1, 2):
            subprocess.run([sys.executable, "-c", CODE, str(n), "1" if monodromy else "0"],
                           env=env, cwd=tmp, check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
