"""Compiled (numba) exact signed distance of a closed triangle mesh on a grid by scanning the
characteristic regions of its features: :meth:`splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.

Loaded through :func:`splinekit._kernels.load`. The nearest point ``q`` of the mesh to a sample
``x`` lies inside a face, inside an edge or at a vertex, and ``x - q`` then satisfies that
feature's first-order condition (it lies in the feature's normal cone):

* face ``t``: ``x`` projects into ``t`` along its normal (a prism, one per side of the plane);
* edge ``(a, b)`` between triangles with inward in-plane edge normals ``w1``, ``w2``: ``x``
  projects into the edge and ``(x - a) . w1 <= 0``, ``(x - a) . w2 <= 0`` (a wedge; on the
  outside of a convex edge, on the inside of a concave one);
* vertex ``v`` with edge directions ``e_j``: ``(x - v) . e_j <= 0`` for all ``j`` (a convex
  cone, whatever the vertex's shape; empty or a line at a saddle or a flat vertex).

So ``x`` lies in the region of its nearest feature, and the least distance to the triangles
owning the regions that contain ``x`` (a vertex belongs to one of its triangles, an edge to
both of its, which hold its nearest point) is its distance: the true nearest triangle's, by the
same :func:`closest_on_triangle` as the brute-force minimum, so the same value to the last bit
(an edge's two triangles may round the distance to it 1 ulp apart: both are measured). A sample
in no region (beyond the band) gets ``inf``.
Every region is widened by :data:`~._gridsdf_regions.DELTA` against rounding (a wider region
only measures more), and cut where it can no longer hold a nearest point: at a radius ``R``
(distance from the feature, :func:`~._gridsdf_regions.cut`) where an upper bound of the distance
over the region's points at that radius is below ``R``. The distance is 1-Lipschitz and a
region is a cone over its feature (a prism: a translate), so beyond ``R`` every point of it has
something nearer than the feature. The upper bound: exact distances on a coarse grid (every
:data:`CUT_NODES`-th sample, by the hierarchy's nearest-triangle search) plus the way to the
nearest node. Without the cut a face's inner prism would run through the solid and out of the
other side.

Each region is a convex polytope (:mod:`._gridsdf_regions`): half-spaces for the samples of each
grid column (bounds on the index along the column's axis, affine in the column), its corners
(the feature's points and their ends along its extreme directions at the cut) for the rows and
columns to visit (the convex hull of the corners projected along the column axis, the longest
side of their box). The regions' order is the triangle hierarchy's (spatial), so the writes of
one region after another stay in cache; the grid is shared among threads in slabs along its
first axis (every thread visits the regions that reach its slab).

Work (82k triangles at 128^3, 1,869,108 samples, 327,682 regions of which 311,507 non-empty):
2.2 columns and 1.6 exact distances a sample (faces 0.8, edges 0.65, vertices 0.14). One
thread, CPU seconds: connectivity 0.05, coarse grid 0.06, regions and their cuts 0.18, scan
0.44 (faces 0.18, edges 0.20, vertices 0.06); the block kernel of :mod:`._gridsdf_kernels` took
2.6-3.8 in the same runs. The region helpers (:func:`~._gridsdf_regions.geometry`,
:func:`~._gridsdf_regions.polytope`, :func:`~._gridsdf_regions.cut`) are inlined: called, with
their 15-19 array arguments, they cost more than their work (both, over all regions, one
thread: 214 ms called, 77 ms inlined). numba's cache is keyed on this file's text alone: a change
to those helpers reaches the cached kernels here only with a change to this file.
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


CHUNKS = 64
"""Parallel chunks of regions in :func:`cut_all`."""


def parts():
    """Slabs of the grid the scan shares out: one per thread."""
    return get_num_threads()


@njit(cache=True, parallel=True)
def cut_all(V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, origin, spacing, shape, G, go, gh, reach, R, kind,
            box):
    """Every region's cut radius ``R`` and kind (:func:`~._gridsdf_regions.geometry`)
    and the box of sample indices its corners span (``box (n, 6)``: first and past-the-last
    index along each axis; the whole grid when it is wide), for the grid ``origin + (i, j, k) *
    spacing`` of ``shape``; a region is never cut beyond the grid's far corner along its axis
    nor beyond ``reach`` (the band)."""
    n = len(R)
    step = max(spacing[0], max(spacing[1], spacing[2]))
    pad = 1e-3
    per = (n + CHUNKS - 1) // CHUNKS
    for chunk in prange(CHUNKS):  # scratch allocated per chunk, not per region
        geo = np.empty(10)
        e = np.empty((VALENCE, 3))
        rays = np.empty((RAYS, 3))
        hs = np.empty((MAXH, 4))
        cor = np.empty((2 * RAYS + 2, 3))
        for r in range(chunk * per, min(n, (chunk + 1) * per)):
            _, kind[r] = geometry(r, V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, geo, e, rays)
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
            rmax = min(rmax + geo[6] + step, reach * (1.0 + 1e-9) + 1e-300)
            R[r] = cut(geo, rmax, step, G, go, gh)
            _, nc = polytope(r, kind[r], R[r], V, T, tri, plane, prism, ea, eb, ptr, nbr, geo, e, rays, origin, spacing,
                             hs, cor)
            for a in range(3):
                mn, mx = np.inf, -np.inf
                for c in range(nc):
                    mn = min(mn, cor[c, a])
                    mx = max(mx, cor[c, a])
                box[r, a] = max(int(np.ceil(mn - pad)), 0)
                box[r, 3 + a] = min(int(np.floor(mx + pad)) + 1, shape[a])


@njit(cache=True, inline="always")
def _measure(px, py, pz, tri, t, q, f, best, out, limit, fn, en, vn):
    """Sample ``f`` at ``(px, py, pz)`` measured against triangle ``t``: its squared distance and
    signed distance written to ``best[f]`` / ``out[f]`` where nearer than ``best[f]`` and within
    ``limit`` (``q``: scratch for the closest point)."""
    reg = closest_on_triangle(px, py, pz, tri, t, q)
    dx, dy, dz = px - q[0], py - q[1], pz - q[2]
    d2 = dx * dx + dy * dy + dz * dz
    if d2 < best[f] and d2 <= limit:
        best[f] = d2
        out[f] = _signed(px, py, pz, d2, t, reg, q, fn, en, vn)


@njit(cache=True, inline="always")
def _stride(axis, ny, nz):
    """Step in the flat (C order) sample index along ``axis``."""
    return ny * nz if axis == 0 else (nz if axis == 1 else 1)


@njit(cache=True, inline="always")
def _hull(pu, pv, k, hu, hv):
    """Convex hull (monotone chain, counter-clockwise, closed: first point repeated) of the
    ``k`` points ``(pu, pv)`` (sorted in place by ``u``) into ``hu``, ``hv``; returns its count
    and the count of its lower chain (``u`` increasing; the upper chain follows, decreasing)."""
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
    return n, low - 1


@njit(cache=True, inline="always")
def _chain_at(cu, cv, n, p, u, upper):
    """``v`` at ``u`` (clamped to the chain's ends) on the chain ``cu``, ``cv`` of ``n`` points
    (``u`` increasing), walking on from segment ``p`` (rows come in increasing ``u``); returns
    ``(v, p)``. Where the chain runs straight along ``v`` (a vertical segment), the lower or the
    higher end (``upper``)."""
    u = min(max(u, cu[0]), cu[n - 1])
    while p < n - 2 and cu[p + 1] < u:
        p += 1
    u0, u1 = cu[p], cu[p + 1]
    if u1 > u0:
        v = cv[p] + (min(u, u1) - u0) / (u1 - u0) * (cv[p + 1] - cv[p])
    else:
        v = max(cv[p], cv[p + 1]) if upper else min(cv[p], cv[p + 1])
    # a vertical segment right after, at this u
    if p < n - 2 and cu[p + 2] == cu[p + 1] and u == cu[p + 1]:
        v = max(v, cv[p + 2]) if upper else min(v, cv[p + 2])
    return v, p


@njit(cache=True, parallel=True)
def scan(V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, R, kind, box, origin, spacing, shape, limit, fn, en, vn,
         best, out, parts, count):
    """The least squared distance ``best`` (flat, C order, ``inf`` to start) and the signed
    distance ``out`` (``inf`` to start; sign by the pseudo-normals ``fn``, ``en``, ``vn`` of the
    nearest feature, as :func:`~._gridsdf_kernels.grid_signed` gives it) at every sample from the regions (:mod:`._gridsdf_regions`; cut radii ``R`` and
    kinds from :func:`cut_all`); distances beyond ``limit`` (squared) are not kept. ``parts``
    slabs along the first axis, one per parallel task, so that no two write one sample.
    ``count[part]``: columns and distances measured."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = len(R)
    m, ne = len(T), len(ea)
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
        uu = np.empty(4 * RAYS + 6)
        uv = np.empty(4 * RAYS + 6)
        aff = np.empty((MAXH, 4))
        row = np.empty(MAXH)
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
            # an edge's other triangle too: the two may round the distance to the edge 1 ulp
            # apart, and the brute-force minimum takes the lower
            t2 = eh[r - 2 * m, 1] // 3 if 2 * m <= r < 2 * m + ne else -1
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
            nl, nu = 0, 0
            if c1 > 0:
                for c in range(c1):
                    pu[c], pv[c] = cor[c, ua], cor[c, va]
                nhull, nl = _hull(pu, pv, c1, hu, hv)
                # the upper chain, turned to increasing u
                nu = nhull - nl + 1
                for c in range(nu):
                    uu[c], uv[c] = hu[nhull - 1 - c], hv[nhull - 1 - c]
                if nl < 2 or nu < 2:  # corners too close to tell apart: the box's rows
                    nl = 0
            # each half-space as a bound on the sample index along w, affine in the column's
            # (u, v): w <= base - cu * u - cv * v (or >=, by the sign of its w component)
            for h in range(h1):
                aw = hs[h, wa] * spacing[wa]
                if aw == 0.0:  # a bound on the column itself
                    aff[h, 0], aff[h, 3] = 0.0, hs[h, 3] - hs[h, ua] * origin[ua] - hs[h, va] * origin[va]
                    aff[h, 1], aff[h, 2] = hs[h, ua] * spacing[ua], hs[h, va] * spacing[va]
                    continue
                inv = 1.0 / aw
                aff[h, 0] = 1.0 if aw > 0.0 else -1.0
                aff[h, 1] = hs[h, ua] * spacing[ua] * inv
                aff[h, 2] = hs[h, va] * spacing[va] * inv
                aff[h, 3] = (hs[h, 3] - hs[h, ua] * origin[ua] - hs[h, va] * origin[va] - hs[h, wa] * origin[wa]) * inv
            stride_u, stride_v, stride_w = _stride(ua, ny, nz), _stride(va, ny, nz), _stride(wa, ny, nz)
            pl, pw = 0, 0
            for iu in range(lo[ua], hi[ua]):
                v0, v1 = lo[va], hi[va]
                if nl > 0:
                    a, pl = _chain_at(hu, hv, nl, pl, float(iu), False)
                    b, pw = _chain_at(uu, uv, nu, pw, float(iu), True)
                    v0 = max(v0, int(np.ceil(a - pad)))
                    v1 = min(v1, int(np.floor(b + pad)) + 1)
                for h in range(h1):
                    row[h] = aff[h, 3] - aff[h, 1] * iu
                for iv in range(v0, v1):
                    wlo, whi = float(lo[wa]), float(hi[wa] - 1)
                    for h in range(h1):
                        x = row[h] - aff[h, 2] * iv
                        g = aff[h, 0]
                        if g > 0.0:
                            whi = min(whi, x)
                        elif g < 0.0:
                            wlo = max(wlo, x)
                        elif x < 0.0:
                            whi = -1.0
                    if whi < wlo:
                        continue
                    w0, w1 = int(np.ceil(wlo)), int(np.floor(whi)) + 1
                    cols += 1
                    evals += w1 - w0
                    f = iu * stride_u + iv * stride_v + w0 * stride_w
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
                        _measure(px, py, pz, tri, t, q, f, best, out, limit, fn, en, vn)
                        if t2 >= 0:
                            _measure(px, py, pz, tri, t2, q, f, best, out, limit, fn, en, vn)
                        f += stride_w
        count[part, 0] = cols
        count[part, 1] = evals
