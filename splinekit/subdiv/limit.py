"""Limit masks: positions and tangents of the limit surface at mesh vertices.

The masks are valid on a mesh whose faces the scheme produces (quads for
Catmull-Clark, triangles for Loop) and whose semi-sharp features have expired
(every sharpness 0 or infinite); :class:`~splinekit.subdiv.surface.SubdivisionSurface`
refines that far first and maps the result back to the control vertices.

- Catmull-Clark, smooth vertex of valence n:
  ``(n^2 v + 4 sum e_j + sum d_j) / (n (n + 5))`` with ``e_j`` the edge
  neighbours and ``d_j`` the diagonal vertices of the incident quads; tangents
  ``sum A cos(2 pi j / n) e_j + (cos(2 pi j / n) + cos(2 pi (j + 1) / n)) d_j`` and
  the same with sines, ``A = 1 + cos(2 pi / n) + cos(pi / n) sqrt(2 (9 + cos(2 pi / n)))``
  (Halstead, Kass, DeRose 1993).
- Loop, smooth vertex: ``(1 - n chi) v + chi sum e_j`` with
  ``chi = 1 / (n + 3 / (8 beta(n)))``; tangents ``sum cos(2 pi j / n) e_j`` and
  ``sum sin(2 pi j / n) e_j``.
- Dart (one infinitely sharp edge, smooth vertex rule), both schemes: the
  smooth masks are not exact there (the crease edge rule breaks the rotational
  symmetry). The map from the dart's fan to its child's fan is a fixed matrix
  per valence, built by refining a canonical fan with the scheme's own rules
  (:func:`dart_fan_matrix`); the limit and tangent masks are its left
  eigenvectors (:func:`dart_masks`).
- Crease (and boundary) vertex, both schemes: the cubic B-spline limit of the
  crease polygon ``(a + 4 v + b) / 6``, tangent ``b - a``.
- Corner: the vertex itself.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology
from .creases import CORNER, CREASE, DART, vertex_rules
from .loop import loop_beta
from .masks import crease_matrix, csr, diag
from .refiner import Refinement


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
    L = sp.csr_matrix(diag(smooth_rows) @ smooth + crease + diag(rule == CORNER))
    darts, dart_part = _dart_rows(t, edge_s, rule, scheme, "limit")
    return _replace_rows(L, darts, dart_part[0]) if darts.any() else L


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
    darts, dart_part = _dart_rows(t, edge_s, rule, scheme, "tangents")
    if darts.any():
        T1, T2 = _replace_rows(T1, darts, dart_part[0]), _replace_rows(T2, darts, dart_part[1])
    return T1, T2, ok


def _replace_rows(M: sp.csr_matrix, rows: np.ndarray, R: sp.csr_matrix) -> sp.csr_matrix:
    """``M`` with its ``rows`` (mask ``(V,)``) replaced by those of ``R``. The other
    rows keep their entries in their order (a sparse sum would reorder them and
    change the rounding of ``M @ X``)."""
    M, R = sp.csr_matrix(M), sp.csr_matrix(R)
    m_row = np.repeat(np.arange(M.shape[0]), np.diff(M.indptr))
    r_row = np.repeat(np.arange(R.shape[0]), np.diff(R.indptr))
    keep, take = ~rows[m_row], rows[r_row]
    row = np.concatenate([m_row[keep], r_row[take]])
    order = np.argsort(row, kind="stable")
    data = np.concatenate([M.data[keep], R.data[take]])[order]
    cols = np.concatenate([M.indices[keep], R.indices[take]])[order]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(row, minlength=M.shape[0]))])
    return sp.csr_matrix((data, cols, indptr), shape=M.shape)


def fan_order(t: Topology, sharp: np.ndarray, vertices: np.ndarray, scheme: str) -> np.ndarray:
    """``(m, 1 + k n)`` vertex indices of the fans of interior ``vertices`` (all of
    valence ``n``; ``k`` = 2 for Catmull-Clark quads, 1 for Loop triangles) in
    canonical order ``[v, e_0 .. e_(n-1), d_0 .. d_(n-1)]``: the edge neighbours
    counter-clockwise starting at the (first) ``sharp`` edge, ``d_j`` the far
    corner of the quad between ``e_j`` and ``e_(j+1)`` (Catmull-Clark only)."""
    ring, n = ordered_rings(t, vertices)
    if ring.size == 0:
        return np.zeros((vertices.size, 0), dtype=np.int64)
    nn = int(n[0])
    ring = ring[:, :nn]
    start = np.argmax(sharp[t.halfedge_edge[ring]], axis=1)
    ring = np.take_along_axis(ring, (start[:, None] + np.arange(nn)) % nn, axis=1)
    cols = [vertices[:, None], t.halfedge_dst[ring]]
    if scheme == "catmull-clark":
        cols.append(t.face_indices[t.next_corner[t.next_corner[ring]]])
    return np.concatenate(cols, axis=1)


def _canonical_fan(scheme: str, n: int) -> Topology:
    """The fan of a valence-``n`` vertex 0 in the order of :func:`fan_order`."""
    j = np.arange(n)
    if scheme == "catmull-clark":
        faces = np.stack([np.zeros(n, dtype=np.int64), 1 + j, 1 + n + j, 1 + (j + 1) % n], axis=1)
    else:
        faces = np.stack([np.zeros(n, dtype=np.int64), 1 + j, 1 + (j + 1) % n], axis=1)
    k = faces.shape[1]
    return Topology(faces.max() + 1, faces.ravel(), np.arange(n + 1) * k)


@cache
def dart_fan_matrix(scheme: str, n: int) -> np.ndarray | None:
    """Subdivision map ``(s, s)`` of the fan of a valence-``n`` dart (``s = 2 n + 1``
    for Catmull-Clark, ``n + 1`` for Loop): fan at level ``k`` -> fan at level
    ``k + 1``, both in the order of :func:`fan_order` with ``e_0`` on the sharp edge.

    Made by refining the canonical fan (edge ``v e_0`` infinitely sharp) once with
    :class:`~splinekit.subdiv.refiner.Refinement`, so the rules are the scheme's
    own. The child fan (vertex point, edge points of the edges at ``v``, face
    points of its faces) depends only on the parent fan, so the fan's own border
    rules do not enter.
    """
    topo = _canonical_fan(scheme, n)
    es = np.zeros(topo.n_edges)
    es[topo.find_edges([[0, 1]])] = np.inf
    r = Refinement(topo, scheme, 1, creases=es, boundary="edge-only")
    parent = fan_order(topo, es > 0, np.array([0]), scheme)[0]
    child = fan_order(r.topology, r.edge_sharpness[-1] > 0, np.array([0]), scheme)[0]
    return r.stencils[0].toarray()[np.ix_(child, parent)] if (parent == np.arange(parent.size)).all() else None


def _fan_reflection(scheme: str, n: int) -> np.ndarray:
    """Permutation of the fan order mirroring the fan at the plane of its sharp
    edge: ``e_j <-> e_(-j)``, ``d_j <-> d_(-1-j)`` (indices mod ``n``)."""
    j = np.arange(n)
    perm = [np.array([0]), 1 + (-j) % n]
    if scheme == "catmull-clark":
        perm.append(1 + n + (-1 - j) % n)
    return np.concatenate(perm)


@cache
def dart_masks(scheme: str, n: int):
    """``(limit, tangent_1, tangent_2)`` masks ``(s,)`` of a valence-``n`` dart on
    its fan (order of :func:`fan_order`), or None where the eigen-structure is
    not the expected one (the caller keeps the smooth masks).

    The fan map ``S`` (:func:`dart_fan_matrix`) commutes with the mirror at the
    sharp edge's plane, so its left eigenvectors split into symmetric and
    antisymmetric ones; each parity is decomposed on its own (no mixing of
    near-equal eigenvalues across parities). ``limit``: the left eigenvector of
    the simple eigenvalue 1 (symmetric), normalized to sum 1. Tangents: the left
    eigenvectors of the largest symmetric (along the sharp edge's plane) and
    antisymmetric (across it) eigenvalues below 1, which must dominate the rest
    of the spectrum; ``tangent_2`` is signed so that ``tangent_1 x tangent_2``
    points like the faces' normal on a planar fan.
    """
    S = dart_fan_matrix(scheme, n)
    if S is None:
        return None
    size = S.shape[0]
    perm = _fan_reflection(scheme, n)
    sym, anti = [], []
    for i in range(size):
        p = perm[i]
        if p == i:
            sym.append(np.eye(size)[i])
        elif i < p:
            sym.append((np.eye(size)[i] + np.eye(size)[p]) / np.sqrt(2))
            anti.append((np.eye(size)[i] - np.eye(size)[p]) / np.sqrt(2))
    parts = []
    for basis in (np.array(sym).T, np.array(anti).T):
        values, vectors = np.linalg.eig(basis.T @ S.T @ basis)
        order = np.argsort(-np.abs(values))
        parts.append((values[order], basis @ vectors[:, order]))
    (vs, ws), (va, wa) = parts
    if abs(vs[0] - 1) > 1e-9 or np.abs(np.imag(vs[:2])).max() > 1e-12 or abs(va[0].imag) > 1e-12:
        return None
    rest = np.abs(np.concatenate([vs[2:], va[1:]]))
    lam_s, lam_a = vs[1].real, va[0].real
    if not (lam_s < 1 - 1e-9 and lam_a < 1 - 1e-9 and rest.max(initial=0) < min(lam_s, lam_a) - 1e-9):
        return None
    limit = ws[:, 0].real / ws[:, 0].real.sum()
    t1, t2 = ws[:, 1].real, wa[:, 0].real
    # orientation on a planar fan whose faces run counter-clockwise about +z
    th = 2 * np.pi * np.arange(n) / n
    e = np.stack([np.cos(th), np.sin(th)], axis=1)
    pts = [np.zeros((1, 2)), e] + ([e + np.roll(e, -1, axis=0)] if scheme == "catmull-clark" else [])
    X = np.concatenate(pts)
    a, b = t1 @ X, t2 @ X
    z = a[0] * b[1] - a[1] * b[0]
    if abs(z) < 1e-9 * np.linalg.norm(a) * np.linalg.norm(b):
        return None
    return limit, t1, t2 if z > 0 else -t2


def _dart_rows(t: Topology, edge_s: np.ndarray, rule: np.ndarray, scheme: str, kind: str):
    """Dart vertices with exact masks: ``(mask (V,), (matrices))`` with one sparse
    ``(V, V)`` matrix of their limit rows (``kind="limit"``) or two of their
    tangent rows (``"tangents"``).

    Covered: interior darts whose one sharp edge is infinitely sharp, whose
    faces are all the scheme's (quads, triangles) and of valence 3 or more;
    other darts keep the smooth masks."""
    V = t.n_vertices
    mask = np.zeros(V, dtype=bool)
    if scheme not in ("catmull-clark", "loop"):
        return mask, None
    candidates = (rule == DART) & (t.vertex_face_count == t.valence) & ~t.boundary_vertices & (t.valence >= 3)
    if not candidates.any():
        return mask, None
    hard = np.isinf(edge_s)
    infinite = np.bincount(t.edges[hard].ravel(), minlength=V) == 1
    wrong = t.face_sizes[t.corner_face] != (4 if scheme == "catmull-clark" else 3)
    bad_face = np.bincount(t.face_indices[wrong], minlength=V) > 0
    verts = np.flatnonzero(candidates & infinite & ~bad_face)
    rows, cols = [], []
    vals = ([], []) if kind == "tangents" else ([],)
    for n in np.unique(t.valence[verts]):
        masks = dart_masks(scheme, int(n))
        if masks is None:
            continue
        sel = verts[t.valence[verts] == n]
        fan = fan_order(t, edge_s > 0, sel, scheme)
        rows.append(np.repeat(sel, fan.shape[1]))
        cols.append(fan.ravel())
        for out, w in zip(vals, masks[1:] if kind == "tangents" else masks[:1]):
            out.append(np.tile(w, sel.size))
        mask[sel] = True
    if not rows:
        return mask, None
    r, c = np.concatenate(rows), np.concatenate(cols)
    return mask, tuple(csr(r, c, np.concatenate(w), (V, V)) for w in vals)


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
