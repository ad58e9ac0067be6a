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

from ..basis import algebra
from ..basis.bernstein import all_bernstein

__all__ = ["CellSet", "cells_of_patches", "edge_samples", "second_derivative_bounds"]


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


def _homogeneous(surface):
    """``(p, q, knots_u, knots_v, coefs (nu, nv, 4))`` of a 3-D spline surface."""
    coefs = np.asarray(surface.homogeneous_points)
    return surface.degree_u, surface.degree_v, surface.knots_u, surface.knots_v, coefs


def _is_bezier(p, U):
    return U.size == 2 * (p + 1) and U[0] == U[p] and U[p + 1] == U[-1]


def cells_of_patches(patches) -> list[CellSet]:
    """Cut 3-D :class:`~splinekit.SplineSurface` patches into Bézier cells, grouped by degrees."""
    groups: dict = {}
    for index, s in enumerate(patches):
        p, q, U, V, coefs = _homogeneous(s)
        entry = groups.setdefault((p, q), ([], [], [], []))
        if _is_bezier(p, U) and _is_bezier(q, V):
            # already one Bézier cell (the common case of patch sets): no knot algebra
            entry[0].append(coefs[None])
            entry[1].append(np.array([index]))
            entry[2].append(np.array([[U[p], U[p + 1], V[q], V[q + 1]]]))
            entry[3].append(np.zeros((1, 2), dtype=np.int64))
            continue
        bu, su = algebra.bezier_segments(p, U, coefs)  # (nsu, p + 1, nv, 4)
        bv, sv = algebra.bezier_segments(q, V, su.transpose(2, 0, 1, 3))  # (nsv, q + 1, nsu, p + 1, 4)
        nets = sv.transpose(2, 0, 3, 1, 4)  # (nsu, nsv, p + 1, q + 1, 4)
        nsu, nsv = nets.shape[:2]
        entry[0].append(nets.reshape(nsu * nsv, p + 1, q + 1, 4))
        entry[1].append(np.full(nsu * nsv, index))
        iu, iv = np.meshgrid(np.arange(nsu), np.arange(nsv), indexing="ij")
        iu, iv = iu.ravel(), iv.ravel()
        entry[2].append(np.column_stack([bu[iu], bu[iu + 1], bv[iv], bv[iv + 1]]))
        entry[3].append(np.column_stack([iu, iv]))
    return [
        CellSet(p, q, np.concatenate(n), np.concatenate(i), np.concatenate(b), np.concatenate(k))
        for (p, q), (n, i, b, k) in sorted(groups.items())
    ]


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
    edges_u = [N[:, :, 0], N[:, :, -1]]  # (c, p + 1, 4)
    edges_v = [N[:, 0, :], N[:, -1, :]]  # (c, q + 1, 4)
    Bu = _bernstein_table(cells.p, 0, 0)  # (p + 1, 5) at EDGE_T
    Bv = _bernstein_table(cells.q, 0, 0)
    pts, extent = [], []
    for e, B in ((edges_u[0], Bu), (edges_u[1], Bu), (edges_v[0], Bv), (edges_v[1], Bv)):
        h = np.einsum("it,cik->ctk", B, e)
        pts.append(h[..., :3] / h[..., 3:])
        cart = e[..., :3] / e[..., 3:]
        extent.append(_norms(cart - cart[:, :1]).max(axis=1))
    return np.stack(pts, axis=1), np.stack(extent, axis=1)
