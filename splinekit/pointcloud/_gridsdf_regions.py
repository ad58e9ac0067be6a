"""The characteristic regions of a closed mesh's faces, edges and vertices, cut to a grid, for
the region-scanning grid kernel :mod:`splinekit.pointcloud._gridsdf_scan` (whose module notes
give the argument). Whole-array numpy, except the compiled per-region cut and vertex cones.

Each region is returned as half-spaces ``a . x <= b`` (``(n, H, 4)``, unused rows ``0 <= 1``),
their count, the box of sample indices its corners span and the triangle that owns it.
"""

from __future__ import annotations

import numpy as np

CUT_NODES = 4
"""Samples between the coarse grid's nodes whose exact distances bound the field from above
(:func:`~._gridsdf_scan.cut`)."""

WIDE = 0.02
"""A wedge or cone whose extreme directions come within ``acos(WIDE)`` of perpendicular to its
axis gets the whole grid as its box (rare: knife edges, spike tips)."""

RAYS = 32
"""Extreme rays kept per vertex cone (more: the whole grid as its box)."""


def _unit(v):
    ln = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(ln > 0, ln, 1.0), ln[..., 0]


def edges(T):
    """Undirected edges of a closed, consistently oriented triangle list ``T (m, 3)``:
    ``(a, b, t1, k1, t2, k2)`` with ``a -> b`` edge ``k1`` of triangle ``t1`` and ``b -> a`` edge
    ``k2`` of ``t2``; None unless every edge has exactly these two uses."""
    m = len(T)
    a = T.ravel()
    b = T[:, [1, 2, 0]].ravel()
    t = np.repeat(np.arange(m), 3)
    k = np.tile(np.arange(3), m)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * (int(T.max()) + 1) + hi
    order = np.lexsort((a > b, key))
    key_s = key[order]
    if len(key_s) % 2 or not (np.all(key_s[0::2] == key_s[1::2]) and np.all(np.diff(key_s[0::2]) > 0)):
        return None
    first, second = order[0::2], order[1::2]
    if not np.all((a[first] < b[first]) & (a[second] > b[second])):
        return None
    return a[first], b[first], t[first], k[first], t[second], k[second]


