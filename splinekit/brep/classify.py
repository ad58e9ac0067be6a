"""Point classification: (u, v) points against a face's trims, 3-D points against a solid.

Both return ``int8`` arrays of :class:`Location` codes: ``INSIDE = 1``, ``ON = 0``, ``OUTSIDE = -1``.

Faces (:func:`contains_uv`)
    The trims are cut into Bézier pieces. A point's crossings with the ``+u`` ray are counted on
    each piece's chord, which is exact whenever the point lies outside the piece's bounding box
    (the piece and its chord then wind around the point equally: both lie in the convex hull of
    the control points). Pieces whose box holds the point are halved (de Casteljau, vectorized over
    all such point/piece pairs) until the point is clear of the box or the piece is shorter than
    an eighth of the tolerance; the point is then ON when it lies within the tolerance of that
    short chord. Inside is decided by the even-odd rule on the summed crossings (so a face with a
    loop turned the wrong way still classifies as its loops are drawn; :mod:`check` reports the
    orientation).

    The ON rule is measured in ``(u, v)``: a point is ON when its ``(u, v)`` distance to a trim
    is at most ``tol_uv = tolerance / speed`` with ``speed`` the surface's largest parametric speed
    ``max(|Su|, |Sv|)`` (sampled), so every ON point is within ``tolerance`` of the trim in 3-D.

Solids (:func:`contains`)
    A bounding-box prefilter, then the generalized winding number of the boundary on a triangle
    mesh of each face (solid angles of the triangles; 1 inside, 0 outside). Points close to the
    mesh, where the mesh's chord error could flip the answer, are decided exactly from their
    closest boundary point: on a face (the surface's closest point, when it lies inside the face's
    trims) the sign of the outward normal, on an edge the sum of the two faces' normals there; ON
    when that distance is within the tolerance.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from .. import limits
from .._validate import as_float_array
from ..basis.bernstein import all_bernstein
from ..errors import ParameterError
from .topology import surface_points

__all__ = ["Location", "INSIDE", "ON", "OUTSIDE", "contains_uv", "contains", "uv_tolerance"]


class Location(IntEnum):
    """Where a point lies relative to a face or a solid."""

    OUTSIDE = -1
    ON = 0
    INSIDE = 1


INSIDE, ON, OUTSIDE = Location.INSIDE, Location.ON, Location.OUTSIDE

_MAX_LEVELS = 64  # halvings of a trim piece: far below any tolerance of a unit-sized piece


# -- faces ----------------------------------------------------------------------------------------
def uv_tolerance(face, tolerance=None):
    """The ``(u, v)`` distance that is at most ``tolerance`` (default the face's; a float or an
    array) in 3-D: ``tolerance / max(|Su|, |Sv|)`` over a grid of the surface's domain (the speed
    is cached per face)."""
    tol = face.tolerance if tolerance is None else (np.asarray(tolerance, dtype=np.float64) if np.ndim(tolerance) else float(tolerance))
    if "speed" not in face._cache:
        (u0, u1), (v0, v1) = face.domain
        s = face.surface
        nu = 4 * max(1, len(s.knots_u) - 2 * s.degree_u - 1) + 1
        nv = 4 * max(1, len(s.knots_v) - 2 * s.degree_v - 1) + 1
        d = s.derivatives_grid(np.linspace(u0, u1, nu), np.linspace(v0, v1, nv), 1)
        speed = max(float(np.linalg.norm(d[1, 0], axis=-1).max()), float(np.linalg.norm(d[0, 1], axis=-1).max()))
        face._cache["speed"] = speed if speed > 0 else 1.0
    return tol / face._cache["speed"]


def _trim_table(face) -> dict:
    """Every trim's Bézier pieces, grouped by degree: ``{p: (H (m, p + 1, 3), loop (m,), edge (m,),
    order (m,))}``; ``H`` rows are homogeneous ``(w u, w v, w)``, ``order`` the piece's position
    along the face's loops (loop after loop). Each loop is closed exactly: an edge's first point is
    moved onto the previous edge's last (gaps beyond tolerance are :mod:`check`'s business).
    Cached on the face."""
    if "trim_table" in face._cache:
        return face._cache["trim_table"]
    rows: dict[int, list] = {}
    count = 0
    for li, lp in enumerate(face.boundary_loops()):
        prev_end = lp[-1].end_uv
        for ei, edge in enumerate(lp):
            pieces = _bezier_coefs(edge.pcurve)
            pieces[0, 0] = np.append(prev_end, 1.0) * pieces[0, 0, 2]
            p = pieces.shape[1] - 1
            for k in range(len(pieces)):
                rows.setdefault(p, []).append((pieces[k], li, ei, count))
                count += 1
            prev_end = pieces[-1, -1, :2] / pieces[-1, -1, 2]
    table = {p: (np.array([r[0] for r in rs]), np.array([r[1] for r in rs]), np.array([r[2] for r in rs]),
                 np.array([r[3] for r in rs])) for p, rs in rows.items()}
    face._cache["trim_table"] = table
    return table


def _bezier_coefs(curve) -> np.ndarray:
    """Homogeneous control points ``(m, p + 1, dim + 1)`` of the curve's Bézier pieces. A curve
    already in Bézier form (clamped, every interior knot of multiplicity ``p``: polylines, the
    conics of :mod:`splinekit.construct`, most converted CAD curves) is sliced directly; others
    go through knot insertion (``to_bezier``)."""
    p, U = curve.degree, curve.knots
    H = curve.homogeneous_points if curve.is_rational else np.column_stack([curve.control_points, np.ones(len(curve.control_points))])
    H = np.array(H, dtype=np.float64)
    _, mult = np.unique(U[p + 1:len(U) - p - 1], return_counts=True)
    if U[0] == U[p] and U[-1] == U[len(U) - p - 1] and np.all(mult == p) and len(H) == p * (len(mult) + 1) + 1:
        idx = p * np.arange(len(mult) + 1)[:, None] + np.arange(p + 1)[None]
        return H[idx]
    out = []
    for b in curve.to_bezier():
        P = np.asarray(b.control_points, dtype=np.float64)
        w = np.ones(len(P)) if b.weights is None else np.asarray(b.weights, dtype=np.float64)
        out.append(np.concatenate([P * w[:, None], w[:, None]], axis=1))
    return np.array(out)


def trim_pieces(face, loop: int | None = None) -> dict:
    """The face's trims (or loop ``loop`` alone) as homogeneous Bézier pieces grouped by degree:
    ``{p: (m, p + 1, 3)}`` (see :func:`_trim_table`)."""
    table = _trim_table(face)
    if loop is None:
        return {p: t[0] for p, t in table.items()}
    return {p: t[0][t[1] == loop] for p, t in table.items() if np.any(t[1] == loop)}


def sample_trims(face, per_piece: int) -> list:
    """Polylines of the face's loops: per loop ``(points (k, 2), edge (k,), j (k,))``, point ``i``
    starting segment ``i`` (cyclically), ``j`` its index within its piece. Curved pieces give
    ``per_piece`` points each (``t = j / per_piece``), straight ones their start point only;
    evaluated for all pieces of a degree at once (Bernstein matrix)."""
    table = _trim_table(face)
    n_pieces = sum(len(t[0]) for t in table.values())
    counts = np.zeros(n_pieces, dtype=np.intp)
    for p, (H, _, _, order) in table.items():
        counts[order] = 1 if p == 1 else per_piece
    start = np.concatenate([[0], np.cumsum(counts)])
    pts = np.empty((start[-1], 2))
    loop_of = np.empty(start[-1], dtype=np.intp)
    edge_of = np.empty(start[-1], dtype=np.intp)
    local = np.empty(start[-1], dtype=np.intp)
    for p, (H, loops, edges, order) in table.items():
        k = 1 if p == 1 else per_piece
        B = all_bernstein(p, np.arange(k) / k)  # (p + 1, k)
        X = np.einsum("ik,mid->mkd", B, H)
        where = (start[order][:, None] + np.arange(k)[None]).ravel()
        pts[where] = (X[..., :2] / X[..., 2:]).reshape(-1, 2)
        loop_of[where] = np.repeat(loops, k)
        edge_of[where] = np.repeat(edges, k)
        local[where] = np.tile(np.arange(k), len(H))
    return [(pts[loop_of == li], edge_of[loop_of == li], local[loop_of == li]) for li in range(len(face.boundary_loops()))]


def _halve(H: np.ndarray):
    """De Casteljau at 1/2 of homogeneous Bézier pieces ``(m, p + 1, k)``: ``(left, right)``."""
    p = H.shape[1] - 1
    left = np.empty_like(H)
    right = np.empty_like(H)
    Q = H.copy()
    left[:, 0] = Q[:, 0]
    right[:, p] = Q[:, p]
    for r in range(1, p + 1):
        Q = 0.5 * (Q[:, :-1] + Q[:, 1:])
        left[:, r] = Q[:, 0]
        right[:, p - r] = Q[:, -1]
    return left, right


def _chord_crossings(a, b, q):
    """Signed crossings ``(n,)`` of the ``+u`` rays from ``q`` with the chords ``a -> b`` (all
    ``(n, 2)``): +1 upward with ``q`` on the left, -1 downward with ``q`` on the right."""
    side = (b[:, 0] - a[:, 0]) * (q[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (q[:, 0] - a[:, 0])
    up = (a[:, 1] <= q[:, 1]) & (b[:, 1] > q[:, 1]) & (side > 0)
    down = (a[:, 1] > q[:, 1]) & (b[:, 1] <= q[:, 1]) & (side < 0)
    return up.astype(np.int64) - down.astype(np.int64)


def _segment_distance(a, b, q):
    """Distances ``(n,)`` from points ``q`` to segments ``a -> b`` (all ``(n, d)``)."""
    ab = b - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    t = np.divide(np.einsum("ij,ij->i", q - a, ab), L2, out=np.zeros(len(q)), where=L2 > 0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(q - (a + t[:, None] * ab), axis=1)


def _classify_uv(pieces: dict, uv: np.ndarray, tol: float) -> np.ndarray:
    """Location codes of ``uv`` ``(n, 2)`` against closed trims given as Bézier pieces."""
    n = len(uv)
    crossings = np.zeros(n, dtype=np.int64)
    on = np.zeros(n, dtype=bool)
    small = tol / 8.0
    # only pairs whose point lies in the piece's v-range (widened by tol) can cross or be near:
    # points sorted by v, each piece takes a contiguous run of them
    order = np.argsort(uv[:, 1], kind="stable")
    vs = uv[order, 1]
    for H0 in pieces.values():
        C0 = H0[:, :, :2] / H0[:, :, 2:]
        first = np.searchsorted(vs, C0[:, :, 1].min(axis=1) - tol, side="left")
        count = np.searchsorted(vs, C0[:, :, 1].max(axis=1) + tol, side="right") - first
        ends = np.cumsum(count)
        # pieces in chunks of about 4e6 pairs (memory budget)
        bounds = np.unique(np.concatenate([[0], np.searchsorted(ends, np.arange(4e6, ends[-1] if len(ends) else 0, 4e6)), [len(H0)]]))
        for c0, c1 in zip(bounds[:-1], bounds[1:]):
            cnt = count[c0:c1]
            total = int(cnt.sum())
            if total == 0:
                continue
            limits.check(total * 8 * 4, "point/trim pairs")
            pc = np.repeat(np.arange(c1 - c0), cnt)
            offs = np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            pt = order[np.repeat(first[c0:c1], cnt) + offs]
            H = H0[c0:c1]
            Hs = H
            for level in range(_MAX_LEVELS + 1):
                if pt.size == 0:
                    break
                C = Hs[:, :, :2] / Hs[:, :, 2:]
                lo, hi = C.min(axis=1), C.max(axis=1)
                q = uv[pt]
                inbox = np.all((q >= lo[pc] - tol) & (q <= hi[pc] + tol), axis=1)
                a, b = C[pc, 0], C[pc, -1]
                clear = ~inbox
                np.add.at(crossings, pt[clear], _chord_crossings(a[clear], b[clear], q[clear]))
                diag = np.linalg.norm(hi - lo, axis=1)
                short = inbox & ((diag[pc] <= small) | (level == _MAX_LEVELS))
                if short.any():
                    near = _segment_distance(a[short], b[short], q[short]) <= tol
                    on[pt[short][near]] = True
                    far = ~near
                    np.add.at(crossings, pt[short][far], _chord_crossings(a[short][far], b[short][far], q[short][far]))
                split = inbox & ~short
                if not split.any():
                    break
                # halve only the pieces some point still needs, then pair each point with both halves
                used, inv = np.unique(pc[split], return_inverse=True)
                left, right = _halve(Hs[used])
                Hs = np.concatenate([left, right])
                pt = np.concatenate([pt[split], pt[split]])
                pc = np.concatenate([inv, inv + len(used)])
    out = np.where(crossings % 2 == 1, np.int8(INSIDE), np.int8(OUTSIDE))
    out[on] = ON
    return out


def contains_uv(face, uv, tolerance: float | None = None) -> np.ndarray:
    """Classify parameter points against the face's trims.

    Parameters
    ----------
    uv : (n, 2) or (2,) array_like
    tolerance : float, optional
        3-D distance (model units) within which a point counts as ON a trim (default the face's
        tolerance); converted to ``(u, v)`` by :func:`uv_tolerance`.

    Returns an ``int8`` array ``(n,)`` (or a scalar for one point) of :class:`Location` codes.
    """
    arr = as_float_array(uv, "uv")
    single = arr.ndim == 1
    pts = arr.reshape(1, -1) if single else arr
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ParameterError(f"uv must have shape (n, 2), got {arr.shape}")
    if not np.isfinite(pts).all():
        raise ParameterError("uv has non-finite values")
    out = _classify_uv(trim_pieces(face), pts, uv_tolerance(face, tolerance))
    return out[0] if single else out


# -- solids ---------------------------------------------------------------------------------------
def _face_mesh(face, per_span: int = 8):
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
    grid = grid[_polygon_parity(rings, grid)]
    if len(grid):
        d, _ = cKDTree(trim * scale).query(grid * scale)
        grid = grid[d > 0.5]
    pts2 = np.unique(np.concatenate([trim, grid]), axis=0)
    if len(pts2) < 3:
        out = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.intp), 0.0)
        face._cache["mesh"] = out
        return out
    tri = Delaunay(pts2 * scale).simplices
    cen = pts2[tri].mean(axis=1)
    tri = tri[_polygon_parity(rings, cen)]
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


def _polygon_parity(rings, q):
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


def _winding_numbers(points, V, T):
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


def _point_triangle_distance(p, a, b, c):
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
        d[o] = np.minimum.reduce([_segment_distance(a[o], b[o], p[o]), _segment_distance(b[o], c[o], p[o]),
                                  _segment_distance(c[o], a[o], p[o])])
    return d


def _near_mesh(solid, Q, tol):
    """Boolean mask ``(n,)``: points within ``3 deviation + 2 tol`` of a face's mesh (where the
    mesh's winding number may differ from the exact one, or the point may be ON)."""
    near = np.zeros(len(Q), dtype=bool)
    for f in solid.faces:
        P, T, dev = _face_mesh(f)
        if len(T) == 0:
            continue
        band = 3.0 * dev + 2.0 * tol
        # the mesh lies in the box of the surface's control points: only points near it count
        sel = np.flatnonzero(_box_distance(Q, f.surface.control_points.reshape(-1, 3)) <= band)
        if sel.size == 0:
            continue
        A, B, C = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
        cen = (A + B + C) / 3.0
        R = float(np.max([np.linalg.norm(X - cen, axis=1).max() for X in (A, B, C)]))
        lists = cKDTree(cen).query_ball_point(Q[sel], band + R)
        counts = np.fromiter((len(x) for x in lists), dtype=np.intp, count=len(sel))
        if not counts.any():
            continue
        qi = np.repeat(sel, counts)
        ti = np.fromiter((j for x in lists for j in x), dtype=np.intp, count=int(counts.sum()))
        limits.check(len(ti) * 8 * 30, "point/triangle distance pairs")
        d = _point_triangle_distance(Q[qi], A[ti], B[ti], C[ti])
        near[qi[d <= band]] = True
    return near


