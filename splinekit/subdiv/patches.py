"""Bicubic patches of Catmull-Clark limit surfaces: the exact patches of regular quads and the
Coons patches that stand in for irregular ones.

A quad whose four corners are smooth, interior and of valence 4 (:func:`regular_faces`) is exactly
the uniform bicubic B-spline patch of its 4 x 4 neighbourhood (:func:`patch_indices`); its Bézier
net is that net mapped by :data:`BSPLINE_TO_BEZIER`. An irregular quad's Coons patch
(:func:`coons_nets`) interpolates the exact limit points at its corners and edge midpoints and
shares its edges with the exact neighbouring patches, so the patches meet continuously.
:data:`QUAD_J` and :data:`QUAD_C` map a quad's parameters to those of its child quads.
"""

from __future__ import annotations

import warnings
from typing import Callable

import numpy as np

from ..basis.bernstein import all_bernstein
from ..mesh.topology import Topology
from .creases import SMOOTH, vertex_rules
from .level import Level

__all__ = ["BSPLINE_TO_BEZIER", "QUAD_C", "QUAD_J", "bezier_nets", "coons_nets", "eval_coons", "eval_patches",
           "patch_indices", "regular_faces"]

# uniform cubic B-spline segment -> cubic Bézier control points
BSPLINE_TO_BEZIER = np.array([[1, 4, 1, 0], [0, 4, 2, 0], [0, 2, 4, 0], [0, 1, 4, 1]], dtype=np.float64) / 6.0

# parent (u, v) -> child (s, t) = J (u, v) + c for the quadrant at corner i
QUAD_J = np.array([[[2, 0], [0, 2]], [[0, 2], [-2, 0]], [[-2, 0], [0, -2]], [[0, -2], [2, 0]]], dtype=np.float64)
QUAD_C = np.array([[0, 0], [0, 2], [2, 2], [2, 0]], dtype=np.float64)

LimitPoints = Callable[[int, np.ndarray], np.ndarray]
"""``(level, vertices (k,)) -> (k, dim)``: exact limit positions of vertices of a refinement level."""


def regular_faces(level: Level, edge_s: np.ndarray | None = None, vertex_s: np.ndarray | None = None) -> np.ndarray:
    """Mask ``(F,)`` of the quads of ``level`` whose limit patch is a uniform bicubic B-spline:
    four interior, smooth (no sharp incident edge or vertex) corners of valence 4.

    The former call ``regular_faces(topology, edge_s, vertex_s)`` still works (deprecated)."""
    if not isinstance(level, Level):
        warnings.warn("regular_faces(topology, edge_s, vertex_s) is deprecated: pass a subdiv Level",
                      DeprecationWarning, stacklevel=2)
        level = Level(level, edge_s, vertex_s, "catmull-clark")
    t = level.topology
    rule = vertex_rules(t, level.edge_sharpness, level.vertex_sharpness)
    good_vertex = (t.valence == 4) & (t.vertex_face_count == 4) & ~t.boundary_vertices & (rule == SMOOTH)
    good_corner = good_vertex[t.face_indices]
    ok = np.add.reduceat(good_corner.astype(np.int64), t.face_offsets[:-1]) if t.n_faces else np.zeros(0, int)
    return (t.face_sizes == 4) & (ok == 4)


def patch_indices(t: Topology, faces: np.ndarray) -> np.ndarray:
    """``(m, 4, 4)`` vertex indices of the B-spline control net of regular quads.

    Entry ``[a, b]``: ``a`` runs along the face's first edge (u), ``b`` along
    its last edge reversed (v); the face's corners sit at ``[1, 1], [2, 1],
    [2, 2], [1, 2]``.
    """
    src, nxt, prv, tw = t.face_indices, t.next_corner, t.prev_corner, t.twin
    base = t.face_offsets[faces]
    X, Y, D, Vc = [], [], [], []
    for k in range(4):
        h = base + k
        g = tw[h]
        X.append(src[nxt[nxt[g]]])
        Y.append(src[prv[g]])
        D.append(src[prv[tw[nxt[g]]]])
        Vc.append(src[h])
    P = np.empty((len(faces), 4, 4), dtype=np.int64)
    P[:, 0, 0], P[:, 1, 0], P[:, 2, 0], P[:, 3, 0] = D[0], X[0], Y[0], D[1]
    P[:, 0, 1], P[:, 1, 1], P[:, 2, 1], P[:, 3, 1] = Y[3], Vc[0], Vc[1], X[1]
    P[:, 0, 2], P[:, 1, 2], P[:, 2, 2], P[:, 3, 2] = X[3], Vc[3], Vc[2], Y[1]
    P[:, 0, 3], P[:, 1, 3], P[:, 2, 3], P[:, 3, 3] = D[3], Y[2], X[2], D[2]
    return P


def _cubic_bspline_basis(x: np.ndarray):
    """Uniform cubic B-spline basis on one span and its derivative: two ``(m, 4)`` arrays."""
    x2, x3 = x * x, x * x * x
    B = np.stack([(1 - x) ** 3, 3 * x3 - 6 * x2 + 4, -3 * x3 + 3 * x2 + 3 * x + 1, x3], axis=-1) / 6.0
    dB = np.stack([-3 * (1 - x) ** 2, 9 * x2 - 12 * x, -9 * x2 + 6 * x + 3, 3 * x2], axis=-1) / 6.0
    return B, dB


