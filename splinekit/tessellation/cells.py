"""Bézier cells: the unit of work of the surface tessellator.

Every patch is cut at its knots into Bézier cells (one per non-empty knot
span pair). A cell keeps its homogeneous control net ``(p + 1, q + 1, 4)``,
the patch it came from and the rectangle of the patch's parameters it covers.
This module also computes, per cell, bounds on the second derivatives (which
set the a-priori sample counts) and the cell's four boundary curves (which
are matched between cells to make the samples on shared edges agree).
"""

from __future__ import annotations

import functools

import numpy as np

from .. import _kernels
from ..basis import algebra
from ..basis.bernstein import all_bernstein

__all__ = ["CellSet", "bezier_matrix", "cells_of_patches", "edge_samples", "second_derivative_bounds"]


class CellSet:
    """Bézier cells of one degree pair ``(p, q)``.

    Attributes
    ----------
    nets : (c, p + 1, q + 1, 4) homogeneous control nets ``(w x, w y, w z, w)``
    rational : (c,) bool, False when the cell's weights are all equal
    patch : (c,) int64 patch index
    box : (c, 4) ``(u0, u1, v0, v1)`` patch parameters the cell covers
    span : (c, 2) ``(iu, iv)``: the cell is Bézier span ``iu`` in u, ``iv`` in v of its patch
    """

    def __init__(self, p, q, nets, patch, box, span):
        self.p, self.q = p, q
        self.nets = np.ascontiguousarray(nets, dtype=np.float64)
        w = self.nets[..., 3].reshape(len(self.nets), -1)
        self.rational = (w.max(axis=1) - w.min(axis=1)) > 1e-14 * w.max(axis=1)
        self.points = self.nets[..., :3] / self.nets[..., 3:]
        self.patch = np.asarray(patch, dtype=np.int64)
        self.box = np.asarray(box, dtype=np.float64).reshape(-1, 4)
        self.span = np.asarray(span, dtype=np.int64).reshape(-1, 2)  # (iu, iv) knot span of the cell in its patch

    def __len__(self):
        return len(self.nets)


def cells_of_patches(patches) -> list[CellSet]:
    """Cut 3-D :class:`~splinekit.SplineSurface` patches into Bézier cells, grouped by degrees.

    Cells keep the order of their patches within each group. Single-cell patches (the
    common case of patch sets) need no knot algebra: their knots are checked and their
    control points stacked once per group (the polynomial ones given unit weights in
    one operation).
    """
    groups: dict = {}
    for index, s in enumerate(patches):
        groups.setdefault((s.degree_u, s.degree_v), []).append(index)
    return [_cellset(p, q, members, [patches[i] for i in members]) for (p, q), members in sorted(groups.items())]


def _bezier_knots(p, knots):
    """``(single (k,) bool, ends (k, 2))``: which knot vectors are one Bézier span
    (``p + 1`` equal values, then ``p + 1`` equal values) and their ``(first, last)``."""
    sized = np.flatnonzero([U.size == 2 * (p + 1) for U in knots])
    single = np.zeros(len(knots), dtype=bool)
    ends = np.zeros((len(knots), 2))
    if sized.size:
        K = np.stack([knots[i] for i in sized])  # (k, 2 p + 2)
        single[sized[(K[:, 0] == K[:, p]) & (K[:, p + 1] == K[:, -1])]] = True
        ends[sized] = K[:, [p, p + 1]]
    return single, ends


def _cellset(p, q, index, surfaces) -> CellSet:
    """The :class:`CellSet` of patches of degrees ``(p, q)`` (their ``index`` in the input)."""
    su, eu = _bezier_knots(p, [s.knots_u for s in surfaces])
    sv, ev = _bezier_knots(q, [s.knots_v for s in surfaces])
    single = su & sv
    parts = [None if one else _split(p, q, s) for one, s in zip(single, surfaces)]
    count = np.array([1 if part is None else len(part[0]) for part in parts])
    start = np.concatenate([[0], np.cumsum(count)])
    nets = np.empty((start[-1], p + 1, q + 1, 4))
    nets[..., 3] = 1.0
    box = np.repeat(np.column_stack([eu, ev]), count, axis=0)  # (u0, u1, v0, v1)
    span = np.zeros((start[-1], 2), dtype=np.int64)
    rational = np.array([s.is_rational for s in surfaces])
    for flag, k in ((False, 3), (True, 4)):  # single-cell patches, polynomial then rational: one stack each
        which = np.flatnonzero(single & (rational == flag))
        if which.size:
            # homogeneous points of a rational patch, Cartesian of a polynomial one (no copies)
            pts = [surfaces[w].homogeneous_points if flag else surfaces[w].control_points for w in which]
            nets[start[which], ..., :k] = np.stack(pts)
    for w in np.flatnonzero(~single):
        nets[start[w] : start[w + 1]], box[start[w] : start[w + 1]], span[start[w] : start[w + 1]] = parts[w]
    return CellSet(p, q, nets, np.repeat(np.asarray(index, dtype=np.int64), count), box, span)


