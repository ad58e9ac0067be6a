"""Edges of trimmed faces, sampled once in 3-D and shared by every face that uses them.

A B-rep edge has one *use* per face (:class:`~splinekit.brep.Edge`: a pcurve in the face's
``(u, v)`` plane and, optionally, the 3-D curve with the same parameter). For a watertight mesh
both faces of an edge must meet at the same points, so the uses are first grouped (by their
``key``; uses without a key by geometry: the same 3-D points at 0, 1/4, 1/2, 3/4 and 1 of the
edge, either direction), then each group is sampled once:

* the parameters start from the 3-D curve's a-priori counts per Bézier span (the bounds of
  :mod:`.curves`, as for every curve) or, without a 3-D curve, a few steps per pcurve span;
* every segment is then measured, for the 3-D curve and for every use: the distance between the
  exact point at the segment's parametric midpoint and the chord's midpoint (for a use: the
  surface at the midpoint of the two samples' ``(u, v)``, the same yardstick the face triangles
  are measured with), and segments over the tolerance are split, a few rounds;
* each use maps the group's parameters onto its own pcurve (affinely, same or opposite
  direction; Gauss-Newton onto the use's curve where the affine map is off), so both faces carry
  ``(u, v)`` images of the very same 3-D points.

All groups are sampled together: curves and surfaces are evaluated through :mod:`.batch`, one
call per round for every edge.

Degenerate uses (a pole: the 3-D image is one point) are not shared: their pcurve is sampled
uniformly at the spacing of the face's interior grid, and every sample is the same 3-D vertex.
"""

from __future__ import annotations

import numpy as np

from ..brep.topology import pair_by_samples
from ..errors import ParameterError
from ..mesh.topology import ranges
from .batch import CurveBatch
from .curves import _span_bounds

__all__ = ["EdgeUse", "check_domains", "edge_uses", "group_uses", "sample_groups"]

EDGE_FRACTIONS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
"""Where along an edge the geometric pairing compares uses."""
MAX_ROUNDS = 8
"""Largest number of measure-and-split rounds per edge."""
MAX_SEGMENTS = 1 << 16
"""Largest number of segments of one edge."""
MAX_SCALED_STEP = 2.0
"""Longest edge segment in a face's scaled parameter plane (units of the interior grid's step):
longer segments are split so the triangles along a trim are not needle fans."""


class EdgeUse:
    """One face's use of an edge, with where it sits: face ``f``, loop ``loop``, position ``pos``."""

    __slots__ = ("f", "loop", "pos", "edge", "face")

    def __init__(self, f, loop, pos, edge, face):
        self.f, self.loop, self.pos, self.edge, self.face = f, loop, pos, edge, face


def _face_name(face, f):
    return f"face {f}" + (f" ({face.name!r})" if face.name else "")


def edge_uses(faces):
    """Every edge use of ``faces`` (face after face, loop after loop) as :class:`EdgeUse`."""
    return [EdgeUse(f, l, k, e, face)
            for f, face in enumerate(faces) for l, loop in enumerate(face.boundary_loops()) for k, e in enumerate(loop)]  # fmt: skip


DOMAIN_SLACK = 1e-2
"""How far (relative to the domain's range) a pcurve may stray outside its surface's domain:
files written by CAD systems carry pcurves a little off the domain (their own tolerances); the
surface is evaluated there by its polynomial extension (which continues a rational arc on its
circle), as OCC does."""


def check_domains(uses, pcurves, surfaces, samples: int = 17):
    """Raise ParameterError naming the face, loop and edge of the first pcurve that leaves its
    surface's parameter domain by more than :data:`DOMAIN_SLACK` of its range (checked at
    ``samples`` points per pcurve)."""
    if not uses:
        return
    f = np.array([u.f for u in uses])
    lo = np.column_stack([surfaces.lu.lo, surfaces.lv.lo])[f]  # (U, 2): (u0, v0) of each use's face
    hi = np.column_stack([surfaces.lu.hi, surfaces.lv.hi])[f]
    slack = DOMAIN_SLACK * (hi - lo)
    # a curve lies in the convex hull of its Bézier pieces' control points (positive weights): when
    # every hull is well inside, no sample can leave (the common case, without evaluating)
    cmin, cmax = _hulls(pcurves)
    margin = 1e-9 * (hi - lo)
    if ((cmin >= lo - slack + margin) & (cmax <= hi + slack - margin)).all():
        return
    dom = np.column_stack([pcurves.breaks.lo, pcurves.breaks.hi])
    r = np.linspace(0.0, 1.0, samples)
    t = (dom[:, :1] + (dom[:, 1:] - dom[:, :1]) * r).ravel()
    uv = pcurves.evaluate(np.repeat(np.arange(len(uses)), samples), t).reshape(len(uses), samples, 2)
    bad = ((uv < (lo - slack)[:, None]) | (uv > (hi + slack)[:, None])).any(axis=(1, 2))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        u = uses[i]
        (u0, u1), (v0, v1) = u.face.domain
        a, b = uv[i].min(axis=0), uv[i].max(axis=0)
        raise ParameterError(
            f"{_face_name(u.face, u.f)}: loop {u.loop} leaves the surface's domain [{u0:g}, {u1:g}] x [{v0:g}, {v1:g}]: "
            f"edge {u.pos} spans [{a[0]:g}, {b[0]:g}] x [{a[1]:g}, {b[1]:g}]")


