"""Input checks shared by the implicit modules: points, bounding boxes, grid origins and spacings,
positive numbers."""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_positive
from ..errors import ParameterError

__all__ = ["check_bounds", "check_points", "origin3", "positive", "spacing3"]


def check_points(points, name: str = "points") -> np.ndarray:
    """``points`` as a C-contiguous finite float64 ``(n, 3)`` array (a single
    ``(3,)`` point becomes ``(1, 3)``); a ParameterError naming the first
    non-finite point and its index otherwise."""
    p = as_float_array(points, name)
    if p.ndim == 1 and p.shape[0] == 3:
        p = p[None, :]
    if p.ndim != 2 or p.shape[1] != 3:
        raise ParameterError(f"{name} must be an (n, 3) array of 3-D points, got shape {p.shape}")
    finite = np.isfinite(p).all(axis=1)
    if not finite.all():
        i = int(np.argmin(finite))
        raise ParameterError(f"{name}[{i}] = {p[i].tolist()} is not finite")
    return np.ascontiguousarray(p)


def check_bounds(bounds, name: str = "bounds"):
    """``(lo (3,), hi (3,))`` read-only float arrays with finite ``lo <= hi``, or None."""
    if bounds is None:
        return None
    try:
        lo, hi = bounds
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a pair (lo, hi) of 3-D points, got {bounds!r}") from None
    lo = as_float_array(lo, f"{name} lo")
    hi = as_float_array(hi, f"{name} hi")
    if lo.shape != (3,) or hi.shape != (3,):
        raise ParameterError(f"{name} must be (lo, hi) with two 3-D points, got shapes {lo.shape} and {hi.shape}")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ParameterError(f"{name} must be finite, got lo={lo.tolist()}, hi={hi.tolist()}")
    if not (lo <= hi).all():
        axis = int(np.argmax(~(lo <= hi)))
        raise ParameterError(f"{name} must have lo <= hi; axis {axis} has lo={float(lo[axis])!r} > hi={float(hi[axis])!r}")
    lo, hi = lo.copy(), hi.copy()
    lo.setflags(write=False)
    hi.setflags(write=False)
    return lo, hi


positive = as_positive  # the shared validator, under the name the implicit modules use


def spacing3(spacing) -> np.ndarray:
    arr = as_float_array(spacing, "spacing")
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,) or not (np.isfinite(arr).all() and (arr > 0).all()):
        raise ParameterError(f"spacing must be a number or 3 finite numbers > 0, got {spacing!r}")
    return arr.astype(np.float64)


def origin3(origin) -> np.ndarray:
    arr = as_float_array(origin, "origin")
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ParameterError(f"origin must be 3 finite numbers, got {origin!r}")
    return arr.astype(np.float64)
