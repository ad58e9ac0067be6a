"""Affine surface patches written as OCC planes.

splinekit's surfaces are all B-splines, so a plane read from a file comes back as a bilinear patch
whose control net is a parallelogram (:func:`splinekit.tessellation.trimmed._is_affine`). Written
as a ``Geom_BSplineSurface`` such a face is free-form to OCC's STEP reader, whose shape healing
re-fits pcurves that lie off their 3-D curves; on a ``Geom_Plane`` it leaves them (measured on the
CATIA ventilator's plane face 10, whose edges have 0.014-0.028 mm gaps: its area change over
export -> import falls from 8.3e-2 to 3.1e-3 mm2, the solid's volume change from 4.8e-6 to 1.8e-8
relative). Gaps between an edge's end and its vertex are still closed by the reader, planes or not.
Planes are also what other CAD systems expect to read.

An affine patch is ``S(u, v) = O + u a + v b`` (``a``, ``b``: 3-D vectors, not parallel). The plane
gets the right-handed orthonormal frame ``X = a / |a|``, ``N = a x b / |a x b|``, ``Y = N x X``, so
its normal is the patch's and a face keeps its orientation; its coordinates are
``(x, y) = M (u, v)`` with ``M = [[a.X, b.X], [0, b.Y]]``. A pcurve maps exactly under ``M``
(B-spline and NURBS curves are affine invariant: map the control points, keep the weights); the
edges' 3-D curves are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..surfaces import BezierSurface, SplineSurface
from ..tessellation.trimmed import _is_affine
from .occ_backend import _ocp

__all__ = ["PlaneFrame", "plane_frame", "plane_to_occ"]

_IDENTITY = 4.0 * np.finfo(np.float64).eps
"""A map ``M`` this close to the identity is the identity: the patch already has the plane's
orthonormal parameter (a plane read from a file keeps OCC's), so its pcurves pass unchanged."""


@dataclass(frozen=True)
class PlaneFrame:
    """The plane of an affine patch: ``origin`` (the patch at (u, v) = (0, 0)), orthonormal
    ``x_dir``, ``y_dir`` and ``normal`` (``(3,)`` each, in the model's length unit), and
    ``matrix``, the ``(2, 2)`` map from the patch's (u, v) to the plane's (x, y), or None when
    that map is the identity."""

    origin: np.ndarray
    x_dir: np.ndarray
    y_dir: np.ndarray
    normal: np.ndarray
    matrix: np.ndarray | None

    def map_pcurve(self, curve):
        """The 2-D ``curve`` in (u, v) as the same curve in the plane's (x, y)."""
        return curve if self.matrix is None else curve.transform(self.matrix)


def plane_frame(surface) -> PlaneFrame | None:
    """The :class:`PlaneFrame` of ``surface`` when it is an affine 3-D patch, else None."""
    if not isinstance(surface, (SplineSurface, BezierSurface)) or not _is_affine(surface):
        return None
    P = np.asarray(surface.control_points, dtype=np.float64)
    if P.shape[-1] != 3:
        return None
    (u0, u1), (v0, v1) = surface.domain
    a = (P[1, 0] - P[0, 0]) / (u1 - u0)
    b = (P[0, 1] - P[0, 0]) / (v1 - v0)
    n = np.cross(a, b)
    if not np.linalg.norm(n) > 0.0:
        return None  # a collapsed patch (a line or a point) is no plane
    X = a / np.linalg.norm(a)
    N = n / np.linalg.norm(n)
    Y = np.cross(N, X)
    M = np.array([[a @ X, b @ X], [0.0, b @ Y]])
    identity = bool(np.abs(M - np.eye(2)).max() <= _IDENTITY)
    origin = P[0, 0] - u0 * a - v0 * b
    return PlaneFrame(origin, X, Y, N, None if identity else M)


def plane_to_occ(frame: PlaneFrame):
    """A ``Geom_Plane`` with ``frame``'s origin, normal and x direction."""
    Geom, gp = _ocp("Geom", "gp")
    axes = gp.gp_Ax3(gp.gp_Pnt(*frame.origin.tolist()), gp.gp_Dir(*frame.normal.tolist()),
                     gp.gp_Dir(*frame.x_dir.tolist()))
    return Geom.Geom_Plane(axes)
