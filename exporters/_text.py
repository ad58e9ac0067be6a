"""Text rows of integers and of unit-range fixed-point numbers, built with numpy (no Python call
per number).

Python's ``%`` formatting costs about 0.2 microseconds per integer and a microsecond per float
(measured on the project's 2-core machine): for the face lines of an OBJ file that is most of the
time of the indices. Here each number becomes a fixed-width field of ASCII digits padded with NUL
bytes, the fields and the literal text between them are laid out in a ``(rows, width)`` byte
array, and the NUL padding is squeezed out in one pass (text never holds a NUL byte).
"""

from __future__ import annotations

import numpy as np

__all__ = ["fixed_rows", "int_rows"]

ROWS_PER_CHUNK = 65_536  # rows built at a time: the byte arrays stay small


def _digits(values: np.ndarray, width: int) -> np.ndarray:
    """``(n, width)`` uint8: the decimal digits of ``values`` ``(n,)`` (non-negative int64),
    right-aligned, leading positions 0 (NUL) except the last digit of a zero."""
    out = np.empty((values.size, width), dtype=np.uint8)
    v = values.copy()
    for w in range(width - 1, -1, -1):
        d = v % 10
        out[:, w] = d + 48
        v //= 10
    # NUL before the first significant digit
    count = np.ones(values.size, dtype=np.int64)  # digits of each value (at least one)
    big = values.copy()
    for _ in range(width - 1):
        big //= 10
        count += big > 0
    out[np.arange(width) < (width - count)[:, None]] = 0
    return out


def _layout(fields: list, literals: list[bytes]) -> bytes:
    """``literals[0] + fields[0] + literals[1] + ... + fields[-1] + literals[-1]`` on every row:
    ``fields`` are ``(n, w_j)`` NUL-padded byte arrays; returns the rows without the padding."""
    n = fields[0].shape[0]
    widths = [len(lit) for lit in literals] + [f.shape[1] for f in fields]
    row = np.zeros((n, sum(widths)), dtype=np.uint8)
    at = 0
    for j, lit in enumerate(literals):
        if lit:
            row[:, at:at + len(lit)] = np.frombuffer(lit, dtype=np.uint8)
            at += len(lit)
        if j < len(fields):
            row[:, at:at + fields[j].shape[1]] = fields[j]
            at += fields[j].shape[1]
    flat = row.ravel()
    return flat[flat != 0].tobytes()


def _emit(parts, sink):
    """``parts`` (an iterable of bytes) joined, or handed to ``sink`` one by one (then None)."""
    if sink is None:
        return b"".join(parts)
    for part in parts:
        sink(part)
    return None


def int_rows(values: np.ndarray, literals: list[bytes], sink=None) -> bytes | None:
    """One row per row of ``values`` ``(n, c)`` (non-negative integers): ``literals[0]``, the first
    value in decimal, ``literals[1]``, ... , the last value, ``literals[c]``; ``c + 1`` literals.

    Same text as ``(literals[0] + "%d" + ... + literals[c]) % row`` for every row. Returned as
    bytes, or, with ``sink``, passed to ``sink(chunk)`` a chunk of rows at a time.
    """
    values = np.asarray(values, dtype=np.int64)
    n, c = values.shape
    if len(literals) != c + 1:
        raise ValueError(f"{c} values per row need {c + 1} literals, got {len(literals)}")
    if n and values.min() < 0:
        raise ValueError("int_rows writes non-negative integers only")
    width = len(str(int(values.max()))) if n else 1
    blocks = (values[s:s + ROWS_PER_CHUNK] for s in range(0, n, ROWS_PER_CHUNK))
    return _emit((_layout([_digits(b[:, j], width) for j in range(c)], literals) for b in blocks), sink)


def fixed_rows(values: np.ndarray, literals: list[bytes], decimals: int = 15, sink=None) -> bytes | None:
    """Like :func:`int_rows` for numbers ``|x| <= 1`` (unit normals), each written with at most
    ``decimals`` digits after the point: ``x`` rounded to the nearest multiple of ``10**-decimals``
    (so within ``0.5e-15`` plus one float64 rounding of ``x`` for 15), trailing zeros and a bare
    point dropped (``1``, ``-0.5``, ``0.123``); no ``-0``.
    """
    values = np.asarray(values, dtype=np.float64)
    n, c = values.shape
    if len(literals) != c + 1:
        raise ValueError(f"{c} values per row need {c + 1} literals, got {len(literals)}")
    if not 0 < decimals <= 15:
        raise ValueError(f"decimals must be 1..15, got {decimals}")
    if not (np.abs(values) <= 1.0).all():
        raise ValueError("fixed_rows writes numbers of magnitude at most 1")
    blocks = (values[s:s + ROWS_PER_CHUNK] for s in range(0, n, ROWS_PER_CHUNK))
    return _emit((_layout([_fixed(b[:, j], decimals) for j in range(c)], literals) for b in blocks), sink)


def _fixed(x: np.ndarray, decimals: int) -> np.ndarray:
    """``(n, 3 + decimals)`` uint8 NUL-padded fields (sign, whole digit, point, decimals) of the
    numbers ``x`` ``(n,)``, ``|x| <= 1``; trailing zero decimals, and then the point, are padding."""
    scale = 10 ** decimals
    m = np.rint(np.abs(x) * scale).astype(np.int64)
    frac = m % scale
    f = np.zeros((m.size, 3 + decimals), dtype=np.uint8)
    f[:, 0] = np.where((x < 0) & (m > 0), ord("-"), 0)
    f[:, 1] = m // scale + 48
    f[:, 2] = np.where(frac > 0, ord("."), 0)
    trailing = np.ones(m.size, dtype=bool)  # still inside the run of trailing zeros
    for w in range(decimals - 1, -1, -1):
        d = (frac % 10).astype(np.uint8)
        trailing &= d == 0
        f[:, 3 + w] = np.where(trailing, 0, d + 48)
        frac //= 10
    return f
