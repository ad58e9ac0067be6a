"""Edges of trimmed faces: a trimming curve in a face's (u, v) domain, the 3-D curve and the
key that pairs it with the neighbouring face's use of the same edge.

An :class:`Edge` is one *use* of an edge by one face (OpenCascade calls it a coedge with its
pcurve). Two faces that share an edge each hold their own ``Edge`` with their own pcurve; the
two uses carry the same ``key`` (OCC import sets it from the shared ``TopoDS_Edge``; sewing sets
it geometrically), and :class:`~splinekit.brep.Shell` pairs them.
"""

from __future__ import annotations

from functools import partial
from typing import Hashable

import numpy as np

from ..curves import BezierCurve, SplineCurve
from ..errors import ParameterError
from .._validate import as_positive
from ..tolerances import OCC_CONFUSION

__all__ = ["Edge", "as_pcurve"]

DEFAULT_TOLERANCE = OCC_CONFUSION
"""Default geometric tolerance of edges and faces (model units), OpenCascade's Precision::Confusion."""


def as_pcurve(curve, what: str = "pcurve", dim: int = 2) -> SplineCurve:
    """``curve`` (a Bézier, B-spline or NURBS curve of dimension ``dim``) as a SplineCurve."""
    if isinstance(curve, BezierCurve):
        curve = curve.to_bspline()
    if not isinstance(curve, SplineCurve):
        raise ParameterError(f"{what} must be a Bézier, B-spline or NURBS curve, got {type(curve).__name__}")
    if curve.dim != dim:
        raise ParameterError(f"{what} must have {dim}-D control points, got {curve.dim}-D")
    return curve


class Edge:
    """One face's use of an edge.

    Parameters
    ----------
    pcurve : 2-D curve
        The trimming curve in the face's ``(u, v)`` parameter plane, oriented so that the face's
        material lies to its left in ``(u, v)`` (outer loops run counter-clockwise, inner loops
        clockwise), whatever the face's ``reversed`` flag.
    curve : 3-D curve, optional
        The edge's curve in space, sharing the pcurve's parameter and direction
        (``surface(pcurve(t)) ~= curve(t)`` within ``tolerance``, OpenCascade's SameParameter).
        ``None`` for a degenerate edge (a pole, a collapsed side) or when only the trim is known.
    key : hashable, optional
        Identity shared by the two uses of one edge in a shell (``None``: not shared / unknown).
    degenerate : bool
        The edge's 3-D image is a single point (a sphere's pole, a cone's apex).
    tolerance : float
        Geometric tolerance of the edge (model units).
    """

    __slots__ = ("_pcurve", "_curve", "_key", "_degenerate", "_tolerance")

    def __init__(self, pcurve, curve=None, *, key: Hashable | None = None, degenerate: bool = False,
                 tolerance: float = DEFAULT_TOLERANCE):
        object.__setattr__(self, "_pcurve", as_pcurve(pcurve))
        object.__setattr__(self, "_curve", None if curve is None else as_pcurve(curve, "curve", 3))
        try:
            hash(key)
        except TypeError:
            raise ParameterError(f"edge key must be hashable, got {type(key).__name__}") from None
        object.__setattr__(self, "_key", key)
        object.__setattr__(self, "_degenerate", bool(degenerate))
        object.__setattr__(self, "_tolerance", as_positive(tolerance, "tolerance"))

    def __setattr__(self, name, value):
        raise AttributeError("Edge is immutable")

    def __reduce__(self):
        # pickling (worker processes, caches): rebuild through the constructor, which the
        # immutable __setattr__ would otherwise block
        return (partial(Edge, key=self._key, degenerate=self._degenerate, tolerance=self._tolerance),
                (self._pcurve, self._curve))

    pcurve = property(lambda self: self._pcurve, doc="2-D trimming curve in the face's (u, v) plane.")
    curve = property(lambda self: self._curve, doc="3-D curve (same parameter as the pcurve) or None.")
    key = property(lambda self: self._key, doc="Identity shared with the neighbouring face's use, or None.")
    degenerate = property(lambda self: self._degenerate, doc="Whether the edge collapses to a point in 3-D.")
    tolerance = property(lambda self: self._tolerance, doc="Geometric tolerance (model units).")

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter range ``(t0, t1)`` of the pcurve (and of the 3-D curve)."""
        return self._pcurve.domain

    @property
    def start_uv(self) -> np.ndarray:
        """``(2,)`` first point of the pcurve."""
        return self._pcurve.evaluate(self.domain[0])

    @property
    def end_uv(self) -> np.ndarray:
        """``(2,)`` last point of the pcurve."""
        return self._pcurve.evaluate(self.domain[1])

    def reversed(self) -> "Edge":
        """The same edge traversed the other way (pcurve and 3-D curve reversed)."""
        return Edge(self._pcurve.reverse(), None if self._curve is None else self._curve.reverse(),
                    key=self._key, degenerate=self._degenerate, tolerance=self._tolerance)

    def with_key(self, key) -> "Edge":
        """A copy with another ``key``."""
        return Edge(self._pcurve, self._curve, key=key, degenerate=self._degenerate, tolerance=self._tolerance)

    def __repr__(self):
        a, b = self.domain
        kind = "degenerate " if self._degenerate else ""
        return f"Edge({kind}pcurve degree {self._pcurve.degree} on [{a:g}, {b:g}], curve={'yes' if self._curve is not None else 'no'}, key={self._key!r})"
