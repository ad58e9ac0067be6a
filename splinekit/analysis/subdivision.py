"""Continuity of every edge of a Catmull-Clark limit surface, all edges evaluated in one batch.

The patches of a :class:`~splinekit.SubdivisionSurface` meet along the edges of its quads, and two
patches sharing an edge parametrize it alike (in opposite directions), so no matching or
closest-point search is needed: the samples of every edge on both sides are evaluated in a few
calls of the surface's evaluator, and each edge is compared from slices of those arrays.
"""

from __future__ import annotations

import numpy as np

from ..diffgeom.curvature import curvature
from ..diffgeom.protocol import SubdivisionPatch
from .compare import compare, curvature_rows, edge_tangent, frame
from .sides import SIDE_NAMES, Side, subdivision_info

__all__ = ["subdivision_continuity"]

_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
"""``(u, v)`` of a quad patch's corners in the order of its face's vertices (side k runs from corner k to k + 1)."""


class _Pointwise(SubdivisionPatch):
    """The patches of one surface queried pointwise: query ``i`` lies on quad ``faces[i]`` (the
    parametric-surface protocol of :class:`~splinekit.SubdivisionPatch`, for arrays of
    ``len(faces)`` parameters)."""

    def __init__(self, surface, faces: np.ndarray):  # no super().__init__: there is no single face to check
        self.surface, self.faces, self.face = surface, faces, -1

    def _first(self, u, v):
        P, Du, Dv, _ = self.surface.evaluate(self.faces, u, v)
        return P, Du, Dv


def _edge_pairs(quads: np.ndarray):
    """``(pairs (E, 2, 2), free)``: the two half-edges ``[face, side]`` of every edge used twice,
    and the count of boundary edges (used once)."""
    start, end = quads, np.roll(quads, -1, axis=1)
    lo, hi = np.minimum(start, end).ravel(), np.maximum(start, end).ravel()
    order = np.lexsort((hi, lo))
    key = np.column_stack([lo[order], hi[order]])
    new = np.concatenate([[True], np.any(key[1:] != key[:-1], axis=1)])
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, len(order)))
    two = starts[counts == 2]
    half = np.column_stack([order[two], order[two + 1]])  # flat half-edge indices
    return np.stack([half // 4, half % 4], axis=-1), int((counts == 1).sum())


def _side_samples(surface, faces, sides, t, reverse: bool):
    """Curvature, first derivatives, uv and pcurve directions of sides ``sides`` of quads ``faces``
    (``(E,)`` each) at fractions ``t`` ``(n,)`` (``reverse``: from the side's end)."""
    a, b = _CORNERS[sides], _CORNERS[(sides + 1) % 4]
    s = 1.0 - t if reverse else t
    uv = (a[:, None, :] + s[None, :, None] * (b - a)[:, None, :]).reshape(-1, 2)
    f = np.repeat(faces, len(t))
    patch = _Pointwise(surface, f)
    c = curvature(patch, uv[:, 0], uv[:, 1])
    ders = patch.derivatives(uv[:, 0], uv[:, 1], 1)
    d_uv = np.repeat(b - a, len(t), axis=0)
    return c, ders, uv, d_uv


def subdivision_continuity(surface, samples: int, gap_tol=None, angle_tol=None, curvature_tol=None):
    """``(edges, free)``: an :class:`~splinekit.analysis.EdgeContinuity` per interior edge of the
    Catmull-Clark ``surface`` (patch indices are its quads), and the number of boundary edges."""
    quads, irregular, normals = subdivision_info(surface)
    pairs, free = _edge_pairs(quads)
    t = np.linspace(0.0, 1.0, samples)
    ca, da, uva, dua = _side_samples(surface, pairs[:, 0, 0], pairs[:, 0, 1], t, False)
    cb, db, uvb, dub = _side_samples(surface, pairs[:, 1, 0], pairs[:, 1, 1], t, True)
    tangent = edge_tangent(da, dua)

    def corner_data(faces, uv):
        # extraordinary samples: the patch corners at extraordinary vertices, with their normals
        f = np.repeat(faces, samples)
        corner = np.where(np.all(np.abs(uv - np.round(uv)) <= 1e-12, axis=1),
                          np.round(uv[:, 0]) + 3 * np.round(uv[:, 1]) - 2 * np.round(uv[:, 0]) * np.round(uv[:, 1]), -1)
        # (0,0) -> 0, (1,0) -> 1, (1,1) -> 2, (0,1) -> 3
        corner = corner.astype(np.int64)
        vertex = np.where(corner >= 0, quads[f, np.maximum(corner, 0)], -1)
        ev = (vertex >= 0) & irregular[np.maximum(vertex, 0)]
        return ev, None if normals is None else normals[np.maximum(vertex, 0)]

    eva, na = corner_data(pairs[:, 0, 0], uva)
    evb, nb = corner_data(pairs[:, 1, 0], uvb)
    edges = []
    for e, ((f, k), (g, l)) in enumerate(pairs):
        rows = slice(e * samples, (e + 1) * samples)
        A = Side(int(f), surface, None, False, SIDE_NAMES[k], None, 0.0, False)
        B = Side(int(g), surface, None, False, SIDE_NAMES[l], None, 0.0, False)
        fa = frame(A, t, uva[rows], dua[rows], da[:, :, rows], curvature_rows(ca, rows), tangent[rows], eva[rows],
                   None if na is None else na[rows])
        fb = frame(B, 1.0 - t, uvb[rows], dub[rows], db[:, :, rows], curvature_rows(cb, rows), tangent[rows], evb[rows],
                   None if nb is None else nb[rows])
        edges.append(compare(fa, fb, gap_tol, angle_tol, curvature_tol))
    return tuple(edges), free
