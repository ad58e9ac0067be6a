"""Compiled (numba) exact signed distance of a closed triangle mesh at every sample of a grid:
:meth:`splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.

Since the region scan of :mod:`._gridsdf_scan` took over, this kernel serves meshes with a
triangle too thin for a plane (``MeshDistance.GRID_SCAN`` False: every mesh).

Loaded through :func:`splinekit._kernels.load`. Per sample it answers what
:meth:`~splinekit.pointcloud.meshdistance.MeshDistance.signed` answers (the exact nearest
triangle, sign by the angle-weighted pseudo-normal of its nearest feature), but it walks the
grid as an octree of blocks and the triangle hierarchy (:mod:`._trianglebvh`) together, a
dual-tree traversal: no block queries the hierarchy from its root.

Why: a sample far from the surface (most of a dense grid) needs, to prove its nearest triangle,
every triangle whose bounding box comes within its distance ``d``; that shell of boxes holds a
cap of the surface of area about ``2 pi d delta`` (``delta`` the box size), some hundred
triangles and a thousand boxes per sample here. For a block with centre ``c``, half extents
``h`` (half-diagonal ``r``) and exact nearest distance ``D = d(c) > FAR * r``, two bounds of
convex analysis (the distance to a triangle is convex, its Hessian at most ``1 / distance``)
do that work once for all its samples:

* upper: every point ``x`` of the block has ``d(x) <= U(x) = D + g_c . (x - c) + eps``, with
  ``g_c`` the unit gradient of the distance at ``c`` and ``eps = r^2 / (2 (D - r))``;
* lower: a triangle at distance ``d_t`` from ``c`` with gradient ``g_t`` there is at least
  ``d_t + g_t . (x - c)`` from ``x``.

So a triangle can be nearest to some point of the block only if
``d_t - D - eps <= sum_i h_i |g_c,i - g_t,i|`` (the block test). A block near the surface
(``D <= FAR * r``) keeps instead every triangle within ``D + 2 r`` of its centre
(``d(x) <= D + r`` and ``d(x, t) >= d_t - r``). Both hold for every point of the block's box,
not only its samples, so a child block (inside it) finds its answer among its parent's items.

The traversal: a top block of ``block^3`` samples starts from the root of the hierarchy; each
block, level by level down to ``2^3``,

1. finds its centre's exact nearest triangle among its parent's items (the parent's nearest
   first, then the triangles whose bound beats the best so far, then a walk below each node
   whose box does): :func:`_centre`; the one pass over the parent's triangles that gives their
   bounds at the centre (:mod:`._gridsdf_bounds`: plane, edge lines and bounding disk, 20
   coefficients each) keeps each bound's gradient there too (:func:`~._gridsdf_bounds.tangent`);
2. keeps the parent's triangles that pass its test, by their bound linearized at its centre
   (:func:`~._gridsdf_bounds.block_test` on the values of step 1, four a triangle; no exact
   distance, no second pass over the 20 coefficients), in one branch-free loop the compiler
   vectorizes;
3. tests the parent's hierarchy nodes, a whole frontier at a time (the block test on each
   node's bounding ball, with its box's distance as the flat bound: ``may_hold``): a node that
   passes is kept when its bounding radius is at most ``open_ratio`` half-diagonals of the
   block, else replaced by its children (tested in turn), a leaf by its four triangles (tested
   by their bounds, in one vectorized pass). Far blocks of 8^3 and 4^3 (``OPENS``) open every node,
   so that the lists the many small blocks filter are triangles only; the leaf blocks (``2^3``)
   always do.

Then each sample of a ``2^3`` block scans its list (about 44 candidates here, a branch-free
loop) and measures exactly only those whose bound beats the best of two seeds (the block
centre's and the previous sample's triangle): about 3.5 a sample, most of them ties.

The lists are one per level (depth first, a parent's list outlives its children), rows padded
off multiples of 4 kB: rows exactly a power of two apart shared cache sets, and the filter,
which streams all 20 rows at once, ran five times slower. The bounds make the answer exact, not
approximate: they only decide which triangles to measure.

Profile (82k triangles at 128^3, one thread, top blocks of 16^3; per sample of 1,854,840):
level 16^3 (576 blocks, 354 near) and 8^3 (4,080, 1,359 near): 2.9 node tests, 3.4 triangle
tests; 4^3 (29,667, 4,596 near): 13.8 triangles filtered, 3.0 node and 3.2 triangle tests,
lists of 240 triangles; 2^3 (233,740, 12,166 near): 30.6 triangles filtered, 2.8 node and 3.4
triangle tests, 1.6 node walks and 0.6 exact distances for the centres, lists of 44; samples:
44 bounds, 3.5 exact distances (1.0 improvements). CPU seconds by level in the module notes of
``benchmarks/bench_sdf_grid.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._gridsdf_bounds import FAR, NB, SLACK, block_test, bound2, margin, may_hold, tangent
from ._meshdistance_kernels import box_d2, closest_on_triangle, walk

CHUNKS = 256
"""Parallel chunks of top blocks (each allocates its work arrays once)."""

OPENS = 2
"""Far blocks of this many levels above the leaf blocks (8^3 and 4^3 under top blocks of 16^3)
open every hierarchy node they are handed (the leaf blocks always do), so that the lists the
many small blocks filter are triangles only (one vectorized loop, no node work)."""


@njit(cache=True, inline="always")
def _signed(px, py, pz, d2, t, region, cp, fn, en, vn):
    """``sqrt(d2)`` with the sign of ``(p - cp) . n`` for the pseudo-normal ``n`` of the feature
    ``region`` of triangle ``t`` (0 face, 1-3 vertex, 4-6 edge; the arrays in BVH order)."""
    if region == 0:
        nx, ny, nz = fn[t, 0], fn[t, 1], fn[t, 2]
    elif region <= 3:
        nx, ny, nz = vn[t, region - 1, 0], vn[t, region - 1, 1], vn[t, region - 1, 2]
    else:
        nx, ny, nz = en[t, region - 4, 0], en[t, region - 4, 1], en[t, region - 4, 2]
    side = (px - cp[0]) * nx + (py - cp[1]) * ny + (pz - cp[2]) * nz
    d = np.sqrt(d2)
    return -d if side < 0.0 else d



@njit(cache=True)
def _centre(cx, cy, cz, seed, climit, nn, nodes, nt, ct, cv, tg, lo, hi, tlo, thi, tri, L, m, stack, q, cp):
    """The exact nearest triangle of the point ``c`` among a block's items (module notes): the
    ``nt`` triangles ``ct`` (bound coefficients ``cv``) and every triangle below the ``nn``
    hierarchy nodes ``nodes``, triangle ``seed`` (-1: none) measured first and the others only
    where their bound beats the best so far; their bounds at ``c`` and the bounds' gradients
    there (:func:`~._gridsdf_bounds.tangent`) are left in ``tg`` (4 rows), for the block test
    of :func:`_filter`, which so needs no second pass over the coefficients. Returns
    ``(squared distance, triangle)``, triangle -1 when nothing lies within ``climit`` (squared);
    the closest point in ``cp``."""
    best, bt = climit, -1
    if seed >= 0:
        closest_on_triangle(cx, cy, cz, tri, seed, q)
        dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 <= best:
            best, bt = d2, seed
            cp[0], cp[1], cp[2] = q[0], q[1], q[2]
    for e in range(nt):
        bl, gx, gy, gz = tangent(cv, e, cx, cy, cz)
        tg[0, e], tg[1, e], tg[2, e], tg[3, e] = bl, gx, gy, gz
    for e in range(nt):
        if tg[0, e] * tg[0, e] > best or ct[e] == bt:
            continue
        closest_on_triangle(cx, cy, cz, tri, ct[e], q)
        dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 < best or (bt < 0 and d2 <= best):
            best, bt = d2, ct[e]
            cp[0], cp[1], cp[2] = q[0], q[1], q[2]
    for i in range(nn):
        best, bt, _ = walk(cx, cy, cz, best, bt, 0, lo, hi, tlo, thi, tri, L, m, stack, q, cp, nodes[i])
    return best, bt


@njit(cache=True, inline="always")
def _node_near(cx, cy, cz, lo, hi, nd, R2):
    """The bounding radius of node ``nd`` when its box comes within ``sqrt(R2)`` of ``c``, else -1."""
    ex = 0.5 * (hi[nd, 0] - lo[nd, 0])
    ey = 0.5 * (hi[nd, 1] - lo[nd, 1])
    ez = 0.5 * (hi[nd, 2] - lo[nd, 2])
    rho = np.sqrt(ex * ex + ey * ey + ez * ez) * (1.0 + SLACK)
    return rho if box_d2(cx, cy, cz, lo, hi, nd) <= R2 else -1.0


@njit(cache=True, inline="always")
def _node_far(cx, cy, cz, lo, hi, nd, R2, D, eps, gx, gy, gz, hn):
    """The bounding radius of node ``nd`` when a triangle inside it may pass the block test of a
    far block (module notes; :func:`may_hold` on its bounding ball, with its box's distance as the
    flat bound), else -1. Branch-free."""
    ex = 0.5 * (hi[nd, 0] - lo[nd, 0])
    ey = 0.5 * (hi[nd, 1] - lo[nd, 1])
    ez = 0.5 * (hi[nd, 2] - lo[nd, 2])
    rho = np.sqrt(ex * ex + ey * ey + ez * ez) * (1.0 + SLACK)
    b2 = box_d2(cx, cy, cz, lo, hi, nd)
    vx, vy, vz = cx - lo[nd, 0] - ex, cy - lo[nd, 1] - ey, cz - lo[nd, 2] - ez
    ok = b2 <= R2 and may_hold(vx, vy, vz, rho, np.sqrt(b2), D, eps, gx, gy, gz, hn)
    return rho if ok else -1.0


@njit(cache=True)
def _filter(pn, pnodes, pt, pct, pcv, nodes, ct, cv, lb, tg, cx, cy, cz, hx, hy, hz, r, D, cp, last, opens_far, open_at,
            lo, hi, L, m, prism_t, front, nxt, gap):
    """A block's items from its parent's (module notes): the block has centre ``c``, half
    extents ``h``, half-diagonal ``r``, exact nearest distance ``D`` at ``c`` (closest point
    ``cp``); the parent's ``pt`` triangles ``pct``, ``pcv`` (their bounds at ``c`` and the
    bounds' gradients in ``tg``, from :func:`_centre`; ``lb`` is scratch)
    and ``pn`` nodes ``pnodes``. A node that passes the block test is kept when its bounding
    radius is at most ``open_at``, else opened (its children tested in turn, a leaf's triangles
    by their own bounds); ``last``, or ``opens_far`` for a far block: every node is opened.
    ``front``, ``nxt``, ``gap``: scratch for the node frontier. Writes the block's triangles to
    ``ct``, ``cv`` and nodes to ``nodes``; returns their counts ``(nodes, triangles)``."""
    near = D <= FAR * r
    if near:
        # d(x) <= D + r and d(x, t) >= d(c, t) - r
        gx, gy, gz, eps, top = 0.0, 0.0, 0.0, 0.0, 0.0
        R = (D + 2.0 * r) * (1.0 + SLACK)
    else:
        gx, gy, gz = (cx - cp[0]) / D, (cy - cp[1]) / D, (cz - cp[2]) / D
        eps = r * r / (2.0 * (D - r)) + SLACK * (D + r)
        top = D + eps + SLACK * (D + r)
        R = (D + hx * abs(gx) + hy * abs(gy) + hz * abs(gz) + eps + r) * (1.0 + SLACK)
    R2 = R * R
    nt = 0
    if near:
        for e in range(pt):
            if tg[0, e] * tg[0, e] <= R2:
                ct[nt] = pct[e]
                for a in range(NB):
                    cv[a, nt] = pcv[a, e]
                nt += 1
    else:
        for e in range(pt):
            lb[e] = block_test(tg[0, e], tg[1, e], tg[2, e], tg[3, e], hx, hy, hz, gx, gy, gz, top)
        for e in range(pt):
            if lb[e] > 0.0:
                continue
            ct[nt] = pct[e]
            for a in range(NB):
                cv[a, nt] = pcv[a, e]
            nt += 1
    if last or (opens_far and not near):
        open_at = -1.0
    # the parent's nodes, level by level of the hierarchy: one pass of tests over the whole
    # frontier (no branch, so the compiler overlaps them), then keep, open or unpack each
    nn = 0
    nf = pn
    for i in range(pn):
        front[i] = pnodes[i]
    t_start = nt
    while nf > 0:
        if near:
            for i in range(nf):
                gap[i] = _node_near(cx, cy, cz, lo, hi, front[i], R2)
        else:
            for i in range(nf):
                gap[i] = _node_far(cx, cy, cz, lo, hi, front[i], R2, D, eps, gx, gy, gz, r)
        nx = 0
        for i in range(nf):
            rho = gap[i]
            if rho < 0.0:
                continue
            nd = front[i]
            if rho <= open_at:
                nodes[nn] = nd
                nn += 1
            elif nd < L:
                nxt[nx] = 2 * nd
                nxt[nx + 1] = 2 * nd + 1
                nx += 2
            else:
                first = (nd - L) * 4
                for t in range(first, min(first + 4, m)):
                    ct[nt] = t
                    for a in range(NB):
                        cv[a, nt] = prism_t[a, t]
                    nt += 1
        front, nxt = nxt, front
        nf = nx
    # the triangles of the opened leaves, tested all at once and compacted in place
    if near:
        for e in range(t_start, nt):
            lb[e] = bound2(cv, e, cx, cy, cz) - R2
    else:
        for e in range(t_start, nt):
            lb[e] = margin(cv, e, cx, cy, cz, hx, hy, hz, gx, gy, gz, top)
    k = t_start
    for e in range(t_start, nt):
        if lb[e] > 0.0:
            continue
        if k < e:
            ct[k] = ct[e]
            for a in range(NB):
                cv[a, k] = cv[a, e]
        k += 1
    nt = k
    return nn, nt


@njit(cache=True)
def _leaves(i0, i1, j0, j1, k0, k1, n, ct, cv, lb, tc, t0, origin, spacing, ny, nz, limit, tri, fn, en, vn, out, q,
            cp):
    """Every sample of ``[i0, i1) x [j0, j1) x [k0, k1)`` from its block's ``n`` candidates:
    first bound from the block centre's nearest triangle ``tc`` and the previous sample's
    ``t0``, then the bounds of all candidates at once (a branch-free loop the
    compiler vectorizes), exact distances only where a bound beats the best so far. Returns
    the last sample's triangle."""
    for i in range(i0, i1):
        for j in range(j0, j1):
            for k in range(k0, k1):
                px = origin[0] + i * spacing[0]
                py = origin[1] + j * spacing[1]
                pz = origin[2] + k * spacing[2]
                br = closest_on_triangle(px, py, pz, tri, tc, cp)
                dx, dy, dz = px - cp[0], py - cp[1], pz - cp[2]
                b2 = dx * dx + dy * dy + dz * dz
                bt = tc
                if t0 != tc and t0 >= 0:
                    reg = closest_on_triangle(px, py, pz, tri, t0, q)
                    dx, dy, dz = px - q[0], py - q[1], pz - q[2]
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 < b2:
                        b2, bt, br = d2, t0, reg
                        cp[0], cp[1], cp[2] = q[0], q[1], q[2]
                for e in range(n):
                    lb[e] = bound2(cv, e, px, py, pz)
                for e in range(n):
                    if lb[e] > b2:
                        continue
                    t = ct[e]
                    if t == bt:
                        continue
                    reg = closest_on_triangle(px, py, pz, tri, t, q)
                    dx, dy, dz = px - q[0], py - q[1], pz - q[2]
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 < b2:
                        b2, bt, br = d2, t, reg
                        cp[0], cp[1], cp[2] = q[0], q[1], q[2]
                t0 = bt
                if b2 <= limit:
                    out[(i * ny + j) * nz + k] = _signed(px, py, pz, b2, bt, br, cp, fn, en, vn)
                else:
                    out[(i * ny + j) * nz + k] = np.inf
    return t0


