"""Compiled (numba) k-nearest-neighbour search and PCA normals on a uniform cell grid.

Loaded through :func:`splinekit._kernels.load`, never by ``import splinekit``;
:mod:`splinekit.pointcloud._pointtree` drives it and falls back to the Morton-ordered hierarchy
of :mod:`splinekit.pointcloud._knn_kernels` where a grid does not fit.

The grid has cubic cells of side ``h`` from the cloud's lower corner ``lo``, ``nx * ny * nz``
of them, numbered ``cx + nx * (cy + ny * cz)`` (x fastest). A counting sort puts the points in
cell order and ``start[c] .. start[c + 1]`` is the run of cell ``c``; so the three cells
``cx - 1 .. cx + 1`` of one (y, z) row are one contiguous run, and the 27 cells around a
point are nine runs read straight through (no tree to walk, no box tests). ``h`` is chosen
(by the caller) so that those 27 cells hold the k nearest neighbours of nearly every point.

A query scans the block of 27 cells into a max-heap of its ``k`` best (a replacement costs
``log2 k`` moves, the candidates are not sorted), then checks the block was wide enough: the
k-th distance must not exceed the distance from the point to the block's boundary (a side on
the border of the grid bounds nothing, no point lies beyond it). If it does, the shell of
cells at distance 2 is scanned too (a 5 x 5 x 5 block); a query still not settled is flagged
for the hierarchy. The normal is computed while the neighbourhood is in cache, and every
result is written at the point's original index (no unsorting pass afterwards).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import _knn_kernels as hierarchy  # the fallback search; its eigen-solve is shared
from ._knn_kernels import _insert, sym3_smallest

CHUNK = 1024
"""Consecutive grid-sorted points per parallel task (equal tasks, spread over the threads)."""


@njit(cache=True, inline="always")
def _cell(x, lo, inv, n_cells):
    """Cell number along one axis of coordinate ``x``, clamped into ``[0, n_cells)``."""
    c = int((x - lo) * inv)
    return min(max(c, 0), n_cells - 1)


@njit(cache=True, inline="always")
def _key(P, i, lo, inv, dims):
    """Cell number of point ``P[i]``."""
    nx, ny = dims[0], dims[1]
    return _cell(P[i, 0], lo[0], inv, nx) + nx * (_cell(P[i, 1], lo[1], inv, ny) + ny * _cell(P[i, 2], lo[2], inv, dims[2]))


@njit(cache=True)
def occupied_cells(P, lo, h, dims):
    """Number of non-empty cells of the grid of side ``h`` (``dims``: cells per axis)."""
    inv = 1.0 / h
    seen = np.zeros(dims[0] * dims[1] * dims[2], dtype=np.uint8)
    count = 0
    for i in range(P.shape[0]):
        key = _key(P, i, lo, inv, dims)
        if seen[key] == 0:
            seen[key] = 1
            count += 1
    return count


@njit(cache=True)
def bounds(P):
    """Lower and upper corners ``(3,), (3,)`` of the box of ``P (n, 3)`` (one pass; numpy's
    reduction along the short axis of an ``(n, 3)`` array is several times slower)."""
    lo = P[0].copy()
    hi = P[0].copy()
    for i in range(1, P.shape[0]):
        for ax in range(3):
            lo[ax] = min(lo[ax], P[i, ax])
            hi[ax] = max(hi[ax], P[i, ax])
    return lo, hi


@njit(cache=True)
def build(P, lo, h, dims):
    """Counting sort of ``P (n, 3)`` by cell: ``(S (n, 3) the points in cell order, order (n,)
    grid position -> original index, start (cells + 1,) the run of each cell, crowding)``, where
    ``crowding`` is the mean number of points in a point's own cell (sum of squared counts / n).
    Cell numbers are computed twice rather than stored (cheaper than another n-array)."""
    n = P.shape[0]
    inv = 1.0 / h
    cells = dims[0] * dims[1] * dims[2]
    start = np.zeros(cells + 1, dtype=np.int64)
    for i in range(n):
        start[_key(P, i, lo, inv, dims)] += 1
    crowding = 0.0
    for c in range(cells):
        crowding += float(start[c]) * start[c]
    for c in range(1, cells):  # start[c] = end of cell c
        start[c] += start[c - 1]
    start[cells] = n
    order = np.empty(n, dtype=np.int64)
    S = np.empty((n, 3))
    for i in range(n - 1, -1, -1):  # filled from each cell's end: start[c] ends at its beginning
        key = _key(P, i, lo, inv, dims)
        pos = start[key] - 1
        start[key] = pos
        order[pos] = i
        S[pos, 0] = P[i, 0]
        S[pos, 1] = P[i, 1]
        S[pos, 2] = P[i, 2]
    return S, order, start, crowding / max(n, 1)


@njit(cache=True, inline="always")
def _scan(S, i, a, b, bd, bi, count, k):
    """Offer grid-sorted points ``a .. b - 1`` (but ``i``) to the ascending list ``bd, bi`` of
    point ``i``'s best ``count`` (at most ``k``); returns the new count."""
    px, py, pz = S[i, 0], S[i, 1], S[i, 2]
    for j in range(a, b):
        dx, dy, dz = S[j, 0] - px, S[j, 1] - py, S[j, 2] - pz
        d2 = dx * dx + dy * dy + dz * dz
        if j != i and (count < k or d2 < bd[k - 1]):
            count = _insert(bd, bi, count, k, d2, j)
    return count


