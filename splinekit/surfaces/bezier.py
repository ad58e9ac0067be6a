"""Tensor-product Bézier patches (rational or not) on [0, 1] x [0, 1].

A patch of degrees ``(m, n)`` is the B-spline surface on Bézier knot vectors;
this class wraps that surface so every operation shares its code.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_direction, as_points, as_weights
from ..basis import algebra
from ..basis.bernstein import bezier_knots
from ..errors import ParameterError
from ..curves.bspline import _elevation_step
from .bspline import BSplineSurface, NurbsSurface, SplineSurface

__all__ = ["BezierSurface"]


class BezierSurface:
    """(Rational) tensor-product Bézier patch.

    Parameters
    ----------
    control_points : array_like, shape (m + 1, n + 1, dim)
        At least 2 x 2 points; degrees are ``(m, n)``.
    weights : array_like, shape (m + 1, n + 1), optional
    """

    __slots__ = ("_spline",)

    def __init__(self, control_points, weights=None):
        P = as_points(control_points, leading=2, min_count=(2, 2))
        m, n = P.shape[0] - 1, P.shape[1] - 1
        if weights is None:
            s = BSplineSurface(m, n, bezier_knots(m), bezier_knots(n), P)
        else:
            s = NurbsSurface(m, n, bezier_knots(m), bezier_knots(n), P, as_weights(weights, P.shape[:2]))
        object.__setattr__(self, "_spline", s)

    @classmethod
    def _from_coefs(cls, coefs, rational):
        obj = object.__new__(cls)
        m, n = coefs.shape[0] - 1, coefs.shape[1] - 1
        s = BSplineSurface._trusted(m, n, bezier_knots(m), bezier_knots(n), np.ascontiguousarray(coefs), rational)
        object.__setattr__(obj, "_spline", s)
        return obj

    def __reduce__(self):
        return (type(self)._from_coefs, (np.array(self._spline._coefs), self.is_rational))

    def __setattr__(self, name, value):
        raise AttributeError("BezierSurface is immutable; operations return new surfaces")

    degree_u = property(lambda self: self._spline.degree_u)
    degree_v = property(lambda self: self._spline.degree_v)
    control_points = property(lambda self: self._spline.control_points, doc="``(m + 1, n + 1, dim)`` (read-only).")
    weights = property(lambda self: self._spline.weights)
    dim = property(lambda self: self._spline.dim)
    is_rational = property(lambda self: self._spline.is_rational)
    shape = property(lambda self: self._spline.shape)
    domain = ((0.0, 1.0), (0.0, 1.0))

    def __eq__(self, other):
        if not isinstance(other, BezierSurface):
            return NotImplemented
        return self._spline == other._spline

    def __hash__(self):
        return hash(("bezier", hash(self._spline)))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        return isinstance(other, BezierSurface) and self._spline.almost_equal(other._spline, tol)

    def __repr__(self):
        kind = "rational " if self.is_rational else ""
        return f"BezierSurface({kind}degree=({self.degree_u}, {self.degree_v}), dim={self.dim})"

    def evaluate(self, u, v):
        """Points at pairs ``(u, v)``: ``u.shape + (dim,)``."""
        return self._spline.evaluate(u, v)

    __call__ = evaluate

    def evaluate_grid(self, us, vs):
        return self._spline.evaluate_grid(us, vs)

    def derivatives(self, u, v, order: int = 1):
        """``(order + 1, order + 1) + u.shape + (dim,)``; ``[k, l]`` is d^(k+l)S/du^k dv^l."""
        return self._spline.derivatives(u, v, order)

    def normal(self, u, v):
        return self._spline.normal(u, v)

    def split(self, t, direction="u"):
        """Two patches split at ``t`` in one direction, each on [0, 1]^2."""
        a, b = self._spline.split(t, direction)
        return BezierSurface._from_coefs(a._coefs, self.is_rational), BezierSurface._from_coefs(b._coefs, self.is_rational)

    def elevate(self, by: int = 1, direction="u"):
        """The same patch with one degree raised by ``by``."""
        d = as_direction(direction)
        by = _elevation_step(by, self.degree_u if d == 0 else self.degree_v)
        C = self._spline._coefs
        if d == 0:
            C = np.einsum("ij,jk...->ik...", algebra.bezier_elevation_matrix(self.degree_u, by), C)
        else:
            C = np.einsum("ij,kj...->ki...", algebra.bezier_elevation_matrix(self.degree_v, by), C)
        return BezierSurface._from_coefs(C, self.is_rational)

    def transform(self, matrix):
        return BezierSurface._from_coefs(self._spline.transform(matrix)._coefs, self.is_rational)

    @classmethod
    def from_bspline(cls, surface: SplineSurface):
        """The Bézier form of a single-patch spline surface (else use ``surface.to_bezier()``)."""
        if not isinstance(surface, SplineSurface):
            raise ParameterError(f"expected a BSplineSurface or NurbsSurface, got {type(surface).__name__}")
        bu, bv = surface.bezier_breakpoints()
        if bu.size != 2 or bv.size != 2:
            raise ParameterError(
                f"surface has {bu.size - 1} x {bv.size - 1} patches; use surface.to_bezier() for the list"
            )
        return surface.to_bezier()[0][0]

    def to_bspline(self):
        """This patch as a :class:`BSplineSurface` / :class:`NurbsSurface` on [0, 1]^2."""
        return self._spline
