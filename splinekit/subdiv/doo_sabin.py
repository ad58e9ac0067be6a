"""One level of Doo-Sabin refinement (any polygons): topology and stencil matrix.

Every parent face corner becomes a child vertex (child ``c`` of corner ``c``),
placed by the Doo-Sabin weights over its face's ``n`` vertices:
``(n + 5) / (4 n)`` for its own vertex and ``(3 + 2 cos(2 pi d / n)) / (4 n)``
for the vertex ``d`` steps further round. Child faces: one per parent face
(its corners), one quad per interior edge and one polygon per vertex with at
least three faces around it. On a regular quad mesh this is the biquadratic
uniform B-spline.

Boundaries and sharp edges: a corner beside a boundary or sharp edge moves
along that edge instead, ``3/4 v + 1/4 w`` (Chaikin's rule, so the boundary
converges to the quadratic B-spline of the boundary polygon); a corner between
two such edges stays at its vertex (corners are interpolated), and so does
one at a sharp vertex. Semi-sharp edges blend the two rules by their
sharpness, which decreases by one per level. Isolated vertices have no corner
and do not survive a Doo-Sabin step.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology, ranges
from .level import Level, RefinementStep
from .masks import csr
from .scheme import Scheme

NAME = "doo-sabin"


def _corner_ring(t: Topology, vertices: np.ndarray, boundary: np.ndarray):
    """Outgoing half-edges around each vertex of ``vertices``, following
    ``h -> next(twin(h))``; boundary vertices start where ``twin(prev(h)) = -1``.

    Returns ``(ring (m, kmax) with -1 padding, lengths (m,))``.
    """
    twin, nxt, prv = t.twin, t.next_corner, t.prev_corner
    offsets, _ = t.vertex_faces
    # any outgoing half-edge per vertex: the corners sorted by vertex
    order = np.argsort(t.face_indices, kind="stable")
    first_of_vertex = np.full(t.n_vertices, -1)
    first_of_vertex[t.face_indices[order[::-1]]] = order[::-1]
    start = first_of_vertex[vertices]
    # boundary vertices: the outgoing half-edge whose previous edge is a boundary
    is_start = twin[prv] < 0
    b_start = np.full(t.n_vertices, -1)
    b_start[t.face_indices[is_start]] = np.flatnonzero(is_start)
    start = np.where(boundary[vertices] & (b_start[vertices] >= 0), b_start[vertices], start)
    counts = np.diff(offsets)[vertices]
    kmax = int(counts.max()) if counts.size else 0
    ring = np.full((vertices.size, kmax), -1)
    h = start.copy()
    alive = np.ones(vertices.size, dtype=bool)
    for k in range(kmax):
        alive &= (k < counts) & (h >= 0)
        ring[alive, k] = h[alive]
        tw = np.where(alive, twin[np.maximum(h, 0)], -1)
        h = np.where(tw >= 0, nxt[np.maximum(tw, 0)], -1)
    lengths = (ring >= 0).sum(axis=1)
    return ring, lengths


def refine(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> RefinementStep:
    """One step on ``t`` with sharpness ``edge_s`` ``(E,)``, ``vertex_s`` ``(V,)``. The result unpacks as
    the former ``(child, S (H, V), crease pairs, their parent sharpness, child vertex sharpness)``."""
    return refine_level(Level(t, edge_s, vertex_s, NAME))


def refine_level(level: Level) -> RefinementStep:
    """One step: ``S`` ``(H, V)`` (one child vertex per parent corner) and the F-, E- and V-faces."""
    t, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
    H, V = t.n_halfedges, t.n_vertices
    c = np.arange(H)
    k = t.face_sizes[t.corner_face]

    # smooth Doo-Sabin weights: corner c against every corner of its face
    rows = np.repeat(c, k)
    pos = ranges(np.zeros(H, dtype=np.int64), k)  # position of each partner corner in its face
    n = k[rows].astype(np.float64)
    d = (pos - t.corner_index[rows]) % k[rows]
    w = np.where(d == 0, (n + 5) / (4 * n), (3 + 2 * np.cos(2 * np.pi * d / n)) / (4 * n))
    cols = t.face_indices[t.face_offsets[t.corner_face[rows]] + pos]
    smooth = csr(rows, cols, w, (H, V))

    # boundary and crease rule along the sharp edge(s) at each corner
    s_next = edge_s[t.halfedge_edge]  # edge from this corner's vertex to the next
    s_prev = edge_s[t.halfedge_edge[t.prev_corner]]
    v, v_next, v_prev = t.face_indices, t.halfedge_dst, t.face_indices[t.prev_corner]
    both = (s_next > 0) & (s_prev > 0)
    only_next = (s_next > 0) & ~both
    only_prev = (s_prev > 0) & ~both
    other = np.where(only_next, v_next, v_prev)
    one = only_next | only_prev
    crease = csr(
        np.concatenate([c[one], c[one], c[both]]),
        np.concatenate([v[one], other[one], v[both]]),
        np.concatenate([np.full(one.sum(), 0.75), np.full(one.sum(), 0.25), np.ones(both.sum())]),
        (H, V),
    )
    ws = np.clip(np.maximum(np.where(s_next > 0, s_next, 0), np.where(s_prev > 0, s_prev, 0)), 0, 1)
    wv = np.clip(vertex_s[v], 0, 1)
    corner = csr(c, v, np.ones(H), (H, V))
    S = sp.diags((1 - wv) * (1 - ws)) @ smooth + sp.diags((1 - wv) * ws) @ crease + sp.diags(wv) @ corner
    S = sp.csr_matrix(S)

    # child faces: F-faces (the corners of each face), E-faces, V-faces
    parts = [t.face_indices * 0 + c]
    sizes = [t.face_sizes]
    h0, h1 = t.edge_halfedges[:, 0], t.edge_halfedges[:, 1]
    interior = h1 >= 0
    a, b = h0[interior], h1[interior]
    eq = np.column_stack([t.next_corner[a], a, t.next_corner[b], b])
    parts.append(eq.ravel())
    sizes.append(np.full(len(eq), 4))
    fan = np.flatnonzero(t.vertex_face_count >= 3)
    ring, lengths = _corner_ring(t, fan, t.boundary_vertices)
    if fan.size:
        # the ring runs h -> next(twin(h)); the vertex face runs the other way
        rev = ring[:, ::-1]
        valid = rev >= 0
        parts.append(rev[valid])
        sizes.append(lengths)
    flat = np.concatenate(parts)
    offsets = np.concatenate([[0], np.cumsum(np.concatenate(sizes))])
    child = Topology(H, flat, offsets, check=False)

    # a sharp interior edge stays sharp along the two child edges beside it
    sharp = np.flatnonzero((edge_s > 0) & interior)
    sa = t.edge_halfedges[sharp, 0]
    sb = t.edge_halfedges[sharp, 1]
    pairs = np.concatenate(
        [np.column_stack([sa, t.next_corner[sa]]), np.column_stack([sb, t.next_corner[sb]])]
    )
    return RefinementStep.from_creases(NAME, child, S, pairs, np.tile(edge_s[sharp], 2), np.zeros(H))


SCHEME = Scheme(NAME, refine_level, child_faces=lambda t: t.n_faces + t.n_edges + t.n_vertices, input_face_size=None,
                output_face_size=4, splits_edges=False)
"""Doo-Sabin as the generic machinery sees it (see :class:`~splinekit.subdiv.scheme.Scheme`); numpy
rules only."""
