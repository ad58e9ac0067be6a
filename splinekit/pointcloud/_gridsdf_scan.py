"""Compiled (numba) exact signed distance of a closed triangle mesh on a grid by scanning the
characteristic regions of its features: :meth:`splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.

Loaded through :func:`splinekit._kernels.load`. The nearest point ``q`` of the mesh to a sample
``x`` lies inside a face, inside an edge or at a vertex, and ``x - q`` then satisfies that
feature's first-order condition (its normal cone):

* face ``t``: ``x`` projects into ``t`` along its normal (a prism, one per side of the plane);
* edge ``(a, b)`` between triangles with inward in-plane edge normals ``w1``, ``w2``: ``x``
  projects into the edge and ``(x - a) . w1 <= 0``, ``(x - a) . w2 <= 0`` (a wedge);
* vertex ``v`` with edge directions ``e_j``: ``(x - v) . e_j <= 0`` for all ``j`` (a cone).

So ``x`` lies in the region of its nearest feature, and the least distance to the triangles
owning the regions that contain ``x`` (an edge or vertex belongs to one of its triangles, which
holds its nearest point) is its distance, exactly as the brute-force minimum over all triangles
gives it (the same :func:`closest_on_triangle`). Every region is widened by :data:`DELTA`
against rounding (a wider region only measures more), and cut where it can no longer hold a
nearest point: at the radius ``R`` (distance from the feature, :func:`cut`) where an upper
bound of the distance field over the region's points at that radius is below ``R``; the
distance is 1-Lipschitz and a region is a cone over its feature, so beyond ``R`` every point
has something nearer than the feature. The upper bound comes from exact distances on a coarse
grid (``G``) plus the distance to the coarse node.

Each region is a convex polytope: half-spaces (:data:`H` at most) for the samples of each grid
column, its corners (the feature's points and their ends along its extreme directions at the
cut) for the box of columns to scan.
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange

from ._gridsdf_kernels import _signed
from ._gridsdf_regions import MAXH, RAYS, VALENCE, cut, geometry, polytope
from ._meshdistance_kernels import closest_on_triangle

CUT_NODES = 8
"""Samples between the nodes of the coarse grid whose exact distances bound the field from
above for the cuts (one thread, 82k triangles at 128^3: 4 costs 0.3 s of queries, 8 about 0.05 s
and 7 % more distances)."""


def parts():
    """Slabs of the grid the scan shares out: one per thread."""
    return get_num_threads()


@njit(cache=True, parallel=True)
def cut_all(V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, origin, spacing, shape, G, go, gh, reach, R, kind,
            owner, box):
    """Every region's cut radius ``R``, kind and owning triangle (:func:`~._gridsdf_regions.geometry`)
    and the box of sample indices its corners span (``box (n, 6)``: first and past-the-last
    index along each axis; the whole grid when it is wide), for the grid ``origin + (i, j, k) *
    spacing`` of ``shape``; a region is never cut beyond the grid's far corner along its axis
    nor beyond ``reach`` (the band)."""
    n = len(R)
    step = max(spacing[0], max(spacing[1], spacing[2]))
    pad = 1e-3
    for r in prange(n):
        geo = np.empty(10)
        e = np.empty((VALENCE, 3))
        rays = np.empty((RAYS, 3))
        hs = np.empty((MAXH, 4))
        cor = np.empty((2 * RAYS + 2, 3))
        owner[r], kind[r] = geometry(r, V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, geo, e, rays)
        for a in range(3):
            box[r, a], box[r, 3 + a] = 0, shape[a]
        R[r] = np.inf
        if kind[r] != 1:
            continue
        rmax = -np.inf
        for c in range(8):
            x = origin[0] + (shape[0] - 1) * spacing[0] * ((c >> 2) & 1)
            y = origin[1] + (shape[1] - 1) * spacing[1] * ((c >> 1) & 1)
            z = origin[2] + (shape[2] - 1) * spacing[2] * (c & 1)
            rmax = max(rmax, (x - geo[0]) * geo[3] + (y - geo[1]) * geo[4] + (z - geo[2]) * geo[5])
        rmax = rmax + geo[6] + step
        R[r] = min(cut(geo, rmax, step, G, go, gh), reach * (1.0 + 1e-9) + 1e-300)
        _, nc = polytope(r, kind[r], R[r], V, T, tri, plane, prism, ea, eb, ptr, nbr, geo, e, rays, origin, spacing, hs,
                         cor)
        for a in range(3):
            mn, mx = np.inf, -np.inf
            for c in range(nc):
                mn = min(mn, cor[c, a])
                mx = max(mx, cor[c, a])
            box[r, a] = max(int(np.ceil(mn - pad)), 0)
            box[r, 3 + a] = min(int(np.floor(mx + pad)) + 1, shape[a])


@njit(cache=True, inline="always")
def _column_range(hs, h0, h1, ua, va, wa, xu, xv, ow, hw, w0, w1):
    """The samples ``[lo, hi)`` along axis ``wa`` of the column at ``(xu, xv)`` (coordinates
    along axes ``ua``, ``va``) inside the half-spaces ``hs[h0:h1]``, within ``[w0, w1)``."""
    lo, hi = float(w0), float(w1 - 1)
    for s in range(h0, h1):
        a = hs[s, wa]
        rest = hs[s, 3] - hs[s, ua] * xu - hs[s, va] * xv - a * ow
        if a > 0.0:
            hi = min(hi, np.floor(rest / (a * hw)))
        elif a < 0.0:
            lo = max(lo, np.ceil(rest / (a * hw)))
        elif rest < 0.0:
            return 0, 0
    if hi < lo:
        return 0, 0
    return int(lo), int(hi) + 1


@njit(cache=True, inline="always")
def _hull(pu, pv, k, hu, hv):
    """Convex hull (monotone chain, counter-clockwise, closed: first point repeated) of the
    ``k`` points ``(pu, pv)`` (sorted in place by ``u``) into ``hu``, ``hv``; returns its count."""
    for i in range(1, k):  # insertion sort by (u, v): k is small
        a, b = pu[i], pv[i]
        j = i - 1
        while j >= 0 and (pu[j] > a or (pu[j] == a and pv[j] > b)):
            pu[j + 1], pv[j + 1] = pu[j], pv[j]
            j -= 1
        pu[j + 1], pv[j + 1] = a, b
    n = 0
    for i in range(k):
        while n >= 2 and (hu[n - 1] - hu[n - 2]) * (pv[i] - hv[n - 2]) - (hv[n - 1] - hv[n - 2]) * (pu[i] - hu[n - 2]) <= 0.0:
            n -= 1
        hu[n], hv[n] = pu[i], pv[i]
        n += 1
    low = n + 1
    for i in range(k - 2, -1, -1):
        while n >= low and (hu[n - 1] - hu[n - 2]) * (pv[i] - hv[n - 2]) - (hv[n - 1] - hv[n - 2]) * (pu[i] - hu[n - 2]) <= 0.0:
            n -= 1
        hu[n], hv[n] = pu[i], pv[i]
        n += 1
    return n


@njit(cache=True, inline="always")
def _row_range(hu, hv, nh, u, pad):
    """``[lo, hi]`` of ``v`` over the hull ``hu``, ``hv`` (closed, ``nh`` points) at ``u``,
    widened by ``pad``; ``lo > hi`` when the line misses it."""
    lo, hi = np.inf, -np.inf
    for e in range(nh - 1):
        u0, u1 = hu[e], hu[e + 1]
        if (u0 - pad <= u <= u1 + pad) or (u1 - pad <= u <= u0 + pad):
            if u1 != u0:
                t = min(max((u - u0) / (u1 - u0), 0.0), 1.0)
                v = hv[e] + t * (hv[e + 1] - hv[e])
            else:
                v = hv[e]
                lo = min(lo, hv[e + 1])
                hi = max(hi, hv[e + 1])
            lo = min(lo, v)
            hi = max(hi, v)
    if nh == 1:
        lo, hi = hv[0], hv[0]
    return lo - pad, hi + pad


@njit(cache=True, parallel=True)
def scan(V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, R, kind, box, origin, spacing, shape, limit, best, who,
         parts, count):
    """The least squared distance ``best`` (flat, C order, ``inf`` to start) and its triangle
    ``who`` at every sample from the regions (:mod:`._gridsdf_regions`; cut radii ``R`` and
    kinds from :func:`cut_all`); distances beyond ``limit`` (squared) are not kept. ``parts``
    slabs along the first axis, one per parallel task, so that no two write one sample.
    ``count[part]``: columns and distances measured."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = len(R)
    per = (nx + parts - 1) // parts
    pad = 1e-3
    for part in prange(parts):
        s0, s1 = part * per, min(nx, (part + 1) * per)
        q = np.empty(3)
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        geo = np.empty(10)
        e = np.empty((VALENCE, 3))
        rays = np.empty((RAYS, 3))
        hs = np.empty((MAXH, 4))
        cor = np.empty((2 * RAYS + 2, 3))
        pu = np.empty(2 * RAYS + 2)
        pv = np.empty(2 * RAYS + 2)
        hu = np.empty(4 * RAYS + 6)
        hv = np.empty(4 * RAYS + 6)
        cols, evals = 0, 0
        for r in range(n):
            if kind[r] == 0:
                continue
            for a in range(3):
                lo[a], hi[a] = box[r, a], box[r, 3 + a]
            lo[0] = max(lo[0], s0)
            hi[0] = min(hi[0], s1)
            if lo[0] >= hi[0] or lo[1] >= hi[1] or lo[2] >= hi[2]:
                continue
            t, _ = geometry(r, V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, geo, e, rays)
            h1, c1 = polytope(r, kind[r], R[r], V, T, tri, plane, prism, ea, eb, ptr, nbr, geo, e, rays, origin, spacing,
                              hs, cor)
            # the longest side innermost: fewest columns
            e0, e1, e2 = hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]
            if e2 >= e0 and e2 >= e1:
                ua, va, wa = 0, 1, 2
            elif e1 >= e0:
                ua, va, wa = 0, 2, 1
            else:
                ua, va, wa = 1, 2, 0
            nhull = 0
            if c1 > 0:
                for c in range(c1):
                    pu[c], pv[c] = cor[c, ua], cor[c, va]
                nhull = _hull(pu, pv, c1, hu, hv)
            for iu in range(lo[ua], hi[ua]):
                xu = origin[ua] + iu * spacing[ua]
                v0, v1 = lo[va], hi[va]
                if nhull > 0:
                    a, b = _row_range(hu, hv, nhull, float(iu), pad)
                    v0 = max(v0, int(np.ceil(a)))
                    v1 = min(v1, int(np.floor(b)) + 1)
                for iv in range(v0, v1):
                    xv = origin[va] + iv * spacing[va]
                    w0, w1 = _column_range(hs, 0, h1, ua, va, wa, xu, xv, origin[wa], spacing[wa], lo[wa], hi[wa])
                    cols += 1
                    evals += w1 - w0
                    for iw in range(w0, w1):
                        if wa == 2:
                            i, j, k = iu, iv, iw
                        elif wa == 1:
                            i, j, k = iu, iw, iv
                        else:
                            i, j, k = iw, iu, iv
                        px = origin[0] + i * spacing[0]
                        py = origin[1] + j * spacing[1]
                        pz = origin[2] + k * spacing[2]
                        closest_on_triangle(px, py, pz, tri, t, q)
                        dx, dy, dz = px - q[0], py - q[1], pz - q[2]
                        d2 = dx * dx + dy * dy + dz * dz
                        f = (i * ny + j) * nz + k
                        if d2 < best[f] and d2 <= limit:
                            best[f] = d2
                            who[f] = t
        count[part, 0] = cols
        count[part, 1] = evals


@njit(cache=True, parallel=True)
def finish(origin, spacing, shape, best, who, tri, fn, en, vn, out):
    """Signed distances from the nearest triangles ``who`` (-1: none within the limit, ``inf``):
    the sign by the pseudo-normal of the nearest feature, as the block kernel gives it."""
    ny, nz = shape[1], shape[2]
    for i in prange(shape[0]):
        q = np.empty(3)
        for j in range(ny):
            for k in range(nz):
                f = (i * ny + j) * nz + k
                t = who[f]
                if t < 0:
                    out[f] = np.inf
                    continue
                px = origin[0] + i * spacing[0]
                py = origin[1] + j * spacing[1]
                pz = origin[2] + k * spacing[2]
                reg = closest_on_triangle(px, py, pz, tri, t, q)
                out[f] = _signed(px, py, pz, best[f], t, reg, q, fn, en, vn)
