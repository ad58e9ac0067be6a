"""Exact distance from points to a triangle mesh: :class:`MeshDistance`, the one mesh distance of
splinekit (point-cloud queries, :func:`splinekit.implicit.from_mesh`, the conversion error
measurements of :mod:`splinekit.convert`).

Unsigned: the exact nearest triangle, closest point and distance of every query point, found by
one of two searches that answer the same question:

* compiled (numba, loaded by :func:`splinekit._kernels.load` for large queries): a depth-first
  walk of a bounding-volume hierarchy over Morton-ordered triangles (:class:`TriangleBVH`),
  nearer child first, each point starting from the previous point's triangle (grid points come
  in order, so that bound is tight and prunes most of the tree);
* numpy (small queries, or compiled code switched off): candidate triangles from a k-d tree over
  triangle centroids, then certified: no triangle outside the ``k`` candidates can be nearer than
  ``d_k - R`` (``d_k`` the k-th nearest centroid distance, ``R`` the largest centroid-to-corner
  distance of any triangle), so points whose best candidate is farther than that are re-queried
  with every triangle whose centroid lies within ``best + R``.

The closest point on a triangle follows the Voronoi-region classification of Ericson,
*Real-Time Collision Detection*, 5.1.5 (on whole arrays here, per point in the kernel, the same
tests in the same order), which also names the feature (face, edge or vertex) it lies on.

Signed (:meth:`MeshDistance.signed`, for a closed, consistently oriented mesh): the sign comes
from the angle-weighted pseudo-normal of that feature (Baerentzen & Aanaes 2005), which is exact
for such a mesh. On the samples of a grid, :meth:`MeshDistance.grid_signed` gives the same
answer with compiled code: by scanning the characteristic regions of the mesh's faces, edges
and vertices (:mod:`._gridsdf_scan`, its module notes), or, for a mesh with a triangle too thin
for a plane, with the kernel of :mod:`._gridsdf_kernels`, which shares most of the work over
blocks of samples.

Every query runs on a copy of the mesh moved and scaled (by a power of two, exactly) to the unit
box: the region tests multiply dot products (length^4) and the pseudo-normals take norms of
cross products, which would overflow for meshes of size ~1e77 and underflow for ~1e-77.
"""

from __future__ import annotations

import os
from functools import cached_property

import numpy as np

from .. import _kernels, limits
from ..errors import ControlPointError, NotManifoldError, ParameterError
from ..mesh.geometry import triangulate
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from ._cloud import as_cloud, kd_tree
from ._gridscan import SCAN_KERNELS, scan_grid
from ._meshsetup import SETUP_KERNELS, grid_arrays
from ._trianglebvh import TriangleBVH

__all__ = ["MeshDistance", "closest_points_on_mesh", "closest_points_on_triangles"]

CANDIDATES = 8
"""Nearest triangle centroids tried per point by the numpy search before its certification step."""

CHUNK = 65536
"""Points per block of the numpy search (bounds temporary memory)."""

EXHAUSTIVE_PAIRS = 1 << 18
"""Point-triangle pairs measured at once by the numpy search's certification step. A point deep
inside a fine mesh has nearly every triangle within its certification radius: 30,000 such points
against 16,600 triangles asked for 18.6 GB in one go before the step was split."""

PAIR_BYTES = 512
"""Bytes per point-triangle pair in that step (Python ints of the ball lists, the triangles'
corners, closest points and their temporaries), for the memory budget."""

KERNELS = "splinekit.pointcloud._meshdistance_kernels"

GRID_KERNELS = "splinekit.pointcloud._gridsdf_kernels"

GRID_BLOCK = 16
"""Samples along each side of the top blocks :meth:`MeshDistance.grid_signed` shares its work
over, halved level by level down to 2^3 (module notes of its kernels)."""

GRID_SCAN = True
"""Whether :meth:`MeshDistance.grid_signed` scans the regions of the mesh's features (False: the
block kernel on every mesh, as it serves meshes with a triangle too thin for a plane)."""

GRID_OPEN = 1.0
"""A block of the grid kernel keeps a hierarchy node (rather than opening it) when the node's
bounding radius is at most this many of the block's half-diagonals (82k triangles at 128^3,
one thread: 0.5, 1 and 2 within the noise of each other)."""

