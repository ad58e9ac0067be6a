"""Limit masks: positions and tangents of the limit surface at mesh vertices.

The masks are valid on a mesh whose faces the scheme produces (quads for
Catmull-Clark, triangles for Loop) and whose semi-sharp features have expired
(every sharpness 0 or infinite); :class:`~splinekit.subdiv.surface.SubdivisionSurface`
refines that far first and maps the result back to the control vertices.

- Smooth vertex: the scheme's own masks (``Scheme.limit_mask``, ``Scheme.tangent_terms``:
  :func:`splinekit.subdiv.catmull_clark.limit_mask`, :func:`splinekit.subdiv.loop.limit_mask`
  and their ``tangent_terms``).
- Dart (one infinitely sharp edge, smooth vertex rule), both schemes: the
  smooth masks are not exact there (the crease edge rule breaks the rotational
  symmetry). The map from the dart's fan to its child's fan is a fixed matrix
  per valence, built by refining a canonical fan with the scheme's own rules
  (:func:`dart_fan_matrix`); the limit and tangent masks are its left
  eigenvectors (:func:`dart_masks`).
- Crease (and boundary) vertex, both schemes: the cubic B-spline limit of the
  crease polygon ``(a + 4 v + b) / 6``, tangent ``b - a``; the normal from the
  eigen-analysis of the scheme's crease-sector map (``Scheme.sector_matrix``).
- Corner: the vertex itself.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..mesh.topology import Topology
from .creases import CORNER, CREASE, DART, vertex_rules
from .level import Level
from .masks import crease_matrix, csr, diag
from .refiner import SCHEMES, Refinement


def _rules(scheme: str):
    """The scheme's :class:`~splinekit.subdiv.scheme.Scheme`; ParameterError when it has no limit masks."""
    rules = SCHEMES[scheme]
    if rules.limit_mask is None:
        raise ParameterError(f"limit masks are implemented for catmull-clark and loop, not {scheme}")
    return rules


def _quads(scheme: str) -> bool:
    """Whether the scheme's fans are quads, whose rings hold the far corners ``d_j`` too."""
    return SCHEMES[scheme].output_face_size == 4


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


def limit_matrix(level: Level) -> sp.csr_matrix:
    """``(V, V)``: limit positions of all vertices of ``level`` from their neighbourhoods."""
    t, edge_s, vertex_s, scheme = level.topology, level.edge_sharpness, level.vertex_sharpness, level.scheme
    rule = vertex_rules(t, edge_s, vertex_s)
    rule[t.vertex_face_count == 0] = CORNER
    smooth_rows = rule <= DART
    smooth = _rules(scheme).limit_mask(t)
    crease = crease_matrix(t, edge_s > 0, rule == CREASE, centre=2.0 / 3.0)
    L = sp.csr_matrix(diag(smooth_rows) @ smooth + crease + diag(rule == CORNER))
    darts, dart_part = _dart_rows(t, edge_s, rule, scheme, "limit")
    return _replace_rows(L, darts, dart_part[0]) if darts.any() else L


def tangent_matrices(level: Level):
    """``(T1, T2, ok)``: ``(V, V)`` tangent masks of the smooth and dart vertices of ``level``
    (whose limit normal is ``T1 @ X`` x ``T2 @ X``), and the mask ``ok`` of the
    vertices they cover."""
    t, edge_s, vertex_s, scheme = level.topology, level.edge_sharpness, level.vertex_sharpness, level.scheme
    V = t.n_vertices
    rule = vertex_rules(t, edge_s, vertex_s)
    ok = (rule <= DART) & (t.vertex_face_count > 0) & ~t.boundary_vertices
    verts = np.flatnonzero(ok)
    ring, n = ordered_rings(t, verts)
    rows, cols, w1, w2 = [], [], [], []
    terms = _rules(scheme).tangent_terms
    for j in range(ring.shape[1]):
        live = j < n
        for out, part in zip((rows, cols, w1, w2), terms(t, ring[live, j], verts[live], n[live].astype(np.float64), j)):
            out += part
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
    if _quads(scheme):
        cols.append(t.face_indices[t.next_corner[t.next_corner[ring]]])
    return np.concatenate(cols, axis=1)


def _canonical_fan(scheme: str, n: int) -> Topology:
    """The fan of a valence-``n`` vertex 0 in the order of :func:`fan_order`."""
    j = np.arange(n)
    if _quads(scheme):
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
    if _quads(scheme):
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
    pts = [np.zeros((1, 2)), e] + ([e + np.roll(e, -1, axis=0)] if _quads(scheme) else [])
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
    if _rules(scheme).limit_mask is None:
        return mask, None
    candidates = (rule == DART) & (t.vertex_face_count == t.valence) & ~t.boundary_vertices & (t.valence >= 3)
    if not candidates.any():
        return mask, None
    hard = np.isinf(edge_s)
    infinite = np.bincount(t.edges[hard].ravel(), minlength=V) == 1
    wrong = t.face_sizes[t.corner_face] != _rules(scheme).output_face_size
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


def _across_mask(scheme: str, k: int) -> np.ndarray:
    """Left eigenvector of the sector map that is symmetric under the sector's
    reflection (``e_j <-> e_(k-j)``, ``d_j <-> d_(k-1-j)``) and has the largest
    eigenvalue below 1: the tangent mask across the crease (the crease tangent
    ``e_k - e_0`` is antisymmetric, eigenvalue 1/2). ``None`` when that
    eigenvalue is not above 1/4."""
    A = _rules(scheme).sector_matrix(k)
    size = A.shape[0]
    perm = np.arange(size)
    perm[1 : k + 2] = np.arange(k + 1, 0, -1)
    if _quads(scheme):
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


def crease_normals(level: Level, X: np.ndarray):
    """Limit normals at the crease, boundary and corner vertices of ``level`` (positions ``X``
    ``(V, 3)``): ``(normals (V, 3), covered (V,))``.

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
    t, edge_s, scheme = level.topology, level.edge_sharpness, level.scheme
    V = t.n_vertices
    rule = vertex_rules(t, edge_s, level.vertex_sharpness)
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
        if _quads(scheme):
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
