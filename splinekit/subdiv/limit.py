"""Limit masks: positions and tangents of the limit surface at mesh vertices.

The masks are valid on a mesh whose faces the scheme produces (quads for
Catmull-Clark, triangles for Loop) and whose semi-sharp features have expired
(every sharpness 0 or infinite); :class:`~splinekit.subdiv.surface.SubdivisionSurface`
refines that far first and maps the result back to the control vertices.

- Catmull-Clark, smooth or dart vertex of valence n:
  ``(n^2 v + 4 sum e_j + sum d_j) / (n (n + 5))`` with ``e_j`` the edge
  neighbours and ``d_j`` the diagonal vertices of the incident quads; tangents
  ``sum A cos(2 pi j / n) e_j + (cos(2 pi j / n) + cos(2 pi (j + 1) / n)) d_j`` and
  the same with sines, ``A = 1 + cos(2 pi / n) + cos(pi / n) sqrt(2 (9 + cos(2 pi / n)))``
  (Halstead, Kass, DeRose 1993).
- Loop, smooth or dart vertex: ``(1 - n chi) v + chi sum e_j`` with
  ``chi = 1 / (n + 3 / (8 beta(n)))``; tangents ``sum cos(2 pi j / n) e_j`` and
  ``sum sin(2 pi j / n) e_j``.
- Crease (and boundary) vertex, both schemes: the cubic B-spline limit of the
  crease polygon ``(a + 4 v + b) / 6``, tangent ``b - a``.
- Corner: the vertex itself.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology
from .creases import CORNER, CREASE, DART, vertex_rules
from .loop import loop_beta
from .masks import crease_matrix, csr, diag


def ordered_rings(t: Topology, vertices: np.ndarray):
    """Outgoing half-edges around interior ``vertices`` in counter-clockwise order
    (``h -> twin(prev(h))``): ``(ring (m, kmax) padded with -1, valence (m,))``."""
    order = np.argsort(t.face_indices, kind="stable")
    first = np.full(t.n_vertices, -1)
    first[t.face_indices[order[::-1]]] = order[::-1]
    h = first[vertices]
    n = t.vertex_face_count[vertices]
    kmax = int(n.max()) if n.size else 0
    ring = np.full((vertices.size, kmax), -1)
    for k in range(kmax):
        live = k < n
        ring[live, k] = h[live]
        h = np.where(live, t.twin[t.prev_corner[np.maximum(h, 0)]], h)
    return ring, n


def limit_matrix(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str) -> sp.csr_matrix:
    """``(V, V)``: limit positions of all vertices from their neighbourhoods."""
    V = t.n_vertices
    rule = vertex_rules(t, edge_s, vertex_s)
    rule[t.vertex_face_count == 0] = CORNER
    smooth_rows = rule <= DART
    n = t.valence.astype(np.float64)
    safe = np.maximum(n, 1)
    a, b = t.edges[:, 0], t.edges[:, 1]
    ends = np.concatenate([a, b])
    other = np.concatenate([b, a])
    if scheme == "catmull-clark":
        denom = safe * (safe + 5)
        centre = n * n / denom
        w_edge = 4.0 / denom
        corner_v = t.face_indices
        diagonal = t.face_indices[t.next_corner[t.next_corner]]
        smooth = diag(centre) + csr(ends, other, w_edge[ends], (V, V)) + csr(corner_v, diagonal, (1.0 / denom)[corner_v], (V, V))
    elif scheme == "loop":
        beta = loop_beta(n)
        with np.errstate(divide="ignore"):
            chi = np.where(n > 0, 1.0 / (n + 3.0 / (8.0 * np.maximum(beta, 1e-300))), 0.0)
        smooth = diag(1.0 - n * chi) + csr(ends, other, chi[ends], (V, V))
    else:
        raise ValueError(f"limit masks exist for catmull-clark and loop, not {scheme}")
    crease = crease_matrix(t, edge_s > 0, rule == CREASE, centre=2.0 / 3.0)
    return sp.csr_matrix(diag(smooth_rows) @ smooth + crease + diag(rule == CORNER))


def tangent_matrices(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str):
    """``(T1, T2, ok)``: ``(V, V)`` tangent masks of smooth and dart vertices
    (whose limit normal is ``T1 @ X`` x ``T2 @ X``), and the mask ``ok`` of the
    vertices they cover."""
    V = t.n_vertices
    rule = vertex_rules(t, edge_s, vertex_s)
    ok = (rule <= DART) & (t.vertex_face_count > 0) & ~t.boundary_vertices
    verts = np.flatnonzero(ok)
    ring, n = ordered_rings(t, verts)
    rows, cols, w1, w2 = [], [], [], []
    for j in range(ring.shape[1]):
        live = j < n
        h = ring[live, j]
        v = verts[live]
        nn = n[live].astype(np.float64)
        th = 2 * np.pi * j / nn
        th1 = 2 * np.pi * (j + 1) / nn
        e = t.halfedge_dst[h]
        if scheme == "catmull-clark":
            A = 1 + np.cos(2 * np.pi / nn) + np.cos(np.pi / nn) * np.sqrt(2 * (9 + np.cos(2 * np.pi / nn)))
            d = t.face_indices[t.next_corner[t.next_corner[h]]]
            rows += [v, v]
            cols += [e, d]
            w1 += [A * np.cos(th), np.cos(th) + np.cos(th1)]
            w2 += [A * np.sin(th), np.sin(th) + np.sin(th1)]
        else:
            rows.append(v)
            cols.append(e)
            w1.append(np.cos(th))
            w2.append(np.sin(th))
    if rows:
        r, c = np.concatenate(rows), np.concatenate(cols)
        T1 = csr(r, c, np.concatenate(w1), (V, V))
        T2 = csr(r, c, np.concatenate(w2), (V, V))
    else:
        T1 = T2 = sp.csr_matrix((V, V))
    return T1, T2, ok
