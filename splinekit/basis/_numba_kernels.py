"""Compiled kernels for the hot evaluation paths (numba, ``cache=True``).

This module imports numba and is itself imported only through
:func:`splinekit._kernels.load` for large evaluations, never when
splinekit is imported. Each kernel performs, per point, exactly the floating-
point operations of the numpy path in the same order (span search, the A2.2
triangle, the sequential sum over local basis functions), so both paths give
the same numbers; the grid kernel sums over the v basis functions where the
numpy path calls BLAS, which agrees to rounding.

Points are processed in chunks under ``prange`` so each thread allocates its
scratch arrays once per chunk, not once per point.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

_CHUNK = 2048


@njit(cache=True, inline="always")
def _span(U, lo, hi, x):
    """Largest i with U[i] <= x, clipped to [lo, hi] (same as the numpy find_span)."""
    if x >= U[hi]:
        return hi
    if x < U[lo + 1]:
        return lo
    a, b = lo, hi
    while b - a > 1:
        mid = (a + b) // 2
        if U[mid] <= x:
            a = mid
        else:
            b = mid
    return a


@njit(cache=True, inline="always")
def _basis(U, p, span, x, N, left, right):
    """A2.2 into N[0..p], with the numpy path's operation order."""
    for j in range(1, p + 1):
        left[j] = x - U[span + 1 - j]
        right[j] = U[span + j] - x
    N[0] = 1.0
    for j in range(1, p + 1):
        saved = 0.0
        for r in range(j):
            temp = N[r] / (right[r + 1] + left[j - r])
            N[r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        N[j] = saved


@njit(cache=True, parallel=True)
def curve_points(p, U, lo, hi, C, u, rational, out):
    """out[m, :dim] = sum_r N_r(u_m) C[span - p + r] (divided by the weight if rational)."""
    m = u.shape[0]
    k = C.shape[1]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        N = np.empty(p + 1)
        left = np.empty(p + 1)
        right = np.empty(p + 1)
        acc = np.empty(k)
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            x = u[i]
            s = _span(U, lo, hi, x)
            _basis(U, p, s, x, N, left, right)
            base = s - p
            for d in range(k):
                acc[d] = N[0] * C[base, d]
            for r in range(1, p + 1):
                for d in range(k):
                    acc[d] = acc[d] + N[r] * C[base + r, d]
            if rational:
                for d in range(k - 1):
                    out[i, d] = acc[d] / acc[k - 1]
            else:
                for d in range(k):
                    out[i, d] = acc[d]


@njit(cache=True, parallel=True)
def surface_points(pu, Uu, lou, hiu, pv, Uv, lov, hiv, C, u, v, rational, out):
    """Pointwise tensor-product evaluation; C is (nu, nv, k)."""
    m = u.shape[0]
    k = C.shape[2]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        Nu = np.empty(pu + 1)
        Nv = np.empty(pv + 1)
        left = np.empty(max(pu, pv) + 1)
        right = np.empty(max(pu, pv) + 1)
        acc = np.empty(k)
        inner = np.empty(k)
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            su = _span(Uu, lou, hiu, u[i])
            sv = _span(Uv, lov, hiv, v[i])
            _basis(Uu, pu, su, u[i], Nu, left, right)
            _basis(Uv, pv, sv, v[i], Nv, left, right)
            bu, bv = su - pu, sv - pv
            for a in range(pu + 1):
                for d in range(k):
                    inner[d] = Nv[0] * C[bu + a, bv, d]
                for b in range(1, pv + 1):
                    for d in range(k):
                        inner[d] = inner[d] + Nv[b] * C[bu + a, bv + b, d]
                if a == 0:
                    for d in range(k):
                        acc[d] = Nu[0] * inner[d]
                else:
                    for d in range(k):
                        acc[d] = acc[d] + Nu[a] * inner[d]
            if rational:
                for d in range(k - 1):
                    out[i, d] = acc[d] / acc[k - 1]
            else:
                for d in range(k):
                    out[i, d] = acc[d]


@njit(cache=True, parallel=True)
def surface_points4(pu, Uu, lou, hiu, pv, Uv, lov, hiv, C, u, v, n_out, divide, out):
    """``surface_points`` for nets with 4 coefficient columns (3-D rational, or
    narrower nets padded with zeros), with scalar accumulators. Same
    operation order as the numpy path."""
    m = u.shape[0]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        Nu = np.empty(pu + 1)
        Nv = np.empty(pv + 1)
        left = np.empty(max(pu, pv) + 1)
        right = np.empty(max(pu, pv) + 1)
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            su = _span(Uu, lou, hiu, u[i])
            sv = _span(Uv, lov, hiv, v[i])
            _basis(Uu, pu, su, u[i], Nu, left, right)
            _basis(Uv, pv, sv, v[i], Nv, left, right)
            bu, bv = su - pu, sv - pv
            a0 = a1 = a2 = a3 = 0.0
            for a in range(pu + 1):
                w = Nv[0]
                row = bu + a
                i0 = w * C[row, bv, 0]
                i1 = w * C[row, bv, 1]
                i2 = w * C[row, bv, 2]
                i3 = w * C[row, bv, 3]
                for b in range(1, pv + 1):
                    w = Nv[b]
                    i0 = i0 + w * C[row, bv + b, 0]
                    i1 = i1 + w * C[row, bv + b, 1]
                    i2 = i2 + w * C[row, bv + b, 2]
                    i3 = i3 + w * C[row, bv + b, 3]
                w = Nu[a]
                if a == 0:
                    a0, a1, a2, a3 = w * i0, w * i1, w * i2, w * i3
                else:
                    a0 = a0 + w * i0
                    a1 = a1 + w * i1
                    a2 = a2 + w * i2
                    a3 = a3 + w * i3
            if divide:
                a0 = a0 / a3
                a1 = a1 / a3
                a2 = a2 / a3
            out[i, 0] = a0
            if n_out > 1:
                out[i, 1] = a1
            if n_out > 2:
                out[i, 2] = a2
            if n_out > 3:
                out[i, 3] = a3


@njit(cache=True, parallel=True)
def grid_tensor4(C, su, Nu, p, sv, Nv, q, n_out, divide, out):
    """Tensor-grid evaluation for nets with 4 coefficient columns (3-D rational,
    or narrower nets padded with zeros).

    For each grid row i: ``row = sum_a Nu[a, i] C[su[i] - p + a]`` (the net
    contracted in u, kept in a small contiguous buffer), then for each j
    ``out[i, j] = sum_b Nv[b, j] row[sv[j] - q + b]``; scalar accumulators stay
    in registers. Writes ``n_out`` columns; ``divide`` divides columns 0-2 by
    column 3 (through one reciprocal, within an ulp of three divisions).
    """
    mu = su.shape[0]
    mv = sv.shape[0]
    nv = C.shape[1]
    for i in prange(mu):
        row = np.empty(nv * 4)
        bu = su[i] - p
        for l in range(nv):
            w = Nu[0, i]
            r0 = w * C[bu, l, 0]
            r1 = w * C[bu, l, 1]
            r2 = w * C[bu, l, 2]
            r3 = w * C[bu, l, 3]
            for a in range(1, p + 1):
                w = Nu[a, i]
                r0 = r0 + w * C[bu + a, l, 0]
                r1 = r1 + w * C[bu + a, l, 1]
                r2 = r2 + w * C[bu + a, l, 2]
                r3 = r3 + w * C[bu + a, l, 3]
            row[4 * l] = r0
            row[4 * l + 1] = r1
            row[4 * l + 2] = r2
            row[4 * l + 3] = r3
        for j in range(mv):
            base = 4 * (sv[j] - q)
            w = Nv[0, j]
            a0 = w * row[base]
            a1 = w * row[base + 1]
            a2 = w * row[base + 2]
            a3 = w * row[base + 3]
            for b in range(1, q + 1):
                w = Nv[b, j]
                o = base + 4 * b
                a0 = a0 + w * row[o]
                a1 = a1 + w * row[o + 1]
                a2 = a2 + w * row[o + 2]
                a3 = a3 + w * row[o + 3]
            if divide:
                inv = 1.0 / a3
                a0 = a0 * inv
                a1 = a1 * inv
                a2 = a2 * inv
            out[i, j, 0] = a0
            if n_out > 1:
                out[i, j, 1] = a1
            if n_out > 2:
                out[i, j, 2] = a2
            if n_out > 3:
                out[i, j, 3] = a3


@njit(cache=True, parallel=True)
def grid_rows(R, sv, Nv, q, rational, out):
    """out[i, j] = sum_b Nv[b, j] R[i, sv[j] - q + b] (divided by the weight if rational).

    R is (mu, nv, k): the control net already contracted with the u basis.
    """
    mu = R.shape[0]
    mv = sv.shape[0]
    k = R.shape[2]
    for i in prange(mu):
        acc = np.empty(k)
        for j in range(mv):
            base = sv[j] - q
            for d in range(k):
                acc[d] = Nv[0, j] * R[i, base, d]
            for b in range(1, q + 1):
                w = Nv[b, j]
                for d in range(k):
                    acc[d] = acc[d] + w * R[i, base + b, d]
            if rational:
                for d in range(k - 1):
                    out[i, j, d] = acc[d] / acc[k - 1]
            else:
                for d in range(k):
                    out[i, j, d] = acc[d]


@njit(cache=True, parallel=True)
def grid_normals4(C, su, Nu, p, sv, Nv, q, rational, noise, out, weak):
    """Unit normals on a tensor grid for nets with 4 coefficient columns.

    ``Nu`` is ``(2, p + 1, mu)`` (values and first derivatives), ``Nv`` likewise.
    Per grid row the net is contracted in u twice (value and u-derivative);
    per point the homogeneous value H and partials Hu, Hv give
    ``Su ~ Hu - wu C`` and ``Sv ~ Hv - wv C`` (positive factors dropped), whose
    cross product is normalized. Points where ``|Su x Sv| <= 1e-10 (|Su| + |Sv|)^2``, or
    where a partial is no longer than ``noise`` (round-off; times the weight, as the partials
    here carry it), are flagged in ``weak`` for the caller's limit-normal rule.
    """
    mu = su.shape[0]
    mv = sv.shape[0]
    nv = C.shape[1]
    for i in prange(mu):
        row = np.empty((2, nv * 4))
        bu = su[i] - p
        for t in range(2):
            for l in range(nv):
                for d in range(4):
                    acc = Nu[t, 0, i] * C[bu, l, d]
                    for a in range(1, p + 1):
                        acc = acc + Nu[t, a, i] * C[bu + a, l, d]
                    row[t, 4 * l + d] = acc
        for j in range(mv):
            base = 4 * (sv[j] - q)
            h0 = h1 = h2 = h3 = 0.0
            u0 = u1 = u2 = u3 = 0.0
            v0 = v1 = v2 = v3 = 0.0
            for b in range(q + 1):
                o = base + 4 * b
                w = Nv[0, b, j]
                dw = Nv[1, b, j]
                h0 += w * row[0, o]
                h1 += w * row[0, o + 1]
                h2 += w * row[0, o + 2]
                h3 += w * row[0, o + 3]
                u0 += w * row[1, o]
                u1 += w * row[1, o + 1]
                u2 += w * row[1, o + 2]
                u3 += w * row[1, o + 3]
                v0 += dw * row[0, o]
                v1 += dw * row[0, o + 1]
                v2 += dw * row[0, o + 2]
                v3 += dw * row[0, o + 3]
            if rational:
                c0 = h0 / h3
                c1 = h1 / h3
                c2 = h2 / h3
                u0 -= u3 * c0
                u1 -= u3 * c1
                u2 -= u3 * c2
                v0 -= v3 * c0
                v1 -= v3 * c1
                v2 -= v3 * c2
            n0 = u1 * v2 - u2 * v1
            n1 = u2 * v0 - u0 * v2
            n2 = u0 * v1 - u1 * v0
            length = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            lu = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
            lv = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
            size = lu + lv
            if length <= 1e-10 * size * size or length == 0.0 or min(lu, lv) <= noise * (h3 if rational else 1.0):
                weak[i, j] = True
                out[i, j, 0] = 0.0
                out[i, j, 1] = 0.0
                out[i, j, 2] = 0.0
            else:
                weak[i, j] = False
                inv = 1.0 / length
                out[i, j, 0] = n0 * inv
                out[i, j, 1] = n1 * inv
                out[i, j, 2] = n2 * inv


@njit(cache=True, inline="always")
def _basis_ders(U, p, span, x, order, ndu, a, left, right, ders):
    """A2.3 into ders[0..order, 0..p] with the numpy path's operation order."""
    for j in range(1, p + 1):
        left[j] = x - U[span + 1 - j]
        right[j] = U[span + j] - x
    ndu[0, 0] = 1.0
    for j in range(1, p + 1):
        saved = 0.0
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    for r in range(p + 1):
        ders[0, r] = ndu[r, p]
        for k in range(1, order + 1):
            ders[k, r] = 0.0
    top = min(order, p)
    for r in range(p + 1):
        s1, s2 = 0, 1
        a[0, 0] = 1.0
        for k in range(1, top + 1):
            d = 0.0
            rk, pk = r - k, p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d = d + a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d = d + a[s2, k] * ndu[r, pk]
            ders[k, r] = d
            s1, s2 = s2, s1
    factor = float(p)
    for k in range(1, top + 1):
        for r in range(p + 1):
            ders[k, r] *= factor
        factor *= p - k


@njit(cache=True, parallel=True)
def curve_derivatives(p, U, lo, hi, C, u, order, rational, binom, out):
    """Derivatives 0..order at each u: ``out`` is ``(order + 1, m, dim)``.

    Homogeneous sums as in the numpy path, then, if ``rational``, the quotient
    rule of A4.2 (``binom[k, i] = C(k, i)``) in the order of
    :func:`splinekit.basis.rational.rational_curve_derivatives`.
    """
    m = u.shape[0]
    kdim = C.shape[1]
    n_chunks = (m + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        ndu = np.empty((p + 1, p + 1))
        a = np.empty((2, p + 1))
        left = np.empty(p + 1)
        right = np.empty(p + 1)
        ders = np.empty((order + 1, p + 1))
        h = np.empty((order + 1, kdim))
        for i in range(c * _CHUNK, min(m, (c + 1) * _CHUNK)):
            x = u[i]
            s = _span(U, lo, hi, x)
            _basis_ders(U, p, s, x, order, ndu, a, left, right, ders)
            base = s - p
            for k in range(order + 1):
                for d in range(kdim):
                    acc = ders[k, 0] * C[base, d]
                    for r in range(1, p + 1):
                        acc = acc + ders[k, r] * C[base + r, d]
                    h[k, d] = acc
            if not rational:
                for k in range(order + 1):
                    for d in range(kdim):
                        out[k, i, d] = h[k, d]
                continue
            w0 = h[0, kdim - 1]
            for k in range(order + 1):
                for d in range(kdim - 1):
                    v = h[k, d]
                    for j in range(1, k + 1):
                        v -= binom[k, j] * h[j, kdim - 1] * out[k - j, i, d]
                    out[k, i, d] = v / w0
