"""Compiled (numba) kernel of the tessellator: one fused pass over an evaluated grid.

Imported lazily through :func:`splinekit.basis.jit._load` (never by ``import
splinekit``); :mod:`splinekit.tessellate.surfaces` keeps a numpy path with the
same results for when numba is absent or ``SPLINEKIT_NUMBA=0``.
"""

from __future__ import annotations

import math

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
