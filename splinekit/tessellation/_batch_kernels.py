"""Compiled (numba) kernels of the B-rep tessellator's scattered surface evaluator
(:class:`.batch.SurfaceBatch`): locating each query's Bézier cell among many surfaces' breaks,
and the cell's point and first partials, one query at a time (no gathered copies of the nets).

Imported lazily through :func:`splinekit._kernels.load` (never by ``import splinekit``);
:mod:`.batch` keeps the numpy path (the same cells and local parameters bit for bit, the points
to rounding) for when numba is absent or ``SPLINEKIT_NUMBA=0``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _locate(k, t, key, lo, hi, start, count, a, b):
    """Piece and local parameter of one query (:meth:`.batch._Breaks.locate`, the same operations)."""
    x = 2 * k + (t - lo[k]) / (hi[k] - lo[k])
    j = np.searchsorted(key, x, side="right") - 1
    j = min(max(j, start[k]), start[k] + count[k] - 1)
    return j, (t - a[j]) / (b[j] - a[j])


@njit(cache=True, nogil=True)
def locate_cells(k, u, v, lu, lv, first, nsv, g, s, t):
    """Global cell ``g`` and local ``(s, t)`` ``(n,)`` of the queries ``(k, u, v)``
    (:meth:`.batch.SurfaceBatch._cells`); ``lu``, ``lv``: the u and v breaks' tables
    ``(key, lo, hi, start, count, a, b)``."""
    for i in range(k.size):
        ki = k[i]
        iu, s[i] = _locate(ki, u[i], lu[0], lu[1], lu[2], lu[3], lu[4], lu[5], lu[6])
        iv, t[i] = _locate(ki, v[i], lv[0], lv[1], lv[2], lv[3], lv[4], lv[5], lv[6])
        g[i] = first[ki] + (iu - lu[3][ki]) * nsv[ki] + (iv - lv[3][ki])


@njit(cache=True, nogil=True)
def _bernstein_pair(p, x, B, D):
    """Bernstein values ``B`` and first derivatives ``D`` ``(p + 1,)`` of degree ``p`` at ``x``
    (the triangular recurrence of :func:`.batch._bernstein`, the same operations)."""
    for i in range(p + 1):
        B[i] = 0.0
        D[i] = 0.0
    B[0] = 1.0
    y = 1.0 - x
    for j in range(1, p):  # degree p - 1 first: the derivatives come from it
        saved = 0.0
        for k in range(j):
            tmp = B[k]
            B[k] = saved + y * tmp
            saved = x * tmp
        B[j] = saved
    if p == 0:
        return
    for i in range(p):
        D[i] -= p * B[i]
        D[i + 1] += p * B[i]
    saved = 0.0
    for k in range(p):
        tmp = B[k]
        B[k] = saved + y * tmp
        saved = x * tmp
    B[p] = saved


@njit(cache=True, nogil=True)
def cell_points(nets, offset, box, g, s, t, sel, partial, S, Su, Sv):
    """Points ``S`` (and, with ``partial``, first partials ``Su``, ``Sv`` in the surfaces' own
    parameters) of the homogeneous Bézier cells ``nets`` ``(C, p + 1, q + 1, 4)`` (global cells
    ``offset ..`` of the table ``box`` ``(*, 4)`` of cell rectangles): for every query ``i`` in
    ``sel``, cell ``g[i]`` at local ``(s[i], t[i])``, written to row ``i`` of the ``(n, 3)``
    outputs (:meth:`.batch.SurfaceBatch.partials`, one query at a time, no gathered copies)."""
    p, q = nets.shape[1] - 1, nets.shape[2] - 1
    Bu, Du = np.empty(p + 1), np.empty(p + 1)
    Bv, Dv = np.empty(q + 1), np.empty(q + 1)
    h, hu, hv = np.empty(4), np.empty(4), np.empty(4)
    for i in sel:
        _bernstein_pair(p, s[i], Bu, Du)
        _bernstein_pair(q, t[i], Bv, Dv)
        net = nets[g[i] - offset]
        for c in range(4):
            h[c] = 0.0
            hu[c] = 0.0
            hv[c] = 0.0
        for a in range(p + 1):
            for b in range(q + 1):
                wb, wd = Bu[a] * Bv[b], Du[a] * Bv[b]
                we = Bu[a] * Dv[b]
                for c in range(4):
                    x = net[a, b, c]
                    h[c] += wb * x
                    if partial:
                        hu[c] += wd * x
                        hv[c] += we * x
        for d in range(3):
            S[i, d] = h[d] / h[3]
        if partial:
            wu = h[3] * (box[g[i], 1] - box[g[i], 0])
            wv = h[3] * (box[g[i], 3] - box[g[i], 2])
            for d in range(3):
                Su[i, d] = (hu[d] - hu[3] * S[i, d]) / wu
                Sv[i, d] = (hv[d] - hv[3] * S[i, d]) / wv
