"""Differential geometry of curves: tangents, curvature, torsion, frames, arc length.

Every function takes a *curve object* and arrays of parameters. A curve object
is anything with ``.derivatives(u, order)`` returning ``(order + 1,) + u.shape +
(dim,)`` (``C, C', ..., C^(order)``): the splinekit :class:`~splinekit.BezierCurve`,
:class:`~splinekit.BSplineCurve` and :class:`~splinekit.NurbsCurve`, or a
:class:`ParametricCurve` wrapping plain numpy functions. Arc-length functions
also need its ``.domain`` ``(a, b)``.

Units: parameters are in the curve's parameter units; curvature and torsion in
1 / length; arc length in length units. Derivatives are taken with respect to
the curve's own parameter unless stated otherwise.

Conventions at degenerate points (never a NaN):

* *Singular parametrization* (``|C'| = 0``): :func:`tangent` uses the first
  non-vanishing higher derivative (as ``curve.tangent`` does); quantities that
  need ``C'`` itself (curvature, torsion, the Frenet frame) raise
  :class:`~splinekit.errors.DomainError` naming the parameter.
* *Vanishing curvature* (a straight piece or an inflection): the torsion is 0
  and the Frenet normal is carried over from the nearest parameter (of the
  same call) where it is defined, see :func:`frenet_frame`.

"Vanishes" is decided with relative thresholds: a derivative ``C^(k)`` vanishes
when ``|C^(k)| <= 1e-12 * size / length**k`` (``size``: the largest absolute
control-point coordinate, at least 1, or the same measured on 33 samples of a
curve without control points; ``length``: the length of the parameter
domain); the curvature vanishes when ``|C''_perp| <= 1e-10 * max(|C''|,
|C'|**2 / size)``, i.e. when the angle between ``C'`` and ``C''`` is below
1e-10 rad or ``curvature * size`` is below 1e-10.

This module holds the tangent, curvatures, torsion and the Frenet frame; it
also offers :class:`ParametricCurve` (:mod:`.parametric_curve`), the arc-length
functions (:mod:`.arc_length`) and :func:`rotation_minimizing_frames`
(:mod:`splinekit.curves.frames`, where sweeps find it), all built on the checked
derivatives of :mod:`splinekit.curves.differential`.
"""

from __future__ import annotations

import numpy as np

from ..curves.differential import (
    _ZERO_DERIVATIVE,
    _as_3d,
    _cross,
    _ders,
    _dot,
    _norm,
    _params,
    _perpendicular,
    _require_regular,
    _scales,
    _tangents,
    _unit,
)
from ..curves.frames import rotation_minimizing_frames
from ..errors import ParameterError
from .arc_length import (
    MAX_PARAMETERS,
    arc_length,
    arc_length_parameters,
    equal_arc_length_parameters,
    reparametrize_by_arc_length,
)
from .parametric_curve import ParametricCurve

__all__ = [
    "MAX_PARAMETERS",
    "ParametricCurve",
    "arc_length",
    "arc_length_parameters",
    "curvature",
    "equal_arc_length_parameters",
    "frenet_frame",
    "reparametrize_by_arc_length",
    "rotation_minimizing_frames",
    "signed_curvature",
    "tangent",
    "torsion",
]

_ZERO_CURVATURE = 1e-10  # relative size under which C''_perp counts as zero



# ----------------------------------------------------------------------------------------
# tangent, curvature, torsion
# ----------------------------------------------------------------------------------------
def tangent(curve, u) -> np.ndarray:
    """Unit tangent vectors ``u.shape + (dim,)``.

    Where ``C'`` vanishes the direction of the first non-vanishing higher
    derivative is used (the one-sided limit from larger parameters); where all
    derivatives inspected vanish (a constant curve) the result is the zero vector.
    """
    u = _params(u)
    flat = u.ravel()
    d1 = _ders(curve, flat, 1)[1]
    size, length = _scales(curve)
    T, _, _ = _tangents(curve, flat, d1, size, length)
    return T.reshape(u.shape + (d1.shape[-1],))


def _per_point_unit(d1: np.ndarray) -> np.ndarray:
    """A power of two ``(n,)`` near ``|C'|`` at each point (1 where ``C'`` vanishes).

    Curvature and torsion are homogeneous of degree -1 in the derivatives:
    dividing the derivatives by the same power of two (exactly) before the
    products keeps squared and cubed lengths inside the float range, whatever
    the units; the result is then divided by it.
    """
    peak = np.abs(d1).max(axis=-1)
    exponent = np.frexp(np.where(peak > 0, peak, 1.0))[1]
    return np.ldexp(1.0, exponent)


def _perp_second(d1: np.ndarray, d2: np.ndarray):
    """``C''`` minus its component along ``C'``, and ``|C'|``: ``(n, dim)``, ``(n,)``."""
    speed = _norm(d1)
    T = _unit(d1, speed)
    return d2 - _dot(d2, T)[:, None] * T, speed


def _regular_derivatives(curve, u, order: int, what: str, dim: int | None = None, hint: str = ""):
    """``(u, d, unit, size)``: parameters, the derivatives ``(order + 1, n, dim)``
    at the flattened ``u`` divided point by point by the power of two ``unit``
    (:func:`_per_point_unit`, so products of derivatives cannot overflow), and
    the curve's size. Raises where ``C'`` vanishes (``what`` names the
    quantity) and, with ``dim``, for curves of another dimension."""
    u = _params(u)
    flat = u.ravel()
    d = _ders(curve, flat, order)
    if dim is not None and d.shape[-1] != dim:
        raise ParameterError(f"{what} needs a {dim}-D curve, got dim={d.shape[-1]}{hint}")
    size, length = _scales(curve)
    _require_regular(_norm(d[1]) > _ZERO_DERIVATIVE * size / length, flat, what)
    unit = _per_point_unit(d[1])
    return u, d / unit[:, None], unit, size