@njit(cache=True)
def _fill_inf(i0, i1, j0, j1, k0, k1, ny, nz, out):
    for i in range(i0, i1):
        for j in range(j0, j1):
            for k in range(k0, k1):
                out[(i * ny + j) * nz + k] = np.inf


@njit(cache=True, parallel=True)
def grid_signed(origin, spacing, shape, limit, block, open_ratio, lo, hi, tlo, thi, tri, L, m, fn, en, vn, prism,
                out):
    """Signed distances (negative inside) of the samples ``origin + (i, j, k) * spacing`` of a
    grid of ``shape`` into ``out`` (flat, C order); ``inf`` for samples whose squared distance
    exceeds ``limit``. Triangles ``tri (m, 3, 3)``, hierarchy boxes ``lo``, ``hi`` (nodes) and
    ``tlo``, ``thi`` (triangles; leaves of 4 from node ``L``), pseudo-normals (face ``fn (m, 3)``,
    edge ``en (m, 3, 3)``, vertex per corner ``vn (m, 3, 3)``) and bound coefficients
    ``prism (m, NB)`` in the hierarchy's order. Top blocks of ``block^3`` samples (``block`` a
    power of two, at least 2), halved level by level down to ``2^3``; a block keeps the nodes
    whose bounding radius is at most ``open_ratio`` times its half-diagonal (module notes)."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    bx = (nx + block - 1) // block
    by = (ny + block - 1) // block
    bz = (nz + block - 1) // block
    n_blocks = bx * by * bz
    nlev = 1
    while (block >> nlev) >= 2:
        nlev += 1
    # top blocks per parallel chunk, consecutive along z so that warm starts carry over; few
    # chunks, so that the per-chunk work arrays (each as long as the mesh) are allocated rarely
    per = max(1, (n_blocks + CHUNKS - 1) // CHUNKS)
    # rows padded to 64 bytes past a multiple of 4 kB: rows a power of two apart would share
    # cache sets (a filter streams all NB rows at once; unpadded, 82k triangles made it 5x slower)
    stride = (m + 511) // 512 * 512 + 8
    prism_t = prism.T
    reach = np.sqrt(limit)
    for chunk in prange((n_blocks + per - 1) // per):
        stack = np.empty(128, dtype=np.int64)
        boxes = np.empty((8 * nlev + 1, 8), dtype=np.int64)
        q = np.empty(3)
        cp = np.empty(3)
        # the items of the block being worked on at each level (depth first, so a parent's
        # items outlive its children); row 0: the whole hierarchy (its root node)
        nodes = np.empty((nlev + 1, 2 * L + 8), dtype=np.int64)
        ct = np.empty((nlev + 1, stride), dtype=np.int64)
        cv = np.empty((nlev + 1, NB, stride))
        lb = np.empty(stride)
        tg = np.empty((4, stride))  # the parent's candidates' bounds and gradients at a centre
        front = np.empty(2 * L + 8, dtype=np.int64)
        nxt = np.empty(2 * L + 8, dtype=np.int64)
        gap = np.empty(2 * L + 8)
        nnod = np.zeros(nlev + 1, dtype=np.int64)
        ntri = np.zeros(nlev + 1, dtype=np.int64)
        tlist = np.full(nlev + 1, -1, dtype=np.int64)
        nodes[0, 0] = 1
        nnod[0] = 1
        t0 = -1
        for blk in range(chunk * per, min(n_blocks, (chunk + 1) * per)):
            i0 = blk // (by * bz) * block
            j0 = (blk // bz) % by * block
            k0 = blk % bz * block
            sp = 1
            boxes[0, 0], boxes[0, 1] = i0, min(i0 + block, nx)
            boxes[0, 2], boxes[0, 3] = j0, min(j0 + block, ny)
            boxes[0, 4], boxes[0, 5] = k0, min(k0 + block, nz)
            boxes[0, 6], boxes[0, 7] = 1, 0
            while sp > 0:
                sp -= 1
                a0, a1, b0, b1, c0, c1, lev = (boxes[sp, 0], boxes[sp, 1], boxes[sp, 2], boxes[sp, 3],
                                               boxes[sp, 4], boxes[sp, 5], boxes[sp, 6])
                hx = 0.5 * (a1 - 1 - a0) * spacing[0]
                hy = 0.5 * (b1 - 1 - b0) * spacing[1]
                hz = 0.5 * (c1 - 1 - c0) * spacing[2]
                cx = origin[0] + a0 * spacing[0] + hx
                cy = origin[1] + b0 * spacing[1] + hy
                cz = origin[2] + c0 * spacing[2] + hz
                r = np.sqrt(hx * hx + hy * hy + hz * hz)
                climit = (reach + r) ** 2 if reach < np.inf else np.inf
                p = lev - 1
                # the centre's exact nearest triangle; none within reach + r: no sample is in the band
                best, tc = _centre(cx, cy, cz, tlist[p], climit, nnod[p], nodes[p], ntri[p], ct[p], cv[p], tg, lo,
                                   hi, tlo, thi, tri, L, m, stack, q, cp)
                if tc < 0:
                    _fill_inf(a0, a1, b0, b1, c0, c1, ny, nz, out)
                    continue
                if lev == 1:
                    tlist[0] = tc  # the next top block's first bound
                last = lev == nlev
                far_end = lev >= nlev - OPENS
                nnod[lev], ntri[lev] = _filter(nnod[p], nodes[p], ntri[p], ct[p], cv[p], nodes[lev], ct[lev], cv[lev],
                                               lb, tg, cx, cy, cz, hx, hy, hz, r, np.sqrt(best), cp, last, far_end,
                                               open_ratio * r, lo, hi, L, m, prism_t, front, nxt, gap)
                tlist[lev] = tc
                if not last:
                    sp = _push_children(boxes, sp, a0, a1, b0, b1, c0, c1, lev + 1, block >> lev)
                else:
                    t0 = _leaves(a0, a1, b0, b1, c0, c1, ntri[lev], ct[lev], cv[lev], lb, tc, t0, origin, spacing, ny,
                                 nz, limit, tri, fn, en, vn, out, q, cp)


@njit(cache=True, inline="always")
def _push_children(boxes, sp, i0, i1, j0, j1, k0, k1, lev, half):
    """Push the (up to) eight parts of side ``half`` of a box (cut by the grid's end), last
    first so that they come off in order."""
    for o in range(7, -1, -1):
        a0, b0, c0 = i0 + (o >> 2) * half, j0 + ((o >> 1) & 1) * half, k0 + (o & 1) * half
        a1, b1, c1 = min(a0 + half, i1), min(b0 + half, j1), min(c0 + half, k1)
        if a0 < a1 and b0 < b1 and c0 < c1:
            boxes[sp, 0], boxes[sp, 1], boxes[sp, 2], boxes[sp, 3] = a0, a1, b0, b1
            boxes[sp, 4], boxes[sp, 5], boxes[sp, 6] = c0, c1, lev
            sp += 1
    return sp
