"""Writing figures to files: the backend for a process without a display, and an atomic save
(temporary name, then renamed) that closes the figure."""
from __future__ import annotations

import os
import sys

from ..files import atomic_path

__all__ = ["files_backend", "save_figure", "finish_figure"]


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


def check_figure_text(name, text):
    """Raise ValueError naming ``name`` when matplotlib cannot render ``text`` (bad math text
    such as '$\\frac{a}{$'): checked before any analysis starts."""
    if not isinstance(text, str):
        raise TypeError(f"{name}: must be a string, got {text!r}")
    if "$" not in text:
        return
    from matplotlib.cbook import is_math_text
    from matplotlib.mathtext import MathTextParser

    if not is_math_text(text):  # an odd number of unescaped dollars: drawn as plain text
        return

    try:
        MathTextParser("path").parse(text)
    except ValueError as exc:
        first = str(exc).strip().splitlines()
        raise ValueError(f"{name}: matplotlib cannot render {text!r} "
                         f"({first[-1] if first else 'bad math text'}); escape a literal "
                         "dollar as \\$") from None


def check_plot_options(path=None, flags=(), ax=None):
    """The options every plot function shares, checked before drawing: ``path`` None or a
    writable file path; ``flags`` (name, value) pairs that must be bools; ``ax`` None or a
    matplotlib Axes."""
    from nlbeam._validate import ArgumentTypeError, flag, output_file

    if path is not None:
        output_file("path", path)
    for name, value in flags:
        flag(name, value)
    if ax is not None and not hasattr(ax, "figure"):
        raise ArgumentTypeError(f"ax: must be a matplotlib Axes or None, got "
                                f"{type(ax).__name__}")


def finish_figure(fig, path, opened, *, tight_layout=None, dpi=None):
    """The end of every plot function: ``tight_layout`` (default: when the call ``opened``
    the figure) lays it out; with a ``path`` it is written there, by ``save_figure`` (atomic,
    then closed) when the call opened it, else by ``fig.savefig`` (the caller's figure stays
    open); dpi: None for each writer's default. Returns ``fig``."""
    if opened if tight_layout is None else tight_layout:
        fig.tight_layout()
    if path is not None:
        kw = {} if dpi is None else {"dpi": dpi}
        if opened:
            save_figure(fig, path, **kw)
        else:
            fig.savefig(path, **kw)
    return fig