@functools.lru_cache(maxsize=256)
def bezier_matrix(p, knots):
    """``(breaks, M (s, p + 1, n))``: the Bézier segments of any degree-``p`` spline on ``knots``
    (a tuple) are ``M @ coefficients``. Cached: B-reps repeat a few knot vectors (lines, circles,
    arcs) over and over, and the decomposition by knot refinement costs far more than the
    product (read-only arrays)."""
    U = np.asarray(knots, dtype=np.float64)
    n = U.size - p - 1
    if U.size == 2 * (p + 1) and U[0] == U[p] and U[p + 1] == U[-1]:  # one Bézier span
        breaks, M = np.array([U[0], U[-1]]), np.eye(n)[None]
    else:
        breaks, M = algebra.bezier_segments(p, U, np.eye(n))
    for a in (breaks, M):
        a.setflags(write=False)
    return breaks, M


def _split(p, q, surface):
    """``(nets (k, p + 1, q + 1, 4), boxes (k, 4), spans (k, 2))`` of a multi-span patch's
    Bézier cells, ``(iu, iv)`` order with ``iu`` major."""
    coefs = np.asarray(surface.homogeneous_points)
    bu, Mu = bezier_matrix(p, tuple(surface.knots_u.tolist()))  # (nsu, p + 1, nu)
    bv, Mv = bezier_matrix(q, tuple(surface.knots_v.tolist()))  # (nsv, q + 1, nv)
    # two contractions, u then v (the order einsum's optimizer picks, without its ~0.1 ms path search per call)
    nets = np.einsum("bjl,ailc->abijc", Mv, np.einsum("aik,klc->ailc", Mu, coefs))  # (nsu, nsv, p + 1, q + 1, 4)
    nsu, nsv = nets.shape[:2]
    iu, iv = np.meshgrid(np.arange(nsu), np.arange(nsv), indexing="ij")
    iu, iv = iu.ravel(), iv.ravel()
    box = np.column_stack([bu[iu], bu[iu + 1], bv[iv], bv[iv + 1]])
    return nets.reshape(nsu * nsv, p + 1, q + 1, 4), box, np.column_stack([iu, iv])


@functools.lru_cache(maxsize=64)
def _bernstein_table(p, samples, order):
    """Bernstein values at ``EDGE_T`` (``samples == 0``) or at ``linspace(0, 1, samples)``
    with derivatives up to ``order`` (cached, read-only)."""
    t = EDGE_T if samples == 0 else np.linspace(0.0, 1.0, samples)
    B = all_bernstein(p, t, order)
    B.setflags(write=False)
    return B


def _norms(x):
    return np.sqrt(np.einsum("...i,...i->...", x, x))


def second_derivative_bounds(cells: CellSet):
    """Per cell ``(Muu, Muv, Mvv, Lu, Lv)`` in the cell's local parameters [0, 1]^2.

    ``M`` bound ``|S_uu|``, ``|S_uv|``, ``|S_vv|`` over the cell; ``L`` are typical
    speeds ``|S_u|``, ``|S_v|`` (for the angle criterion). Polynomial cells use
    the control net: ``S_uu = p (p - 1) sum D2_u P B`` so ``|S_uu| <= p (p - 1)
    max |D2_u P|`` (a true bound). Rational cells sample the exact second
    derivatives (quotient rule) on a grid and add a safety margin; the
    tessellator measures and refines afterwards, so the estimate only needs to
    be close.
    """
    p, q, c = cells.p, cells.q, len(cells)
    P = cells.points
    Muu, Muv, Mvv = np.zeros(c), np.zeros(c), np.zeros(c)
    if p >= 2:
        Muu = p * (p - 1) * _norms(P[:, 2:] - 2 * P[:, 1:-1] + P[:, :-2]).reshape(c, -1).max(axis=1)
    if q >= 2:
        Mvv = q * (q - 1) * _norms(P[:, :, 2:] - 2 * P[:, :, 1:-1] + P[:, :, :-2]).reshape(c, -1).max(axis=1)
    Muv = p * q * _norms(P[:, 1:, 1:] - P[:, 1:, :-1] - P[:, :-1, 1:] + P[:, :-1, :-1]).reshape(c, -1).max(axis=1)
    Lu = p * _norms(P[:, 1:] - P[:, :-1]).reshape(c, -1).mean(axis=1)
    Lv = q * _norms(P[:, :, 1:] - P[:, :, :-1]).reshape(c, -1).mean(axis=1)
    rat = np.flatnonzero(cells.rational)
    if rat.size:
        su, suv, sv = _sampled_second_derivatives(cells.nets[rat], p, q)
        Muu[rat], Muv[rat], Mvv[rat] = 1.5 * su, 1.5 * suv, 1.5 * sv
    return Muu, Muv, Mvv, Lu, Lv


