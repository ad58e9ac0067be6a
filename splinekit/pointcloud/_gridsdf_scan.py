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
from numba import njit, prange

from ._gridsdf_kernels import _signed
from ._meshdistance_kernels import closest_on_triangle

H = 16
"""Half-spaces per region at most (a vertex of valence up to ``H - 1``, plus the cut)."""

DELTA = 1e-9
"""Absolute widening of every region's half-spaces (unit box): rounding moves a computed
plane by about ``1e-16`` of the mesh's size."""


@njit(cache=True, inline="always")
def _upper(cx, cy, cz, G, go, gh, gn):
    """An upper bound of the distance at ``c`` (unit box): the nearest coarse node's exact
    distance plus the way there."""
    i = min(max(int(np.floor((cx - go[0]) / gh[0] + 0.5)), 0), gn[0] - 1)
    j = min(max(int(np.floor((cy - go[1]) / gh[1] + 0.5)), 0), gn[1] - 1)
    k = min(max(int(np.floor((cz - go[2]) / gh[2] + 0.5)), 0), gn[2] - 1)
    dx, dy, dz = cx - (go[0] + i * gh[0]), cy - (go[1] + j * gh[1]), cz - (go[2] + k * gh[2])
    return G[i, j, k] + np.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, inline="always")
def _beaten(R, mx, my, mz, ax, ay, az, rho, spread, G, go, gh, gn):
    """True when every point at radius ``R`` of a region (inside the ball of radius
    ``rho + R spread`` about ``m + R a``) has something nearer than ``R``."""
    u = _upper(mx + R * ax, my + R * ay, mz + R * az, G, go, gh, gn) + rho + R * spread
    return u * (1.0 + 1e-9) + 1e-12 < R


@njit(cache=True)
def cut(mx, my, mz, ax, ay, az, rho, spread, rmax, step, G, go, gh, gn):
    """A radius beyond which a region holds no nearest point (module notes), at most ``rmax``:
    doubling from ``step``, then four halvings of the last interval."""
    R = step
    while R < rmax and not _beaten(R, mx, my, mz, ax, ay, az, rho, spread, G, go, gh, gn):
        R *= 2.0
    if R >= rmax:
        return rmax
    lo, hi = 0.5 * R, R
    for _ in range(4):
        mid = 0.5 * (lo + hi)
        if _beaten(mid, mx, my, mz, ax, ay, az, rho, spread, G, go, gh, gn):
            hi = mid
        else:
            lo = mid
    return hi


@njit(cache=True, parallel=True)
def cuts(m, A, rho, spread, rmax, step, G, go, gh, gn):
    """:func:`cut` of every region (rows of ``m``, ``A``, ``rho``, ``spread``, ``rmax``)."""
    out = np.empty(len(rho))
    for r in prange(len(rho)):
        out[r] = cut(m[r, 0], m[r, 1], m[r, 2], A[r, 0], A[r, 1], A[r, 2], rho[r], spread[r], rmax[r], step, G, go,
                     gh, gn)
    return out


