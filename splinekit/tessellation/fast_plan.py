"""The tolerance-independent plan of the fast B-rep tessellation path (:mod:`.fast_mesh`).

Most faces of machined parts are planes bounded by lines and circles, and cylinders (holes,
bosses) bounded by two circles and their seam or rulings. On such faces the tessellation needs
no interior points and no measuring rounds:

* a plane's deviation is zero inside: its boundary polygon (with holes) is the whole mesh, and
  with only straight edges that polygon is the same at every tolerance;
* a circle needs ``ceil(sweep / step)`` segments, with the step given in closed form by the
  sagitta ``r (1 - cos(step / 2)) <= tol`` and the angle criterion;
* a right circular cylinder is straight along its rulings: a strip of triangles between its two
  circles is exact along them and errs across them exactly as its circles do;
* a face of revolution with a circular profile (a sphere or torus piece, :mod:`.revolution`)
  bounded by two parallels (or a pole) and two meridians is meshed in latitude strips on the
  same circle samples (:mod:`.latitude`), its deviation measured in closed form.

:func:`build_plan` recognises such a face set once (faces are immutable: the plan is kept with
the tessellator's per-face-set preparation) and returns None for any other: those go through
the general path (:mod:`.trimmed`) whole. Everything the plan claims is checked against the
faces' own evaluators when it is built (the edges' samples against the recognised lines and
circles, every use's ``(u, v)`` map against its surface), and its loops are checked as the
general path would check them (closed, oriented, not crossing, nested right: :mod:`.plan_checks`),
so a first call needs no general-path mesh. The recognition runs over all faces and edges at once
(circle fits, circle maps, the uses' ``(u, v)`` maps), not one object at a time; the faces' kinds
come from :mod:`.plan_faces`.
"""

from __future__ import annotations

import functools

import mapbox_earcut as earcut
import numpy as np

from ..mesh.topology import ranges
from ..tolerances import WELD
from .arcs import REL, CircleMaps, _cross, _dot, _norm, _unwrap, fit_circles, segments
from .latitude import latitude_plan
from .plan_faces import CYLINDER, PLANE, REVOLUTION, _mask, curved_faces, cylinder_loops
from .plan_checks import loops_valid
from .revolution import Revolutions
from .welding import close_pairs, components

__all__ = ["CYLINDER", "PLANE", "REVOLUTION", "FastPlan", "build_plan", "planar_triangles"]

SAMPLES = 129
"""Samples per edge used to recognise its shape (at least :data:`PER_PIECE` per conic piece for 16
pieces), unless every edge of the face set has at most 4 pieces: then :data:`FEW_SAMPLES`."""
FRACTIONS = np.linspace(0.0, 1.0, SAMPLES)
FRACTIONS.setflags(write=False)
FEW_SAMPLES = 33
"""Samples per edge when no edge has more than 4 conic pieces (:func:`sample_parameters`): every
fourth of the :data:`SAMPLES`, plus the two a circle is fitted through and their mirror images."""
PER_PIECE = 8
"""Fewest samples per conic piece of an edge: five points on a circle make a conic that circle."""

MERIDIAN, PARALLEL = 2.0, 1.0
"""Factors on the radius of the arcs of faces of revolution (their sagitta aimed at ``1 / factor`` of
the tolerance): a meridian sets the rows' spacing, which must leave room for the rows' own steps
(:mod:`.latitude`); a parallel is raised per call to what its row needs. 2.0 measured fewest
triangles on the filleted box and cylinder (1.6: +5%, 2.4: +1-5% at 1e-3 and 1e-4)."""