def _hulls(curves):
    """``(lo, hi)`` ``(n, dim)``: the bounding box of each curve's Bézier control points (a
    :class:`.batch.CurveBatch`), one pass per degree."""
    lo, hi = np.empty((len(curves.degree), curves.dim)), np.empty((len(curves.degree), curves.dim))
    for p, segs in curves.segs.items():
        on = np.flatnonzero(curves.degree == p)
        P = segs[..., :-1] / segs[..., -1:]  # (rows, p + 1, dim) Cartesian
        at = curves.first_row[on]
        lo[on] = np.minimum.reduceat(P.min(axis=1), at)
        hi[on] = np.maximum.reduceat(P.max(axis=1), at)
    return lo, hi


def group_uses(uses, weld: float, pcurves, surfaces):
    """Groups of the uses that are one edge: lists of use indices.

    Uses with equal keys form a group; keyless, non-degenerate uses are paired geometrically
    (:func:`splinekit.brep.topology.pair_by_samples` on the five points of
    :data:`EDGE_FRACTIONS`: all within ``weld`` of each other, in the same or the opposite
    direction); degenerate uses stay alone. The samples come from the tessellator's evaluators
    (``pcurves``, ``surfaces``: :mod:`.batch` evaluators of the uses' pcurves and the faces'
    surfaces); :mod:`splinekit.brep` topology may supply the pairing of a shell instead.
    """
    by_key: dict = {}
    loose = []
    singles = []
    for i, u in enumerate(uses):
        if u.edge.degenerate:
            singles.append([i])
        elif u.edge.key is not None:
            by_key.setdefault(u.edge.key, []).append(i)
        else:
            loose.append(i)
    groups = list(by_key.values()) + singles
    if loose:
        loose_a = np.asarray(loose)
        dom = np.column_stack([pcurves.breaks.lo, pcurves.breaks.hi])[loose_a]
        t = (dom[:, :1] + (dom[:, 1:] - dom[:, :1]) * EDGE_FRACTIONS).ravel()
        k = np.repeat(loose_a, EDGE_FRACTIONS.size)
        uv = pcurves.evaluate(k, t)
        face = np.array([uses[i].f for i in loose])
        pts = surfaces.evaluate(np.repeat(face, EDGE_FRACTIONS.size), uv[:, 0], uv[:, 1]).reshape(len(loose), -1, 3)
        lab = pair_by_samples(pts, weld)
        order = np.argsort(lab, kind="stable")
        cuts = np.flatnonzero(np.diff(lab[order])) + 1
        groups += [[loose[j] for j in part] for part in np.split(order, cuts)]
    return groups


class SampledGroup:
    """The samples of one edge group.

    Attributes
    ----------
    points : (m + 1, 3) the shared 3-D points (one point for a degenerate use)
    params : dict use index -> (m + 1,) the use's own pcurve parameters, in the group's order
        (decreasing for a use that runs against the representative)
    uv : dict use index -> (m + 1, 2) the use's ``(u, v)`` at those parameters
    degenerate : bool
    """

    __slots__ = ("points", "params", "uv", "degenerate")