THIN = 1e-6
"""A triangle whose edge cross product is shorter than this times its two edges' lengths gets
no plane in the grid kernel's bounds (it is then always measured exactly)."""

GRID_WORK_BYTES = 1024
"""Bytes per triangle and thread of the grid kernel's work arrays: per level (four for
GRID_BLOCK = 16) and the root, a list of triangles with their 20 bound coefficients and a list
of hierarchy nodes (at most half as many as triangles), a node frontier and scratch values."""

# features of a closest point: 0 face interior, 1-3 vertex 0-2, 4 edge 01, 5 edge 12, 6 edge 20
FACE, EDGE01, EDGE12, EDGE20 = 0, 4, 5, 6


def _dot(x, y):
    return np.einsum("nd,nd->n", x, y)


def _on_segments(p, a, b):
    ab = b - a
    L = _dot(ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(L > 0, _dot(p - a, ab) / np.where(L > 0, L, 1.0), 0.0)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def _closest_and_feature(p, a, b, c):
    """Closest points ``(m, 3)`` of triangles ``(a, b, c)`` to points ``p`` (all ``(m, 3)``) and
    their features ``(m,)`` (module notes). Degenerate triangles are treated as their edges."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    feature = np.full(len(p), FACE, dtype=np.int64)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = va + vb + vc
        out = a + (vb / den)[:, None] * ab + (vc / den)[:, None] * ac
        # later assignments take precedence, in the reverse of Ericson's (and the kernel's) test order
        e = (d4 - d3) + (d5 - d6)
        regions = (
            ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), lambda: b + ((d4 - d3) / e)[:, None] * (c - b), EDGE12),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), lambda: a + (d2 / (d2 - d6))[:, None] * ac, EDGE20),
            ((d6 >= 0) & (d5 <= d6), lambda: c, 3),
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), lambda: a + (d1 / (d1 - d3))[:, None] * ab, EDGE01),
            ((d3 >= 0) & (d4 <= d3), lambda: b, 2),
            ((d1 <= 0) & (d2 <= 0), lambda: a, 1),
        )
        for m, point, code in regions:
            if m.any():
                out[m] = point()[m]
                feature[m] = code
    bad = ~np.isfinite(out).all(axis=1)
    if bad.any():
        q = [_on_segments(p[bad], x[bad], y[bad]) for x, y in ((a, b), (b, c), (c, a))]
        d = np.stack([np.linalg.norm(qq - p[bad], axis=1) for qq in q])
        k = d.argmin(axis=0)
        out[bad] = np.stack(q)[k, np.arange(d.shape[1])]
        feature[bad] = EDGE01 + k
    return out, feature


def closest_points_on_triangles(p, a, b, c) -> np.ndarray:
    """Closest points ``(m, 3)`` of triangles ``(a, b, c)`` to points ``p``, all ``(m, 3)``.

    Degenerate (zero-area) triangles are treated as their three edges.
    """
    return _closest_and_feature(p, a, b, c)[0]


QUERY_WORK = 60
"""Cost of one query point on the numpy path, in :mod:`splinekit._kernels` work units: 19-120
microseconds of CPU a point (meshes of 320 to 40,000 triangles, points near and far) where a
curve point costs 0.2-0.5, measured in one loaded run; sixty is the cheap end. So a first query
of 33,334 points or more loads the compiled search at once: near the 20,480 triangles of an
icosphere(5), the cheapest case measured, that first call took 0.62-0.63 s of CPU with the load
against 0.80-1.00 s on the numpy path (at twenty units it stayed on the numpy path up to
100,000 points)."""

MIN_QUERIES = 1000
"""Smallest query sent to the compiled search once it is loaded (the numpy path serves smaller
ones)."""


def _pseudo_normals(V, T, topo):
    """Angle-weighted pseudo-normals ``(face (m, 3), edge (m, 3, 3), vertex (n, 3))`` of a closed
    triangle mesh (its :class:`Topology` ``topo``); the edge array holds, per triangle and local
    edge (01, 12, 20), the sum of the unit normals of the edge's two triangles. NotManifoldError
    when an edge has not two triangles."""
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    n = np.cross(b - a, c - a)
    ln = np.linalg.norm(n, axis=1)
    fn = n / np.where(ln > 0, ln, 1.0)[:, None]
    # edges: corner k of triangle t is the half-edge T[t, k] -> T[t, k + 1]; the
    # topology's edge table gives the edge shared by the two triangles using it
    inv = topo.halfedge_edge
    counts = np.bincount(inv, minlength=len(topo.edges))
    if (counts != 2).any():
        e = int(np.flatnonzero(counts != 2)[0])
        a, b = (int(v) for v in topo.edges[e])
        raise NotManifoldError(
            f"the mesh is not closed: edge ({a}, {b}) has {int(counts[e])} triangles (a closed mesh has 2 on "
            "every edge); a signed distance needs a closed mesh"
        )
    rep = np.repeat(fn, 3, axis=0)
    esum = np.stack([np.bincount(inv, weights=rep[:, k]) for k in range(3)], axis=1)
    edge_n = esum[inv].reshape(len(T), 3, 3)
    # corner angles for the vertex normals
    P = V[T]
    ang = np.empty((len(T), 3))
    for k in range(3):
        u = P[:, (k + 1) % 3] - P[:, k]
        w = P[:, (k + 2) % 3] - P[:, k]
        ang[:, k] = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    corner_v = T.ravel()
    weighted = (fn[:, None, :] * ang[:, :, None]).reshape(-1, 3)
    vn = np.stack([np.bincount(corner_v, weights=weighted[:, k], minlength=len(V)) for k in range(3)], axis=1)
    return fn, edge_n, vn


class MeshDistance:
    """Reusable exact distance queries to one triangle mesh (module notes).

    Parameters
    ----------
    vertices : (nv, 3) float64
    triangles : (T, 3) int
        Any triangles for :meth:`query`; a closed, consistently oriented mesh for :meth:`signed`.
    """

    def __init__(self, vertices, triangles):
        V = as_cloud(vertices, "vertices")
        tris = np.ascontiguousarray(triangles, dtype=np.int64)
        if tris.ndim != 2 or tris.shape[1] != 3 or len(tris) == 0:
            raise ParameterError(f"triangles must have shape (T, 3) with T >= 1, got {tris.shape}")
        if tris.min() < 0 or tris.max() >= len(V):
            raise ParameterError(f"triangle indices must lie in [0, {len(V) - 1}]")
        self.V, self.tris = V, tris
        lo, hi = V.min(axis=0), V.max(axis=0)
        with np.errstate(over="ignore"):
            size = float((hi - lo).max())
        if not np.isfinite(size):
            raise ControlPointError("the mesh is wider than the float range; rescale it")
        self._shift = 0.5 * lo + 0.5 * hi
        # a power of two: scaling by it is exact
        self._scale = float(2.0 ** np.ceil(np.log2(max(size, np.finfo(float).tiny))))
        self.unit_vertices = (V - self._shift) / self._scale
        self.corners = self.unit_vertices[tris]

    @classmethod
    def of_mesh(cls, mesh):
        """The distance queries of a PolyMesh (faces fan-triangulated, which keeps their orientation)."""
        if not isinstance(mesh, PolyMesh):
            raise ParameterError(f"mesh must be a splinekit PolyMesh, got {type(mesh).__name__}")
        tris, _ = triangulate(mesh)
        return cls(mesh.vertices, tris)

    # -- search structures, built on first use ------------------------------------------------
    @cached_property
    def centroids(self) -> np.ndarray:
        return self.corners.mean(axis=1)

    @cached_property
    def reach(self) -> float:
        """Largest centroid-to-corner distance of any triangle (unit box)."""
        return float(np.linalg.norm(self.corners - self.centroids[:, None], axis=2).max())

    @cached_property
    def tree(self):
        """k-d tree over the triangle centroids (the numpy search)."""
        return kd_tree(self.centroids)

    @cached_property
    def bvh(self) -> TriangleBVH:
        """Bounding-volume hierarchy over the triangles (the compiled search; built by compiled
        passes too unless compiled code is switched off)."""
        return TriangleBVH(self.unit_vertices, self.tris, _kernels.load(SETUP_KERNELS))

    @cached_property
    def topology(self) -> Topology:
        """The triangles' connectivity: corner ``k`` of triangle ``t`` is half-edge ``3 t + k``."""
        return Topology(len(self.V), self.tris.ravel(), np.arange(len(self.tris) + 1, dtype=np.int64) * 3, check=False)

    @cached_property
    def pseudo_normals(self):
        """``(face, edge, vertex)`` pseudo-normals for :meth:`signed`; NotManifoldError when open."""
        return _pseudo_normals(self.unit_vertices, self.tris, self.topology)

    @cached_property
    def _grid_arrays(self):
        """The arrays below (and the region scan's connectivity) from the compiled set-up
        (:mod:`._meshsetup`), or None when compiled code is switched off."""
        K = _kernels.load(SETUP_KERNELS)
        return None if K is None else grid_arrays(K, self.unit_vertices, self.tris, self.bvh, THIN)

    @cached_property
    def _bvh_normals(self):
        """Pseudo-normals in the hierarchy's triangle order: face ``(m, 3)``, edge ``(m, 3, 3)``
        and, per triangle corner, vertex ``(m, 3, 3)``."""
        if self._grid_arrays is not None and self._grid_arrays.normals is not None:
            return self._grid_arrays.normals
        fn, en, vn = self.pseudo_normals
        order = self.bvh.order
        return (np.ascontiguousarray(fn[order]), np.ascontiguousarray(en[order]),
                np.ascontiguousarray(vn[self.tris[order]]))

    @cached_property
    def _bvh_planes(self):
        """Per triangle in the hierarchy's order: unit plane normal ``(m, 3)`` (zero for a
        triangle too thin for its normal to be accurate) and bounding ball ``(m, 4)`` (centroid,
        radius), for the bounds of :mod:`._gridsdf_kernels`."""
        if self._grid_arrays is not None:
            return self._grid_arrays.plane, self._grid_arrays.ball
        tri = self.bvh.tri
        e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        n = np.cross(e1, e2)
        ln = np.linalg.norm(n, axis=1)
        # a cross product this small against its edges has a direction rounding may turn
        thin = ~(ln > THIN * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1))
        plane = n / np.where(thin, 1.0, ln)[:, None]
        plane[thin] = 0.0
        cen = tri.mean(axis=1)
        rad = np.linalg.norm(tri - cen[:, None], axis=2).max(axis=1)
        ball = np.column_stack([cen, rad * (1.0 + 1e-12) + 1e-15])  # rounding may only widen it
        return np.ascontiguousarray(plane), np.ascontiguousarray(ball)

    @cached_property
    def _bvh_prisms(self):
        """Per triangle in the hierarchy's order, ``(m, 20)``: plane ``(n, n . a)``, edge lines
        ``(u_k, u_k . a_k)`` (unit in-plane normals pointing out) and bounding disk (centroid,
        radius), for the bound of :mod:`._gridsdf_kernels` (none for a triangle too thin)."""
        if self._grid_arrays is not None:
            return self._grid_arrays.prism
        tri = self.bvh.tri
        plane, ball = self._bvh_planes
        out = np.zeros((len(tri), 20))
        out[:, :3] = plane
        out[:, 3] = np.einsum("ij,ij->i", plane, tri[:, 0])
        for k in range(3):
            a, b = tri[:, k], tri[:, (k + 1) % 3]
            u = np.cross(b - a, plane)
            ln = np.linalg.norm(u, axis=1)
            u /= np.where(ln > 0, ln, 1.0)[:, None]
            out[:, 4 + 4 * k : 7 + 4 * k] = u
            out[:, 7 + 4 * k] = np.einsum("ij,ij->i", u, a)
        out[:, 16:] = ball  # its bounding disk: centroid and radius
        thin = ~plane.any(axis=1)
        out[thin] = 0.0
        out[thin, 19] = np.inf  # no disk either
        return out

    # -- queries ---------------------------------------------------------------------------
    def query(self, points):
        """``(distances (m,), closest points (m, 3), triangle (m,))`` of ``points`` ``(m, 3)``.

        Points so far from the mesh (about ``1e154`` times its size) that their
        squared distance overflows raise ControlPointError."""
        P = as_cloud(points, "points")
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused below
            dist, tri, close, _ = self._nearest((P - self._shift) / self._scale, np.inf)
            dist, close = dist * self._scale, close * self._scale + self._shift
        bad = ~(np.isfinite(dist) & np.isfinite(close).all(axis=1))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ControlPointError(
                f"the distance from points[{i}] = {P[i].tolist()} to the mesh overflows the float range; rescale"
            )
        return dist, close, tri

    def signed(self, points, max_distance=np.inf, *, kernels=None):
        """``(signed distance (m,), found (m,))`` in model units, negative inside, for finite
        ``points`` ``(m, 3)``; points farther than ``max_distance`` get ``inf`` and no sign
        (``found`` False). The mesh must be closed and consistently oriented (NotManifoldError
        otherwise); a mesh oriented inside out as a whole gets negated distances. ``kernels``:
        the compiled module :data:`KERNELS`, to search with it whatever the query's size (for a
        caller that has asked the loader itself because its own alternative costs far more per
        point than the numpy search); by default the query's size decides."""
        fn, en, vn = self.pseudo_normals
        P = (np.asarray(points, dtype=np.float64) - self._shift) / self._scale
        d, tri, cp, feature = self._nearest(P, max_distance / self._scale, kernels)
        found = tri >= 0
        t, f = tri[found], feature[found]
        normal = fn[t]
        vert = (f >= 1) & (f <= 3)
        normal[vert] = vn[self.tris[t[vert], f[vert] - 1]]
        edge = f >= EDGE01
        normal[edge] = en[t[edge], f[edge] - EDGE01]
        side = np.einsum("ij,ij->i", P[found] - cp[found], normal)
        out = d.copy()
        out[found] = np.where(side < 0, -d[found], d[found])
        return out * self._scale, found

    def grid_signed(self, origin, spacing, shape, max_distance=np.inf):
        """Signed distances (model units, negative inside) at the samples ``origin + (i, j, k) *
        spacing`` of a grid of ``shape`` (3 ints), as an array of that shape, ``inf`` beyond
        ``max_distance``; what :meth:`signed` gives at those points, computed by scanning the
        regions of the mesh's features (module notes of :mod:`splinekit.pointcloud._gridsdf_scan`)
        or by blocks of samples (:mod:`splinekit.pointcloud._gridsdf_kernels`). None when
        compiled code does not serve this job (then call :meth:`signed` on the points)."""
        shape = tuple(int(x) for x in shape)
        total = int(np.prod(shape))
        scan = _kernels.load(SCAN_KERNELS, work=total)
        if scan is None:
            return None
        o = (np.asarray(origin, dtype=np.float64) - self._shift) / self._scale
        h = np.asarray(spacing, dtype=np.float64) / self._scale
        with np.errstate(over="ignore"):
            limit = float(max_distance / self._scale) ** 2
        out = scan_grid(self, scan, o, h, shape, limit) if GRID_SCAN else None
        if out is None:  # a triangle too thin for a plane, or many knife edges: the block kernel
            limits.check(GRID_WORK_BYTES * len(self.tris) * (os.cpu_count() or 1),
                         f"the grid distance kernel's work arrays for {len(self.tris):,} triangles")
            fn, en, vn = self._bvh_normals
            b = self.bvh
            out = np.empty(total)
            _kernels.load(GRID_KERNELS).grid_signed(o, h, np.array(shape, dtype=np.int64), limit, GRID_BLOCK, GRID_OPEN,
                                                    b.lo, b.hi, b.tlo, b.thi, b.tri, b.n_leaves, b.m, fn, en, vn,
                                                    self._bvh_prisms, out)
        return (out * self._scale).reshape(shape)

    def _nearest(self, P, max_distance, kernels=None):
        """Nearest triangle of unit-box points ``P``: ``(d, triangle, closest, feature)``; beyond
        ``max_distance`` ``d`` is inf and the triangle -1. Compiled search for large queries
        (or whenever ``kernels`` is given)."""
        if kernels is None:
            kernels = _kernels.load(KERNELS, work=len(P) * QUERY_WORK, min_work=MIN_QUERIES * QUERY_WORK)
        if kernels is not None:
            return self.bvh.nearest(kernels, P, max_distance)
        dist, close, tri, feature = self._search(P)
        far = ~(dist <= max_distance)
        if far.any():
            dist[far], tri[far] = np.inf, -1
        return dist, tri, close, feature

    def _pairs(self, P, t):
        C = self.corners[t]
        q, feature = _closest_and_feature(P, C[:, 0], C[:, 1], C[:, 2])
        return q, np.linalg.norm(q - P, axis=1), feature

    def _search(self, P):
        """The numpy search (module notes): ``(d, closest, triangle, feature)`` of unit-box points."""
        m = len(P)
        dist, close = np.empty(m), np.empty((m, 3))
        tri, feature = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
        k = min(CANDIDATES, len(self.tris))
        for s in range(0, m, CHUNK):
            Q = P[s : s + CHUNK]
            dc, ic = self.tree.query(Q, k=k, workers=-1)
            dc, ic = dc.reshape(len(Q), k), ic.reshape(len(Q), k)
            # an overflowing distance leaves the tree without a candidate (index n): any
            # triangle will do, its distance overflows too and query refuses the point
            ic = np.minimum(ic, len(self.tris) - 1)
            q, d, f = self._pairs(np.repeat(Q, k, axis=0), ic.ravel())
            d = d.reshape(len(Q), k)
            j = d.argmin(axis=1)
            rows = np.arange(len(Q))
            best = d[rows, j]
            block = slice(s, s + len(Q))
            dist[block] = best
            close[block] = q.reshape(len(Q), k, 3)[rows, j]
            tri[block] = ic[rows, j]
            feature[block] = f.reshape(len(Q), k)[rows, j]
            if k < len(self.tris):
                unsure = np.flatnonzero(best > dc[:, -1] - self.reach)
                if unsure.size:
                    self._exhaustive(Q, s, unsure, best[unsure], (dist, close, tri, feature))
        return dist, close, tri, feature

    def _exhaustive(self, Q, s, unsure, best, out):
        """Certify the points ``Q[unsure]`` against every triangle within their radius, in groups
        of at most :data:`EXHAUSTIVE_PAIRS` pairs (one point's pairs always fit: at most all triangles)."""
        radius = best + self.reach * (1 + 1e-12) + 1e-300
        counts = np.asarray(self.tree.query_ball_point(Q[unsure], radius, workers=-1, return_length=True), dtype=np.int64)
        per_group = max(EXHAUSTIVE_PAIRS, len(self.tris))
        limits.check(per_group * PAIR_BYTES, "the point/triangle pairs of a mesh-distance query")
        ends = np.cumsum(counts)
        start = 0
        while start < len(unsure):
            base = ends[start - 1] if start else 0
            stop = max(start + 1, int(np.searchsorted(ends, base + per_group, side="right")))
            g = np.arange(start, stop)
            self._certify(Q, s, unsure[g], best[g], radius[g], out)
            start = stop

    def _certify(self, Q, s, unsure, best, radius, out):
        dist, close, tri, feature = out
        lists = self.tree.query_ball_point(Q[unsure], radius, workers=-1)
        counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
        if counts.sum() == 0:
            return
        t = np.fromiter((i for x in lists for i in x), dtype=np.int64, count=int(counts.sum()))
        owner = np.repeat(np.arange(len(unsure)), counts)
        q, d, f = self._pairs(Q[unsure][owner], t)
        order = np.lexsort((d, owner))
        first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]
        o = owner[first]
        better = d[first] < dist[s + unsure[o]]
        i = s + unsure[o[better]]
        pick = first[better]
        dist[i], close[i], tri[i], feature[i] = d[pick], q[pick], t[pick], f[pick]


def closest_points_on_mesh(mesh, points):
    """Exact distances ``(m,)``, closest points ``(m, 3)`` and triangle indices ``(m,)``
    from ``points`` ``(m, 3)`` to a polygon mesh (faces fan-triangulated)."""
    return MeshDistance.of_mesh(mesh).query(points)
