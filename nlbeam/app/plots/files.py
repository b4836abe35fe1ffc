"""Writing figures to files: the backend for a process without a display, and an atomic save
(temporary name, then renamed) that closes the figure."""
from __future__ import annotations

import os
import sys

from ..files import atomic_path

__all__ = ["files_backend", "save_figure"]


def files_backend():
    """Select matplotlib's Agg backend (files only) unless pyplot is already loaded: an
    interactive session keeps its backend."""
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")


def save_figure(fig, path, dpi=110):
    """Write ``fig`` to ``path`` atomically (format from the extension, PNG without one) and
    close it, also on failure. Returns ``path``."""
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=os.path.splitext(path)[1][1:] or "png")
    finally:
        plt.close(fig)
    return path
