"""Compiled (numba) kernels of the tessellator: one fused pass over an evaluated grid,
and the fixed per-call work of small models (a-priori bounds of rational cells, the
weld sweep and its components, vertex gathering, the post-weld triangle remap, pole
normals and the orientation test).

Imported lazily through :func:`splinekit._kernels.load` (never by ``import
splinekit``); the tessellation modules that call these kernels (:mod:`.grids`,
:mod:`.welding`, :mod:`.assembly`, :mod:`.poles`, :mod:`.cells`) keep a numpy path with the
same results (bit for bit, except the rounding of the fused pass's normals) for when
numba is absent or ``SPLINEKIT_NUMBA=0``.
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
        j = max(j, i + 1)
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
            lo[d] = min(lo[d], V[i, d])
            hi[d] = max(hi[d], V[i, d])
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


@njit(cache=True, nogil=True)
def sampled_second_derivatives(nets, Bu, Bv):
    """``(c, 3)`` maxima of ``|S_uu|``, ``|S_uv|``, ``|S_vv|`` of rational Bézier cells
    ``nets`` ``(c, p + 1, q + 1, 4)`` (homogeneous) over a sample grid, from the
    Bernstein values and derivatives ``Bu`` ``(3, p + 1, s)``, ``Bv`` ``(3, q + 1, s)``
    (quotient rule)."""
    c, p1, q1 = nets.shape[0], nets.shape[1], nets.shape[2]
    su, sv = Bu.shape[2], Bv.shape[2]
    out = np.zeros((c, 3))
    T = np.empty((3, q1, 4))
    A = np.empty((3, 3, 4))
    D = np.empty((3, 3))
    for g in range(c):
        for s in range(su):
            # T[a, j] = d^a/du^a of the homogeneous column j at u sample s
            for a in range(3):
                for j in range(q1):
                    for k in range(4):
                        acc = 0.0
                        for i in range(p1):
                            acc += Bu[a, i, s] * nets[g, i, j, k]
                        T[a, j, k] = acc
            for t in range(sv):
                for a in range(3):
                    for b in range(3 - a):
                        for k in range(4):
                            acc = 0.0
                            for j in range(q1):
                                acc += Bv[b, j, t] * T[a, j, k]
                            A[a, b, k] = acc
                w = A[0, 0, 3]
                for d in range(3):
                    S = A[0, 0, d] / w
                    Su = (A[1, 0, d] - A[1, 0, 3] * S) / w
                    Sv = (A[0, 1, d] - A[0, 1, 3] * S) / w
                    D[0, d] = (A[2, 0, d] - 2 * A[1, 0, 3] * Su - A[2, 0, 3] * S) / w
                    D[1, d] = (A[1, 1, d] - A[1, 0, 3] * Sv - A[0, 1, 3] * Su - A[1, 1, 3] * S) / w
                    D[2, d] = (A[0, 2, d] - 2 * A[0, 1, 3] * Sv - A[0, 2, 3] * S) / w
                for e in range(3):
                    # summed in the order numpy's einsum uses, so the numpy path's counts are matched bit for bit
                    x2 = (D[e, 0] * D[e, 0] + D[e, 2] * D[e, 2]) + D[e, 1] * D[e, 1]
                    r = math.sqrt(x2)
                    if r > out[g, e] or math.isnan(r):  # (a NaN sticks, as in numpy's max)
                        out[g, e] = r
    return out


@njit(cache=True, nogil=True)
def _homogeneous_partials(Bu, Bv, net, k, A):
    """``A[a, b]`` ``(2, 2, 4)``: d^a/du^a d^b/dv^b of the homogeneous cell ``net``
    ``(p + 1, q + 1, 4)`` at point ``k`` of the Bernstein tables ``Bu`` ``(2, p + 1, K)``,
    ``Bv`` ``(2, q + 1, K)``."""
    for a in range(2):
        for b in range(2):
            for c in range(4):
                acc = 0.0
                for i in range(net.shape[0]):
                    for j in range(net.shape[1]):
                        acc += Bu[a, i, k] * Bv[b, j, k] * net[i, j, c]
                A[a, b, c] = acc


@njit(cache=True, nogil=True)
def _partials(A, S, Su, Sv, Suv):
    """Cartesian ``S``, ``Su``, ``Sv``, ``Suv`` ``(3,)`` from homogeneous partials ``A``."""
    w = A[0, 0, 3]
    for d in range(3):
        S[d] = A[0, 0, d] / w
    for d in range(3):
        Su[d] = (A[1, 0, d] - A[1, 0, 3] * S[d]) / w
        Sv[d] = (A[0, 1, d] - A[0, 1, 3] * S[d]) / w
    for d in range(3):
        Suv[d] = (A[1, 1, d] - A[1, 0, 3] * Sv[d] - A[0, 1, 3] * Su[d] - A[1, 1, 3] * S[d]) / w


@njit(cache=True, nogil=True)
def limit_normals(nets, Bu, Bv):
    """``(h, 3)`` unit limit normals at collapsed edges: ``Su x Suv + Suv x Sv`` of the cells
    ``nets`` ``(h, p + 1, q + 1, 4)`` at the first ``h`` points of the Bernstein tables
    ``Bu`` ``(2, p + 1, 2 h)``, ``Bv`` ``(2, q + 1, 2 h)`` (values, first derivatives),
    oriented like ``Su x Sv`` at the last ``h`` points (slightly inside the cells), which
    also stands in where the limit direction vanishes."""
    h = nets.shape[0]
    out = np.empty((h, 3))
    A = np.empty((2, 2, 4))
    S, Su, Sv, Suv = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    alt, ref = np.empty(3), np.empty(3)
    for k in range(h):
        _homogeneous_partials(Bu, Bv, nets[k], k, A)
        _partials(A, S, Su, Sv, Suv)
        alt[0] = (Su[1] * Suv[2] - Su[2] * Suv[1]) + (Suv[1] * Sv[2] - Suv[2] * Sv[1])
        alt[1] = (Su[2] * Suv[0] - Su[0] * Suv[2]) + (Suv[2] * Sv[0] - Suv[0] * Sv[2])
        alt[2] = (Su[0] * Suv[1] - Su[1] * Suv[0]) + (Suv[0] * Sv[1] - Suv[1] * Sv[0])
        _homogeneous_partials(Bu, Bv, nets[k], h + k, A)
        _partials(A, S, Su, Sv, Suv)
        ref[0] = Su[1] * Sv[2] - Su[2] * Sv[1]
        ref[1] = Su[2] * Sv[0] - Su[0] * Sv[2]
        ref[2] = Su[0] * Sv[1] - Su[1] * Sv[0]
        if alt[0] * ref[0] + alt[1] * ref[1] + alt[2] * ref[2] < 0:
            for d in range(3):
                alt[d] *= -1.0
        size = math.sqrt(alt[0] * alt[0] + alt[1] * alt[1] + alt[2] * alt[2])
        if size <= 1e-14 * (math.sqrt(ref[0] * ref[0] + ref[1] * ref[1] + ref[2] * ref[2]) + 1e-300):
            for d in range(3):
                alt[d] = ref[d]
        size = max(math.sqrt(alt[0] * alt[0] + alt[1] * alt[1] + alt[2] * alt[2]), 1e-300)
        for d in range(3):
            out[k, d] = alt[d] / size
    return out


@njit(cache=True, nogil=True)
def gather_piece(Vp, Np, Kp, U, W, pid, Li, Lr, m, int_at, ring_at, V, N, WK, UV, VP):
    """Copy one grid's vertex data into the mesh arrays: the interior local vertices ``Li``
    of its ``c`` cells from row ``int_at`` on, the ring ones ``Lr`` from ``ring_at``.
    ``Vp``, ``Np`` ``(c, per, 3)``, ``Kp`` ``(c, per)`` weak flags, ``U`` ``(c, n + 1)``,
    ``W`` ``(c, m + 1)`` grid parameters, ``pid`` ``(c,)`` patches; ``m + 1`` columns."""
    c = Vp.shape[0]
    for L, at in ((Li, int_at), (Lr, ring_at)):
        row = at
        for g in range(c):
            for k in range(L.size):
                v = L[k]
                for d in range(3):
                    V[row, d] = Vp[g, v, d]
                    N[row, d] = Np[g, v, d]
                WK[row] = Kp[g, v]
                UV[row, 0] = U[g, v // (m + 1)]
                UV[row, 1] = W[g, v % (m + 1)]
                VP[row] = pid[g]
                row += 1


@njit(cache=True, nogil=True)
def weld_triangles(E0, FE, rep, NI, NR, T, FP):
    """Remap the triangles ``E0`` ``(t, 3)`` (patches ``FE``) that touch a grid ring after
    welding: ring vertex ``NI + r`` becomes ``NI + rep[r]``; triangles that collapse are
    dropped, and so are repeats (same corners in the same cyclic order: the first is
    kept); the ring vertices still in use are renumbered ``NI, NI + 1, ...`` in their
    order. The survivors are written, in their order, to ``T`` ``(>= t, 3)`` and ``FP``.
    Returns ``(count, E0 of the survivors, kept ring vertices (ascending))``; needs
    ``(NI + NR)^3`` to fit an int64 (the dedup key)."""
    n = E0.shape[0]
    nv = NI + NR
    E = np.empty((n, 3), dtype=np.int64)
    good = np.zeros(n, dtype=np.bool_)
    key = np.empty(n, dtype=np.int64)
    for f in range(n):
        for d in range(3):
            x = E0[f, d]
            E[f, d] = x if x < NI else NI + rep[x - NI]
        a, b, c = E[f, 0], E[f, 1], E[f, 2]
        if a != b and b != c and a != c:
            good[f] = True
            # the rotation that starts at the smallest corner has the smallest key
            key[f] = min((a * nv + b) * nv + c, min((b * nv + c) * nv + a, (c * nv + a) * nv + b))
    idx = np.flatnonzero(good)
    order = idx[np.argsort(key[idx], kind="mergesort")]  # stable: equal keys by triangle order
    for k in range(1, order.size):
        if key[order[k]] == key[order[k - 1]]:
            good[order[k]] = False
    new_ring = np.full(NR, -1, dtype=np.int64)
    count = 0
    for f in range(n):
        if good[f]:
            count += 1
            for d in range(3):
                if E[f, d] >= NI:
                    new_ring[E[f, d] - NI] = 0
    kept_n = 0
    for r in range(NR):
        if new_ring[r] == 0:
            new_ring[r] = NI + kept_n
            kept_n += 1
    kept = np.empty(kept_n, dtype=np.int64)
    for r in range(NR):
        if new_ring[r] >= 0:
            kept[new_ring[r] - NI] = r
    E0_kept = np.empty((count, 3), dtype=np.int64)
    row = 0
    for f in range(n):
        if good[f]:
            for d in range(3):
                x = E[f, d]
                T[row, d] = x if x < NI else new_ring[x - NI]
                E0_kept[row, d] = E0[f, d]
            FP[row] = FE[f]
            row += 1
    return count, E0_kept, kept
