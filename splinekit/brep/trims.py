"""Trimming loops in a face's (u, v) plane: their Bézier pieces, sampled polylines, the (u, v)
tolerance, and the classification of (u, v) points against them.

The trims are cut into Bézier pieces (homogeneous, grouped by degree, one cached table per face).
A point's crossings with the ``+u`` ray are counted on each piece's chord, which is exact whenever
the point lies outside the piece's bounding box (the piece and its chord then wind around the
point equally: both lie in the convex hull of the control points). Pieces whose box holds the
point are halved (de Casteljau, vectorized over all such point/piece pairs) until the point is
clear of the box or the piece is shorter than an eighth of the tolerance; the point is then ON
when it lies within the tolerance of that short chord. Inside is decided by the even-odd rule on
the summed crossings (so a face with a loop turned the wrong way still classifies as its loops
are drawn; :mod:`check` reports the orientation). Only point/piece pairs whose point lies in the
piece's v-range are formed (points sorted by v).

The ON rule is measured in ``(u, v)``: a point is ON when its ``(u, v)`` distance to a trim is at
most ``tol_uv = tolerance / speed`` with ``speed`` the surface's largest parametric speed
``max(|Su|, |Sv|)`` (sampled), so every ON point is within ``tolerance`` of the trim in 3-D.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from .. import limits
from ..basis.bernstein import all_bernstein

__all__ = ["Location", "INSIDE", "ON", "OUTSIDE", "uv_tolerance", "trim_pieces", "sample_trims", "trim_arcs", "classify_uv"]


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


def sample_trims(face, per_piece: int, pieces: bool = False) -> list:
    """Polylines of the face's loops: per loop ``(points (k, 2), edge (k,), j (k,))``, point ``i``
    starting segment ``i`` (cyclically), ``j`` its index within its piece. Curved pieces give
    ``per_piece`` points each (``t = j / per_piece``), straight ones their start point only;
    evaluated for all pieces of a degree at once (Bernstein matrix). ``pieces=True`` adds a fourth
    array, the piece of each point (its position along the loops, for :func:`trim_arcs`)."""
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
    piece_of = np.repeat(np.arange(n_pieces), counts)
    return [(pts[loop_of == li], edge_of[loop_of == li], local[loop_of == li]) + ((piece_of[loop_of == li],) if pieces else ())
            for li in range(len(face.boundary_loops()))]


def trim_arcs(face, piece, t0, t1, n: int) -> np.ndarray:
    """Points ``(h, n + 1, 2)`` of the trims' Bézier pieces ``piece`` ``(h,)`` (positions along
    the loops, as :func:`sample_trims` gives them) at ``n + 1`` parameters evenly from ``t0`` to
    ``t1`` ``(h,)`` (piece parameters in ``[0, 1]``)."""
    table = _trim_table(face)
    piece = np.asarray(piece, dtype=np.intp)
    t = np.asarray(t0, float)[:, None] + (np.asarray(t1, float) - np.asarray(t0, float))[:, None] * np.linspace(0.0, 1.0, n + 1)
    out = np.empty(t.shape + (2,))
    for p, (H, _, _, order) in table.items():
        row_of = np.full(max(int(order.max()), int(piece.max(initial=0))) + 1, -1, dtype=np.intp)
        row_of[order] = np.arange(len(order))
        sel = np.flatnonzero(row_of[piece] >= 0) if piece.size else piece
        if sel.size == 0:
            continue
        B = all_bernstein(p, t[sel].ravel())  # (p + 1, h n)
        X = np.einsum("ik,kid->kd", B, np.repeat(H[row_of[piece[sel]]], n + 1, axis=0))
        out[sel] = (X[:, :2] / X[:, 2:]).reshape(sel.size, n + 1, 2)
    return out


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


def segment_distance(a, b, q):
    """Distances ``(n,)`` from points ``q`` to segments ``a -> b`` (all ``(n, d)``)."""
    ab = b - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    t = np.divide(np.einsum("ij,ij->i", q - a, ab), L2, out=np.zeros(len(q)), where=L2 > 0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(q - (a + t[:, None] * ab), axis=1)


def classify_uv(pieces: dict, uv: np.ndarray, tol: float) -> np.ndarray:
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
                    near = segment_distance(a[short], b[short], q[short]) <= tol
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


