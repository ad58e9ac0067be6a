"""The characteristic regions of a closed mesh's faces, edges and vertices as convex polytopes,
cut where they can no longer hold a nearest point: compiled (numba) helpers of the
region-scanning grid kernel :mod:`splinekit.pointcloud._gridsdf_scan`, whose module notes give
the argument, inlined there.

Regions are numbered: ``[0, m)`` the faces' prisms on the side their normal points to,
``[m, 2m)`` on the other side, then one wedge per edge, then one cone per vertex. All in the
unit box of :class:`~splinekit.pointcloud.meshdistance.MeshDistance`; triangles in the
hierarchy's order. :func:`geometry` gives a region's cone (centre, axis, spread);
:func:`polytope` its half-spaces and corners once its cut radius is known.
"""

from __future__ import annotations

import numpy as np
from numba import njit

DELTA = 1e-9
"""Absolute widening of every region's half-spaces (unit box): rounding moves a computed
plane by about ``1e-16`` of the mesh's size, so a sample whose nearest point lies on a feature
is inside its computed region; a wider region only measures more."""

FLAT = 1e-12
"""An edge whose two inward edge normals cancel to this (coplanar triangles) or a vertex whose
cone's extreme rays cancel to ``FLAT_RAYS`` per ray gets no region: its points lie in its
triangles' prisms, widened by :data:`DELTA` (the mesh spans at most the unit box)."""

FLAT_RAYS = 1e-6

WIDE = 0.02
"""A wedge or cone with an extreme direction within ``acos(WIDE)`` of perpendicular to its axis
is not cut and spans the whole grid (knife edges, spike tips: rare)."""

RAYS = 32
"""Extreme rays of a vertex cone kept (more: the cone spans the whole grid)."""

VALENCE = 64
"""Edges at a vertex whose cone is computed (more: the cone spans the whole grid)."""

MAXH = 16
"""Half-spaces of a vertex cone at most: its first ``MAXH - 1`` edges and the cut (fewer
constraints only widen it)."""


@njit(cache=True, inline="always")
def _upper(cx, cy, cz, G, go, gh):
    """An upper bound of the distance at ``c``: the nearest coarse node's exact distance plus
    the way there."""
    i = min(max(int(np.floor((cx - go[0]) / gh[0] + 0.5)), 0), G.shape[0] - 1)
    j = min(max(int(np.floor((cy - go[1]) / gh[1] + 0.5)), 0), G.shape[1] - 1)
    k = min(max(int(np.floor((cz - go[2]) / gh[2] + 0.5)), 0), G.shape[2] - 1)
    dx, dy, dz = cx - (go[0] + i * gh[0]), cy - (go[1] + j * gh[1]), cz - (go[2] + k * gh[2])
    return G[i, j, k] + np.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, inline="always")
def _beaten(R, geo, G, go, gh):
    """True when every point at distance ``R`` from a region's feature (inside the ball of
    radius ``rho + R spread`` about ``m + R a``, ``geo`` as :func:`geometry` fills it) has
    something nearer than ``R``."""
    u = _upper(geo[0] + R * geo[3], geo[1] + R * geo[4], geo[2] + R * geo[5], G, go, gh) + geo[6] + R * geo[7]
    return u * (1.0 + 1e-9) + 1e-12 < R


@njit(cache=True, inline="always")
def cut(geo, rmax, step, G, go, gh):
    """A radius beyond which a region holds no nearest point, at most ``rmax``: ``rmax`` when
    :func:`_beaten` rejects it (a region running out of the grid unopposed: one test), else
    doubling from ``step``, then four halvings of the last interval. The distance is
    1-Lipschitz and a region is a cone over its feature, so a radius that :func:`_beaten`
    accepts holds for every larger one (module notes of the scan kernel)."""
    if not _beaten(rmax, geo, G, go, gh):
        return rmax
    R = step
    while R < rmax and not _beaten(R, geo, G, go, gh):
        R *= 2.0
    if R >= rmax:
        return rmax
    lo, hi = 0.5 * R, R
    for _ in range(4):
        mid = 0.5 * (lo + hi)
        if _beaten(mid, geo, G, go, gh):
            hi = mid
        else:
            lo = mid
    return hi


