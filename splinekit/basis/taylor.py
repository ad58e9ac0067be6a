"""A spline as one polynomial per non-empty knot span (Taylor form at the span's left end).

On span ``s`` (``a_s <= u < a_(s+1)``) a degree-``p`` spline is the polynomial
``C(u) = sum_j c_sj x^j`` with ``x = u - a_s`` and ``c_sj = C^(j)(a_s+) / j!``. Evaluating
that form takes ``p`` multiply-adds per coordinate and no division, where the
Cox-de Boor triangle (A2.2) takes ``p (p + 1) / 2`` divisions and the sum over
``p + 1`` control points; so the compiled curve kernels evaluate from this table,
built once per curve (the curve is immutable and caches it).

The form is well conditioned for the low degrees of CAD curves: converting the
local Bernstein form into powers of ``x`` amplifies rounding by at most about
``2^p`` (``x`` never leaves ``[0, h_s]``), so it is used up to :data:`MAX_DEGREE`.
"""

from __future__ import annotations

from math import factorial

import numpy as np

from .bspline import basis_ders_t, combine

__all__ = ["MAX_DEGREE", "span_taylor"]

MAX_DEGREE = 5
"""Highest degree evaluated through the Taylor table: rounding grows like ``2^p`` times the
coefficients' size (tests/test_curve_taylor.py holds it to 1e-13 of it); higher degrees keep the
A2.2 kernels."""


def span_taylor(degree: int, knots: np.ndarray, coefs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints and Taylor coefficients of every derivative on every non-empty span.

    Parameters
    ----------
    degree : int, ``p``
    knots : ``(n + p + 1,)`` float64, a valid knot vector
    coefs : ``(n, k)`` float64 (homogeneous for a rational curve)

    Returns
    -------
    breaks : ``(S + 1,)`` the left ends of the ``S`` non-empty spans of the domain, then its right end
    table : ``(p + 1, S, p + 1, k)``; ``table[r, s, j]`` is the coefficient of ``x^j`` in the
        ``r``-th derivative on span ``s`` (``x = u - breaks[s]``): ``C^(r + j)(breaks[s]+) / j!``,
        zero where ``r + j > p``.
    """
    p = degree
    n = knots.size - p - 1
    spans = np.flatnonzero(knots[p:n] < knots[p + 1 : n + 1]) + p
    left = knots[spans]
    breaks = np.append(left, knots[spans[-1] + 1])
    # all derivatives from the right at each span's left end: (p + 1, S, k)
    ders = combine(coefs, p, spans, basis_ders_t(p, knots, spans, left, p))
    table = np.zeros((p + 1, spans.size, p + 1, coefs.shape[1]))
    for r in range(p + 1):
        for j in range(p + 1 - r):
            table[r, :, j] = ders[r + j] / factorial(j)
    return breaks, table
