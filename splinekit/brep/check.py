"""Validity of trimmed faces, shells and solids: a list of named problems, like OpenCascade's
``BRepCheck_Analyzer``.

Constructors stay permissive and fast; whatever hands a B-rep on (importers, exporters, booleans)
calls ``obj.raise_if_invalid()`` (or ``obj.validated()``), which raises :class:`~splinekit.errors.TrimError`
for a face's trims and :class:`~splinekit.errors.BRepError` otherwise, naming the face and the problem.

Problems found (the ``kind`` of each :class:`Problem`):

faces
    ``open-loop`` (consecutive edges' ends further apart than the tolerance in 3-D, through the
    surface, or not meeting in ``(u, v)``), ``trim-outside-domain``, ``self-intersecting-loop``,
    ``crossing-loops`` (two loops cross or touch), ``wrong-loop-orientation`` (outer not
    counter-clockwise or inner not clockwise, by signed area), ``inner-loop-outside`` (a hole not
    inside the outer loop, or inside another hole), ``pcurve-deviation`` (the surface at the pcurve
    is further from the 3-D curve than the tolerance).
shells
    the faces' problems, ``inconsistent-orientation`` (a shared edge used twice in the same
    sense), ``non-manifold-edge`` (used by more than two faces).
solids
    the shells' problems, ``open-shell`` (free edges), ``inward-shell`` (the outer shell's signed
    volume is negative, or a void's positive; estimated on a coarse mesh).

Loops are checked on polylines of the trims sampled per Bézier piece; crossings are found among
segments paired by a KD-tree on their mid points (no all-pairs loop).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..closest import project
from ..errors import BRepError, TrimError
from .coarse_mesh import face_mesh
from .trims import OUTSIDE, classify_uv, sample_trims, segment_distance, trim_arcs, trim_pieces, uv_tolerance
from .topology import surface_points

__all__ = ["Problem", "Checkable", "check_face", "check_shell", "check_solid", "FACE_KINDS"]

FACE_KINDS = frozenset({"open-loop", "trim-outside-domain", "self-intersecting-loop", "crossing-loops",
                        "wrong-loop-orientation", "inner-loop-outside", "pcurve-deviation"})
"""Problems of a single face's trims (raised as TrimError)."""

_PER_PIECE = 24  # polyline samples per Bézier piece of a trim


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a B-rep.

    ``kind`` names the problem (see the module doc), ``message`` says it in words with the face's
    name, ``value`` is the measured quantity (a gap, a deviation, an area, a count) or None;
    ``shell``, ``face``, ``loop``, ``edge`` locate it (indices; None where not applicable).
    """

    kind: str
    message: str
    value: float | None = None
    shell: int | None = None
    face: int | None = None
    loop: int | None = None
    edge: int | None = None

    @property
    def where(self) -> dict:
        """The non-None location indices, e.g. ``{"face": 3, "loop": 1}``."""
        return {k: getattr(self, k) for k in ("shell", "face", "loop", "edge") if getattr(self, k) is not None}

    def located(self, message: str, **where) -> "Problem":
        """The same problem with another ``message`` and more location indices (a face's problem
        seen from its shell)."""
        fields = {k: getattr(self, k) for k in ("kind", "value", "shell", "face", "loop", "edge")}
        fields.update({k: v for k, v in where.items() if fields.get(k) is None})
        return Problem(message=message, **fields)


def _face_label(face, index=None) -> str:
    """``face 3 'top'``, ``face 'top'``, ``face 3`` or ``face``."""
    return "face" + ("" if index is None else f" {index}") + (f" {face.name!r}" if face.name else "")


# -- faces ----------------------------------------------------------------------------------------
def _loop_polylines(face):
    """Per loop: ``(points (k, 2), edge index of each segment (k,), arc (k, 3))``; segment ``i``
    runs from point ``i`` to point ``i + 1`` (cyclically) and is a chord of the trim arc
    ``[piece, t0, t1]`` (see :func:`~.trims.trim_arcs`)."""
    polys = []
    for p, e, j, piece in sample_trims(face, _PER_PIECE, pieces=True):
        per = np.bincount(piece)[piece]  # points (= segments) of each point's piece
        polys.append((p, e, np.column_stack([piece, j / per, (j + 1) / per])))
    return _split_long_segments(polys)


def _split_long_segments(polys):
    """Cut segments longer than twice the median into equal parts (exactly on them), so that a
    KD-tree radius of the longest segment pairs each segment with its neighbours only. The parts
    keep their segment's owner and arc."""
    lengths = np.concatenate([np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1) for p, _, _ in polys])
    # at most four parts per segment on average: on a sliver face (u range 4e-4, v range 1, the
    # SolidWorks part) the median is a short side's chord and the long sides made 2.6 million parts
    h = max(2.0 * float(np.median(lengths)), float(lengths.sum()) / (4.0 * lengths.size))
    if not h > 0:
        return polys
    out = []
    for p, owner, arc in polys:
        q = np.roll(p, -1, axis=0)
        k = np.maximum(1, np.ceil(np.linalg.norm(q - p, axis=1) / h)).astype(np.intp)
        seg = np.repeat(np.arange(len(p)), k)
        frac = (np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)) / np.repeat(k, k)
        # each part's arc: the same fraction of its segment's parameter interval (parts of one
        # arc stay disjoint, so only truly adjacent parts share an end)
        t0, t1 = arc[seg, 1], arc[seg, 2]
        step = (t1 - t0) / np.repeat(k, k)
        parts = np.column_stack([arc[seg, 0], t0 + frac * (t1 - t0), t0 + frac * (t1 - t0) + step])
        out.append((p[seg] + frac[:, None] * (q[seg] - p[seg]), owner[seg], parts))
    return out