@njit(cache=True, inline="always")
def _slack(x, lo, h, c, r, n_cells):
    """Distance from coordinate ``x`` (in cell ``c``) to the nearer face of the block of cells
    ``c - r .. c + r`` along one axis; a face on the border of the grid bounds nothing (inf)."""
    below = x - (lo + (c - r) * h) if c - r > 0 else np.inf
    above = (lo + (c + r + 1) * h) - x if c + r < n_cells - 1 else np.inf
    return min(below, above)


@njit(cache=True, inline="always")
def _settled(S, i, lo, h, guard, cx, cy, cz, r, dims, worst):
    """True when no point outside the block of radius ``r`` (cells) around point ``i`` can be
    nearer than ``worst`` (squared), with ``guard`` (length) for the rounding of cell numbers."""
    g = min(_slack(S[i, 0], lo[0], h, cx, r, dims[0]), _slack(S[i, 1], lo[1], h, cy, r, dims[1]),
            _slack(S[i, 2], lo[2], h, cz, r, dims[2])) - guard
    return g > 0.0 and worst <= g * g


@njit(cache=True, inline="always")
def _cell_of(S, i, lo, inv, dims):
    return _cell(S[i, 0], lo[0], inv, dims[0]), _cell(S[i, 1], lo[1], inv, dims[1]), _cell(S[i, 2], lo[2], inv, dims[2])


@njit(cache=True)
def _query_wide(S, start, lo, h, guard, dims, k, i, bd, bi):
    """The slow path of a query: the ``k`` nearest grid-sorted points of point ``i`` among the
    5 x 5 x 5 cells around it into ``bd, bi`` (ascending, ``i`` first); returns ``k``, or
    ``-1`` when that block does not settle the query (the caller hands it to the hierarchy)."""
    nx, ny, nz = dims[0], dims[1], dims[2]
    cx, cy, cz = _cell_of(S, i, lo, 1.0 / h, dims)
    bd[0] = 0.0
    bi[0] = i
    count = 1
    x0, x1 = max(cx - 2, 0), min(cx + 2, nx - 1)
    for z in range(max(cz - 2, 0), min(cz + 3, nz)):
        for y in range(max(cy - 2, 0), min(cy + 3, ny)):
            row = nx * (y + ny * z)
            count = _scan(S, i, start[row + x0], start[row + x1 + 1], bd, bi, count, k)
    if count == k and _settled(S, i, lo, h, guard, cx, cy, cz, 2, dims, bd[k - 1]):
        return count
    return -1


