"""Evaluate many curves or many surfaces at once.

A B-rep has dozens to thousands of edges and faces, each with its own degree and knots; calling
every curve's or surface's own evaluator costs a Python round trip per object and round. Here
every object is cut once into Bézier pieces (curve segments; surface cells, :mod:`.cells`),
grouped by degree, and a batch of ``(object, parameter)`` queries is answered with one Bernstein
evaluation per degree group: locate the piece (one ``searchsorted`` over all objects' breaks),
map to the piece's local parameter, combine.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix

from .. import _kernels
from ..mesh.topology import ranges
from .cells import bezier_matrix, cells_of_patches

__all__ = ["CurveBatch", "SurfaceBatch"]

KERNELS = "splinekit.tessellation._batch_kernels"
"""The compiled kernels of the surface batch (:mod:`._batch_kernels`), used once loaded."""
CHUNK = 1 << 14
"""Queries evaluated per block (bounds the temporaries' memory)."""
SPARSE_FROM = 2048
"""Blocks of at least this many queries combine control points through a sparse product."""


def _bernstein(p, t):
    """``(p + 1, n)`` Bernstein polynomials of degree ``p`` at ``t`` ``(n,)``, by the
    triangular recurrence on whole arrays (no argument checks: the batch evaluators' inner
    loop; :func:`~splinekit.basis.bernstein.all_bernstein` is the checked public form)."""
    B = np.zeros((p + 1, t.size))
    B[0] = 1.0
    s = 1.0 - t
    for j in range(1, p + 1):
        saved = np.zeros(t.size)
        for k in range(j):
            tmp = B[k].copy()
            B[k] = saved + s * tmp
            saved = t * tmp
        B[j] = saved
    return B


def _bernstein_d(p, t):
    """``(p + 1, n)`` first derivatives of the degree-``p`` Bernstein polynomials at ``t``."""
    D = np.zeros((p + 1, t.size))
    if p > 0:
        B = _bernstein(p - 1, t)
        D[1:] += p * B
        D[:-1] -= p * B
    return D


class _Breaks:
    """Locates parameters among the breaks of many objects: object ``k`` has pieces
    ``first[k] .. first[k] + count[k] - 1`` over the sorted breaks ``breaks[k]``."""

    def __init__(self, breaks, first):
        self._set(np.concatenate(breaks), np.array([len(b) - 1 for b in breaks], dtype=np.int64), first)

    @classmethod
    def of_flat(cls, flat, count, first):
        """The same from all objects' breaks end to end (``flat``; object ``k`` has ``count[k] + 1``)."""
        out = object.__new__(cls)
        out._set(flat, count, first)
        return out

    def _set(self, flat, count, first):
        # whole-array passes, not one numpy call per object: a face set's first tessellation
        # builds these for hundreds of pcurves
        self.count = count
        self.first = np.asarray(first, dtype=np.int64)
        end = np.cumsum(count + 1)
        self.lo, self.hi = flat[end - count - 1], flat[end - 1]
        piece = np.ones(flat.size, dtype=bool)
        piece[end - 1] = False  # each object's last break starts no piece
        start = np.flatnonzero(piece)
        self.a, self.b = flat[start], flat[start + 1]  # per piece, in object order
        # all breaks on one increasing axis: object k occupies [2 k, 2 k + 1]
        k = np.repeat(np.arange(count.size), count)
        self.key = 2 * k + (self.a - self.lo[k]) / (self.hi[k] - self.lo[k])
        self.start = (end - count - 1 - np.arange(count.size)).astype(np.int64)
        # the arrays :meth:`locate` reads, for the compiled kernel
        self.table = (self.key, self.lo, self.hi, self.start, self.count, self.a, self.b)

    def locate(self, k, t):
        """``(piece (n,), local (n,))``: the piece of object ``k`` holding ``t`` (by object
        order) and the local parameter in [0, 1] (slightly outside for ``t`` off the domain)."""
        g = 2 * k + (t - self.lo[k]) / (self.hi[k] - self.lo[k])
        j = np.searchsorted(self.key, g, side="right") - 1
        j = np.clip(j, self.start[k], self.start[k] + self.count[k] - 1)
        return j, (t - self.a[j]) / (self.b[j] - self.a[j])


class CurveBatch:
    """Many spline curves of one dimension as a table of Bézier pieces, evaluated together:
    ``evaluate(k, t)`` gives the points of curve ``k[i]`` at ``t[i]``.

    Unlike :class:`splinekit.curves.batch.CurveBatch` (knot spans, results bitwise equal to each
    curve's own evaluation), this one keeps the pieces themselves: the edge sampler walks them
    (``breaks``, ``first_row``) and bounds each by its control polygon (``segs``)."""

    def __init__(self, curves):
        self.dim = curves[0].dim if curves else 0
        C = len(curves)
        self.degree = np.array([c.degree for c in curves], dtype=np.int64)
        # curves on one knot vector share one decomposition matrix: one product per knot vector
        by_knots: dict = {}
        for i, c in enumerate(curves):
            by_knots.setdefault((c.degree, c.knots.tobytes()), []).append(i)
        group = np.empty(C, dtype=np.int64)
        decomposed = []  # per knot vector: (members, breaks, Bézier segments (m, s, p + 1, dim + 1))
        for g, ((p, _), members) in enumerate(by_knots.items()):
            br, M = bezier_matrix(p, tuple(curves[members[0]].knots.tolist()))
            if any(curves[i].is_rational for i in members):
                coefs = np.stack([_homogeneous(curves[i]) for i in members])  # (m, n, dim + 1)
            else:  # polynomial curves (most pcurves): unit weights appended once for all
                P = np.stack([curves[i].control_points for i in members])
                coefs = np.concatenate([P, np.ones(P.shape[:2] + (1,))], axis=2)
            members = np.array(members, dtype=np.int64)
            group[members] = g
            decomposed.append((members, br, np.einsum("sij,mjk->msik", M, coefs)))
        # each degree's segments in one table, curve after curve (in the curves' order)
        nseg = np.array([len(br) - 1 for _, br, _ in decomposed], dtype=np.int64)[group] if C else np.zeros(0, np.int64)
        first = np.zeros(C, dtype=np.int64)
        self.segs = {}
        for p in np.unique(self.degree).tolist():
            on = np.flatnonzero(self.degree == p)
            first[on] = np.cumsum(nseg[on]) - nseg[on]
            self.segs[p] = np.empty((int(nseg[on].sum()), p + 1, self.dim + 1))
        for members, _, S in decomposed:
            rows = first[members][:, None] + np.arange(S.shape[1])
            self.segs[int(self.degree[members[0]])][rows] = S
        if C:
            brs = [br for _, br, _ in decomposed]
            nbr = np.array([len(br) for br in brs], dtype=np.int64)
            at = (np.cumsum(nbr) - nbr)[group]  # each curve's breaks: its knot vector's, end to end
            flat = np.concatenate(brs)[ranges(at, nseg + 1)]
            self.breaks = _Breaks.of_flat(flat, nseg, first)
        else:
            self.breaks = None
        self.first_row = first

    def segments(self, k):
        """``(p, rows)``: the degree and Bézier segment rows of curve ``k``."""
        p = int(self.degree[k])
        return p, self.first_row[k] + np.arange(self.breaks.count[k])

    def evaluate(self, k, t):
        """``(n, dim)`` points of curves ``k`` ``(n,)`` at ``t`` ``(n,)`` each."""
        return self._run(k, t, False)

    def partials(self, k, t):
        """``(C, dC/dt)`` ``(n, dim)`` each: points and first derivatives in the curves' parameters."""
        return self._run(k, t, True)

    def _run(self, k, t, partial):
        k = np.asarray(k, dtype=np.int64)
        t = np.asarray(t, dtype=np.float64)
        out = [np.empty((t.size, self.dim)) for _ in range(2 if partial else 1)]
        if t.size == 0:
            return tuple(out) if partial else out[0]
        j, s = self.breaks.locate(k, t)
        row = self.breaks.first[k] + (j - self.breaks.start[k])
        deg = self.degree[k]
        for p in np.unique(deg):
            sel = np.flatnonzero(deg == p) if len(self.segs) > 1 else slice(None)
            segs = self.segs[int(p)][row[sel]]
            h = np.einsum("in,nik->nk", _bernstein(int(p), s[sel]), segs)  # (n, dim + 1) homogeneous
            C = h[:, :-1] / h[:, -1:]
            out[0][sel] = C
            if partial:  # quotient rule, then local -> curve parameter
                dh = np.einsum("in,nik->nk", _bernstein_d(int(p), s[sel]), segs)
                width = (self.breaks.b - self.breaks.a)[j[sel]]
                out[1][sel] = (dh[:, :-1] - dh[:, -1:] * C) / (h[:, -1:] * width[:, None])
        return tuple(out) if partial else out[0]


def _homogeneous(curve):
    """``(n, dim + 1)`` homogeneous control points (unit weights for a polynomial curve)."""
    if curve.is_rational:
        return np.asarray(curve.homogeneous_points)
    P = np.asarray(curve.control_points)
    return np.column_stack([P, np.ones(len(P))])


class SurfaceBatch:
    """Many spline surfaces evaluated together: ``evaluate(k, u, v)`` gives the points of
    surface ``k[i]`` at ``(u[i], v[i])``; ``partials`` also the first derivatives."""

    def __init__(self, surfaces):
        self.cellsets = cells_of_patches(surfaces)
        sizes = [len(cs) for cs in self.cellsets]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.set_of = np.repeat(np.arange(len(self.cellsets)), sizes)
        patch = np.concatenate([cs.patch for cs in self.cellsets])
        span = np.concatenate([cs.span for cs in self.cellsets])
        box = np.concatenate([cs.box for cs in self.cellsets])
        C, S = len(patch), len(surfaces)
        self.first = np.full(S, C, dtype=np.int64)
        np.minimum.at(self.first, patch, np.arange(C))
        self.nsv = np.zeros(S, dtype=np.int64)
        np.maximum.at(self.nsv, patch, span[:, 1] + 1)
        ncell = np.bincount(patch, minlength=S)
        self.nsu = ncell // self.nsv
        # cells of one surface are contiguous, (iu, iv) order with iu major: its u breaks are
        # the u starts of every nsv-th cell and the last cell's end, its v breaks the v starts of
        # its first nsv cells and the last cell's end (all surfaces in one pass each)
        last = self.first + ncell - 1
        ju = ranges(np.zeros(S, dtype=np.int64), self.nsu + 1)  # 0 .. nsu per surface
        end = ju == np.repeat(self.nsu, self.nsu + 1)
        row = np.where(end, np.repeat(last, self.nsu + 1), np.repeat(self.first, self.nsu + 1) + ju * np.repeat(self.nsv, self.nsu + 1))
        flat_u = box[row, np.where(end, 1, 0)]
        jv = ranges(np.zeros(S, dtype=np.int64), self.nsv + 1)
        end = jv == np.repeat(self.nsv, self.nsv + 1)
        flat_v = box[np.where(end, np.repeat(last, self.nsv + 1), np.repeat(self.first, self.nsv + 1) + jv), np.where(end, 3, 2)]
        self.lu = _Breaks.of_flat(flat_u, self.nsu, np.zeros(S))
        self.lv = _Breaks.of_flat(flat_v, self.nsv, np.zeros(S))
        self._bu = self._bv = None
        self.box = box

    @property
    def bu(self):
        """Per surface its ``u`` breaks ``(nsu + 1,)`` (a list of arrays)."""
        if self._bu is None:
            self._bu = [np.append(a, h) for a, h in zip(np.split(self.lu.a, np.cumsum(self.nsu)[:-1]), self.lu.hi)]
        return self._bu

    @property
    def bv(self):
        """Per surface its ``v`` breaks ``(nsv + 1,)`` (a list of arrays)."""
        if self._bv is None:
            self._bv = [np.append(a, h) for a, h in zip(np.split(self.lv.a, np.cumsum(self.nsv)[:-1]), self.lv.hi)]
        return self._bv

    def _cells(self, k, u, v):
        jit = _kernels.get(KERNELS)
        if jit is not None:
            g, s, t = np.empty(k.size, dtype=np.int64), np.empty(k.size), np.empty(k.size)
            jit.locate_cells(k, u, v, self.lu.table, self.lv.table, self.first, self.nsv, g, s, t)
            return g, s, t
        iu, s = self.lu.locate(k, u)
        iv, t = self.lv.locate(k, v)
        iu -= self.lu.start[k]
        iv -= self.lv.start[k]
        return self.first[k] + iu * self.nsv[k] + iv, s, t

    def evaluate(self, k, u, v):
        """``(n, 3)`` points of surfaces ``k`` ``(n,)`` at ``(u, v)`` ``(n,)`` each."""
        return self._run(k, u, v, False)

    def partials(self, k, u, v):
        """``(S, Su, Sv)`` ``(n, 3)`` each: points and first partials in the surfaces' parameters."""
        return self._run(k, u, v, True)

    def _run(self, k, u, v, partial):
        k = np.asarray(k, dtype=np.int64)
        n = k.size
        out = [np.empty((n, 3)) for _ in range(3 if partial else 1)]
        if n == 0:
            return tuple(out) if partial else out[0]
        g, s, t = self._cells(k, np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
        sets = self.set_of[g]
        jit = _kernels.get(KERNELS)
        for c in np.flatnonzero(np.bincount(sets, minlength=len(self.cellsets))):
            sel = np.flatnonzero(sets == c) if len(self.cellsets) > 1 else np.arange(n)
            cs = self.cellsets[c]
            if jit is not None:  # one query at a time, compiled, straight into the outputs
                S, Su, Sv = out if partial else (out[0], out[0], out[0])
                jit.cell_points(cs.nets, int(self.offsets[c]), self.box, g, s, t, sel, partial, S, Su, Sv)
                continue
            table = cs.nets.reshape(-1, 4)  # (cells * (p + 1) * (q + 1), 4) homogeneous
            m = (cs.p + 1) * (cs.q + 1)
            for lo in range(0, sel.size, CHUNK):
                part = sel[lo : lo + CHUNK]
                gl = g[part] - self.offsets[c]
                Bu, Bv = _bernstein(cs.p, s[part]), _bernstein(cs.q, t[part])
                # each query combines the m control points of its cell: a sparse (queries x table)
                # product reads the small table in place of gathering an (n, p + 1, q + 1, 4) copy
                # of the nets (which cost ten times as much from about 10k queries on)
                if part.size >= SPARSE_FROM:
                    cols = (gl[:, None] * m + np.arange(m)).ravel()
                    ptr = np.arange(0, m * part.size + 1, m)

                def combine(A, B):
                    w = A.T[:, :, None] * B.T[:, None, :]  # (queries, p + 1, q + 1) weights
                    if part.size < SPARSE_FROM:  # few queries: the gathered copy is cheaper than building the matrix
                        return np.einsum("nm,nmk->nk", w.reshape(part.size, m), cs.nets[gl].reshape(part.size, m, 4))
                    return csr_matrix((w.ravel(), cols, ptr), shape=(part.size, table.shape[0])) @ table

                h = combine(Bu, Bv)
                S = h[:, :3] / h[:, 3:]
                out[0][part] = S
                if partial:  # quotient rule, then local -> surface parameters
                    hu = combine(_bernstein_d(cs.p, s[part]), Bv)
                    hv = combine(Bu, _bernstein_d(cs.q, t[part]))
                    box = self.box[g[part]]
                    out[1][part] = (hu[:, :3] - hu[:, 3:] * S) / (h[:, 3:] * (box[:, 1] - box[:, 0])[:, None])
                    out[2][part] = (hv[:, :3] - hv[:, 3:] * S) / (h[:, 3:] * (box[:, 3] - box[:, 2])[:, None])
        return tuple(out) if partial else out[0]
