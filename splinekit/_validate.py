"""Input checks shared by every constructor and operation.

Each function converts its argument to a C-contiguous float64 (or int) array of
the expected shape and raises a :class:`~splinekit.errors.SplineKitError`
subclass naming the argument when it cannot.
"""

from __future__ import annotations

import operator
import os

import numpy as np

from .errors import (
    ControlPointError,
    DegreeError,
    DomainError,
    ParameterError,
    WeightError,
)
from .tolerances import DEFAULT


def as_float_array(value, name: str, error=ParameterError) -> np.ndarray:
    """``value`` as a float64 array; booleans, integers and floats only.

    Strings and complex numbers are refused rather than parsed or truncated.
    """
    try:
        raw = np.asarray(value)
        if raw.dtype.kind in "biuf":
            return raw.astype(np.float64, copy=False)
        if raw.dtype.kind == "O":
            return raw.astype(np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise error(f"{name} must be real numbers, got {type(value).__name__}: {exc}") from None
    raise error(f"{name} must be real numbers, got an array of dtype {raw.dtype}")


def as_int(value, name: str, minimum: int | None = None, error=ParameterError) -> int:
    """Return ``value`` as a Python int, refusing floats such as 2.5 and bools."""
    if isinstance(value, bool):
        raise error(f"{name} must be an integer, got bool {value!r}")
    try:
        result = operator.index(value)
    except TypeError:
        raise error(f"{name} must be an integer, got {value!r}") from None
    if minimum is not None and result < minimum:
        raise error(f"{name} must be >= {minimum}, got {result}")
    return int(result)


def as_indices(value, name: str, count: int | None = None, error=ParameterError, range_error=None) -> np.ndarray:
    """Integer indices as an int64 array of ``value``'s shape.

    Refuses what is not an integer (``0.5``, and also ``1.0``, ``True``, ``"0"``,
    NaN) with ``error``; with ``count``, an index outside ``0 .. count - 1``
    (including one beyond int64) with ``range_error`` (default ``error``).
    """
    range_error = error if range_error is None else range_error
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError, OverflowError):  # ragged or unconvertible
        raise error(f"{name} must be integer indices, got {value!r}") from None
    if arr.dtype == object:  # Python ints beyond int64, or mixed objects
        flat = arr.ravel().tolist()
        for x in flat:
            if isinstance(x, bool) or not hasattr(x, "__index__"):
                raise error(f"{name} must be integer indices, got {x!r}")
        big = [int(x) for x in flat if not -(2**63) <= int(x) < 2**63]
        if big:
            raise range_error(f"{name} {big[0]} is outside 0..{'' if count is None else count - 1}")
        arr = np.array([int(x) for x in flat], dtype=np.int64).reshape(arr.shape)
    if arr.size and arr.dtype.kind not in "iu":
        raise error(f"{name} must be integer indices, got {arr.ravel()[0]!r} (dtype {arr.dtype})")
    if arr.dtype.kind == "u" and arr.size and arr.max() > np.iinfo(np.int64).max:
        raise range_error(f"{name} {int(arr.max())} is outside 0..{'' if count is None else count - 1}")
    arr = arr.astype(np.int64)
    if count is not None and arr.size:
        bad = (arr < 0) | (arr >= count)
        if bad.any():
            raise range_error(f"{name} {int(arr[bad][0])} is outside 0..{count - 1}")
    return arr


def as_path(value, name: str = "path") -> str | bytes:
    """A file-system path (``str``, ``bytes`` or ``os.PathLike``) as ``os.fspath`` gives it.

    Refuses with ParameterError what the operating system would refuse with a
    bare ValueError or TypeError: a non-path, an empty path, a NUL byte.
    """
    try:
        path = os.fspath(value)
    except TypeError:
        raise ParameterError(f"{name} must be a str, bytes or os.PathLike, got {type(value).__name__}") from None
    if len(path) == 0:
        raise ParameterError(f"{name} is empty")
    if ("\0" if isinstance(path, str) else b"\0") in path:
        raise ParameterError(f"{name} {path!r} contains a NUL byte, which no file name may hold")
    return path


