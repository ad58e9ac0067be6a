"""Tensor-product Bézier patches (rational or not) on [0, 1] x [0, 1].

:class:`BezierSurface` is defined in :mod:`splinekit.surfaces.bspline`, beside
the B-spline types it converts to and from; this module keeps its old import path.
"""

from .bspline import BezierSurface

__all__ = ["BezierSurface"]
