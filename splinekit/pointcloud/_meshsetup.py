"""The per-triangle and per-vertex arrays of :class:`~splinekit.pointcloud.meshdistance.MeshDistance`'s
compiled grid searches, built in a few compiled passes (:mod:`._meshsetup_kernels`) instead of
the numpy builders that stay beside them (``MeshDistance._bvh_planes``, ``_bvh_prisms``,
``_bvh_normals``, :func:`._gridscan.adjacency`), with which they agree bit for bit.

Why: on a grid of 1.9 M samples about an 82k-triangle mesh the region scan itself took 0.4 s of
two threads, and the numpy set-up before it (pseudo-normals with their edge table and scatter
sums, the hierarchy's planes and prisms, their copies into the hierarchy's order, the scan's
connectivity) 0.25-0.3 s of one. Here every per-triangle array is made once, in the
hierarchy's order, in parallel; the pseudo-normals of edges and vertices are gathered (each
half-edge's twin, found through a vertex -> corner list, and each vertex's corners) instead of
summed by ``bincount`` over a sorted edge table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import limits

SETUP_KERNELS = "splinekit.pointcloud._meshsetup_kernels"

MAX_VALENCE = 64
"""Most triangles at a vertex for the compiled connectivity: it finds twins and sorts neighbours
by scanning each vertex's corners (quadratic in the valence); a mesh with a busier vertex (a fan
of thousands of triangles) takes the numpy builders' sorts instead."""

SETUP_BYTES = 640
"""Bytes per triangle of the compiled set-up's arrays (about 80 numbers), for the memory budget."""


@dataclass(frozen=True)
class GridArrays:
    """A mesh's arrays for the compiled grid searches, triangles in the hierarchy's order.

    ``plane (m, 3)``, ``ball (m, 4)``, ``prism (m, 20)``: as ``MeshDistance._bvh_planes`` and
    ``_bvh_prisms``; ``normals``: ``(face (m, 3), edge (m, 3, 3), vertex per corner (m, 3, 3))``
    pseudo-normals as ``MeshDistance._bvh_normals``, and ``adjacency``: the region scan's
    connectivity as :func:`._gridscan.adjacency` gives it; both None unless the mesh is closed
    and consistently oriented (every half-edge has exactly one opposite) with at most
    :data:`MAX_VALENCE` triangles at a vertex, when the numpy builders serve (and name what is
    wrong)."""

    plane: np.ndarray
    ball: np.ndarray
    prism: np.ndarray
    normals: tuple | None
    adjacency: tuple | None


def grid_arrays(K, V, T, bvh, thin):
    """:class:`GridArrays` of the mesh ``V (nv, 3)``, ``T (m, 3)`` (unit box) and its
    hierarchy ``bvh``; ``K``: the compiled module :data:`SETUP_KERNELS`; ``thin``: a triangle
    whose cross product is at most ``thin`` times its two edges' lengths gets no plane."""
    m, nv = len(T), len(V)
    limits.check(SETUP_BYTES * m, f"the grid set-up's arrays for {m:,} triangles")
    tri, order = bvh.tri, bvh.order
    fn, plane = np.empty((m, 3)), np.empty((m, 3))
    ball, prism = np.empty((m, 4)), np.empty((m, 20))
    sin_ang, cos_ang = np.empty((m, 3)), np.empty((m, 3))
    K.faces(tri, thin, fn, plane, ball, prism, sin_ang, cos_ang)
    nT = np.empty((m, 3), dtype=np.int64)
    vorder, new, at = K.renumber(T, order, nv, nT)
    ptr, corner, ahead, distinct = K.corners(T, at, new)
    twin = np.empty(3 * m, dtype=np.int64)
    if not distinct or np.diff(ptr).max() > MAX_VALENCE or K.twins(nT, ptr, corner, ahead, twin) > 0:
        return GridArrays(plane, ball, prism, None, None)
    # numpy's arctan2, as the numpy builder's (it may round otherwise than the C library's)
    ang = np.arctan2(sin_ang, cos_ang)
    ne = 3 * m // 2
    ea, eb = np.empty(ne, dtype=np.int64), np.empty(ne, dtype=np.int64)
    eh = np.empty((ne, 2), dtype=np.int64)
    K.edges(nT, order, vorder, twin, ea, eb, eh)
    vsum, nV = np.empty((nv, 3)), np.empty((nv, 3))
    nbr, vown = np.empty(3 * m, dtype=np.int64), np.empty(nv, dtype=np.int64)
    K.vertices(V, vorder, ptr, corner, ahead, fn, ang, vsum, nV, nbr, vown)
    en, vn = np.empty((m, 3, 3)), np.empty((m, 3, 3))
    K.triangles(nT, order, twin, fn, vsum, en, vn)
    adjacency = (nV, nT, ea, eb, eh, ptr, nbr, vown)
    return GridArrays(plane, ball, prism, (fn, en, vn), adjacency)
