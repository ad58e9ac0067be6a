"""A linear-time check of a STEP file before OpenCascade parses it.

OCC's STEP parser builds nested parameter lists recursively, about 150 bytes of C stack per
level: a few hundred KB of balanced parentheses crash the whole process with a segmentation
fault, which no Python code can catch (measured with OCP 7.9: an 8 MB main-thread stack survives
50,000 levels and crashes at 60,000; a 512 KB thread stack survives 2,000 and crashes at 5,000). :func:`scan_step` therefore reads the file once with numpy and
refuses, with a :class:`~splinekit.errors.FileFormatError` naming the problem and the limit:

- parentheses nested deeper than :data:`MAX_NESTING` outside strings and comments;
- a byte other than printable ASCII, tab or a line break outside strings and comments, a
  statement whose parentheses do not balance, a reference ``#n`` to an entity that is not
  defined, or an entity defined twice (OCC reports these syntax errors, then its transfer
  crashes or hangs on what it made of them);
- a file or entity count whose OCC model would not fit the memory budget
  (:func:`splinekit.limits.check`; OCC holds each entity as several C++ objects).

Parentheses, semicolons and ``#`` inside STEP strings (``'...'``, where ``''`` is an escaped
quote) and comments (``/* ... */``) do not count. A character lies inside a string exactly when
an odd number of quotes outside comments precede it (an escaped quote adds two), so one
cumulative count suffices, plus a step per comment.
"""

from __future__ import annotations

import os
import re
import stat
from typing import NamedTuple

import numpy as np

from splinekit import limits
from splinekit.errors import FileFormatError

__all__ = ["MAX_NESTING", "StepScan", "scan_step", "syntax_errors"]

MAX_NESTING = 200
"""Deepest parenthesis nesting accepted. CAD systems write a handful of levels (the deepest of
fifteen files from thirteen systems is 4: an entity, a list, a list of lists); at 150 bytes a
level OCC would crash near 800 levels on a 128 KB thread stack (musl's default), so 200 leaves a
wide margin on both sides."""

BYTES_PER_FILE_BYTE = 40
"""Memory charged per byte of STEP text for OCC's reading and translation (measured peak
resident size over file size: 18 to 36 on the real files above 500 KB, where OCC's fixed 10 MB
no longer dominates)."""

BYTES_PER_ENTITY = 4096
"""Memory charged per entity (measured: 1.2 to 4 KB per entity on the same files), so that a
file of tiny entities, which costs more per byte, is charged enough."""


class StepScan(NamedTuple):
    """What :func:`scan_step` measured: the file size in bytes, the number of entity
    instances (``;``-terminated statements outside strings and comments, header included)
    and the deepest parenthesis nesting."""

    size: int
    entities: int
    depth: int


def _inside(data: bytes, a: np.ndarray) -> np.ndarray:
    """``(len(data),)`` bool: the byte lies inside a string or a comment (quotes and comment
    marks included).

    A byte is inside a string when an odd number of counted quotes precede it (an escaped quote
    ``''`` adds two); the count is kept modulo 256 in uint8, which preserves its parity, so the
    temporaries are one byte per byte. Quotes inside comments do not count: comments are found
    one at a time, each ``/*`` tested by the parity of the quotes before it (a step per comment,
    or per string holding ``/*``; none for the usual file without comments).
    """
    quote = a == ord("'")
    if b"/*" in data:
        q = np.flatnonzero(quote)
        candidates = np.flatnonzero((a[:-1] == ord("/")) & (a[1:] == ord("*")))
        removed, k, comments = 0, 0, []
        while k < candidates.size:
            c = int(candidates[k])
            before = int(np.searchsorted(q, c))
            if (before - removed) & 1:  # inside a string: go on after its next quote
                if before == q.size:
                    break
                k = int(np.searchsorted(candidates, q[before], side="right"))
                continue
            close = data.find(b"*/", c + 2)
            end = len(data) if close < 0 else close + 2
            removed += int(np.searchsorted(q, end)) - before
            comments.append((c, end))
            k = int(np.searchsorted(candidates, end))
        for start, end in comments:
            quote[start:end] = False
    inside = (np.cumsum(quote, dtype=np.uint8) & 1).astype(bool)
    inside |= quote
    if b"/*" in data:
        for start, end in comments:
            inside[start:end] = True
    return inside


_DEFINITION = re.compile(rb"#(\d+)\s*=")
_REFERENCE = re.compile(rb"#(\d+)")
_NOT_A_NAME = re.compile(rb"#(?!\d)")
# an integer literal (not part of a real, an entity name or an identifier) of ten or more digits
_BIG_INTEGER = re.compile(rb"(?<![\w.#+-])[+-]?\d{10,}(?![\w.])")


