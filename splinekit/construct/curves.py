"""Exact curves: lines, polylines and the conics as rational quadratic NURBS.

Circles, arcs and ellipses follow The NURBS Book A7.1: an arc of sweep
``theta`` is cut into ``ceil(|theta| / 90 deg)`` equal segments, each a
rational quadratic Bézier whose middle weight is ``cos(segment / 2)``; the
segments are joined by double knots on the parameter domain ``[0, 1]``. The
result lies exactly on the circle (up to rounding); its parametrization is
not proportional to the angle.

Planar curves are placed in 3-D by ``center``, the plane ``normal`` and an
optional in-plane ``x_axis`` (angles are measured from it, counter-clockwise
about the normal). With 2-D input (``center`` of shape ``(2,)``) pass
``normal=None``; angles are then measured from ``x_axis`` (default the
x-axis) counter-clockwise.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_points, as_real
from ..curves import BSplineCurve, NurbsCurve
from ..errors import ParameterError
from ..tolerances import ANGULAR_CONFUSION
from ._checks import as_positive, as_vector, plane_frame

__all__ = ["line", "polyline", "circle", "arc", "ellipse", "arc_through_points", "unit_arc"]

TWO_PI = 2.0 * math.pi
# sweeps within this many radians of a full turn count as a full turn
_ANGLE_SLACK = ANGULAR_CONFUSION


def unit_arc(start_angle: float, end_angle: float):
    """Rational quadratic arc of the unit circle (A7.1), in plane coordinates.

    Returns ``(knots (2s + 4,), coords (2s + 1, 2), weights (2s + 1,))`` for
    ``s`` segments: the control points are ``coords[:, 0] * X + coords[:, 1] * Y``
    in any orthonormal frame ``(X, Y)``. Angles in radians; ``end - start`` may
    be negative (clockwise) and at most a full turn in size.
    """
    sweep = end_angle - start_angle
    if not sweep != 0.0:
        raise ParameterError(f"the arc sweeps no angle: start_angle = end_angle = {start_angle!r}")
    if abs(sweep) > TWO_PI + _ANGLE_SLACK:
        raise ParameterError(f"the arc sweeps {sweep!r} radians; at most a full turn (2 pi) is allowed")
    full = abs(abs(sweep) - TWO_PI) <= _ANGLE_SLACK
    if full:
        sweep = math.copysign(TWO_PI, sweep)
    n_seg = max(1, math.ceil(abs(sweep) / (0.5 * math.pi) - 1e-9))
    step = sweep / n_seg
    ends = start_angle + step * np.arange(n_seg + 1)
    mids = ends[:-1] + 0.5 * step
    w_mid = math.cos(0.5 * step)
    coords = np.empty((2 * n_seg + 1, 2))
    coords[0::2, 0] = np.cos(ends)
    coords[0::2, 1] = np.sin(ends)
    coords[1::2, 0] = np.cos(mids) / w_mid
    coords[1::2, 1] = np.sin(mids) / w_mid
    if full:
        coords[-1] = coords[0]  # close exactly
    weights = np.ones(2 * n_seg + 1)
    weights[1::2] = w_mid
    inner = np.repeat(np.arange(1, n_seg) / n_seg, 2)
    knots = np.concatenate([[0.0, 0.0, 0.0], inner, [1.0, 1.0, 1.0]])
    return knots, coords, weights


def _center_and_frame(center, normal, x_axis, x_name="x_axis"):
    c = as_vector(center, "center")
    X, Y = plane_frame(normal, x_axis, c.size, x_name)
    return c, X, Y


def _placed_arc(c, X, Y, rx, ry, start, end) -> NurbsCurve:
    knots, uv, w = unit_arc(start, end)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused by NurbsCurve, naming it
        P = c + (rx * uv[:, :1]) * X + (ry * uv[:, 1:]) * Y
    return NurbsCurve(2, knots, P, w)


def _angle(value, name):
    return as_real(value, name)


def line(start, end) -> BSplineCurve:
    """Straight segment from ``start`` to ``end`` (any dimension): degree 1 on ``[0, 1]``."""
    P = as_points(_stack_two(start, end), "line end points")
    if np.array_equal(P[0], P[1]):
        raise ParameterError(f"line needs two distinct points, got start = end = {P[0].tolist()}")
    return BSplineCurve(1, [0.0, 0.0, 1.0, 1.0], P)


def _stack_two(a, b):
    try:
        return np.array([np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)])
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"start and end must be points of the same dimension: {exc}") from None


def polyline(points) -> BSplineCurve:
    """Degree-1 curve through ``points`` ``(n, dim)``, ``n >= 2``.

    The knots are the normalized cumulative chord lengths on ``[0, 1]``, so the
    curve is parametrized proportionally to arc length. Consecutive points
    must differ.
    """
    P = as_points(points, "points", min_count=(2,))
    with np.errstate(over="ignore", invalid="ignore"):  # reported below, naming the problem
        chords = np.linalg.norm(np.diff(P, axis=0), axis=1)
        total = chords.sum()
    if not (np.isfinite(chords).all() and np.isfinite(total)):
        raise ParameterError("points are so far apart that their distances overflow")
    zero = np.flatnonzero(chords == 0.0)
    if zero.size:
        i = int(zero[0])
        raise ParameterError(f"points[{i}] and points[{i + 1}] coincide ({P[i].tolist()}); a polyline needs distinct consecutive points")
    s = np.concatenate([[0.0], np.cumsum(chords)])
    s /= s[-1]
    s[-1] = 1.0
    return BSplineCurve(1, np.concatenate([[0.0], s, [1.0]]), P)


def arc(center, normal, radius, start_angle, end_angle, *, x_axis=None) -> NurbsCurve:
    """Circular arc as a rational quadratic NURBS on ``[0, 1]`` (A7.1).

    Parameters
    ----------
    center : (3,) or (2,) array_like
    normal : (3,) array_like or None
        Plane normal (3-D); None for 2-D input.
    radius : float > 0
    start_angle, end_angle : float
        Radians, measured from ``x_axis`` counter-clockwise about ``normal``;
        ``end_angle < start_angle`` runs clockwise. ``0 < |end - start| <= 2 pi``.
    x_axis : (3,) or (2,) array_like, optional
        Direction of angle 0 (projected into the plane); default a fixed
        perpendicular of the normal (3-D) or ``(1, 0)`` (2-D).

    Returns a :class:`~splinekit.NurbsCurve` of degree 2 with
    ``2 * ceil(|sweep| / 90 deg) + 1`` control points.
    """
    c, X, Y = _center_and_frame(center, normal, x_axis)
    r = as_positive(radius, "radius")
    return _placed_arc(c, X, Y, r, r, _angle(start_angle, "start_angle"), _angle(end_angle, "end_angle"))


def circle(center, normal, radius, *, x_axis=None) -> NurbsCurve:
    """Full circle: 4 quarter arcs, 9 control points, starting on ``x_axis`` (A7.1)."""
    c, X, Y = _center_and_frame(center, normal, x_axis)
    r = as_positive(radius, "radius")
    return _placed_arc(c, X, Y, r, r, 0.0, TWO_PI)


def ellipse(center, normal, major_radius, minor_radius, *, major_axis=None) -> NurbsCurve:
    """Full ellipse: the affine image of :func:`circle` (exact).

    ``major_radius >= minor_radius > 0``; ``major_axis`` gives the direction of
    the major axis (projected into the plane), where the curve starts.
    """
    c, X, Y = _center_and_frame(center, normal, major_axis, "major_axis")
    a = as_positive(major_radius, "major_radius")
    b = as_positive(minor_radius, "minor_radius")
    if b > a:
        raise ParameterError(f"minor_radius = {b!r} exceeds major_radius = {a!r}")
    return _placed_arc(c, X, Y, a, b, 0.0, TWO_PI)


def arc_through_points(p0, p1, p2) -> NurbsCurve:
    """The circular arc from ``p0`` through ``p1`` to ``p2`` (2-D or 3-D points).

    The arc starts exactly at ``p0`` and ends exactly at ``p2``. Raises
    :class:`~splinekit.errors.ParameterError` when the points are collinear
    or two of them coincide.
    """
    pts = [as_vector(p, name) for p, name in ((p0, "p0"), (p1, "p1"), (p2, "p2"))]
    dim = pts[0].size
    if any(p.size != dim for p in pts):
        raise ParameterError(f"p0, p1, p2 must have the same dimension, got {[p.size for p in pts]}")
    a, b, c = (np.concatenate([p, np.zeros(3 - dim)]) for p in pts)
    for (i, j), (x, y) in (((0, 1), (a, b)), ((0, 2), (a, c)), ((1, 2), (b, c))):
        if np.array_equal(x, y):
            raise ParameterError(f"p{i} and p{j} coincide at {pts[i].tolist()}")
    # work relative to p0 in units of the points' spread: the construction
    # squares and cubes differences, which would overflow (or underflow) for
    # points far apart (or very close) in absolute units
    lo, hi = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
    scale = float((hi / 2 - lo / 2).max())  # halved first: no overflow near the float limit
    u, v = (b / scale - a / scale), (c / scale - a / scale)
    w = np.cross(u, v)
    ww = float(np.dot(w, w))
    if not ww > (1e-12 * float(np.linalg.norm(u)) * float(np.linalg.norm(v))) ** 2:
        raise ParameterError(f"p0, p1, p2 are collinear ({pts[0].tolist()}, {pts[1].tolist()}, {pts[2].tolist()}): no circle passes through them")
    offset = np.cross(np.dot(u, u) * v - np.dot(v, v) * u, w) / (2.0 * ww)  # center - p0, in units of scale
    normal = w / math.sqrt(ww)
    rel = float(np.linalg.norm(offset))
    X = -offset / rel
    Y = np.cross(normal, X)
    d2 = v - offset
    end = math.atan2(float(np.dot(d2, Y)), float(np.dot(d2, X)))
    if end <= 0.0:
        end += TWO_PI
    knots, uv, wts = unit_arc(0.0, end)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported by NurbsCurve, naming it
        P = a + scale * (offset + (rel * uv[:, :1]) * X + (rel * uv[:, 1:]) * Y)
    P[0], P[-1] = a, c
    return NurbsCurve(2, knots, P[:, :dim], wts)
