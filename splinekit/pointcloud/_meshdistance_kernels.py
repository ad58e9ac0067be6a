"""Compiled (numba) nearest-triangle search of :class:`splinekit.pointcloud.meshdistance.MeshDistance`.

Loaded through :func:`splinekit._kernels.load`, never by ``import splinekit``. The numpy path it
must agree with is in :mod:`splinekit.pointcloud.meshdistance`: :func:`closest_on_triangle` is
the scalar form of its ``closest_points_on_triangles`` (the same Voronoi-region tests in the
same order, the same feature codes), and :func:`nearest` answers what its k-d tree search
answers, the exact nearest triangle, by walking the bounding-volume hierarchy ``TriangleBVH`` (:mod:`._trianglebvh`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, inline="always")
def closest_on_triangle(px, py, pz, tris, k, out):
    """Closest point of triangle ``tris[k]`` (3, 3) to ``p`` written to ``out``; returns
    its feature: 0 face, 1-3 vertex 0-2, 4 edge 01, 5 edge 12, 6 edge 20.
    Classified by the Voronoi regions of vertices, then edges, then the face."""
    t = tris[k]
    ax, ay, az = t[0, 0], t[0, 1], t[0, 2]
    abx, aby, abz = t[1, 0] - ax, t[1, 1] - ay, t[1, 2] - az
    acx, acy, acz = t[2, 0] - ax, t[2, 1] - ay, t[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        out[0], out[1], out[2] = ax, ay, az
        return 1
    bpx, bpy, bpz = px - t[1, 0], py - t[1, 1], pz - t[1, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        out[0], out[1], out[2] = t[1, 0], t[1, 1], t[1, 2]
        return 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        s = d1 / (d1 - d3)
        out[0], out[1], out[2] = ax + s * abx, ay + s * aby, az + s * abz
        return 4
    cpx, cpy, cpz = px - t[2, 0], py - t[2, 1], pz - t[2, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        out[0], out[1], out[2] = t[2, 0], t[2, 1], t[2, 2]
        return 3
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        s = d2 / (d2 - d6)
        out[0], out[1], out[2] = ax + s * acx, ay + s * acy, az + s * acz
        return 6
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        s = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        bx, by, bz = t[1, 0], t[1, 1], t[1, 2]
        out[0] = bx + s * (t[2, 0] - bx)
        out[1] = by + s * (t[2, 1] - by)
        out[2] = bz + s * (t[2, 2] - bz)
        return 5
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    out[0] = ax + abx * v + acx * w
    out[1] = ay + aby * v + acy * w
    out[2] = az + abz * v + acz * w
    return 0


@njit(cache=True, inline="always")
def box_d2(px, py, pz, lo, hi, i):
    """Squared distance from ``p`` to the box ``lo[i]..hi[i]`` (inf for an empty box)."""
    dx = max(lo[i, 0] - px, 0.0, px - hi[i, 0])
    dy = max(lo[i, 1] - py, 0.0, py - hi[i, 1])
    dz = max(lo[i, 2] - pz, 0.0, pz - hi[i, 2])
    return dx * dx + dy * dy + dz * dz


@njit(cache=True, inline="always")
def walk(px, py, pz, best, bt, br, lo, hi, tlo, thi, tri, L, m, stack, q, cp, root):
    """Depth-first search of the BVH below node ``root`` (1 for all of it) for the nearest
    triangle of ``p``, nearer child first, pruning
    every box farther than the squared distance ``best`` (that of triangle ``bt``, region
    ``br``, closest point ``cp``; ``bt = -1`` for none yet). Returns the improved
    ``(best, bt, br)`` and leaves the closest point in ``cp``."""
    sp = 1
    stack[0] = root
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if box_d2(px, py, pz, lo, hi, node) > best:
            continue
        if node >= L:
            first = (node - L) * 4
            for t in range(first, min(first + 4, m)):
                # the triangle's own box first: a cheap lower bound
                if box_d2(px, py, pz, tlo, thi, t) > best:
                    continue
                r = closest_on_triangle(px, py, pz, tri, t, q)
                dx, dy, dz = px - q[0], py - q[1], pz - q[2]
                d2 = dx * dx + dy * dy + dz * dz
                if d2 < best or (bt < 0 and d2 <= best):
                    best, bt, br = d2, t, r
                    cp[0], cp[1], cp[2] = q[0], q[1], q[2]
        else:
            a, b = 2 * node, 2 * node + 1
            da = box_d2(px, py, pz, lo, hi, a)
            db = box_d2(px, py, pz, lo, hi, b)
            # push the farther child first so that the nearer one is searched first
            if da <= db:
                if db <= best:
                    stack[sp] = b
                    sp += 1
                if da <= best:
                    stack[sp] = a
                    sp += 1
            else:
                if da <= best:
                    stack[sp] = a
                    sp += 1
                if db <= best:
                    stack[sp] = b
                    sp += 1
    return best, bt, br


@njit(cache=True, inline="always")
def seeded(px, py, pz, limit, prev, lo, hi, tlo, thi, tri, L, m, stack, q, cp):
    """:func:`walk` within the squared distance ``limit``, first bounded by triangle ``prev``
    (-1 for none): ``(best, bt, br)`` with the closest point in ``cp``."""
    best, bt, br = limit, -1, 0
    if prev >= 0:
        r = closest_on_triangle(px, py, pz, tri, prev, q)
        dx, dy, dz = px - q[0], py - q[1], pz - q[2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 <= best:
            best, bt, br = d2, prev, r
            cp[0], cp[1], cp[2] = q[0], q[1], q[2]
    return walk(px, py, pz, best, bt, br, lo, hi, tlo, thi, tri, L, m, stack, q, cp, 1)


@njit(cache=True, parallel=True)
def nearest(P, limit, lo, hi, tlo, thi, tri, L, m, out_d2, out_tri, out_cp, out_reg):
    """Depth-first BVH search per point, nearer child first; each point starts
    from the previous point's triangle (grid points come in order, so that
    bound is tight and prunes most of the tree)."""
    n = P.shape[0]
    chunk = 1024
    for c in prange((n + chunk - 1) // chunk):
        stack = np.empty(128, dtype=np.int64)
        q = np.empty(3)
        cp = np.empty(3)
        prev = -1
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            best, bt, br = seeded(P[i, 0], P[i, 1], P[i, 2], limit, prev, lo, hi, tlo, thi, tri, L, m, stack, q, cp)
            if bt >= 0:
                prev = bt
                out_d2[i] = best
                out_tri[i] = bt
                out_reg[i] = br
                out_cp[i, 0], out_cp[i, 1], out_cp[i, 2] = cp[0], cp[1], cp[2]
