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


def int_rows(values: np.ndarray, literals: list[bytes]) -> bytes:
    """One row per row of ``values`` ``(n, c)`` (non-negative integers): ``literals[0]``, the first
    value in decimal, ``literals[1]``, ... , the last value, ``literals[c]``; ``c + 1`` literals.

    Same text as ``(literals[0] + "%d" + ... + literals[c]) % row`` for every row.
    """
    values = np.asarray(values, dtype=np.int64)
    n, c = values.shape
    if len(literals) != c + 1:
        raise ValueError(f"{c} values per row need {c + 1} literals, got {len(literals)}")
    if not n:
        return b""
    if values.min() < 0:
        raise ValueError("int_rows writes non-negative integers only")
    width = len(str(int(values.max())))
    parts = []
    for s in range(0, n, ROWS_PER_CHUNK):
        block = values[s:s + ROWS_PER_CHUNK]
        parts.append(_layout([_digits(block[:, j], width) for j in range(c)], literals))
    return b"".join(parts)


def fixed_rows(values: np.ndarray, literals: list[bytes], decimals: int = 15) -> bytes:
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
    if not n:
        return b""
    if not (np.abs(values) <= 1.0).all():
        raise ValueError("fixed_rows writes numbers of magnitude at most 1")
    scale = 10 ** decimals
    parts = []
    for s in range(0, n, ROWS_PER_CHUNK):
        block = values[s:s + ROWS_PER_CHUNK]
        fields = []
        for j in range(c):
            m = np.rint(np.abs(block[:, j]) * scale).astype(np.int64)
            whole, frac = m // scale, m % scale
            f = np.zeros((m.size, 3 + decimals), dtype=np.uint8)  # sign, whole digit, point, decimals
            f[:, 0] = np.where((block[:, j] < 0) & (m > 0), ord("-"), 0)
            f[:, 1] = whole + 48
            # the decimals, zero-padded on the left, then trailing zeros turned to padding
            digits = np.empty((m.size, decimals), dtype=np.uint8)
            v = frac.copy()
            trailing = np.ones(m.size, dtype=bool)  # still inside the run of trailing zeros
            for w in range(decimals - 1, -1, -1):
                d = (v % 10).astype(np.uint8)
                trailing &= d == 0
                digits[:, w] = np.where(trailing, 0, d + 48)
                v //= 10
            f[:, 3:] = digits
            f[:, 2] = np.where(frac > 0, ord("."), 0)
            fields.append(f)
        parts.append(_layout(fields, literals))
    return b"".join(parts)
