"""Differential geometry of curves and surfaces on (n, ...) arrays.

* :mod:`.protocol`: the parametric-surface protocol (``domain``, ``evaluate``,
  ``derivatives``) and adapters for user functions, graphs ``z = f(x, y)``,
  implicit surfaces and subdivision limit patches;
* :mod:`.curvature`: fundamental forms, Gaussian/mean/principal curvature and
  directions, shape operator (parametric and implicit surfaces);
* :mod:`.geodesics`: geodesic initial and boundary value problems;
* :mod:`.curves`: tangent, curvature, torsion, Frenet and rotation-minimizing
  frames, arc length and its inverse.
"""

from . import curves
from .curvature import ImplicitCurvature, SurfaceCurvature, curvature
from .geodesics import Geodesic, christoffel_symbols, geodesic, trace_geodesic
from .protocol import ExplicitSurface, ImplicitSurface, ParametricSurface, SubdivisionPatch, Surface

__all__ = [
    "curves",
    "curvature",
    "SurfaceCurvature",
    "ImplicitCurvature",
    "Geodesic",
    "geodesic",
    "trace_geodesic",
    "christoffel_symbols",
    "Surface",
    "ParametricSurface",
    "ExplicitSurface",
    "ImplicitSurface",
    "SubdivisionPatch",
]
