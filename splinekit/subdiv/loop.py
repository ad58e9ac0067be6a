"""One level of Loop refinement (triangles): topology and stencil matrix.

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
    S_v = vertex_point_matrix(t, edge_s, vertex_s, smooth_v)
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


SCHEME = Scheme(NAME, refine_level, child_faces=lambda t: 4 * t.n_faces, input_face_size=3, output_face_size=3,
                splits_edges=True, kernel=LOOP, valence_weights=loop_beta)
"""Loop as the generic machinery sees it (see :class:`~splinekit.subdiv.scheme.Scheme`)."""
