"""Local refinement for the limit surface: the fans of vertices and the neighbourhoods of faces.

The limit position and tangents of a vertex depend only on its fan (the faces around it), and
the Catmull-Clark limit surface over a face only on its one-ring neighbourhood. So where the limit
masks do not apply yet (a semi-sharp feature, a non-quad face) only the fans are refined until
they do (:func:`settled_fans`, :func:`exact_limit_rows`), and an evaluation deep below a face
refines only the union of the neighbourhoods of the faces queried (:func:`neighbourhoods`): the
cost grows linearly with the sharpness or the depth where refining the whole mesh would grow it
fourfold per level.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology, ranges
from .level import Level
from .limit import crease_normals, limit_matrix, tangent_matrices
from .refiner import SCHEMES, Refinement

__all__ = ["MAX_DESCENT", "descended_limit_rows", "exact_limit_rows", "fan_normals", "mask_normals", "neighbourhoods",
           "settled_fans", "unsettled_vertices"]

MAX_DESCENT = 128
"""Most levels a vertex's fan is refined for its semi-sharp features to expire. Past
that the fan has shrunk by at least ``0.7**128 < 1e-19`` of its size (the
subdominant eigenvalues of the Catmull-Clark and Loop smooth and crease-sector
maps are at most about 0.66), so the remaining finite sharpness is treated as
infinite: the difference is below rounding."""


def unsettled_vertices(level: Level) -> np.ndarray:
    """Mask ``(V,)`` of the vertices whose limit masks do not apply yet: a finite
    positive sharpness on the vertex or an incident edge (its rule will change),
    or an incident face of another size than the scheme makes (for Catmull-Clark, not a quad)."""
    t, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
    semi = (edge_s > 0) & np.isfinite(edge_s)
    out = np.bincount(t.edges[semi].ravel(), minlength=t.n_vertices) > 0
    out |= (vertex_s > 0) & np.isfinite(vertex_s)
    odd = t.face_sizes[t.corner_face] != SCHEMES[level.scheme].output_face_size
    out[t.face_indices[odd]] = True
    return out & (t.vertex_face_count > 0)


def exact_limit_rows(level: Level, crease_method: str = "uniform", vertices: np.ndarray | None = None):
    """Sparse ``(k, V)`` limit stencils of ``vertices`` (distinct; default all) of
    ``level``, semi-sharp features included.

    :func:`~splinekit.subdiv.limit.limit_matrix` rows where the masks apply
    (every sharpness at the vertex 0 or infinite); the rows of the other
    vertices come from :func:`descended_limit_rows`, which refines only their
    fans, so the cost grows linearly with the sharpness, not fourfold per unit.
    """
    vertices = np.arange(level.n_vertices) if vertices is None else np.asarray(vertices, dtype=np.int64)
    L = limit_matrix(level)[vertices]
    pending = unsettled_vertices(level)[vertices]
    if not pending.any():
        return L
    rows = descended_limit_rows(level, crease_method, vertices[pending]).tocoo()
    keep = sp.diags((~pending).astype(np.float64)) @ L
    moved = sp.csr_matrix((rows.data, (np.flatnonzero(pending)[rows.row], rows.col)), shape=L.shape)
    return sp.csr_matrix(keep + moved)


def descended_limit_rows(level: Level, crease_method: str, centres: np.ndarray):
    """Sparse ``(k, V)`` limit stencils of the vertices ``centres`` (distinct) of ``level``,
    from their fans refined until the masks apply (see :func:`settled_fans`)."""
    blocks, owners = [], []
    for fans, W, centre, ids in settled_fans(level, crease_method, centres):
        blocks.append(limit_matrix(fans)[centre] @ W)
        owners.append(ids)
    order = np.argsort(np.concatenate(owners), kind="stable")
    return sp.csr_matrix(sp.vstack(blocks, format="csr")[order])


def settled_fans(level: Level, crease_method: str, centres: np.ndarray, X: np.ndarray | None = None):
    """Refine the fans of the vertices ``centres`` (distinct, with faces) of ``level``
    until the limit masks apply at them.

    The limit position and tangents of a vertex depend only on its fan (the
    faces around it): the fan of its child is made of the child faces at it,
    whose corners (its vertex point, the edge points of its edges, the face
    points of its faces) come from the parent fan, and whose sharpness comes
    from its own edges (and, for Chaikin creases, the other edges at it). So
    each level refines the disjoint union of the fans still unsettled (see
    :func:`unsettled_vertices`) by one level and keeps only their child fans:
    ``ceil(s)`` levels of a few faces per vertex for sharpness ``s`` (at most
    :data:`MAX_DESCENT`), where refining the whole mesh would cost ``4**s``
    times the mesh. The union's outer border is in no centre's child fan, so
    the (boundary) rules there do not matter.

    Yields, level by level, ``(fans, data, centre, ids)`` for the fans settled at
    that level: the union as a :class:`~splinekit.subdiv.level.Level`, ``data`` (see below) on the union's vertices, the settled
    centres' vertices in the union and their positions in ``centres``.
    Without ``X``, ``data`` is the sparse map from the vertices of ``level`` to the
    union's vertices. With positions ``X`` ``(V, dim)`` of ``level``, it is the
    union's positions relative to the centre of their fan: the fans shrink by
    half per level, and the tangents (differences of ring points) would drown
    in the rounding of absolute positions after a few dozen levels.
    """
    t, scheme = level.topology, level.scheme
    topo, vertex, centre, edge, fan = _vertex_fans(t, centres)
    es, vs = level.edge_sharpness[edge], level.vertex_sharpness[vertex]
    if X is None:
        data = sp.csr_matrix((np.ones(vertex.size), (np.arange(vertex.size), vertex)), shape=(vertex.size, t.n_vertices))
    else:
        data = X[vertex] - X[centres[fan]]
    ids = np.arange(centres.size)
    for depth in range(MAX_DESCENT):
        r = Refinement(topo, scheme, 1, creases=es, corners=vs, boundary="edge-only", crease_method=crease_method)
        fans = r.finest
        topo, es, vs = fans.topology, fans.edge_sharpness, fans.vertex_sharpness
        data = sp.csr_matrix(fans.stencil @ data) if X is None else fans.stencil @ data
        # vertex points keep their parent's index: the centres are where they were
        done = ~unsettled_vertices(fans)[centre]
        if depth == MAX_DESCENT - 1:
            done[:] = True
        if done.any():
            yield fans, data, centre[done], ids[done]
        if done.all():
            return
        ids = ids[~done]
        topo, sub, centre, edge, fan = _vertex_fans(topo, centre[~done])
        es, vs, data = es[edge], vs[sub], data[sub]
        if X is not None:
            data = data - data[centre[fan]]


def _vertex_fans(t: Topology, centres: np.ndarray):
    """The disjoint union of the fans (the faces at a vertex) of the distinct
    ``centres``: ``(topology, vertex of t per union vertex, the centres in the
    union, edge of t per union edge, fan (position in centres) per union vertex)``."""
    offsets, vface = t.vertex_faces
    counts = offsets[centres + 1] - offsets[centres]
    owner = np.repeat(np.arange(centres.size), counts)
    g = vface[ranges(offsets[centres], counts)]
    gs = t.face_sizes[g]
    corner_owner = np.repeat(owner, gs)
    corners = ranges(t.face_offsets[g], gs)
    keys, new_index = np.unique(corner_owner * t.n_vertices + t.face_indices[corners], return_inverse=True)
    vertex = keys % t.n_vertices
    topo = Topology(keys.size, new_index.ravel(), np.concatenate([[0], np.cumsum(gs)]), check=False)
    centre = np.searchsorted(keys, np.arange(centres.size) * t.n_vertices + centres)
    edge = t.find_edges(vertex[topo.edges])
    return topo, vertex, centre, edge, keys // t.n_vertices


def neighbourhoods(level: Level, X: np.ndarray, faces: np.ndarray, max_faces: int | None = None):
    """The disjoint union of the one-ring neighbourhoods (all faces sharing a
    vertex) of the distinct ``faces`` of ``level`` (vertices ``X``), as ``(mesh, edge sharpness, vertex
    sharpness, face_in_union)``; None when it would have more than
    ``max_faces`` faces.

    Under Catmull-Clark refinement the limit surface over a face depends only
    on this neighbourhood, at every level: so refining the (small) union
    instead of the whole mesh evaluates those faces exactly, to depths the
    whole mesh could not afford. The union's own borders are outside every
    queried face's neighbourhood, so their (boundary) rules do not matter.
    """
    t = level.topology
    offsets, vface = t.vertex_faces
    sizes = t.face_sizes[faces]
    owner = np.repeat(np.arange(faces.size), sizes)
    corners = ranges(t.face_offsets[faces], sizes)
    verts = t.face_indices[corners]
    counts = offsets[verts + 1] - offsets[verts]
    own = np.repeat(owner, counts)
    pos = ranges(offsets[verts], counts)
    pair = np.unique(own * t.n_faces + vface[pos])
    if max_faces is not None and pair.size > max_faces:
        return None
    own, g = pair // t.n_faces, pair % t.n_faces
    gs = t.face_sizes[g]
    cown = np.repeat(own, gs)
    cpos = ranges(t.face_offsets[g], gs)
    keys, new_index = np.unique(cown * t.n_vertices + t.face_indices[cpos], return_inverse=True)
    vertex = keys % t.n_vertices
    union_offsets = np.concatenate([[0], np.cumsum(gs)])
    topo = Topology(keys.size, new_index.ravel(), union_offsets, check=False)
    mesh = PolyMesh.from_topology(X[vertex], topo)
    base_edges = t.find_edges(vertex[topo.edges])
    creases = np.where(base_edges >= 0, level.edge_sharpness[np.maximum(base_edges, 0)], 0.0)
    corners = level.vertex_sharpness[vertex]
    where = np.flatnonzero(g == faces[own])
    return mesh, creases, corners, where


def mask_normals(level: Level, X: np.ndarray):
    """Limit normals ``(V, 3)`` (not unit) where the tangent masks (smooth and dart
    vertices) or the crease sectors (see :func:`~splinekit.subdiv.limit.crease_normals`)
    give them, and the mask ``(V,)`` of those vertices; valid where every sharpness
    at the vertex is 0 or infinite."""
    T1, T2, ok = tangent_matrices(level)
    n = np.cross(T1 @ X, T2 @ X)
    if not ok.all():
        cn, covered = crease_normals(level, X)
        use = ~ok & covered
        n[use] = cn[use]
        ok = ok | covered
    return n, ok


def fan_normals(t: Topology, P: np.ndarray) -> np.ndarray:
    """Sum over the faces at each vertex of the face's vector area (Newell), ``(V, 3)``."""
    a = P[t.face_indices]
    b = P[t.halfedge_dst]
    cross = np.cross(a, b)
    face_area = np.zeros((t.n_faces, 3))
    np.add.at(face_area, t.corner_face, cross)
    out = np.zeros((t.n_vertices, 3))
    np.add.at(out, t.face_indices, face_area[t.corner_face])
    return out
