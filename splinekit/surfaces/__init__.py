"""Bézier, B-spline and NURBS tensor-product surfaces."""

from .bezier import BezierSurface
from .bspline import BSplineSurface, NurbsSurface, SplineSurface

__all__ = ["BezierSurface", "BSplineSurface", "NurbsSurface", "SplineSurface"]
