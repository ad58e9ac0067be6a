"""Child connectivity of the edge-splitting schemes (Catmull-Clark, Loop), built
without sorting: every parent edge ``e = (a, b)`` becomes the child edges
``2e = (a, V + e)`` and ``2e + 1 = (b, V + e)``, and the scheme adds its own
interior edges. Knowing which child half-edges lie on each child edge, the
edge tables of the child :class:`~splinekit.mesh.topology.Topology` are filled
directly (the generic construction sorts all half-edges)."""

from __future__ import annotations

import numpy as np

from ..mesh.topology import Topology


def child_topology(t: Topology, n_child_vertices: int, faces: np.ndarray, offsets: np.ndarray,
                   out_he: np.ndarray, in_he: np.ndarray, inner_edges: np.ndarray, inner_pairs: np.ndarray) -> Topology:
    """Child topology with prefilled edge tables.

    ``out_he[c]`` / ``in_he[c]``: the child half-edges running from ``src(c)`` to
    the edge point of parent half-edge ``c``, and from that edge point to
    ``dst(c)``. ``inner_edges`` ``(k, 2)`` are the scheme's new edges (child
    vertex pairs, low first) and ``inner_pairs`` ``(k, 2)`` their two
    half-edges. Child edges are numbered: the 2E halves, then the inner edges.
    """
    V, E = t.n_vertices, t.n_edges
    e = np.arange(E)
    p0, p1 = t.edge_halfedges[:, 0], t.edge_halfedges[:, 1]
    has1 = p1 >= 0
    p1s = np.maximum(p1, 0)
    # which child edge is the half at src(p0): 2e when src(p0) is the edge's low end
    ka = (t.face_indices[p0] != t.edges[:, 0]).astype(np.int64)
    pairs = np.empty((2 * E + len(inner_edges), 2), dtype=np.int64)
    pairs[2 * e + ka, 0] = out_he[p0]
    pairs[2 * e + ka, 1] = np.where(has1, in_he[p1s], -1)
    pairs[2 * e + 1 - ka, 0] = in_he[p0]
    pairs[2 * e + 1 - ka, 1] = np.where(has1, out_he[p1s], -1)
    pairs[2 * E :] = inner_pairs
    edges = np.empty((2 * E + len(inner_edges), 2), dtype=np.int64)
    edges[0 : 2 * E : 2, 0] = t.edges[:, 0]
    edges[1 : 2 * E : 2, 0] = t.edges[:, 1]
    edges[0 : 2 * E, 1] = np.repeat(V + e, 2)
    edges[2 * E :] = inner_edges
    he_edge = np.empty(faces.size, dtype=np.int64)
    idx = np.arange(len(pairs))
    he_edge[pairs[:, 0]] = idx
    second = pairs[:, 1] >= 0
    he_edge[pairs[second, 1]] = idx[second]
    return Topology(n_child_vertices, faces, offsets, check=False, edge_table=(edges, he_edge, pairs))