def scan_step(path, what: str | None = None) -> StepScan:
    """Measure the STEP file ``path`` and refuse what OpenCascade cannot read safely.

    Reads the file once; time and memory are linear in its size (about 10 bytes of
    temporaries per parenthesis). ``what`` names the file in messages (default: the path).

    Raises
    ------
    FileFormatError
        the file cannot be read, or its parentheses nest deeper than :data:`MAX_NESTING`
        (the message gives the depth, the limit and the line where it is first exceeded).
    ResourceLimitError
        the file size or entity count would need more memory than the budget in OCC.
    """
    path = os.fspath(path)
    what = what or f"STEP file {path!r}"
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):  # a FIFO or device would block or never end
            raise FileFormatError(f"cannot read {what}: it is not a regular file")
        size = info.st_size
        limits.check(size * BYTES_PER_FILE_BYTE, f"reading the {size}-byte {what} with OpenCascade")
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise FileFormatError(f"cannot read {what}: {reason}") from exc
    a = np.frombuffer(data, dtype=np.uint8)
    inside = _inside(data, a)
    # outside strings and comments a STEP file is printable ASCII (ISO 10303-21's basic alphabet)
    # and line breaks; OCC's parser crashed on other bytes there
    odd = ~inside & ((a > 126) | ((a < 32) & (a != 9) & (a != 10) & (a != 13)))
    if odd.any():
        at = int(np.argmax(odd))
        line = data.count(b"\n", 0, at) + 1
        raise FileFormatError(
            f"{what}: the byte 0x{a[at]:02X} at line {line} (byte {at}) is outside strings and comments, "
            "where STEP allows only printable ASCII"
        )
    marks = np.flatnonzero(((a == ord("(")) | (a == ord(")")) | (a == ord(";"))) & ~inside)
    kinds = a[marks]
    entities = int(np.count_nonzero(kinds == ord(";")))
    limits.check(entities * BYTES_PER_ENTITY, f"reading the {entities} entities of {what} with OpenCascade")
    step = np.zeros(marks.size, dtype=np.int32)
    step[kinds == ord("(")] = 1
    step[kinds == ord(")")] = -1
    raw = np.cumsum(step, dtype=np.int32)
    # a surplus ")" must not hide deeper nesting after it: count as from zero again
    level = raw - np.minimum(np.minimum.accumulate(raw), 0) if raw.size else raw
    depth = int(level.max()) if level.size else 0
    if depth > MAX_NESTING:
        at = int(marks[np.argmax(level > MAX_NESTING)])
        line = data.count(b"\n", 0, at) + 1
        raise FileFormatError(
            f"{what}: parentheses nest {depth} levels deep (first beyond {MAX_NESTING} at byte {at}, "
            f"line {line}); at most {MAX_NESTING} are accepted, since OpenCascade's parser crashes "
            "on deep nesting and CAD systems write only a few levels"
        )
    # every statement (up to its ";") closes what it opens; OCC's parser reports a statement that
    # does not, then its transfer can crash on what it made of it
    bad = (raw < 0) | ((kinds == ord(";")) & (raw != 0))
    if bad.any() or (raw.size and raw[-1] != 0):
        at = int(marks[np.argmax(bad)]) if bad.any() else len(data)
        problem = "a ')' closes nothing" if bad.any() and raw[np.argmax(bad)] < 0 else "a '(' is not closed"
        line = data.count(b"\n", 0, at) + 1
        raise FileFormatError(f"{what}: unbalanced parentheses: {problem} in the statement ending at line {line} (byte {at})")
    _check_references(np.where(inside, np.uint8(32), a).tobytes(), what)
    return StepScan(size, entities, depth)


def syntax_errors(step_reader, what: str) -> None:
    """Raise FileFormatError if OCC's parser reported syntax errors while loading the file into
    ``step_reader`` (a ``STEPControl_Reader``, after ``ReadFile``). OCC loads such a file anyway
    (``ReadFile`` returns ``RetDone``), and its transfer then crashes or hangs on the broken
    entities; this is the net behind :func:`scan_step` for syntax errors the scan does not see."""
    check = step_reader.StepModel().GlobalCheck()
    if check.HasFailed():
        try:
            first = check.CFail(1)
        except Exception:  # noqa: BLE001 - only the message is missing
            first = "?"
        raise FileFormatError(f"{what}: OpenCascade's parser reports {check.NbFails()} syntax error(s), the first: {first}")


def _check_references(text: bytes, what: str) -> None:
    """Refuse a reference ``#n`` to an entity the file does not define, and an entity defined
    twice (``text``: the file with strings and comments blanked). OpenCascade reports an
    unresolved reference and then dereferences it: a segmentation fault or a hang in the
    transfer."""
    big = _BIG_INTEGER.search(text)
    if big is not None:
        line = text.count(b"\n", 0, big.start()) + 1
        raise FileFormatError(f"{what}: the integer {big.group().decode()[:40]} at line {line} is beyond 32 bits "
                              "(OCC reads integers as 32-bit and crashed on such counts)")
    stray = _NOT_A_NAME.search(text)
    if stray is not None:
        line = text.count(b"\n", 0, stray.start()) + 1
        raise FileFormatError(f"{what}: a '#' not followed by an entity number at line {line} (byte {stray.start()})")
    defined = np.array(_DEFINITION.findall(text), dtype=bytes)
    used = np.array(_REFERENCE.findall(text), dtype=bytes)
    if defined.size == 0:
        return  # no DATA entities: OCC refuses the file on its own
    too_long = next((n for n in (defined, used) if n.dtype.itemsize > 18), None)
    if too_long is not None:
        raise FileFormatError(f"{what}: an entity number has more than 18 digits")
    defined, used = defined.astype(np.int64), used.astype(np.int64)
    ids, counts = np.unique(defined, return_counts=True)
    if (counts > 1).any():
        raise FileFormatError(f"{what}: entity #{int(ids[counts > 1][0])} is defined {int(counts.max())} times")
    missing = ~np.isin(used, ids)
    if missing.any():
        raise FileFormatError(
            f"{what}: entity #{int(used[missing][0])} is referenced but not defined "
            f"({int(np.unique(used[missing]).size)} undefined references in all)"
        )
