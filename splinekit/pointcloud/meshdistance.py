"""Exact unsigned distance from points to a triangle mesh.

Candidate triangles come from a k-d tree over triangle centroids; the result is
then certified: no triangle outside the ``k`` candidates can be nearer than
``d_k - R`` (``d_k`` the k-th nearest centroid distance, ``R`` the largest
centroid-to-corner distance of any triangle), so points whose best candidate is
farther than that are re-queried with every triangle whose centroid lies within
``best + R``. The closest point on each triangle follows the Voronoi-region
classification of Ericson, *Real-Time Collision Detection*, 5.1.5, on whole
arrays.
"""

from __future__ import annotations

import numpy as np

from ..errors import ControlPointError, ParameterError
from ._cloud import as_cloud, kd_tree

__all__ = ["MeshDistance", "closest_points_on_mesh", "closest_points_on_triangles"]

CANDIDATES = 8
"""Nearest triangle centroids tried per point before the certification step."""

CHUNK = 65536


def _dot(x, y):
    return np.einsum("nd,nd->n", x, y)


def _on_segments(p, a, b):
    ab = b - a
    L = _dot(ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(L > 0, _dot(p - a, ab) / np.where(L > 0, L, 1.0), 0.0)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def closest_points_on_triangles(p, a, b, c) -> np.ndarray:
    """Closest points ``(m, 3)`` of triangles ``(a, b, c)`` to points ``p``, all ``(m, 3)``.

    Degenerate (zero-area) triangles are treated as their three edges.
    """
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        den = va + vb + vc
        out = a + (vb / den)[:, None] * ab + (vc / den)[:, None] * ac
        # later assignments take precedence, in the reverse of Ericson's test order
        e = (d4 - d3) + (d5 - d6)
        m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
        out[m] = (b + ((d4 - d3) / e)[:, None] * (c - b))[m]
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        out[m] = (a + (d2 / (d2 - d6))[:, None] * ac)[m]
        m = (d6 >= 0) & (d5 <= d6)
        out[m] = c[m]
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        out[m] = (a + (d1 / (d1 - d3))[:, None] * ab)[m]
        m = (d3 >= 0) & (d4 <= d3)
        out[m] = b[m]
        m = (d1 <= 0) & (d2 <= 0)
        out[m] = a[m]
    bad = ~np.isfinite(out).all(axis=1)
    if bad.any():
        q = [_on_segments(p[bad], x[bad], y[bad]) for x, y in ((a, b), (b, c), (c, a))]
        d = np.stack([np.linalg.norm(qq - p[bad], axis=1) for qq in q])
        out[bad] = np.stack(q)[d.argmin(axis=0), np.arange(d.shape[1])]
    return out


class MeshDistance:
    """Reusable distance queries to one triangle mesh.

    Parameters
    ----------
    vertices : (nv, 3) float64
    triangles : (T, 3) int
    """

    def __init__(self, vertices, triangles):
        V = as_cloud(vertices, "vertices")
        tris = np.asarray(triangles, dtype=np.int64)
        if tris.ndim != 2 or tris.shape[1] != 3 or len(tris) == 0:
            raise ParameterError(f"triangles must have shape (T, 3) with T >= 1, got {tris.shape}")
        if tris.min() < 0 or tris.max() >= len(V):
            raise ParameterError(f"triangle indices must lie in [0, {len(V) - 1}]")
        self.V, self.tris = V, tris
        # the Voronoi-region tests multiply dot products (length^4): they run on a copy
        # moved and scaled (by a power of two, exactly) to the unit box, so meshes of any
        # size neither overflow nor underflow; results are scaled back
        lo, hi = V.min(axis=0), V.max(axis=0)
        with np.errstate(over="ignore"):
            size = float((hi - lo).max())
        if not np.isfinite(size):
            raise ControlPointError("the mesh is wider than the float range; rescale it")
        self._shift = 0.5 * lo + 0.5 * hi
        self._scale = float(2.0 ** np.ceil(np.log2(max(size, np.finfo(float).tiny))))
        self.corners = ((V - self._shift) / self._scale)[tris]
        self.centroids = self.corners.mean(axis=1)
        self.reach = float(np.linalg.norm(self.corners - self.centroids[:, None], axis=2).max())
        self.tree = kd_tree(self.centroids)

    @classmethod
    def of_mesh(cls, mesh):
        """The distance queries of a PolyMesh (faces fan-triangulated)."""
        from ..mesh.geometry import triangulate
        from ..mesh.polymesh import PolyMesh

        if not isinstance(mesh, PolyMesh):
            raise ParameterError(f"mesh must be a splinekit PolyMesh, got {type(mesh).__name__}")
        tris, _ = triangulate(mesh)
        return cls(mesh.vertices, tris)

    def _pairs(self, P, t):
        C = self.corners[t]
        q = closest_points_on_triangles(P, C[:, 0], C[:, 1], C[:, 2])
        return q, np.linalg.norm(q - P, axis=1)

    def query(self, points):
        """``(distances (m,), closest points (m, 3), triangle (m,))`` of ``points`` ``(m, 3)``.

        Points so far from the mesh (about ``1e154`` times its size) that their
        squared distance overflows raise ControlPointError."""
        P = as_cloud(points, "points")
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused below
            dist, close, tri = self._query((P - self._shift) / self._scale)
            dist, close = dist * self._scale, close * self._scale + self._shift
        bad = ~(np.isfinite(dist) & np.isfinite(close).all(axis=1))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ControlPointError(
                f"the distance from points[{i}] = {P[i].tolist()} to the mesh overflows the float range; rescale"
            )
        return dist, close, tri

    def _query(self, P):
        m = len(P)
        dist, close, tri = np.empty(m), np.empty((m, 3)), np.empty(m, dtype=np.int64)
        k = min(CANDIDATES, len(self.tris))
        for s in range(0, m, CHUNK):
            Q = P[s:s + CHUNK]
            dc, ic = self.tree.query(Q, k=k, workers=-1)
            dc, ic = dc.reshape(len(Q), k), ic.reshape(len(Q), k)
            # an overflowing distance leaves the tree without a candidate (index n): any
            # triangle will do, its distance overflows too and query refuses the point
            ic = np.minimum(ic, len(self.tris) - 1)
            q, d = self._pairs(np.repeat(Q, k, axis=0), ic.ravel())
            d = d.reshape(len(Q), k)
            j = d.argmin(axis=1)
            rows = np.arange(len(Q))
            best = d[rows, j]
            dist[s:s + len(Q)] = best
            close[s:s + len(Q)] = q.reshape(len(Q), k, 3)[rows, j]
            tri[s:s + len(Q)] = ic[rows, j]
            if k < len(self.tris):
                unsure = np.flatnonzero(best > dc[:, -1] - self.reach)
                if unsure.size:
                    self._exhaustive(Q, s, unsure, best[unsure], dist, close, tri)
        return dist, close, tri

    def _exhaustive(self, Q, s, unsure, best, dist, close, tri):
        lists = self.tree.query_ball_point(Q[unsure], best + self.reach * (1 + 1e-12) + 1e-300, workers=-1)
        counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
        if counts.sum() == 0:
            return
        t = np.fromiter((i for x in lists for i in x), dtype=np.int64, count=int(counts.sum()))
        owner = np.repeat(np.arange(len(unsure)), counts)
        q, d = self._pairs(Q[unsure][owner], t)
        order = np.lexsort((d, owner))
        first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]
        o = owner[first]
        better = d[first] < dist[s + unsure[o]]
        i = s + unsure[o[better]]
        dist[i], close[i], tri[i] = d[first][better], q[first][better], t[first][better]


def closest_points_on_mesh(mesh, points):
    """Exact distances ``(m,)``, closest points ``(m, 3)`` and triangle indices ``(m,)``
    from ``points`` ``(m, 3)`` to a polygon mesh (faces fan-triangulated)."""
    return MeshDistance.of_mesh(mesh).query(points)
