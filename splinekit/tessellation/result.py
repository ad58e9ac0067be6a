"""Result types of :func:`splinekit.tessellation.tessellate`.

:class:`Tessellation` is a triangle :class:`~splinekit.PolyMesh` that also
carries, per vertex, the exact surface normal, the patch parameters and the
patch index, per face the patch index, and the achieved chordal deviation.
:class:`Polyline` is the result for a curve.
"""

from __future__ import annotations

import numpy as np

from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology

__all__ = ["Polyline", "Tessellation"]


def _frozen(a, dtype=np.float64):
    out = np.ascontiguousarray(a, dtype=dtype)
    out.setflags(write=False)
    return out


class Tessellation(PolyMesh):
    """A watertight triangle mesh of one or more parametric patches.

    Besides everything a :class:`~splinekit.PolyMesh` offers (``vertices``
    ``(n, 3)``, ``faces`` ``(F, 3)``, ``is_closed``, ``volume``, ...):

    Attributes
    ----------
    normals : (n, 3) float64
        Exact unit surface normals ``Su x Sv / |Su x Sv|`` at the vertices (the
        limit normal at a collapsed edge such as a pole); for a closed body
        whose patches face inward, triangles and normals are flipped so the
        body faces outward (positive volume). A vertex shared by several
        patches carries the normal of one of them.
    uv : (n, 2) float64
        Parameters of each vertex in its patch (``vertex_patch``).
    vertex_patch : (n,) int64
        Index of the patch (in the order the patches were given) each vertex
        was evaluated on.
    face_patch : (F,) int64
        Index of the patch each triangle belongs to.
    corner_uv : (F, 3, 2) float64
        Parameters of each triangle corner in the triangle's own patch (a
        vertex on an edge shared by two patches has different parameters in
        each; ``uv`` holds only one of them). A point with barycentric
        coordinates ``b`` in a triangle maps to ``b @ corner_uv[f]``.
    max_deviation : float
        Largest distance (model units) between the exact surface point at the
        parametric centre of a triangle, or at the parametric midpoint of an
        edge, and the corresponding point of the flat triangle or edge.
    tolerance : float
        The absolute chordal tolerance that was requested (model units).
    """

    __slots__ = ()

    @classmethod
    def _build(cls, vertices, triangles, normals, uv, vertex_patch, face_patch, corner_uv, max_deviation, tolerance):
        tris = np.ascontiguousarray(triangles, dtype=np.int64)
        topology = Topology(len(vertices), tris.ravel(), np.arange(len(tris) + 1, dtype=np.int64) * 3, check=False)
        obj = cls._adopt(vertices, topology)
        for name, value in (
            ("normals", _frozen(normals)),
            ("uv", _frozen(uv)),
            ("vertex_patch", _frozen(vertex_patch, np.int64)),
            ("face_patch", _frozen(face_patch, np.int64)),
            ("_corner_source", corner_uv),
            ("max_deviation", float(max_deviation)),
            ("tolerance", float(tolerance)),
        ):
            obj.__dict__[name] = value
        return obj

    @property
    def corner_uv(self) -> np.ndarray:
        """``(F, 3, 2)`` parameters of each triangle corner in the triangle's own patch."""
        cached = self.__dict__.get("_corner_uv")
        if cached is None:
            src = self.__dict__["_corner_source"]
            if isinstance(src, tuple):  # (pre-weld uv, triangles before the edge block, their pre-weld corners)
                uv, n_in, edge = src
                cached = np.concatenate([uv[self.faces[:n_in]], uv[edge]])
            else:
                cached = np.asarray(src, dtype=np.float64)
            cached = _frozen(cached)
            self.__dict__["_corner_uv"] = cached
            self.__dict__["_corner_source"] = cached
        return cached

    def __reduce__(self):
        return (
            _rebuild_tessellation,
            (
                np.array(self.vertices),
                np.array(self.faces),
                np.array(self.normals),
                np.array(self.uv),
                np.array(self.vertex_patch),
                np.array(self.face_patch),
                np.array(self.corner_uv),
                self.max_deviation,
                self.tolerance,
            ),
        )

    def __repr__(self):
        return (
            f"Tessellation(vertices={self.n_vertices}, triangles={self.n_faces}, "
            f"patches={int(self.face_patch.max()) + 1 if self.n_faces else 0}, "
            f"max_deviation={self.max_deviation:.3g}, tolerance={self.tolerance:.3g})"
        )


def _rebuild_tessellation(*args):
    return Tessellation._build(*args)


class Polyline:
    """An adaptive polyline of a curve.

    Attributes
    ----------
    points : (n, dim) float64
        Points on the curve, in parameter order.
    params : (n,) float64
        Curve parameters of the points (increasing).
    max_deviation : float
        Largest distance between the curve point at the parametric midpoint of
        a segment and the segment's midpoint (model units).
    tolerance : float
        The absolute chordal tolerance that was requested.
    """

    __slots__ = ("max_deviation", "params", "points", "tolerance")

    def __init__(self, points, params, max_deviation, tolerance):
        for name, value in (
            ("points", _frozen(points)),
            ("params", _frozen(params)),
            ("max_deviation", float(max_deviation)),
            ("tolerance", float(tolerance)),
        ):
            object.__setattr__(self, name, value)

    def __setattr__(self, name, value):
        raise AttributeError("Polyline is immutable")

    def __len__(self):
        return len(self.points)

    @property
    def segments(self) -> np.ndarray:
        """``(n - 1, 2)`` index pairs of consecutive points."""
        i = np.arange(len(self.points) - 1)
        return np.column_stack([i, i + 1])

    def __repr__(self):
        return (
            f"Polyline(points={len(self.points)}, max_deviation={self.max_deviation:.3g}, "
            f"tolerance={self.tolerance:.3g})"
        )
