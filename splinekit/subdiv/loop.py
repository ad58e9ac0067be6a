"""Loop (triangles): the rules of one refinement level (topology and stencil matrix) and the
smooth limit masks.

Child vertices: the V vertex points, then the E edge points. Each triangle
``(a, b, c)`` becomes four. The smooth vertex rule uses Loop's original weight
``beta(n) = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n``, as OpenSubdiv does
(libigl uses Warren's ``3 / (8 n)``, which differs except at valence 3 and 6).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import MeshTopologyError
from ..mesh.topology import Topology
from ._compiled import LOOP
from .creases import child_sharpness
from .level import Level, RefinementStep
from .masks import csr, diag, edge_blend, midpoint_matrix, neighbor_matrix, vertex_point_matrix
from .scheme import Scheme, refine_once
from .split import child_topology

NAME = "loop"


def loop_beta(n: np.ndarray) -> np.ndarray:
    """Loop's smooth-vertex neighbour weight for valence ``n`` (0 where ``n == 0``)."""
    n = np.asarray(n, dtype=np.float64)
    safe = np.maximum(n, 1)
    beta = (0.625 - (0.375 + 0.25 * np.cos(2 * np.pi / safe)) ** 2) / safe
    return np.where(n > 0, beta, 0.0)


def refine(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> RefinementStep:
    """One step on the triangles ``t`` with sharpness ``edge_s`` ``(E,)``, ``vertex_s`` ``(V,)``; large
    meshes use the compiled kernels, which give the same step as :func:`refine_numpy`. The result
    unpacks as the former ``(child, S, crease pairs, their parent sharpness, child vertex sharpness)``."""
    require_triangles(t)
    return refine_once(SCHEME, Level(t, edge_s, vertex_s, NAME))


def require_triangles(t: Topology):
    """MeshTopologyError naming the first face of ``t`` that is not a triangle."""
    if not (t.face_sizes == 3).all():
        f = int(np.flatnonzero(t.face_sizes != 3)[0])
        raise MeshTopologyError(f"Loop subdivision needs triangles; face {f} has {int(t.face_sizes[f])} vertices")


def refine_numpy(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> RefinementStep:
    """:func:`refine` by the numpy rules only."""
    return refine_level(Level(t, edge_s, vertex_s, NAME))


def refine_level(level: Level) -> RefinementStep:
    """One step by the numpy rules: ``S`` ``(V + E, V)`` and four child triangles per triangle."""
    t, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
    require_triangles(t)
    V, E = t.n_vertices, t.n_edges

    # edge points: 3/8 (v0 + v1) + 1/8 (opposite vertices) when smooth
    h = np.arange(t.n_halfedges)
    opposite = t.face_indices[t.prev_corner]
    smooth_e = 0.75 * midpoint_matrix(t) + csr(t.halfedge_edge[h], opposite, np.full(h.size, 0.125), (E, V))
    ws = edge_blend(edge_s)
    S_e = diag(1.0 - ws) @ smooth_e + diag(ws) @ midpoint_matrix(t)

    # vertex points: (1 - n beta) v + beta sum(neighbours)
    n = t.valence
    beta = loop_beta(n)
    smooth_v = diag(1.0 - n * beta) + neighbor_matrix(t, beta)
    S_v = vertex_point_matrix(level, smooth_v)
    S = sp.vstack([S_v, S_e], format="csr")

    tri = t.face_indices.reshape(-1, 3)
    e = t.halfedge_edge.reshape(-1, 3) + V  # e[:, 0] = edge a-b, e[:, 1] = b-c, e[:, 2] = c-a
    faces = np.stack(
        [
            np.column_stack([tri[:, 0], e[:, 0], e[:, 2]]),
            np.column_stack([e[:, 0], tri[:, 1], e[:, 1]]),
            np.column_stack([e[:, 2], e[:, 1], tri[:, 2]]),
            np.column_stack([e[:, 0], e[:, 1], e[:, 2]]),
        ],
        axis=1,
    ).reshape(-1)
    # child half-edges per triangle T (12 T + k): corner triangles at a, b, c then the middle one
    T = 12 * np.arange(t.n_faces)
    local_out, local_in = np.array([0, 4, 8]), np.array([3, 7, 2])
    i = t.corner_index
    out_he = T[t.corner_face] + local_out[i]
    in_he = T[t.corner_face] + local_in[i]
    inner_edges = np.stack(
        [np.sort(np.column_stack([e[:, 0], e[:, 2]]), axis=1),
         np.sort(np.column_stack([e[:, 0], e[:, 1]]), axis=1),
         np.sort(np.column_stack([e[:, 2], e[:, 1]]), axis=1)],
        axis=1,
    ).reshape(-1, 2)
    inner_pairs = np.stack(
        [np.column_stack([T + 1, T + 11]), np.column_stack([T + 5, T + 9]), np.column_stack([T + 6, T + 10])], axis=1
    ).reshape(-1, 2)
    child = child_topology(t, V + E, faces, np.arange(4 * t.n_faces + 1) * 3, out_he, in_he, inner_edges, inner_pairs)

    sharp = np.flatnonzero(edge_s > 0)
    pairs = np.concatenate(
        [np.column_stack([t.edges[sharp, 0], V + sharp]), np.column_stack([V + sharp, t.edges[sharp, 1]])]
    )
    child_vertex_s = np.concatenate([child_sharpness(vertex_s), np.zeros(child.n_vertices - V)])
    return RefinementStep.from_creases(NAME, child, S, pairs, np.tile(edge_s[sharp], 2), child_vertex_s)


# -- limit masks ---------------------------------------------------------------------------------
def limit_mask(t: Topology) -> sp.spmatrix:
    """``(V, V)`` limit positions of smooth vertices: ``(1 - n chi) v + chi sum e_j`` with
    ``chi = 1 / (n + 3 / (8 beta(n)))``."""
    V = t.n_vertices
    n = t.valence.astype(np.float64)
    beta = loop_beta(n)
    with np.errstate(divide="ignore"):
        chi = np.where(n > 0, 1.0 / (n + 3.0 / (8.0 * np.maximum(beta, 1e-300))), 0.0)
    a, b = t.edges[:, 0], t.edges[:, 1]
    ends, other = np.concatenate([a, b]), np.concatenate([b, a])
    return diag(1.0 - n * chi) + csr(ends, other, chi[ends], (V, V))


def tangent_terms(t: Topology, h: np.ndarray, v: np.ndarray, n: np.ndarray, j: int):
    """Terms of the two tangent masks at the ``j``-th ring position of smooth vertices ``v`` (valence
    ``n``, outgoing half-edges ``h``, counter-clockwise): ``(rows, cols, w1, w2)``, lists of arrays.
    ``sum cos(2 pi j / n) e_j`` and ``sum sin(2 pi j / n) e_j``."""
    th = 2 * np.pi * j / n
    return [v], [t.halfedge_dst[h]], [np.cos(th)], [np.sin(th)]


def sector_matrix(k: int) -> np.ndarray:
    """Subdivision map ``(k + 2, k + 2)`` of a one-sided crease ring with ``k`` triangles, in the
    order ``[v, e_0 .. e_k]``; ``v e_0`` and ``v e_k`` are the sharp edges (crease rule at v), the
    edges between them smooth (``3/8, 3/8, 1/8, 1/8``)."""
    size = k + 2
    A = np.zeros((size, size))
    A[0, 0], A[0, 1], A[0, k + 1] = 0.75, 0.125, 0.125
    for j in range(k + 1):
        if j in (0, k):
            A[1 + j, [0, 1 + j]] = 0.5
        else:
            A[1 + j, [0, 1 + j]] = 0.375
            A[1 + j, [j, 2 + j]] += 0.125
    return A


SCHEME = Scheme(NAME, refine_level, child_faces=lambda t: 4 * t.n_faces, input_face_size=3, output_face_size=3,
                splits_edges=True, kernel=LOOP, valence_weights=loop_beta, limit_mask=limit_mask,
                tangent_terms=tangent_terms, sector_matrix=sector_matrix)
"""Loop as the generic machinery sees it (see :class:`~splinekit.subdiv.scheme.Scheme`)."""
