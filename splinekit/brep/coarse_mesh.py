"""Coarse triangle meshes of trimmed faces, for winding numbers, distance bands and volume signs.

Not the tessellation (:mod:`splinekit.tessellation` meshes to a requested tolerance, watertight
across edges): these meshes only need a known, measured deviation from the face. Vertices are
exact surface points: the trims sampled per Bézier piece and a ``(u, v)`` grid kept clear of them,
triangulated by Delaunay in ``(u, v)`` and kept where the triangles' centroids lie inside the
sampled trims. Each face also gets a cap: a fan from one apex to its sampled trims, with the same
oriented boundary, whose winding number equals the mesh's away from the face.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from .topology import surface_points
from .trims import sample_trims, segment_distance

__all__ = ["face_mesh", "face_cap", "winding_numbers", "point_triangle_distance", "segment_distance"]


def face_mesh(face, per_span: int = 8):
    """A triangle mesh of the trimmed face: ``(vertices (k, 3), triangles (t, 3), deviation)``.

    Vertices are the trims sampled per Bézier piece plus a ``(u, v)`` grid kept clear of the trims
    by half a cell: ``per_span`` cells per knot span in a curved direction, one in a straight one,
    more where needed for cells about as long as wide in 3-D. A Delaunay triangulation of them is
    kept where the triangles' centroids are inside the trims (dense trim samples make every trim
    chord a Delaunay edge). ``deviation`` bounds the mesh's distance from the face, estimated at
    edge mid points. Triangles face outward (flipped on reversed faces). Cached on the face.
    """
    if "mesh" in face._cache:
        return face._cache["mesh"]
    s = face.surface
    axes = []
    for knots, degree in ((s.knots_u, s.degree_u), (s.knots_v, s.degree_v)):
        br = np.unique(knots[degree:len(knots) - degree])
        axes.append((br, per_span if degree > 1 else 1))
    # equalize the 3-D cell sizes: cells as long as wide within a factor 2
    coarse = [np.unique(np.concatenate([np.linspace(a, b, k + 1) for a, b in zip(br[:-1], br[1:])])) for br, k in axes]
    G = s.evaluate_grid(coarse[0], coarse[1])
    hu = float(np.linalg.norm(np.diff(G, axis=0), axis=-1).max()) if G.shape[0] > 1 else 0.0
    hv = float(np.linalg.norm(np.diff(G, axis=1), axis=-1).max()) if G.shape[1] > 1 else 0.0
    h = max(min(hu, hv), 1e-300)
    counts = [max(1, min(256, int(np.ceil(hu / (2.0 * h)))) ) * axes[0][1],
              max(1, min(256, int(np.ceil(hv / (2.0 * h))))) * axes[1][1]]
    lines = [np.unique(np.concatenate([np.linspace(a, b, k + 1) for a, b in zip(br[:-1], br[1:])]))
             for (br, _), k in zip(axes, counts)]
    cell = np.array([np.diff(lines[0]).max(), np.diff(lines[1]).max()])
    # trims: curved pieces per_span points, then every segment cut to at most a cell
    rings = [_refine_polygon(p, cell) for p, _, _ in sample_trims(face, per_span)]
    trim = np.concatenate(rings)
    face._cache["cap"] = _cap(face, rings)
    scale = 1.0 / np.maximum(cell, 1e-300)  # u and v in cells: "half a cell" the same both ways
    U, V = np.meshgrid(lines[0], lines[1], indexing="ij")
    grid = np.stack([U.ravel(), V.ravel()], axis=1)
    grid = grid[polygon_parity(rings, grid)]
    if len(grid):
        from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep
        d, _ = cKDTree(trim * scale).query(grid * scale)
        grid = grid[d > 0.5]
    pts2 = np.unique(np.concatenate([trim, grid]), axis=0)
    if len(pts2) < 3:
        out = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.intp), 0.0)
        face._cache["mesh"] = out
        return out
    from scipy.spatial import Delaunay  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep
    tri = Delaunay(pts2 * scale).simplices
    cen = pts2[tri].mean(axis=1)
    tri = tri[polygon_parity(rings, cen)]
    # counter-clockwise in (u, v): the normal Su x Sv side
    a, b, c = pts2[tri[:, 0]], pts2[tri[:, 1]], pts2[tri[:, 2]]
    ccw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) > 0
    tri = np.where(ccw[:, None], tri, tri[:, [0, 2, 1]])
    if face.reversed:
        tri = tri[:, [0, 2, 1]]
    P = surface_points(face, pts2)
    # deviation: the surface at the (u, v) mid points of triangle edges against the 3-D chords'
    # mid points, and the trims' mid points against their chords
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    mid_uv = 0.5 * (pts2[e[:, 0]] + pts2[e[:, 1]])
    dev = np.linalg.norm(surface_points(face, mid_uv) - 0.5 * (P[e[:, 0]] + P[e[:, 1]]), axis=1)
    # and the trims' own curvature: the twice-as-dense samples' odd points against the chords
    # (sampled twice as densely, a curved piece's odd points are the mid points of the coarse
    # segments, whose ends are their neighbours)
    dev_trim = 0.0
    for p2, _, j in sample_trims(face, 2 * per_span):
        odd = np.flatnonzero(j % 2 == 1)
        if odd.size:
            S = surface_points(face, p2)
            prev, nxt = S[odd - 1], S[(odd + 1) % len(S)]
            dev_trim = max(dev_trim, float(np.linalg.norm(S[odd] - 0.5 * (prev + nxt), axis=1).max()))
    out = (P, tri, float(max(dev.max(initial=0.0), dev_trim)))
    face._cache["mesh"] = out
    return out


def face_cap(face):
    """The face's cap ``(V (k + 1, 3), T (k, 3))``: a fan from one apex to its sampled trims
    (built with its mesh, cached)."""
    face_mesh(face)
    return face._cache["cap"]


def polygon_parity(rings, q):
    """Even-odd inside test ``(n,)`` of points ``q`` ``(n, 2)`` against the closed polygons
    ``rings`` (the mesh's own boundary). Each segment meets only the points in its v-range:
    points sorted by v, each segment takes a contiguous run of them."""
    a = np.concatenate(rings)
    b = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    order = np.argsort(q[:, 1], kind="stable")
    vs = q[order, 1]
    lo = np.searchsorted(vs, np.minimum(a[:, 1], b[:, 1]), side="left")
    count = np.searchsorted(vs, np.maximum(a[:, 1], b[:, 1]), side="right") - lo
    total = int(count.sum())
    limits.check(total * 8 * 6, "point/segment pairs")
    seg = np.repeat(np.arange(len(a)), count)
    pt = order[np.repeat(lo, count) + np.arange(total) - np.repeat(np.cumsum(count) - count, count)]
    A, B, Q = a[seg], b[seg], q[pt]
    straddle = (A[:, 1] <= Q[:, 1]) != (B[:, 1] <= Q[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = A[:, 0] + (Q[:, 1] - A[:, 1]) * (B[:, 0] - A[:, 0]) / (B[:, 1] - A[:, 1])
    hits = straddle & (Q[:, 0] < x)
    return np.bincount(pt[hits], minlength=len(q)) % 2 == 1


def _cap(face, rings):
    """A fan of triangles ``(V (k + 1, 3), T (k, 3))`` from one apex (the mean of the trims'
    points) to every segment of the face's sampled trims ``rings`` (closed polygons in
    ``(u, v)``): the same oriented boundary as the face's mesh. Its winding number equals the
    mesh's at every point outside the convex hull of the two, hence outside the box of the
    surface's control points."""
    P = [surface_points(face, r) for r in rings]
    V = np.concatenate(P)
    apex = V.mean(axis=0)
    start = np.cumsum([0] + [len(r) for r in rings])[:-1]
    i = np.concatenate([s + np.arange(len(r)) for s, r in zip(start, rings)])
    j = np.concatenate([s + np.roll(np.arange(len(r)), -1) for s, r in zip(start, rings)])
    k = np.full(len(i), len(V))
    T = np.stack([k, j, i] if face.reversed else [k, i, j], axis=1)
    return np.concatenate([V, apex[None]]), T


