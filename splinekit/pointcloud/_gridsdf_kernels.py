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

Candidates carry a bound instead of a closest point: a triangle lies in its plane
``n . y = n . a``, inside its three edge lines ``u_k . y <= u_k . a_k`` (``u_k`` the unit
in-plane normals pointing out) and inside its bounding disk (centroid ``m``, radius ``rho``),
so with ``p = n . x - n . a`` and ``v`` the in-plane part of ``x - m``,
``d(x, t) >= sqrt(p^2 + max(0, max_k (u_k . x - u_k . a_k), |v| - rho)^2)``: exact when ``x``
faces the triangle or one of its edges, within the disk's slack beyond a vertex, and
independent of any centre (20 coefficients per triangle, ``MeshDistance._bvh_prisms``; a
sliver whose normal rounding could turn gets none and is always measured). It is convex in
``x`` (the norm of nonnegative convex parts), so linearized at a point it bounds from below
around it, which is how the blocks' lists shrink without exact distances:

* a far top block of ``block^3`` samples (``block`` = 8) collects its list by the range query;
  each of its eight halves (4^3) finds its own exact nearest triangle among that list (measuring
  only the candidates whose bound beats the best so far), then keeps the candidates whose bound,
  linearized at its centre, passes the block test for it; each 2^3 quarter does the same from
  its parent's list; each sample scans its 2^3 block's list (about 44 candidates here, a
  branch-free loop the compiler vectorizes) and measures exactly only those whose bound beats
  the best of two seeds (the block centre's and the previous sample's triangle): about 3.5 a
  sample, most of them ties (the triangles around the nearest vertex);
* a block near the surface (``D <= FAR * r``) is split in eight, each part with its own centre
  query; a 2^3 part still near takes every triangle within ``D + 2 r`` of its centre
  (``d(x) <= D + r`` and ``d(x, t) >= d_t - r``). A far block's parts are far (``FAR`` = 2).

The lists of a chunk of blocks are one per level (depth first, a parent's list outlives its
children), rows padded off multiples of 4 kB: rows exactly a power of two apart shared cache
sets, and the filter, which streams all 20 rows at once, ran five times slower. The bounds make
the answer exact, not approximate: they only decide which triangles to measure.

Profile (82k triangles at 128^3, one thread; counts per sample of 1,854,840): range queries
2,721 at 8^3, 6,276 at 4^3 and 36,768 at 2^3 (12,166 of them near), 11.7 hierarchy nodes, 6.9
exact distances; filters 42.8 candidates scanned, 0.7 exact distances, 6.7 kept; leaves 44
bounds, 3.5 exact distances (1.2 ties). CPU time about half the range and centre queries (their
nodes and exact distances spread over the three levels), half the filters and the leaves (the
module notes of ``benchmarks/bench_sdf_grid.py`` have the timings).
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
"""Absolute margin (unit box) of the candidates' bounds: a triangle lies on its computed plane
and inside its computed edge lines and disk up to rounding of about ``1e-16`` times its size
(a triangle too thin for that gets no bound, module notes); the bounds are lowered by this much."""

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


NB = 20
"""Bound coefficients per candidate (``prism`` rows, module notes)."""


@njit(cache=True, inline="always")
def _keep(cv, e, prism, t):
    """Candidate column ``e`` of ``cv`` (NB, n): the bound coefficients ``prism[t]`` of triangle ``t``."""
    for a in range(NB):
        cv[a, e] = prism[t, a]


@njit(cache=True, inline="always")
def _bound_parts(cv, e, px, py, pz):
    """The parts of candidate ``e``'s lower bound at ``p`` (module notes), shared by
    :func:`_margin` and :func:`_bound2`: the signed distance ``hh`` to the triangle's plane, the
    signed distances ``s0, s1, s2`` past its edge lines, and ``v``, the offset of ``p``'s foot on
    the plane from the bounding disk's centre."""
    hh = px * cv[0, e] + py * cv[1, e] + pz * cv[2, e] - cv[3, e]
    s0 = px * cv[4, e] + py * cv[5, e] + pz * cv[6, e] - cv[7, e]
    s1 = px * cv[8, e] + py * cv[9, e] + pz * cv[10, e] - cv[11, e]
    s2 = px * cv[12, e] + py * cv[13, e] + pz * cv[14, e] - cv[15, e]
    vx = px - cv[16, e] - hh * cv[0, e]
    vy = py - cv[17, e] - hh * cv[1, e]
    vz = pz - cv[18, e] - hh * cv[2, e]
    return hh, s0, s1, s2, vx, vy, vz


