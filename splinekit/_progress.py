"""A tiny progress bar for the command line, drawn on stderr only when it is a terminal.

No dependency. A bar is a context manager::

    with progress(len(items), "tessellating") as bar:
        for item in items:
            ...
            bar.advance()

When the stream is not a terminal (a pipe, a file, a test capturing output)
or bars are disabled (``--quiet``), nothing at all is written. Bars opened
while another is open (tessellating inside "building models") stay silent, so
the outer bar keeps the line.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress", "progress", "set_enabled", "is_enabled"]

_ENABLED = True
_OPEN = 0  # bars currently open; only the outermost one draws
_WIDTH = 28  # characters of the bar itself
_MIN_INTERVAL = 0.1  # seconds between redraws, so a fast loop does not flood the terminal


def set_enabled(flag: bool) -> None:
    """Switch all progress bars on (the default) or off (``--quiet``)."""
    global _ENABLED
    _ENABLED = bool(flag)


def is_enabled() -> bool:
    """Whether progress bars may draw (see :func:`set_enabled`)."""
    return _ENABLED


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class Progress:
    """A bar counting ``done`` out of ``total`` steps, labelled ``label``.

    Draws ``label [#####.....] done/total  elapsed`` on one line of ``stream``
    (stderr by default), rewriting it in place, and clears the line on exit.
    Use it as a context manager: it draws (on a terminal, with bars enabled,
    and when no other bar is open) only between ``__enter__`` and ``__exit__``.
    ``show=False`` makes a bar that never draws and leaves inner bars free to.
    """

    def __init__(self, total: int, label: str = "", stream=None, show: bool = True):
        self.show = bool(show)
        self.total = max(int(total), 0)
        self.label = str(label)
        self.stream = sys.stderr if stream is None else stream
        self.active = False
        self.done = 0
        self._start = time.perf_counter()
        self._drawn = 0.0

    def __enter__(self) -> "Progress":
        global _OPEN
        if self.show:  # a hidden bar neither draws nor silences the bars opened inside it
            self.active = _ENABLED and _OPEN == 0 and _is_terminal(self.stream)
            _OPEN += 1
        self._draw(force=True)
        return self

    def __exit__(self, *exc) -> None:
        global _OPEN
        if self.show:
            _OPEN -= 1
        self.close()

    def advance(self, steps: int = 1, label: str | None = None) -> None:
        """Count ``steps`` more steps done (and optionally change the label)."""
        self.done = min(self.done + int(steps), self.total) if self.total else self.done + int(steps)
        if label is not None:
            self.label = str(label)
        self._draw()

    def line(self) -> str:
        """The text of the bar as it would be drawn now (without the carriage return)."""
        elapsed = time.perf_counter() - self._start
        if self.total:
            filled = int(round(_WIDTH * self.done / self.total))
            bar = "#" * filled + "." * (_WIDTH - filled)
            return f"{self.label} [{bar}] {self.done}/{self.total} {elapsed:5.1f}s"
        return f"{self.label} {self.done} {elapsed:5.1f}s"

    def _draw(self, force: bool = False) -> None:
        if not self.active:
            return
        now = time.perf_counter()
        if not force and now - self._drawn < _MIN_INTERVAL and self.done < self.total:
            return
        self._drawn = now
        self.stream.write("\r\x1b[2K" + self.line())
        self.stream.flush()

    def close(self) -> None:
        """Erase the bar's line (only if one was drawn)."""
        if self.active:
            self.stream.write("\r\x1b[2K")
            self.stream.flush()
            self.active = False


def progress(total: int, label: str = "", stream=None, show: bool = True) -> Progress:
    """A :class:`Progress` bar of ``total`` steps (use it as a context manager)."""
    return Progress(total, label, stream, show)
