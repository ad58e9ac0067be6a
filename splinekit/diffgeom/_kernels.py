"""Compiled curvature on a tensor grid of a spline surface (numba).

One pass per grid point: the six partials up to order 2 from the banded basis
values (the net contracted in u once per grid row, as in
``basis._numba_kernels.grid_tensor4``), the rational quotient rule, then the
same algebra as :func:`splinekit.diffgeom.curvature._from_derivatives`, with
no temporaries between the stages. Imported only through
:func:`splinekit._kernels.load` for large grids.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

# output fields, in order, per grid point
FIELDS = (
    ("points", 3), ("normal", 3), ("E", 1), ("F", 1), ("G", 1), ("L", 1), ("M", 1), ("N", 1),
    ("gaussian", 1), ("mean", 1), ("k1", 1), ("k2", 1), ("directions", 6), ("directions_uv", 4),
    ("shape_operator", 4), ("singular", 1),
)  # fmt: skip
N_FIELDS = sum(width for _, width in FIELDS)


@njit(cache=True, parallel=True)
def grid_curvature(C, su, Nu, p, sv, Nv, q, rational, out):  # noqa: C901 - one fused loop on purpose
    """Fill ``out`` ``(N_FIELDS, mu, mv)`` (layout :data:`FIELDS`: one plane per
    scalar, so every field is a view of it without copying) from the
    homogeneous net ``C`` ``(nu, nv, 4)`` (column 3 the weight; ignored unless
    ``rational``) and the basis derivatives ``Nu`` ``(3, p + 1, mu)``,
    ``Nv`` ``(3, q + 1, mv)`` at spans ``su``, ``sv``."""
    mu = su.shape[0]
    mv = sv.shape[0]
    nv = C.shape[1]
    for i in prange(mu):
        row = np.zeros((3, nv, 4))
        bu = su[i] - p
        for a in range(3):
            for l in range(nv):
                for c in range(4):
                    acc = 0.0
                    for k in range(p + 1):
                        acc += Nu[a, k, i] * C[bu + k, l, c]
                    row[a, l, c] = acc
        A = np.empty((3, 3, 4))
        S = np.empty((3, 3, 3))
        for j in range(mv):
            bv = sv[j] - q
            for a in range(3):
                for b in range(3 - a):
                    for c in range(4):
                        acc = 0.0
                        for k in range(q + 1):
                            acc += Nv[b, k, j] * row[a, bv + k, c]
                        A[a, b, c] = acc
            # Cartesian partials (quotient rule for rational nets)
            if rational:
                w = A[0, 0, 3]
                for c in range(3):
                    s0 = A[0, 0, c] / w
                    su_ = (A[1, 0, c] - A[1, 0, 3] * s0) / w
                    sv_ = (A[0, 1, c] - A[0, 1, 3] * s0) / w
                    S[0, 0, c] = s0
                    S[1, 0, c] = su_
                    S[0, 1, c] = sv_
                    S[2, 0, c] = (A[2, 0, c] - 2.0 * A[1, 0, 3] * su_ - A[2, 0, 3] * s0) / w
                    S[1, 1, c] = (A[1, 1, c] - A[1, 0, 3] * sv_ - A[0, 1, 3] * su_ - A[1, 1, 3] * s0) / w
                    S[0, 2, c] = (A[0, 2, c] - 2.0 * A[0, 1, 3] * sv_ - A[0, 2, 3] * s0) / w
            else:
                for a in range(3):
                    for b in range(3 - a):
                        for c in range(3):
                            S[a, b, c] = A[a, b, c]
            o = out[:, i, j]
            for c in range(3):
                o[c] = S[0, 0, c]
            xu0, xu1, xu2 = S[1, 0, 0], S[1, 0, 1], S[1, 0, 2]
            xv0, xv1, xv2 = S[0, 1, 0], S[0, 1, 1], S[0, 1, 2]
            n0 = xu1 * xv2 - xu2 * xv1
            n1 = xu2 * xv0 - xu0 * xv2
            n2 = xu0 * xv1 - xu1 * xv0
            E = xu0 * xu0 + xu1 * xu1 + xu2 * xu2
            F = xu0 * xv0 + xu1 * xv1 + xu2 * xv2
            G = xv0 * xv0 + xv1 * xv1 + xv2 * xv2
            nn = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            size = np.sqrt(E) + np.sqrt(G)
            if not nn > 1e-10 * size * size:  # singular: filled in by the caller
                o[N_FIELDS - 1] = 1.0
                continue
            o[N_FIELDS - 1] = 0.0
            n0 /= nn
            n1 /= nn
            n2 /= nn
            L = S[2, 0, 0] * n0 + S[2, 0, 1] * n1 + S[2, 0, 2] * n2
            M = S[1, 1, 0] * n0 + S[1, 1, 1] * n1 + S[1, 1, 2] * n2
            N = S[0, 2, 0] * n0 + S[0, 2, 1] * n1 + S[0, 2, 2] * n2
            det1 = E * G - F * F
            # orthonormal frame e1 = Su / |Su|, e2 = n x e1; [Su Sv] = B [[a, b], [0, c]]
            aa = np.sqrt(E)
            e10, e11, e12 = xu0 / aa, xu1 / aa, xu2 / aa
            e20 = n1 * e12 - n2 * e11
            e21 = n2 * e10 - n0 * e12
            e22 = n0 * e11 - n1 * e10
            bb = e10 * xv0 + e11 * xv1 + e12 * xv2
            cc = e20 * xv0 + e21 * xv1 + e22 * xv2
            pp = L / (aa * aa)
            qq = (M - bb * pp * aa) / (aa * cc)
            rr = (N - 2.0 * bb * qq * cc - bb * bb * pp) / (cc * cc)
            m = 0.5 * (pp + rr)
            half = 0.5 * (pp - rr)
            d = np.hypot(half, qq)
            t = 0.5 * np.arctan2(qq, half)
            ct, st = np.cos(t), np.sin(t)
            d10, d11, d12 = ct * e10 + st * e20, ct * e11 + st * e21, ct * e12 + st * e22
            o[3], o[4], o[5] = n0, n1, n2
            o[6], o[7], o[8] = E, F, G
            o[9], o[10], o[11] = L, M, N
            o[12] = (L * N - M * M) / det1
            o[13] = (E * N - 2.0 * F * M + G * L) / (2.0 * det1)
            o[14], o[15] = m + d, m - d
            o[16], o[17], o[18] = d10, d11, d12
            o[19] = n1 * d12 - n2 * d11
            o[20] = n2 * d10 - n0 * d12
            o[21] = n0 * d11 - n1 * d10
            dv1 = st / cc
            dv2 = ct / cc
            o[22], o[23] = (ct - bb * dv1) / aa, dv1
            o[24], o[25] = (-st - bb * dv2) / aa, dv2
            o[26] = (G * L - F * M) / det1
            o[27] = (G * M - F * N) / det1
            o[28] = (E * M - F * L) / det1
            o[29] = (E * N - F * M) / det1
