"""The integration kernels of a run, compiled (or loaded from numba's disk cache) in this
process before a process pool forks its workers.

numba compiles a kernel in the process that first calls it; the workers of a pool forked
before that each compile it again, at once (twice the CPU on two cores, for the same code).
Forked after ``prepare_kernels``, they inherit the compiled kernels. Only the kernels the
analyses need: the plain one (records, brute-force integrations) always, the variational
one for a diagram with stability or a stability chart.
"""
from __future__ import annotations

__all__ = ["prepare_kernels", "needs_variational"]


def needs_variational(inputs):
    """Whether the analysis of these job inputs integrates the variational equations (a
    diagram with stability, a stability chart)."""
    kind = inputs["analysis"]
    if kind == "chart":
        return True
    return kind == "periodic" and bool(inputs["periodic"].get("stability", True))


def prepare_kernels(todo):
    """Compile or load here the kernels the analyses ``todo`` (job inputs) need, once per
    kernel package (a custom force has its own). Returns the number of kernels made ready."""
    from nlbeam.integrate import compile_kernels

    from .scenes.schema import build_model

    done = set()
    for inputs in todo:
        model = build_model(inputs["model"])
        name = model.kernels().__name__
        for monodromy in (False, True) if needs_variational(inputs) else (False,):
            if (name, monodromy) not in done:
                done.add((name, monodromy))
                compile_kernels(model, monodromy)
    return len(done)