def _subdivide(owner, a, b, n):
    """Split pieces ``[a, b]`` (sorted by ``owner``, consecutive pieces of an owner sharing
    ends) into ``n`` equal steps each. Returns ``(t, owner_of_t)``: the steps' starts, each
    owner's last end appended after its pieces."""
    n = np.asarray(n, dtype=np.int64)
    P = len(n)
    last = np.flatnonzero(np.append(owner[1:] != owner[:-1], True))  # each owner's last piece
    rank = np.cumsum(np.concatenate([[0], owner[1:] != owner[:-1]]))  # owners before (dense)
    start = np.concatenate([[0], np.cumsum(n)[:-1]]) + rank
    total = int(n.sum()) + last.size
    t = np.empty(total)
    who = np.empty(total, dtype=np.int64)
    piece = np.repeat(np.arange(P), n)
    j = np.arange(piece.size) - np.repeat(np.cumsum(n) - n, n)
    pos = start[piece] + j
    t[pos] = a[piece] + (b - a)[piece] * (j / n[piece])
    who[pos] = owner[piece]
    end = start[last] + n[last]
    t[end] = b[last]
    who[end] = owner[last]
    return t, who


def _straight_use(use) -> bool:
    """Whether the use's edge is a line segment in space and in ``(u, v)`` (degree 1, two
    control points, non-rational, both)."""
    e = use.edge
    return all(c is not None and c.degree == 1 and len(c.control_points) == 2 and c.weights is None
               for c in (e.curve, e.pcurve))  # fmt: skip


