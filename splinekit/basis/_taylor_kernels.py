"""Compiled curve kernels on the per-span Taylor table (numba, ``cache=True``).

Loaded only through :func:`splinekit._kernels.load`. The table comes from
:func:`splinekit.basis.taylor.span_taylor`: per point, a span lookup (the previous
point's span is tried first, so sorted parameters cost two comparisons, scattered ones
a binary search over the breakpoints) and a Horner sum of ``p`` multiply-adds per
coordinate, instead of A2.2's ``p (p + 1) / 2`` divisions and ``p + 1`` products per
coordinate. Results agree with the numpy path (A2.2) to rounding, not bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

_CHUNK = 4096


@njit(cache=True, inline="always")
def _piece(breaks, x, hint):
    """Span ``s`` with ``breaks[s] <= x < breaks[s + 1]``, clipped to ``[0, S - 1]``."""
    last = breaks.shape[0] - 2
    if breaks[hint] <= x and x < breaks[hint + 1]:
        return hint
    if x >= breaks[last]:
        return last
    if x < breaks[1]:
        return 0
    a, b = 0, last
    while b - a > 1:
        mid = (a + b) // 2
        if breaks[mid] <= x:
            a = mid
        else:
            b = mid
    return a


@njit(cache=True, parallel=True)
def curve_points(breaks, table, u, rational, out):
    """``out[m, :dim]``: the curve at ``u[m]`` from ``table[0]`` (divided by the weight if rational)."""
    m = u.shape[0]
    p = table.shape[2] - 1
    k = table.shape[3]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        acc = np.empty(k)
        s = 0
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            s = _piece(breaks, u[i], s)
            x = u[i] - breaks[s]
            for d in range(k):
                acc[d] = table[0, s, p, d]
            for j in range(p - 1, -1, -1):
                for d in range(k):
                    acc[d] = acc[d] * x + table[0, s, j, d]
            if rational:
                inv = 1.0 / acc[k - 1]
                for d in range(k - 1):
                    out[i, d] = acc[d] * inv
            else:
                for d in range(k):
                    out[i, d] = acc[d]


@njit(cache=True, parallel=True)
def curve_derivatives(breaks, table, u, order, rational, binom, out):
    """Derivatives 0..order at each ``u``: ``out`` is ``(order + 1, m, dim)``.

    Homogeneous derivatives by Horner from ``table[r]`` (zero above the degree), then, if
    ``rational``, the quotient rule of A4.2 (``binom[k, i] = C(k, i)``) as in
    :func:`splinekit.basis.rational.rational_curve_derivatives`.
    """
    m = u.shape[0]
    p = table.shape[2] - 1
    kdim = table.shape[3]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        h = np.zeros((order + 1, kdim))  # rows above the degree stay zero
        s = 0
        top = min(order, p)
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            s = _piece(breaks, u[i], s)
            x = u[i] - breaks[s]
            for r in range(top + 1):
                for d in range(kdim):
                    acc = table[r, s, p - r, d]
                    for j in range(p - r - 1, -1, -1):
                        acc = acc * x + table[r, s, j, d]
                    h[r, d] = acc
            if not rational:
                for r in range(order + 1):
                    for d in range(kdim):
                        out[r, i, d] = h[r, d]
                continue
            # the quotient rule of _numba_kernels.curve_derivatives, repeated here: numba's disk
            # cache keys a kernel on its own file, so a helper shared across files could go stale
            w0 = h[0, kdim - 1]
            for r in range(order + 1):
                for d in range(kdim - 1):
                    v = h[r, d]
                    for j in range(1, r + 1):
                        v -= binom[r, j] * h[j, kdim - 1] * out[r - j, i, d]
                    out[r, i, d] = v / w0
