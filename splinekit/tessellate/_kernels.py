"""Compiled (numba) kernel of the tessellator: one fused pass over an evaluated grid.

Imported lazily through :func:`splinekit.basis.jit._load` (never by ``import
splinekit``); :mod:`splinekit.tessellate.surfaces` keeps a numpy path with the
same results for when numba is absent or ``SPLINEKIT_NUMBA=0``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def measure_grid(H, Hu, Hv, C1, C2, rational, ri, ci, tol2, weld2, check_collapsed, do_angle, V, N, weak, err):
    """Vertices, unit normals and per-cell maxima of an evaluated grid.

    Inputs in the layout ``(rows, grid, coordinate, columns)``: ``H`` the
    half-step grid ``(2 n + 1, c, k, 2 m + 1)``, ``Hu``/``Hv`` first partials at
    the vertices ``(n + 1, c, k, m + 1)``, ``C1``/``C2`` the triangle centres
    ``(n, c, k, m)``; homogeneous (``k = 4``) when ``rational``. ``ri``/``ci`` map
    a row/column index to its knot span. Outputs: ``V``, ``N`` ``(c, n + 1, m + 1, 3)``,
    ``weak`` ``(c, n + 1, m + 1)`` (collapsed normals), ``err`` ``(c, spans_u,
    spans_v, 6)``: maxima of the squared deviations at u-edge, v-edge and
    diagonal midpoints / triangle centres, then the minima of the cosines
    between the normals at the ends of u, v and diagonal edges.
    """
    A2 = H.shape[0]
    c = H.shape[1]
    B2 = H.shape[3]
    n = (A2 - 1) // 2
    m = (B2 - 1) // 2
    third = 1.0 / 3.0
    for g in range(c):
        # vertices and normals
        for i in range(n + 1):
            for j in range(m + 1):
                w = H[2 * i, g, 3, 2 * j] if rational else 1.0
                x0 = H[2 * i, g, 0, 2 * j] / w
                x1 = H[2 * i, g, 1, 2 * j] / w
                x2 = H[2 * i, g, 2, 2 * j] / w
                V[g, i, j, 0] = x0
                V[g, i, j, 1] = x1
                V[g, i, j, 2] = x2
                a0, a1, a2 = Hu[i, g, 0, j], Hu[i, g, 1, j], Hu[i, g, 2, j]
                b0, b1, b2 = Hv[i, g, 0, j], Hv[i, g, 1, j], Hv[i, g, 2, j]
                if rational:
                    wu, wv = Hu[i, g, 3, j], Hv[i, g, 3, j]
                    a0 -= wu * x0
                    a1 -= wu * x1
                    a2 -= wu * x2
                    b0 -= wv * x0
                    b1 -= wv * x1
                    b2 -= wv * x2
                n0 = a1 * b2 - a2 * b1
                n1 = a2 * b0 - a0 * b2
                n2 = a0 * b1 - a1 * b0
                l2 = n0 * n0 + n1 * n1 + n2 * n2
                s = a0 * a0 + a1 * a1 + a2 * a2 + b0 * b0 + b1 * b1 + b2 * b2
                wk = l2 <= 1e-20 * s * s
                weak[g, i, j] = wk
                inv = 1.0 if wk else 1.0 / math.sqrt(l2)
                N[g, i, j, 0] = n0 * inv
                N[g, i, j, 1] = n1 * inv
                N[g, i, j, 2] = n2 * inv
        # u edges (i, j) - (i + 1, j)
        for i in range(n):
            for j in range(m + 1):
                w = H[2 * i + 1, g, 3, 2 * j] if rational else 1.0
                d2 = 0.0
                e2 = 0.0
                for d in range(3):
                    t = H[2 * i + 1, g, d, 2 * j] / w - 0.5 * (V[g, i, j, d] + V[g, i + 1, j, d])
                    d2 += t * t
                    t = V[g, i + 1, j, d] - V[g, i, j, d]
                    e2 += t * t
                r, s = ri[i], ci[j]
                err[g, r, s, 0] = max(err[g, r, s, 0], d2)
                if do_angle and e2 > tol2 and not (weak[g, i, j] or weak[g, i + 1, j]):
                    cs = N[g, i, j, 0] * N[g, i + 1, j, 0] + N[g, i, j, 1] * N[g, i + 1, j, 1] + N[g, i, j, 2] * N[g, i + 1, j, 2]
                    if cs >= 0.0 and cs < err[g, r, s, 3]:
                        err[g, r, s, 3] = cs
        # v edges (i, j) - (i, j + 1)
        for i in range(n + 1):
            for j in range(m):
                w = H[2 * i, g, 3, 2 * j + 1] if rational else 1.0
                d2 = 0.0
                e2 = 0.0
                for d in range(3):
                    t = H[2 * i, g, d, 2 * j + 1] / w - 0.5 * (V[g, i, j, d] + V[g, i, j + 1, d])
                    d2 += t * t
                    t = V[g, i, j + 1, d] - V[g, i, j, d]
                    e2 += t * t
                r, s = ri[i], ci[j]
                err[g, r, s, 1] = max(err[g, r, s, 1], d2)
                if do_angle and e2 > tol2 and not (weak[g, i, j] or weak[g, i, j + 1]):
                    cs = N[g, i, j, 0] * N[g, i, j + 1, 0] + N[g, i, j, 1] * N[g, i, j + 1, 1] + N[g, i, j, 2] * N[g, i, j + 1, 2]
                    if cs >= 0.0 and cs < err[g, r, s, 4]:
                        err[g, r, s, 4] = cs
        # quads: diagonal (i, j) - (i + 1, j + 1) and the centres of both triangles
        for i in range(n):
            for j in range(m):
                w = H[2 * i + 1, g, 3, 2 * j + 1] if rational else 1.0
                w1 = C1[i, g, 3, j] if rational else 1.0
                w2 = C2[i, g, 3, j] if rational else 1.0
                dd = 0.0
                t1 = 0.0
                t2 = 0.0
                e00_10 = 0.0
                e10_11 = 0.0
                e00_11 = 0.0
                e01_11 = 0.0
                e00_01 = 0.0
                for d in range(3):
                    p00 = V[g, i, j, d]
                    p10 = V[g, i + 1, j, d]
                    p01 = V[g, i, j + 1, d]
                    p11 = V[g, i + 1, j + 1, d]
                    t = H[2 * i + 1, g, d, 2 * j + 1] / w - 0.5 * (p00 + p11)
                    dd += t * t
                    t = C1[i, g, d, j] / w1 - (p00 + p10 + p11) * third
                    t1 += t * t
                    t = C2[i, g, d, j] / w2 - (p00 + p11 + p01) * third
                    t2 += t * t
                    e00_10 += (p10 - p00) * (p10 - p00)
                    e10_11 += (p11 - p10) * (p11 - p10)
                    e00_11 += (p11 - p00) * (p11 - p00)
                    e01_11 += (p11 - p01) * (p11 - p01)
                    e00_01 += (p01 - p00) * (p01 - p00)
                if check_collapsed:
                    # triangles with two coincident corners are dropped after welding
                    if e00_10 <= weld2 or e10_11 <= weld2 or e00_11 <= weld2:
                        t1 = 0.0
                    if e01_11 <= weld2 or e00_01 <= weld2 or e00_11 <= weld2:
                        t2 = 0.0
                worst = max(dd, max(t1, t2))
                r, s = ri[i], ci[j]
                err[g, r, s, 2] = max(err[g, r, s, 2], worst)
                if do_angle and e00_11 > tol2 and not (weak[g, i, j] or weak[g, i + 1, j + 1]):
                    cs = (N[g, i, j, 0] * N[g, i + 1, j + 1, 0] + N[g, i, j, 1] * N[g, i + 1, j + 1, 1]
                          + N[g, i, j, 2] * N[g, i + 1, j + 1, 2])
                    if cs >= 0.0 and cs < err[g, r, s, 5]:
                        err[g, r, s, 5] = cs


@njit(cache=True, nogil=True)
def close_pairs(X, r, sweep, limit):
    """``(k, 2)`` index pairs of the points ``X`` ``(n, 3)`` at most ``r`` apart (each pair
    once, in no particular order): a sweep along the unit direction ``sweep`` ``(3,)``.
    Returns ``(pairs, ok)``; ``ok`` is False (and ``pairs`` empty) when the sweep would
    test more than ``limit`` candidate pairs, for the caller's k-d tree to answer."""
    n = X.shape[0]
    proj = np.empty(n)
    for i in range(n):
        proj[i] = X[i, 0] * sweep[0] + X[i, 1] * sweep[1] + X[i, 2] * sweep[2]
    order = np.argsort(proj)
    ps = proj[order]
    eps4 = 4.0 * np.finfo(np.float64).eps
    # the window's margin covers rounding of the projections; the exact test follows
    ends = np.empty(n, dtype=np.int64)
    total = 0
    j = 0
    for i in range(n):
        top = ps[i] + r * (1.0 + 1e-6) + eps4 * abs(ps[i])
        if j < i + 1:
            j = i + 1
        while j < n and ps[j] <= top:
            j += 1
        ends[i] = j
        total += j - i - 1
    if total > limit:
        return np.zeros((0, 2), dtype=np.int64), False
    out = np.empty((total, 2), dtype=np.int64)
    k = 0
    r2 = r * r
    for i in range(n):
        a = order[i]
        for jj in range(i + 1, ends[i]):
            b = order[jj]
            d0 = X[a, 0] - X[b, 0]
            d1 = X[a, 1] - X[b, 1]
            d2 = X[a, 2] - X[b, 2]
            if d0 * d0 + d1 * d1 + d2 * d2 <= r2:
                out[k, 0] = a
                out[k, 1] = b
                k += 1
    return out[:k].copy(), True