@njit(cache=True, inline="always")
def _margin(cv, e, px, py, pz, hx, hy, hz, gx, gy, gz, top):
    """The block test of candidate ``e`` for a block (centre ``p``, half extents ``h``, upper
    bound's gradient ``g``, ``top`` = ``D + eps`` plus margin): positive when its bound,
    linearized at ``p`` (it is convex in ``x``, so that bounds it from below), stays above the
    upper bound all over the block (module notes). Branch-free (selects), so that the loop over
    the candidates vectorizes."""
    hh, s0, s1, s2, vx, vy, vz = _bound_parts(cv, e, px, py, pz)
    lv = np.sqrt(vx * vx + vy * vy + vz * vz)
    sd = lv - cv[19, e]
    # the largest in-plane part and its gradient (unit direction)
    ss, ux, uy, uz = s0, cv[4, e], cv[5, e], cv[6, e]
    c1 = s1 > ss
    ss, ux, uy, uz = (s1 if c1 else ss), (cv[8, e] if c1 else ux), (cv[9, e] if c1 else uy), (cv[10, e] if c1 else uz)
    c2 = s2 > ss
    ss, ux, uy, uz = (s2 if c2 else ss), (cv[12, e] if c2 else ux), (cv[13, e] if c2 else uy), (cv[14, e] if c2 else uz)
    cd = sd > ss
    il = 1.0 / max(lv, 1e-300)
    ss, ux, uy, uz = (sd if cd else ss), (vx * il if cd else ux), (vy * il if cd else uy), (vz * il if cd else uz)
    a = max(abs(hh) - TOL, 0.0)
    a = a if hh >= 0.0 else -a
    ss = max(ss - TOL, 0.0)
    bl = np.sqrt(a * a + ss * ss)
    ib = 1.0 / max(bl, 1e-300)
    tx = gx - (a * cv[0, e] + ss * ux) * ib
    ty = gy - (a * cv[1, e] + ss * uy) * ib
    tz = gz - (a * cv[2, e] + ss * uz) * ib
    turn = hx * abs(tx) + hy * abs(ty) + hz * abs(tz)
    # a zero bound (p on the triangle's prism) always passes
    return bl - top - turn * (1.0 + SLACK) if bl > 0.0 else -1.0


@njit(cache=True, inline="always")
def _bound2(cv, e, px, py, pz):
    """Squared lower bound of the distance from ``p`` to candidate ``e``'s triangle (module
    notes): plane part squared plus in-plane part squared, each lowered by :data:`TOL`;
    branch-free."""
    hh, s0, s1, s2, vx, vy, vz = _bound_parts(cv, e, px, py, pz)
    sd = np.sqrt(vx * vx + vy * vy + vz * vz) - cv[19, e]
    ss = max(max(s0, s1, s2, sd) - TOL, 0.0)
    hh = max(abs(hh) - TOL, 0.0)
    return hh * hh + ss * ss


@njit(cache=True)
def _range(cx, cy, cz, hx, hy, hz, r, D, cp, near, lo, hi, tlo, thi, tri, L, m, plane, ball, prism, stack, q, ct,
           cv):
    """The candidates of a block (centre ``c``, half extents ``h``, half-diagonal ``r``, exact
    nearest distance ``D`` at ``c`` with closest point ``cp``) from the hierarchy into ``ct``,
    ``cv``; returns their count. Far (``near`` False): the triangles that pass the block test
    (module notes); near: every triangle within ``D + 2 r`` of ``c``."""
    if near:
        gx, gy, gz, eps, hn = 0.0, 0.0, 0.0, 0.0, 0.0
        R = (D + 2.0 * r) * (1.0 + SLACK)
    else:
        gx, gy, gz = (cx - cp[0]) / D, (cy - cp[1]) / D, (cz - cp[2]) / D
        eps = r * r / (2.0 * (D - r)) + SLACK * (D + r)
        hn = r
        R = D + hx * abs(gx) + hy * abs(gy) + hz * abs(gz) + eps + r
    R2 = R * R
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
            closest_on_triangle(cx, cy, cz, tri, t, q)
            dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
            d2 = dx * dx + dy * dy + dz * dz
            if not d2 <= R2:  # also drops the NaN of a degenerate triangle
                continue
            dt = np.sqrt(d2)
            if not near:
                ux, uy, uz = dx / dt, dy / dt, dz / dt
                if dt - D - eps > hx * abs(gx - ux) + hy * abs(gy - uy) + hz * abs(gz - uz):
                    continue
            ct[nc] = t
            _keep(cv, nc, prism, t)
            nc += 1
    return nc


