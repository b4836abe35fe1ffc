"""A diagram that came out empty stops the run: ``check_not_empty`` raises before it is cached
or drawn, naming the scene (``nlbeam run`` and ``nlbeam figures`` then exit non-zero).

An empty diagram means that every shooting solve of the brute-force grid failed: nothing a
figure could show, and, for a scene that drew a diagram before, a sign that the integration
went wrong (e.g. a variational kernel that does not integrate the variational equations,
'singular Jacobian at iteration 1' at every frequency).
"""
from __future__ import annotations

import os

__all__ = ["EmptyDiagramError", "check_not_empty"]


class EmptyDiagramError(RuntimeError):
    """A scene's diagram has no branch point (every solve failed)."""


def _first_line(text, n=160):
    line = str(text).strip().splitlines()[0] if str(text).strip() else ""
    return line if len(line) <= n else line[:n - 3] + "..."


def check_not_empty(scene, job, result, warned=()):
    """Raise EmptyDiagramError if ``result`` of the periodic ``job`` of ``scene`` has no branch
    point; the message (one line) names the scene file and title, the analysis, and the first
    of the warnings ``warned`` that its computation gave."""
    if job.kind != "periodic":
        return
    if sum(len(b.values) for b in getattr(result, "branches", [])) > 0:
        return
    where = os.path.basename(scene.path) if scene.path else "scene"
    why = f" (first warning: {_first_line(warned[0])})" if warned else ""
    raise EmptyDiagramError(
        f"scene {where} ({scene.title}): the diagram {job.description or job.variant} came out "
        f"empty: every solve failed{why}; nothing cached or drawn. If this scene drew a "
        f"diagram before, the integration kernels are suspect: remove numba's cache (the "
        f"__pycache__ folders of nlbeam/_kernels, or NUMBA_CACHE_DIR) and run again; "
        f"otherwise try a finer brute-force grid (n_grid) or another f_range")