MAX_DEGREE = 128
"""Largest degree (and derivative order) accepted. Cost grows like p**2 per
point (p**3 for derivatives) and Bernstein coefficients of higher degree are
far beyond double precision; OpenCascade stops at 25."""


def as_degree(value, name: str = "degree") -> int:
    """A polynomial degree: an integer in ``[1, MAX_DEGREE]``."""
    degree = as_int(value, name, minimum=1, error=DegreeError)
    if degree > MAX_DEGREE:
        raise DegreeError(f"{name} = {degree} exceeds the largest supported degree {MAX_DEGREE}")
    return degree


def as_points(value, name: str = "control_points", leading: int = 1, min_count=None) -> np.ndarray:
    """Control points as a float64 array of shape ``(n_1, ..., n_leading, dim)``.

    ``leading`` is the number of index axes (1 for curves, 2 for surfaces).
    ``min_count`` is a tuple of minimum lengths of the index axes.
    """
    arr = as_float_array(value, name, ControlPointError)
    if arr.ndim != leading + 1:
        axes = ", ".join(["n"] * leading if leading == 1 else ["nu", "nv"])
        raise ControlPointError(
            f"{name} must have shape ({axes}, dim), got an array of shape {arr.shape}"
        )
    if arr.shape[-1] < 1:
        raise ControlPointError(f"{name} must have at least one coordinate, got shape {arr.shape}")
    if min_count is not None:
        for axis, (have, need) in enumerate(zip(arr.shape[:-1], min_count)):
            if have < need:
                raise ControlPointError(
                    f"{name} needs at least {need} points along axis {axis}, got {have}"
                )
    bad = ~np.isfinite(arr)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0][:-1])
        raise ControlPointError(f"{name}{list(index)} is not finite: {arr[index].tolist()}")
    return np.ascontiguousarray(arr)


def as_weights(value, shape: tuple, name: str = "weights") -> np.ndarray:
    """Rational weights: finite, strictly positive, of the given shape."""
    arr = as_float_array(value, name, WeightError)
    if arr.shape != tuple(shape):
        raise WeightError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    bad = ~(np.isfinite(arr) & (arr > 0))
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise WeightError(
            f"{name}{list(index)} = {float(arr[index])!r}: weights must be finite and > 0"
        )
    return np.ascontiguousarray(arr)


def homogeneous(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``(w * P, w)`` with the weight as the last column; refuses overflow."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.concatenate([points * weights[..., None], weights[..., None]], axis=-1)
    if not np.isfinite(out).all():
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0][:-1])
        raise ControlPointError(f"weight times control point {list(index)} overflows the float range")
    return out


def finite_points(points: np.ndarray, what: str) -> np.ndarray:
    """``points`` unchanged if finite, else a ControlPointError saying ``what`` overflowed."""
    if not np.isfinite(points).all():
        raise ControlPointError(f"{what} gives non-finite control points (overflow)")
    return points


def overflow_safe(geometry, compute, points: np.ndarray, lead: int) -> np.ndarray:
    """``compute(geometry)`` without overflow: evaluated on ``geometry._scaled(-k)``
    (coordinates times ``2**-k``, exact, ``k`` such that every control point is
    below 1 in size) and scaled back by ``2**k``.

    ``compute`` returns points ``(..., dim)`` (``lead`` = 0) or derivatives with
    ``lead`` leading order axes (1 for curves, 2 for surfaces), whose entry
    ``[0]`` (``[0, 0]``) holds the points. Points are convex combinations of the
    control ``points`` ``(..., dim)``: they are clipped to the control points'
    bounding box, which holds the exact point (so only rounding is removed), and
    are always finite. A derivative whose true size exceeds the float range
    raises DomainError.
    """
    flat = points.reshape(-1, points.shape[-1])
    k = int(np.frexp(max(float(np.abs(flat).max()), 1.0))[1])  # max |P| < 2**k
    lo, hi = np.ldexp(flat.min(axis=0), -k), np.ldexp(flat.max(axis=0), -k)
    out = np.array(compute(geometry._scaled(-k)), dtype=np.float64)
    first = (0,) * lead
    out[first] = np.clip(out[first], lo, hi)
    with np.errstate(over="ignore"):
        out = np.ldexp(out, k)
    if not np.isfinite(out).all():
        raise DomainError(
            "a derivative exceeds the float range (about 1.8e308) at the requested parameters; scale the geometry down"
        )
    return out


