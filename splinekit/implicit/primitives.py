"""Exact signed-distance primitives with analytic gradients.

Every primitive is an :class:`~splinekit.implicit.base.Implicit` whose value is
the true signed distance (model units, negative inside) and whose gradient is
analytic. Where the distance is not differentiable (the medial axis: a
sphere's centre, a box's inner diagonal planes, a torus's core circle and
axis, a cylinder's axis) the gradient returned is one of the one-sided values,
or zero where no direction is preferred (so :meth:`normal` raises there).

=========================================  ===============================================
primitive                                  solid
=========================================  ===============================================
``sphere(center, radius)``                 ``|p - c| <= r``
``box(center, size)``                      axis-aligned, edge lengths ``size`` (3,)
``rounded_box(center, size, radius)``      the box with edges and corners rounded by
                                           ``radius`` (outer size still ``size``)
``torus(center, major, minor, axis=z)``    tube of radius ``minor`` around the circle of
                                           radius ``major`` about ``axis``
``cylinder(center, radius, height, z)``    capped; ``center`` is the axis midpoint
``capsule(a, b, radius)``                  points within ``radius`` of the segment ``ab``
``cone(a, b, radius_a, radius_b=0)``       capped (truncated) cone along ``a -> b`` with
                                           radius ``radius_a`` at ``a`` and ``radius_b`` at
                                           ``b``: a pointed cone with apex ``b`` by default
``plane(point, normal)``                   the half-space behind the plane (``normal``
                                           points out of the solid)
=========================================  ===============================================

Solids of revolution (torus, cylinder, cone) are reduced to a 2-D distance in
the meridian half-plane ``(rho, h)`` (``rho`` the distance from the axis, ``h``
the coordinate along it): the distance in 3-D is the 2-D distance to the
meridian section, and the 3-D gradient is ``g_rho e_rho + g_h axis``.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array
from ..errors import ParameterError
from ._checks import positive
from .base import Implicit

__all__ = ["box", "capsule", "cone", "cylinder", "plane", "rounded_box", "sphere", "torus"]


def _vector(value, name: str) -> np.ndarray:
    v = as_float_array(value, name)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ParameterError(f"{name} must be a finite 3-D vector, got {value!r}")
    v = v.copy()
    v.setflags(write=False)
    return v


def _unit(value, name: str) -> np.ndarray:
    v = _vector(value, name)
    length = float(np.linalg.norm(v))
    if not length > 0:
        raise ParameterError(f"{name} must be a non-zero vector, got {v.tolist()}")
    return v / length


def _safe_unit_rows(v, length):
    """``v / length`` per row, zero where the length is zero (an undefined direction)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        out = v / length[:, None]
        huge = np.isinf(length)
        if huge.any():  # |v| overflowed: normalize the rescaled rows instead
            w = v[huge] / np.abs(v[huge]).max(axis=1)[:, None]
            out[huge] = w / np.linalg.norm(w, axis=1)[:, None]
    return np.where((length > 0)[:, None], out, 0.0)


def _disc_extent(axis, radius):
    """Half-extents along x, y, z of a disc of ``radius`` normal to the unit ``axis``."""
    return radius * np.sqrt(np.clip(1.0 - axis**2, 0.0, 1.0))