@njit(cache=True, nogil=True)
def _root(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True, nogil=True)
def components(n, a, b):
    """``(n,)`` label of each of ``n`` nodes linked by the edges ``a[k] - b[k]``: the smallest
    node of its connected component (union-find, the larger root always hooked under the
    smaller one, so every root is its component's smallest node)."""
    parent = np.arange(n)
    for k in range(a.size):
        x = _root(parent, a[k])
        y = _root(parent, b[k])
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y
    for i in range(n):
        parent[i] = _root(parent, i)
    return parent


@njit(cache=True, nogil=True)
def clearly_positive_volume(V, F):
    """True when the signed volume of the triangles ``F`` ``(f, 3)`` over the vertices
    ``V`` ``(n, 3)``, about the bounding-box centre, is positive by a margin far above
    rounding (``1e-9`` of the sum of the absolute tetrahedron volumes)."""
    if V.shape[0] == 0:
        return False
    lo = V[0].copy()
    hi = V[0].copy()
    for i in range(1, V.shape[0]):
        for d in range(3):
            x = V[i, d]
            if x < lo[d]:
                lo[d] = x
            if x > hi[d]:
                hi[d] = x
    c0 = 0.5 * (lo[0] + hi[0])
    c1 = 0.5 * (lo[1] + hi[1])
    c2 = 0.5 * (lo[2] + hi[2])
    s = 0.0
    sa = 0.0
    for f in range(F.shape[0]):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        a0, a1, a2 = V[i, 0] - c0, V[i, 1] - c1, V[i, 2] - c2
        b0, b1, b2 = V[j, 0] - c0, V[j, 1] - c1, V[j, 2] - c2
        e0, e1, e2 = V[k, 0] - c0, V[k, 1] - c1, V[k, 2] - c2
        det = a0 * (b1 * e2 - b2 * e1) + a1 * (b2 * e0 - b0 * e2) + a2 * (b0 * e1 - b1 * e0)
        s += det
        sa += abs(det)
    return s > 1e-9 * sa