@njit(cache=True)
def vertex_rays(vpos, nbr_ptr, nbr, rays, nray):
    """Extreme rays of each vertex's cone ``{y : y . e_j <= 0}`` (``e_j`` its unit edge
    directions, CSR ``nbr_ptr``, ``nbr``): the unit normals of planes through two edges that
    satisfy every constraint (to ``1e-12``), at most ``rays.shape[1]``; ``nray[v] = -1`` when
    there are more."""
    nv = len(nbr_ptr) - 1
    cap = rays.shape[1]
    e = np.empty((64, 3))
    for v in range(nv):
        a, b = nbr_ptr[v], nbr_ptr[v + 1]
        k = b - a
        if k > 64:
            nray[v] = -1
            continue
        for j in range(k):
            w = nbr[a + j]
            dx, dy, dz = vpos[w, 0] - vpos[v, 0], vpos[w, 1] - vpos[v, 1], vpos[w, 2] - vpos[v, 2]
            ln = np.sqrt(dx * dx + dy * dy + dz * dz)
            e[j, 0], e[j, 1], e[j, 2] = dx / ln, dy / ln, dz / ln
        n = 0
        for i in range(k):
            for j in range(i + 1, k):
                cx = e[i, 1] * e[j, 2] - e[i, 2] * e[j, 1]
                cy = e[i, 2] * e[j, 0] - e[i, 0] * e[j, 2]
                cz = e[i, 0] * e[j, 1] - e[i, 1] * e[j, 0]
                ln = np.sqrt(cx * cx + cy * cy + cz * cz)
                if ln < 1e-9:
                    continue
                cx, cy, cz = cx / ln, cy / ln, cz / ln
                for s in (1.0, -1.0):
                    ok = True
                    for q in range(k):
                        if s * (cx * e[q, 0] + cy * e[q, 1] + cz * e[q, 2]) > 1e-12:
                            ok = False
                            break
                    if ok:
                        if n < cap:
                            rays[v, n, 0], rays[v, n, 1], rays[v, n, 2] = s * cx, s * cy, s * cz
                        n += 1
        nray[v] = n if n <= cap else -1


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
def scan(hptr, hs, cptr, corners, owner, origin, spacing, shape, tri, limit, best, who, parts, count):
    """The least squared distance ``best`` (flat, C order, ``inf`` to start) and its triangle
    ``who`` at every sample from the regions: region ``r`` has the half-spaces
    ``hs[hptr[r]:hptr[r + 1]]`` (rows ``a, b`` for ``a . x <= b``), the corners
    ``corners[cptr[r]:cptr[r + 1]]`` in sample-index units (a region ``wide`` has none and spans
    the grid) and the triangle ``owner[r]``; distances beyond ``limit`` (squared) are not kept.
    ``parts`` slabs along the first axis, one per parallel task, so that no two write one
    sample. ``count[part]``: columns and distances measured."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = len(owner)
    per = (nx + parts - 1) // parts
    pad = 1e-3
    for part in prange(parts):
        s0, s1 = part * per, min(nx, (part + 1) * per)
        q = np.empty(3)
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        pu = np.empty(64)
        pv = np.empty(64)
        hu = np.empty(130)
        hv = np.empty(130)
        cols, evals = 0, 0
        for r in range(n):
            c0, c1 = cptr[r], cptr[r + 1]
            if c1 > c0:
                for a in range(3):
                    mn, mx = np.inf, -np.inf
                    for c in range(c0, c1):
                        mn = min(mn, corners[c, a])
                        mx = max(mx, corners[c, a])
                    lo[a] = max(int(np.ceil(mn - pad)), 0)
                    hi[a] = min(int(np.floor(mx + pad)) + 1, shape[a])
            else:
                for a in range(3):
                    lo[a], hi[a] = 0, shape[a]
            lo[0] = max(lo[0], s0)
            hi[0] = min(hi[0], s1)
            if lo[0] >= hi[0] or lo[1] >= hi[1] or lo[2] >= hi[2]:
                continue
            # the longest side innermost: fewest columns
            e0, e1, e2 = hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]
            if e2 >= e0 and e2 >= e1:
                ua, va, wa = 0, 1, 2
            elif e1 >= e0:
                ua, va, wa = 0, 2, 1
            else:
                ua, va, wa = 1, 2, 0
            nhull = 0
            if c1 > c0:
                for c in range(c0, c1):
                    pu[c - c0], pv[c - c0] = corners[c, ua], corners[c, va]
                nhull = _hull(pu, pv, c1 - c0, hu, hv)
            t = owner[r]
            h0, h1 = hptr[r], hptr[r + 1]
            for iu in range(lo[ua], hi[ua]):
                xu = origin[ua] + iu * spacing[ua]
                v0, v1 = lo[va], hi[va]
                if nhull > 0:
                    a, b = _row_range(hu, hv, nhull, float(iu), pad)
                    v0 = max(v0, int(np.ceil(a)))
                    v1 = min(v1, int(np.floor(b)) + 1)
                for iv in range(v0, v1):
                    xv = origin[va] + iv * spacing[va]
                    w0, w1 = _column_range(hs, h0, h1, ua, va, wa, xu, xv, origin[wa], spacing[wa], lo[wa], hi[wa])
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
