"""Checked derivatives and unit tangents of any *curve object*: the helpers that
the rotation-minimizing frames (:mod:`.frames`) and the differential geometry
of curves (:mod:`splinekit.diffgeom.curves`) share.

A curve object is anything with ``.derivatives(u, order)`` returning
``(order + 1,) + u.shape + (dim,)`` (a splinekit curve or a
:class:`~splinekit.diffgeom.curves.ParametricCurve`); some helpers also use its
``.domain``, ``.control_points`` and ``.degree`` when it has them. The
thresholds are described in :mod:`splinekit.diffgeom.curves`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array
from ..errors import DomainError, ParameterError

_ZERO_DERIVATIVE = 1e-12  # relative size under which a derivative counts as zero


def _require_finite(values: np.ndarray, flat: np.ndarray, what: str):
    bad = ~np.isfinite(values)
    if bad.any():
        where = np.argwhere(bad)[0]
        i = where[-2] if values.ndim >= 2 else where[0]
        raise DomainError(f"{what} is not finite at u = {float(flat[i])!r}")


def _check_curve(curve):
    if not callable(getattr(curve, "derivatives", None)):
        raise ParameterError(
            f"curve must have a .derivatives(u, order) method (a splinekit curve or a ParametricCurve), "
            f"got {type(curve).__name__}"
        )


def _params(u, name: str = "u") -> np.ndarray:
    arr = as_float_array(u, name, DomainError)
    if not np.isfinite(arr).all():
        raise DomainError(f"{name} = {float(arr[~np.isfinite(arr)].ravel()[0])!r} is not finite")
    return arr


def _ders(curve, flat: np.ndarray, order: int) -> np.ndarray:
    """``curve.derivatives(flat, order)`` checked to be ``(order + 1, n, dim)`` and finite."""
    _check_curve(curve)
    d = as_float_array(curve.derivatives(flat, order), "curve.derivatives(u, order)")
    if d.ndim != 3 or d.shape[:2] != (order + 1, flat.size):
        raise ParameterError(
            f"curve.derivatives(u, {order}) must return shape ({order + 1}, {flat.size}, dim), got {d.shape}"
        )
    _require_finite(d, flat, "curve.derivatives(u, order)")
    return d


def _domain(curve) -> tuple[float, float]:
    dom = getattr(curve, "domain", None)
    if dom is None:
        raise ParameterError(f"curve must have a .domain (a, b); {type(curve).__name__} has none")
    a, b = (float(x) for x in dom)
    return a, b


def _scales(curve) -> tuple[float, float]:
    """``(size, length)``: the geometric size (at least 1) and the length of the parameter domain."""
    dom = getattr(curve, "domain", None)
    if dom is not None:
        a, b = (float(x) for x in dom)
        length = b - a if b > a else 1.0
    else:
        a = b = None
        length = 1.0
    P = getattr(curve, "control_points", None)
    if P is not None:
        size = float(np.abs(np.asarray(P, dtype=np.float64)).max())
    elif a is not None:
        size = float(np.abs(_ders(curve, np.linspace(a, b, 33), 0)[0]).max())
    else:
        size = 1.0
    return max(size, 1.0), length


def _max_fallback_order(curve) -> int:
    """Highest derivative order inspected when ``C'`` vanishes: the degree of a
    splinekit curve (a polynomial span has no non-zero derivative beyond it),
    else 3."""
    degree = getattr(curve, "degree", None)
    if isinstance(degree, (int, np.integer)) and degree >= 1:
        return max(int(degree), 2)
    return 3


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products ``(n,)`` of ``(n, k)`` arrays."""
    return np.einsum("ij,ij->i", a, b)


def _norm(v: np.ndarray) -> np.ndarray:
    """Euclidean norms of the rows of ``v``: ``(n,)`` for ``(n, k)``, or ``(m, n)`` for ``(m, n, k)``."""
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of broadcastable ``(..., 3)`` arrays (cheaper than ``np.cross`` on small rows)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _unit(v: np.ndarray, norms: np.ndarray | None = None) -> np.ndarray:
    if norms is None:
        norms = _norm(v)
    return np.divide(v, norms[..., None], out=np.zeros_like(v), where=norms[..., None] > 0)


def _tangents(curve, flat: np.ndarray, d1: np.ndarray, size: float, length: float):
    """Unit tangents ``(n, dim)`` and a mask of where one exists."""
    norms = _norm(d1)
    regular = norms > _ZERO_DERIVATIVE * size / length
    T = _unit(d1, np.where(regular, norms, 0.0))
    defined = regular.copy()
    if not regular.all():
        idx = np.flatnonzero(~regular)
        K = _max_fallback_order(curve)
        higher = _ders(curve, flat[idx], K)[2:]  # C'' ... C^(K)
        hn = _norm(higher)
        usable = hn > _ZERO_DERIVATIVE * size / length ** np.arange(2, K + 1)[:, None]
        first = usable.argmax(axis=0)
        found = usable.any(axis=0)
        m = np.arange(idx.size)
        T[idx] = np.where(found[:, None], _unit(higher[first, m], hn[first, m]), 0.0)
        defined[idx] = found
    return T, defined, regular


def _require_regular(regular: np.ndarray, flat: np.ndarray, what: str):
    if not regular.all():
        u0 = float(flat[np.flatnonzero(~regular)[0]])
        raise DomainError(
            f"the first derivative vanishes at u = {u0!r} (a singular parametrization); {what} is undefined there"
        )


def _as_3d(v: np.ndarray, what: str) -> np.ndarray:
    """``(n, 3)``: 3-D vectors as they are, planar ones embedded in the plane z = 0."""
    if v.shape[-1] == 3:
        return v
    if v.shape[-1] == 2:
        return np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)
    raise ParameterError(f"{what} needs a 2-D or 3-D curve, got dim={v.shape[-1]}")


def _perpendicular(T: np.ndarray) -> np.ndarray:
    """A unit vector ``(n, 3)`` orthogonal to each unit ``T``: the coordinate axis
    least aligned with ``T`` (the first such axis on ties), made orthogonal to ``T``."""
    axis = np.abs(T).argmin(axis=-1)
    e = np.zeros_like(T)
    e[np.arange(T.shape[0]), axis] = 1.0
    e -= _dot(e, T)[:, None] * T
    return _unit(e)

