"""Adaptive, watertight tessellation of patch sets.

Design (whole-array work; Python loops run over degree pairs, sample-count
classes, multi-span patches and refinement rounds, never over points or
triangles):

1. Every patch is cut into Bézier cells (:mod:`.cells`). A cell is sampled on a
   uniform ``n x m`` grid of its local parameters; the a-priori counts come from
   bounds on the second derivatives (linear interpolation over a step ``h``
   errs by at most ``h^2 / 8 max |S''|``) and from the angle tolerance.
2. Shared edges must carry the same samples on both sides. Each cell has a
   "u node" (the samples along its two u-running edges) and a "v node". Cell
   edges that coincide (same points at t = 0, 1/4, 1/2, 3/4, 1, in either
   orientation), and neighbouring cells of one patch, link their nodes; every
   connected set of nodes takes the largest count of its members. Uniform
   samples of a whole edge are symmetric under reversal, so orientation does
   not matter.
3. Evaluation: single-cell patches (Bézier patch sets) in batches of equal
   degrees and counts as ``Bu @ net @ Bv^T`` (two products for the whole
   batch); a multi-span patch as one tensor grid on the concatenation of its
   spans' samples (banded collocation matrices). Each grid is evaluated at the
   vertices (with first partials, for the normals), at the half-step points
   (edge midpoints, quad centres) and at the triangle centres, and one fused
   pass (compiled with numba when available, else numpy) measures the
   deviations and normal angles per cell.
4. A pilot round at no more than ``PILOT`` steps per cell predicts the counts
   (the error is quadratic in the step); cells still over the tolerance are
   refined by ``sqrt(deviation / tolerance)``, the counts re-propagated and
   only the changed cells (patches) evaluated again.
5. Grids are triangulated by index arithmetic. Only vertices on a grid's
   boundary can merge: collapsed cell edges (poles) become one vertex, the
   rest are welded where they lie within the weld distance (a sweep along one
   direction, :func:`_close_pairs`), and only triangles touching a grid
   boundary are remapped, and dropped when they collapse.
6. A closed body facing inward is turned outward; the common cases (an open
   mesh: nothing welded; an outward body: clearly positive volume) are told
   apart cheaply, without building the mesh's edge table.

Small models spend most of their time in fixed per-call work rather than in
evaluation, so the bookkeeping avoids sorts, sparse matrices and per-patch
Python work where a cached table or one whole-array operation does; with numba,
the weld, the triangle remap, the vertex gathering, the pole normals and the
rational a-priori bounds run as compiled kernels (:mod:`._kernels`) that give the
numpy path's results bit for bit.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

from ..basis.bernstein import all_bernstein
from .. import limits
from .cells import CellSet, cells_of_patches, edge_samples, second_derivative_bounds
from .result import Tessellation

__all__ = ["tessellate_patches"]

MAX_COUNT = 4096
"""Largest number of segments per cell and direction."""
MAX_ROUNDS = 8
"""Largest number of measure-and-refine rounds."""
ANGLE_MAX_COUNT = 64
"""The angle criterion refines a cell direction only while it has fewer steps than this."""
BYTES_PER_TRIANGLE = 420
"""Peak memory per triangle of a tessellation (the sample grids of every round, the
welding tables and the result), measured on the teapot at 1.6 and 5.5 million
triangles (405-410 bytes); what :func:`splinekit.limits.check` is given."""
PILOT = 8
"""Largest per-direction count of the first (pilot) evaluation of a cell."""
PILOT_TARGET = 0.8
"""Counts predicted from the pilot aim at this fraction of the tolerance."""
WELD = 1e-8
"""Weld and edge-matching distance, relative to the model's bounding-box diagonal."""


def _kernels():
    """The compiled kernel module, or None (numba missing, or SPLINEKIT_NUMBA=0)."""
    from ..basis import jit

    if not jit._enabled():
        return None
    return jit._load("splinekit.tessellation._kernels")


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


class _Grid:
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
        from ..basis import design_matrix

        us, rs = _span_params(bu, counts_u)
        vs, cs = _span_params(bv, counts_v)

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
        from scipy.sparse import vstack

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
        jit = _kernels()
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


def _span_params(breaks, counts):
    """``(params, starts)``: ``counts[i]`` equal steps over ``[breaks[i], breaks[i + 1]]``
    (shared ends once), and the index of each span's first step."""
    counts = np.asarray(counts, dtype=np.int64)
    span = np.repeat(np.arange(counts.size), counts)
    k = np.arange(span.size) - np.repeat(np.cumsum(counts) - counts, counts)
    a, b = breaks[:-1], breaks[1:]
    t = a[span] + (b - a)[span] * (k / counts[span])
    return np.concatenate([t, breaks[-1:]]), np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)


