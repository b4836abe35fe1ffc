"""A diagram that came out empty stops the run: ``check_not_empty`` raises before it is cached
or drawn, naming the scene (``nlbeam run`` and ``nlbeam figures`` then exit non-zero).

In a scene with a [sweep], an empty diagram at one sweep value does not stop the other values
(``SweepEmpties``): each empty one is reported (a line naming the scene and the value) and
left uncached, the others are computed and cached, and at the end one EmptyDiagramError
lists the empty values, before anything is drawn (the figures would miss those values): the
run exits non-zero, and a re-run computes only the values that came out empty.

An empty diagram means that every shooting solve of the brute-force grid failed: nothing a
figure could show, and, for a scene that drew a diagram before, a sign that the integration
went wrong (e.g. a variational kernel that does not integrate the variational equations,
'singular Jacobian at iteration 1' at every frequency).
"""
from __future__ import annotations

import os
import sys

__all__ = ["EmptyDiagramError", "check_not_empty", "SweepEmpties"]


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


class SweepEmpties:
    """The empty diagrams of a sweep's values, collected (``check``) instead of raised at the
    first, each reported on stderr at once (--quiet too: it is an error); ``raise_any`` raises
    one EmptyDiagramError naming them all."""

    def __init__(self, scene):
        self.scene, self.errors = scene, []

    def check(self, job, result, warned=()):
        """True if ``result`` may be cached (not an empty diagram); an empty one is reported
        at once and collected."""
        try:
            check_not_empty(self.scene, job, result, warned)
            return True
        except EmptyDiagramError as exc:
            if self.scene.sweep is None:   # no other values to go on with
                raise
            self.errors.append((job, exc))
            print(f"nlbeam: error: {exc}", file=sys.stderr, flush=True)
            return False

    def raise_any(self):
        if not self.errors:
            return
        where = os.path.basename(self.scene.path) if self.scene.path else "scene"
        values = "; ".join(j.variant or j.description for j, _ in self.errors)
        raise EmptyDiagramError(
            f"scene {where} ({self.scene.title}): {len(self.errors)} diagram(s) of the sweep "
            f"came out empty ({values}); those are neither cached nor drawn, the other values "
            f"are cached (a re-run computes only these); nothing drawn")