@njit(cache=True, inline="always")
def _gather(S, start, dims, cx, cy, cz, buf, ids):
    """The points of the 27 cells around cell ``(cx, cy, cz)`` into ``buf (3, m)`` (coordinates,
    one row an axis, so distance loops vectorize) and ``ids (m,)`` (grid-sorted indices), the
    cell's own row first; grows the buffers when they are too small. Returns ``(m, buf, ids)``."""
    nx, ny, nz = dims[0], dims[1], dims[2]
    x0, x1 = max(cx - 1, 0), min(cx + 1, nx - 1)
    m = 0
    for z in range(max(cz - 1, 0), min(cz + 2, nz)):
        for y in range(max(cy - 1, 0), min(cy + 2, ny)):
            row = nx * (y + ny * z)
            m += start[row + x1 + 1] - start[row + x0]
    if m > ids.shape[0]:
        buf = np.empty((3, 2 * m))
        ids = np.empty(2 * m, dtype=np.int64)
    m = 0
    for t in range(9):
        # t = 0 is the cell's own row; the other eight follow
        y, z = cy + (t + 4) % 9 % 3 - 1, cz + (t + 4) % 9 // 3 - 1
        if y < 0 or y >= ny or z < 0 or z >= nz:
            continue
        row = nx * (y + ny * z)
        for j in range(start[row + x0], start[row + x1 + 1]):
            buf[0, m] = S[j, 0]
            buf[1, m] = S[j, 1]
            buf[2, m] = S[j, 2]
            ids[m] = j
            m += 1
    return m, buf, ids


@njit(cache=True, inline="always")
def _select(S, i, m, buf, ids, work, k, guess, bd, bi):
    """The ``k`` nearest of point ``i`` among the ``m`` gathered candidates into ``bd, bi``
    (ascending, ``i`` first); returns the count found (``min(k, m)``).

    Few branches that can mispredict: squared distances to all candidates (a loop that
    vectorizes); a threshold, the previous query's k-th squared distance ``guess``, doubled
    until at least ``k`` candidates fall within it and narrowed while more than ``1.5 k`` do
    (counting passes that vectorize too); the candidates within it compacted without a branch;
    only those (``k`` to ``1.5 k`` of about ``6 k``) go through the ordered insertion. ``work (3, >= m)`` is scratch."""
    px, py, pz = S[i, 0], S[i, 1], S[i, 2]
    d2 = work[0]
    for j in range(m):
        dx, dy, dz = buf[0, j] - px, buf[1, j] - py, buf[2, j] - pz
        d2[j] = dx * dx + dy * dy + dz * dz
    tau = guess if guess > 0.0 else np.inf
    low = 0.0  # a threshold known to hold fewer than k
    while True:
        c = 0
        for j in range(m):
            c += d2[j] <= tau
        if c < k and tau < np.inf:
            low = tau
            tau = tau * 2.0 if tau * 2.0 < np.inf else np.inf
        elif 2 * c > 3 * k and tau > low * 1.0625 and tau < np.inf:
            tau = 0.5 * (tau + low) if low > 0.0 else 0.5 * tau
        else:
            break
    cd, cj = work[1], work[2]
    c = 0
    for j in range(m):  # compaction without a branch: every candidate is written, the kept ones advance
        cd[c] = d2[j]
        cj[c] = j
        c += d2[j] <= tau
    bd[0] = 0.0
    bi[0] = i
    count = 1
    for a in range(c):
        j = ids[int(cj[a])]
        if j != i and (count < k or cd[a] < bd[k - 1]):
            count = _insert(bd, bi, count, k, cd[a], j)
    return count