def _solid_mesh(solid):
    """All faces' meshes as one ``(V, T)`` (cached on the solid)."""
    if "mesh" not in solid._cache:
        meshes = [_face_mesh(f) for f in solid.faces]
        offsets = np.cumsum([0] + [len(m[0]) for m in meshes])
        solid._cache["mesh"] = (np.concatenate([m[0] for m in meshes]),
                                np.concatenate([m[1] + o for m, o in zip(meshes, offsets)]))
    return solid._cache["mesh"]


def _solid_winding_numbers(solid, Q, tol):
    """Winding numbers ``(n,)`` of the solid's boundary at ``Q``: per face, its mesh for the points
    inside the box of its control points and, where it has fewer triangles, its cap (the same
    value, exactly) for the points outside."""
    w = np.zeros(len(Q))
    for f in solid.faces:
        P, T, _ = _face_mesh(f)
        cV, cT = f._cache["cap"] if "cap" in f._cache else (P, T)
        if len(cT) >= len(T):
            w += _winding_numbers(Q, P, T)
            continue
        cp = f.surface.control_points.reshape(-1, 3)
        margin = tol + 1e-9 * float(np.ptp(cp, axis=0).max())
        near = np.all((Q >= cp.min(axis=0) - margin) & (Q <= cp.max(axis=0) + margin), axis=1)
        w[near] += _winding_numbers(Q[near], P, T)
        w[~near] += _winding_numbers(Q[~near], cV, cT)
    return w