class Sphere(Implicit):
    """``|p - c| - r``."""

    def __init__(self, center, radius):
        super().__init__(bounds=(center - radius, center + radius), exact=True, convex=True)
        self.center, self.radius = center, radius

    def __repr__(self):
        return f"sphere({self.center.tolist()}, {self.radius!r})"

    def _value(self, p):
        return np.linalg.norm(p - self.center, axis=1) - self.radius

    def _value_gradient(self, p):
        v = p - self.center
        d = np.linalg.norm(v, axis=1)
        return d - self.radius, _safe_unit_rows(v, d)

    def _gradient(self, p):
        return self._value_gradient(p)[1]

    def _hessian(self, p):
        # (I - n n^T) / |p - c|: infinite at the centre, where _checked reports the point
        v = p - self.center
        d = np.linalg.norm(v, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            n = v / d[:, None]
            return (np.eye(3)[None] - n[:, :, None] * n[:, None, :]) / d[:, None, None]


class Box(Implicit):
    """Axis-aligned box: ``|max(q, 0)| + min(max_i q_i, 0)`` with ``q = |p - c| - b``."""

    def __init__(self, center, half):
        super().__init__(bounds=(center - half, center + half), exact=True, convex=True)
        self.center, self.half = center, half

    def __repr__(self):
        return f"box({self.center.tolist()}, {(2 * self.half).tolist()})"

    def _value(self, p):
        q = np.abs(p - self.center) - self.half
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return outside + np.minimum(q.max(axis=1), 0.0)

    def _gradient(self, p):
        v = p - self.center
        sign = np.where(v < 0.0, -1.0, 1.0)
        q = np.abs(v) - self.half
        qp = np.maximum(q, 0.0)
        out_len = np.linalg.norm(qp, axis=1)
        # inside (or on the surface): the face of the largest q
        inside = np.zeros_like(v)
        inside[np.arange(len(v)), np.argmax(q, axis=1)] = 1.0
        g = np.where((out_len > 0)[:, None], _safe_unit_rows(qp, out_len), inside)
        return sign * g


class Revolved(Implicit):
    """A solid of revolution about the axis through ``origin`` along unit
    ``axis``, given by a 2-D distance in the meridian half-plane."""

    def __init__(self, origin, axis, *, bounds, convex, exact=True):
        super().__init__(bounds=bounds, exact=exact, convex=convex)
        self.origin, self.axis = origin, axis

    def _meridian(self, p):
        """``(rho, h, w)``: distance from the axis, coordinate along it, radial vectors ``(n, 3)``."""
        v = p - self.origin
        h = v @ self.axis
        w = v - h[:, None] * self.axis
        return np.sqrt(np.einsum("ij,ij->i", w, w)), h, w

    def _distance2d(self, rho, h, grad: bool):
        """``d`` of the meridian section, and ``(g_rho, g_h)`` when ``grad``."""
        raise NotImplementedError

    def _value(self, p):
        rho, h, _ = self._meridian(p)
        return self._distance2d(rho, h, False)[0]

    def _value_gradient(self, p):
        rho, h, w = self._meridian(p)
        d, g_rho, g_h = self._distance2d(rho, h, True)
        return d, g_rho[:, None] * _safe_unit_rows(w, rho) + g_h[:, None] * self.axis

    def _gradient(self, p):
        return self._value_gradient(p)[1]


class Torus(Revolved):
    """``sqrt((rho - R)^2 + h^2) - r``: the distance to the core circle minus
    ``r``. Exact for ``r <= R``; for a spindle torus (``r > R``) it is exact
    outside only: inside, the dimples on the axis can be nearer than
    ``r - dist(core)`` (at the centre ``F = R - r`` while the dimples lie
    ``sqrt(r^2 - R^2)`` away), so ``is_exact_sdf`` is False."""

    def __init__(self, center, axis, major, minor):
        ext = _disc_extent(axis, major) + minor
        super().__init__(center, axis, bounds=(center - ext, center + ext), convex=False, exact=minor <= major)
        self.major, self.minor = major, minor

    def __repr__(self):
        return f"torus({self.origin.tolist()}, {self.major!r}, {self.minor!r}, axis={self.axis.tolist()})"

    def _distance2d(self, rho, h, grad):
        x = rho - self.major
        d = np.hypot(x, h)
        if not grad:
            return d - self.minor, None, None
        with np.errstate(divide="ignore", invalid="ignore"):
            gx, gh = x / d, h / d
        core = d > 0  # on the core circle no direction is preferred
        return d - self.minor, np.where(core, gx, 0.0), np.where(core, gh, 0.0)


class Cone(Revolved):
    """Capped cone (frustum) from ``a`` (radius ``ra``) to ``b`` (radius ``rb``)
    along the axis of length ``L``: the meridian section is the trapezoid
    ``(0, 0), (ra, 0), (rb, L), (0, L)``; its distance is the smallest distance
    to the bottom cap, the slanted side and the top cap (the edge on the axis is
    not boundary: by symmetry the mirrored half of the section is never
    nearer), negative inside."""

    def __init__(self, a, b, ra, rb):
        axis_vec = b - a
        length = float(np.linalg.norm(axis_vec))
        axis = axis_vec / length
        lo = np.minimum(a - _disc_extent(axis, ra), b - _disc_extent(axis, rb))
        hi = np.maximum(a + _disc_extent(axis, ra), b + _disc_extent(axis, rb))
        super().__init__(a, axis, bounds=(lo, hi), convex=True)
        self.a, self.b, self.ra, self.rb, self.length = a, b, ra, rb, length
        self._ex, self._ey = rb - ra, length  # the slanted side, from (ra, 0) to (rb, L)
        self._ee = self._ex**2 + length**2
        side = np.hypot(self._ex, length)
        self._side_normal = (length / side, -self._ex / side)  # outward, in (rho, h)

    def __repr__(self):
        return f"cone({self.a.tolist()}, {self.b.tolist()}, {self.ra!r}, {self.rb!r})"

    def _distance2d(self, rho, h, grad):
        L = self.length
        # offsets (x, y) from the nearest point of each boundary segment
        bx, by = np.maximum(rho - self.ra, 0.0), h  # bottom cap, (0, 0)-(ra, 0)
        tx, ty = np.maximum(rho - self.rb, 0.0), h - L  # top cap, (0, L)-(rb, L)
        u, v = rho - self.ra, h
        t = np.clip((u * self._ex + v * self._ey) / self._ee, 0.0, 1.0)
        sx, sy = u - t * self._ex, v - t * self._ey  # slanted side
        b2, t2, s2 = bx * bx + by * by, tx * tx + ty * ty, sx * sx + sy * sy
        top = t2 < b2
        cx, cy, c2 = np.where(top, tx, bx), np.where(top, ty, by), np.minimum(b2, t2)
        side = s2 < c2
        x, y = np.where(side, sx, cx), np.where(side, sy, cy)
        d = np.sqrt(np.minimum(c2, s2))
        # inside: strictly between the caps and left of the slanted side
        inside = (h > 0.0) & (h < L) & (u * self._ey - v * self._ex < 0.0)
        sign = np.where(inside, -1.0, 1.0)
        if not grad:
            return sign * d, None, None
        with np.errstate(divide="ignore", invalid="ignore"):
            gx, gy = sign * x / d, sign * y / d
        # on the surface itself (d = 0): the outward normal of the segment reached
        on = ~(d > 0)
        if on.any():
            nx = np.where(side, self._side_normal[0], 0.0)
            ny = np.where(side, self._side_normal[1], np.where(top, 1.0, -1.0))
            gx, gy = np.where(on, nx, gx), np.where(on, ny, gy)
        return sign * d, gx, gy


class Cylinder(Revolved):
    """Capped cylinder about its axis midpoint: the meridian section is the
    rectangle ``rho <= r``, ``|h| <= H / 2``, whose distance is a 2-D box's."""

    def __init__(self, center, axis, radius, height):
        ext = _disc_extent(axis, radius) + 0.5 * height * np.abs(axis)
        super().__init__(center, axis, bounds=(center - ext, center + ext), convex=True)
        self.radius, self.height = radius, height

    def __repr__(self):
        return f"cylinder({self.origin.tolist()}, {self.radius!r}, {self.height!r}, axis={self.axis.tolist()})"

    def _distance2d(self, rho, h, grad):
        qx, qy = rho - self.radius, np.abs(h) - 0.5 * self.height
        ox, oy = np.maximum(qx, 0.0), np.maximum(qy, 0.0)
        out = np.hypot(ox, oy)
        d = out + np.minimum(np.maximum(qx, qy), 0.0)
        if not grad:
            return d, None, None
        with np.errstate(divide="ignore", invalid="ignore"):
            gx, gy = ox / out, oy / out
        # inside or on the surface: the side or the cap, whichever is nearer
        cap = qy >= qx
        gx = np.where(out > 0, gx, np.where(cap, 0.0, 1.0))
        gy = np.where(out > 0, gy, np.where(cap, 1.0, 0.0))
        return d, gx, np.where(h < 0.0, -gy, gy)


class Capsule(Implicit):
    """``|p - a - t (b - a)| - r`` with ``t`` the clamped projection onto the segment."""

    def __init__(self, a, b, radius):
        super().__init__(bounds=(np.minimum(a, b) - radius, np.maximum(a, b) + radius), exact=True, convex=True)
        self.a, self.b, self.radius = a, b, radius
        self._e = b - a
        self._ee = float(self._e @ self._e)

    def __repr__(self):
        return f"capsule({self.a.tolist()}, {self.b.tolist()}, {self.radius!r})"

    def _offset(self, p):
        v = p - self.a
        if self._ee == 0.0:  # coincident ends: a sphere
            return v
        t = np.clip((v @ self._e) / self._ee, 0.0, 1.0)
        return v - t[:, None] * self._e

    def _value(self, p):
        return np.linalg.norm(self._offset(p), axis=1) - self.radius

    def _value_gradient(self, p):
        w = self._offset(p)
        d = np.linalg.norm(w, axis=1)
        return d - self.radius, _safe_unit_rows(w, d)

    def _gradient(self, p):
        return self._value_gradient(p)[1]


class Plane(Implicit):
    """``(p - p0) . n``: the half-space behind the plane (unbounded)."""

    def __init__(self, point, normal):
        super().__init__(bounds=None, exact=True, convex=True)
        self.point, self.unit_normal = point, normal
        self._c = float(point @ normal)

    def __repr__(self):
        return f"plane({self.point.tolist()}, {self.unit_normal.tolist()})"

    def _value(self, p):
        return p @ self.unit_normal - self._c

    def _gradient(self, p):
        return np.broadcast_to(self.unit_normal, p.shape).copy()

    def _hessian(self, p):
        return np.zeros((len(p), 3, 3))


# -- constructors -------------------------------------------------------------------------------
def sphere(center=(0.0, 0.0, 0.0), radius=1.0) -> Implicit:
    """Sphere of ``radius`` > 0 about ``center`` (3,)."""
    return Sphere(_vector(center, "center"), positive(radius, "radius"))


def _size(size):
    s = as_float_array(size, "size")
    if s.ndim == 0:
        s = np.full(3, float(s))
    if s.shape != (3,) or not np.isfinite(s).all():
        raise ParameterError(f"size must be a finite number or 3-D vector, got {size!r}")
    if not (s > 0).all():
        i = int(np.argmax(~(s > 0)))
        raise ParameterError(f"size must be > 0 along every axis; size[{i}] = {float(s[i])!r}")
    return s


def box(center=(0.0, 0.0, 0.0), size=1.0) -> Implicit:
    """Axis-aligned box about ``center`` (3,) with edge lengths ``size`` (a number or (3,))."""
    return Box(_vector(center, "center"), 0.5 * _size(size))


def rounded_box(center=(0.0, 0.0, 0.0), size=1.0, radius=0.1) -> Implicit:
    """Axis-aligned box of outer edge lengths ``size`` with edges rounded by
    ``radius`` (0 <= radius <= min(size) / 2): the offset by ``radius`` of the
    box shrunk by ``2 radius``, an exact signed distance."""
    size = _size(size)
    r = positive(radius, "radius", allow_zero=True)
    if r > 0.5 * size.min():
        raise ParameterError(f"radius must be at most min(size) / 2 = {float(0.5 * size.min())!r}, got {r!r}")
    inner = Box(_vector(center, "center"), 0.5 * size - r)
    return inner.offset(r) if r > 0 else inner


def torus(center=(0.0, 0.0, 0.0), major=1.0, minor=0.25, axis=(0.0, 0.0, 1.0)) -> Implicit:
    """Torus about ``axis`` (3,) through ``center``: a tube of radius ``minor``
    around the circle of radius ``major`` (both > 0; ``minor > major`` gives a
    spindle torus, whose ``F`` is an exact distance outside only)."""
    return Torus(_vector(center, "center"), _unit(axis, "axis"), positive(major, "major"), positive(minor, "minor"))


def cylinder(center=(0.0, 0.0, 0.0), radius=1.0, height=1.0, axis=(0.0, 0.0, 1.0)) -> Implicit:
    """Capped cylinder of ``radius`` and ``height`` (both > 0) whose axis runs
    along ``axis`` through ``center`` (the midpoint of the axis segment)."""
    return Cylinder(_vector(center, "center"), _unit(axis, "axis"), positive(radius, "radius"), positive(height, "height"))


def capsule(a, b, radius) -> Implicit:
    """Points within ``radius`` > 0 of the segment from ``a`` to ``b`` (3,)
    (a sphere when they coincide)."""
    return Capsule(_vector(a, "a"), _vector(b, "b"), positive(radius, "radius"))


def cone(a, b, radius_a, radius_b=0.0) -> Implicit:
    """Capped cone along the axis from ``a`` to ``b`` (distinct points (3,)),
    of radius ``radius_a`` at ``a`` and ``radius_b`` at ``b`` (both >= 0, not
    both 0): a pointed cone with its apex at ``b`` by default, a frustum
    otherwise. The base discs are flat caps."""
    a, b = _vector(a, "a"), _vector(b, "b")
    if not np.linalg.norm(b - a) > 0:
        raise ParameterError(f"a cone needs distinct end points a and b, got a = b = {a.tolist()}")
    ra = positive(radius_a, "radius_a", allow_zero=True)
    rb = positive(radius_b, "radius_b", allow_zero=True)
    if ra == 0 and rb == 0:
        raise ParameterError("radius_a and radius_b are both 0: the cone has no volume")
    # the distance projects onto the slanted side through its squared length
    with np.errstate(over="ignore"):
        side2 = np.float64(rb - ra) ** 2 + np.float64(np.linalg.norm(b - a)) ** 2
    if not np.isfinite(side2):
        raise ParameterError(
            f"a cone with radii {ra!r}, {rb!r} and axis length {float(np.linalg.norm(b - a))!r} is beyond the float "
            "range of its distance computation (sizes up to about 1e154)"
        )
    return Cone(a, b, ra, rb)


def plane(point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)) -> Implicit:
    """The half-space ``(p - point) . n <= 0`` behind the plane through
    ``point`` with (non-zero, normalized here) ``normal``."""
    return Plane(_vector(point, "point"), _unit(normal, "normal"))