@njit(cache=True, inline="always")
def _unit3(x, y, z):
    ln = np.sqrt(x * x + y * y + z * z)
    return x / ln, y / ln, z / ln, ln


@njit(cache=True, inline="always")
def _rays(v, V, ptr, nbr, e, rays):
    """The extreme rays of vertex ``v``'s cone ``{y : y . e_j <= 0}`` (``e_j`` its unit edge
    directions, written to ``e``): unit normals of planes through two edges that satisfy every
    constraint (to ``1e-12``) into ``rays``; returns their count, -1 when there are more than
    it holds or the vertex has more than :data:`VALENCE` edges."""
    a, b = ptr[v], ptr[v + 1]
    k = b - a
    if k > VALENCE:
        return -1
    for j in range(k):
        w = nbr[a + j]
        e[j, 0], e[j, 1], e[j, 2], _ = _unit3(V[w, 0] - V[v, 0], V[w, 1] - V[v, 1], V[w, 2] - V[v, 2])
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
                    if n == rays.shape[0]:
                        return -1
                    rays[n, 0], rays[n, 1], rays[n, 2] = s * cx, s * cy, s * cz
                    n += 1
    return n


@njit(cache=True, inline="always")
def geometry(r, V, T, tri, plane, prism, ea, eb, eh, ptr, nbr, vown, geo, e, rays):
    """Region ``r``'s cone into ``geo``: centre ``m`` (0-2), unit axis ``a`` (3-5), the radius
    ``rho`` of its feature about ``m`` (6), the spread (7: every point at distance ``R`` from
    the feature lies within ``rho + R spread`` of ``m + R a``), the least cosine between ``a``
    and an extreme direction (8). Returns ``(owner, kind)``: kind 0 none (a flat edge or
    vertex), 1 cut by a radius, 2 wide (spans the grid); for a vertex its rays stay in
    ``rays`` (count in ``geo[9]``), its unit edge directions in ``e``."""
    m = len(T)
    ne = len(ea)
    if r < 2 * m:
        t = r % m
        s = 1.0 if r < m else -1.0
        geo[0] = (tri[t, 0, 0] + tri[t, 1, 0] + tri[t, 2, 0]) / 3.0
        geo[1] = (tri[t, 0, 1] + tri[t, 1, 1] + tri[t, 2, 1]) / 3.0
        geo[2] = (tri[t, 0, 2] + tri[t, 1, 2] + tri[t, 2, 2]) / 3.0
        geo[3], geo[4], geo[5] = s * plane[t, 0], s * plane[t, 1], s * plane[t, 2]
        rho = 0.0
        for c in range(3):
            dx, dy, dz = tri[t, c, 0] - geo[0], tri[t, c, 1] - geo[1], tri[t, c, 2] - geo[2]
            rho = max(rho, np.sqrt(dx * dx + dy * dy + dz * dz))
        geo[6], geo[7], geo[8] = rho * (1.0 + 1e-12), 0.0, 1.0
        return t, 1
    if r < 2 * m + ne:
        i = r - 2 * m
        h1, h2 = eh[i, 0], eh[i, 1]
        t1, k1, t2, k2 = h1 // 3, h1 % 3, h2 // 3, h2 % 3
        a, b = ea[i], eb[i]
        ex, ey, ez, le = _unit3(V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2])
        w1x, w1y, w1z = -prism[t1, 4 + 4 * k1], -prism[t1, 5 + 4 * k1], -prism[t1, 6 + 4 * k1]
        w2x, w2y, w2z = -prism[t2, 4 + 4 * k2], -prism[t2, 5 + 4 * k2], -prism[t2, 6 + 4 * k2]
        sx, sy, sz = w1x + w2x, w1y + w2y, w1z + w2z
        if sx * sx + sy * sy + sz * sz < FLAT * FLAT:
            return t1, 0
        # the wedge's extreme directions: perpendicular to the edge and to one inward normal,
        # on the outer side of the other
        d1x, d1y, d1z = ey * w1z - ez * w1y, ez * w1x - ex * w1z, ex * w1y - ey * w1x
        if d1x * w2x + d1y * w2y + d1z * w2z > 0.0:
            d1x, d1y, d1z = -d1x, -d1y, -d1z
        d2x, d2y, d2z = ey * w2z - ez * w2y, ez * w2x - ex * w2z, ex * w2y - ey * w2x
        if d2x * w1x + d2y * w1y + d2z * w1z > 0.0:
            d2x, d2y, d2z = -d2x, -d2y, -d2z
        ax, ay, az, la = _unit3(d1x + d2x, d1y + d2y, d1z + d2z)
        c1 = min(d1x * ax + d1y * ay + d1z * az, d2x * ax + d2y * ay + d2z * az)
        geo[0], geo[1], geo[2] = 0.5 * (V[a, 0] + V[b, 0]), 0.5 * (V[a, 1] + V[b, 1]), 0.5 * (V[a, 2] + V[b, 2])
        geo[3], geo[4], geo[5] = ax, ay, az
        geo[6] = 0.5 * le * (1.0 + 1e-12)
        geo[8] = c1
        e[0, 0], e[0, 1], e[0, 2] = d1x, d1y, d1z
        e[1, 0], e[1, 1], e[1, 2] = d2x, d2y, d2z
        e[2, 0], e[2, 1], e[2, 2] = w1x, w1y, w1z
        e[3, 0], e[3, 1], e[3, 2] = w2x, w2y, w2z
        e[4, 0], e[4, 1], e[4, 2] = ex, ey, ez
        if not la > 1e-9 or c1 < WIDE:
            geo[7] = 2.0
            return t1, 2
        geo[7] = 2.0 * np.sqrt(max(0.5 * (1.0 - c1), 0.0))
        return t1, 1
    v = r - 2 * m - ne
    owner = vown[v]
    geo[0], geo[1], geo[2], geo[6] = V[v, 0], V[v, 1], V[v, 2], 0.0
    n = _rays(v, V, ptr, nbr, e, rays)
    geo[9] = n
    if n == 0:
        return owner, 0
    if n < 0:
        geo[3], geo[4], geo[5], geo[7], geo[8] = 1.0, 0.0, 0.0, 2.0, 0.0
        return owner, 2
    sx, sy, sz = 0.0, 0.0, 0.0
    for j in range(n):
        sx, sy, sz = sx + rays[j, 0], sy + rays[j, 1], sz + rays[j, 2]
    ln = np.sqrt(sx * sx + sy * sy + sz * sz)
    if ln < FLAT_RAYS * n:
        return owner, 0
    geo[3], geo[4], geo[5] = sx / ln, sy / ln, sz / ln
    c1 = 1.0
    for j in range(n):
        c1 = min(c1, rays[j, 0] * geo[3] + rays[j, 1] * geo[4] + rays[j, 2] * geo[5])
    geo[8] = c1
    if c1 < WIDE:
        geo[7] = 2.0
        return owner, 2
    geo[7] = 2.0 * np.sqrt(max(0.5 * (1.0 - c1), 0.0))
    return owner, 1


