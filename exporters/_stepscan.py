"""A linear-time check of a STEP file before OpenCascade parses it.

OCC's STEP parser builds nested parameter lists recursively, about 150 bytes of C stack per
level: a few hundred KB of balanced parentheses (about 60,000 levels on an 8 MB main-thread
stack, about 3,000 on a 512 KB thread stack) crash the whole process with a segmentation fault,
which no Python code can catch. :func:`scan_step` therefore reads the file once with numpy and
refuses, with a :class:`~splinekit.errors.FileFormatError` naming the problem and the limit:

- parentheses nested deeper than :data:`MAX_NESTING` outside strings and comments;
- a file or entity count whose OCC model would not fit the memory budget
  (:func:`splinekit.limits.check`; OCC holds each entity as several C++ objects).

Parentheses inside STEP strings (``'...'``, where ``''`` is an escaped quote) and comments
(``/* ... */``) do not count. Without comments a character lies inside a string exactly when an
odd number of quotes precede it (an escaped quote adds two), so one cumulative count suffices;
a file with comments is split into strings and comments by one left-to-right pass (a Python step
per string, only for such files).
"""

from __future__ import annotations

import os
import re
from typing import NamedTuple

import numpy as np

from splinekit import limits
from splinekit.errors import FileFormatError

__all__ = ["MAX_NESTING", "StepScan", "scan_step"]

MAX_NESTING = 200
"""Deepest parenthesis nesting accepted. CAD systems write at most a handful of levels (the
deepest of fifteen files from thirteen systems is 4: an entity, a list, a list of lists); OCC
crashes somewhere between 850 levels (a 128 KB thread stack) and 60,000 (an 8 MB stack), so 200
leaves both a wide margin for real files and one of four or more below the crash."""

BYTES_PER_FILE_BYTE = 40
"""Memory OCC needs per byte of STEP text while reading and translating (measured: 15 to 25 on
the files of thirteen CAD systems, peak resident size over file size; rounded up)."""

BYTES_PER_ENTITY = 4096
"""Memory OCC needs per entity (measured: 1 to 2 KB per entity on real files; a file of tiny
entities costs more per byte than :data:`BYTES_PER_FILE_BYTE` assumes)."""


class StepScan(NamedTuple):
    """What :func:`scan_step` measured: the file size in bytes, the number of entity
    instances (``;``-terminated statements outside strings and comments, header included)
    and the deepest parenthesis nesting."""

    size: int
    entities: int
    depth: int


_STRING_OR_COMMENT = re.compile(rb"'|/\*")
_STRING_TAIL = re.compile(rb"[^']*(?:''[^']*)*'")  # the rest of a string after its opening quote


def _skipped_ranges(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, ends)`` of the strings and comments of ``data``, left to right (a string
    or comment left open runs to the end)."""
    starts, ends, pos = [], [], 0
    while True:
        m = _STRING_OR_COMMENT.search(data, pos)
        if m is None:
            break
        start = m.start()
        if m.group() == b"'":
            tail = _STRING_TAIL.match(data, m.end())
            end = len(data) if tail is None else tail.end()
        else:
            close = data.find(b"*/", m.end())
            end = len(data) if close < 0 else close + 2
        starts.append(start)
        ends.append(end)
        pos = end
    return np.array(starts, dtype=np.int64), np.array(ends, dtype=np.int64)


def _outside(data: bytes, a: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Boolean mask over ``positions`` (sorted byte offsets): not inside a string or comment."""
    if b"/*" not in data:
        quotes = np.flatnonzero(a == ord("'"))
        return (np.searchsorted(quotes, positions) & 1) == 0
    starts, ends = _skipped_ranges(data)
    return np.searchsorted(starts, positions, side="right") == np.searchsorted(ends, positions, side="right")


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
        size = os.stat(path).st_size
        limits.check(size * BYTES_PER_FILE_BYTE, f"reading the {size}-byte {what} with OpenCascade")
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise FileFormatError(f"cannot read {what}: {reason}") from exc
    a = np.frombuffer(data, dtype=np.uint8)
    marks = np.flatnonzero((a == ord("(")) | (a == ord(")")) | (a == ord(";")))
    marks = marks[_outside(data, a, marks)]
    kinds = a[marks]
    entities = int(np.count_nonzero(kinds == ord(";")))
    limits.check(entities * BYTES_PER_ENTITY, f"reading the {entities} entities of {what} with OpenCascade")
    step = np.zeros(marks.size, dtype=np.int32)
    step[kinds == ord("(")] = 1
    step[kinds == ord(")")] = -1
    level = np.cumsum(step, dtype=np.int32)
    if level.size:
        # a surplus ")" must not hide deeper nesting after it: count as from zero again
        level -= np.minimum(np.minimum.accumulate(level), 0)
    depth = int(level.max()) if level.size else 0
    if depth > MAX_NESTING:
        at = int(marks[np.argmax(level > MAX_NESTING)])
        line = data.count(b"\n", 0, at) + 1
        raise FileFormatError(
            f"{what}: parentheses nest {depth} levels deep (first beyond {MAX_NESTING} at byte {at}, "
            f"line {line}); at most {MAX_NESTING} are accepted, since OpenCascade's parser crashes "
            "on deep nesting and CAD systems write only a few levels"
        )
    return StepScan(size, entities, depth)