def _bounding_box(solid):
    """Box of every face's control points (contains the solid by the convex-hull property)."""
    pts = np.concatenate([f.surface.control_points.reshape(-1, 3) for f in solid.faces])
    return pts.min(axis=0), pts.max(axis=0)


def contains(solid, points, tolerance: float | None = None) -> np.ndarray:
    """Classify 3-D points against a solid: ``int8`` :class:`Location` codes ``(n,)``.

    Parameters
    ----------
    points : (n, 3) or (3,) array_like
    tolerance : float, optional
        Distance (model units) within which a point is ON the boundary; default the largest face
        tolerance.
    """
    from ..closest import project

    arr = as_float_array(points, "points")
    single = arr.ndim == 1
    P = arr.reshape(1, -1) if single else arr
    if P.ndim != 2 or P.shape[1] != 3:
        raise ParameterError(f"points must have shape (n, 3), got {arr.shape}")
    if not np.isfinite(P).all():
        raise ParameterError("points have non-finite values")
    faces = solid.faces
    tol = max(f.tolerance for f in faces) if tolerance is None else float(tolerance)
    out = np.full(len(P), np.int8(OUTSIDE))
    lo, hi = _bounding_box(solid)
    cand = np.flatnonzero(np.all((P >= lo - tol) & (P <= hi + tol), axis=1))
    if cand.size == 0:
        return out[0] if single else out
    Q = P[cand]
    w = _solid_winding_numbers(solid, Q, tol)
    out[cand] = np.where(np.rint(w) % 2 == 1, np.int8(INSIDE), np.int8(OUTSIDE))
    # near the mesh, its chord error may decide wrongly: settle those points exactly
    near = np.flatnonzero(_near_mesh(solid, Q, tol))
    if near.size:
        out[cand[near]] = _closest_feature_side(solid, Q[near], tol, out[cand[near]], project)
    return out[0] if single else out


