"""Catmull-Clark: the rules of one refinement level (topology and stencil matrix) and the
smooth limit masks.

Child vertices are ordered: the V vertex points (child ``v`` of parent vertex
``v``), then the E edge points, then the F face points. Each parent corner
becomes one quad ``(vertex point, edge point, face point, previous edge point)``,
so any polygon goes in and quads come out.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology
from ._compiled import CATMULL_CLARK
from .creases import child_sharpness
from .level import Level, RefinementStep
from .masks import csr, diag, edge_blend, midpoint_matrix, neighbor_matrix, vertex_point_matrix
from .scheme import Scheme, refine_once
from .split import child_topology

NAME = "catmull-clark"


def face_point_matrix(t: Topology) -> sp.csr_matrix:
    """``(F, V)``: the centroid of each face."""
    return csr(t.corner_face, t.face_indices, 1.0 / t.face_sizes[t.corner_face], (t.n_faces, t.n_vertices))


def refine(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> RefinementStep:
    """One step on ``t`` with sharpness ``edge_s`` ``(E,)``, ``vertex_s`` ``(V,)``; large meshes use the
    compiled kernels, which give the same step as :func:`refine_numpy`. The result unpacks as the
    former ``(child, S, crease pairs, their parent sharpness, child vertex sharpness)``."""
    return refine_once(SCHEME, Level(t, edge_s, vertex_s, NAME))


def refine_numpy(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> RefinementStep:
    """:func:`refine` by the numpy rules only."""
    return refine_level(Level(t, edge_s, vertex_s, NAME))


def refine_level(level: Level) -> RefinementStep:
    """One step by the numpy rules: ``S`` ``(V + E + F, V)`` and the child quads."""
    t, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
    V, E, F = t.n_vertices, t.n_edges, t.n_faces
    Sf = face_point_matrix(t)

    # edge points: (v0 + v1 + f0 + f1) / 4 when smooth, the midpoint when sharp
    interior = t.edge_faces >= 0
    rows = np.repeat(np.arange(E), 2)[interior.ravel()]
    cols = t.edge_faces.ravel()[interior.ravel()]
    smooth_e = 0.5 * midpoint_matrix(t) + csr(rows, cols, np.full(rows.size, 0.25), (E, F)) @ Sf
    ws = edge_blend(edge_s)
    S_e = diag(1.0 - ws) @ smooth_e + diag(ws) @ midpoint_matrix(t)

    # vertex points: ((n - 2) v + (1/n) sum(neighbours) + (1/n) sum(face points)) / n
    n = t.valence.astype(np.float64)
    live = n > 0
    inv2 = np.where(live, 1.0 / np.maximum(n, 1) ** 2, 0.0)
    centre = np.where(live, (n - 2) / np.maximum(n, 1), 1.0)
    vf = csr(t.face_indices, t.corner_face, inv2[t.face_indices], (V, F))
    smooth_v = diag(centre) + neighbor_matrix(t, inv2) + vf @ Sf
    S_v = vertex_point_matrix(level, smooth_v)

    S = sp.vstack([S_v, S_e, Sf], format="csr")

    c = np.arange(t.n_halfedges)
    quads = np.column_stack(
        [t.face_indices, V + t.halfedge_edge, V + E + t.corner_face, V + t.halfedge_edge[t.prev_corner]]
    )
    # child half-edges: 4c (v -> edge point), 4c+1 (edge point -> face point),
    # 4c+2 (face point -> previous edge point), 4c+3 (previous edge point -> v)
    inner_edges = np.column_stack([V + t.halfedge_edge, V + E + t.corner_face])  # the spoke of corner c
    inner_pairs = np.column_stack([4 * c + 1, 4 * t.next_corner + 2])
    child = child_topology(t, V + E + F, quads.ravel(), np.arange(c.size + 1) * 4,
                           out_he=4 * c, in_he=4 * t.next_corner + 3, inner_edges=inner_edges, inner_pairs=inner_pairs)

    sharp = np.flatnonzero(edge_s > 0)
    pairs = np.concatenate(
        [np.column_stack([t.edges[sharp, 0], V + sharp]), np.column_stack([V + sharp, t.edges[sharp, 1]])]
    )
    child_vertex_s = np.concatenate([child_sharpness(vertex_s), np.zeros(child.n_vertices - V)])
    return RefinementStep.from_creases(NAME, child, S, pairs, np.tile(edge_s[sharp], 2), child_vertex_s)


# -- limit masks ---------------------------------------------------------------------------------
def limit_mask(t: Topology) -> sp.spmatrix:
    """``(V, V)`` limit positions of smooth vertices of a quad mesh:
    ``(n^2 v + 4 sum e_j + sum d_j) / (n (n + 5))`` with ``e_j`` the edge neighbours and ``d_j``
    the diagonal vertices of the incident quads (Halstead, Kass, DeRose 1993)."""
    V = t.n_vertices
    n = t.valence.astype(np.float64)
    denom = np.maximum(n, 1) * (np.maximum(n, 1) + 5)
    a, b = t.edges[:, 0], t.edges[:, 1]
    ends, other = np.concatenate([a, b]), np.concatenate([b, a])
    corner_v = t.face_indices
    diagonal = t.face_indices[t.next_corner[t.next_corner]]
    return (diag(n * n / denom) + csr(ends, other, (4.0 / denom)[ends], (V, V))
            + csr(corner_v, diagonal, (1.0 / denom)[corner_v], (V, V)))


def tangent_terms(t: Topology, h: np.ndarray, v: np.ndarray, n: np.ndarray, j: int):
    """Terms of the two tangent masks at the ``j``-th ring position of smooth vertices ``v`` (valence
    ``n``, outgoing half-edges ``h``, counter-clockwise): ``(rows, cols, w1, w2)``, lists of arrays.
    ``sum A cos(2 pi j / n) e_j + (cos(2 pi j / n) + cos(2 pi (j + 1) / n)) d_j`` and the same with
    sines, ``A = 1 + cos(2 pi / n) + cos(pi / n) sqrt(2 (9 + cos(2 pi / n)))``."""
    th, th1 = 2 * np.pi * j / n, 2 * np.pi * (j + 1) / n
    A = 1 + np.cos(2 * np.pi / n) + np.cos(np.pi / n) * np.sqrt(2 * (9 + np.cos(2 * np.pi / n)))
    e = t.halfedge_dst[h]
    d = t.face_indices[t.next_corner[t.next_corner[h]]]
    return [v, v], [e, d], [A * np.cos(th), np.cos(th) + np.cos(th1)], [A * np.sin(th), np.sin(th) + np.sin(th1)]


def sector_matrix(k: int) -> np.ndarray:
    """Subdivision map ``(2 k + 2, 2 k + 2)`` of a one-sided crease ring with ``k`` quads, in the
    order ``[v, e_0 .. e_k, d_0 .. d_(k-1)]`` (``d_j`` the far corner of face j, between ``e_j`` and
    ``e_(j+1)``); ``v e_0`` and ``v e_k`` are the sharp edges (crease rule at v), the edges between
    them smooth. The child ring has the same layout (vertex point, edge points, face points)."""
    size = 2 * k + 2
    A = np.zeros((size, size))
    e = lambda j: 1 + j  # noqa: E731
    d = lambda j: k + 2 + j  # noqa: E731
    A[0, 0], A[0, e(0)], A[0, e(k)] = 0.75, 0.125, 0.125
    face = np.zeros((k, size))
    for j in range(k):
        face[j, [0, e(j), d(j), e(j + 1)]] = 0.25
        A[d(j)] = face[j]
    for j in range(k + 1):
        if j in (0, k):
            A[e(j), [0, e(j)]] = 0.5
        else:
            A[e(j), [0, e(j)]] = 0.25
            A[e(j)] += 0.25 * (face[j - 1] + face[j])
    return A


SCHEME = Scheme(NAME, refine_level, child_faces=lambda t: t.n_halfedges, input_face_size=None, output_face_size=4,
                splits_edges=True, kernel=CATMULL_CLARK, limit_mask=limit_mask, tangent_terms=tangent_terms,
                sector_matrix=sector_matrix)
"""Catmull-Clark as the generic machinery sees it (see :class:`~splinekit.subdiv.scheme.Scheme`)."""
