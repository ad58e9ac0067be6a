"""Where the commands write, and how they format what they write: one-line errors, counts,
sizes, tables, bounding boxes and measures that may overflow."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import MeshTopologyError


class Console:
    """Results go to stdout unless ``quiet``; details only when ``verbose`` (and not quiet)."""

    def __init__(self, quiet: bool = False, verbose: bool = False):
        self.quiet, self.verbose = quiet, verbose

    def out(self, text: str = "") -> None:
        if not self.quiet:
            print(text, flush=True)

    def detail(self, text: str) -> None:
        if self.verbose and not self.quiet:
            print(text, flush=True)


def first_line(exc: BaseException) -> str:
    """The first line of ``exc``'s message (its type name when the message is empty)."""
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def one_line(text: str) -> str:
    """``text`` with every character that ends a line or steers a terminal (newline, carriage
    return, escape, the separators \\x1c-\\x1e, U+2028...) written as its escape: arguments echoed
    in an error message cannot break it into several lines."""
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in text)


def is_tty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def error_line(text: str, after_echo: bool = False) -> None:
    """``text`` as one line on stderr; a closed stderr is no further error. ``after_echo``: on a
    terminal, start a fresh line first (the terminal has echoed ``^C``)."""
    try:
        sys.stderr.write(("\n" if after_echo and is_tty(sys.stderr) else "") + one_line(text) + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def size_text(nbytes: int) -> str:
    """A file size in B, kB or MB (powers of 1000)."""
    for unit in ("B", "kB", "MB"):
        if nbytes < 1000 or unit == "MB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.1f} {unit}"
        nbytes /= 1000.0
    return ""  # pragma: no cover


def count(n: int, word: str, plural: str | None = None) -> str:
    """``"1 face"``, ``"3 faces"``, ``"2 bodies"`` (with ``plural``)."""
    return f"{n} {word if n == 1 else (plural or word + 's')}"


def number_text(x) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def value_text(x) -> str:
    """A measured value for a table: integers as they are, floats to 10 digits, None as ``--``."""
    if x is None:
        return "--"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f"{x:.10g}"


def table(rows, header) -> str:
    """Rows of strings as left-aligned columns under ``header``, with a rule below it."""
    rows = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    lines = [fmt.format(*header).rstrip(), "  ".join("-" * w for w in widths)]
    lines += [fmt.format(*r).rstrip() for r in rows]
    return "\n".join(lines)


BEYOND = "-- (beyond the float range)"


def bbox_text(lo, hi) -> str:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    with np.errstate(over="ignore"):  # coordinates near the float limits: a size beyond it is said so
        size = hi - lo
    return (f"[{', '.join(f'{x:.6g}' for x in lo)}] .. [{', '.join(f'{x:.6g}' for x in hi)}] "
            f"(size {' x '.join(f'{x:.6g}' if np.isfinite(x) else 'beyond the float range' for x in size)})")


def measure_text(get, fmt: str) -> str:
    """``get()`` (an area or a volume) formatted with ``fmt``, or why there is no number: on a mesh
    near the float limits the measure overflows (MeshTopologyError), which is worth a note in a
    summary, not a failed command after its files are written."""
    try:
        value = float(get())
    except MeshTopologyError as exc:
        return f"-- ({first_line(exc)})"
    return format(value, fmt) if np.isfinite(value) else BEYOND