def _closest_feature_side(solid, Q, tol, fallback, project):
    """Location codes of points ``Q`` near the boundary from their closest boundary point: a
    face's interior foot (sign of the outward normal) or an edge (sign of the two faces' normals
    summed). Points whose closest feature is a vertex keep ``fallback`` (the winding number)."""
    n = len(Q)
    best = np.full(n, np.inf)
    side = np.zeros(n)
    faces = solid.faces
    # the mesh's vertices lie on the boundary: their nearest one bounds the closest distance, so
    # faces and edges whose box is further away are skipped
    V, _ = _solid_mesh(solid)
    bound = cKDTree(V).query(Q)[0] * (1.0 + 1e-9) + tol
    for f in faces:
        sel = np.flatnonzero(_box_distance(Q, f.surface.control_points.reshape(-1, 3)) < np.minimum(best, bound))
        if sel.size == 0:
            continue
        pr = project(f.surface, Q[sel])
        uv = np.asarray(pr.parameters).reshape(len(sel), 2)
        ok = contains_uv(f, uv) != OUTSIDE
        better = ok & (pr.distances < best[sel])
        if better.any():
            nrm = f.normals(uv[better, 0], uv[better, 1])
            idx = sel[better]
            best[idx] = pr.distances[better]
            side[idx] = np.einsum("ij,ij->i", Q[idx] - pr.points[better], nrm)
    vertex = np.zeros(n, dtype=bool)
    for shell in solid.shells:
        topo = shell.topology
        sf = shell.faces
        for g in topo.edges:
            if g.degenerate:
                continue
            fi, li, ei = g.uses[0]
            e = sf[fi].boundary_loops()[li][ei]
            if e.curve is None:
                continue
            sel = np.flatnonzero(_box_distance(Q, e.curve.control_points) < np.minimum(best, bound))
            if sel.size == 0:
                continue
            pr = project(e.curve, Q[sel])
            hit = pr.distances < best[sel]
            if not hit.any():
                continue
            better = sel[hit]
            t = np.asarray(pr.parameters).reshape(len(sel))[hit]
            feet = pr.points[hit]
            dist = pr.distances[hit]
            a, b = e.domain
            at_end = (np.abs(t - a) <= 1e-9 * max(1.0, abs(b - a))) | (np.abs(t - b) <= 1e-9 * max(1.0, abs(b - a)))
            nsum = np.zeros((len(better), 3))
            for (fj, lj, ej) in g.uses:
                use = sf[fj].boundary_loops()[lj][ej]
                # the other use's (u, v) at the same 3-D point: through its own curve's parameter
                uvu = _use_uv(sf[fj], use, t if use is e else None, feet, project)
                nsum += sf[fj].normals(uvu[:, 0], uvu[:, 1])
            best[better] = dist
            side[better] = np.einsum("ij,ij->i", Q[better] - feet, nsum)
            vertex[better] = at_end
    result = np.where(side > 0, np.int8(OUTSIDE), np.int8(INSIDE))
    result[vertex] = fallback[vertex]
    result[best <= tol] = ON
    result[~np.isfinite(best)] = fallback[~np.isfinite(best)]
    return result


def _box_distance(Q, pts):
    """Distances ``(n,)`` from points ``Q`` to the bounding box of ``pts`` (a lower bound of the
    distance to a curve or surface with these control points)."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return np.linalg.norm(np.maximum(lo - Q, 0.0) + np.maximum(Q - hi, 0.0), axis=1)


def _use_uv(face, use, t, points, project):
    """``(u, v)`` ``(n, 2)`` on ``face`` of ``points`` lying on the edge ``use``: from the edge
    parameter ``t`` when known, else by projecting onto the use's 3-D curve, or (no curve) onto
    the face's surface."""
    if t is None and use.curve is not None:
        t = np.asarray(project(use.curve, points).parameters).reshape(len(points))
    if t is not None:
        return use.pcurve.evaluate(t)
    return np.asarray(project(face.surface, points).parameters).reshape(len(points), 2)