@njit(cache=True, inline="always")
def _query(S, start, lo, h, guard, dims, k, i, cell, m, buf, ids, work, guess, bd, bi):
    """The ``k`` nearest grid-sorted points of point ``i`` (in ``cell``, whose 27 cells are
    gathered in ``m, buf, ids``) into ``bd, bi``, ascending, ``i`` first; returns ``k``, or
    ``-1`` when even the wide block does not settle the query."""
    count = _select(S, i, m, buf, ids, work, k, guess, bd, bi)
    if count == k and _settled(S, i, lo, h, guard, cell[0], cell[1], cell[2], 1, dims, bd[k - 1]):
        return count
    return _query_wide(S, start, lo, h, guard, dims, k, i, bd, bi)


@njit(cache=True, parallel=True)
def search(S, order, start, lo, h, guard, dims, k, out_d, out_idx, out_kth, out_values, out_normals, unsettled):
    """The ``k`` nearest neighbours of every point, and their PCA normals, on the grid.

    Writes at each point's original row (``order[i]`` for grid-sorted point ``i``): the
    distances ``out_d (n, k)`` ascending and original indices ``out_idx (n, k)`` of its
    neighbours, the point itself first; the squared distance to the k-th ``out_kth (n,)``; the
    eigenvalues of their covariance ascending ``out_values (n, 3)`` (length^2) and the unit
    eigenvector of the smallest ``out_normals (n, 3)``. An output with no rows is skipped.
    ``unsettled (n,)`` (grid order) is set to 1 where the grid could not settle the query:
    that row is left unwritten for the hierarchy.
    """
    n = S.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        buf = np.empty((3, 64 * k))
        ids = np.empty(64 * k, dtype=np.int64)
        work = np.empty((3, 64 * k))
        bd = np.empty(k)
        bi = np.empty(k, dtype=np.int64)
        eig = np.empty(6)
        cell = np.full(3, -1, dtype=np.int64)
        m = 0
        guess = 0.0
        inv = 1.0 / h
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            cx, cy, cz = _cell_of(S, i, lo, inv, dims)
            if cx != cell[0] or cy != cell[1] or cz != cell[2]:  # a new cell: gather its block once
                cell[0], cell[1], cell[2] = cx, cy, cz
                m, buf, ids = _gather(S, start, dims, cx, cy, cz, buf, ids)
                if m > work.shape[1]:
                    work = np.empty((3, ids.shape[0]))
            count = _query(S, start, lo, h, guard, dims, k, i, cell, m, buf, ids, work, guess, bd, bi)
            unsettled[i] = count < 0
            if count < 0:
                continue
            guess = bd[k - 1]
            o = order[i]
            if out_kth.shape[0]:
                out_kth[o] = bd[k - 1]
            if out_d.shape[0]:
                for j in range(k):
                    out_d[o, j] = np.sqrt(bd[j])
            if out_idx.shape[0]:
                for j in range(k):
                    out_idx[o, j] = order[bi[j]]
            if out_normals.shape[0]:
                # one pass over offsets from the query point: they are of the neighbourhood's
                # size, so removing their mean afterwards costs rounding of that size only (as
                # the two-pass form about the centroid would)
                px, py, pz = S[i, 0], S[i, 1], S[i, 2]
                mx = my = mz = sxx = syy = szz = sxy = syz = sxz = 0.0
                for j in range(k):
                    t = bi[j]
                    x, y, z = S[t, 0] - px, S[t, 1] - py, S[t, 2] - pz
                    mx += x
                    my += y
                    mz += z
                    sxx += x * x
                    syy += y * y
                    szz += z * z
                    sxy += x * y
                    syz += y * z
                    sxz += x * z
                mx /= k
                my /= k
                mz /= k
                sxx = sxx / k - mx * mx
                syy = syy / k - my * my
                szz = szz / k - mz * mz
                sxy = sxy / k - mx * my
                syz = syz / k - my * mz
                sxz = sxz / k - mx * mz
                sym3_smallest(sxx, syy, szz, sxy, syz, sxz, eig)
                for j in range(3):
                    out_values[o, j] = eig[j]
                    out_normals[o, j] = eig[3 + j]
