"""Bézier curves (rational or not) on the parameter [0, 1].

A Bézier curve of degree ``p`` is the B-spline on the knot vector
``[0]*(p+1) + [1]*(p+1)``; this class wraps that spline, so evaluation,
derivatives, splitting and elevation run through the same vectorized code as
every other spline (de Casteljau's triangle is the Cox-de Boor triangle on
those knots).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_points, as_weights
from ..basis import algebra
from ..basis.bernstein import bezier_knots
from ..errors import ParameterError
from .bspline import BSplineCurve, NurbsCurve, SplineCurve, _elevation_step

__all__ = ["BezierCurve"]


class BezierCurve:
    """(Rational) Bézier curve.

    Parameters
    ----------
    control_points : array_like, shape (p + 1, dim)
        At least two points; the degree is ``len(control_points) - 1``.
    weights : array_like, shape (p + 1,), optional
        Positive weights for a rational curve.
    """

    __slots__ = ("_spline",)

    def __init__(self, control_points, weights=None):
        P = as_points(control_points, min_count=(2,))
        p = P.shape[0] - 1
        if weights is None:
            spline = BSplineCurve(p, bezier_knots(p), P)
        else:
            spline = NurbsCurve(p, bezier_knots(p), P, as_weights(weights, (p + 1,)))
        object.__setattr__(self, "_spline", spline)

    @classmethod
    def _from_coefs(cls, coefs: np.ndarray, rational: bool):
        obj = object.__new__(cls)
        p = coefs.shape[0] - 1
        object.__setattr__(obj, "_spline", BSplineCurve._trusted(p, bezier_knots(p), coefs, rational))
        return obj

    def __reduce__(self):
        return (type(self)._from_coefs, (np.array(self._spline._coefs), self.is_rational))

    def __setattr__(self, name, value):
        raise AttributeError("BezierCurve is immutable; operations return new curves")

    # attributes
    degree = property(lambda self: self._spline.degree, doc="Degree ``p``.")
    control_points = property(lambda self: self._spline.control_points, doc="``(p + 1, dim)`` (read-only).")
    weights = property(lambda self: self._spline.weights, doc="``(p + 1,)`` or ``None``.")
    dim = property(lambda self: self._spline.dim, doc="Number of coordinates.")
    is_rational = property(lambda self: self._spline.is_rational)
    domain = (0.0, 1.0)

    def __len__(self):
        return len(self._spline)

    def __eq__(self, other):
        if not isinstance(other, BezierCurve):
            return NotImplemented
        return self._spline == other._spline

    def __hash__(self):
        return hash(("bezier", hash(self._spline)))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        return isinstance(other, BezierCurve) and self._spline.almost_equal(other._spline, tol)

    def __repr__(self):
        kind = "rational " if self.is_rational else ""
        return f"BezierCurve({kind}degree={self.degree}, dim={self.dim})"

    # evaluation
    def evaluate(self, t) -> np.ndarray:
        """Points ``t.shape + (dim,)`` for ``t`` in [0, 1]."""
        return self._spline.evaluate(t)

    __call__ = evaluate

    def derivatives(self, t, order: int = 1) -> np.ndarray:
        """``(order + 1,) + t.shape + (dim,)``: the curve and its derivatives."""
        return self._spline.derivatives(t, order)

    def tangent(self, t) -> np.ndarray:
        return self._spline.tangent(t)

    def arc_length(self, tol: float = 1e-12) -> float:
        return self._spline.arc_length(tol=tol)

    # operations
    def split(self, t):
        """Two Bézier curves on [0, t] and [t, 1], each reparametrized to [0, 1]."""
        left, right = self._spline.split(t)
        return (
            BezierCurve._from_coefs(left._coefs, self.is_rational),
            BezierCurve._from_coefs(right._coefs, self.is_rational),
        )

    def elevate(self, by: int = 1):
        """The same curve with degree ``p + by``."""
        by = _elevation_step(by, self.degree)
        E = algebra.bezier_elevation_matrix(self.degree, by)
        return BezierCurve._from_coefs(E @ self._spline._coefs, self.is_rational)

    def transform(self, matrix):
        return BezierCurve._from_coefs(self._spline.transform(matrix)._coefs, self.is_rational)

    def reverse(self):
        return BezierCurve._from_coefs(self._spline._coefs[::-1], self.is_rational)

    @classmethod
    def from_bspline(cls, curve: SplineCurve):
        """The Bézier form of a single-span spline curve (use ``curve.to_bezier()``
        for several spans); the parameter is mapped onto [0, 1]."""
        if not isinstance(curve, SplineCurve):
            raise ParameterError(f"expected a BSplineCurve or NurbsCurve, got {type(curve).__name__}")
        if curve.bezier_breakpoints().size != 2:
            raise ParameterError(
                f"curve has {curve.bezier_breakpoints().size - 1} knot spans; a Bézier curve has one "
                "(use curve.to_bezier() for the list of segments)"
            )
        return curve.to_bezier()[0]

    def to_bspline(self):
        """This curve as a :class:`BSplineCurve` / :class:`NurbsCurve` on [0, 1]."""
        return self._spline
