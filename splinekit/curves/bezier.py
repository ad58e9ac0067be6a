"""Bézier curves (rational or not) on the parameter [0, 1].

:class:`BezierCurve` is defined in :mod:`splinekit.curves.bspline`, beside the
B-spline types it converts to and from; this module keeps its old import path.
"""

from .bspline import BezierCurve

__all__ = ["BezierCurve"]
