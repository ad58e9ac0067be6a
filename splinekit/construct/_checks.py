"""Argument checks shared by the construction functions (vectors, axes, curves)."""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_real
from ..curves import SplineCurve
from ..errors import ParameterError


def as_vector(value, name: str, dims=(2, 3)) -> np.ndarray:
    """A finite point or vector ``(dim,)`` with ``dim`` in ``dims``."""
    arr = as_float_array(value, name, ParameterError)
    if arr.ndim != 1 or arr.shape[0] not in dims:
        want = " or ".join(f"({d},)" for d in dims)
        raise ParameterError(f"{name} must have shape {want}, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ParameterError(f"{name} = {arr.tolist()} is not finite")
    return np.array(arr, dtype=np.float64)


def as_unit(value, name: str, dims=(3,)) -> np.ndarray:
    """A non-zero vector normalized to unit length."""
    vec = as_vector(value, name, dims)
    length = float(np.linalg.norm(vec))
    if length == 0.0:
        raise ParameterError(f"{name} = {vec.tolist()} has zero length; a direction is needed")
    if not np.isfinite(length) or length < 1e-150:
        raise ParameterError(f"{name} = {vec.tolist()} is too short (or too long) to normalize")
    return vec / length


def as_positive(value, name: str) -> float:
    """A finite number > 0."""
    x = as_real(value, name)
    if not x > 0:
        raise ParameterError(f"{name} must be > 0, got {x!r}")
    return x


def as_curve(value, name: str):
    """A splinekit B-spline or NURBS curve."""
    if not isinstance(value, SplineCurve):
        raise ParameterError(f"{name} must be a BSplineCurve or NurbsCurve, got {type(value).__name__}")
    return value


def perpendicular(normal: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to the unit 3-vector ``normal``.

    Built from the coordinate axis least aligned with ``normal`` so that the
    choice is deterministic and well conditioned.
    """
    e = np.zeros(3)
    e[int(np.argmin(np.abs(normal)))] = 1.0
    x = e - np.dot(e, normal) * normal
    return x / np.linalg.norm(x)


def plane_frame(normal, x_axis, dim: int, x_name: str = "x_axis"):
    """Orthonormal in-plane axes ``(X, Y)`` ``(dim,)`` each.

    In 3-D, ``normal`` is required and ``(X, Y, normal)`` is right-handed; ``X``
    is ``x_axis`` with its component along ``normal`` removed (default: a
    deterministic perpendicular). In 2-D, ``normal`` must be None and ``X``
    defaults to ``(1, 0)``; ``Y`` is ``X`` turned by +90 degrees.
    """
    if dim == 2:
        if normal is not None:
            raise ParameterError("a 2-D construction takes no normal (pass normal=None)")
        X = np.array([1.0, 0.0]) if x_axis is None else as_unit(x_axis, x_name, (2,))
        return X, np.array([-X[1], X[0]])
    if normal is None:
        raise ParameterError("a 3-D construction needs the plane normal")
    n = as_unit(normal, "normal")
    if x_axis is None:
        X = perpendicular(n)
    else:
        raw = as_unit(x_axis, x_name)
        X = raw - np.dot(raw, n) * n
        length = float(np.linalg.norm(X))
        if length < 1e-9:
            raise ParameterError(f"{x_name} = {np.asarray(x_axis).tolist()} is parallel to the normal; it must lie in the plane")
        X = X / length
    Y = np.cross(n, X)
    return X, Y / np.linalg.norm(Y)
