"""The result of a projection and the checks of its inputs (query points, tolerance)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_float_array, as_positive
from ..errors import ParameterError

__all__ = ["Projection"]

MAX_COORDINATE = 1e150
"""Largest absolute coordinate of a query point, in units of the geometry's size
when that exceeds ``LARGE`` (else in model units): squared distances (k-d tree,
Newton residuals) must stay within the float range."""


@dataclass(frozen=True, eq=False)
class Projection:
    """Closest points of a batch of points.

    Attributes
    ----------
    parameters : ndarray or None
        Curve parameters ``(n,)``, surface parameters ``(n, 2)`` as ``(u, v)``
        pairs, or ``None`` for an implicit surface.
    points : ndarray, shape (n, dim)
        The closest points on the geometry.
    distances : ndarray, shape (n,)
        Euclidean distances from the input points to ``points`` (model units).

    For input points of shape ``shape + (dim,)`` the leading ``(n,)`` above is
    ``shape``.
    """

    parameters: np.ndarray | None
    points: np.ndarray
    distances: np.ndarray


def _readonly(arr):
    arr = np.array(arr, dtype=np.float64, order="C")  # a copy; keeps 0-d results 0-d
    arr.setflags(write=False)
    return arr


def _as_query_points(points, dim: int, unit: float = 1.0):
    """``points / unit`` as a finite ``(n, dim)`` array and its leading shape."""
    P = as_float_array(points, "points", ParameterError)
    if P.ndim == 0 or P.shape[-1] != dim:
        raise ParameterError(
            f"points must have shape (n, {dim}) for this {dim}-D geometry, got an array of shape {P.shape}"
        )
    lead = P.shape[:-1]
    P = P.reshape(-1, dim)
    bad = ~np.isfinite(P).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        index = tuple(int(j) for j in np.unravel_index(i, lead)) if lead else ()
        raise ParameterError(f"points{list(index)} = {P[i].tolist()} is not finite")
    far = np.abs(P).max(axis=1, initial=0.0) > MAX_COORDINATE * unit
    if far.any():
        i = int(np.flatnonzero(far)[0])
        index = tuple(int(j) for j in np.unravel_index(i, lead)) if lead else ()
        raise ParameterError(
            f"points{list(index)} = {P[i].tolist()} has a coordinate beyond {MAX_COORDINATE * unit:g}: "
            "squared distances would overflow"
        )
    return np.ascontiguousarray(P / unit), lead


def _positive_tolerance(value) -> float:
    return as_positive(value, "tolerance")
