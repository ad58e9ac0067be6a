"""Evaluated sample grids of Bézier cells and multi-span patches, with their measured deviations.

A grid is evaluated at its vertices (with first partials, for the normals), at the
half-step points (edge midpoints, quad centres) and at the triangle centres; one fused
pass (a compiled kernel once loaded, else numpy) measures the chordal deviations and
normal angles per cell. Arrays use the layout ``(rows, grid, coordinate, columns)``.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
from scipy.sparse import vstack

from .. import _kernels
from ..basis import design_matrix
from ..basis.bernstein import all_bernstein
from .cells import CellSet

__all__ = ["Grid", "span_params"]


def _product(A, B):
    """``A @ B`` for a small inner dimension (a degree + 1). Large outputs go through
    einsum's plain loop: BLAS is several times slower on such skinny products (and its
    threads compete with everything else on a small machine)."""
    if A.shape[0] * B.shape[1] < 100_000:
        return A @ B
    return np.einsum("ij,jk->ik", A, B)


@functools.lru_cache(maxsize=128)
def _bern(p, n, where, order=0):
    """``(len(t), p + 1)`` Bernstein values (or ``order``-th derivatives) at the uniform
    sample set ``where`` of ``n`` steps: ``"nodes"`` ``i / n``, ``"halves"`` ``i / (2 n)``,
    ``"first"`` / ``"second"`` thirds ``(i + 1/3) / n``, ``(i + 2/3) / n``. Cached: the
    same few sets recur for every batch and round (read-only arrays)."""
    if where == "nodes":
        t = np.arange(n + 1) / n
    elif where == "halves":
        t = np.arange(2 * n + 1) / (2 * n)
    else:
        t = (np.arange(n) + (1 / 3 if where == "first" else 2 / 3)) / n
    B = all_bernstein(p, t) if order == 0 else all_bernstein(p, t, order)[order]
    B = np.ascontiguousarray(B.T)
    B.setflags(write=False)
    return B


@functools.lru_cache(maxsize=128)
def _row_block(p, n):
    """The u tables of a cell grid stacked for one product (cached, read-only):
    ``(rows (R, p + 1), sizes, offsets)`` with the blocks half steps, d/du at the nodes,
    nodes, first and second triangle-centre thirds."""
    rows = [_bern(p, n, "halves"), _bern(p, n, "nodes", 1), _bern(p, n, "nodes"), _bern(p, n, "first"),
            _bern(p, n, "second")]  # fmt: skip
    sizes = tuple(len(r) for r in rows)
    block = np.concatenate(rows)
    block.setflags(write=False)
    return block, sizes, (0, *itertools.accumulate(sizes))


def _cross2(a, b):
    """Cross product along axis 2 of ``(a, c, 3, b)`` arrays."""
    return np.stack(
        [
            a[:, :, 1] * b[:, :, 2] - a[:, :, 2] * b[:, :, 1],
            a[:, :, 2] * b[:, :, 0] - a[:, :, 0] * b[:, :, 2],
            a[:, :, 0] * b[:, :, 1] - a[:, :, 1] * b[:, :, 0],
        ],
        axis=2,
    )


def _sq2(x):
    """Squared Euclidean length along axis 2 of an ``(a, c, 3, b)`` array -> ``(a, c, b)``."""
    out = x[:, :, 0] * x[:, :, 0]
    out += x[:, :, 1] * x[:, :, 1]
    out += x[:, :, 2] * x[:, :, 2]
    return out


def _reduce_max(x, rs, cs):
    """Per-cell maxima of an ``(rows, c, cols)`` array: rows split at ``rs``, columns at ``cs``
    -> ``(c * len(rs) * len(cs),)`` in the order (grid cell, row span, column span)."""
    y = np.maximum.reduceat(x, rs, axis=0) if len(rs) > 1 else x.max(axis=0, keepdims=True)
    y = np.maximum.reduceat(y, cs, axis=2) if len(cs) > 1 else y.max(axis=2, keepdims=True)
    return y.transpose(1, 0, 2).ravel()


class Grid:
    """Evaluated tensor grids and their measured deviations.

    Either ``c`` Bézier cells that share their counts ``n x m`` (evaluated together,
    :meth:`cells`), or one multi-span patch on the concatenation of its spans'
    samples (:meth:`patch`; the patch's own grid evaluators). Arrays use the
    layout ``(rows, grid, coordinate, columns)``; per-cell results (``err_u``,
    ``err_v``, ``err_d``, ``ang_u``, ``ang_v``) follow ``self.cells``.
    """

    @classmethod
    def cells(cls, cellset: CellSet, idx, n, m, tol, angle_tol, weld_tol, collapsed):
        p, q = cellset.p, cellset.q
        rational = bool(cellset.rational[idx].any())
        k = 4 if rational else 3
        nets = cellset.nets[idx] if rational else cellset.points[idx]
        c = len(idx)
        # (p + 1, c, k, q + 1): rows of the first product
        flat = np.ascontiguousarray(nets.transpose(1, 0, 3, 2)).reshape(p + 1, c * k * (q + 1))
        rows, sizes, offsets = _row_block(p, n)
        T = _product(rows, flat)  # (sum rows, c * k * (q + 1))
        T = T.reshape(-1, q + 1)
        starts = [o * c * k for o in offsets]

        def grid(block, Bv):
            a = sizes[block]
            part = T[starts[block] : starts[block + 1]]
            return _product(part, Bv.T).reshape(a, c, k, Bv.shape[0])

        H = grid(0, _bern(q, m, "halves"))  # half-step grid, homogeneous
        Hu = grid(1, _bern(q, m, "nodes"))  # d/du at the vertices
        Hv = grid(2, _bern(q, m, "nodes", 1))  # d/dv at the vertices
        C1 = grid(4, _bern(q, m, "first"))  # centres of triangles (00, 10, 11): (i + 2/3, j + 1/3)
        C2 = grid(3, _bern(q, m, "second"))  # centres of triangles (00, 11, 01): (i + 1/3, j + 2/3)
        self = cls()
        self.kind, self.set, self.local, self.n, self.m = "cells", cellset, np.asarray(idx), n, m
        zero = np.zeros(1, dtype=np.int64)
        self._finish(H, Hu, Hv, C1, C2, rational, tol, angle_tol, weld_tol, bool(collapsed[idx].any()), zero, zero)
        return self

    @classmethod
    def patch(cls, surface, index, bu, bv, counts_u, counts_v, tol, angle_tol, weld_tol, collapsed):
        us, rs = span_params(bu, counts_u)
        vs, cs = span_params(bv, counts_v)

        def halves(t):
            out = np.empty(2 * t.size - 1)
            out[0::2] = t
            out[1::2] = 0.5 * (t[:-1] + t[1:])
            return out

        du, dv = np.diff(us), np.diff(vs)
        u1, u2 = us[:-1] + du / 3.0, us[:-1] + 2.0 * du / 3.0
        v1, v2 = vs[:-1] + dv / 3.0, vs[:-1] + 2.0 * dv / 3.0
        rational = surface.is_rational and bool(np.ptp(surface.weights) > 1e-14 * surface.weights.max())
        coefs = np.asarray(surface.homogeneous_points if rational else surface.control_points)
        nu_c, nv_c, k = coefs.shape
        p, q, U, Vk = surface.degree_u, surface.degree_v, surface.knots_u, surface.knots_v
        # banded (CSR) collocation matrices: two sparse products per grid, p + 1 (q + 1)
        # multiply-adds per output value
        rows = [design_matrix(p, U, halves(us)), design_matrix(p, U, us, 1), design_matrix(p, U, us),
                design_matrix(p, U, u1), design_matrix(p, U, u2)]
        sizes = [r.shape[0] for r in rows]
        T = vstack(rows, format="csr") @ coefs.reshape(nu_c, nv_c * k)  # (R, nv_c * k)
        T = np.ascontiguousarray(T.reshape(-1, nv_c, k).transpose(1, 0, 2)).reshape(nv_c, -1)  # (nv_c, R * k)
        starts = np.concatenate([[0], np.cumsum(sizes)]) * k

        def grid(block, t, order=0):
            Nv = design_matrix(q, Vk, t, order)  # (b, nv_c)
            out = Nv @ T[:, starts[block] : starts[block + 1]]  # (b, a * k)
            # (a, 1, k, b), contiguous along b: the kernel walks the columns innermost
            return np.ascontiguousarray(out.reshape(len(t), sizes[block], 1, k).transpose(1, 2, 3, 0))

        H = grid(0, halves(vs))
        Hu = grid(1, vs)
        Hv = grid(2, vs, 1)
        C1 = grid(4, v1)
        C2 = grid(3, v2)
        self = cls()
        self.kind, self.index, self.us, self.vs, self.rs, self.cs = "patch", index, us, vs, rs, cs
        self.n, self.m = us.size - 1, vs.size - 1
        self._finish(H, Hu, Hv, C1, C2, rational, tol, angle_tol, weld_tol, collapsed, rs, cs)
        return self

    def _finish(self, H, Hu, Hv, C1, C2, rational, tol, angle_tol, weld_tol, check_collapsed, rs, cs):
        """Vertices ``V`` and unit normals ``N`` ``(c, n + 1, m + 1, 3)``, ``weak`` normals
        and the per-cell deviations, by the compiled kernel when available."""
        jit = _kernels.get("splinekit.tessellation._kernels")
        if jit is None:
            S, V, Su, Sv, C1, C2 = _cartesian(H, Hu, Hv, C1, C2, rational)
            self._measure(S, V, Su, Sv, C1, C2, tol, angle_tol, weld_tol, check_collapsed, rs, cs)
            self.V = self.V.transpose(1, 0, 3, 2)
            self.N = self.N.transpose(1, 0, 3, 2)
            self.weak = self.weak.transpose(1, 0, 2)
            return
        c, n, m = H.shape[1], (H.shape[0] - 1) // 2, (H.shape[3] - 1) // 2
        ri, ci = _span_of_index(rs, n), _span_of_index(cs, m)
        V = np.empty((c, n + 1, m + 1, 3))
        N = np.empty((c, n + 1, m + 1, 3))
        weak = np.empty((c, n + 1, m + 1), dtype=np.bool_)
        err = np.zeros((c, rs.size, cs.size, 6))
        err[..., 3:] = 1.0
        jit.measure_grid(H, Hu, Hv, C1, C2, bool(rational), ri, ci, float(tol * tol), float(weld_tol * weld_tol),
                         bool(check_collapsed), angle_tol is not None, V, N, weak, err)
        err = err.reshape(-1, 6)
        self.V, self.N, self.weak = V, N, weak
        self.err_u, self.err_v, self.err_d = np.sqrt(err[:, 0]), np.sqrt(err[:, 1]), np.sqrt(err[:, 2])
        self.ang_u = self.ang_v = None
        if angle_tol is not None:
            ang = np.arccos(np.clip(err[:, 3:], -1.0, 1.0))
            self.ang_u = np.maximum(ang[:, 0], ang[:, 2])
            self.ang_v = np.maximum(ang[:, 1], ang[:, 2])

    def _measure(self, S, V, Su, Sv, C1, C2, tol, angle_tol, weld_tol, check_collapsed, rs, cs):
        """Unit normals at the vertices and per-cell deviations (see the class docstring)."""
        N = _cross2(Su, Sv)
        ln2 = _sq2(N)
        scale = _sq2(Su) + _sq2(Sv)
        self.weak = ln2 <= 1e-20 * scale * scale  # (n + 1, c, m + 1): collapsed points
        N /= np.sqrt(np.where(self.weak, 1.0, ln2))[:, :, None, :]
        # squared deviations at edge midpoints, diagonal midpoints and triangle centres
        V00, V10, V01, V11 = V[:-1, :, :, :-1], V[1:, :, :, :-1], V[:-1, :, :, 1:], V[1:, :, :, 1:]
        du = _sq2(S[1::2, :, :, ::2] - 0.5 * (V[:-1] + V[1:]))  # (n, c, m + 1)
        dv = _sq2(S[::2, :, :, 1::2] - 0.5 * (V[:, :, :, :-1] + V[:, :, :, 1:]))  # (n + 1, c, m)
        diag = V00 + V11
        dd = _sq2(S[1::2, :, :, 1::2] - 0.5 * diag)  # (n, c, m)
        t1 = _sq2(C1 - (diag + V10) / 3.0)
        t2 = _sq2(C2 - (diag + V01) / 3.0)
        if check_collapsed:
            # triangles with two coincident corners are dropped after welding: do not measure them
            w2 = weld_tol * weld_tol
            e_u, e_v, e_d = _sq2(V10 - V00), _sq2(V11 - V10), _sq2(V11 - V00)
            e_u2, e_v2 = _sq2(V11 - V01), _sq2(V01 - V00)
            t1 = np.where((e_u <= w2) | (e_v <= w2) | (e_d <= w2), 0.0, t1)
            t2 = np.where((e_u2 <= w2) | (e_v2 <= w2) | (e_d <= w2), 0.0, t2)
        self.err_u = np.sqrt(_reduce_max(du, rs, cs))
        self.err_v = np.sqrt(_reduce_max(dv, rs, cs))
        self.err_d = np.sqrt(_reduce_max(np.maximum(dd, np.maximum(t1, t2)), rs, cs))
        self.ang_u = self.ang_v = None
        if angle_tol is not None:
            # angle between exact normals at the two ends of each grid edge. Excluded: collapsed
            # points, edges shorter than the tolerance, and normals more than 90 degrees apart
            # (a fold or cusp of the surface, which no refinement resolves)
            weak = self.weak
            ang = []
            for A, B, W in (
                (N[:-1], N[1:], weak[:-1] | weak[1:]),
                (N[:, :, :, :-1], N[:, :, :, 1:], weak[:, :, :-1] | weak[:, :, 1:]),
                (N[:-1, :, :, :-1], N[1:, :, :, 1:], weak[:-1, :, :-1] | weak[1:, :, 1:]),
            ):
                cos = np.einsum("ackb,ackb->acb", A, B)
                cos[W | (cos < 0)] = 1.0
                ang.append(cos)
            ang[0][_sq2(V[1:] - V[:-1]) <= tol * tol] = 1.0
            ang[1][_sq2(V[:, :, :, 1:] - V[:, :, :, :-1]) <= tol * tol] = 1.0
            ang[2][_sq2(V11 - V00) <= tol * tol] = 1.0
            worst = [np.arccos(np.clip(-_reduce_max(-a, rs, cs), -1.0, 1.0)) for a in ang]
            self.ang_u = np.maximum(worst[0], worst[2])
            self.ang_v = np.maximum(worst[1], worst[2])
        self.V, self.N = V, N


def _span_of_index(starts, n):
    """``(n + 1,)`` span of each grid row (column) ``0 .. n``, spans starting at ``starts``."""
    if starts.size == 1:
        return np.zeros(n + 1, dtype=np.int64)
    return (np.searchsorted(starts, np.arange(n + 1), side="right") - 1).astype(np.int64)


def _cartesian(H, Hu, Hv, C1, C2, rational):
    """Points, vertices and (multiples of) the first partials from homogeneous grids."""
    if not rational:
        return H, H[::2, :, :, ::2], Hu, Hv, C1, C2
    S = H[:, :, :3] / H[:, :, 3:]
    V = S[::2, :, :, ::2]
    # (Hu - wu S) = w Su: the cross product is a positive multiple (w^2) of Su x Sv
    Su = Hu[:, :, :3] - Hu[:, :, 3:] * V
    Sv = Hv[:, :, :3] - Hv[:, :, 3:] * V
    return S, V, Su, Sv, C1[:, :, :3] / C1[:, :, 3:], C2[:, :, :3] / C2[:, :, 3:]


def span_params(breaks, counts):
    """``(params, starts)``: ``counts[i]`` equal steps over ``[breaks[i], breaks[i + 1]]``
    (shared ends once), and the index of each span's first step."""
    counts = np.asarray(counts, dtype=np.int64)
    span = np.repeat(np.arange(counts.size), counts)
    k = np.arange(span.size) - np.repeat(np.cumsum(counts) - counts, counts)
    a, b = breaks[:-1], breaks[1:]
    t = a[span] + (b - a)[span] * (k / counts[span])
    return np.concatenate([t, breaks[-1:]]), np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)