def sample_groups(uses, groups, scales, tol, angle_tol, surfaces, pc, memo=None, flat=None):
    """Sample every group (see the module docstring), all groups at once.

    ``scales`` ``(F, 2)`` per face: parameter units -> interior grid steps in u and v;
    ``surfaces``: a :class:`.batch.SurfaceBatch` of the faces' surfaces (in face order);
    ``pc``: a :class:`.batch.CurveBatch` of the uses' pcurves; ``memo``: a dict kept with the
    face set (its tolerance-independent part: representatives, 3-D curve batch, directions,
    span bounds, filled on the first call); ``flat`` ``(F,)`` bool: faces that are affine maps
    of their parameters (planes: :func:`.trimmed._affine`).

    A line segment whose every use lies on a flat face needs its two end points only at any
    tolerance (the chord is the edge, its ``(u, v)`` images are straight, and the face's one
    grid step spans it): such groups are sampled once and kept in ``memo``.
    Returns a list of :class:`SampledGroup`, one per group.
    """
    memo = {} if memo is None else memo
    if "head" not in memo:
        face = np.array([u.f for u in uses], dtype=np.int64)
        degenerate = np.array([uses[g[0]].edge.degenerate for g in groups], dtype=bool)
        group_of = np.empty(len(uses), dtype=np.int64)
        for g, members in enumerate(groups):
            group_of[members] = g
        memo["head"] = face, degenerate, group_of
    face, degenerate, group_of = memo["head"]
    pdom = np.column_stack([pc.breaks.lo, pc.breaks.hi])
    G = len(groups)
    out = [SampledGroup() for _ in range(G)]

    # degenerate uses: uniform samples at the face grid's spacing, one 3-D point
    dg = np.flatnonzero(degenerate)
    if dg.size:
        ui = np.array([groups[g][0] for g in dg])
        a, b = pdom[ui, 0], pdom[ui, 1]
        ends = pc.evaluate(np.repeat(ui, 2), np.column_stack([a, b]).ravel()).reshape(-1, 2, 2)
        steps = np.abs(ends[:, 1] - ends[:, 0]) * scales[face[ui]]
        n = np.clip(np.ceil(np.hypot(steps[:, 0], steps[:, 1])), 1, MAX_SEGMENTS).astype(np.int64)
        t, who = _subdivide(np.arange(dg.size), a, b, n)
        uv = pc.evaluate(ui[who], t)
        pole = surfaces.evaluate(face[ui], ends[:, 0, 0], ends[:, 0, 1])
        cut = np.flatnonzero(np.diff(who)) + 1
        for k, (tk, uvk) in enumerate(zip(_pieces(t, cut), _pieces(uv, cut))):
            o = out[dg[k]]
            o.points, o.params, o.uv, o.degenerate = pole[k : k + 1], {int(ui[k]): tk}, {int(ui[k]): uvk}, True

    if "straight" not in memo:
        straight = np.array([not degenerate[g] and flat is not None and all(flat[uses[i].f] and _straight_use(uses[i]) for i in members)
                             for g, members in enumerate(groups)], dtype=bool)  # fmt: skip
        memo["straight"] = straight, _end_samples(uses, groups, np.flatnonzero(straight), G, face, pdom, surfaces, pc, group_of, ~straight)
    straight, fixed = memo["straight"]
    for g, smp in fixed.items():
        out[g] = smp
    live = np.flatnonzero(~degenerate & ~straight)
    if live.size == 0:
        return out
    if "live" not in memo:  # the tolerance-independent part, computed once per face set
        memo["live"] = _live_groups(uses, groups, live, G, face, pdom, surfaces, pc, group_of, degenerate | straight)
    rep, has_curve, curve_of, c3, dom, lu, lg, flip, span_bounds = memo["live"]
    a, b = dom[lg, 0], dom[lg, 1]
    c, d = pdom[lu, 0], pdom[lu, 1]

    def exact(k, t):
        return _exact(k, t, has_curve, curve_of, c3, rep, pc, surfaces, face)

    # initial parameters: the 3-D curve's a-priori counts per Bézier span (the curve
    # tessellator's bounds), or a few steps per pcurve span
    cur = np.flatnonzero(has_curve)
    raw = np.flatnonzero(~has_curve)
    n_curve = np.zeros(0)
    if cur.size:
        n_row = {}
        for p, (M, L) in span_bounds.items():
            n = np.sqrt(M / (8.0 * tol))
            if angle_tol is not None:
                with np.errstate(divide="ignore", invalid="ignore"):
                    n = np.maximum(n, np.where(L > 0, M / (L * angle_tol), 0.0))
            n_row[p] = n
        j = ranges(c3.breaks.start, c3.breaks.count)  # every piece, object order
        obj = np.repeat(np.arange(cur.size), c3.breaks.count)
        row = c3.first_row[obj] + (j - c3.breaks.start[obj])
        deg = c3.degree[obj]
        n_curve = np.empty(j.size)
        for p, n in n_row.items():
            n_curve[deg == p] = n[row[deg == p]]
        pieces_c = (cur[obj], c3.breaks.a[j], c3.breaks.b[j], n_curve)
    else:
        pieces_c = (np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), np.zeros(0))
    j = ranges(pc.breaks.start[rep[raw]], pc.breaks.count[rep[raw]])
    obj = np.repeat(raw, pc.breaks.count[rep[raw]])
    pieces_p = (obj, pc.breaks.a[j], pc.breaks.b[j], np.full(j.size, 4.0))
    owners, lo, hi, counts = (np.concatenate([x, y]) for x, y in zip(pieces_c, pieces_p))
    order = np.argsort(owners, kind="stable")
    owners, lo, hi = owners[order], lo[order], hi[order]
    counts = np.clip(np.ceil(np.nan_to_num(counts[order], nan=MAX_SEGMENTS, posinf=MAX_SEGMENTS)), 1, MAX_SEGMENTS)
    t, who = _subdivide(owners, lo, hi, counts)

    for round_ in range(MAX_ROUNDS):
        seg = np.flatnonzero(who[1:] == who[:-1])  # segment = sample i to i + 1
        both = exact(np.concatenate([who, who[seg]]), np.concatenate([t, 0.5 * (t[seg] + t[seg + 1])]))
        X, Xm = both[: t.size], both[t.size :]
        chord = 0.5 * (X[seg] + X[seg + 1])
        factor = np.zeros(t.size)
        factor[seg] = np.linalg.norm(Xm - chord, axis=1) / tol
        # every use: the group's samples mapped onto its pcurve
        gstart = np.concatenate([[0], np.flatnonzero(np.diff(who)) + 1])
        gcount = np.diff(np.append(gstart, t.size))
        idx = ranges(gstart[lg], gcount[lg])  # sample of each use-sample
        owner = np.repeat(np.arange(lu.size), gcount[lg])
        r = (t[idx] - a[owner]) / (b[owner] - a[owner])
        s = np.where(flip[owner], d[owner] - r * (d - c)[owner], c[owner] + r * (d - c)[owner])
        uv = pc.evaluate(lu[owner], s)
        useg = np.flatnonzero(owner[1:] == owner[:-1])
        fu = face[lu[owner]]
        # the use's points (to check the map) and its chords' parametric midpoints, in one call
        mid = 0.5 * (uv[useg] + uv[useg + 1])
        P = surfaces.evaluate(np.concatenate([fu, fu[useg]]), np.concatenate([uv[:, 0], mid[:, 0]]),
                              np.concatenate([uv[:, 1], mid[:, 1]]))  # fmt: skip
        on, Pm = P[: uv.shape[0]], P[uv.shape[0] :]
        off = np.linalg.norm(on - X[idx], axis=1) > 1e-2 * tol
        if off.any():  # the affine map misses: project onto those uses' curves, all at once
            sel = np.flatnonzero(np.isin(owner, owner[off]))  # every sample of those uses, use after use
            o = owner[sel]
            end = np.ones(sel.size, dtype=bool)  # a use's first and last samples are the edge's vertices
            end[1:-1] = (o[1:-1] != o[:-2]) | (o[1:-1] != o[2:])
            inner = sel[~end]
            s[inner] = _project(lu[owner[inner]], s[inner], X[idx[inner]], c[owner[inner]], d[owner[inner]],
                                face[lu[owner[inner]]], pc, surfaces)  # fmt: skip
            uv[sel] = pc.evaluate(lu[o], s[sel])
            mid = 0.5 * (uv[useg] + uv[useg + 1])
            Pm = surfaces.evaluate(fu[useg], mid[:, 0], mid[:, 1])
            on = surfaces.evaluate(fu, uv[:, 0], uv[:, 1])
        # A sloppy file's 3-D curve lies off the face by up to its edge tolerance: a chord cannot
        # come closer to the surface than its ends, so the allowance is the tolerance plus the
        # ends' gap (against the bare tolerance, every round split these edges: 50,000 samples).
        gap = np.linalg.norm(on - X[idx], axis=1)
        allowed = tol + np.maximum(gap[useg], gap[useg + 1])
        dev = np.linalg.norm(Pm - 0.5 * (X[idx[useg]] + X[idx[useg + 1]]), axis=1) * (tol / allowed)
        step = (uv[useg + 1] - uv[useg]) * scales[fu[useg]]
        # the scaled-length criterion is linear in the step, the chordal one quadratic
        np.maximum.at(factor, idx[useg], np.maximum(dev / tol, (np.hypot(step[:, 0], step[:, 1]) / MAX_SCALED_STEP) ** 2))
        over = factor[seg] > 1.0
        if not over.any() or round_ == MAX_ROUNDS - 1 or t.size > MAX_SEGMENTS * live.size:
            break
        pieces = np.where(over, np.ceil(np.minimum(np.sqrt(factor[seg]) * 1.1, 8.0)), 1)
        t, who = _subdivide(who[seg], t[seg], t[seg + 1], pieces)

    cut = np.flatnonzero(np.diff(who)) + 1
    for k, Xk in enumerate(_pieces(X, cut)):
        o = out[live[k]]
        o.points, o.degenerate, o.params, o.uv = Xk, False, {}, {}
    ucut = np.flatnonzero(np.diff(owner)) + 1
    for o, (sk_, uvk) in enumerate(zip(_pieces(s, ucut), _pieces(uv, ucut))):
        grp = out[live[lg[o]]]
        grp.params[int(lu[o])] = sk_
        grp.uv[int(lu[o])] = uvk
    return out


