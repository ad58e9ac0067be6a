"""Normals of a triangle mesh split at its sharp edges, for the maps of a plain mesh.

A mesh's vertex normal averages every face around the vertex, so at the edge of a box it
points diagonally and a draft or zebra map smears across the edge. Here every corner of every
triangle gets the area-weighted mean of the normals of the triangles around its vertex that
lie within :data:`CREASE_DEGREES` of its own triangle's normal (a smoothing group); corners
of one vertex whose groups agree are merged again, so a smooth mesh keeps its vertices and a
box gets one vertex per face at each corner.
"""

from __future__ import annotations

import numpy as np

from .. import limits

__all__ = ["CREASE_DEGREES", "split_at_creases"]

CREASE_DEGREES = 40.0
"""Triangles whose normals differ by more than this meet at a sharp edge (the pictures' outline angle)."""

_BYTES_PER_PAIR = 80  # (corner, neighbouring triangle) pairs: indices, a dot product, weights


def split_at_creases(points, triangles):
    """``(vertex, normals, triangles)``: for each new vertex the index of the ``points`` row it
    copies ``(m,)``, its unit normal ``(m, 3)`` (zero where the area around it vanishes) and
    the triangles ``(T, 3)`` over the new vertices."""
    P = np.asarray(points, dtype=np.float64)
    T = np.asarray(triangles, dtype=np.int64)
    area_normal = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])  # twice the area, along the normal
    length = np.linalg.norm(area_normal, axis=1, keepdims=True)
    unit = np.divide(area_normal, length, out=np.zeros_like(area_normal), where=length > 0)
    corner_vertex = T.ravel()
    corner_triangle = np.repeat(np.arange(len(T)), 3)
    # the triangles around each vertex, as a CSR list
    order = np.argsort(corner_vertex, kind="stable")
    starts = np.searchsorted(corner_vertex[order], np.arange(len(P) + 1))
    valence = np.diff(starts)
    per_corner = valence[corner_vertex]
    limits.check(int(per_corner.sum()) * _BYTES_PER_PAIR, "the crease-split normals of a mesh")
    owner = np.repeat(np.arange(len(corner_vertex)), per_corner)
    offset = np.arange(len(owner)) - np.repeat(np.cumsum(per_corner) - per_corner, per_corner)
    neighbour = corner_triangle[order[starts[corner_vertex[owner]] + offset]]
    cos = np.einsum("ij,ij->i", unit[corner_triangle[owner]], unit[neighbour])
    same = cos >= np.cos(np.radians(CREASE_DEGREES))
    summed = np.stack([np.bincount(owner[same], weights=area_normal[neighbour[same], k], minlength=len(corner_vertex))
                       for k in range(3)], axis=1)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    normals = np.divide(summed, length, out=np.zeros_like(summed), where=length > 0)
    # corners of one vertex with the same group sum (bit for bit: same triangles, same order) merge
    key = np.column_stack([corner_vertex.astype(np.float64), normals])
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return corner_vertex[first], normals[first], inverse.reshape(-1, 3)