def build(kern, V, T, tri, plane, prism, origin, spacing, shape, G, gorigin, gspacing, reach, H):
    """Regions of the mesh (unit box; ``V`` vertices, ``T`` triangles in the hierarchy's order,
    ``tri`` their corners, ``plane`` unit normals, ``prism`` the bound coefficients of
    :mod:`._gridsdf_bounds`, whose rows 4-15 are the outward in-plane edge normals and offsets)
    for the grid ``origin + (i, j, k) * spacing`` of ``shape``, cut with the coarse exact
    distances ``G`` (nodes ``gorigin + index * gspacing``) and at ``reach`` (the band).
    ``kern``: the compiled module. Returns ``(hs, nh, box, owner)``, or None when the mesh is
    not a closed 2-manifold with every triangle's plane defined."""
    ed = edges(T)
    if ed is None or not plane.any(axis=1).all():
        return None
    delta = kern.DELTA
    shape = np.asarray(shape)
    glo, ghi = origin, origin + (shape - 1) * spacing
    corners = np.array([[glo[0] if i & 4 else ghi[0], glo[1] if i & 2 else ghi[1], glo[2] if i & 1 else ghi[2]]
                        for i in range(8)])
    gn = np.array(G.shape, dtype=np.int64)
    step = float(spacing.max())

    def cuts(m, A, rho, spread):
        rmax = np.max((corners[None] - m[:, None]) @ A[:, :, None], axis=1)[:, 0] + rho + step
        R = kern.cuts(m, A, rho, spread, rmax, step, G, gorigin, gspacing, gn)
        return np.minimum(R, reach * (1.0 + 1e-9) + rho + step)

    out = []
    # faces: one prism per side of the plane
    u = prism[:, 4:16].reshape(-1, 3, 4)  # (m, 3 edges, (u, u . a))
    cen = tri.mean(axis=1)
    rho_t = np.linalg.norm(tri - cen[:, None], axis=2).max(axis=1)
    off = np.einsum("ij,ij->i", plane, tri[:, 0])
    for s in (1.0, -1.0):
        A = s * plane
        R = cuts(cen, A, rho_t, np.zeros(len(tri)))
        hs = np.zeros((len(tri), 5, 4))
        hs[:, :3] = u
        hs[:, :3, 3] += delta
        hs[:, 3, :3], hs[:, 3, 3] = -A, -s * off + delta
        hs[:, 4, :3], hs[:, 4, 3] = A, s * off + R + delta
        pts = np.concatenate([tri, tri + R[:, None, None] * A[:, None, :]], axis=1)
        out.append((hs, np.ones(hs.shape[:2], dtype=bool), pts, np.ones(pts.shape[:2], dtype=bool), np.arange(len(tri)),
                    np.zeros(len(tri), dtype=bool)))
    # edges: a wedge between the two triangles' inward edge normals
    a, b, t1, k1, t2, k2 = ed
    pa, pb = V[a], V[b]
    e, le = _unit(pb - pa)
    w1, w2 = -u[t1, k1, :3], -u[t2, k2, :3]
    flat = np.linalg.norm(w1 + w2, axis=1) < 1e-12  # in the two prisms' widened sides
    d1 = np.cross(e, w1)
    d1 *= np.where(np.einsum("ij,ij->i", d1, w2) <= 0, 1.0, -1.0)[:, None]
    d2 = np.cross(e, w2)
    d2 *= np.where(np.einsum("ij,ij->i", d2, w1) <= 0, 1.0, -1.0)[:, None]
    A, la = _unit(d1 + d2)
    keep = ~flat
    c1 = np.minimum(np.einsum("ij,ij->i", d1, A), np.einsum("ij,ij->i", d2, A))
    wide = (la < 1e-9) | (c1 < WIDE)
    mid = 0.5 * (pa + pb)
    spread = 2.0 * np.sqrt(np.maximum(0.5 * (1.0 - c1), 0.0))
    R = cuts(mid, A, 0.5 * le, np.where(wide, 2.0, spread))
    hs = np.zeros((len(a), 5, 4))
    hs[:, 0, :3], hs[:, 0, 3] = -e, -np.einsum("ij,ij->i", e, pa) + delta
    hs[:, 1, :3], hs[:, 1, 3] = e, np.einsum("ij,ij->i", e, pb) + delta
    hs[:, 2, :3], hs[:, 2, 3] = w1, np.einsum("ij,ij->i", w1, pa) + delta
    hs[:, 3, :3], hs[:, 3, 3] = w2, np.einsum("ij,ij->i", w2, pa) + delta
    hs[:, 4, :3], hs[:, 4, 3] = A, np.einsum("ij,ij->i", A, pa) + R + delta
    live = np.ones(hs.shape[:2], dtype=bool)
    live[wide, 4] = False
    ends = (R / np.maximum(c1, WIDE))[:, None, None]
    pts = np.concatenate([pa[:, None], pb[:, None], pa[:, None] + ends * d1[:, None], pb[:, None] + ends * d1[:, None],
                          pa[:, None] + ends * d2[:, None], pb[:, None] + ends * d2[:, None]], axis=1)
    out.append((hs[keep], live[keep], pts[keep], np.ones(pts[keep].shape[:2], dtype=bool), t1[keep], wide[keep]))
    # vertices: the cone of directions making an obtuse angle with every edge
    nv = len(V)
    src = np.concatenate([a, b])
    dst = np.concatenate([b, a])
    order = np.argsort(src, kind="stable")
    nbr = dst[order]
    ptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=nv))])
    rays = np.zeros((nv, RAYS, 3))
    nray = np.zeros(nv, dtype=np.int64)
    kern.vertex_rays(V, ptr, nbr, rays, nray)
    used = ptr[1:] > ptr[:-1]
    ray_ok = np.arange(RAYS)[None, :] < np.maximum(nray, 0)[:, None]
    A, la = _unit(np.where(ray_ok[:, :, None], rays, 0.0).sum(axis=1))
    cosr = np.where(ray_ok, np.einsum("vrj,vj->vr", rays, A), 1.0)
    c1 = cosr.min(axis=1)
    cone = used & (nray != 0) & ~((nray > 0) & (la < 1e-6 * np.maximum(nray, 1)))  # no cone, or a line
    wide = (nray < 0) | (c1 < WIDE)
    spread = np.where(wide, 2.0, 2.0 * np.sqrt(np.maximum(0.5 * (1.0 - c1), 0.0)))
    R = cuts(V, A, np.zeros(nv), spread)
    val = np.minimum(ptr[1:] - ptr[:-1], H - 1)
    hv = np.zeros((nv, H, 4))
    slot = np.arange(H - 1)[None, :]
    pick = np.minimum(ptr[:-1, None] + slot, len(nbr) - 1)
    ev, _ = _unit(V[nbr[pick]] - V[:, None])
    hv[:, :H - 1, :3] = ev
    hv[:, :H - 1, 3] = np.einsum("vsj,vj->vs", ev, V) + delta
    hv[:, H - 1, :3], hv[:, H - 1, 3] = A, np.einsum("ij,ij->i", A, V) + R + delta
    live = np.zeros((nv, H), dtype=bool)
    live[:, :H - 1] = slot < val[:, None]
    live[:, H - 1] = ~wide
    ends = np.where(ray_ok, R[:, None] / np.maximum(cosr, WIDE), 0.0)
    pts = np.concatenate([V[:, None], V[:, None] + ends[:, :, None] * rays], axis=1)
    pl = np.concatenate([np.ones((nv, 1), dtype=bool), ray_ok], axis=1)
    owner_v = np.zeros(nv, dtype=np.int64)
    for c in range(3):
        owner_v[T[:, c]] = np.arange(len(T))  # any triangle at the vertex holds it
    out.append((hv[cone], live[cone], pts[cone], pl[cone], owner_v[cone], wide[cone]))

    # compressed rows: region r's half-spaces hs[hptr[r]:hptr[r + 1]], corners likewise
    hs_l, hn_l, pt_l, pn_l, own_l = [], [], [], [], []
    for hs, live, pts, pl, own, wide in out:
        hs_l.append(hs[live])
        hn_l.append(live.sum(axis=1))
        pl = pl & ~wide[:, None]
        pt_l.append((pts[pl] - origin) / spacing)
        pn_l.append(pl.sum(axis=1))
        own_l.append(own)
    hptr = np.concatenate([[0], np.cumsum(np.concatenate(hn_l))])
    cptr = np.concatenate([[0], np.cumsum(np.concatenate(pn_l))])
    return hptr, np.concatenate(hs_l), cptr, np.concatenate(pt_l), np.concatenate(own_l)