def as_params(value, domain: tuple, name: str = "u", rtol: float = DEFAULT.param) -> np.ndarray:
    """Parameters as a float64 array of any shape, checked to lie in ``domain``.

    Values within ``rtol * (b - a)`` outside ``[a, b]`` are clamped onto it;
    anything further out, or non-finite, raises :class:`DomainError`.
    """
    arr = as_float_array(value, name, DomainError)
    a, b = domain
    slack = rtol * max(b - a, 1.0)
    ok = (arr >= a - slack) & (arr <= b + slack)  # False for NaN
    if not ok.all():
        bad = float(arr[~ok].ravel()[0])
        raise DomainError(f"{name} = {bad!r} lies outside the parameter domain [{a!r}, {b!r}]")
    return np.clip(arr, a, b)


def as_real(value, name: str, error=ParameterError) -> float:
    """A single finite real number."""
    arr = as_float_array(value, name, error)
    if arr.ndim != 0:
        raise error(f"{name} must be a single number, got an array of shape {arr.shape}")
    x = float(arr)
    if not np.isfinite(x):
        raise error(f"{name} must be finite, got {x!r}")
    return x


def as_positive(value, name: str, allow_zero: bool = False) -> float:
    """A finite real ``> 0`` (or ``>= 0`` with ``allow_zero``): sizes, radii, tolerances."""
    x = as_real(value, name)
    if not (x > 0 or (allow_zero and x == 0)):
        raise ParameterError(f"{name} must be {'>= 0' if allow_zero else '> 0'}, got {x!r}")
    return x


def as_order(value, name: str = "order") -> int:
    """A derivative order: an integer in ``[0, MAX_DEGREE]``."""
    order = as_int(value, name, minimum=0)
    if order > MAX_DEGREE:
        raise ParameterError(f"{name} = {order} exceeds the largest supported derivative order {MAX_DEGREE}")
    return order


def as_direction(value) -> int:
    """``"u"`` -> 0, ``"v"`` -> 1."""
    if value in ("u", "U", 0):
        return 0
    if value in ("v", "V", 1):
        return 1
    raise ParameterError(f"direction must be 'u' or 'v', got {value!r}")


def as_affine(matrix, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Split an affine map into (linear ``(dim, dim)``, translation ``(dim,)``).

    Accepts a ``(dim, dim)`` linear map or a ``(dim + 1, dim + 1)`` homogeneous
    matrix whose last row is ``[0, ..., 0, 1]``.
    """
    m = as_float_array(matrix, "matrix")
    if not np.isfinite(m).all():
        raise ParameterError("matrix has non-finite entries")
    if m.shape == (dim, dim):
        return m, np.zeros(dim)
    if m.shape == (dim + 1, dim + 1):
        expected = np.zeros(dim + 1)
        expected[-1] = 1.0
        if not np.allclose(m[-1], expected, rtol=0, atol=1e-12):
            raise ParameterError(
                f"the last row of a homogeneous matrix must be {expected.tolist()}, got {m[-1].tolist()}"
            )
        return m[:dim, :dim], m[:dim, dim]
    raise ParameterError(
        f"matrix must have shape ({dim}, {dim}) or ({dim + 1}, {dim + 1}) for {dim}-D points, got {m.shape}"
    )


def frozen(arr: np.ndarray) -> np.ndarray:
    """A read-only, C-contiguous float64 copy-if-needed of ``arr``."""
    out = np.array(arr, dtype=np.float64, order="C", copy=True)
    out.setflags(write=False)
    return out