@njit(cache=True, inline="always")
def _row(hs, n, x, y, z, b):
    hs[n, 0], hs[n, 1], hs[n, 2], hs[n, 3] = x, y, z, b
    return n + 1


@njit(cache=True, inline="always")
def _corner(cor, n, x, y, z, origin, spacing):
    cor[n, 0] = (x - origin[0]) / spacing[0]
    cor[n, 1] = (y - origin[1]) / spacing[1]
    cor[n, 2] = (z - origin[2]) / spacing[2]
    return n + 1


@njit(cache=True, inline="always")
def polytope(r, kind, R, V, T, tri, plane, prism, ea, eb, ptr, nbr, geo, e, rays, origin, spacing, hs, cor):
    """Region ``r`` (after :func:`geometry`, whose ``geo``, ``e``, ``rays`` it reads) cut at
    radius ``R``: its half-spaces ``a . x <= b`` into ``hs`` and its corners in sample-index
    units into ``cor`` (none when ``kind`` is 2: it spans the grid). Returns their counts."""
    m = len(T)
    ne = len(ea)
    ax, ay, az = geo[3], geo[4], geo[5]
    nh, nc = 0, 0
    if r < 2 * m:
        t = r % m
        s = 1.0 if r < m else -1.0
        for k in range(3):
            nh = _row(hs, nh, prism[t, 4 + 4 * k], prism[t, 5 + 4 * k], prism[t, 6 + 4 * k],
                      prism[t, 7 + 4 * k] + DELTA)
        off = s * (plane[t, 0] * tri[t, 0, 0] + plane[t, 1] * tri[t, 0, 1] + plane[t, 2] * tri[t, 0, 2])
        nh = _row(hs, nh, -ax, -ay, -az, -off + DELTA)
        nh = _row(hs, nh, ax, ay, az, off + R + DELTA)
        for c in range(3):
            x, y, z = tri[t, c, 0], tri[t, c, 1], tri[t, c, 2]
            nc = _corner(cor, nc, x, y, z, origin, spacing)
            nc = _corner(cor, nc, x + R * ax, y + R * ay, z + R * az, origin, spacing)
        return nh, nc
    if r < 2 * m + ne:
        i = r - 2 * m
        a, b = ea[i], eb[i]
        ex, ey, ez = e[4, 0], e[4, 1], e[4, 2]
        nh = _row(hs, nh, -ex, -ey, -ez, -(ex * V[a, 0] + ey * V[a, 1] + ez * V[a, 2]) + DELTA)
        nh = _row(hs, nh, ex, ey, ez, ex * V[b, 0] + ey * V[b, 1] + ez * V[b, 2] + DELTA)
        for w in (2, 3):
            nh = _row(hs, nh, e[w, 0], e[w, 1], e[w, 2], e[w, 0] * V[a, 0] + e[w, 1] * V[a, 1] + e[w, 2] * V[a, 2] + DELTA)
        if kind == 2:
            return nh, 0
        nh = _row(hs, nh, ax, ay, az, ax * V[a, 0] + ay * V[a, 1] + az * V[a, 2] + R + DELTA)
        for p in (a, b):
            nc = _corner(cor, nc, V[p, 0], V[p, 1], V[p, 2], origin, spacing)
            for d in (0, 1):
                f = R / (e[d, 0] * ax + e[d, 1] * ay + e[d, 2] * az)
                nc = _corner(cor, nc, V[p, 0] + f * e[d, 0], V[p, 1] + f * e[d, 1], V[p, 2] + f * e[d, 2], origin,
                             spacing)
        return nh, nc
    v = r - 2 * m - ne
    k = min(ptr[v + 1] - ptr[v], MAXH - 1)
    if ptr[v + 1] - ptr[v] > VALENCE:  # no unit edge directions were made
        for j in range(k):
            w = nbr[ptr[v] + j]
            e[j, 0], e[j, 1], e[j, 2], _ = _unit3(V[w, 0] - V[v, 0], V[w, 1] - V[v, 1], V[w, 2] - V[v, 2])
    for j in range(k):
        nh = _row(hs, nh, e[j, 0], e[j, 1], e[j, 2], e[j, 0] * V[v, 0] + e[j, 1] * V[v, 1] + e[j, 2] * V[v, 2] + DELTA)
    if kind == 2:
        return nh, 0
    nh = _row(hs, nh, ax, ay, az, ax * V[v, 0] + ay * V[v, 1] + az * V[v, 2] + R + DELTA)
    nc = _corner(cor, nc, V[v, 0], V[v, 1], V[v, 2], origin, spacing)
    for j in range(int(geo[9])):
        f = R / (rays[j, 0] * ax + rays[j, 1] * ay + rays[j, 2] * az)
        nc = _corner(cor, nc, V[v, 0] + f * rays[j, 0], V[v, 1] + f * rays[j, 1], V[v, 2] + f * rays[j, 2], origin,
                     spacing)
    return nh, nc
