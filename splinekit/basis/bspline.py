"""Vectorized B-spline basis functions (The NURBS Book, A2.1-A2.3).

Every routine works on whole arrays of parameters at once; Python loops run
only over the degree. Internally basis values are laid out as ``(p + 1, m)``
(one contiguous row per local basis function), which keeps each step of the
Cox-de Boor triangle a contiguous vector operation; the public functions return
the conventional ``(m, p + 1)``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_degree, as_float_array, as_order, as_params
from ..errors import KnotVectorError
from .knots import domain, validate_knots

__all__ = ["find_span", "basis_funs", "basis_ders", "design_matrix"]


def find_span(degree: int, knots: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Knot span index ``i`` with ``U[i] <= u < U[i+1]`` for each ``u`` (A2.1).

    ``u`` at the right end of the domain belongs to the last non-empty span.
    Spans are clipped to the non-empty spans of the domain, so values
    marginally outside it are extrapolated from the end spans.
    Returns an int64 array shaped like ``u``.
    """
    lo, hi = span_bounds(degree, knots)
    span = np.searchsorted(knots, u, side="right") - 1
    return np.clip(span, lo, hi)


def span_bounds(degree: int, knots: np.ndarray) -> tuple[int, int]:
    """First and last non-empty knot spans of the domain ``[U[p], U[n]]``."""
    n = knots.size - degree - 1
    nonempty = np.flatnonzero(knots[degree:n] < knots[degree + 1 : n + 1]) + degree
    return int(nonempty[0]), int(nonempty[-1])


def _left_right(degree, knots, span, u):
    """``left[j] = u - U[span+1-j]``, ``right[j] = U[span+j] - u`` for j = 1..p."""
    j = np.arange(1, degree + 1)[:, None]
    left = u - knots[span - j + 1]
    right = knots[span + j] - u
    # index 0 unused; pad so that left[j], right[j] read like the book
    pad = np.zeros((1,) + np.shape(u))
    return np.concatenate([pad, left]), np.concatenate([pad, right])


def basis_funs_t(degree: int, knots: np.ndarray, span: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Non-zero basis functions ``N[span-p+r, p](u)`` as a ``(p + 1, m)`` array (A2.2)."""
    u = np.asarray(u, dtype=np.float64).ravel()
    span = np.asarray(span).ravel()
    left, right = _left_right(degree, knots, span, u)
    N = np.empty((degree + 1, u.size))
    N[0] = 1.0
    for j in range(1, degree + 1):
        saved = np.zeros(u.size)
        for r in range(j):
            temp = N[r] / (right[r + 1] + left[j - r])
            N[r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        N[j] = saved
    return N


def basis_ders_t(degree: int, knots: np.ndarray, span: np.ndarray, u: np.ndarray, order: int) -> np.ndarray:
    """Basis functions and derivatives as an ``(order + 1, p + 1, m)`` array (A2.3).

    Entry ``[k, r]`` is the k-th derivative of ``N[span-p+r, p]``; derivatives
    above the degree are zero.
    """
    p = degree
    u = np.asarray(u, dtype=np.float64).ravel()
    span = np.asarray(span).ravel()
    m = u.size
    if order == 0:
        return basis_funs_t(p, knots, span, u)[None]
    left, right = _left_right(p, knots, span, u)
    # ndu[j, r]: upper triangle holds basis values of rising degree, lower the knot differences
    ndu = np.empty((p + 1, p + 1, m))
    ndu[0, 0] = 1.0
    for j in range(1, p + 1):
        saved = np.zeros(m)
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    ders = np.zeros((order + 1, p + 1, m))
    ders[0] = ndu[:, p]
    top = min(order, p)
    a = np.empty((2, p + 1, m))
    for r in range(p + 1):
        s1, s2 = 0, 1
        a[0, 0] = 1.0
        for k in range(1, top + 1):
            d = np.zeros(m)
            rk, pk = r - k, p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d = d + a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d = d + a[s2, k] * ndu[r, pk]
            ders[k, r] = d
            s1, s2 = s2, s1
    factor = float(p)
    for k in range(1, top + 1):
        ders[k] *= factor
        factor *= p - k
    return ders


def basis_funs(degree: int, knots, span, u) -> np.ndarray:
    """Non-zero basis functions at each ``u``: ``(m, p + 1)``; column ``r`` is ``N[span-p+r]``."""
    return basis_funs_t(degree, np.asarray(knots, dtype=np.float64), span, u).T


def basis_ders(degree: int, knots, span, u, order: int) -> np.ndarray:
    """Non-zero basis derivatives: ``(order + 1, m, p + 1)``; ``[k, :, r]`` is d^k N[span-p+r]."""
    return basis_ders_t(degree, np.asarray(knots, dtype=np.float64), span, u, order).transpose(0, 2, 1)


def design_matrix(degree: int, knots, u, order: int = 0) -> sp.csr_matrix:
    """Collocation matrix ``A[i, j] = d^order N[j, p](u[i])`` as CSR ``(m, n)``.

    ``A @ control_points`` evaluates a non-rational spline (or its
    ``order``-th derivative) at ``u``; the same matrix serves fitting.
    Checks its arguments (the other functions here are the unchecked kernels).
    """
    degree = as_degree(degree)
    order = as_order(order)
    U = as_float_array(knots, "knots", KnotVectorError)
    if U.ndim != 1 or U.size < 2 * degree + 2:
        raise KnotVectorError(f"knots must be 1-D with at least 2 * degree + 2 = {2 * degree + 2} values, got shape {U.shape}")
    n = U.size - degree - 1
    U = validate_knots(U, degree, n)
    u = as_params(u, domain(degree, U), "u").ravel()
    span = find_span(degree, U, u)
    vals = basis_ders_t(degree, U, span, u, order)[order]  # (p+1, m)
    cols = span[None, :] - degree + np.arange(degree + 1)[:, None]
    rows = np.broadcast_to(np.arange(u.size), cols.shape)
    return sp.csr_matrix((vals.T.ravel(), (rows.T.ravel(), cols.T.ravel())), shape=(u.size, n))


def combine(coefs: np.ndarray, degree: int, span: np.ndarray, funs: np.ndarray) -> np.ndarray:
    """``sum_r funs[..., r, m] * coefs[span[m] - p + r]``.

    ``coefs`` is ``(n, ...)``; ``funs`` is ``(..., p + 1, m)``; returns
    ``(..., m) + coefs.shape[1:]``. One gather per local basis function: the
    loop runs over the degree only.
    """
    out = None
    base = span - degree
    trailing = (None,) * (coefs.ndim - 1)
    for r in range(degree + 1):
        rows = coefs[base + r]  # (m, ...)
        term = funs[(..., r, slice(None)) + trailing] * rows
        out = term if out is None else out + term
    return out
