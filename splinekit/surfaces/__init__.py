"""Bézier, B-spline and NURBS tensor-product surfaces."""

from .bspline import BezierSurface, BSplineSurface, NurbsSurface, SplineSurface

__all__ = ["BezierSurface", "BSplineSurface", "NurbsSurface", "SplineSurface"]