def curvature(curve, u) -> np.ndarray:
    """Curvature ``u.shape`` (>= 0, in 1 / length) of a curve of any dimension.

    ``kappa = |C''_perp| / |C'|**2`` with ``C''_perp`` the part of ``C''``
    orthogonal to ``C'``; this equals ``sqrt(Gram(C', C'')) / |C'|**3`` and, in
    3-D, ``|C' x C''| / |C'|**3``, without the cancellation of the Gram
    determinant. Raises :class:`DomainError` where ``C'`` vanishes.
    """
    u, d, unit, _ = _regular_derivatives(curve, u, 2, "the curvature")
    speed = _norm(d[1])
    if d.shape[-1] == 3:
        num = _norm(_cross(d[1], d[2])) / speed
    elif d.shape[-1] == 2:
        num = np.abs(d[1, :, 0] * d[2, :, 1] - d[1, :, 1] * d[2, :, 0]) / speed
    else:
        num = _norm(_perp_second(d[1], d[2])[0])
    return (num / speed**2 / unit).reshape(u.shape)


def signed_curvature(curve, u) -> np.ndarray:
    """Signed curvature ``u.shape`` of a planar (2-D) curve: ``(x' y'' - y' x'') / |C'|**3``,
    positive where the curve turns counter-clockwise."""
    u, d, unit, _ = _regular_derivatives(curve, u, 2, "the signed curvature", dim=2, hint=" (use curvature)")
    speed = _norm(d[1])
    cross = d[1, :, 0] * d[2, :, 1] - d[1, :, 1] * d[2, :, 0]
    return (cross / speed**3 / unit).reshape(u.shape)


def _straight(perp: np.ndarray, d1: np.ndarray, d2: np.ndarray, size: float) -> np.ndarray:
    """Mask of points where the curvature vanishes (see the module docstring)."""
    scale = np.maximum(_norm(d2), _dot(d1, d1) / size)
    return _norm(perp) <= _ZERO_CURVATURE * scale


def torsion(curve, u) -> np.ndarray:
    """Torsion ``u.shape`` (1 / length) of a 3-D curve: ``det(C', C'', C''') / |C' x C''|**2``.

    Positive for a right-handed helix. Where the curvature vanishes (straight
    pieces, inflections) the torsion is defined as 0. Raises
    :class:`DomainError` where ``C'`` vanishes.
    """
    u, d, unit, size = _regular_derivatives(curve, u, 3, "the torsion", dim=3)
    straight = _straight(_perp_second(d[1], d[2])[0], d[1], d[2], size / unit)
    cross = _cross(d[1], d[2])
    c2 = _dot(cross, cross)
    det = _dot(cross, d[3])
    out = np.divide(det, c2, out=np.zeros_like(det), where=~straight & (c2 > 0))
    return (out / unit).reshape(u.shape)


# ----------------------------------------------------------------------------------------
# frames
# ----------------------------------------------------------------------------------------
def frenet_frame(curve, u):
    """Frenet frame ``(T, N, B)``, each ``u.shape + (3,)``, of a 3-D (or planar, embedded at z = 0) curve.

    ``T = C' / |C'|``, ``N`` the unit part of ``C''`` orthogonal to ``T``,
    ``B = T x N``. Where the curvature vanishes ``N`` is undefined; it is then
    the normal of the nearest parameter of this call where it is defined,
    made orthogonal to ``T`` (or, if there is none, or it is parallel to
    ``T``, the coordinate axis least aligned with ``T`` made orthogonal to it).
    So the frame is always orthonormal and right-handed, but at a straight
    piece it depends on the other parameters passed. Raises
    :class:`DomainError` where ``C'`` vanishes.
    """
    u = _params(u)
    flat = u.ravel()
    d = _ders(curve, flat, 2)
    size, length = _scales(curve)
    d1, d2 = _as_3d(d[1], "frenet_frame"), _as_3d(d[2], "frenet_frame")
    _require_regular(_norm(d1) > _ZERO_DERIVATIVE * size / length, flat, "the Frenet frame")
    unit = _per_point_unit(d1)  # the frame is invariant under this scaling; squares stay in range
    d1, d2 = d1 / unit[:, None], d2 / unit[:, None]
    perp, speed = _perp_second(d1, d2)
    T = _unit(d1, speed)
    straight = _straight(perp, d1, d2, size / unit)
    N = _unit(perp)
    if straight.any():
        N[straight] = _carried_normals(flat, T, N, straight)
    B = _cross(T, N)
    shape = u.shape + (3,)
    return T.reshape(shape), N.reshape(shape), B.reshape(shape)


def _carried_normals(flat, T, N, undefined):
    """Normals at the ``undefined`` points: the nearest defined one, projected orthogonal to ``T``."""
    idx = np.flatnonzero(undefined)
    Tu = T[idx]
    out = _perpendicular(Tu)
    good = np.flatnonzero(~undefined)
    if good.size:
        order = good[np.argsort(flat[good], kind="stable")]
        keys = flat[order]
        pos = np.clip(np.searchsorted(keys, flat[idx]), 1, max(keys.size - 1, 1))
        left = order[np.clip(pos - 1, 0, keys.size - 1)]
        right = order[np.clip(pos, 0, keys.size - 1)]
        nearest = np.where(np.abs(flat[left] - flat[idx]) <= np.abs(flat[right] - flat[idx]), left, right)
        cand = N[nearest] - _dot(N[nearest], Tu)[:, None] * Tu
        cn = _norm(cand)
        ok = cn > 1e-6
        out[ok] = cand[ok] / cn[ok, None]
    return out

