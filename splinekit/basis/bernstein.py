"""Bernstein polynomials, computed by the stable triangular scheme.

``B_i^n(t) = C(n, i) t^i (1 - t)^(n - i)``. The values come from the same
Cox-de Boor triangle as the B-spline basis on the Bézier knot vector
``[0]*(n+1) + [1]*(n+1)``, which for t in [0, 1] only forms convex
combinations and so stays accurate at high degree (no large binomials).
"""

from __future__ import annotations

import numpy as np

from .._validate import MAX_DEGREE, as_float_array, as_int, as_order
from ..errors import DegreeError, DomainError
from .bspline import basis_ders_t, basis_funs_t

__all__ = ["bernstein", "all_bernstein", "bezier_knots"]


def bezier_knots(degree: int) -> np.ndarray:
    """The knot vector ``[0]*(p+1) + [1]*(p+1)`` of a degree-``p`` Bézier segment."""
    return np.concatenate([np.zeros(degree + 1), np.ones(degree + 1)])


def _finite(t: np.ndarray, n: int) -> np.ndarray:
    """``t`` checked: finite, and close enough to [0, 1] for degree ``n``.

    Outside [0, 1] the triangle extrapolates; its denominators ``(b - t) + (t - a)``
    lose every digit once ``|t|`` nears 2**53, and the values ``~ (2 |t|)**n``
    overflow beyond ``0.5 * 10**(300 / n)``, so ``|t|`` is limited to the smaller.
    """
    if not np.isfinite(t).all():
        bad = float(t[~np.isfinite(t)].ravel()[0])
        raise DomainError(f"t = {bad!r} is not finite")
    limit = min(1e15, 0.5 * 10 ** (300 / max(n, 1)))
    far = np.abs(t) > limit
    if far.any():
        bad = float(t[far].ravel()[0])
        raise DomainError(f"t = {bad!r} is too far outside [0, 1] for degree {n} (|t| <= {limit:.3g})")
    return t


def all_bernstein(n: int, t, order: int = 0) -> np.ndarray:
    """All degree-``n`` Bernstein polynomials (and derivatives) at ``t``.

    Returns ``(n + 1,) + t.shape`` for ``order == 0``, else
    ``(order + 1, n + 1) + t.shape``. Valid for any real ``t`` (polynomial
    extension outside [0, 1]).
    """
    n = as_int(n, "n", minimum=0)
    if n > MAX_DEGREE:
        raise DegreeError(f"n = {n} exceeds the largest supported degree {MAX_DEGREE}")
    order = as_order(order)
    t = _finite(as_float_array(t, "t"), n)
    shape = t.shape
    flat = t.ravel()
    if n == 0:
        vals = np.ones((1, flat.size))
        out = vals if order == 0 else np.concatenate([vals[None], np.zeros((order, 1, flat.size))])
    else:
        span = np.full(flat.size, n)
        if order == 0:
            out = basis_funs_t(n, bezier_knots(n), span, flat)
        else:
            out = basis_ders_t(n, bezier_knots(n), span, flat, order)
    return out.reshape(out.shape[:-1] + shape)


def bernstein(n: int, i: int, t) -> np.ndarray:
    """Bernstein basis polynomial ``B_i^n`` at the array ``t`` (shape of ``t``).

    ``B_i^n`` is identically zero for ``i < 0`` or ``i > n``.
    """
    n = as_int(n, "n", minimum=0)
    if n > MAX_DEGREE:
        raise DegreeError(f"n = {n} exceeds the largest supported degree {MAX_DEGREE}")
    i = as_int(i, "i")
    t = _finite(as_float_array(t, "t"), n)
    if i < 0 or i > n:
        return np.zeros(t.shape)
    return all_bernstein(n, t)[i]