def planar_triangles(polygons):
    """Triangles ``(t, 3)`` (counter-clockwise, indices into its own points) of each polygon
    ``(uv (n, 2), ring_ends)`` (rings: outer first, then holes, ending at ``ring_ends``), by ear
    clipping (one call per polygon, the checks for all at once); None unless every polygon gets
    a proper triangulation: ``n + 2 holes - 2`` triangles, its outer ring counter-clockwise and
    its holes clockwise, their areas summing to the polygon's (ear clipping drops collinear points
    and does not check that holes lie inside)."""
    Ts, offsets, base = [], [], 0
    for uv, ring_ends in polygons:
        T = earcut.triangulate_float64(uv, ring_ends.astype(np.uint32)).reshape(-1, 3).astype(np.int64)
        if len(T) != len(uv) + 2 * (len(ring_ends) - 1) - 2:
            return None
        Ts.append(T)
        offsets.append(base)
        base += len(uv)
    if not polygons:
        return []
    P = np.concatenate([uv for uv, _ in polygons])
    count = np.array([len(T) for T in Ts])
    poly = np.repeat(np.arange(len(Ts)), count)
    T = np.concatenate(Ts) + np.repeat(offsets, count)[:, None]
    a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    T = np.where((area < 0)[:, None], T[:, [0, 2, 1]], T) - np.repeat(offsets, count)[:, None]
    # the rings, polygon after polygon
    ends = np.concatenate([e + o for (_, e), o in zip(polygons, offsets)])
    nrings = np.array([len(e) for _, e in polygons])
    starts = np.concatenate([[0], ends[:-1]])
    nxt = np.arange(1, len(P) + 1)
    nxt[ends - 1] = starts
    shoelace = P[:, 0] * P[nxt, 1] - P[nxt, 0] * P[:, 1]
    ring = np.repeat(np.arange(len(ends)), ends - starts)
    signed = np.bincount(ring, shoelace, len(ends))
    outer = np.zeros(len(ends), dtype=bool)
    outer[np.cumsum(nrings) - nrings] = True
    # the outer ring counter-clockwise, the holes clockwise: the material on the loops' left
    if not np.where(outer, signed > 0, signed < 0).all():
        return None
    ring_poly = np.repeat(np.arange(len(Ts)), nrings)
    total = np.bincount(ring_poly, signed, len(Ts))
    scale = np.bincount(ring_poly, np.abs(signed), len(Ts))
    if (np.abs(np.bincount(poly, np.abs(area), len(Ts)) - total) > 1e-9 * scale).any():
        return None
    return np.split(T, np.cumsum(count)[:-1])


class FastPlan:
    """What :func:`.fast_mesh.fast_tessellation` needs at every tolerance (see the module
    docstring). Arrays per edge group ``g`` (G), per use ``i`` (U, in :func:`.edges.edge_uses`
    order) and per face ``f`` (F); arcs are numbered ``a`` among the circle groups."""

    __slots__ = (
        "faces", "kind", "reversed", "corners", "end_vid", "arc_of", "arcs", "arc_c", "arc_r", "arc_e1", "arc_e2",
        "arc_sweep", "arc_closed", "arc_min", "arc_factor", "use_group", "use_face", "use_flip", "use_uv0",
        "use_arc_cyl", "A", "b", "normal", "origin", "fixed_T", "fixed_face", "curved_planes",
        "loop_first", "cyl", "cyl_faces", "map_error", "checked",
        # derived for the per-call path (:func:`_derive`)
        "use_arc", "start_vid", "start_X", "au", "au_arc", "au_flip", "au_slot", "au_off", "au_sense", "au_v",
        "au_A", "au_b", "maps", "slot_of_face", "slot_centre", "slot_axis", "slot_sign", "slot_radius", "slot_lo",
        "slot_hi", "cp_loops", "cp_first_use", "cp_loop_uses", "use_slot", "use_off", "use_sense", "n_line_uses",
        "kernel_args", "zb_use", "zb_slot", "zt_use", "zt_slot", "face_first_use", "plane_offset", "static",
        "lat",  # faces of revolution: their :class:`.latitude.LatitudePlan`, or None
    )  # fmt: skip


def sample_parameters(prep, rep):
    """``(keep (k,), through)``: the samples (indices into :data:`SAMPLES` uniform fractions of the
    pcurve's domain) that recognise every edge group's shape, from its representative use ``rep``
    ``(G,)``, and the indices in ``keep`` of the two a circle is fitted through
    (:func:`.arcs.fit_circles`: the samples at a third and two thirds of the :data:`SAMPLES`,
    whatever the count). All :data:`SAMPLES` unless each group's 3-D curve has at most
    ``(FEW_SAMPLES - 1) / PER_PIECE`` conic pieces, counted as its pcurve's pieces, each split at
    most ``degree`` times per knot line of its surface (a line pcurve on a plane: one; a full
    circle of four quarters: four; a line around a four-span cylinder: four), and its shortest
    pcurve piece spans at least that fraction of its domain: then every fourth (:data:`FEW_SAMPLES`),
    plus the two fitting ones and their mirror images (37). Most machined parts need the fewer: a
    quarter of the samples' arrays and of their evaluations."""
    pc = prep.pcurves.breaks
    curve = np.repeat(np.arange(pc.count.size), pc.count)
    width = (pc.b - pc.a) / (pc.hi - pc.lo)[curve]  # each piece's share of its pcurve's domain
    shortest = np.minimum.reduceat(width, pc.start)[rep]
    f = prep.table.face[rep]
    lines = prep.batch.nsu[f] + prep.batch.nsv[f] - 2  # the face's inner knot lines
    pieces = pc.count[rep] * (1 + prep.pcurves.degree[rep] * lines)
    most = (FEW_SAMPLES - 1) // PER_PIECE
    few = (pieces <= most) & (shortest * most >= 1.0 - 1e-9)
    return _kept(SAMPLES, FEW_SAMPLES if few.all() else SAMPLES)