def _sampled_second_derivatives(nets, p, q, samples: int = 6):
    """Max of ``|S_uu|``, ``|S_uv|``, ``|S_vv|`` of rational cells on a ``samples^2`` grid."""
    Bu = _bernstein_table(p, samples, 2)  # (3, p + 1, s)
    Bv = _bernstein_table(q, samples, 2)
    kernels = _kernels.get("splinekit.tessellation._kernels")
    if kernels is not None:
        M = kernels.sampled_second_derivatives(np.ascontiguousarray(nets), np.ascontiguousarray(Bu), np.ascontiguousarray(Bv))
        return M[:, 0], M[:, 1], M[:, 2]
    # A[a, b] = d^a/du^a d^b/dv^b of the homogeneous patch: (c, s, s, 4)
    A = {}
    for a in range(3):
        T = np.einsum("is,cijk->csjk", Bu[a], nets)
        for b in range(3 - a):
            A[a, b] = np.einsum("jt,csjk->cstk", Bv[b], T)
    w = {key: val[..., 3:] for key, val in A.items()}
    S = A[0, 0][..., :3] / w[0, 0]
    Su = (A[1, 0][..., :3] - w[1, 0] * S) / w[0, 0]
    Sv = (A[0, 1][..., :3] - w[0, 1] * S) / w[0, 0]
    Suu = (A[2, 0][..., :3] - 2 * w[1, 0] * Su - w[2, 0] * S) / w[0, 0]
    Svv = (A[0, 2][..., :3] - 2 * w[0, 1] * Sv - w[0, 2] * S) / w[0, 0]
    Suv = (A[1, 1][..., :3] - w[1, 0] * Sv - w[0, 1] * Su - w[1, 1] * S) / w[0, 0]
    c = len(nets)
    return tuple(_norms(x).reshape(c, -1).max(axis=1) for x in (Suu, Suv, Svv))


EDGE_T = np.array([0.0, 0.25, 0.5, 0.75, 1.0])


def edge_samples(cells: CellSet):
    """The four boundary curves of every cell at ``t = 0, 1/4, 1/2, 3/4, 1``.

    Returns ``(points (c, 4, 5, 3), collapsed (c, 4) extent)``: edges in the
    order ``v = 0``, ``v = 1`` (running along u), ``u = 0``, ``u = 1`` (along v),
    and the largest distance of an edge's control points from its first one
    (zero when the edge collapses to a point, as at a pole).
    """
    N = cells.nets
    edges_u = np.stack([N[:, :, 0], N[:, :, -1]], axis=1)  # (c, 2, p + 1, 4)
    edges_v = np.stack([N[:, 0, :], N[:, -1, :]], axis=1)  # (c, 2, q + 1, 4)
    Bu = _bernstein_table(cells.p, 0, 0)  # (p + 1, 5) at EDGE_T
    Bv = _bernstein_table(cells.q, 0, 0)
    pts, extent = [], []
    for e, B in ((edges_u, Bu), (edges_v, Bv)):  # both edges of a direction at once
        h = np.einsum("it,ceik->cetk", B, e)
        pts.append(h[..., :3] / h[..., 3:])
        cart = e[..., :3] / e[..., 3:]
        extent.append(_norms(cart - cart[:, :, :1]).max(axis=2))
    return np.concatenate(pts, axis=1), np.concatenate(extent, axis=1)
