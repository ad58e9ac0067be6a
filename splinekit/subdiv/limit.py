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


def _sector_ring_matrix(scheme: str, k: int) -> np.ndarray:
    """Subdivision map of a one-sided crease ring with ``k`` faces.

    Ring order: ``[v, e_0 .. e_k, d_0 .. d_(k-1)]`` for Catmull-Clark quads
    (``d_j`` the far corner of face j, between ``e_j`` and ``e_(j+1)``) and
    ``[v, e_0 .. e_k]`` for Loop; ``v e_0`` and ``v e_k`` are the sharp edges
    (crease rule at v), the edges ``v e_j`` between them are smooth. The
    child ring has the same layout (vertex point, edge points, face points).
    """
    if scheme == "catmull-clark":
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


def _across_mask(scheme: str, k: int) -> np.ndarray:
    """Left eigenvector of the sector map that is symmetric under the sector's
    reflection (``e_j <-> e_(k-j)``, ``d_j <-> d_(k-1-j)``) and has the largest
    eigenvalue below 1: the tangent mask across the crease (the crease tangent
    ``e_k - e_0`` is antisymmetric, eigenvalue 1/2). ``None`` when that
    eigenvalue is not above 1/4."""
    A = _sector_ring_matrix(scheme, k)
    size = A.shape[0]
    perm = np.arange(size)
    perm[1 : k + 2] = np.arange(k + 1, 0, -1)
    if scheme == "catmull-clark":
        perm[k + 2 :] = np.arange(2 * k + 1, k + 1, -1)
    values, vectors = np.linalg.eig(A.T)
    best, mask = 0.25 + 1e-9, None
    for lam, vec in zip(values, vectors.T):
        if abs(lam.imag) > 1e-12 or lam.real >= 1 - 1e-9 or lam.real <= best:
            continue
        # the reflection commutes with A: the symmetric part of an eigenvector is one too
        sym = 0.5 * (vec.real + vec.real[perm])
        if np.abs(sym).max() > 1e-6 * np.abs(vec).max():
            best, mask = lam.real, sym
    # a symmetric eigenvalue of at most 1/4 = (1/2)^2 is a second-order term, not a
    # tangent: the sector is degenerate there (one face); the caller uses its edges
    return mask


def crease_normals(t: Topology, X: np.ndarray, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str):
    """Limit normals at crease, boundary and corner vertices: ``(normals (V, 3), covered (V,))``.

    The fan around such a vertex splits at its sharp edges into sectors. In a
    sector of a crease (or boundary) vertex the limit tangent plane is spanned
    by the crease tangent ``e_k - e_0`` and the tangent across it from the
    sector's eigen-analysis (:func:`_across_mask`); at a corner (and in a
    one-face sector, where the across eigenvalue degenerates) each bounding
    crease curve leaves the vertex towards its neighbour, so the sector's
    plane is spanned by ``e_0 - v`` and ``e_k - v``. Each sector's unit normal
    is exact; where there are several sectors (an interior crease, a corner)
    the surface has several normals and their normalized sum is returned.
    """
    V = t.n_vertices
    rule = vertex_rules(t, edge_s, vertex_s)
    sharp = edge_s > 0
    target = ((rule == CREASE) | (rule == CORNER)) & (t.vertex_face_count > 0)
    # a sector starts at an outgoing half-edge on a sharp edge (CCW rotation h -> twin(prev(h)))
    starts = np.flatnonzero(target[t.face_indices] & sharp[t.halfedge_edge])
    normals = np.zeros((V, X.shape[1]))
    covered = np.zeros(V, dtype=bool)
    if starts.size == 0:
        return normals, covered
    h = starts.copy()
    faces = [h.copy()]
    alive = np.ones(starts.size, dtype=bool)
    for _ in range(int(t.vertex_face_count.max())):
        back = t.prev_corner[h]
        stop = sharp[t.halfedge_edge[back]] | (t.twin[back] < 0)
        alive &= ~stop
        if not alive.any():
            break
        h = np.where(alive, t.twin[back], h)
        faces.append(np.where(alive, h, -1))
    ring = np.column_stack(faces)  # (sectors, kmax) outgoing half-edges, -1 padded
    k = (ring >= 0).sum(axis=1)
    v = t.face_indices[starts]
    e0 = X[t.halfedge_dst[starts]]
    last = ring[np.arange(starts.size), k - 1]
    ek = X[t.face_indices[t.prev_corner[last]]]
    masks = {int(kk): _across_mask(scheme, int(kk)) for kk in np.unique(k)}
    degenerate = np.array([masks[int(kk)] is None for kk in k], dtype=bool)
    is_corner = (rule[v] == CORNER) | degenerate
    along = np.where(is_corner[:, None], e0 - X[v], ek - e0)
    across = np.where(is_corner[:, None], ek - X[v], 0.0)
    for kk in np.unique(k[~is_corner]):
        sel = np.flatnonzero(~is_corner & (k == kk))
        mask = masks[int(kk)]
        hs = ring[sel, :kk]
        ring_pts = [X[v[sel]], X[t.halfedge_dst[hs]].transpose(1, 0, 2), X[t.face_indices[t.prev_corner[hs[:, -1]]]][None]]
        pts = [ring_pts[0][None]] + [ring_pts[1], ring_pts[2]]
        if scheme == "catmull-clark":
            pts.append(X[t.face_indices[t.next_corner[t.next_corner[hs]]]].transpose(1, 0, 2))
        stack = np.concatenate(pts, axis=0)  # (ring size, m, dim)
        across[sel] = np.einsum("r,rmd->md", mask, stack)
    # orient each sector like its faces: e_0 -> v -> ... runs counter-clockwise
    n = np.cross(along, across) if X.shape[1] == 3 else np.zeros_like(along)
    fan = np.zeros_like(n)
    for j in range(ring.shape[1]):
        hj = ring[:, j]
        live = hj >= 0
        hh = np.maximum(hj, 0)
        a = X[t.halfedge_dst[hh]] - X[v]
        b = X[t.face_indices[t.prev_corner[hh]]] - X[v]
        fan += np.where(live[:, None], np.cross(a, b), 0.0)
    flip = np.einsum("md,md->m", n, fan) < 0
    n[flip] *= -1
    length = np.linalg.norm(n, axis=1, keepdims=True)
    unit = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    np.add.at(normals, v, unit)
    np.logical_or.at(covered, v, length[:, 0] > 0)
    return normals, covered
