"""CSG, smooth blends, offsets and rigid/uniform transforms of implicits.

All results are :class:`~splinekit.implicit.base.Implicit` objects with analytic
gradients built from their operands' gradients (the gradient of ``min`` is the
gradient of the smaller operand; on a seam, where both are equal, the first
operand's). Which of them are exact signed distances is tabulated in
:mod:`splinekit.implicit.base`.

Smooth blends use the quadratic polynomial smooth minimum with blend radius
``k`` (model units)::

    h = clip(1/2 + (b - a) / (2k), 0, 1)
    smin(a, b) = h a + (1 - h) b - k h (1 - h)

which equals ``min(a, b)`` where ``|a - b| >= k``, never exceeds it, and lies
at most ``k / 4`` below it (at ``a = b``). Its gradient is ``h grad a + (1 - h)
grad b``. ``smax(a, b) = -smin(-a, -b)``.

Bounds: every implicit carries a box and a growth factor ``c`` such that for
every ``t >= 0`` the sublevel set ``F <= t`` lies in the box grown by ``c t``
on every side (``c = 1`` for a true distance: its sublevel sets are offsets
of the solid). The rules here keep that true: a union's box is the hull of
its operands' boxes (grown by ``c k / 4`` for a smooth union, as ``smin >=
min - k / 4``), an intersection's is their overlap (the overlap of boxes grown
by ``c t`` is the overlap grown by ``c t``), a difference keeps the first
operand's box, an offset by ``r > 0`` grows the box by ``c r`` and a shell by
``c t / 2``; a rotated box is replaced by the axis-aligned box of its
corners, and ``c`` is multiplied by ``max_i sum_j |R_ij|`` (at most
``sqrt(3)``), the growth of that box when the rotated one grows. So ``F > 0``
outside the box always, and offsets of CSG trees stay inside their boxes.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_real
from ..errors import ParameterError
from ._checks import positive
from .base import Implicit, register_csg

__all__ = [
    "Complement",
    "Difference",
    "Intersection",
    "Offset",
    "Shell",
    "SmoothIntersection",
    "SmoothUnion",
    "Transformed",
    "Union",
    "complement",
    "difference",
    "intersection",
    "offset",
    "rotation_matrix",
    "shell",
    "smooth_difference",
    "smooth_intersection",
    "smooth_union",
    "transformed",
    "union",
]

ORTHOGONALITY_TOL = 1e-9
"""Largest entry of ``R^T R - I`` accepted for a rotation matrix."""


def _operand(obj, name: str) -> Implicit:
    if not isinstance(obj, Implicit):
        raise ParameterError(f"{name} must be a splinekit.implicit.Implicit, got {type(obj).__name__}")
    return obj


def _hull(a, b):
    if a is None or b is None:
        return None
    return np.minimum(a[0], b[0]), np.maximum(a[1], b[1])


def _overlap(a, b):
    if a is None:
        return b
    if b is None:
        return a
    lo, hi = np.maximum(a[0], b[0]), np.minimum(a[1], b[1])
    # disjoint boxes: an empty solid; a flat box at the overlap's centre keeps lo <= hi
    mid = 0.5 * (lo + hi)
    return np.minimum(lo, mid), np.maximum(hi, mid)


def _growth(a, b):
    """Growth factor of a box made from the boxes of ``a`` and ``b`` (the largest
    of the bounded operands'; see the module notes)."""
    factors = [x._growth for x in (a, b) if x.bounds is not None]
    return max(factors) if factors else 1.0


def _grown(box, r):
    if box is None:
        return None
    return box[0] - r, box[1] + r


# -- hard CSG -----------------------------------------------------------------------------------
class _Binary(Implicit):
    def __init__(self, a, b, *, bounds, exact=False, convex=False, growth=None):
        if growth is None:
            growth = _growth(a, b)
        super().__init__(bounds=bounds, exact=exact, convex=convex, growth=growth)
        self.a, self.b = a, b

    def __repr__(self):
        return f"{type(self).__name__}({self.a!r}, {self.b!r})"

    def _gradient(self, p):
        return self._value_gradient(p)[1]


class Union(_Binary):
    """``min(a, b)``: the union of two solids (exact outside only)."""

    def __init__(self, a, b):
        super().__init__(a, b, bounds=_hull(a.bounds, b.bounds))

    def _value(self, p):
        return np.minimum(self.a._value(p), self.b._value(p))

    def _value_gradient(self, p):
        (fa, ga), (fb, gb) = self.a._value_gradient(p), self.b._value_gradient(p)
        first = fa <= fb
        return np.where(first, fa, fb), np.where(first[:, None], ga, gb)


class Intersection(_Binary):
    """``max(a, b)``: the intersection of two solids (exact inside only)."""

    def __init__(self, a, b):
        super().__init__(a, b, bounds=_overlap(a.bounds, b.bounds), convex=a._convex and b._convex)

    def _value(self, p):
        return np.maximum(self.a._value(p), self.b._value(p))

    def _value_gradient(self, p):
        (fa, ga), (fb, gb) = self.a._value_gradient(p), self.b._value_gradient(p)
        first = fa >= fb
        return np.where(first, fa, fb), np.where(first[:, None], ga, gb)


class Difference(_Binary):
    """``max(a, -b)``: ``a`` with ``b`` removed."""

    def __init__(self, a, b):
        super().__init__(a, b, bounds=a.bounds, growth=a._growth)

    def _value(self, p):
        return np.maximum(self.a._value(p), -self.b._value(p))

    def _value_gradient(self, p):
        (fa, ga), (fb, gb) = self.a._value_gradient(p), self.b._value_gradient(p)
        first = fa >= -fb
        return np.where(first, fa, -fb), np.where(first[:, None], ga, -gb)


class Complement(Implicit):
    """``-a``: everything outside ``a`` (unbounded; exact when ``a`` is)."""

    def __init__(self, a):
        super().__init__(bounds=None, exact=a.is_exact_sdf)
        self.a = a

    def __repr__(self):
        return f"Complement({self.a!r})"

    def _value(self, p):
        return -self.a._value(p)

    def _gradient(self, p):
        return -self.a._gradient(p)

    def _value_gradient(self, p):
        f, g = self.a._value_gradient(p)
        return -f, -g

    def _hessian(self, p):
        return -self.a._hessian(p)


def union(a, b) -> Implicit:
    """``a | b``: ``min(a, b)``."""
    return Union(_operand(a, "a"), _operand(b, "b"))


def intersection(a, b) -> Implicit:
    """``a & b``: ``max(a, b)``."""
    return Intersection(_operand(a, "a"), _operand(b, "b"))


def difference(a, b) -> Implicit:
    """``a - b``: ``max(a, -b)``."""
    return Difference(_operand(a, "a"), _operand(b, "b"))


def complement(a) -> Implicit:
    """``-a``; the complement of a complement is the original object."""
    a = _operand(a, "a")
    return a.a if isinstance(a, Complement) else Complement(a)


# -- smooth blends ------------------------------------------------------------------------------
def _smin(a, b, k):
    """Quadratic smooth minimum and its weight ``h`` on ``a``: ``(value, h)``."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return h * a + (1.0 - h) * b - k * h * (1.0 - h), h


class SmoothUnion(_Binary):
    """Polynomial smooth minimum of ``a`` and ``b`` with blend radius ``k``."""

    def __init__(self, a, b, k):
        super().__init__(a, b, bounds=_grown(_hull(a.bounds, b.bounds), _growth(a, b) * 0.25 * k))
        self.k = k

    def _value(self, p):
        return _smin(self.a._value(p), self.b._value(p), self.k)[0]

    def _value_gradient(self, p):
        (fa, ga), (fb, gb) = self.a._value_gradient(p), self.b._value_gradient(p)
        f, h = _smin(fa, fb, self.k)
        return f, h[:, None] * ga + (1.0 - h[:, None]) * gb


class SmoothIntersection(_Binary):
    """Polynomial smooth maximum ``-smin(-a, -b)`` with blend radius ``k``."""

    def __init__(self, a, b, k):
        super().__init__(a, b, bounds=_overlap(a.bounds, b.bounds))
        self.k = k

    def _value(self, p):
        return -_smin(-self.a._value(p), -self.b._value(p), self.k)[0]

    def _value_gradient(self, p):
        (fa, ga), (fb, gb) = self.a._value_gradient(p), self.b._value_gradient(p)
        f, h = _smin(-fa, -fb, self.k)
        return -f, h[:, None] * ga + (1.0 - h[:, None]) * gb


def smooth_union(a, b, radius) -> Implicit:
    """Union of ``a`` and ``b`` with a fillet of blend radius ``radius`` > 0 (model units)."""
    return SmoothUnion(_operand(a, "a"), _operand(b, "b"), positive(radius, "radius"))


def smooth_intersection(a, b, radius) -> Implicit:
    """Intersection of ``a`` and ``b`` with its edges rounded over ``radius`` > 0."""
    return SmoothIntersection(_operand(a, "a"), _operand(b, "b"), positive(radius, "radius"))


def smooth_difference(a, b, radius) -> Implicit:
    """``a`` minus ``b`` with the cut edges rounded over ``radius`` > 0."""
    return SmoothIntersection(_operand(a, "a"), complement(_operand(b, "b")), positive(radius, "radius"))


# -- offsets ------------------------------------------------------------------------------------
class Offset(Implicit):
    """``a - r``: grown by ``r`` (model units; shrunk for ``r < 0``)."""

    def __init__(self, a, r):
        exact = a.is_exact_sdf and a._convex and r >= 0
        super().__init__(
            bounds=_grown(a.bounds, a._growth * max(r, 0.0)), exact=exact, convex=a._convex and r >= 0, growth=a._growth
        )
        self.a, self.r = a, r

    def __repr__(self):
        return f"Offset({self.a!r}, {self.r!r})"

    def _value(self, p):
        return self.a._value(p) - self.r

    def _gradient(self, p):
        return self.a._gradient(p)

    def _value_gradient(self, p):
        f, g = self.a._value_gradient(p)
        return f - self.r, g

    def _hessian(self, p):
        return self.a._hessian(p)


class Shell(Implicit):
    """``|a| - t / 2``: a hollow shell of thickness ``t`` centred on ``a = 0``."""

    def __init__(self, a, t):
        super().__init__(bounds=_grown(a.bounds, a._growth * 0.5 * t), growth=a._growth)
        self.a, self.t = a, t

    def __repr__(self):
        return f"Shell({self.a!r}, {self.t!r})"

    def _value(self, p):
        return np.abs(self.a._value(p)) - 0.5 * self.t

    def _value_gradient(self, p):
        f, g = self.a._value_gradient(p)
        return np.abs(f) - 0.5 * self.t, np.where((f < 0.0)[:, None], -g, g)

    def _gradient(self, p):
        return self._value_gradient(p)[1]


def offset(a, distance) -> Implicit:
    """``a - r`` (see :class:`Offset`)."""
    return Offset(_operand(a, "a"), as_real(distance, "distance"))


def shell(a, thickness) -> Implicit:
    """``|a| - t / 2`` for a thickness ``t`` > 0 (see :class:`Shell`)."""
    return Shell(_operand(a, "a"), positive(thickness, "thickness"))


# -- transforms ---------------------------------------------------------------------------------
def rotation_matrix(matrix_or_axis, angle=None) -> np.ndarray:
    """A proper rotation ``(3, 3)`` from a matrix (checked orthogonal with
    det +1 to ``ORTHOGONALITY_TOL``) or from an axis ``(3,)`` and an angle in
    radians (Rodrigues' formula, right-handed about the axis)."""
    m = as_float_array(matrix_or_axis, "rotation")
    if angle is None:
        if m.shape != (3, 3):
            raise ParameterError(
                f"rotate takes a (3, 3) rotation matrix or an axis (3,) and an angle, got an array of shape {m.shape}"
            )
        if not np.isfinite(m).all():
            raise ParameterError(f"the rotation matrix must be finite, got {m.tolist()}")
        err = float(np.max(np.abs(m.T @ m - np.eye(3))))
        if err > ORTHOGONALITY_TOL:
            raise ParameterError(f"the rotation matrix is not orthogonal: max |R^T R - I| = {err:.3g} > {ORTHOGONALITY_TOL}")
        if np.linalg.det(m) < 0:
            raise ParameterError("the rotation matrix has det -1 (a reflection); rotate needs det +1")
        return m.copy()
    if m.shape != (3,) or not np.isfinite(m).all():
        raise ParameterError(f"the rotation axis must be a finite 3-D vector, got {matrix_or_axis!r}")
    length = float(np.linalg.norm(m))
    if not length > 0:
        raise ParameterError(f"the rotation axis must be non-zero, got {m.tolist()}")
    theta = as_real(angle, "angle")
    x, y, z = m / length
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(theta) * K + (1.0 - np.cos(theta)) * (K @ K)


class Transformed(Implicit):
    """``s a(R^T (p - t) / s)``: ``a`` scaled by ``s`` > 0, then rotated by ``R``,
    then moved by ``t``. Distances stay exact (``R`` orthogonal, ``s`` uniform)."""

    def __init__(self, a, R, t, s):
        # an axis-aligned cube of half-width w, rotated, has an axis-aligned box of
        # half-widths w * sum_j |R_ij|: the growth factor of the new box
        growth = a._growth * float(np.abs(R).sum(axis=1).max())
        super().__init__(bounds=self._box(a.bounds, R, t, s), exact=a.is_exact_sdf, convex=a._convex, growth=growth)
        self.a, self.R, self.t, self.s = a, R, t, s

    @staticmethod
    def _box(box, R, t, s):
        if box is None:
            return None
        lo, hi = box
        corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        moved = s * corners @ R.T + t
        return moved.min(axis=0), moved.max(axis=0)

    def __repr__(self):
        return f"Transformed({self.a!r}, s={self.s!r}, t={self.t.tolist()})"

    def _local(self, p):
        # row vectors: R^T (p - t) is (p - t) @ R
        return ((p - self.t) @ self.R) / self.s

    def _value(self, p):
        return self.s * self.a._value(self._local(p))

    def _gradient(self, p):
        return self.a._gradient(self._local(p)) @ self.R.T

    def _value_gradient(self, p):
        f, g = self.a._value_gradient(self._local(p))
        return self.s * f, g @ self.R.T

    def _hessian(self, p):
        H = self.a._hessian(self._local(p))
        return np.einsum("ij,njk,lk->nil", self.R, H, self.R) / self.s


def transformed(a, *, translation=None, rotation=None, scale=None) -> Implicit:
    """``a`` scaled (about the origin), then rotated, then translated; nested
    transforms are merged into one."""
    a = _operand(a, "a")
    R = np.eye(3) if rotation is None else rotation
    s = 1.0 if scale is None else positive(scale, "scale")
    if translation is None:
        t = np.zeros(3)
    else:
        t = as_float_array(translation, "translation")
        if t.shape != (3,) or not np.isfinite(t).all():
            raise ParameterError(f"translation must be a finite 3-D vector, got {translation!r}")
    if isinstance(a, Transformed):
        # outer (R, t, s) after inner (R1, t1, s1): R R1, t + s R t1, s s1
        return Transformed(a.a, R @ a.R, t + s * (R @ a.t), s * a.s)
    return Transformed(a, R, t.astype(np.float64), s)


# the operators and transforms of every Implicit build these nodes (base.py, _CSG)
register_csg(
    union=union,
    intersection=intersection,
    difference=difference,
    complement=complement,
    transformed=transformed,
    rotation_matrix=rotation_matrix,
    offset=offset,
    shell=shell,
)