def _pieces(a, cut):
    """``a`` cut before the indices ``cut`` (as ``np.split``, which costs several numpy calls
    per piece: this runs for every edge of every call)."""
    bounds = [0, *cut.tolist(), len(a)]
    return [a[i:j] for i, j in zip(bounds[:-1], bounds[1:])]


def _exact(k, t, has_curve, curve_of, c3, rep, pc, surfaces, face):
    """3-D points of live groups ``k`` at the representatives' parameters ``t``: the 3-D curve,
    or the representative's surface at its pcurve."""
    X = np.empty((t.size, 3))
    cur = has_curve[k]
    if cur.any():
        X[cur] = c3.evaluate(curve_of[k[cur]], t[cur])
    if not cur.all():
        r = rep[k[~cur]]
        uv = pc.evaluate(r, t[~cur])
        X[~cur] = surfaces.evaluate(face[r], uv[:, 0], uv[:, 1])
    return X


def _end_samples(uses, groups, idx, G, face, pdom, surfaces, pc, group_of, excluded):
    """``{group: SampledGroup}`` of the groups ``idx`` sampled at their two end points only
    (``excluded``: the groups not in ``idx``, as :func:`_live_groups` takes them)."""
    if idx.size == 0:
        return {}
    rep, has_curve, curve_of, c3, dom, lu, lg, flip, _ = _live_groups(uses, groups, idx, G, face, pdom, surfaces, pc, group_of, excluded)
    k = np.repeat(np.arange(idx.size), 2)
    X = _exact(k, dom.ravel(), has_curve, curve_of, c3, rep, pc, surfaces, face).reshape(-1, 2, 3)
    c, d = pdom[lu, 0], pdom[lu, 1]
    s = np.where(flip[:, None], np.column_stack([d, c]), np.column_stack([c, d]))
    uv = pc.evaluate(np.repeat(lu, 2), s.ravel()).reshape(-1, 2, 2)
    out = {}
    for j, g in enumerate(idx.tolist()):
        o = out[g] = SampledGroup()
        o.points, o.degenerate, o.params, o.uv = X[j], False, {}, {}
    for i, u in enumerate(lu.tolist()):
        o = out[int(idx[lg[i]])]
        o.params[u], o.uv[u] = s[i], uv[i]
    return out


