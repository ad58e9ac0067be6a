"""Compiled (numba) k-nearest-neighbour search and PCA normals of :mod:`splinekit.pointcloud`.

Loaded through :func:`splinekit._kernels.load`, never by ``import splinekit``. The numpy path
they must agree with is scipy's cKDTree query (:func:`splinekit.pointcloud._cloud.neighbours`)
followed by :func:`splinekit.pointcloud._cloud.covariances` and
:func:`~splinekit.pointcloud._cloud.smallest_eigenpairs`; :mod:`splinekit.pointcloud._pointtree`
drives them. The faster cell grid of :mod:`splinekit.pointcloud._cellgrid_kernels` answers
first; this hierarchy serves the queries the grid cannot settle and clouds no grid fits.

The search structure is a bounding-volume hierarchy over the points sorted along a Morton
curve: leaves of :data:`LEAF` consecutive sorted points, a complete binary tree stored as a heap
(node 1 the root, node ``i`` with children ``2i`` and ``2i + 1``, the leaves ``L .. 2L - 1``).
It adapts to any distribution (clusters, sheets, lines) with no cell size to tune. A query
first takes the ``2k`` points around it in Morton order (nearly always close, so the bound is
tight from the start), then walks the tree nearer child first and skips every box farther than
its current k-th neighbour. Queries run in Morton order too, so consecutive ones touch the same
nodes (the cache-friendly order that makes this faster than cKDTree's own per-point walk).

The normal of a neighbourhood is computed in the same pass as its search, while its points
are still in cache: covariance about the neighbourhood's centroid, then the closed-form
eigen-analysis of :func:`sym3_smallest`. Results are written at each point's original row
(``order[row]``), for the rows asked (all of them, or those the grid left).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._cloud import DEGENERATE  # the threshold of the vectorized eigen-solve, shared

LEAF = 8
"""Sorted points per leaf of the tree."""

_BITS = 21  # Morton bits per axis: 63 in all, a non-negative int64



@njit(cache=True, inline="always")
def _spread(x):
    """The low 21 bits of ``x`` spread out to every third bit."""
    x &= 0x1FFFFF
    x = (x | (x << 32)) & 0x1F00000000FFFF
    x = (x | (x << 16)) & 0x1F0000FF0000FF
    x = (x | (x << 8)) & 0x100F00F00F00F00F
    x = (x | (x << 4)) & 0x10C30C30C30C30C3
    x = (x | (x << 2)) & 0x1249249249249249
    return x


@njit(cache=True, parallel=True)
def morton_codes(P, lo, inv):
    """Morton codes ``(n,)`` int64 of points ``P`` quantized as ``(P - lo) * inv`` (21 bits an axis)."""
    n = P.shape[0]
    out = np.empty(n, dtype=np.int64)
    top = (1 << _BITS) - 1
    for i in prange(n):
        code = 0
        for ax in range(3):
            q = int((P[i, ax] - lo[ax]) * inv[ax])
            q = min(max(q, 0), top)
            code |= _spread(q) << (2 - ax)
        out[i] = code
    return out


@njit(cache=True)
def node_boxes(S, L):
    """Boxes ``(lo (2L, 3), hi (2L, 3))`` of the heap over sorted points ``S`` (:data:`LEAF` a leaf);
    empty leaves (past the last point) get empty boxes (lo = inf, hi = -inf)."""
    n = S.shape[0]
    lo = np.full((2 * L, 3), np.inf)
    hi = np.full((2 * L, 3), -np.inf)
    for j in range(L):
        node = L + j
        for t in range(j * LEAF, min((j + 1) * LEAF, n)):
            for ax in range(3):
                v = S[t, ax]
                if v < lo[node, ax]:
                    lo[node, ax] = v
                if v > hi[node, ax]:
                    hi[node, ax] = v
    for node in range(L - 1, 0, -1):
        for ax in range(3):
            lo[node, ax] = min(lo[2 * node, ax], lo[2 * node + 1, ax])
            hi[node, ax] = max(hi[2 * node, ax], hi[2 * node + 1, ax])
    return lo, hi


@njit(cache=True, inline="always")
def _box_d2(px, py, pz, lo, hi, i):
    dx = max(lo[i, 0] - px, 0.0, px - hi[i, 0])
    dy = max(lo[i, 1] - py, 0.0, py - hi[i, 1])
    dz = max(lo[i, 2] - pz, 0.0, pz - hi[i, 2])
    return dx * dx + dy * dy + dz * dz


@njit(cache=True, inline="always")
def _insert(bd, bi, count, k, d2, j):
    """Insert ``(d2, j)`` into the ascending list ``bd, bi`` of ``count`` entries (at most ``k``);
    equal distances keep their order of arrival. Returns the new count."""
    if count < k:
        pos = count
        count += 1
    else:
        pos = k - 1
    while pos > 0 and bd[pos - 1] > d2:
        bd[pos] = bd[pos - 1]
        bi[pos] = bi[pos - 1]
        pos -= 1
    bd[pos] = d2
    bi[pos] = j
    return count


@njit(cache=True, inline="always")
def _knn_one(S, lo, hi, L, k, i, bd, bi, stack):
    """The ``k`` nearest sorted points of sorted point ``i`` into ``bd`` (squared distances,
    ascending) and ``bi`` (sorted indices); ``i`` itself first."""
    n = S.shape[0]
    px, py, pz = S[i, 0], S[i, 1], S[i, 2]
    bd[0] = 0.0
    bi[0] = i
    count = 1
    # seed: the 2k neighbours in Morton order (a tight first bound)
    a = max(0, i - k)
    b = min(n, i + k + 1)
    for j in range(a, b):
        if j == i:
            continue
        dx, dy, dz = S[j, 0] - px, S[j, 1] - py, S[j, 2] - pz
        d2 = dx * dx + dy * dy + dz * dz
        if count < k or d2 < bd[k - 1]:
            count = _insert(bd, bi, count, k, d2, j)
    sp = 1
    stack[0] = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        worst = bd[k - 1] if count == k else np.inf
        if _box_d2(px, py, pz, lo, hi, node) >= worst:
            continue
        if node >= L:
            first = (node - L) * LEAF
            for j in range(first, min(first + LEAF, n)):
                if a <= j < b:  # seeded already
                    continue
                dx, dy, dz = S[j, 0] - px, S[j, 1] - py, S[j, 2] - pz
                d2 = dx * dx + dy * dy + dz * dz
                if count < k or d2 < bd[k - 1]:
                    count = _insert(bd, bi, count, k, d2, j)
        else:
            c0, c1 = 2 * node, 2 * node + 1
            d0 = _box_d2(px, py, pz, lo, hi, c0)
            d1 = _box_d2(px, py, pz, lo, hi, c1)
            # the farther child goes on the stack first, so the nearer one is searched first
            if d0 <= d1:
                if d1 < worst:
                    stack[sp] = c1
                    sp += 1
                if d0 < worst:
                    stack[sp] = c0
                    sp += 1
            else:
                if d0 < worst:
                    stack[sp] = c0
                    sp += 1
                if d1 < worst:
                    stack[sp] = c1
                    sp += 1
    return count


@njit(cache=True, parallel=True)
def knn(S, order, rows, L, lo, hi, k, out_d, out_idx):
    """``k`` nearest neighbours of the sorted points ``rows``: distances ``out_d (n, k)``
    ascending and original indices ``out_idx (n, k)``, the point itself first, written at the
    point's original row ``order[row]`` (``order``: sorted -> original index). A neighbour that
    could not be found (only with distances overflowing to inf) is left as ``inf`` (index 0)."""
    m = rows.shape[0]
    chunk = 2048
    for c in prange((m + chunk - 1) // chunk):
        stack = np.empty(256, dtype=np.int64)
        bd = np.empty(k)
        bi = np.empty(k, dtype=np.int64)
        for r in range(c * chunk, min(m, (c + 1) * chunk)):
            i = rows[r]
            count = _knn_one(S, lo, hi, L, k, i, bd, bi, stack)
            o = order[i]
            for j in range(k):
                if j < count:
                    out_d[o, j] = np.sqrt(bd[j])
                    out_idx[o, j] = order[bi[j]]
                else:
                    out_d[o, j] = np.inf
                    out_idx[o, j] = 0


@njit(cache=True, inline="always")
def sym3_smallest(a, b, c, d, e, f, out):
    """Eigenvalues of the symmetric matrix ``[[a, d, f], [d, b, e], [f, e, c]]`` ascending into
    ``out[0:3]`` and a unit eigenvector of the smallest into ``out[3:6]``.

    The scalar form of :func:`splinekit.pointcloud._cloud.smallest_eigenpairs` (the
    trigonometric roots of the characteristic cubic, the eigenvector as the longest cross
    product of two rows of ``C - lambda_min I``), with the same fallback where the two
    smallest eigenvalues coincide (every cross product is rounding noise): a unit vector
    orthogonal to the longest row, which then spans the third eigenvector's direction.
    """
    q = (a + b + c) / 3.0
    aq, bq, cq = a - q, b - q, c - q
    p1 = d * d + e * e + f * f
    p = np.sqrt((aq * aq + bq * bq + cq * cq + 2.0 * p1) / 6.0)
    if p > 0.0:
        r = (aq * (bq * cq - e * e) - d * (d * cq - e * f) + f * (d * e - bq * f)) / (2.0 * p * p * p)
        r = min(max(r, -1.0), 1.0)
        phi = np.arccos(r) / 3.0
        top = q + 2.0 * p * np.cos(phi)
        low = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    else:
        top = low = q
    out[0] = low
    out[1] = 3.0 * q - top - low
    out[2] = top
    r0x, r0y, r0z = a - low, d, f
    r1x, r1y, r1z = d, b - low, e
    r2x, r2y, r2z = f, e, c - low
    best = -1.0
    vx = vy = vz = 0.0
    for pair in range(3):
        if pair == 0:
            ux, uy, uz, wx, wy, wz = r0x, r0y, r0z, r1x, r1y, r1z
        elif pair == 1:
            ux, uy, uz, wx, wy, wz = r0x, r0y, r0z, r2x, r2y, r2z
        else:
            ux, uy, uz, wx, wy, wz = r1x, r1y, r1z, r2x, r2y, r2z
        cx = uy * wz - uz * wy
        cy = uz * wx - ux * wz
        cz = ux * wy - uy * wx
        nn = cx * cx + cy * cy + cz * cz
        if nn > best:
            best, vx, vy, vz = nn, cx, cy, cz
    # the longest row, for the degenerate fallback and its threshold
    l0 = r0x * r0x + r0y * r0y + r0z * r0z
    l1 = r1x * r1x + r1y * r1y + r1z * r1z
    l2 = r2x * r2x + r2y * r2y + r2z * r2z
    if l0 >= l1 and l0 >= l2:
        gx, gy, gz, gl = r0x, r0y, r0z, l0
    elif l1 >= l2:
        gx, gy, gz, gl = r1x, r1y, r1z, l1
    else:
        gx, gy, gz, gl = r2x, r2y, r2z, l2
    if best <= (DEGENERATE * gl) ** 2:
        # rank one (or zero): any vector orthogonal to the longest row; cross it with the axis
        # it has least of
        ax, ay, az = abs(gx), abs(gy), abs(gz)
        if ax <= ay and ax <= az:
            vx, vy, vz = 0.0, gz, -gy
        elif ay <= az:
            vx, vy, vz = -gz, 0.0, gx
        else:
            vx, vy, vz = gy, -gx, 0.0
        best = vx * vx + vy * vy + vz * vz
        if best == 0.0:  # the zero matrix: every direction is an eigenvector
            vx, vy, vz, best = 0.0, 0.0, 1.0, 1.0
    s = 1.0 / np.sqrt(best)
    out[3] = vx * s
    out[4] = vy * s
    out[5] = vz * s


@njit(cache=True, parallel=True)
def knn_normals(S, order, rows, L, lo, hi, k, out_values, out_normals, out_kth, out_idx, want_idx):
    """PCA normals of the sorted points ``rows`` over their ``k`` nearest neighbours.

    Writes, at the point's original row ``order[row]``: the covariance eigenvalues ascending
    ``out_values (n, 3)`` (length^2), the unit eigenvector of the smallest ``out_normals (n, 3)``,
    the squared distance to the k-th neighbour ``out_kth (n,)`` (inf when distances overflow)
    and, when ``want_idx``, the original neighbour indices ``out_idx (n, k)``, the point itself first.
    """
    m = rows.shape[0]
    chunk = 2048
    for c in prange((m + chunk - 1) // chunk):
        stack = np.empty(256, dtype=np.int64)
        bd = np.empty(k)
        bi = np.empty(k, dtype=np.int64)
        eig = np.empty(6)
        for r in range(c * chunk, min(m, (c + 1) * chunk)):
            i = rows[r]
            o = order[i]
            count = _knn_one(S, lo, hi, L, k, i, bd, bi, stack)
            if count < k:
                out_kth[o] = np.inf
                for j in range(3):
                    out_values[o, j] = 0.0
                    out_normals[o, j] = 0.0
                continue
            out_kth[o] = bd[k - 1]
            if want_idx:
                for j in range(k):
                    out_idx[o, j] = order[bi[j]]
            mx = my = mz = 0.0
            for j in range(k):
                t = bi[j]
                mx += S[t, 0]
                my += S[t, 1]
                mz += S[t, 2]
            mx /= k
            my /= k
            mz /= k
            sxx = syy = szz = sxy = syz = sxz = 0.0
            for j in range(k):
                t = bi[j]
                x, y, z = S[t, 0] - mx, S[t, 1] - my, S[t, 2] - mz
                sxx += x * x
                syy += y * y
                szz += z * z
                sxy += x * y
                syz += y * z
                sxz += x * z
            sym3_smallest(sxx / k, syy / k, szz / k, sxy / k, syz / k, sxz / k, eig)
            for j in range(3):
                out_values[o, j] = eig[j]
                out_normals[o, j] = eig[3 + j]