def _sagittas(face, P0, P1, arcs):
    """``(n,)`` distance of each chord ``P0 P1`` from its arc's middle point (0 on straight arcs)."""
    mid = trim_arcs(face, arcs[:, 0].astype(np.intp), arcs[:, 1], arcs[:, 2], 2)[:, 1]
    return segment_distance(P0, P1, mid)


_CONFIRM_STEPS = 8
"""Chords per trim arc in each zoom that confirms a touching found on the polylines."""
_CONFIRM_ZOOMS = 8
"""Zooms: each keeps 3 of the 8 chords around the closest pair, so eight leave 1/2600 of the arc
and a sagitta 1/7,000,000 of the polyline's."""
_CONFIRM_CHUNK = 1024


def _arc_distances(face, arc_a, arc_b):
    """Distances ``(h,)`` between the trim arcs ``arc_a`` and ``arc_b`` (``(h, 3)`` rows
    ``[piece, t0, t1]``), found on the polylines of chords: a polyline of a curved arc cuts its
    corners by up to its sagitta (0.1 on a hole of radius 47 in 24 chords), so two loops a little
    closer than that seem to touch. Each arc pair is cut into chords again and again, each time
    around the closest chords of the last (see :data:`_CONFIRM_ZOOMS`)."""
    if len(arc_a) > _CONFIRM_CHUNK:  # bounded memory: h n^2 chord pairs at a time
        return np.concatenate([_arc_distances(face, arc_a[k : k + _CONFIRM_CHUNK], arc_b[k : k + _CONFIRM_CHUNK])
                               for k in range(0, len(arc_a), _CONFIRM_CHUNK)])
    a, b = arc_a.astype(float).copy(), arc_b.astype(float).copy()
    n = _CONFIRM_STEPS
    h = len(a)
    d = np.zeros(h)
    for _ in range(_CONFIRM_ZOOMS):
        A = trim_arcs(face, a[:, 0].astype(np.intp), a[:, 1], a[:, 2], n)  # (h, n + 1, 2)
        B = trim_arcs(face, b[:, 0].astype(np.intp), b[:, 1], b[:, 2], n)
        i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        i, j = i.ravel(), j.ravel()
        dist = _segment_distances(A[:, i].reshape(-1, 2), A[:, i + 1].reshape(-1, 2),
                                  B[:, j].reshape(-1, 2), B[:, j + 1].reshape(-1, 2)).reshape(h, -1)
        best = dist.argmin(axis=1)
        d = dist[np.arange(h), best]
        # zoom on the closest chords (with a neighbour on each side, inside the arc)
        for arc, k in ((a, i[best]), (b, j[best])):
            step = (arc[:, 2] - arc[:, 1]) / n
            lo = arc[:, 1] + np.maximum(k - 1, 0) * step
            hi = arc[:, 1] + np.minimum(k + 2, n) * step
            arc[:, 1], arc[:, 2] = lo, hi
    return d


