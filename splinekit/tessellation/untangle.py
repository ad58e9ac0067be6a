"""Trims that cross in the parameter plane: the crossing test, and the repair of crossings the
file's own edge tolerances allow.

Some CAD exports carry sliver faces in which two edges run alongside each other closer than the
tolerance the file gives them (1e-4 apart in space, tolerances of 1e-2): their pcurves, each only
good to that tolerance, cross in ``(u, v)``. Within its tolerance such an edge may lie anywhere,
so the boundary points of the edge with the larger tolerance are moved in ``(u, v)`` (never in
3-D: both faces of an edge keep the very same points) to just inside the other edge's polyline,
on the material side. The caller then checks that the surface at every moved ``(u, v)`` stays
within that edge's tolerance of its 3-D point; on a sane file (tolerances of 1e-7) no crossing
passes that check and the face is refused as before.

All coordinates here are in the faces' scaled, laid-out parameter plane (the interior grid's
step is about one).
"""

from __future__ import annotations

import numpy as np

from .. import limits

__all__ = ["crossing", "crossing_pairs", "untangle"]

SHIFT = 1e-5
"""Distance (scaled grid steps) at which a moved boundary point is put inside the fixed edge's
polyline, ten times more each round while crossings remain. Small: a flat direction of a face
has few, long grid steps, so a step can be a large distance in space (the caller's check
against the edge tolerance decides); Triangle's exact predicates take such thin slivers."""
REACH = 1.0
"""Only points within this distance (scaled grid steps) of the other edge's polyline move."""
ROUNDS = 5


def _orient(p, q, r):
    return np.sign((q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0]))


