"""The loop checks of a fast plan, so that a first call need not run the general path to validate.

The general path (:mod:`.trimmed`) refuses trimming loops that are open, face the wrong way,
cross or touch, or nest wrongly, by triangulating them at the requested tolerance. The fast path
(:mod:`.fast_plan`) meshes only faces whose loops it understands exactly (lines and circle arcs
through exact maps), so the same questions can be asked of the exact loops once per face set, at
any tolerance:

* closed: every use ends at the welded corner where the next use of its loop starts, in 3-D,
  and at the same ``(u, v)`` (to :data:`UV_RTOL` of the face's parameter range);
* cylinders and faces of revolution: one loop that is a rectangle in ``(u, v)`` run
  counter-clockwise (checked where the plan is built, :func:`.plan_faces.cylinder_loops` and
  :func:`.latitude.latitude_plan`), so closure is all that is left;
* planes: each loop as a polygon through its corners and, along its circle arcs, through
  :data:`.fast_plan.SAMPLES` points of the exact arc (uniform in angle; much finer than a mesh at
  a coarse tolerance); the outer loop counter-clockwise and the holes
  clockwise (signed area), no segment crossing or touching another
  (:func:`.untangle.crossing_pairs`, exact orientation tests), and every hole inside the outer
  loop and outside the other holes (a crossing-number test of one of its points).

A face set that passes is meshed by the fast path from its first call. One that fails is not
refused here: it goes through the general path first, as before, which raises the named error
(or, for a sloppy file's crossing within its edge tolerances, repairs it). So these checks may be
stricter than the general path, never looser, on the loops the fast path meshes.
"""

from __future__ import annotations

import numpy as np

from ..mesh.topology import ranges
from .untangle import crossing_pairs

__all__ = ["loops_valid"]

UV_RTOL = 1e-9
"""Largest ``(u, v)`` gap between a use's end and the next use's start, relative to the face's
parameter range (the fast path puts both at the same vertex)."""


def loops_valid(plan, table, pred, uv0, uv1, plane, arc_use, arcs=None) -> bool:
    """Whether the loops of the plan's faces are closed and, on planes, simple, nested and
    oriented (see the module docstring). ``table``: the face set's :class:`.loops.LoopTable`;
    ``pred`` ``(U, k, 2)``: each use's ``(u, v)`` at its ``k`` recognition samples (from its start
    to its end); ``uv0``, ``uv1`` ``(U, 2)``: its ends; ``plane`` ``(U,)`` bool: uses on planes;
    ``arc_use`` ``(U,)`` bool: uses along circle arcs (the others are straight in ``(u, v)`` on a
    plane); ``arcs`` ``(U, m, 2)``: the points of the arc uses on planes for their polygons (from
    start to end; default ``pred``)."""
    g, flip = plan.use_group, plan.use_flip
    start = np.where(flip, plan.end_vid[g, 1], plan.end_vid[g, 0])
    end = np.where(flip, plan.end_vid[g, 0], plan.end_vid[g, 1])
    nxt = table.next_use
    if (end != start[nxt]).any():
        return False
    F = len(plan.faces)
    flo, fhi = np.full((F, 2), np.inf), np.full((F, 2), -np.inf)
    np.minimum.at(flo, table.face, pred.min(axis=1))
    np.maximum.at(fhi, table.face, pred.max(axis=1))
    frange = (fhi - flo).max(axis=1)  # the face's loops' extent in (u, v)
    if (np.abs(uv1 - uv0[nxt]) > UV_RTOL * frange[table.face][:, None]).any():
        return False
    loops = np.flatnonzero(plane[table.first])
    if loops.size == 0:
        return True
    # the planes' loops as polygons: a straight use gives its start, an arc use its samples but the last
    uses = ranges(table.first[loops], table.count[loops])
    arcs = pred if arcs is None else arcs
    k = arcs.shape[1] - 1
    per = np.where(arc_use[uses], k, 1)
    which = np.repeat(uses, per)
    j = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per)
    P = np.where(arc_use[which][:, None], arcs[which, j], pred[which, 0])
    face = table.face[which]
    size = np.add.reduceat(per, np.cumsum(table.count[loops]) - table.count[loops])
    first = np.cumsum(size) - size
    after = np.arange(1, len(P) + 1)
    after[first + size - 1] = first
    area = np.add.reduceat(P[:, 0] * P[after, 1] - P[after, 0] * P[:, 1], first)
    outer = table.loop_index[loops] == 0
    if not np.where(outer, area > 0, area < 0).all():
        return False
    # crossings, every face in its own unit box side by side (segments of different faces never meet)
    lo = np.full((F, 2), np.inf)
    hi = np.full((F, 2), -np.inf)
    np.minimum.at(lo, face, P)
    np.maximum.at(hi, face, P)
    Q = (P - lo[face]) / np.maximum(hi - lo, 1e-300)[face]
    Q[:, 0] += 3.0 * face
    segs = np.column_stack([np.arange(len(P)), after])
    if crossing_pairs(Q, segs)[0].size:
        return False
    # nesting: one point of each hole inside its face's outer loop and outside its other holes
    holes = np.flatnonzero(~outer)
    if holes.size == 0:
        return True
    loop_of = np.repeat(np.arange(loops.size), size)
    lface = table.face[table.first[loops]]
    # (hole, segment) pairs on the same face, the hole's own loop left out
    seg_face = face
    by_face = np.argsort(seg_face, kind="stable")
    fcount = np.bincount(seg_face, minlength=F)
    fstart = np.cumsum(fcount) - fcount
    hf = lface[holes]
    h = np.repeat(holes, fcount[hf])
    s = by_face[ranges(fstart[hf], fcount[hf])]
    other = loop_of[s] != h
    h, s = h[other], s[other]
    p = Q[first[h]]
    a, b = Q[s], Q[after[s]]
    # a ray from p towards +u crosses the segment (half-open in v: a shared vertex counts once)
    up = (a[:, 1] <= p[:, 1]) != (b[:, 1] <= p[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (p[:, 1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    hit = up & (x > p[:, 0])
    # the (hole, loop) pairs crossed an odd number of times: the loops the hole's point lies inside,
    # which must be exactly its own face's outer loop (pairs as sorted codes, not a loops x loops table)
    pair = h.astype(np.int64) * loops.size + loop_of[s]
    codes, hits = np.unique(pair[hit], return_counts=True)
    outer_of_face = np.full(F, -1, dtype=np.int64)
    outer_of_face[lface[outer]] = np.flatnonzero(outer)
    want = np.sort(holes.astype(np.int64) * loops.size + outer_of_face[lface[holes]])
    return bool(np.array_equal(codes[hits % 2 == 1], want))
