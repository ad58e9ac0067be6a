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
those (they lie within ``D + s + eps + r`` of ``c``, ``s = sum_i h_i |g_c,i|``). Each sample then
computes the exact distance only to the candidates whose linear lower bound beats its best so
far. The bounds make the answer exact, not approximate: they only decide which triangles to
measure. Blocks near the surface (``D <= FAR * r``) walk the hierarchy per sample, each sample
starting from its neighbour's triangle.
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
    edge ``en (m, 3, 3)``, vertex per corner ``vn (m, 3, 3)``) in the hierarchy's order."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    bx = (nx + block - 1) // block
    by = (ny + block - 1) // block
    bz = (nz + block - 1) // block
    n_blocks = bx * by * bz
    # blocks per parallel chunk, consecutive along z so that warm starts carry over; few chunks,
    # so that the per-chunk work arrays (each as long as the mesh) are allocated rarely
    per = max(4, (n_blocks + CHUNKS - 1) // CHUNKS)
    reach = np.sqrt(limit)
    for chunk in prange((n_blocks + per - 1) // per):
        stack = np.empty(128, dtype=np.int64)
        q = np.empty(3)
        cp = np.empty(3)
        # the block's candidates (triangle, distance, closest point, plane normal, in-plane
        # direction away from the triangle), then the same sorted by distance, one row per axis
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
            ib = blk // (by * bz)
            jb = (blk // bz) % by
            kb = blk % bz
            i0, j0, k0 = ib * block, jb * block, kb * block
            i1, j1, k1 = min(i0 + block, nx), min(j0 + block, ny), min(k0 + block, nz)
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
            climit = (reach + r) ** 2 if reach < np.inf else np.inf
            best, tc, _ = seeded(cx, cy, cz, climit, prev, lo, hi, tlo, thi, tri, L, m, stack, q, cp)
            if tc < 0:
                continue
            prev = tc
            D = np.sqrt(best)
            if D <= FAR * r:
                # near the surface: one walk per sample, each from its neighbour's triangle
                t0 = tc
                for i in range(i0, i1):
                    for j in range(j0, j1):
                        for k in range(k0, k1):
                            px = origin[0] + i * spacing[0]
                            py = origin[1] + j * spacing[1]
                            pz = origin[2] + k * spacing[2]
                            b2, bt, br = seeded(px, py, pz, limit, t0, lo, hi, tlo, thi, tri, L, m, stack, q, cp)
                            if bt >= 0:
                                t0 = bt
                                out[(i * ny + j) * nz + k] = _signed(px, py, pz, b2, bt, br, cp, fn, en, vn)
                continue
            gx, gy, gz = (cx - cp[0]) / D, (cy - cp[1]) / D, (cz - cp[2]) / D
            eps = r * r / (2.0 * (D - r)) + SLACK * (D + r)
            s = hx * abs(gx) + hy * abs(gy) + hz * abs(gz)
            hn = np.sqrt(hx * hx + hy * hy + hz * hz)
            R = D + s + eps + r
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
                if node < L:
                    stack[sp] = 2 * node
                    stack[sp + 1] = 2 * node + 1
                    sp += 2
                    continue
                first = (node - L) * 4
                for t in range(first, min(first + 4, m)):
                    if box_d2(cx, cy, cz, tlo, thi, t) > R2:
                        continue
                    # the block test from the triangle's bounding sphere (centre b, radius rho)
                    # before its exact distance: d_t >= |c - b| - rho and
                    # |g_c - g_t| <= |g_c - (c - b) / |c - b|| + 2 rho / |c - b|
                    vx, vy, vz = cx - ball[t, 0], cy - ball[t, 1], cz - ball[t, 2]
                    mc = np.sqrt(vx * vx + vy * vy + vz * vz)
                    rho = ball[t, 3]
                    if mc > 2.0 * rho:
                        ex, ey, ez = gx - vx / mc, gy - vy / mc, gz - vz / mc
                        turn = np.sqrt(ex * ex + ey * ey + ez * ez) + 2.0 * rho / mc
                        if mc - rho - D - eps > hn * turn * (1.0 + SLACK):
                            continue
                    reg = closest_on_triangle(cx, cy, cz, tri, t, q)
                    dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
                    d2 = dx * dx + dy * dy + dz * dz
                    if not d2 <= R2:  # also drops the NaN of a degenerate triangle
                        continue
                    dt = np.sqrt(d2)
                    ux, uy, uz = dx / dt, dy / dt, dz / dt
                    if dt - D - eps <= hx * abs(gx - ux) + hy * abs(gy - uy) + hz * abs(gz - uz):
                        _keep(nc, t, reg, dt, q, dx, dy, dz, plane, ct, cd, cq, cn, cw)
                        nc += 1
            # candidates by distance from the centre: a sample stops at the first one whose
            # lower bound d_t - |x - c| already exceeds its best
            by_d = np.argsort(cd[:nc])
            sd = cd[by_d]
            for e in range(nc):  # sorted copies, contiguous for the per-sample loop
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
                        ox, oy, oz = px - cx, py - cy, pz - cz
                        off = np.sqrt(ox * ox + oy * oy + oz * oz)
                        # the candidates near enough (sphere bound), then their half-plane bounds
                        # all at once (a branch-free loop the compiler vectorizes)
                        ne = nc
                        cut = np.sqrt(b2) * (1.0 + SLACK) + off
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