def _refine_polygon(p, cell):
    """The closed polygon ``p`` ``(k, 2)`` with every segment cut into equal parts no longer than
    ``cell`` ``(2,)`` in either coordinate (points exactly on the segments)."""
    q = np.roll(p, -1, axis=0)
    k = np.maximum(1, np.ceil((np.abs(q - p) / cell).max(axis=1))).astype(np.intp)
    seg = np.repeat(np.arange(len(p)), k)
    frac = (np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)) / np.repeat(k, k)
    return p[seg] + frac[:, None] * (q[seg] - p[seg])


def winding_numbers(points, V, T):
    """Generalized winding numbers ``(n,)`` of the triangle mesh ``V[T]`` at ``points`` ``(n, 3)``:
    sum of the triangles' signed solid angles (Van Oosterom and Strackee) over 4 pi."""
    n = len(points)
    w = np.zeros(n)
    if len(T) == 0 or n == 0:
        return w
    A, B, C = (V[T[:, i]] for i in range(3))
    chunk = max(1, int(5e5 // len(T)))
    for s in range(0, n, chunk):
        p = points[s:s + chunk]
        limits.check(len(p) * len(T) * 8 * 16, "winding-number pairs")
        # components as (c, t) arrays: plain products beat reductions over a length-3 axis
        ax, ay, az = (A[None, :, k] - p[:, k, None] for k in range(3))
        bx, by, bz = (B[None, :, k] - p[:, k, None] for k in range(3))
        cx, cy, cz = (C[None, :, k] - p[:, k, None] for k in range(3))
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc + (bx * cx + by * cy + bz * cz) * la
               + (cx * ax + cy * ay + cz * az) * lb)
        w[s:s + chunk] = np.arctan2(det, den).sum(axis=1)
    return w / (2.0 * np.pi)


def point_triangle_distance(p, a, b, c):
    """Distances ``(n,)`` from points ``p`` to triangles ``(a, b, c)`` (all ``(n, 3)``): the
    closest point by Voronoi regions of the vertices, edges and interior (Ericson 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp, cp = p - b, p - c
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
    q = a + v[:, None] * ab + w[:, None] * ac
    # outside the interior: the nearest of the three edges (clamped segments) is the answer
    outside = (va < 0) | (vb < 0) | (vc < 0) | (denom == 0)
    d = np.linalg.norm(p - q, axis=1)
    if outside.any():
        o = outside
        d[o] = np.minimum.reduce([segment_distance(a[o], b[o], p[o]), segment_distance(b[o], c[o], p[o]),
                                  segment_distance(c[o], a[o], p[o])])
    return d


