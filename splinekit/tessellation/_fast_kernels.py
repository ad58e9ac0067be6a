"""Compiled (numba) kernels of the fast B-rep tessellation path (:mod:`.fast_mesh`): the per-call
work between the circle counts and the result, in two passes around the ear clipping.

A small part's call is a fixed cost of numpy calls (about 150 of them, 1-3 us each), not
arithmetic; these kernels do the same steps in two calls. Loaded through
:func:`splinekit._kernels.load` (never by ``import splinekit``); :mod:`.fast_mesh` keeps the numpy
path, and both give meshes with the same topology counts and the same guarantees (the
triangulations may differ where rounding of the transcendental functions moves an ear-clipping
choice).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True, inline="always")
def _search(keys, key, lo, hi):
    """First index in ``keys[lo:hi + 1]`` whose key is >= ``key`` (``hi`` if none): the piece."""
    a, b = lo, hi
    while a < b:
        m = (a + b) // 2
        if keys[m] < key:
            a = m + 1
        else:
            b = m
    return a


@njit(cache=True, nogil=True, inline="always")
def _param(q, theta, akey, table, first, last, sweep, full):
    th = theta - TWO_PI * math.floor(theta / TWO_PI)
    if not full and th > 0.5 * (sweep[q] + TWO_PI):
        th -= TWO_PI
    k = _search(akey, 8.0 * q + th, first[q], last[q])
    lo, span, mid, lam, tq = table[k, 0], table[k, 1], table[k, 2], table[k, 3], table[k, 4]
    s = 0.5 * (math.tan(0.5 * (th - mid)) / tq + 1.0)
    return lo + span * (lam * s / ((1.0 - s) + lam * s))


@njit(cache=True, nogil=True, inline="always")
def _angle(q, t, tkey, table, first, last, t0, t1):
    k = _search(tkey, 2.0 * q + (t - t0[q]) / (t1[q] - t0[q]), first[q], last[q])
    lo, span, mid, lam, tq = table[k, 0], table[k, 1], table[k, 2], table[k, 3], table[k, 4]
    x = (t - lo) / span
    s = x / (x + lam * (1.0 - x))
    return mid + 2.0 * math.atan(tq * (2.0 * s - 1.0))


@njit(cache=True, nogil=True)
def points(n, n_corners, use_face, use_arc, use_flip, start_vid, start_X, use_uv0, use_slot, use_off, use_sense,
           arc_c, arc_r, arc_e1, arc_e2, arc_sweep, A, b, akey, table, first, last, sweep, full):  # fmt: skip
    """The loops' points (every use's samples in its own direction, its last one left to the
    next use): ``(cnt (U,), ustart (U,), vid (P,), X (P, 3), uv (P, 2), face (P,), n_vid)``."""
    U = use_face.size
    cnt = np.empty(U, np.int64)
    ustart = np.empty(U, np.int64)
    total = 0
    for i in range(U):
        cnt[i] = 1 if use_arc[i] < 0 else n[use_arc[i]]
        ustart[i] = total
        total += cnt[i]
    abase = np.empty(n.size, np.int64)
    nv = n_corners
    for a in range(n.size):
        abase[a] = nv
        nv += n[a] - 1
    vid = np.empty(total, np.int64)
    X = np.empty((total, 3))
    uv = np.empty((total, 2))
    face = np.empty(total, np.int64)
    for i in range(U):
        s, f, a = ustart[i], use_face[i], use_arc[i]
        vid[s] = start_vid[i]
        for d in range(3):
            X[s, d] = start_X[i, d]
        uv[s, 0], uv[s, 1] = use_uv0[i, 0], use_uv0[i, 1]
        for k in range(cnt[i]):
            face[s + k] = f
        if a < 0:
            continue
        na = n[a]
        for k in range(1, na):
            kk = na - k if use_flip[i] else k
            th = arc_sweep[a] * kk / na
            c, sn = math.cos(th), math.sin(th)
            p = s + k
            vid[p] = abase[a] + kk - 1
            for d in range(3):
                X[p, d] = arc_c[a, d] + arc_r[a] * (c * arc_e1[a, d] + sn * arc_e2[a, d])
            q = use_slot[i]
            if q >= 0:
                uv[p, 0] = _param(q, use_off[i] + use_sense[i] * th, akey, table, first, last, sweep, full)
                uv[p, 1] = use_uv0[i, 1]
            else:
                for r in range(2):
                    uv[p, r] = A[f, r, 0] * X[p, 0] + A[f, r, 1] * X[p, 1] + A[f, r, 2] * X[p, 2] + b[f, r]
    return cnt, ustart, vid, X, uv, face, nv


@njit(cache=True, nogil=True)
def _chain(uses, slots, q, ustart, cnt, out):
    """Point indices of slot ``q``'s chain (its uses' points in order) into ``out``; returns the count."""
    m = 0
    for j in range(uses.size):
        if slots[j] == q:
            i = uses[j]
            for k in range(cnt[i]):
                out[m] = ustart[i] + k
                m += 1
    return m


@njit(cache=True, nogil=True)
def strip(bp, nb, tp, nt, uv, lo, span, T, w):
    """Rows ``w ..`` of ``T``: the counter-clockwise triangles of the strip between the bottom
    chain ``bp[:nb]`` and the top chain ``tp[:nt]`` (point indices, both in increasing ``u`` =
    ``uv[:, 0]``, sharing their end ``u``): the chain whose next point comes first advances,
    the bottom on ties within 1e-9 of the span (as :func:`.fast_mesh._zipper`). Returns the
    next free row."""
    i = j = 0
    while i < nb - 1 or j < nt - 1:
        bottom = j == nt - 1 or (i < nb - 1 and (uv[bp[i + 1], 0] - lo) / span - 1e-9 <= (uv[tp[j + 1], 0] - lo) / span)
        T[w, 0] = bp[i]
        if bottom:  # (b_i, b_i+1, t_j)
            T[w, 1] = bp[i + 1]
            T[w, 2] = tp[j]
            i += 1
        else:  # (b_i, t_j+1, t_j)
            T[w, 1] = tp[j + 1]
            T[w, 2] = tp[j]
            j += 1
        w += 1
    return w


@njit(cache=True, nogil=True)
def finish(tol, angle_tol, ustart, cnt, vid, X, uv, face, n_vid, fixed_T, fixed_face, face_first_use, Tp, wanted,
           cp_first_use, cp_loop_uses, zb_use, zb_slot, zt_use, zt_slot, slot_lo, slot_hi, slot_radius, slot_centre,
           slot_axis, slot_sign, tkey, table, first, last, t0, t1, normal, reversed_, slot_of_face, plane_offset):  # fmt: skip
    """Triangles and vertices of the mesh: ``(ok, T (t, 3) vertex ids, corner_uv (t, 3, 2),
    face of each triangle, V, N, UV, VP, max_dev)``; ``ok`` False where the caller must fall
    back (ear clipping not a triangulation, a deviation or an angle over the limit)."""
    F = face_first_use.size
    # planes with circles: the ear clipping checked (count, orientation, areas per face)
    ok = Tp.shape[0] == wanted
    got = np.zeros(F)
    for t in range(Tp.shape[0]):
        i, j, k = Tp[t, 0], Tp[t, 1], Tp[t, 2]
        ar = (uv[j, 0] - uv[i, 0]) * (uv[k, 1] - uv[i, 1]) - (uv[j, 1] - uv[i, 1]) * (uv[k, 0] - uv[i, 0])
        if not ar > 0:
            ok = False
        got[face[i]] += ar
    poly = np.zeros(F)
    for L in range(cp_first_use.size):
        u0 = cp_first_use[L]
        p0 = ustart[u0]
        m = 0
        for i in range(u0, u0 + cp_loop_uses[L]):
            m += cnt[i]
        for k in range(m):
            i, j = p0 + k, p0 + (k + 1) % m
            poly[face[i]] += uv[i, 0] * uv[j, 1] - uv[j, 0] * uv[i, 1]
    big = 0.0
    for f in range(F):
        big = max(big, abs(poly[f]))
    for f in range(F):
        if abs(got[f] - poly[f]) > 1e-9 * big:
            ok = False
    # cylinders: strips between the bottom and top chains (ties within 1e-9 of the span: bottom)
    n_slots = slot_lo.size
    n_cyl = 0
    bp = np.empty(uv.shape[0], np.int64)
    tp = np.empty(uv.shape[0], np.int64)
    for q in range(n_slots):
        n_cyl += _chain(zb_use, zb_slot, q, ustart, cnt, bp) + _chain(zt_use, zt_slot, q, ustart, cnt, tp) - 2
    n_tri = fixed_T.shape[0] + Tp.shape[0] + n_cyl
    T = np.empty((n_tri, 3), np.int64)  # loop point indices
    tf = np.empty(n_tri, np.int64)
    w = 0
    for t in range(fixed_T.shape[0]):
        s = ustart[face_first_use[fixed_face[t]]]
        for c in range(3):
            T[w, c] = fixed_T[t, c] + s
        tf[w] = fixed_face[t]
        w += 1
    for t in range(Tp.shape[0]):
        for c in range(3):
            T[w, c] = Tp[t, c]
        tf[w] = face[Tp[t, 0]]
        w += 1
    max_dev = plane_offset
    bary = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0]])
    for q in range(n_slots):
        nb = _chain(zb_use, zb_slot, q, ustart, cnt, bp)
        m = 0  # the top chain, reversed into increasing u
        for j in range(zt_use.size - 1, -1, -1):
            if zt_slot[j] == q:
                i = zt_use[j]
                for k in range(cnt[i] - 1, -1, -1):
                    tp[m] = ustart[i] + k
                    m += 1
        nt = m
        f = face[bp[0]]
        w0 = w
        w = strip(bp, nb, tp, nt, uv, slot_lo[q], slot_hi[q] - slot_lo[q], T, w)
        for t in range(w0, w):
            tf[t] = f
            # measured in closed form: S(u, v) = C(u) + (v - v0) D, so only u matters
            th = np.empty(3)
            cs = np.empty((3, 2))
            for c in range(3):
                th[c] = _angle(q, uv[T[t, c], 0], tkey, table, first, last, t0, t1)
                cs[c, 0], cs[c, 1] = math.cos(th[c]), math.sin(th[c])
            if angle_tol > 0 and max(th[0], th[1], th[2]) - min(th[0], th[1], th[2]) > angle_tol * (1.0 + 1e-9):
                ok = False
            for r in range(4):
                ub = bary[r, 0] * uv[T[t, 0], 0] + bary[r, 1] * uv[T[t, 1], 0] + bary[r, 2] * uv[T[t, 2], 0]
                tm = _angle(q, ub, tkey, table, first, last, t0, t1)
                dx = math.cos(tm) - (bary[r, 0] * cs[0, 0] + bary[r, 1] * cs[1, 0] + bary[r, 2] * cs[2, 0])
                dy = math.sin(tm) - (bary[r, 0] * cs[0, 1] + bary[r, 1] * cs[1, 1] + bary[r, 2] * cs[2, 1])
                max_dev = max(max_dev, slot_radius[q] * math.sqrt(dx * dx + dy * dy))
    if max_dev > tol:
        ok = False
    # vertices: the first loop point of each is its representative (face, (u, v), normal)
    rep = np.full(n_vid, -1, np.int64)
    for p in range(vid.size - 1, -1, -1):
        rep[vid[p]] = p
    V = np.empty((n_vid, 3))
    N = np.empty((n_vid, 3))
    UV = np.empty((n_vid, 2))
    VP = np.empty(n_vid, np.int64)
    for v in range(n_vid):
        p = rep[v]
        f = face[p]
        VP[v] = f
        UV[v, 0], UV[v, 1] = uv[p, 0], uv[p, 1]
        for d in range(3):
            V[v, d] = X[p, d]
        q = slot_of_face[f]
        if q < 0:
            for d in range(3):
                N[v, d] = normal[f, d]
        else:
            r = np.empty(3)
            dot = 0.0
            for d in range(3):
                r[d] = X[p, d] - slot_centre[q, d]
                dot += r[d] * slot_axis[q, d]
            length = 0.0
            for d in range(3):
                r[d] -= dot * slot_axis[q, d]
                length += r[d] * r[d]
            length = math.sqrt(length)
            for d in range(3):
                N[v, d] = slot_sign[q] * r[d] / length
    TV = np.empty((n_tri, 3), np.int64)
    CUV = np.empty((n_tri, 3, 2))
    for t in range(n_tri):
        flip = reversed_[tf[t]]
        for c in range(3):
            p = T[t, 3 - c] if flip and c > 0 else T[t, c]  # reversed face: corners 0, 2, 1
            TV[t, c] = vid[p]
            CUV[t, c, 0], CUV[t, c, 1] = uv[p, 0], uv[p, 1]
    return ok, TV, CUV, tf, V, N, UV, VP, max_dev