def _surface_derivatives(face, uv):
    """First derivatives ``(2, 2, n, 3)`` of the face's surface at ``uv`` clamped into its domain."""
    (u0, u1), (v0, v1) = face.domain
    return face.surface.derivatives(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1), 1)


def _signed_area(p):
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _segment_distances(a0, a1, b0, b1):
    """Distances ``(n,)`` between segments ``a0 a1`` and ``b0 b1`` (all ``(n, 2)``): 0 when they
    cross, else the smallest end point to segment distance."""
    def orient(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    d1, d2 = orient(a0, a1, b0), orient(a0, a1, b1)
    d3, d4 = orient(b0, b1, a0), orient(b0, b1, a1)
    cross = (d1 * d2 < 0) & (d3 * d4 < 0)
    d = np.minimum.reduce([segment_distance(a0, a1, b0), segment_distance(a0, a1, b1),
                           segment_distance(b0, b1, a0), segment_distance(b0, b1, a1)])
    return np.where(cross, 0.0, d)


def check_face(face) -> list:
    """The problems of one trimmed face (messages name it by its ``name``)."""
    index = None
    label = _face_label(face)
    problems = []
    tol = face.tolerance
    tol_uv = uv_tolerance(face)
    (u0, u1), (v0, v1) = face.domain
    loops = face.boundary_loops()
    explicit = face.is_trimmed

    # closure: each edge's end against the next edge's start, within the two edges' tolerances
    # (each end lies within its edge's tolerance of the shared vertex). Measured in 3-D through
    # the surface, both as the distance of the two surface points and as the length of the
    # (u, v) gap mapped by the surface's derivatives there: the first misses a jump across a
    # seam (same 3-D point), the second forgives a gap along a pole (no 3-D length).
    for li, loop in enumerate(loops):
        ends = np.array([e.end_uv for e in loop])
        starts = np.array([e.start_uv for e in loop[1:] + loop[:1]])
        etol = np.array([e.tolerance for e in loop])
        limit = np.maximum(tol, etol + np.roll(etol, -1))
        gap3 = np.linalg.norm(surface_points(face, ends) - surface_points(face, starts), axis=1)
        d = _surface_derivatives(face, 0.5 * (ends + starts))
        duv = starts - ends
        gap_lin = np.linalg.norm(d[1, 0] * duv[:, :1] + d[0, 1] * duv[:, 1:], axis=1)
        for ei in np.flatnonzero((gap3 > limit) | (gap_lin > limit)):
            nxt = (ei + 1) % len(loop)
            if gap3[ei] > limit[ei]:
                what, value = f"{gap3[ei]:.3g} in 3-D", gap3[ei]
            else:
                what, value = (f"{np.linalg.norm(duv[ei]):.3g} in (u, v), {gap_lin[ei]:.3g} in 3-D along the surface "
                               "(the ends meet in space only: across a seam?)"), gap_lin[ei]
            problems.append(Problem("open-loop", f"{label}: loop {li} is open between edges {ei} and {nxt}: gap {what} "
                                    f"(tolerance {limit[ei]:g})", float(value), face=index, loop=li, edge=int(ei)))
    if not explicit:
        return problems

    polys = _loop_polylines(face)
    # inside the surface's domain: the excursion's length in 3-D, mapped by the derivatives at the
    # nearest domain point (so a step in u at a pole, which has no length, is forgiven), within
    # twice the edge's tolerance (the clamped point and the true one each within it)
    etols = [np.array([e.tolerance for e in lp]) for lp in loops]
    for li, (p, owner, _) in enumerate(polys):
        clamped = np.stack([np.clip(p[:, 0], u0, u1), np.clip(p[:, 1], v0, v1)], axis=1)
        out_of = np.flatnonzero(np.any(clamped != p, axis=1))
        if out_of.size == 0:
            continue
        d = _surface_derivatives(face, clamped[out_of])
        step = p[out_of] - clamped[out_of]
        over = np.linalg.norm(d[1, 0] * step[:, :1] + d[0, 1] * step[:, 1:], axis=1)
        bad = over > 2.0 * np.maximum(tol, etols[li][owner[out_of]])
        if bad.any():
            k = out_of[int(np.argmax(np.where(bad, over, -np.inf)))]
            far = float(np.abs(step).max())
            problems.append(Problem("trim-outside-domain", f"{label}: loop {li}, edge {int(owner[k])} leaves the surface's domain "
                                    f"[{u0:g}, {u1:g}] x [{v0:g}, {v1:g}] at (u, v) = ({p[k, 0]:.6g}, {p[k, 1]:.6g}): "
                                    f"{far:.3g} in (u, v), {float(over.max()):.3g} in 3-D (tolerance {2.0 * max(tol, float(etols[li][owner[k]])):g})", float(over.max()),
                                    face=index, loop=li, edge=int(owner[k])))

    # orientation by signed area: outer counter-clockwise, inner clockwise
    areas = [_signed_area(p) for p, _, _ in polys]
    for li, a in enumerate(areas):
        if (li == 0 and a <= 0) or (li > 0 and a >= 0):
            want = "counter-clockwise (outer loop)" if li == 0 else "clockwise (inner loop)"
            problems.append(Problem("wrong-loop-orientation", f"{label}: loop {li} runs the wrong way: signed area {a:.6g} in (u, v), "
                                    f"expected {want}", float(a), face=index, loop=li))

    # crossings and touchings among all segments, candidates paired by a KD-tree on mid points;
    # degenerate edges (a pole's side, or a point) are left out: the loop steps over them, since
    # their ends are one point in space whatever their (u, v)
    kept = []
    for li, (p, owner, arc) in enumerate(polys):
        solid = ~np.array([loops[li][k].degenerate for k in owner], dtype=bool) if len(owner) else np.zeros(0, bool)
        kept.append((p[solid], owner[solid], arc[solid]) if solid.sum() >= 2 else (p, owner, arc))
    P0 = np.concatenate([p for p, _, _ in kept])
    P1 = np.concatenate([np.roll(p, -1, axis=0) for p, _, _ in kept])
    arcs = np.concatenate([arc for _, _, arc in kept])
    loop_of = np.concatenate([np.full(len(p), li) for li, (p, _, _) in enumerate(kept)])
    pos = np.concatenate([np.arange(len(p)) for p, _, _ in kept])
    length = np.array([len(p) for p, _, _ in kept])[loop_of]
    edge_of = np.concatenate([o for _, o, _ in kept])
    mid = 0.5 * (P0 + P1)
    seg_len = np.linalg.norm(P1 - P0, axis=1)
    half = 0.5 * seg_len
    first = np.concatenate([[0], np.cumsum([len(p) for p, _, _ in kept])[:-1]])
    cum = np.cumsum(seg_len)
    start_len = cum - seg_len - (cum - seg_len)[first][loop_of]  # arc length before each segment, in its loop
    loop_len = np.bincount(loop_of, seg_len)[loop_of]
    seg_tol = np.concatenate([etols[li][o] for li, (_, o, _) in enumerate(kept)])
    sag = _sagittas(face, P0, P1, arcs)
    from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep
    pairs = cKDTree(mid).query_pairs(2.0 * float(half.max() + sag.max()) + tol_uv, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        same = loop_of[i] == loop_of[j]
        gap = np.abs(pos[i] - pos[j])
        # neighbours along the loop: adjacent segments, or segments joined by a chain shorter
        # than twice their edges' tolerance (a pcurve that starts with a 2e-7 spike back along the
        # previous edge, within its 5e-4 tolerance, is not the loop touching itself)
        a, b = np.minimum(i, j), np.maximum(i, j)
        between = start_len[b] - start_len[a] - seg_len[a]
        around = loop_len[a] - (start_len[b] - start_len[a]) - seg_len[b]
        reach = 2.0 * tol_uv * np.maximum(1.0, np.maximum(seg_tol[a], seg_tol[b]) / tol)
        adjacent = same & ((gap == 1) | (gap == length[i] - 1) | (np.minimum(between, around) <= reach))
        i, j, same = i[~adjacent], j[~adjacent], same[~adjacent]
        d = _segment_distances(P0[i], P1[i], P0[j], P1[j])
        # the chords of curved arcs cut corners by up to their sagitta: pairs closer than the
        # tolerance plus (twice) their sagittas are measured again on the arcs themselves
        near = np.flatnonzero((d <= tol_uv + 2.0 * (sag[i] + sag[j])) & (np.maximum(sag[i], sag[j]) > tol_uv))
        if near.size:
            d[near] = _arc_distances(face, arcs[i[near]], arcs[j[near]])
        hit = d <= tol_uv
        reported = set()
        for k in np.flatnonzero(hit):
            li, lj = int(loop_of[i[k]]), int(loop_of[j[k]])
            key = (min(li, lj), max(li, lj))
            if key in reported:
                continue
            reported.add(key)
            where = f"near (u, v) = ({mid[i[k], 0]:.6g}, {mid[i[k], 1]:.6g})"
            if same[k]:
                problems.append(Problem("self-intersecting-loop", f"{label}: loop {li} crosses or touches itself (edges {int(edge_of[i[k]])} and {int(edge_of[j[k]])}) {where}",
                                        float(d[k]), face=index, loop=li, edge=int(edge_of[i[k]])))
            else:
                problems.append(Problem("crossing-loops", f"{label}: loops {li} and {lj} cross or touch {where}",
                                        float(d[k]), face=index, loop=li, edge=int(edge_of[i[k]])))

    # holes inside the outer loop (all their points, by winding) and not inside one another (a
    # hole's first point, tested only against the holes whose box holds it)
    if len(polys) > 1:
        holes = np.concatenate([p for p, _, _ in polys[1:]])
        owner = np.concatenate([np.full(len(p), li) for li, (p, _, _) in enumerate(polys) if li > 0])
        outer = classify_uv(trim_pieces(face, 0), holes, tol_uv)
        for li in np.unique(owner[outer == OUTSIDE]):
            problems.append(Problem("inner-loop-outside", f"{label}: inner loop {li} is not inside the outer loop",
                                    float(np.mean(outer[owner == li] == OUTSIDE)), face=index, loop=int(li)))
        lo = np.array([p.min(axis=0) for p, _, _ in polys[1:]])
        hi = np.array([p.max(axis=0) for p, _, _ in polys[1:]])
        first = np.array([p[0] for p, _, _ in polys[1:]])
        inbox = np.all((first[:, None] >= lo[None]) & (first[:, None] <= hi[None]), axis=2)
        np.fill_diagonal(inbox, False)
        for i, k in zip(*np.nonzero(inbox)):
            if classify_uv(trim_pieces(face, int(k) + 1), first[i:i + 1], tol_uv)[0] != OUTSIDE:
                problems.append(Problem("inner-loop-outside", f"{label}: inner loop {i + 1} lies inside inner loop {k + 1}",
                                        None, face=index, loop=int(i) + 1))

    # pcurve against 3-D curve at the same parameter (the data model's SameParameter); when they
    # disagree, say whether the curves are at least the same point set (only the parameter off)
    for li, loop in enumerate(loops):
        for ei, e in enumerate(loop):
            if e.curve is None:
                continue
            br = np.union1d(e.pcurve.bezier_breakpoints(), e.curve.bezier_breakpoints())
            a, b = e.domain
            br = br[(br >= a) & (br <= b)]
            t = (br[:-1, None] + (br[1:] - br[:-1])[:, None] * np.linspace(0.0, 1.0, 17)[None]).ravel()
            on_surface = surface_points(face, e.pcurve.evaluate(t))
            dev = float(np.linalg.norm(on_surface - e.curve.evaluate(t), axis=1).max())
            limit = max(e.tolerance, tol)
            if dev > limit:
                apart = float(project(e.curve, on_surface).distances.max())
                how = (f"; as point sets they are {apart:.3g} apart (only the parameters differ)" if apart <= limit
                       else f"; {apart:.3g} apart as point sets")
                problems.append(Problem("pcurve-deviation", f"{label}: loop {li}, edge {ei}: the surface at the pcurve is {dev:.3g} "
                                        f"from the 3-D curve at the same parameter (tolerance {limit:g}){how}", dev,
                                        face=index, loop=li, edge=ei))
    return problems


# -- shells and solids ------------------------------------------------------------------------------
def check_shell(shell, index: int | None = None) -> list:
    """The problems of a shell: its faces', inconsistent orientation, non-manifold edges."""
    problems = []
    for fi, f in enumerate(shell.faces):
        # the face's messages start with its label; name its index in the shell too
        own, label = _face_label(f), ("" if index is None else f"shell {index}, ") + _face_label(f, fi)
        problems += [p.located(label + p.message[len(own):], shell=index, face=fi) for p in f.check()]
    topo = shell.topology
    faces = shell.faces
    for gi, why in topo.badly_used:
        g = topo.edges[gi]
        names = ", ".join(_face_label(faces[u[0]], u[0]) for u in g.uses)
        fi, li, ei = g.uses[0]
        if why == "same-direction":
            problems.append(Problem("inconsistent-orientation", f"the edge shared by {names} is used twice in the same sense: "
                                    "the faces' orientations disagree", None, shell=index, face=fi, loop=li, edge=ei))
        elif why == "non-manifold":
            problems.append(Problem("non-manifold-edge", f"an edge is used {len(g.uses)} times (by {names})", float(len(g.uses)),
                                    shell=index, face=fi, loop=li, edge=ei))
    return problems


def _signed_volume(shell) -> tuple[float, float]:
    """Signed volume of the shell's faces' coarse meshes (divergence theorem), a cheap estimate,
    and a bound of its error: each face's mesh area times its measured deviation from the face
    (the volume between the mesh and the face), summed."""
    total = bound = 0.0
    for f in shell.faces:
        P, T, dev = face_mesh(f)
        if len(T):
            A, B, C = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
            total += float(np.einsum("ij,ij->i", A, np.cross(B, C)).sum()) / 6.0
            bound += 0.5 * float(np.linalg.norm(np.cross(B - A, C - A), axis=1).sum()) * dev
    return total, bound


def check_solid(solid) -> list:
    """The problems of a solid: its shells', open shells, shells pointing the wrong way."""
    problems = []
    for si, sh in enumerate(solid.shells):
        problems += check_shell(sh, si)
        topo = sh.topology
        free = topo.free_edges
        if free:
            fi, li, ei = free[0].uses[0]
            problems.append(Problem("open-shell", f"shell {si} of the solid is open: {len(free)} free edge(s), the first on "
                                    f"{_face_label(sh.faces[fi], fi)}, loop {li}, edge {ei}", float(len(free)),
                                    shell=si, face=fi, loop=li, edge=ei))
        elif not any(p.kind in ("inconsistent-orientation", "non-manifold-edge") and p.shell == si for p in problems):
            vol, err = _signed_volume(sh)
            # only a sign the estimate is sure of: coarse meshes of strongly curved faces may not be
            if abs(vol) > 2.0 * err and ((si == 0 and vol < 0) or (si > 0 and vol > 0)):
                want = "outward (positive volume)" if si == 0 else "into the void (negative volume)"
                problems.append(Problem("inward-shell", f"shell {si} points the wrong way: signed volume {vol:.6g}, expected {want}",
                                        vol, shell=si))
    return problems


def _cached(obj, compute):
    if "check" not in obj._cache:
        obj._cache["check"] = tuple(compute())
    return list(obj._cache["check"])


class Checkable:
    """``check()``, ``is_valid``, ``raise_if_invalid()`` and ``validated()`` for faces, shells and
    solids; subclasses provide ``_problems()``."""

    __slots__ = ()

    def _problems(self) -> list:
        raise NotImplementedError

    def check(self) -> list:
        """The named :class:`Problem` list (empty when valid). Cached on the immutable object."""
        return _cached(self, self._problems)

    @property
    def is_valid(self) -> bool:
        """``not self.check()``."""
        return not self.check()

    def raise_if_invalid(self) -> None:
        """Raise :class:`~splinekit.errors.TrimError` (a face's trims) or
        :class:`~splinekit.errors.BRepError` (anything else) naming the first problem's face and
        the problem; the message lists the others' count."""
        problems = self.check()
        if not problems:
            return
        first = problems[0]
        more = f" (and {len(problems) - 1} more problem(s))" if len(problems) > 1 else ""
        error = TrimError if first.kind in FACE_KINDS else BRepError
        raise error(f"{type(self).__name__}{f' {self.name!r}' if self.name else ''} is invalid: [{first.kind}] {first.message}{more}")

    def validated(self):
        """``self`` when valid; raises as :meth:`raise_if_invalid` otherwise."""
        self.raise_if_invalid()
        return self