def _node_groups(cellsets, patch_of, span_of, nsv, weld_tol):
    """Connected sets of cell nodes that must share samples, and per-cell collapsed-edge flags.

    Node ``2 g`` is global cell ``g``'s u samples, ``2 g + 1`` its v samples.
    Returns ``(labels (2 C,), collapsed (C, 4) bool)``.
    """
    pts, ext = [], []
    for cs in cellsets:
        p, e = edge_samples(cs)
        pts.append(p)
        ext.append(e)
    pts = np.concatenate(pts)  # (C, 4, 5, 3)
    ext = np.concatenate(ext)  # (C, 4)
    C = len(pts)
    collapsed = ext <= weld_tol
    flat = pts.reshape(C * 4, 5, 3)
    live = np.flatnonzero(~collapsed.ravel())
    node = 2 * (np.arange(C * 4) // 4) + (np.arange(C * 4) % 4 >= 2)
    links = [np.zeros((0, 2), dtype=np.int64)]
    if live.size > 1:
        pairs = _close_pairs(flat[live, 2], weld_tol)
        if len(pairs):
            a, b = live[pairs[:, 0]], live[pairs[:, 1]]
            A, B = flat[a], flat[b]
            same = (np.linalg.norm(A - B, axis=-1) <= weld_tol).all(axis=1)
            flip = (np.linalg.norm(A - B[:, ::-1], axis=-1) <= weld_tol).all(axis=1)
            ok = same | flip
            links.append(np.column_stack([node[a[ok]], node[b[ok]]]))
    # neighbours along a knot line of one patch share nodes (also when the line collapses)
    g = np.arange(C)
    step = nsv[patch_of]
    right = np.flatnonzero(span_of[:, 1] + 1 < step)  # cell (iu, iv + 1) is g + 1
    below = g + step
    down = np.flatnonzero(below < C)
    down = down[patch_of[below[down]] == patch_of[down]]  # cell (iu + 1, iv) is g + nsv
    links.append(np.column_stack([2 * right, 2 * (right + 1)]))
    links.append(np.column_stack([2 * down + 1, 2 * below[down] + 1]))
    links = np.concatenate(links)
    return _components(2 * C, links[:, 0], links[:, 1]), collapsed


_SWEEP = np.array([0.5773502691896258, 0.6289340932953637, -0.5206089939262417])
"""Unit direction of the sweep in :func:`_close_pairs`: generic, so that the planes
of axis-aligned geometry do not project many points onto one value."""


def _close_pairs(X, r):
    """``(k, 2)`` index pairs ``i != j`` of the points ``X`` ``(n, 3)`` at most ``r`` apart
    (each pair once). A sweep along one direction: points are sorted by their
    projection, each is paired with those whose projection lies within ``r`` above
    its own, and the candidates are kept when they are truly within ``r``. Points to
    weld are few and isolated, so the candidates are few; should they not be (many
    points on a plane across the sweep), a k-d tree answers instead."""
    n = len(X)
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64)
    jit = _kernels()
    if jit is not None:
        pairs, ok = jit.close_pairs(np.ascontiguousarray(X, dtype=np.float64), float(r), _SWEEP, 16 * n + 1000)
        if ok:
            return pairs
        from scipy.spatial import cKDTree

        return cKDTree(X).query_pairs(r=r, output_type="ndarray")
    proj = X @ _SWEEP
    order = np.argsort(proj, kind="stable")
    ps = proj[order]
    # the margin covers rounding of the projections; the exact test follows
    end = np.searchsorted(ps, ps + r * (1.0 + 1e-6) + 4.0 * np.finfo(float).eps * np.abs(ps), side="right")
    count = end - np.arange(1, n + 1)
    total = int(count.sum())
    if total > 16 * n + 1000:
        from scipy.spatial import cKDTree

        return cKDTree(X).query_pairs(r=r, output_type="ndarray")
    i = np.repeat(np.arange(n), count)
    j = i + 1 + (np.arange(total) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[i], order[j]
    d = X[a] - X[b]
    ok = np.einsum("ij,ij->i", d, d) <= r * r
    return np.column_stack([a[ok], b[ok]])


def _components(n, a, b):
    """``(n,)`` label of each of ``n`` nodes linked by the edges ``a[k] - b[k]``: the smallest
    node of its connected component. Roots hook onto the smallest root they are linked
    to, then every node jumps to its root; a few rounds of whole-array operations, far
    cheaper than building a sparse graph for the small graphs of a tessellation (or
    a compiled union-find with the same labels)."""
    jit = _kernels()
    if jit is not None:
        return jit.components(int(n), np.ascontiguousarray(a, dtype=np.int64), np.ascontiguousarray(b, dtype=np.int64))
    lab = np.arange(n)
    while a.size:
        la, lb = lab[a], lab[b]
        lo = np.minimum(la, lb)
        new = lab.copy()
        np.minimum.at(new, la, lo)
        np.minimum.at(new, lb, lo)
        while True:  # pointer jumping: labels only decrease, so this ends at the roots
            jumped = new[new]
            if np.array_equal(jumped, new):
                break
            new = jumped
        if np.array_equal(new, lab):
            break
        lab = new
    return lab


def _initial_counts(cellsets, tol, angle_tol, bounds=None):
    """A-priori sample counts ``(nu, nv)`` per global cell (``bounds``: the cell sets'
    :func:`.cells.second_derivative_bounds` when already computed; they do not depend on ``tol``)."""
    nu, nv = [], []
    for i, cs in enumerate(cellsets):
        Muu, Muv, Mvv, Lu, Lv = second_derivative_bounds(cs) if bounds is None else bounds[i]
        # h_u^2 (Muu + Muv) / 8 + h_v^2 (Mvv + Muv) / 8 >= the bound (h_u^2 Muu + 2 h_u h_v Muv + h_v^2 Mvv) / 8
        a = np.sqrt((Muu + Muv) / (4.0 * tol))
        b = np.sqrt((Mvv + Muv) / (4.0 * tol))
        if angle_tol is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                a = np.maximum(a, np.where(Lu > 0, Muu / (Lu * angle_tol), 0.0))
                b = np.maximum(b, np.where(Lv > 0, Mvv / (Lv * angle_tol), 0.0))
        nu.append(np.clip(np.ceil(np.nan_to_num(a, nan=MAX_COUNT, posinf=MAX_COUNT)), 1, MAX_COUNT))
        nv.append(np.clip(np.ceil(np.nan_to_num(b, nan=MAX_COUNT, posinf=MAX_COUNT)), 1, MAX_COUNT))
    return np.concatenate(nu).astype(np.int64), np.concatenate(nv).astype(np.int64)


def _propagate(nu, nv, labels):
    """Counts raised to the largest of each linked set of nodes."""
    counts = np.empty(2 * nu.size, dtype=np.int64)
    counts[0::2], counts[1::2] = nu, nv
    top = np.zeros(labels.max() + 1, dtype=np.int64)
    np.maximum.at(top, labels, counts)
    counts = top[labels]
    return counts[0::2].copy(), counts[1::2].copy()


def _grid_triangles(n, m):
    """``(2 n m, 3)`` local vertex indices of an ``(n + 1) x (m + 1)`` grid, counter-clockwise
    in (u, v): triangles ``(00, 10, 11)`` and ``(00, 11, 01)`` per quad."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    v00 = (i * (m + 1) + j).ravel()
    v10, v01 = v00 + (m + 1), v00 + 1
    v11 = v10 + 1
    return np.stack([np.column_stack([v00, v10, v11]), np.column_stack([v00, v11, v01])], axis=1).reshape(-1, 3)


def _edge_locals(n, m):
    """Local vertex indices along the four cell edges (v = 0, v = 1, u = 0, u = 1)."""
    i, j = np.arange(n + 1), np.arange(m + 1)
    return [i * (m + 1), i * (m + 1) + m, j, n * (m + 1) + j]


def tessellate_patches(patches, tol: float, angle_tol, weld_scale: float) -> Tessellation:
    """Tessellate validated 3-D spline patches (see :func:`splinekit.tessellation.tessellate`).

    ``tol`` is the absolute chordal tolerance, ``angle_tol`` radians or None,
    ``weld_scale`` the model size (bounding-box diagonal) used for welding.
    """
    weld_tol = WELD * weld_scale
    cellsets = cells_of_patches(patches)
    sizes = [len(cs) for cs in cellsets]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    C = int(offsets[-1])
    set_of = np.repeat(np.arange(len(cellsets)), sizes)
    patch_of = np.concatenate([cs.patch for cs in cellsets])
    span_of = np.concatenate([cs.span for cs in cellsets])
    box_of = np.concatenate([cs.box for cs in cellsets])
    # cells of one patch are contiguous, in (iu, iv) order with iu major
    n_cells = np.bincount(patch_of, minlength=len(patches))
    first = np.full(len(patches), C, dtype=np.int64)
    np.minimum.at(first, patch_of, np.arange(C))
    nsv = np.zeros(len(patches), dtype=np.int64)
    np.maximum.at(nsv, patch_of, span_of[:, 1] + 1)
    labels, collapsed = _node_groups(cellsets, patch_of, span_of, nsv, weld_tol)
    any_collapsed = collapsed.any(axis=1)
    multi = n_cells[patch_of] > 1
    nu, nv = _initial_counts(cellsets, tol, angle_tol)
    done_u = np.zeros(C, dtype=np.int64)  # counts each cell was last evaluated with
    done_v = np.zeros(C, dtype=np.int64)
    record = np.full(C, -1, dtype=np.int64)  # which grid holds each cell's latest evaluation
    grids: list[_Grid] = []
    # The a-priori counts are upper estimates (a bound over the whole cell); a pilot
    # evaluation at no more than PILOT steps measures the actual error, from which the
    # counts are predicted (error ~ h^2), up or down. Later rounds only refine.
    apriori_u, apriori_v = _propagate(nu, nv, labels)
    nu, nv = np.minimum(apriori_u, PILOT), np.minimum(apriori_v, PILOT)
    for round_ in range(MAX_ROUNDS):
        nu, nv = _propagate(nu, nv, labels)
        todo = np.flatnonzero((nu != done_u) | (nv != done_v))
        if todo.size == 0:
            break
        # every cell's current counts: the mesh this round would hold, checked before its grids exist
        total = 2 * float((nu.astype(np.float64) * nv).sum())
        limits.check(total * BYTES_PER_TRIANGLE, f"tessellation at tolerance {tol:.3g} ({total:,.0f} triangles)")
        new = []
        # single-cell patches: group by (cell set, nu, nv), evaluate each group at once
        single = todo[~multi[todo]]
        if single.size:
            # one int64 key per cell, ordered like the rows (set, nu, nv): counts are <= MAX_COUNT
            base = MAX_COUNT + 1
            key = (set_of[single] * base + nu[single]) * base + nv[single]
            uniq, inverse = np.unique(key, return_inverse=True)
            order = np.argsort(inverse, kind="stable")
            bounds = np.searchsorted(inverse[order], np.arange(len(uniq) + 1))
            for g, (s, n, m) in enumerate(zip(uniq // base**2, uniq // base % base, uniq % base)):
                members = single[order[bounds[g] : bounds[g + 1]]]
                flags = any_collapsed[offsets[s] : offsets[s + 1]]
                grid = _Grid.cells(cellsets[s], members - offsets[s], int(n), int(m), tol, angle_tol, weld_tol, flags)
                grid.cells = members
                new.append(grid)
        # multi-span patches: one tensor grid each, on the concatenated span samples
        for P in np.unique(patch_of[todo[multi[todo]]]):
            cells = np.arange(first[P], first[P] + n_cells[P])
            shape = (n_cells[P] // nsv[P], nsv[P])
            counts_u = nu[cells].reshape(shape).max(axis=1)
            counts_v = nv[cells].reshape(shape).max(axis=0)
            box = box_of[cells]
            bu = np.append(box[:: shape[1], 0], box[-1, 1])
            bv = np.append(box[: shape[1], 2], box[-1, 3])
            grid = _Grid.patch(
                patches[P], int(P), bu, bv, counts_u, counts_v, tol, angle_tol, weld_tol, bool(any_collapsed[cells].any())
            )
            grid.cells = cells
            grid.counts = (counts_u, counts_v)
            new.append(grid)
        for grid in new:
            record[grid.cells] = len(grids)
            grids.append(grid)
        done_u[todo], done_v[todo] = nu[todo], nv[todo]
        # measure: which cells still exceed the tolerances
        fu, fv = np.ones(C), np.ones(C)
        for b in new:
            cells = b.cells
            # a diagonal or centre error is charged to each direction in proportion to its
            # edge error (all of it to the dominant one; to both when neither edge errs)
            top = np.maximum(b.err_u, b.err_v)
            safe = np.where(top > 0, top, 1.0)
            share_u = np.where(top > 0, b.err_u / safe, 1.0)
            share_v = np.where(top > 0, b.err_v / safe, 1.0)
            gu = np.sqrt(np.maximum(b.err_u, b.err_d * share_u) / tol)
            gv = np.sqrt(np.maximum(b.err_v, b.err_d * share_v) / tol)
            if angle_tol is not None:
                # the angle criterion shapes coarse grids only; it never drives a cell past
                # ANGLE_MAX_COUNT steps (the chordal tolerance alone governs finer grids)
                gu = np.maximum(gu, np.where(nu[cells] < ANGLE_MAX_COUNT, b.ang_u / angle_tol, 0.0))
                gv = np.maximum(gv, np.where(nv[cells] < ANGLE_MAX_COUNT, b.ang_v / angle_tol, 0.0))
            fu[cells], fv[cells] = gu, gv
        over_u, over_v = fu > 1.0, fv > 1.0
        if round_ == 0:
            # predicted counts where the pilot was coarser than the a-priori estimate
            # clipped as floats: an error far above a tiny tolerance gives inf, which no int holds
            pu = np.clip(np.ceil(nu * fu / math.sqrt(PILOT_TARGET)), 1, MAX_COUNT).astype(np.int64)
            pv = np.clip(np.ceil(nv * fv / math.sqrt(PILOT_TARGET)), 1, MAX_COUNT).astype(np.int64)
            nu = np.where(nu < apriori_u, pu, nu)
            nv = np.where(nv < apriori_v, pv, nv)
            over_u &= nu == done_u
            over_v &= nv == done_v
        elif not (over_u.any() or over_v.any()):
            break
        # the error falls like h^2: scale the count by sqrt(error / tol), with a margin
        grow_u = np.minimum(np.ceil(nu * np.minimum(fu * 1.15, 8.0)), MAX_COUNT).astype(np.int64)
        grow_v = np.minimum(np.ceil(nv * np.minimum(fv * 1.15, 8.0)), MAX_COUNT).astype(np.int64)
        nu = np.where(over_u, np.maximum(grow_u, np.minimum(nu + 1, MAX_COUNT)), nu)
        nv = np.where(over_v, np.maximum(grow_v, np.minimum(nv + 1, MAX_COUNT)), nv)
    cell_index = _CellIndex(cellsets, offsets, first, n_cells, nsv, box_of)
    mesh, welded, V, T = _assemble(grids, record, collapsed, span_of, cell_index, tol, weld_tol)
    return _outward(mesh, welded, V, T)


@functools.lru_cache(maxsize=256)
def _ring_split(n, m):
    """Index tables of an ``(n + 1) x (m + 1)`` grid (cached, read-only): interior and
    ring (border) local vertices ``Li``, ``Lr``; each vertex's ``slot`` among its kind;
    the ``on_ring`` mask; the local triangles off the ring and touching it."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(m + 1), indexing="ij")
    on_ring = ((i == 0) | (i == n) | (j == 0) | (j == m)).ravel()
    Li, Lr = np.flatnonzero(~on_ring), np.flatnonzero(on_ring)
    slot = np.empty(on_ring.size, dtype=np.int64)
    slot[Li] = np.arange(Li.size)
    slot[Lr] = np.arange(Lr.size)
    tmpl = _grid_triangles(n, m)
    touch = on_ring[tmpl].any(axis=1)
    out = (Li, Lr, slot, on_ring, tmpl[~touch], tmpl[touch])
    for a in out:
        a.setflags(write=False)
    return out


@functools.lru_cache(maxsize=512)
def _template_slots(n, m, touching):
    """``(is_ring, slot)`` ``(t, 3)`` of the local triangles of an ``(n + 1) x (m + 1)`` grid
    off the ring (``touching=False``) or touching it (cached, read-only)."""
    _, _, slot, on_ring, tmpl_in, tmpl_edge = _ring_split(n, m)
    tmpl = tmpl_edge if touching else tmpl_in
    out = (on_ring[tmpl], slot[tmpl])
    for a in out:
        a.setflags(write=False)
    return out


class _Piece:
    """One evaluated grid's share of the mesh, split into interior and ring (grid
    boundary) vertices: only ring vertices can be welded, so interior vertices are
    numbered first and never renumbered, and only triangles touching the ring are
    remapped, filtered and deduplicated."""

    def __init__(self, b, keep, collapsed, span_of):
        n, m = b.n, b.m
        per = (n + 1) * (m + 1)
        if b.kind == "cells":
            sel = keep
            cs = b.set
            local = b.local[keep]
            box = cs.box[local]
            U = box[:, 0, None] + (box[:, 1] - box[:, 0])[:, None] * (np.arange(n + 1) / n)  # (c, n + 1)
            W = box[:, 2, None] + (box[:, 3] - box[:, 2])[:, None] * (np.arange(m + 1) / m)  # (c, m + 1)
            self.pid = cs.patch[local]
        else:
            sel = np.array([0])
            U, W = b.us[None], b.vs[None]
            self.pid = np.array([b.index])
        c = sel.size
        if c == b.V.shape[0]:
            sel = slice(None)  # every cell of the grid is current: no copy
        self.Li, self.Lr, self.slot, self.on_ring, self.tmpl_in, self.tmpl_edge = _ring_split(n, m)
        self.n, self.m, self.c, self.per = n, m, c, per
        self.V = b.V[sel].reshape(c, per, 3)
        self.N = b.N[sel].reshape(c, per, 3)
        self.weak = b.weak[sel].reshape(c, per)
        self.U, self.W = U, W
        # collapsed cell edges: (ring vertex, ring vertex it becomes), in this piece's ring slots
        pins = []
        slot, on_ring = self.slot, self.on_ring
        col = collapsed[b.cells[keep]]
        if col.any():
            if b.kind == "cells":
                for e, loc in enumerate(_edge_locals(n, m)):
                    # every collapsed edge e of a cell k: its ring vertices -> the edge's first one
                    r = (np.flatnonzero(col[:, e])[:, None] * self.Lr.size + slot[loc]).ravel()
                    pins.append(np.column_stack([r, np.repeat(r[:: loc.size], loc.size)]))
            else:
                cu, cv = b.counts
                r0s, c0s = np.concatenate([[0], np.cumsum(cu)]), np.concatenate([[0], np.cumsum(cv)])
                for k, e in zip(*np.nonzero(col)):
                    iu, iv = span_of[b.cells[k]]
                    rows, cols = np.arange(r0s[iu], r0s[iu + 1] + 1), np.arange(c0s[iv], c0s[iv + 1] + 1)
                    loc = rows * (m + 1) + cols[0 if e == 0 else -1] if e < 2 else rows[0 if e == 2 else -1] * (m + 1) + cols
                    if on_ring[loc].all():  # (an interior knot line that collapses is left as is)
                        r = slot[loc]
                        pins.append(np.column_stack([r, np.full(r.size, r[0])]))
        self.pins = np.concatenate(pins) if pins else np.zeros((0, 2), dtype=np.int64)

    def uv(self, L):
        """``(c, len(L), 2)`` parameters of the local vertices ``L``."""
        i, j = L // (self.m + 1), L % (self.m + 1)
        return np.stack([self.U[:, i], self.W[:, j]], axis=-1)

    def triangles(self, touching, int_base, ring_base, out=None):
        """Global triangles ``(c * t, 3)`` of the local triangles touching the ring
        (``touching=True``, ``tmpl_edge``) or not (``tmpl_in``)."""
        ni, nr = self.Li.size, self.Lr.size
        is_ring, slot = _template_slots(self.n, self.m, touching)
        cell = np.arange(self.c)[:, None, None]
        base = np.where(is_ring[None], ring_base + cell * nr, int_base + cell * ni)
        if out is None:
            return (base + slot[None]).reshape(-1, 3)
        np.add(base, slot[None], out=out.reshape(self.c, len(slot), 3))
        return out


def _outward(mesh, welded, vertices, triangles):
    """A closed body whose patches all face inward (``Su x Sv`` pointing into
    the solid, e.g. a profile revolved the other way round) turned outward:
    triangle winding, corner parameters and normals flipped, so its volume is
    positive, as OCC's solids and manifold3d expect. An unwelded mesh is open,
    and an outward closed one is recognised by a cheap volume sum: both skip the
    edge table that ``is_closed`` builds. ``vertices`` ``(n, 3)`` and ``triangles``
    ``(F, 3)`` are the mesh's arrays."""
    if len(triangles) == 0 or not welded or _clearly_positive_volume(vertices, triangles):
        return mesh
    if not mesh.is_closed or mesh.volume >= 0:
        return mesh
    return type(mesh)._build(
        mesh.vertices, np.asarray(mesh.faces)[:, ::-1], -mesh.normals, mesh.uv, mesh.vertex_patch,
        mesh.face_patch, np.asarray(mesh.corner_uv)[:, ::-1], mesh.max_deviation, mesh.tolerance,
    )  # fmt: skip


def _clearly_positive_volume(vertices, triangles) -> bool:
    """True when the signed volume about the bounding-box centre is positive by a margin
    far above rounding (then ``mesh.volume``, the same sum, is positive if the mesh is
    closed, and an open mesh is left as it is anyway)."""
    jit = _kernels()
    if jit is not None:
        return bool(jit.clearly_positive_volume(np.ascontiguousarray(vertices, dtype=np.float64),
                                                np.ascontiguousarray(triangles, dtype=np.int64)))  # fmt: skip
    X = np.array(vertices.T, order="C")  # (3, n) copy: rows are fast to reduce and gather
    X -= 0.5 * (X.min(axis=1) + X.max(axis=1))[:, None]
    F = triangles
    a, b, c = (X.take(F[:, k], axis=1) for k in range(3))  # (3, F) each
    det = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    return bool(det.sum() > 1e-9 * np.abs(det).sum())


def _gather(pieces):
    """``(V, N, WK, UV, VP)`` vertex data of the pieces: interior vertices of every
    piece, then ring vertices."""
    V = np.concatenate([p.V[:, p.Li].reshape(-1, 3) for p in pieces] + [p.V[:, p.Lr].reshape(-1, 3) for p in pieces])
    N = np.concatenate([p.N[:, p.Li].reshape(-1, 3) for p in pieces] + [p.N[:, p.Lr].reshape(-1, 3) for p in pieces])
    WK = np.concatenate([p.weak[:, p.Li].ravel() for p in pieces] + [p.weak[:, p.Lr].ravel() for p in pieces])
    UV = np.concatenate([p.uv(p.Li).reshape(-1, 2) for p in pieces] + [p.uv(p.Lr).reshape(-1, 2) for p in pieces])
    VP = np.concatenate([np.repeat(p.pid, p.Li.size) for p in pieces] + [np.repeat(p.pid, p.Lr.size) for p in pieces])
    return V, N, WK, UV, VP


def _weld_triangles(E0, FE, rep, NI, NR, T, FP, n_in):
    """The triangles ``E0`` (patches ``FE``) touching a grid ring remapped after welding
    (ring vertex ``NI + r`` becomes ``NI + rep[r]``), without those that collapse or
    repeat, the ring vertices still in use renumbered after the interior ones, written
    into ``T``, ``FP`` from row ``n_in`` on. Returns ``(T, FP, E0, kept)``: the arrays
    cut to size, the survivors' pre-weld corners and the kept ring vertices."""
    full = np.concatenate([np.arange(NI), NI + rep])
    E = full[E0]
    good = (E[:, 0] != E[:, 1]) & (E[:, 1] != E[:, 2]) & (E[:, 0] != E[:, 2])
    E, FE, E0 = E[good], FE[good], E0[good]
    # drop exact duplicates (same corners in the same cyclic order) made by welding
    if len(E):
        nv = NI + NR
        if nv < 2_000_000:  # one int64 key per triangle: a 1-D sort instead of a row sort
            # the rotation that starts at the smallest corner has the smallest key
            a, b, c = E[:, 0], E[:, 1], E[:, 2]
            key = np.minimum(np.minimum((a * nv + b) * nv + c, (b * nv + c) * nv + a), (c * nv + a) * nv + b)
            _, first_idx = np.unique(key, return_index=True)
        else:
            rot = np.argmin(E, axis=1)
            canon = np.take_along_axis(E, (rot[:, None] + np.arange(3)) % 3, axis=1)
            _, first_idx = np.unique(canon, axis=0, return_index=True)
        if first_idx.size != len(E):
            first_idx.sort()
            E, FE, E0 = E[first_idx], FE[first_idx], E0[first_idx]
    # keep the ring vertices still in use, renumbered after the interior ones
    used = np.zeros(NR, dtype=bool)
    ring_refs = E[E >= NI] - NI
    used[ring_refs] = True
    kept = np.flatnonzero(used)
    new_ring = np.full(NR, -1, dtype=np.int64)
    new_ring[kept] = NI + np.arange(kept.size)
    E = np.where(E >= NI, new_ring[np.maximum(E - NI, 0)], E)
    T[n_in : n_in + len(E)], FP[n_in : n_in + len(E)] = E, FE
    T, FP = T[: n_in + len(E)], FP[: n_in + len(E)]
    return T, FP, E0, kept


def _assemble(grids, record, collapsed, span_of, cell_index, tol, weld_tol):
    """Concatenate the latest evaluation of every cell, weld and triangulate.

    Returns ``(mesh, welded, vertices, triangles)``: ``welded`` is False when no two grid
    vertices were merged (then every grid's border edges keep their single triangle: the
    mesh is open); the arrays are the mesh's, as built.
    """
    pieces = []
    max_dev = 0.0
    for r, b in enumerate(grids):
        keep = np.flatnonzero(record[b.cells] == r)
        if keep.size == 0:
            continue
        pieces.append(_Piece(b, keep, collapsed, span_of))
        max_dev = max(max_dev, float(np.max(b.err_u[keep])), float(np.max(b.err_v[keep])), float(np.max(b.err_d[keep])))
    n_int = [p.c * p.Li.size for p in pieces]
    n_ring = [p.c * p.Lr.size for p in pieces]
    int_base = np.concatenate([[0], np.cumsum(n_int)]).astype(np.int64)
    NI = int(int_base[-1])
    ring_base = NI + np.concatenate([[0], np.cumsum(n_ring)]).astype(np.int64)
    NR = int(ring_base[-1]) - NI
    # vertex data: interior vertices of every piece, then ring vertices
    jit = _kernels()
    if jit is not None:
        V, N, UV = np.empty((NI + NR, 3)), np.empty((NI + NR, 3)), np.empty((NI + NR, 2))
        WK, VP = np.empty(NI + NR, dtype=np.bool_), np.empty(NI + NR, dtype=np.int64)
        for k, p in enumerate(pieces):
            jit.gather_piece(p.V, p.N, p.weak, p.U, p.W, p.pid, p.Li, p.Lr, p.m, int_base[k], ring_base[k],
                             V, N, WK, UV, VP)  # fmt: skip
    else:
        V, N, WK, UV, VP = _gather(pieces)
    # triangles: those touching the ring go last (only they can change); the interior
    # ones are written once, straight into the final array
    n_in = sum(p.c * len(p.tmpl_in) for p in pieces)
    n_edge = sum(p.c * len(p.tmpl_edge) for p in pieces)
    T = np.empty((n_in + n_edge, 3), dtype=np.int64)
    FP = np.empty(n_in + n_edge, dtype=np.int64)
    at = 0
    for k, p in enumerate(pieces):
        size = p.c * len(p.tmpl_in)
        p.triangles(False, int_base[k], ring_base[k], out=T[at : at + size])
        FP[at : at + size] = np.repeat(p.pid, len(p.tmpl_in))
        at += size
    T_edge = [p.triangles(True, int_base[k], ring_base[k]) for k, p in enumerate(pieces)]
    F_edge = [np.repeat(p.pid, len(p.tmpl_edge)) for p in pieces]
    E0 = np.concatenate(T_edge)  # before welding
    FE = np.concatenate(F_edge)
    # weld ring vertices: collapsed edges first, then coincident points (close pairs)
    rep = np.arange(NR)
    pins = [p.pins + (ring_base[k] - NI) for k, p in enumerate(pieces) if len(p.pins)]
    if pins:
        pins = np.concatenate(pins)
        rep[pins[:, 0]] = pins[:, 1]
    present = np.zeros(NR, dtype=bool)
    present[rep] = True
    cand = np.flatnonzero(present)  # np.unique(rep), without the sort
    pairs = _close_pairs(V[NI + cand], weld_tol)
    if len(pairs):
        # every candidate becomes the first (smallest) candidate of its welded group
        lab = _components(cand.size, pairs[:, 0], pairs[:, 1])
        remap = np.arange(NR)
        remap[cand] = cand[lab]
        rep = remap[rep]
    if jit is not None and NI + NR < 2_000_000:
        count, E0, kept = jit.weld_triangles(E0, FE, rep, NI, NR, T[n_in:], FP[n_in:])
        T, FP = T[: n_in + count], FP[: n_in + count]
    else:
        T, FP, E0, kept = _weld_triangles(E0, FE, rep, NI, NR, T, FP, n_in)
    UV_pre = UV
    if kept.size != NR:
        # move the kept ring vertices down over the dropped ones (interior ones stay put)
        nv = NI + kept.size
        UV = UV.copy()  # the pre-weld parameters stay available for corner_uv
        for X in (V, N, UV, VP, WK):
            X[NI:nv] = X[NI + kept]
        V, N, UV, VP, WK = V[:nv], N[:nv], UV[:nv], VP[:nv], WK[:nv]
    if WK.any():
        _fix_weak_normals(N, WK, UV, VP, cell_index)
    mesh = Tessellation._build(V, T, N, UV, VP, FP, (UV_pre, n_in, E0), max_dev, tol)
    return mesh, bool(len(pins) or len(pairs)), V, T


class _CellIndex:
    """Finds the Bézier cell (and its local parameters) of points given by patch and (u, v)."""

    def __init__(self, cellsets, offsets, first, n_cells, nsv, box_of):
        self.cellsets, self.offsets = cellsets, offsets
        self.first, self.n_cells, self.nsv, self.box_of = first, n_cells, nsv, box_of
        self.set_of = np.repeat(np.arange(len(cellsets)), np.diff(offsets))

    def locate(self, P, u, v):
        """Global cell ``(k,)`` and local ``(s, t)`` of the points ``(P[i], u[i], v[i])``."""
        g = self.first[P]  # right for single-cell patches
        for p in np.unique(P[self.n_cells[P] > 1]):
            sel = np.flatnonzero(P == p)
            ns_v = self.nsv[p]
            ns_u = self.n_cells[p] // ns_v
            box = self.box_of[self.first[p] : self.first[p] + self.n_cells[p]]
            bu = np.append(box[::ns_v, 0], box[-1, 1])
            bv = np.append(box[:ns_v, 2], box[-1, 3])
            iu = np.clip(np.searchsorted(bu, u[sel], side="right") - 1, 0, ns_u - 1)
            iv = np.clip(np.searchsorted(bv, v[sel], side="right") - 1, 0, ns_v - 1)
            g[sel] = self.first[p] + iu * ns_v + iv
        box = self.box_of[g]
        return g, (u - box[:, 0]) / (box[:, 1] - box[:, 0]), (v - box[:, 2]) / (box[:, 3] - box[:, 2])


def _partial_tables(s, t, p, q):
    """Bernstein values and first derivatives ``(2, p + 1, k)``, ``(2, q + 1, k)`` at the
    local parameters ``s``, ``t`` ``(k,)``."""
    if p == q:  # one table for both directions (values are per point)
        B = all_bernstein(p, np.concatenate([s, t]), 1)  # (2, p + 1, 2 k)
        return B[..., : s.size], B[..., s.size :]
    return all_bernstein(p, s, 1), all_bernstein(q, t, 1)


def _cell_partials(nets, s, t, p, q):
    """``(S, Su, Sv, Suv)`` ``(k, 3)`` of Bézier cells ``nets`` ``(k, p + 1, q + 1, 4)`` at
    local parameters ``s, t`` ``(k,)`` (rational quotient rule)."""
    Bu, Bv = _partial_tables(s, t, p, q)
    A = [[np.einsum("ik,jk,kijc->kc", Bu[a], Bv[b], nets) for b in range(2)] for a in range(2)]
    w = A[0][0][:, 3:]
    S = A[0][0][:, :3] / w
    Su = (A[1][0][:, :3] - A[1][0][:, 3:] * S) / w
    Sv = (A[0][1][:, :3] - A[0][1][:, 3:] * S) / w
    Suv = (A[1][1][:, :3] - A[1][0][:, 3:] * Sv - A[0][1][:, 3:] * Su - A[1][1][:, 3:] * S) / w
    return S, Su, Sv, Suv


def _cross(a, b):
    """Row-wise cross product of ``(k, 3)`` arrays (``np.cross`` costs more on small inputs)."""
    return np.column_stack([
        a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
        a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
        a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
    ])  # fmt: skip


def _fix_weak_normals(N, weak, UV, VP, cells: _CellIndex):
    """Limit normals where ``Su x Sv`` vanishes (a collapsed edge such as a pole): the
    direction ``Su x Suv + Suv x Sv`` (the limit of ``Su x Sv / v`` at ``v -> 0``),
    oriented like the normal at a point slightly inside the cell."""
    idx = np.flatnonzero(weak)
    g, s, t = cells.locate(VP[idx], UV[idx, 0], UV[idx, 1])
    sets = cells.set_of[g]
    jit = _kernels()
    for k in np.unique(sets):
        sel = np.flatnonzero(sets == k)
        cs = cells.cellsets[k]
        nets = cs.nets[g[sel] - cells.offsets[k]]
        s_in, t_in = s[sel] + 1e-3 * (0.5 - s[sel]), t[sel] + 1e-3 * (0.5 - t[sel])
        if jit is not None:
            Bu, Bv = _partial_tables(np.concatenate([s[sel], s_in]), np.concatenate([t[sel], t_in]), cs.p, cs.q)
            N[idx[sel]] = jit.limit_normals(nets, np.ascontiguousarray(Bu), np.ascontiguousarray(Bv))
            continue
        # the points and the points slightly inside, in one evaluation
        _, Su, Sv, Suv = _cell_partials(np.concatenate([nets, nets]), np.concatenate([s[sel], s_in]),
                                        np.concatenate([t[sel], t_in]), cs.p, cs.q)  # fmt: skip
        h = sel.size
        alt = _cross(Su[:h], Suv[:h]) + _cross(Suv[:h], Sv[:h])
        ref = _cross(Su[h:], Sv[h:])
        alt[np.einsum("ij,ij->i", alt, ref) < 0] *= -1.0
        size = np.linalg.norm(alt, axis=1)
        tiny = size <= 1e-14 * (np.linalg.norm(ref, axis=1) + 1e-300)
        alt[tiny] = ref[tiny]
        N[idx[sel]] = alt / np.maximum(np.linalg.norm(alt, axis=1), 1e-300)[:, None]