@functools.lru_cache(maxsize=4)
def _kept(samples, few):
    """``(keep, through)`` of :func:`sample_parameters` for ``few`` of ``samples`` (cached, read-only)."""
    through = np.array([samples // 3, (2 * samples) // 3])
    # every step-th, and symmetric about the middle: a use that runs against its group reads the
    # samples backwards
    keep = np.union1d(np.arange(0, samples, (samples - 1) // (few - 1)), np.concatenate([through, samples - 1 - through]))
    keep.setflags(write=False)
    return keep, tuple(np.searchsorted(keep, through).tolist())


def build_plan(prep):
    """The :class:`FastPlan` of the face set ``prep`` (:class:`.trimmed._Prepared`), or None if
    any face is not a plane, a right circular cylinder or a face of revolution of the shapes
    above, or any edge is neither a straight segment, a circle arc nor a pole."""
    faces, uses, groups, size = prep.faces, prep.uses, prep.groups, prep.size
    if not uses:
        return None
    F, U, G = len(faces), len(uses), len(groups)
    found = curved_faces(prep, size)
    if found is None:
        return None
    kind, cyl, rev = found
    use_face = np.array([u.f for u in uses], dtype=np.int64)
    # a collapsed edge (a pole) only where a face of revolution meets its axis
    degenerate = np.array([u.edge.degenerate for u in uses], dtype=bool)
    if (kind[use_face[degenerate]] != REVOLUTION).any():
        return None
    n_degenerate = np.bincount(prep.table.group_of, degenerate, G)
    pole_group = n_degenerate == np.bincount(prep.table.group_of, minlength=G)
    if (pole_group != (n_degenerate > 0)).any():
        return None
    use_group = prep.table.group_of
    pdom = np.column_stack([prep.pcurves.breaks.lo, prep.pcurves.breaks.hi])
    # every group's shape, from its first use's surface at its pcurve
    rep = np.array([g[0] for g in groups], dtype=np.int64)
    keep, through = sample_parameters(prep, rep)
    r = FRACTIONS[keep]
    K = keep.size  # samples per group
    t = (pdom[rep, :1] + (pdom[rep, 1:] - pdom[rep, :1]) * r).ravel()
    # the groups' samples, and each use's (u, v) at a third of its domain and at its ends: one
    # evaluation of all pcurves instead of four
    ids = np.arange(U)
    uv, third, use_uv0, use_uv1 = np.split(
        prep.pcurves.evaluate(np.concatenate([np.repeat(rep, K), ids, ids, ids]),
                              np.concatenate([t, pdom[:, 0] + (pdom[:, 1] - pdom[:, 0]) / 3.0, pdom[:, 0], pdom[:, 1]])),
        np.cumsum([G * K, U, U]))  # fmt: skip
    # every face's point and partials at its domain's corner: an affine face (a plane) is
    # S + (u - u0) Su + (v - v0) Sv exactly, so its points need no surface evaluator
    corner = np.column_stack([prep.batch.lu.lo, prep.batch.lv.lo])  # (F, 2)
    S, (Su, Sv) = prep.origin, prep.partials
    all_flat = bool(prep.affine.all())

    def surface_points(f, uv):
        if all_flat:  # only planes (a box, a chamfered block): no selection
            d = uv - corner[f]
            return S[f] + d[:, :1] * Su[f] + d[:, 1:] * Sv[f]
        out = np.empty((len(f), 3))
        flat = prep.affine[f]
        k = np.flatnonzero(flat)
        fk, d = f[k], uv[k] - corner[f[k]]
        out[k] = S[fk] + d[:, :1] * Su[fk] + d[:, 1:] * Sv[fk]
        k = np.flatnonzero(~flat)
        if k.size:
            out[k] = prep.batch.evaluate(f[k], uv[k, 0], uv[k, 1])
        return out

    X, Y = np.split(surface_points(np.concatenate([np.repeat(use_face[rep], K), use_face]), np.concatenate([uv, third])), [G * K])
    X = X.reshape(G, K, 3)
    # every group a pole, a straight segment or a circle arc
    curved = np.flatnonzero(~pole_group & ~segments(X, size))
    if curved.size:
        fits = fit_circles(X[curved], size, through)
        if not fits.ok.all():
            return None
    arcs = [fits.circle(i) for i in range(curved.size)]
    arc_of = np.full(G, -1, dtype=np.int64)
    arc_of[curved] = np.arange(curved.size)
    # each use's direction against its group's samples
    nearest = np.argmin(_norm(X[use_group] - Y[:, None]), axis=1)
    use_flip = nearest > K // 2
    # the corners: the groups' end points welded as the general path welds them
    ends = np.concatenate([X[:, 0], X[:, -1]])
    pairs = close_pairs(ends, max(WELD * size, 10.0 * prep.edge_tol))
    lab = components(len(ends), pairs[:, 0], pairs[:, 1]) if len(pairs) else np.arange(len(ends))
    first, vid = np.unique(lab, return_index=True, return_inverse=True)[1:]
    plan = FastPlan()
    plan.faces, plan.kind, plan.reversed, plan.arcs, plan.arc_of = faces, kind, prep.reversed, arcs, arc_of
    plan.corners, plan.end_vid = ends[first], vid.reshape(2, G).T.copy()
    plan.use_group, plan.use_face, plan.use_flip, plan.use_uv0 = use_group, use_face, use_flip, use_uv0
    plan.arc_c = np.array([a.centre for a in arcs]).reshape(-1, 3)
    plan.arc_e1 = np.array([a.e1 for a in arcs]).reshape(-1, 3)
    plan.arc_e2 = np.array([a.e2 for a in arcs]).reshape(-1, 3)
    plan.arc_r = np.array([a.radius for a in arcs], dtype=np.float64)
    plan.arc_sweep = np.array([a.sweep for a in arcs], dtype=np.float64)
    plan.arc_closed = np.array([a.closed for a in arcs], dtype=bool)
    plan.arc_min = np.where(plan.arc_closed, 3, 1)  # a closed circle is at least a triangle
    # planes: (u, v) = A X + b, unit normal (outward), a point
    plan.A = np.linalg.pinv(np.stack([Su, Sv], axis=2))  # (F, 2, 3): (u, v) of a point of an affine face
    plan.b = corner - np.einsum("fij,fj->fi", plan.A, S)
    n = _cross(Su, Sv)
    length = _norm(n)[:, None]  # zero at a pole (a face of revolution: not used)
    plan.normal = n / np.where(length > 0, length, 1.0) * np.where(prep.reversed, -1.0, 1.0)[:, None]
    plan.origin = S
    plan.cyl = cyl
    # every use's (u, v) map, checked on its group's samples against its surface
    samples = X[use_group]  # (U, K, 3)
    samples = np.where(use_flip[:, None, None], samples[:, ::-1], samples)
    pred = np.empty((U, K, 2))
    pred[:] = np.einsum("uij,usj->usi", plan.A[use_face], samples) + plan.b[use_face][:, None]
    # cylinders: per arc use (offset, sense) of its angles in the face's circle; its samples'
    # (u, v) through the face's circle map; a ruling runs iso-u, v affine along it
    plan.use_arc_cyl = arc_cyl = np.zeros((U, 2))
    slots = sorted(cyl)
    plan.maps = CircleMaps([cyl[f].cmap for f in slots]) if slots else None
    slot_of_face = np.full(F, -1, dtype=np.int64)
    slot_of_face[slots] = np.arange(len(slots))
    cu = np.flatnonzero((kind[use_face] == CYLINDER) & (arc_of[use_group] >= 0))
    if cu.size:
        a, q = arc_of[use_group[cu]], slot_of_face[use_face[cu]]
        cc = np.array([cyl[f].cmap.circle.centre for f in slots])[q]
        ce1 = np.array([cyl[f].cmap.circle.e1 for f in slots])[q]
        ce2 = np.array([cyl[f].cmap.circle.e2 for f in slots])[q]
        # the arc's points at its start and a quarter of its sweep, as angles in the cylinder's circle
        ang = np.column_stack([np.zeros(cu.size), 0.25 * plan.arc_sweep[a]])
        d = plan.arc_c[a][:, None] + plan.arc_r[a][:, None, None] * (np.cos(ang)[..., None] * plan.arc_e1[a][:, None]
                                                                   + np.sin(ang)[..., None] * plan.arc_e2[a][:, None]) - cc[:, None]  # fmt: skip
        th = np.mod(np.arctan2(_dot(d, ce2[:, None]), _dot(d, ce1[:, None])), 2 * np.pi)
        arc_cyl[cu, 0] = th[:, 0]
        arc_cyl[cu, 1] = np.where(np.mod(th[:, 1] - th[:, 0], 2 * np.pi) < np.pi, 1.0, -1.0)
        d = X[use_group[cu]] - plan.arc_c[a][:, None]
        theta = _unwrap(np.mod(np.arctan2(_dot(d, plan.arc_e2[a][:, None]), _dot(d, plan.arc_e1[a][:, None])), 2 * np.pi))
        theta -= theta[:, :1]
        theta = np.where(use_flip[cu][:, None], theta[:, ::-1], theta)
        pred[cu, :, 0] = plan.maps.param(np.repeat(q, K), (arc_cyl[cu, :1] + arc_cyl[cu, 1:] * theta).ravel()).reshape(-1, K)
        pred[cu, :, 1] = use_uv0[cu, 1:]
        pred[cu, 0], pred[cu, -1] = use_uv0[cu], use_uv1[cu]
    ru = np.flatnonzero((kind[use_face] == CYLINDER) & (arc_of[use_group] < 0))
    if ru.size:
        pred[ru] = np.linspace(use_uv0[ru], use_uv1[ru], SAMPLES, axis=1)[:, keep]
    revs = Revolutions([rev[f] for f in sorted(rev)]) if rev else None
    vu = np.flatnonzero(kind[use_face] == REVOLUTION)
    if vu.size:
        rq = np.searchsorted(np.array(sorted(rev)), use_face[vu])
        line = np.linspace(use_uv0[vu], use_uv1[vu], SAMPLES, axis=1)[:, keep]  # a pole's (u, v), straight
        pred[vu] = revs.uv_of(rq, samples[vu], line, arc_of[use_group[vu]] >= 0)
    back = surface_points(np.repeat(use_face, K), pred.reshape(-1, 2))
    # (a sloppy file's edges off their faces take the general path, which allows for that)
    map_error = float(_norm(back.reshape(U, K, 3) - samples).max())
    if map_error > 10.0 * REL * size:
        return None
    if not cylinder_loops(plan, prep, use_uv0, use_uv1):
        return None
    plan.lat = latitude_plan(plan, prep.table.loop, rev, revs, pole_group, use_uv0, use_uv1, size) if rev else None
    if rev and plan.lat is None:
        return None
    plan.map_error = map_error
    # the loops checked on their exact shapes, so that a first call needs no general-path mesh
    plane_use, arc_use = kind[use_face] == PLANE, arc_of[use_group] >= 0
    arcs = _plane_arcs(plan, np.flatnonzero(plane_use & arc_use), pred)
    plan.checked = loops_valid(plan, prep.table, pred, use_uv0, use_uv1, plane_use, arc_use, arcs)
    # straight-edged planes: triangulated once (indices into the face's loop points, which are
    # its uses' start corners at every tolerance); uses and loops run face after face, so all
    # plane faces are split at once, with no numpy calls per face
    table = prep.table
    plane = np.flatnonzero(kind == PLANE)
    curved_uses = np.bincount(use_face, arc_use, F)[plane] > 0
    fixed, bent = plane[~curved_uses], plane[curved_uses]
    n_uses, n_loops = np.bincount(use_face, minlength=F), np.bincount(table.loop_face, minlength=F)
    first_use = np.cumsum(n_uses) - n_uses
    on = _mask(F, fixed)[table.loop_face]
    uv = np.split(use_uv0[ranges(first_use[fixed], n_uses[fixed])], np.cumsum(n_uses[fixed])[:-1])
    ring_ends = (table.first + table.count - first_use[table.loop_face])[on]
    polygons = list(zip(uv, np.split(ring_ends, np.cumsum(n_loops[fixed])[:-1]))) if fixed.size else []
    plan.loop_first = table.first
    plan.cp_loops = np.flatnonzero(_mask(F, bent)[table.loop_face])
    plan.curved_planes = list(zip(bent.tolist(), np.split(plan.cp_loops, np.cumsum(n_loops[bent])[:-1]))) if bent.size else []
    fixed_T = planar_triangles(polygons)
    if fixed_T is None:
        return None
    plan.fixed_T = np.concatenate(fixed_T) if fixed_T else np.zeros((0, 3), dtype=np.int64)
    plan.fixed_face = np.repeat(fixed, n_uses[fixed] + 2 * n_loops[fixed] - 4)  # n + 2 holes - 2 triangles each
    plan.cp_first_use, plan.cp_loop_uses = prep.table.first[plan.cp_loops], prep.table.count[plan.cp_loops]
    _derive(plan)
    return plan


def _plane_arcs(plan, uses, pred):
    """``(U, SAMPLES, 2)``: the ``(u, v)`` of :data:`SAMPLES` points of the exact circle arc of each
    of ``uses`` (arc uses on planes), uniform in angle from the use's start to its end (the ends:
    ``pred``'s), for the loop checks' polygons (:func:`.plan_checks.loops_valid`; the other rows
    are left zero)."""
    out = np.zeros((len(pred), SAMPLES, 2))
    if uses.size == 0:
        return out
    a, f = plan.arc_of[plan.use_group[uses]], plan.use_face[uses]
    theta = plan.arc_sweep[a][:, None] * FRACTIONS
    theta = np.where(plan.use_flip[uses][:, None], theta[:, ::-1], theta)
    X = plan.arc_c[a][:, None] + plan.arc_r[a][:, None, None] * (np.cos(theta)[..., None] * plan.arc_e1[a][:, None]
                                                               + np.sin(theta)[..., None] * plan.arc_e2[a][:, None])  # fmt: skip
    out[uses] = np.einsum("uij,usj->usi", plan.A[f], X) + plan.b[f][:, None]
    out[uses, 0], out[uses, -1] = pred[uses, 0], pred[uses, -1]
    return out


def _derive(plan):
    """The flat arrays the per-call path indexes (see :class:`FastPlan`): per arc use ``au`` its
    arc, direction, cylinder slot (-1 on a plane), angle offset and sense in the cylinder's
    circle, constant ``v``, plane map; per cylinder slot its axis, orientation, ``u`` range and
    the uses of its bottom and top chains; the circles' count factors; the planes' offsets."""
    g = plan.use_group
    plan.use_arc = plan.arc_of[g]
    plan.start_vid = np.where(plan.use_flip, plan.end_vid[g, 1], plan.end_vid[g, 0])
    plan.start_X = plan.corners[plan.start_vid]
    au = plan.au = np.flatnonzero(plan.use_arc >= 0)
    slots = sorted(plan.cyl)
    slot_of_face = plan.slot_of_face = np.full(len(plan.faces), -1, dtype=np.int64)
    slot_of_face[slots] = np.arange(len(slots))
    plan.au_arc, plan.au_flip, plan.au_slot = plan.use_arc[au], plan.use_flip[au], slot_of_face[plan.use_face[au]]
    plan.au_off, plan.au_sense = plan.use_arc_cyl[au, 0], plan.use_arc_cyl[au, 1]
    plan.au_v = plan.use_uv0[au, 1]
    plan.au_A, plan.au_b = plan.A[plan.use_face[au]], plan.b[plan.use_face[au]]
    plan.face_first_use = np.searchsorted(plan.use_face, np.arange(len(plan.faces)))
    # a circle's count factor: its parametric midpoints on a cylinder stray by up to kappa step^2 / 8
    # radians along it (at right angles to the sagitta), so the deviation is at most about
    # sagitta * sqrt(1 + kappa^2); 2% margin for the higher-order terms (the result is measured)
    plan.arc_factor = np.ones(len(plan.arcs))
    plan.zb_use = None
    lat = plan.lat
    if lat is not None:  # faces of revolution: the factors above, with the maps' Möbius margin
        ku, kv = lat.revs.kappa_u, lat.revs.kappa_v
        for arcs, kappa, half in ((lat.bot_arc, ku, PARALLEL), (lat.top_arc, ku, PARALLEL),
                                  (lat.mer_arc[:, 0], kv, MERIDIAN), (lat.mer_arc[:, 1], kv, MERIDIAN)):  # fmt: skip
            on = arcs >= 0
            np.maximum.at(plan.arc_factor, arcs[on], half * np.sqrt(1.0 + (1.02 * kappa[on]) ** 2))
    if slots:
        on = plan.au_slot >= 0
        np.maximum.at(plan.arc_factor, plan.au_arc[on], np.sqrt(1.0 + (1.02 * plan.maps.kappa[plan.au_slot[on]]) ** 2))
        plan.slot_centre = np.array([plan.cyl[f].cmap.circle.centre for f in slots])
        plan.slot_axis = np.array([plan.cyl[f].axis for f in slots])
        plan.slot_radius = np.array([plan.cyl[f].cmap.circle.radius for f in slots])
        plan.slot_sign = np.array([plan.cyl[f].sign * (-1.0 if plan.reversed[f] else 1.0) for f in slots])
        zb, zbs, zt, zts, lo, hi = [], [], [], [], [], []
        for q, f in enumerate(slots):
            order, nb = plan.cyl_faces[f]
            zb.append(order[: nb + 1])  # the bottom uses, then the ruling at u_hi (its start: the bottom's end)
            zbs.append(np.full(nb + 1, q))
            lo.append(plan.use_uv0[order[0], 0])
            hi.append(plan.use_uv0[order[nb], 0])
        for q, f in reversed(list(enumerate(slots))):  # reversed as a whole below: each top chain runs in u
            order, nb = plan.cyl_faces[f]
            zt.append(order[nb + 1 :])  # the top uses, then the ruling at u_lo
            zts.append(np.full(len(order) - nb - 1, q))
        plan.zb_use, plan.zb_slot = np.concatenate(zb), np.concatenate(zbs)
        plan.zt_use, plan.zt_slot = np.concatenate(zt), np.concatenate(zts)
        plan.slot_lo, plan.slot_hi = np.array(lo), np.array(hi)
    # how far the planes' points lie off their planes (their deviation): corners, and circles
    # (centre offset plus the tilt of their plane)
    pu = np.flatnonzero(plan.kind[plan.use_face] == PLANE)
    f = plan.use_face[pu]
    off = np.abs(np.einsum("ij,ij->i", plan.start_X[pu] - plan.origin[f], plan.normal[f]))
    a = plan.use_arc[pu]
    arc = a >= 0
    if arc.any():
        n, aa = plan.normal[f[arc]], a[arc]
        tilt = np.abs(np.einsum("ij,ij->i", n, plan.arc_e1[aa])) + np.abs(np.einsum("ij,ij->i", n, plan.arc_e2[aa]))
        off[arc] = np.maximum(off[arc], np.abs(np.einsum("ij,ij->i", plan.arc_c[aa] - plan.origin[f[arc]], n)) + plan.arc_r[aa] * tilt)
    # added to the measured deviation: how far the points may lie off their faces (rounding)
    plan.plane_offset = max(float(off.max()) if off.size else 0.0, plan.map_error)
    plan.static = None
    # per use (for the compiled kernels): cylinder slot (-1: a plane or a ruling), angle offset and sense
    plan.use_slot = np.full(len(g), -1, dtype=np.int64)
    plan.use_slot[au] = plan.au_slot
    plan.use_off, plan.use_sense = plan.use_arc_cyl[:, 0].copy(), plan.use_arc_cyl[:, 1].copy()
    plan.n_line_uses = int((plan.use_arc < 0).sum())
    e, ei = np.zeros(0), np.zeros(0, dtype=np.int64)
    m = plan.maps if slots else None
    maps = (m.akey, m.table, m.first, m.last, m.sweep, m.full) if m else (e, np.zeros((0, 5)), ei, ei, e, True)
    angle = (m.tkey, m.table, m.first, m.last, m.t0, m.t1) if m else (e, np.zeros((0, 5)), ei, ei, e, e)
    zips = ((plan.zb_use, plan.zb_slot, plan.zt_use, plan.zt_slot, plan.slot_lo, plan.slot_hi, plan.slot_radius,
             plan.slot_centre, plan.slot_axis, plan.slot_sign) if slots  # fmt: skip
            else (ei, ei, ei, ei, e, e, e, np.zeros((0, 3)), np.zeros((0, 3)), e))
    plan.kernel_args = maps, angle, zips