def _live_groups(uses, groups, live, G, face, pdom, surfaces, pc, group_of, degenerate):
    """The tolerance-independent data of the non-degenerate groups: ``(rep, has_curve,
    curve_of, c3, dom, lu, lg, flip, span_bounds)`` (representative use per group, whether it
    has a 3-D curve, its index in the 3-D curve batch ``c3``, the representative's parameter
    domain, the uses of live groups and their group, whether each runs against its
    representative, and the 3-D curves' per-span bounds by degree)."""
    # the representative of each group: a use with a 3-D curve if there is one
    rep = np.array([next((i for i in groups[g] if uses[i].edge.curve is not None), groups[g][0]) for g in live])
    has_curve = np.array([uses[i].edge.curve is not None for i in rep], dtype=bool)
    curve_of = np.full(live.size, -1, dtype=np.int64)
    curve_of[has_curve] = np.arange(int(has_curve.sum()))
    c3 = CurveBatch([uses[i].edge.curve for i in rep[has_curve]])
    dom = pdom[rep].copy()
    if has_curve.any():
        dom[has_curve] = np.array([uses[i].edge.curve.domain for i in rep[has_curve]])
    slot = np.full(G, -1, dtype=np.int64)  # group -> index among live groups
    slot[live] = np.arange(live.size)
    # the uses of live groups, and whether each runs against its representative
    lu = np.flatnonzero(~degenerate[group_of])
    lg = slot[group_of[lu]]  # live group of each use
    a, b = dom[lg, 0], dom[lg, 1]
    c, d = pdom[lu, 0], pdom[lu, 1]
    ref = _exact(lg, a + (b - a) / 3.0, has_curve, curve_of, c3, rep, pc, surfaces, face)
    probe = pc.evaluate(np.repeat(lu, 2), np.column_stack([c + (d - c) / 3.0, d - (d - c) / 3.0]).ravel())
    P = surfaces.evaluate(np.repeat(face[lu], 2), probe[:, 0], probe[:, 1]).reshape(-1, 2, 3)
    flip = np.linalg.norm(P[:, 1] - ref, axis=1) < np.linalg.norm(P[:, 0] - ref, axis=1)
    span_bounds = {p: _span_bounds(p, segs) for p, segs in c3.segs.items()} if has_curve.any() else {}
    return rep, has_curve, curve_of, c3, dom, lu, lg, flip, span_bounds


def _project(k, s, X, c, d, f, pc, surfaces, rounds: int = 6):
    """Gauss-Newton steps moving the pcurve parameters ``s`` ``(n,)`` (of pcurves ``k`` in the
    batch ``pc``, on faces ``f``) so that the surface points approach ``X`` ``(n, 3)``, kept in
    ``[c, d]`` (either order), where the affine guess is off. A point stops once its step is
    negligible. Surfaces through the batch evaluator, which also answers slightly off the
    domain (pcurves of files often stray a little)."""
    s = s.copy()
    lo, hi = np.minimum(c, d), np.maximum(c, d)
    active = np.arange(s.size)
    for _ in range(rounds):
        if active.size == 0:
            break
        P, dP = pc.partials(k[active], s[active])
        S, Su, Sv = surfaces.partials(f[active], P[:, 0], P[:, 1])
        F1 = Su * dP[:, :1] + Sv * dP[:, 1:]
        r = X[active] - S
        denom = np.einsum("ij,ij->i", F1, F1)
        step = np.einsum("ij,ij->i", F1, r) / np.where(denom > 0, denom, 1.0)
        s[active] = np.clip(s[active] + step, lo[active], hi[active])
        active = active[np.abs(step) > 1e-14 * (hi - lo + 1.0)[active]]
    return s
