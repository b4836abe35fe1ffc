"""Progress of long computations on stderr: a bar redrawn in place on a terminal, plain lines
(at most one every ``PLAIN_EVERY`` s, and the last) when stderr is a file or a pipe, nothing
under ``--quiet``. Standard library only (a bar is 20 lines; no dependency for it).

``Progress(prefix)`` is a callable ``progress(msg)`` for status lines (what
``continuation.frequency_response(progress=...)`` calls per branch) and has
``bar(label, done, total, unit)`` for a quantity that advances (seconds simulated,
analyses done).
"""
from __future__ import annotations

import sys
import time

__all__ = ["Progress", "end_bar_line", "PLAIN_EVERY", "BAR_WIDTH"]

PLAIN_EVERY = 5.0  # s between plain progress lines of one bar
BAR_WIDTH = 24  # characters of the bar


_DRAWING = []  # the Progress whose bar is on the terminal's current line, if any


def end_bar_line():
    """End a bar's terminal line before other output (a warning) is printed."""
    if _DRAWING:
        _DRAWING[0].close()


class Progress:
    """Progress lines and bars for one command (module doc). prefix: put before every line
    ('nlbeam run' -> 'nlbeam run: ...'); quiet: print nothing; stream: default sys.stderr;
    tty: force the terminal (True) or plain (False) form, default ``stream.isatty()``;
    write: a callable(str) that takes the plain lines instead (then no bar is drawn)."""

    def __init__(self, prefix="", *, quiet=False, stream=None, tty=None, write=None):
        self.prefix = f"{prefix}: " if prefix else ""
        self.quiet = quiet
        self.stream = stream if stream is not None else sys.stderr
        self.write = write  # callable(str) taking the plain lines instead of the stream
        self.tty = write is None and bool(
            tty if tty is not None else getattr(self.stream, "isatty", lambda: False)())
        self._open = False  # a bar drawn on the current terminal line
        self._last = {}  # label -> time of its last plain line

    def __call__(self, msg):
        """One status line."""
        if self.quiet:
            return
        self._close_bar()
        self._line(f"{self.prefix}{msg}")

    def _line(self, text):
        if self.write is not None:
            self.write(text)
        else:
            print(text, file=self.stream, flush=True)

    def bar(self, label, done, total, unit=""):
        """Show that ``done`` of ``total`` (in ``unit``) of ``label`` is done."""
        if self.quiet:
            return
        frac = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
        amount = f"{done:.4g} / {total:.4g}{' ' + unit if unit else ''}"
        if self.tty:
            n = int(round(frac * BAR_WIDTH))
            self.stream.write(f"\r{self.prefix}{label} [{'#' * n}{'.' * (BAR_WIDTH - n)}] "
                              f"{amount} ({100 * frac:.0f} %)\x1b[K")
            self.stream.flush()
            self._open = True
            _DRAWING[:] = [self]
            if frac >= 1.0:
                self._close_bar()
            return
        now = time.perf_counter()
        if frac >= 1.0 or now - self._last.get(label, -1e300) >= PLAIN_EVERY:
            self._last[label] = now
            self._line(f"{self.prefix}{label}: {amount}")

    def _close_bar(self):
        if self._open:
            self.stream.write("\n")
            self.stream.flush()
            self._open = False
            if _DRAWING and _DRAWING[0] is self:
                _DRAWING.clear()

    def close(self):
        """End a bar left open (call before other output)."""
        self._close_bar()
