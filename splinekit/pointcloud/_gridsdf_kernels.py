"""Compiled (numba) exact signed distance of a closed triangle mesh at every sample of a grid:
:meth:`splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.

Loaded through :func:`splinekit._kernels.load`. Per sample it answers what
:meth:`~splinekit.pointcloud.meshdistance.MeshDistance.signed` answers (the exact nearest
triangle, sign by the angle-weighted pseudo-normal of its nearest feature), but it walks the
grid by blocks of ``block^3`` samples and spends most of its work once per block, not once per
sample.

Why: a sample far from the surface (most of a dense grid) needs, to prove its nearest triangle,
every triangle whose bounding box comes within its distance ``d``; that shell of boxes holds a
cap of the surface of area about ``2 pi d delta`` (``delta`` the box size), some hundred
triangles and a thousand boxes per sample here. For a block with centre ``c``, half extents
``h`` (half-diagonal ``r``) and exact nearest distance ``D = d(c) > FAR * r``, two bounds of
convex analysis (the distance to a triangle is convex, its Hessian at most ``1 / distance``)
do that work once:

* upper: every sample ``x`` of the block has ``d(x) <= U(x) = D + g_c . (x - c) + eps``, with
  ``g_c`` the unit gradient of the distance at ``c`` and ``eps = r^2 / (2 (D - r))``;
* lower: a triangle at distance ``d_t`` from ``c`` with gradient ``g_t`` there is at least
  ``d_t + g_t . (x - c)`` from ``x``.

So a triangle can be nearest to some sample only if ``d_t - D - eps <= sum_i h_i |g_c,i - g_t,i|``
(the largest of ``(g_c - g_t) . (x - c)`` over the block); one range query per block collects
those (they lie within ``D + s + eps + r`` of ``c``, ``s = sum_i h_i |g_c,i|``). The query skips
a node of the hierarchy, and a triangle before its exact distance, when that test fails for
everything in its bounding ball (:func:`_may_hold`).

Each sample then measures exactly only the candidates whose half-plane bound beats its best so
far: a triangle lies in its plane, on the far side of the line through its closest point ``q``
to the centre across ``w``, the in-plane part of ``c - q`` (for ``q`` on an edge or a vertex;
the plane alone for ``q`` inside the face), so the distance from ``x`` to that half-plane,
``sqrt((n . (x - q))^2 + max(0, w . (x - q))^2)``, bounds ``d(x, t)`` from below. It is exact
while ``x``'s closest point stays on the same edge, much tighter than the linear bound
``d_t + g_t . (x - c)`` it contains, and costs two dot products (a branch-free loop over the
candidates). A sliver triangle whose normal rounding could turn gets no plane (always measured).

A block near the surface (``D <= FAR * r``) is split in eight; a part still near takes every
triangle within ``D + 2 r`` of its centre (``d(x) <= D + r`` and ``d(x, t) >= d_t - r``) and the
same per-sample scan. The bounds make the answer exact, not approximate: they only decide which
triangles to measure.

Profile (82k triangles at 128^3, one thread, CPU time; the module notes of
``benchmarks/bench_sdf_grid.py`` have the figures): about 10 % the blocks' centre queries, 55 %
the range queries (about 550 exact distances per far block of 64 samples, of which about 275
pass the test), 35 % the per-sample scans (about 200 half-plane bounds and 11 exact distances
per sample, most of those ties: the triangles around the nearest vertex).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._meshdistance_kernels import box_d2, closest_on_triangle, seeded

FAR = 2.0
"""A block is handled by its candidate list when its centre is farther than this many
half-diagonals from the surface (the upper bound needs more than one)."""

SLACK = 1e-12
"""Relative margin of the block tests against rounding (they only prune; a wider margin only
measures a few more triangles)."""


TOL = 1e-9
"""Absolute margin (unit box) of the half-plane bounds: a triangle lies in its computed plane,
and on the computed side of the line through its closest point, up to rounding of about
``1e-16 / WMIN`` times its size; the bounds are lowered by this much."""

WMIN = 1e-6
"""Shortest in-plane offset (unit box) whose direction is used for the half-plane bound;
shorter ones (rounding could turn them) bound by the plane alone."""

CHUNKS = 256
"""Parallel chunks of blocks (each allocates its work arrays once)."""


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


@njit(cache=True, inline="always")
def _may_hold(vx, vy, vz, rho, flat, D, eps, gx, gy, gz, hn):
    """False when no triangle within the ball of radius ``rho`` at ``c - v`` (``v = (vx, vy, vz)``)
    can pass the block test ``d_t - D - eps <= sum_i h_i |g_c,i - g_t,i|`` (module notes):
    its closest point ``q`` lies in the ball, so ``d_t >= max(|v| - rho, flat)`` (``flat`` a
    lower bound from the triangle's plane, or 0), and the unit vector ``g_t = (c - q) / d_t`` is
    within ``2 rho / |v|`` of ``v / |v|``; ``sum_i h_i |.| <= |h| |.|`` (``hn = |h|``)."""
    mc = np.sqrt(vx * vx + vy * vy + vz * vz)
    if mc <= 2.0 * rho:
        return True
    ex, ey, ez = gx - vx / mc, gy - vy / mc, gz - vz / mc
    turn = np.sqrt(ex * ex + ey * ey + ez * ez) + 2.0 * rho / mc
    return max(mc - rho, flat) - D - eps <= hn * turn * (1.0 + SLACK) + SLACK * (D + hn)


@njit(cache=True, inline="always")
def _keep(e, t, reg, dt, q, dx, dy, dz, plane, ct, cd, cq, cn, cw):
    """Store candidate ``e``: triangle ``t`` whose closest point to the block centre ``c`` is
    ``q`` (feature ``reg``) at distance ``dt``, ``(dx, dy, dz) = c - q``. With it the half-plane
    that holds the triangle: its plane (unit normal ``plane[t]``, zero when degenerate) cut by
    the line through ``q`` across ``w``, the in-plane part of ``c - q`` (zero for a face point:
    then only the plane bounds)."""
    nx, ny, nz = plane[t, 0], plane[t, 1], plane[t, 2]
    ct[e] = t
    cd[e] = dt
    cq[e, 0], cq[e, 1], cq[e, 2] = q[0], q[1], q[2]
    cn[e, 0], cn[e, 1], cn[e, 2] = nx, ny, nz
    cw[e, 0], cw[e, 1], cw[e, 2] = 0.0, 0.0, 0.0
    if reg == 0:
        return
    a = dx * nx + dy * ny + dz * nz
    wx, wy, wz = dx - a * nx, dy - a * ny, dz - a * nz
    lw = np.sqrt(wx * wx + wy * wy + wz * wz)
    if lw > WMIN:
        cw[e, 0], cw[e, 1], cw[e, 2] = wx / lw, wy / lw, wz / lw


@njit(cache=True, parallel=True)
def grid_signed(origin, spacing, shape, limit, block, lo, hi, tlo, thi, tri, L, m, fn, en, vn, plane, ball, out):
    """Signed distances (negative inside) of the samples ``origin + (i, j, k) * spacing`` of a
    grid of ``shape`` into ``out`` (flat, C order); ``inf`` for samples whose squared distance
    exceeds ``limit``. Triangles ``tri (m, 3, 3)``, boxes and pseudo-normals (face ``fn (m, 3)``,
    edge ``en (m, 3, 3)``, vertex per corner ``vn (m, 3, 3)``), unit plane normals ``plane (m, 3)``
    and bounding balls ``ball (m, 4)`` in the hierarchy's order. Blocks of ``block^3`` samples;
    one near the surface is split in eight."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    bx = (nx + block - 1) // block
    by = (ny + block - 1) // block
    bz = (nz + block - 1) // block
    n_blocks = bx * by * bz
    half = (block + 1) // 2
    # blocks per parallel chunk, consecutive along z so that warm starts carry over; few chunks,
    # so that the per-chunk work arrays (each as long as the mesh) are allocated rarely
    per = max(4, (n_blocks + CHUNKS - 1) // CHUNKS)
    for chunk in prange((n_blocks + per - 1) // per):
        stack = np.empty(128, dtype=np.int64)
        q = np.empty(3)
        cp = np.empty(3)
        # a block's candidates (triangle, distance from the centre, closest point, plane normal,
        # in-plane direction away from the triangle), then sorted by distance, one row per axis
        ct = np.empty(m, dtype=np.int64)
        cd = np.empty(m)
        cq = np.empty((m, 3))
        cn = np.empty((m, 3))
        cw = np.empty((m, 3))
        st = np.empty(m, dtype=np.int64)
        sq = np.empty((3, m))
        sn = np.empty((3, m))
        sw = np.empty((3, m))
        lb = np.empty(m)
        prev = -1
        for blk in range(chunk * per, min(n_blocks, (chunk + 1) * per)):
            i0 = blk // (by * bz) * block
            j0 = (blk // bz) % by * block
            k0 = blk % bz * block
            i1, j1, k1 = min(i0 + block, nx), min(j0 + block, ny), min(k0 + block, nz)
            prev, near = _block(i0, i1, j0, j1, k0, k1, True, prev, origin, spacing, ny, nz, limit, lo, hi, tlo,
                                thi, tri, L, m, fn, en, vn, plane, ball, out, stack, q, cp, ct, cd, cq, cn, cw,
                                st, sq, sn, sw, lb)
            if not near:
                continue
            for o in range(8):
                a0, b0, c0 = i0 + (o >> 2) * half, j0 + ((o >> 1) & 1) * half, k0 + (o & 1) * half
                a1, b1, c1 = min(a0 + half, i1), min(b0 + half, j1), min(c0 + half, k1)
                if a0 < a1 and b0 < b1 and c0 < c1:
                    prev, _ = _block(a0, a1, b0, b1, c0, c1, False, prev, origin, spacing, ny, nz, limit, lo, hi,
                                     tlo, thi, tri, L, m, fn, en, vn, plane, ball, out, stack, q, cp, ct, cd, cq,
                                     cn, cw, st, sq, sn, sw, lb)


@njit(cache=True)
def _block(i0, i1, j0, j1, k0, k1, split, prev, origin, spacing, ny, nz, limit, lo, hi, tlo, thi, tri, L, m, fn, en,
           vn, plane, ball, out, stack, q, cp, ct, cd, cq, cn, cw, st, sq, sn, sw, lb):
    """The samples ``[i0, i1) x [j0, j1) x [k0, k1)`` into ``out`` (module notes); ``prev`` a
    triangle near the block (-1 for none). Returns ``(triangle nearest the centre, near)``:
    with ``split``, a block near the surface is left to the caller (``near`` True), which
    splits it; without, such a block takes every triangle within ``D + 2 r`` of its centre."""
    hx = 0.5 * (i1 - 1 - i0) * spacing[0]
    hy = 0.5 * (j1 - 1 - j0) * spacing[1]
    hz = 0.5 * (k1 - 1 - k0) * spacing[2]
    cx = origin[0] + i0 * spacing[0] + hx
    cy = origin[1] + j0 * spacing[1] + hy
    cz = origin[2] + k0 * spacing[2] + hz
    r = np.sqrt(hx * hx + hy * hy + hz * hz)
    for i in range(i0, i1):
        for j in range(j0, j1):
            for k in range(k0, k1):
                out[(i * ny + j) * nz + k] = np.inf
    # the centre's exact nearest triangle; none within reach + r: no sample is in the band
    reach = np.sqrt(limit)
    climit = (reach + r) ** 2 if reach < np.inf else np.inf
    best, tc, _ = seeded(cx, cy, cz, climit, prev, lo, hi, tlo, thi, tri, L, m, stack, q, cp)
    if tc < 0:
        return prev, False
    D = np.sqrt(best)
    near = D <= FAR * r
    if near and split:
        return tc, True
    if near:
        # every sample x has d(x) <= D + r and d(x, t) >= d_t - r
        gx, gy, gz, eps, hn = 0.0, 0.0, 0.0, 0.0, 0.0
        R = (D + 2.0 * r) * (1.0 + SLACK)
    else:
        gx, gy, gz = (cx - cp[0]) / D, (cy - cp[1]) / D, (cz - cp[2]) / D
        eps = r * r / (2.0 * (D - r)) + SLACK * (D + r)
        hn = r
        R = D + hx * abs(gx) + hy * abs(gy) + hz * abs(gz) + eps + r
    R2 = R * R
    # range query: the triangles within R of the centre that pass the block test
    nc = 0
    sp = 1
    stack[0] = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if box_d2(cx, cy, cz, lo, hi, node) > R2:
            continue
        if not near:
            # the block test for everything in the node's bounding ball
            bx_ = 0.5 * (lo[node, 0] + hi[node, 0])
            by_ = 0.5 * (lo[node, 1] + hi[node, 1])
            bz_ = 0.5 * (lo[node, 2] + hi[node, 2])
            ex, ey, ez = hi[node, 0] - bx_, hi[node, 1] - by_, hi[node, 2] - bz_
            rho = np.sqrt(ex * ex + ey * ey + ez * ez) * (1.0 + SLACK)
            if not _may_hold(cx - bx_, cy - by_, cz - bz_, rho, 0.0, D, eps, gx, gy, gz, hn):
                continue
        if node < L:
            stack[sp] = 2 * node
            stack[sp + 1] = 2 * node + 1
            sp += 2
            continue
        first = (node - L) * 4
        for t in range(first, min(first + 4, m)):
            if box_d2(cx, cy, cz, tlo, thi, t) > R2:
                continue
            vx, vy, vz = cx - ball[t, 0], cy - ball[t, 1], cz - ball[t, 2]
            if not near:
                # the block test from the triangle's bounding ball and plane first
                flat = abs(vx * plane[t, 0] + vy * plane[t, 1] + vz * plane[t, 2]) - TOL
                if not _may_hold(vx, vy, vz, ball[t, 3], flat, D, eps, gx, gy, gz, hn):
                    continue
            reg = closest_on_triangle(cx, cy, cz, tri, t, q)
            dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
            d2 = dx * dx + dy * dy + dz * dz
            if not d2 <= R2:  # also drops the NaN of a degenerate triangle
                continue
            dt = np.sqrt(d2)
            if not near:
                ux, uy, uz = dx / dt, dy / dt, dz / dt
                if dt - D - eps > hx * abs(gx - ux) + hy * abs(gy - uy) + hz * abs(gz - uz):
                    continue
            _keep(nc, t, reg, dt, q, dx, dy, dz, plane, ct, cd, cq, cn, cw)
            nc += 1
    # candidates by distance from the centre, the arrays the samples read contiguous
    by_d = np.argsort(cd[:nc])
    sd = cd[by_d]
    for e in range(nc):
        c = by_d[e]
        st[e] = ct[c]
        for a in range(3):
            sq[a, e], sn[a, e], sw[a, e] = cq[c, a], cn[c, a], cw[c, a]
    t0 = tc
    for i in range(i0, i1):
        for j in range(j0, j1):
            for k in range(k0, k1):
                px = origin[0] + i * spacing[0]
                py = origin[1] + j * spacing[1]
                pz = origin[2] + k * spacing[2]
                # first bound: the better of the centre's and the previous sample's triangle
                br = closest_on_triangle(px, py, pz, tri, tc, cp)
                dx, dy, dz = px - cp[0], py - cp[1], pz - cp[2]
                b2 = dx * dx + dy * dy + dz * dz
                bt = tc
                if t0 != tc:
                    reg = closest_on_triangle(px, py, pz, tri, t0, q)
                    dx, dy, dz = px - q[0], py - q[1], pz - q[2]
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 < b2:
                        b2, bt, br = d2, t0, reg
                        cp[0], cp[1], cp[2] = q[0], q[1], q[2]
                # the candidates near enough (d(x, t) >= d_t - |x - c|), then their half-plane
                # bounds all at once (a branch-free loop the compiler vectorizes)
                ox, oy, oz = px - cx, py - cy, pz - cz
                cut = np.sqrt(b2) * (1.0 + SLACK) + np.sqrt(ox * ox + oy * oy + oz * oz)
                ne = nc
                for e in range(nc):
                    if sd[e] > cut:
                        ne = e
                        break
                for e in range(ne):
                    ax, ay, az = px - sq[0, e], py - sq[1, e], pz - sq[2, e]
                    hh = max(abs(ax * sn[0, e] + ay * sn[1, e] + az * sn[2, e]) - TOL, 0.0)
                    ss = max(ax * sw[0, e] + ay * sw[1, e] + az * sw[2, e] - TOL, 0.0)
                    lb[e] = hh * hh + ss * ss
                for e in range(ne):
                    if lb[e] > b2:
                        continue
                    t = st[e]
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
    return tc, False