@njit(cache=True)
def _filter(n, st, sv, dt_, dv, lb, seed, cx, cy, cz, hx, hy, hz, r, climit, tri, q, cp):
    """A child block's candidates (centre ``c``, half extents ``h``, half-diagonal ``r``) from
    its parent's ``n`` (``st``, ``sv``) into ``dt_``, ``dv``: the candidates' bounds are convex
    in ``x``, so linearized at ``c`` they bound from below over the block (module notes). First
    the exact nearest triangle at ``c``, among the parent's candidates (which hold it; ``seed``
    the parent's nearest, measured first), measuring only those whose bound beats the best.
    Returns ``(count, nearest triangle)``, count -1 when nothing lies within ``climit``
    (squared) of ``c``; leaves the nearest point in ``cp``."""
    closest_on_triangle(cx, cy, cz, tri, seed, cp)
    dx, dy, dz = cx - cp[0], cy - cp[1], cz - cp[2]
    best = dx * dx + dy * dy + dz * dz
    bt = seed
    for e in range(n):
        lb[e] = _bound2(sv, e, cx, cy, cz)
    for e in range(n):
        if lb[e] >= best or st[e] == bt:
            continue
        closest_on_triangle(cx, cy, cz, tri, st[e], q)
        dx, dy, dz = cx - q[0], cy - q[1], cz - q[2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 < best:
            best, bt = d2, st[e]
            cp[0], cp[1], cp[2] = q[0], q[1], q[2]
    if not best <= climit:
        return -1, bt
    D = np.sqrt(best)
    dx, dy, dz = cx - cp[0], cy - cp[1], cz - cp[2]
    nd = 0
    if D <= FAR * r:
        # near: d(x) <= D + r and d(x, t) >= bound(c) - r
        R2 = ((D + 2.0 * r) * (1.0 + SLACK)) ** 2
        for e in range(n):
            if lb[e] <= R2:
                dt_[nd] = st[e]
                for a in range(NB):
                    dv[a, nd] = sv[a, e]
                nd += 1
        return nd, bt
    gx, gy, gz = dx / D, dy / D, dz / D
    eps = r * r / (2.0 * (D - r)) + SLACK * (D + r)
    for e in range(n):
        lb[e] = _margin(sv, e, cx, cy, cz, hx, hy, hz, gx, gy, gz, D + eps + SLACK * (D + r))
    for e in range(n):
        if lb[e] > 0.0:
            continue
        dt_[nd] = st[e]
        for a in range(NB):
            dv[a, nd] = sv[a, e]
        nd += 1
    return nd, bt


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
                    lb[e] = _bound2(cv, e, px, py, pz)
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
def grid_signed(origin, spacing, shape, limit, block, lo, hi, tlo, thi, tri, L, m, fn, en, vn, plane, ball, prism,
                out):
    """Signed distances (negative inside) of the samples ``origin + (i, j, k) * spacing`` of a
    grid of ``shape`` into ``out`` (flat, C order); ``inf`` for samples whose squared distance
    exceeds ``limit``. Triangles ``tri (m, 3, 3)``, boxes and pseudo-normals (face ``fn (m, 3)``,
    edge ``en (m, 3, 3)``, vertex per corner ``vn (m, 3, 3)``), unit plane normals ``plane (m, 3)``,
    bounding balls ``ball (m, 4)`` and bound coefficients ``prism (m, NB)`` (module notes) in the
    hierarchy's order. Top blocks of ``block^3``
    samples (``block`` a power of two, at least 2), halved level by level down to ``2^3``."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    bx = (nx + block - 1) // block
    by = (ny + block - 1) // block
    bz = (nz + block - 1) // block
    n_blocks = bx * by * bz
    nlev = 1
    while (block >> nlev) >= 2:
        nlev += 1
    # blocks per parallel chunk, consecutive along z so that warm starts carry over; few chunks,
    # so that the per-chunk work arrays (each as long as the mesh) are allocated rarely
    per = max(1, (n_blocks + CHUNKS - 1) // CHUNKS)
    stride = (m + 511) // 512 * 512 + 8
    for chunk in prange((n_blocks + per - 1) // per):
        stack = np.empty(128, dtype=np.int64)
        boxes = np.empty((8 * nlev + 1, 8), dtype=np.int64)
        q = np.empty(3)
        cp = np.empty(3)
        # per level, the candidates of the block being worked on at that level
        # rows padded to 64 bytes past a multiple of 4 kB: rows a power of two apart would share
        # cache sets (a filter streams all NB rows at once; unpadded, 82k triangles made it 5x slower)
        ct = np.empty((nlev, stride), dtype=np.int64)
        cv = np.empty((nlev, NB, stride))
        lb = np.empty(stride)
        nlist = np.zeros(nlev, dtype=np.int64)
        tlist = np.zeros(nlev, dtype=np.int64)
        prev = -1
        t0 = -1
        for blk in range(chunk * per, min(n_blocks, (chunk + 1) * per)):
            i0 = blk // (by * bz) * block
            j0 = (blk // bz) % by * block
            k0 = blk % bz * block
            sp = 1
            boxes[0, 0], boxes[0, 1] = i0, min(i0 + block, nx)
            boxes[0, 2], boxes[0, 3] = j0, min(j0 + block, ny)
            boxes[0, 4], boxes[0, 5] = k0, min(k0 + block, nz)
            boxes[0, 6], boxes[0, 7] = 0, 0
            # depth first, so that a parent's list (one per level) outlives its children
            while sp > 0:
                sp -= 1
                a0, a1, b0, b1, c0, c1, lev, fresh = (boxes[sp, 0], boxes[sp, 1], boxes[sp, 2], boxes[sp, 3],
                                                      boxes[sp, 4], boxes[sp, 5], boxes[sp, 6], boxes[sp, 7])
                hx = 0.5 * (a1 - 1 - a0) * spacing[0]
                hy = 0.5 * (b1 - 1 - b0) * spacing[1]
                hz = 0.5 * (c1 - 1 - c0) * spacing[2]
                cx = origin[0] + a0 * spacing[0] + hx
                cy = origin[1] + b0 * spacing[1] + hy
                cz = origin[2] + c0 * spacing[2] + hz
                r = np.sqrt(hx * hx + hy * hy + hz * hz)
                reach = np.sqrt(limit)
                climit = (reach + r) ** 2 if reach < np.inf else np.inf
                if fresh == 0:
                    # the centre's exact nearest triangle; none within reach + r: no sample is in the band
                    best, tc, _ = seeded(cx, cy, cz, climit, prev, lo, hi, tlo, thi, tri, L, m, stack, q, cp)
                    if tc < 0:
                        _fill_inf(a0, a1, b0, b1, c0, c1, ny, nz, out)
                        continue
                    prev = tc
                    D = np.sqrt(best)
                    near = D <= FAR * r
                    if near and lev < nlev - 1:
                        sp = _push_children(boxes, sp, a0, a1, b0, b1, c0, c1, lev + 1, block >> (lev + 1), 0)
                        continue
                    n = _range(cx, cy, cz, hx, hy, hz, r, D, cp, near, lo, hi, tlo, thi, tri, L, m, plane, ball,
                               prism, stack, q, ct[lev], cv[lev])
                else:
                    n, tc = _filter(nlist[lev - 1], ct[lev - 1], cv[lev - 1], ct[lev], cv[lev], lb, tlist[lev - 1],
                                    cx, cy, cz, hx, hy, hz, r, climit, tri, q, cp)
                    if n < 0:
                        _fill_inf(a0, a1, b0, b1, c0, c1, ny, nz, out)
                        continue
                nlist[lev], tlist[lev] = n, tc
                if lev < nlev - 1:
                    sp = _push_children(boxes, sp, a0, a1, b0, b1, c0, c1, lev + 1, block >> (lev + 1), 1)
                else:
                    t0 = _leaves(a0, a1, b0, b1, c0, c1, n, ct[lev], cv[lev], lb, tc, t0, origin, spacing, ny, nz,
                                 limit, tri, fn, en, vn, out, q, cp)


@njit(cache=True, inline="always")
def _push_children(boxes, sp, i0, i1, j0, j1, k0, k1, lev, half, mode):
    """Push the (up to) eight parts of side ``half`` of a box (cut by the grid's end), last
    first so that they come off in order."""
    for o in range(7, -1, -1):
        a0, b0, c0 = i0 + (o >> 2) * half, j0 + ((o >> 1) & 1) * half, k0 + (o & 1) * half
        a1, b1, c1 = min(a0 + half, i1), min(b0 + half, j1), min(c0 + half, k1)
        if a0 < a1 and b0 < b1 and c0 < c1:
            boxes[sp, 0], boxes[sp, 1], boxes[sp, 2], boxes[sp, 3] = a0, a1, b0, b1
            boxes[sp, 4], boxes[sp, 5], boxes[sp, 6], boxes[sp, 7] = c0, c1, lev, mode
            sp += 1
    return sp
