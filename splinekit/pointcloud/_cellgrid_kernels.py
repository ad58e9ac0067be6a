"""Compiled (numba) k-nearest-neighbour search and PCA normals on a uniform cell grid.

Loaded through :func:`splinekit._kernels.load`, never by ``import splinekit``;
:mod:`splinekit.pointcloud._pointtree` drives it and falls back to the Morton-ordered hierarchy
of :mod:`splinekit.pointcloud._knn_kernels` where a grid does not fit.

The grid has cubic cells of side ``h`` from the cloud's lower corner ``lo``, ``dims`` of them
along the axes. Only the cells that hold points matter, so cells are not stored densely:
cell ``(cx, cy, cz)`` goes to slot ``(row(cy, cz) + cx) & mask`` of a table of ``mask + 1``
slots (a power of two, two to four per point), ``row`` a hash of the (y, z) row. Consecutive
cells of a row land in consecutive slots, so after a counting sort of the points by slot
(``start[s] .. start[s + 1]`` the run of slot ``s``) the three cells ``cx - 1 .. cx + 1`` of a
row are one run read straight through (two where it wraps past the last slot), and the 27 cells
around a point are nine runs. Rows that collide share slots: their points are extra candidates,
measured like the others, never missed ones. ``h`` is chosen (by the caller) so that the 27
cells hold the k nearest neighbours of nearly every point; a far outlier that inflates the
bounding box costs nothing, as no cell is stored for empty space.

Queries go cell by cell: the candidates of a cell's 27 cells are gathered once for all its
points (coordinates one row an axis, so distance loops vectorize), and each point selects its
``k`` nearest among them (:func:`_select`). Then the block must have been wide enough: the
k-th distance must not exceed the distance from the point to the block's boundary (a side on
the border of the grid bounds nothing, no point lies beyond it). If it does, the 5 x 5 x 5
block is scanned; a query still not settled is flagged for the hierarchy. The normal is
computed while the neighbourhood is in cache, and every result is written at the point's
original index (no unsorting pass afterwards).
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
def _row(cy, cz):
    """Hash of the (y, z) row of cells: a splitmix-style mix, so that rows near each other
    (which the surface passes through together) land far apart in the table; below 2**62."""
    x = np.uint64(cy) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(cz)
    x ^= x >> np.uint64(30)
    x *= np.uint64(0xBF58476D1CE4E5B9)
    x ^= x >> np.uint64(31)
    return np.int64(x >> np.uint64(2))


@njit(cache=True, inline="always")
def _slot(P, i, lo, inv, dims, mask):
    """Table slot of the cell of point ``P[i]``."""
    cx = _cell(P[i, 0], lo[0], inv, dims[0])
    return (_row(_cell(P[i, 1], lo[1], inv, dims[1]), _cell(P[i, 2], lo[2], inv, dims[2])) + cx) & mask


@njit(cache=True, inline="always")
def _block(mask, cx, cy, cz, r, dims, iv):
    """The table slots of the block of cells ``c - r .. c + r`` around cell ``(cx, cy, cz)``
    as ``n`` disjoint ascending slot ranges ``iv[0, t] .. iv[1, t]`` (returns ``n``): one range
    a row, split where it wraps past the last slot, overlapping ranges (rows that collide)
    merged so that no point is read twice. ``iv (2, >= 2 (2r + 1)^2)`` int64."""
    x0, x1 = max(cx - r, 0), min(cx + r, dims[0] - 1)
    n = 0
    for z in range(max(cz - r, 0), min(cz + r + 1, dims[2])):
        for y in range(max(cy - r, 0), min(cy + r + 1, dims[1])):
            first = (_row(y, z) + x0) & mask
            stop = first + x1 - x0 + 1
            if stop <= mask + 1:
                iv[0, n], iv[1, n] = first, stop
                n += 1
            else:
                iv[0, n], iv[1, n] = first, mask + 1
                iv[0, n + 1], iv[1, n + 1] = 0, stop - mask - 1
                n += 2
    for a in range(1, n):  # insertion sort by start: at most 50 ranges
        s0, s1 = iv[0, a], iv[1, a]
        b = a
        while b > 0 and iv[0, b - 1] > s0:
            iv[0, b], iv[1, b] = iv[0, b - 1], iv[1, b - 1]
            b -= 1
        iv[0, b], iv[1, b] = s0, s1
    merged = 0
    for a in range(n):
        if merged > 0 and iv[0, a] <= iv[1, merged - 1]:
            iv[1, merged - 1] = max(iv[1, merged - 1], iv[1, a])
        else:
            iv[0, merged], iv[1, merged] = iv[0, a], iv[1, a]
            merged += 1
    return merged


@njit(cache=True)
def crowding(P, lo, h, dims, mask):
    """Mean number of points in a point's own cell of the grid of side ``h`` (``dims``: cells
    per axis): the sum of squared counts over ``n``, counted by slot (rows sharing a slot count
    as one cell, as the search reads them)."""
    inv = 1.0 / h
    count = np.zeros(mask + 1, dtype=np.int32)
    total = 0
    for i in range(P.shape[0]):
        key = _slot(P, i, lo, inv, dims, mask)
        total += 2 * count[key] + 1  # (c + 1)^2 - c^2
        count[key] += 1
    return total / max(P.shape[0], 1)


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
def build(P, lo, h, dims, mask):
    """Counting sort of ``P (n, 3)`` by slot: ``(S (n, 3) the points in slot order, order (n,)
    grid position -> original index, start (mask + 2,) the run of each slot, crowding)``, where
    ``crowding`` is the mean number of points in a point's own slot (sum of squared counts / n).
    Slots are computed twice rather than stored (cheaper than another n-array)."""
    n = P.shape[0]
    inv = 1.0 / h
    slots = mask + 1
    start = np.zeros(slots + 1, dtype=np.int64)
    for i in range(n):
        start[_slot(P, i, lo, inv, dims, mask)] += 1
    crowding = 0.0
    for c in range(slots):
        crowding += float(start[c]) * start[c]
    for c in range(1, slots):  # start[c] = end of slot c
        start[c] += start[c - 1]
    start[slots] = n
    order = np.empty(n, dtype=np.int64)
    S = np.empty((n, 3))
    for i in range(n - 1, -1, -1):  # filled from each slot's end: start[c] ends at its beginning
        key = _slot(P, i, lo, inv, dims, mask)
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
    """Cell ``(cx, cy, cz)`` of point ``S[i]``."""
    return _cell(S[i, 0], lo[0], inv, dims[0]), _cell(S[i, 1], lo[1], inv, dims[1]), _cell(S[i, 2], lo[2], inv, dims[2])


@njit(cache=True)
def _query_wide(S, start, lo, h, guard, dims, mask, k, i, bd, bi, iv):
    """The slow path of a query: the ``k`` nearest grid-sorted points of point ``i`` among the
    5 x 5 x 5 cells around it into ``bd, bi`` (ascending, ``i`` first); returns ``k``, or
    ``-1`` when that block does not settle the query (the caller hands it to the hierarchy)."""
    cx, cy, cz = _cell_of(S, i, lo, 1.0 / h, dims)
    bd[0] = 0.0
    bi[0] = i
    count = 1
    for t in range(_block(mask, cx, cy, cz, 2, dims, iv)):
        count = _scan(S, i, start[iv[0, t]], start[iv[1, t]], bd, bi, count, k)
    if count == k and _settled(S, i, lo, h, guard, cx, cy, cz, 2, dims, bd[k - 1]):
        return count
    return -1


@njit(cache=True, inline="always")
def _gather(S, start, dims, mask, cx, cy, cz, buf, ids, iv):
    """The points of the 27 cells around cell ``(cx, cy, cz)`` (and of rows sharing their
    slots) into ``buf (3, m)`` (coordinates, one row an axis, so distance loops vectorize) and
    ``ids (m,)`` (grid-sorted indices); grows the buffers when they are too small. Returns
    ``(m, buf, ids)``."""
    runs = _block(mask, cx, cy, cz, 1, dims, iv)
    m = 0
    for t in range(runs):
        m += start[iv[1, t]] - start[iv[0, t]]
    if m > ids.shape[0]:
        buf = np.empty((3, 2 * m))
        ids = np.empty(2 * m, dtype=np.int64)
    m = 0
    for t in range(runs):
        for j in range(start[iv[0, t]], start[iv[1, t]]):
            buf[0, m] = S[j, 0]
            buf[1, m] = S[j, 1]
            buf[2, m] = S[j, 2]
            ids[m] = j
            m += 1
    return m, buf, ids


@njit(cache=True, inline="always")
def _select(S, i, m, buf, ids, work, k, guess, bd, bi):
    """The ``k`` nearest of point ``i`` among the ``m`` gathered candidates into ``bd, bi``
    (squared distances and grid-sorted indices, ``i`` first); returns the count found
    (``min(k, m)``).

    Few branches that can mispredict: squared distances to all candidates (a loop that
    vectorizes); a threshold, the previous query's k-th squared distance ``guess``, doubled
    until at least ``k`` candidates fall within it and narrowed while more than ``1.5 k`` do
    (counting passes that vectorize too); the candidates within it compacted without a branch;
    of those (``k`` to ``1.5 k`` of about ``7 k``) the farthest dropped one by one. No ordering:
    ``bd, bi`` come out in no particular order after the point itself (an ordered insertion
    of the compacted candidates cost 1.4 times as much; the caller that wants them ascending
    sorts the ``k``).
    ``work (3, >= m)`` is scratch."""
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
        c += (d2[j] <= tau) & (ids[j] != i)  # the point itself is left out: it goes first
    while c > k - 1:  # drop the farthest until k - 1 remain: a few passes over about 1.5 k values
        far = 0
        for a in range(1, c):
            if cd[a] > cd[far]:
                far = a
        c -= 1
        cd[far] = cd[c]
        cj[far] = cj[c]
    bd[0] = 0.0
    bi[0] = i
    for a in range(c):
        bd[a + 1] = cd[a]
        bi[a + 1] = ids[int(cj[a])]
    return c + 1


@njit(cache=True, inline="always")
def _farthest(bd, k):
    worst = bd[0]
    for j in range(1, k):
        worst = max(worst, bd[j])
    return worst


@njit(cache=True, inline="always")
def _query(S, start, lo, h, guard, dims, mask, k, i, cell, m, buf, ids, work, guess, bd, bi, iv):
    """The ``k`` nearest grid-sorted points of point ``i`` (in ``cell``, whose 27 cells are
    gathered in ``m, buf, ids``) into ``bd, bi``, ``i`` first; returns ``k``, or ``-1`` when
    even the wide block does not settle the query."""
    count = _select(S, i, m, buf, ids, work, k, guess, bd, bi)
    if count == k and _settled(S, i, lo, h, guard, cell[0], cell[1], cell[2], 1, dims, _farthest(bd, k)):
        return count
    return _query_wide(S, start, lo, h, guard, dims, mask, k, i, bd, bi, iv)


@njit(cache=True, parallel=True)
def search(S, order, start, lo, h, guard, dims, mask, k, out_d, out_idx, out_kth, out_values, out_normals,
           unsettled):
    """The ``k`` nearest neighbours of every point, and their PCA normals, on the grid.

    Writes at each point's original row (``order[i]`` for grid-sorted point ``i``): the
    distances ``out_d (n, k)`` ascending and original indices ``out_idx (n, k)`` of its
    neighbours, the point itself first (the others in no particular order unless ``out_d`` is
    asked for too); the squared distance to the k-th ``out_kth (n,)``; the
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
        iv = np.empty((2, 50), dtype=np.int64)  # slot ranges of a block, 5 x 5 rows at most
        cell = np.full(3, -1, dtype=np.int64)
        m = 0
        guess = 0.0
        inv = 1.0 / h
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            cx, cy, cz = _cell_of(S, i, lo, inv, dims)
            if cx != cell[0] or cy != cell[1] or cz != cell[2]:  # a new cell: gather its block once
                cell[0], cell[1], cell[2] = cx, cy, cz
                m, buf, ids = _gather(S, start, dims, mask, cx, cy, cz, buf, ids, iv)
                if m > work.shape[1]:
                    work = np.empty((3, ids.shape[0]))
            count = _query(S, start, lo, h, guard, dims, mask, k, i, cell, m, buf, ids, work, guess, bd, bi, iv)
            unsettled[i] = count < 0
            if count < 0:
                continue
            guess = _farthest(bd, k)
            o = order[i]
            if out_kth.shape[0]:
                out_kth[o] = guess
            if out_d.shape[0]:
                # ascending, the point itself (at 0, distance 0) staying first among ties
                # (insertion sort: the point's own entry, distance 0, is never passed)
                for a in range(2, k):
                    _insert(bd, bi, a, k, bd[a], bi[a])
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