def eval_patches(t: Topology, X: np.ndarray, faces: np.ndarray, u: np.ndarray, v: np.ndarray):
    """Points and (u, v) partials ``(m, dim)`` x 3 of the regular quads ``faces`` ``(m,)`` of ``t``
    (vertices ``X``) at their local parameters ``u, v`` ``(m,)``."""
    idx = patch_indices(t, faces)  # (m, 4, 4)
    net = X[idx]  # (m, 4, 4, dim)
    Bu, dBu = _cubic_bspline_basis(u)
    Bv, dBv = _cubic_bspline_basis(v)
    p = np.einsum("ma,mb,mabd->md", Bu, Bv, net)
    du = np.einsum("ma,mb,mabd->md", dBu, Bv, net)
    dv = np.einsum("ma,mb,mabd->md", Bu, dBv, net)
    return p, du, dv


def bezier_nets(t: Topology, X: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Bicubic Bézier control nets ``(m, 4, 4, dim)`` of regular quads."""
    net = X[patch_indices(t, faces)]
    return np.einsum("ia,mabd,jb->mijd", BSPLINE_TO_BEZIER, net, BSPLINE_TO_BEZIER)


def _side_curve(net, side):
    """Bézier control points ``(m, 4, dim)`` of side ``side`` (in face order) of nets ``(m, 4, 4, dim)``."""
    if side == 0:
        return net[:, :, 0]
    if side == 1:
        return net[:, 3, :]
    if side == 2:
        return net[:, ::-1, 3]
    return net[:, 0, ::-1]


def coons_nets(limit_points: LimitPoints, level: int, t: Topology, X: np.ndarray, regular: np.ndarray,
               faces: np.ndarray) -> np.ndarray:
    """Bicubic Coons nets ``(m, 4, 4, dim)`` for the irregular quads ``faces`` of refinement level
    ``level`` (topology ``t``, vertices ``X``, regularity mask ``regular`` ``(F,)``); ``limit_points``
    gives the exact limit positions of that level's vertices and the next's (see
    :meth:`~splinekit.subdiv.SubdivisionSurface.to_bsplines`)."""
    m = faces.size
    dim = X.shape[1]
    # limit positions of the corners, and of the edge points of the next level for the midpoints
    h = t.face_offsets[faces][:, None] + np.arange(4)  # (m, 4) half-edges in face order
    ends = limit_points(level, np.stack([t.face_indices[h], t.halfedge_dst[h]]).ravel())
    ends = ends.reshape(2, m, 4, dim)
    mids = limit_points(level + 1, t.n_vertices + t.halfedge_edge[h].ravel()).reshape(m, 4, dim)
    curves = np.empty((4, m, 4, dim))
    for k in range(4):
        h = t.face_offsets[faces] + k
        a, b, mid = ends[0, :, k], ends[1, :, k], mids[:, k]
        # cubic through a, mid (at 1/2), b: the quadratic with those values, raised to degree 3
        q1 = 2 * mid - 0.5 * (a + b)
        curves[k] = np.stack([a, (a + 2 * q1) / 3, (2 * q1 + b) / 3, b], axis=1)
        g = t.twin[h]
        shared = (g >= 0) & regular[t.corner_face[np.maximum(g, 0)]]
        if shared.any():
            gf = t.corner_face[g[shared]]
            gside = g[shared] - t.face_offsets[gf]
            nets = bezier_nets(t, X, gf)
            exact = np.empty((shared.sum(), 4, dim))
            for sd in range(4):
                sel = gside == sd
                if sel.any():
                    exact[sel] = _side_curve(nets[sel], sd)[:, ::-1]
            curves[k][shared] = exact
    # sides in face order: 0 bottom (u), 1 right (v), 2 top (reversed u), 3 left (reversed v)
    bottom, right, top, left = curves[0], curves[1], curves[2][:, ::-1], curves[3][:, ::-1]
    i = np.arange(4)[:, None, None] / 3.0
    j = np.arange(4)[None, :, None] / 3.0
    P00, P30, P33, P03 = bottom[:, 0], bottom[:, 3], top[:, 3], top[:, 0]
    return (
        (1 - i) * left[:, None, :, :] + i * right[:, None, :, :]
        + (1 - j) * bottom[:, :, None, :] + j * top[:, :, None, :]
        - ((1 - i) * (1 - j) * P00[:, None, None] + i * (1 - j) * P30[:, None, None]
           + (1 - i) * j * P03[:, None, None] + i * j * P33[:, None, None])
    )


def eval_coons(limit_points: LimitPoints, level: int, t: Topology, X: np.ndarray, regular: np.ndarray,
               faces: np.ndarray, u: np.ndarray, v: np.ndarray):
    """Points and partials of the Coons patches of irregular quads (the fallback
    of :meth:`SubdivisionSurface.evaluate`, the same patches as ``to_bsplines``)."""
    nets = coons_nets(limit_points, level, t, X, regular, faces)  # (m, 4, 4, dim)
    Bu = all_bernstein(3, u, order=1)  # (2, 4, m)
    Bv = all_bernstein(3, v, order=1)
    p = np.einsum("am,bm,mabd->md", Bu[0], Bv[0], nets)
    du = np.einsum("am,bm,mabd->md", Bu[1], Bv[0], nets)
    dv = np.einsum("am,bm,mabd->md", Bu[0], Bv[1], nets)
    return p, du, dv