def crossing_pairs(P, segs):
    """Index arrays ``(a, b)`` of the segments ``P[segs]`` that cross or touch a non-adjacent one.
    A sweep along x: candidate pairs have overlapping x ranges (few, for trims made of short
    chords), then exact orientation tests."""
    A, B = P[segs[:, 0]], P[segs[:, 1]]
    x0, x1 = np.minimum(A[:, 0], B[:, 0]), np.maximum(A[:, 0], B[:, 0])
    order = np.argsort(x0, kind="stable")
    xs = x0[order]
    end = np.searchsorted(xs, x1[order], side="right")
    count = np.maximum(end - np.arange(1, len(xs) + 1), 0)
    total = int(count.sum())
    if total > 1_000_000:
        limits.check(total * 64, "the trim crossing test")
    i = np.repeat(np.arange(len(xs)), count)
    j = i + 1 + (np.arange(i.size) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[i], order[j]
    shared = (segs[a, 0] == segs[b, 0]) | (segs[a, 0] == segs[b, 1]) | (segs[a, 1] == segs[b, 0]) | (segs[a, 1] == segs[b, 1])
    a, b = a[~shared], b[~shared]
    o1, o2 = _orient(A[a], B[a], A[b]), _orient(A[a], B[a], B[b])
    o3, o4 = _orient(A[b], B[b], A[a]), _orient(A[b], B[b], B[a])
    hit = (o1 * o2 <= 0) & (o3 * o4 <= 0)
    # collinear pairs (all orientations zero) cross only if their extents overlap
    col = (o1 == 0) & (o2 == 0)
    if col.any():
        ya0, ya1 = np.minimum(A[a, 1], B[a, 1]), np.maximum(A[a, 1], B[a, 1])
        yb0, yb1 = np.minimum(A[b, 1], B[b, 1]), np.maximum(A[b, 1], B[b, 1])
        xa0, xa1, xb0, xb1 = x0[a], x1[a], x0[b], x1[b]
        overlap = (np.maximum(xa0, xb0) <= np.minimum(xa1, xb1)) & (np.maximum(ya0, yb0) <= np.minimum(ya1, yb1))
        hit &= ~col | overlap
    return a[hit], b[hit]


def crossing(P, segs):
    """Index of a segment that crosses or touches another non-adjacent one, or -1. Triangle must
    never see crossing segments: it splits them at new points (or, for some inputs, crashes)."""
    a, _ = crossing_pairs(P, segs)
    return int(a[0]) if a.size else -1


def _push(P, pts, fixed_segs, shift):
    """Move the points ``P[pts]`` that lie within :data:`REACH` of the polyline ``fixed_segs``
    and less than ``shift`` to its left (or right of it) to ``shift`` left of their closest point
    on it. Points whose closest point is an end of the polyline (a corner) stay."""
    A, B = P[fixed_segs[:, 0]], P[fixed_segs[:, 1]]
    limits.check(len(pts) * len(fixed_segs) * 64, "the trim untangling")
    Q = P[pts]
    D = B - A
    L2 = np.maximum(np.einsum("ij,ij->i", D, D), 1e-300)
    t = np.einsum("pij,ij->pi", Q[:, None, :] - A[None], D) / L2
    tc = np.clip(t, 0.0, 1.0)
    foot = A[None] + tc[..., None] * D[None]
    dist = np.linalg.norm(Q[:, None, :] - foot, axis=2)
    dist[(fixed_segs[None, :, 0] == pts[:, None]) | (fixed_segs[None, :, 1] == pts[:, None])] = np.inf
    k = np.argmin(dist, axis=1)
    row = np.arange(len(pts))
    tk, d = tc[row, k], dist[row, k]
    # the ends of the fixed polyline: points that appear in one of its segments only
    ends = np.bincount(fixed_segs.ravel(), minlength=len(P)) == 1
    at_end = ((tk <= 0.0) & ends[fixed_segs[k, 0]]) | ((tk >= 1.0) & ends[fixed_segs[k, 1]])
    n = np.column_stack([-D[k, 1], D[k, 0]]) / np.sqrt(L2[k])[:, None]
    f = foot[row, k]
    side = np.einsum("ij,ij->i", Q - f, n)
    move = (d < REACH) & (side < shift) & ~at_end
    P[pts[move]] = f[move] + shift * n[move]
    return int(move.sum())


def _straighten(P, segs, a, b, owner, corner):
    """An edge crossing itself (segments ``a[i]`` and ``b[i]`` of one edge: a pcurve that
    doubles back, or samples that project onto one ``(u, v)``): the points of the run between
    the two segments are spread evenly on the chord between the run's end points, which stay.
    Returns how many points moved."""
    if a.size == 0:
        return 0
    lo = np.minimum(segs[a, 0], segs[b, 0])
    hi = np.maximum(segs[a, 1], segs[b, 1])
    moved = 0
    for i0, i1 in zip(lo.tolist(), hi.tolist()):
        if i1 <= i0 + 1 or owner[i1 - 1] != owner[i0]:  # the wrap of a loop, or one segment
            continue
        run = np.arange(i0 + 1, i1)
        run = run[~corner[run]]
        f = (run - i0) / (i1 - i0)
        P[run] = P[i0] + f[:, None] * (P[i1] - P[i0])
        moved += run.size
    return moved


def untangle(P, segs, owner, corner, weight):
    """Boundary points ``P`` ``(n, 2)`` (closed loops ``segs``) with crossings removed by moving
    points of the crossing edges, or None where that does not remove them (an edge crossing
    itself, or crossings that persist). ``owner`` ``(n,)``: the edge (use) each point belongs
    to; ``corner`` ``(n,)`` bool: loop corners (never moved); ``weight`` per owner: its edge
    tolerance (the edge with the larger one moves). Returns ``(P', moved (n,) bool)``."""
    P0 = P
    P = P.copy()
    seg_owner = owner[segs[:, 0]]
    for r in range(ROUNDS):
        a, b = crossing_pairs(P, segs)
        if a.size == 0:
            return P, np.any(P != P0, axis=1)
        oa, ob = seg_owner[a], seg_owner[b]
        same = oa == ob
        moved = _straighten(P, segs, a[same], b[same], owner, corner)
        a, b, oa, ob = a[~same], b[~same], oa[~same], ob[~same]
        a_moves = (weight[oa] > weight[ob]) | ((weight[oa] == weight[ob]) & (oa > ob))
        pairs = np.unique(np.column_stack([np.where(a_moves, oa, ob), np.where(a_moves, ob, oa)]), axis=0)
        for mv, fx in pairs:
            pts = np.flatnonzero((owner == mv) & ~corner)
            if pts.size:
                moved += _push(P, pts, segs[seg_owner == fx], SHIFT * 10.0**r)
        if moved == 0:
            return None
    return None
