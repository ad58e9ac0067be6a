"""Bézier, B-spline and NURBS curves."""

from .bezier import BezierCurve
from .bspline import BSplineCurve, NurbsCurve, SplineCurve

__all__ = ["BezierCurve", "BSplineCurve", "NurbsCurve", "SplineCurve"]
