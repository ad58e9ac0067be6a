"""Bézier, B-spline and NURBS curves."""

from .bspline import BezierCurve, BSplineCurve, NurbsCurve, SplineCurve

__all__ = ["BezierCurve", "BSplineCurve", "NurbsCurve", "SplineCurve"]
