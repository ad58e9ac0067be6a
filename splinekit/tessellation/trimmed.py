"""Watertight tessellation of trimmed faces, shells and solids.

Faces bounded by their natural domain that share no edge with another face (a whole sphere or
torus: only seams and poles) are meshed by the patch path (:mod:`.natural`). Face sets made only
of planes, right circular cylinders and sphere or torus pieces bounded by parallels, meridians
and poles, with straight segments and circle arcs for edges (boxes, plates with holes, chamfered
blocks, cylinders, filleted boxes and cylinders: most machined parts) take a fast path
(:mod:`.fast_plan`, :mod:`.fast_mesh`, :mod:`.latitude`): a tolerance-independent plan, built once
per face set on its first call with its loops checked on their exact shapes (:mod:`.plan_checks`;
loops it does not accept go through the general path below first, which raises on bad ones),
and per call only
the circles' counts in closed form, ear clipping of the planes' boundary polygons, strips on the
cylinders and latitude strips on the spheres and tori, with the same guarantees and the same
``max_deviation`` yardstick. Every other face
set, and any call the fast path cannot keep a guarantee on, takes the general path whole.

Design of the general path (whole-array work; Python loops run over faces, edges and refinement
rounds, never over points or triangles):

1. Interior grid (:mod:`.face_grids`). Each face's surface is cut into Bézier cells
   (:mod:`.cells`); the same a-priori bounds on the second derivatives that size the untrimmed
   patch grids give each cell its ``nu x nv`` steps, and a knot span row (column) takes the
   largest count of its cells; that grid is evaluated once and each span's count lowered to
   what its measured chord error needs (the bounds hold over whole cells, so they over-count on
   spheres and rational arcs): one tensor grid of parameters per face. Everything that does
   not depend on the tolerance (batch evaluators, bounds, edge uses and their pairing, checks)
   is computed once per face set and cached on its first face.
2. Scaled parameter plane. Each face is triangulated in ``(u, v)`` scaled by
   ``(steps in u / range of u, steps in v / range of v)``: there the grid's step is about one in
   both directions, i.e. lengths measure the local chordal error, so Delaunay triangles that are
   well shaped in this plane are the ones that spend the fewest triangles on the tolerance
   (a cylinder's long, thin triangles along its rulings; square ones on a sphere).
3. Edges (:mod:`.edges`): every edge is sampled once in 3-D, to the tolerance, and every face
   that uses it gets the ``(u, v)`` images of the same points, so the mesh is watertight by
   construction: shared vertices are shared indices, not welded copies. Loop corners are the
   edge end points, welded once.
4. Constrained Delaunay triangulation of every face at once (Shewchuk's Triangle, through the
   ``triangle`` package): the faces' scaled planes are laid side by side, the trims are the
   segments, grid points within half a step of a trim are dropped (no slivers). Triangles are
   kept or dropped by region: a triangle whose edge runs along a trim in the trim's direction
   lies on the material side (loops keep the material on their left), and the label spreads
   over the triangles connected without crossing a trim (one sparse connected-components pass).
   Trims must not cross; where they do within their edges' own tolerance (sliver faces of some
   CAD exports), the looser edge's points are first moved apart in ``(u, v)`` only
   (:mod:`.untangle`).
5. Measure and refine: the deviation is measured at every triangle's centre and every edge's
   midpoint (the surface at the barycentric ``(u, v)`` against the flat triangle's point); the
   midpoints of interior edges over the tolerance (and the centres of triangles over it whose
   edges are fine) are added to the point set and the faces triangulated again, for a few rounds.
   On an affine face (a plane whose parametrization is a parallelogram) the surface at a mean
   of ``(u, v)`` is the mean of the surface points, so its deviation comes from the corners'
   offsets alone, without evaluating; a line segment used only by such faces is sampled at its
   two ends once per face set (:func:`.edges.sample_groups`).
6. Orientation: triangles run counter-clockwise in ``(u, v)``, so their normals follow
   ``Su x Sv``; a reversed face's triangles are flipped. Triangles that collapse in 3-D (two
   corners on one pole) are dropped.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels, limits
from .._signals import reraise_interrupt
from ..errors import BackendError, ParameterError
from ..tolerances import WELD
from .batch import CurveBatch, SurfaceBatch
from .cells import second_derivative_bounds
from .edges import _face_name, _pieces, check_domains, edge_uses, group_uses, sample_groups
from .face_grids import face_grids
from .fast_mesh import fast_tessellation
from .fast_plan import build_plan
from .loops import Layout, LoopTable, gather_loops
from .natural import concatenate, natural_faces, surfaces_of, tessellate_natural
from .result import Tessellation
from .surfaces import BYTES_PER_TRIANGLE
from .untangle import crossing, untangle
from .welding import close_pairs, components

__all__ = ["tessellate_faces"]

MAX_ROUNDS = 8
"""Largest number of measure-and-refine rounds."""
CLEARANCE = 0.5
"""Grid points closer than this (in scaled grid steps) to a trim are dropped."""
# WELD (from splinekit.tolerances): weld distance of edge end points, relative to the model's
# bounding-box diagonal (or the edges' own tolerances where larger).


def _triangulator():
    try:
        import triangle
    except ImportError as exc:  # pragma: no cover - a core dependency
        reraise_interrupt(exc)
        raise BackendError("tessellating trimmed faces needs the 'triangle' package: pip install triangle") from exc
    return triangle


def _edge_vertices(samples, size, tolerance, memo):
    """Mesh vertices of the edge samples: end points welded (within the weld distance), inner
    samples numbered after them. Returns ``(vid_of_group, xyz (n, 3))``. The ends are the edges'
    vertices at every tolerance, so their welding is kept in ``memo`` (the face set's)."""
    if "ends" not in memo:
        ends = np.concatenate([[s.points[0], s.points[-1]] for s in samples]) if samples else np.zeros((0, 3))
        pairs = close_pairs(ends, max(WELD * size, 10.0 * tolerance))
        lab = components(len(ends), pairs[:, 0], pairs[:, 1]) if len(pairs) else np.arange(len(ends))
        first, end_vid = np.unique(lab, return_index=True, return_inverse=True)[1:]
        memo["ends"] = ends[first], end_vid.reshape(-1, 2)
    corners, end_vid = memo["ends"]
    deg = np.array([s.degenerate for s in samples], dtype=bool)
    m = np.array([len(next(iter(s.uv.values()))) if s.degenerate else len(s.points) for s in samples], dtype=np.int64)
    inner = np.where(deg, 0, m - 2)
    base = len(corners) + np.cumsum(inner) - inner  # first inner vertex of each group
    g = np.repeat(np.arange(len(samples)), m)
    j = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m)
    vid = base[g] + j - 1
    vid[j == 0] = end_vid[g[j == 0], 0]
    last = j == m[g] - 1
    vid[last] = end_vid[g[last], 1]
    vid[deg[g]] = end_vid[g[deg[g]], 0]
    xyz = [corners] + [s.points[1:-1] for s in samples if not s.degenerate]
    return _pieces(vid, np.cumsum(m)[:-1]), np.concatenate(xyz)


def _grid_points(grids, layout, P, segs):
    """Interior grid points of every face (scaled, laid out) at least :data:`CLEARANCE` from the
    trims (``P[segs]``: the trims' segments, scaled, laid out). Returns ``(face, uv)``."""
    from scipy.spatial import cKDTree

    fs, uvs = [], []
    for f, g in enumerate(grids):
        if g.us.size <= 2 and g.vs.size <= 2:  # one span each way (a plane): the domain's ends only
            continue
        lo, hi = layout.lo[f], layout.hi[f]
        margin = CLEARANCE / g.scale
        us = g.us[(g.us > lo[0] + margin[0]) & (g.us < hi[0] - margin[0])]
        vs = g.vs[(g.vs > lo[1] + margin[1]) & (g.vs < hi[1] - margin[1])]
        if us.size and vs.size:
            U, V = np.meshgrid(us, vs, indexing="ij")
            uvs.append(np.column_stack([U.ravel(), V.ravel()]))
            fs.append(np.full(U.size, f))
    if not uvs:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    fidx, uv = np.concatenate(fs), np.concatenate(uvs)
    dense = _densify(P, segs, 0.5 * CLEARANCE)
    d, _ = cKDTree(dense).query(layout.place(fidx, uv), distance_upper_bound=CLEARANCE)
    keep = ~np.isfinite(d)
    return fidx[keep], uv[keep]


def _densify(P, segs, step):
    """Points every ``step`` or closer along the segments ``P[segs]``."""
    a, b = P[segs[:, 0]], P[segs[:, 1]]
    n = np.maximum(np.ceil(np.linalg.norm(b - a, axis=1) / step), 1).astype(np.int64)
    seg = np.repeat(np.arange(len(segs)), n)
    frac = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)) / n[seg]
    return a[seg] + (b - a)[seg] * frac[:, None]


def _without_crossings(faces, index, uses, batch, layout, pface, puv, pxyz, segs, owner):
    """The boundary points' ``(u, v)`` ``(n, 2)``, where trims cross moved apart as far as the
    edges' own tolerances allow (:func:`.untangle.untangle`: the surface at a moved point's new
    ``(u, v)`` must lie within its edge's tolerance of its 3-D point); else ParameterError
    naming the face. ``owner`` ``(n,)``: the edge use of each point."""
    P = layout.place(pface, puv)
    bad = crossing(P, segs)
    if bad < 0:
        return puv
    corner = np.concatenate([[True], owner[1:] != owner[:-1]])
    weight = np.array([u.edge.tolerance for u in uses], dtype=np.float64)
    fixed = untangle(P, segs, owner, corner, weight)
    if fixed is not None:
        uv = layout.unplace(pface, fixed[0])
        k = np.flatnonzero(fixed[1])
        off = np.linalg.norm(batch.evaluate(pface[k], uv[k, 0], uv[k, 1]) - pxyz[k], axis=1)
        if np.all(off <= weight[owner[k]]):
            return uv
    f = int(pface[segs[bad, 0]])
    raise ParameterError(f"{_face_name(faces[f], index[f])}: its trimming loops cross or touch each other (or themselves)")


def _half_edges(T):
    """``(a, b)`` ``(t, 3)``: the edge opposite corner ``k`` of each counter-clockwise triangle,
    directed as the triangle runs (Triangle's ``neighbors[:, k]`` lies across it)."""
    return T[:, [1, 2, 0]], T[:, [2, 0, 1]]


def _keep_inside(T, N, nxt):
    """Which triangles ``T`` ``(t, 3)`` (counter-clockwise; ``N`` their neighbours across each
    corner's opposite edge, -1 on the hull) lie on the material side of the trims (``nxt[i]``:
    the point after boundary point ``i`` in its loop, -1 for other points). A triangle with an
    edge running along a trim lies to its left, inside; one running against it lies outside;
    the label spreads over triangles connected across non-trim edges. Returns ``(keep (t,)
    bool, conflict, along (t, 3) bool)``: ``conflict`` is a triangle whose region is both inside
    and outside (crossing or badly nested loops), or -1; ``along`` marks edges on a trim."""
    a, b = _half_edges(T)
    fwd = nxt[a] == b  # nxt of an interior point is -1, never a point index
    rev = nxt[b] == a
    along = fwd | rev
    t, k = np.nonzero((N >= 0) & ~along)
    lab = components(len(T), t, N[t, k])
    inside = np.zeros(len(T), dtype=bool)
    outside = np.zeros(len(T), dtype=bool)
    inside[lab[np.nonzero(fwd)[0]]] = True
    outside[lab[np.nonzero(rev)[0]]] = True
    both = np.flatnonzero(inside & outside)
    conflict = int(np.flatnonzero(np.isin(lab, both))[0]) if both.size else -1
    return inside[lab], conflict, along


def _affine(surfaces) -> np.ndarray:
    """``(n,)`` bool: which ``surfaces`` are affine maps of their parameters (one bilinear span
    whose control points form a parallelogram, equal weights): planes on which a flat triangle's
    point is the surface's point at the same barycentric (u, v). All candidates in one pass."""
    out = np.zeros(len(surfaces), dtype=bool)
    cand = [i for i, s in enumerate(surfaces) if s.degree_u == 1 and s.degree_v == 1 and s.control_points.shape[:2] == (2, 2)]
    if not cand:
        return out
    P = np.stack([surfaces[i].control_points for i in cand])  # (k, 2, 2, 3)
    twist = P[:, 1, 1] - P[:, 1, 0] - P[:, 0, 1] + P[:, 0, 0]
    flat = np.abs(twist).max(axis=1) <= 1e-14 * np.maximum(np.abs(P).reshape(len(cand), -1).max(axis=1), 1e-300)
    for k, i in enumerate(cand):  # rational: only with equal weights
        w = surfaces[i].weights
        if w is not None and np.ptp(np.asarray(w)) > 0:
            flat[k] = False
    out[cand] = flat
    return out


class _Prepared:
    """What a face set's tessellation needs at any tolerance, computed once per face set and kept
    in the first face's ``_cache`` (faces are immutable): the surfaces' batch evaluator and
    second-derivative bounds, the edge uses, their pcurves' batch evaluator (domains checked),
    the groups of uses that are one edge, their loops' indices, which faces are affine and the
    tolerance-independent memo of the edge sampler and the grids."""

    __slots__ = ("faces", "size", "batch", "_bounds", "edge_tol", "uses", "pcurves", "groups", "table", "affine",
                 "origin", "partials", "reversed", "memo", "index", "natural", "rest")

    def __init__(self, faces, size, index=None):
        self.faces, self.size = tuple(faces), size
        self.index = np.arange(len(faces)) if index is None else index  # the faces' numbers in messages
        self.batch = SurfaceBatch([face.surface for face in faces])
        self._bounds = None  # the general path's second-derivative bounds: on first use (:attr:`bounds`)
        self.edge_tol = max((e.tolerance for face in faces for e in face.edges), default=0.0)
        self.uses = edge_uses(faces)
        self.pcurves = CurveBatch([u.edge.pcurve for u in self.uses])
        check_domains(self.uses, self.pcurves, self.batch)
        self.groups = group_uses(self.uses, max(WELD * size, 2.0 * self.edge_tol), self.pcurves, self.batch)
        self.table = LoopTable(self.faces, self.uses, self.groups)
        self.affine = _affine([face.surface for face in faces])
        # an affine face's partials are constant: taken once at its domain's corner (``origin``: the point there)
        corner = np.array([self.batch.lu.lo, self.batch.lv.lo])
        self.origin, *self.partials = self.batch.partials(np.arange(len(faces)), corner[0], corner[1])
        self.reversed = np.array([face.reversed for face in faces], dtype=bool)
        self.memo = {}
        # faces bounded by their natural domain that share no edge go to the patch path
        # (.natural); the others, if any, keep a preparation of their own (.rest)
        natural = natural_faces(self.faces, self.uses, self.table) if index is None else np.zeros(len(faces), bool)
        self.natural = self.rest = None
        if natural.any():
            k = np.flatnonzero(natural)
            self.natural = k, surfaces_of([faces[i] for i in k]), self.reversed[k]
            if not natural.all():
                k = np.flatnonzero(~natural)
                self.rest = _Prepared([faces[i] for i in k], size, k)

    @property
    def bounds(self):
        """Per face the second-derivative bounds of its Bézier cells (the general path's grids;
        the fast path never needs them)."""
        if self._bounds is None:
            self._bounds = [second_derivative_bounds(cs) for cs in self.batch.cellsets]
        return self._bounds

    @classmethod
    def of(cls, faces, size):
        """The cached preparation of ``faces`` (the same face objects in the same order and the
        same model size), else a new one, cached."""
        cache = faces[0]._cache
        prep = cache.get("tessellate")
        if not (prep is not None and prep.size == size and len(prep.faces) == len(faces)
                and all(a is b for a, b in zip(prep.faces, faces))):  # fmt: skip
            prep = cache["tessellate"] = cls(faces, size)
        return prep


def tessellate_faces(faces, tol: float, angle_tol, size: float) -> Tessellation:
    """Tessellate :class:`~splinekit.brep.TrimmedFace` objects as one watertight mesh (see
    :func:`splinekit.tessellation.tessellate`). ``tol``: absolute chordal tolerance;
    ``angle_tol``: radians or None; ``size``: model size (bounding-box diagonal)."""
    prep = _Prepared.of(faces, size)
    if prep.natural is not None:  # faces bounded by their natural domain (a whole sphere, torus): .natural
        k, surfaces, flip = prep.natural
        mesh = tessellate_natural(surfaces, flip, tol, angle_tol, size)
        if prep.rest is None:
            return mesh
        return concatenate([(mesh, k), (_tessellate_trimmed(prep.rest, tol, angle_tol), prep.rest.index)], tol)
    plan = prep.memo.get("fast", False)  # False: not decided yet for this face set
    if plan is False:
        plan = build_plan(prep)
        if plan is None or not plan.checked:
            # loops the plan's own checks do not accept (.plan_checks) go through the general
            # path first, which raises on bad loops (or repairs a sloppy file's crossings), so
            # both paths refuse the same input; the fast mesh is still the result where there is one
            mesh = _tessellate_trimmed(prep, tol, angle_tol)
            prep.memo["fast"] = plan
            fast = fast_tessellation(plan, tol, angle_tol) if plan is not None else None
            return mesh if fast is None else fast
        prep.memo["fast"] = plan
    if plan:
        mesh = fast_tessellation(plan, tol, angle_tol)
        if mesh is not None:
            return mesh
    return _tessellate_trimmed(prep, tol, angle_tol)


def _tessellate_trimmed(prep, tol: float, angle_tol) -> Tessellation:
    """The general path (the module docstring's steps 1-6) on the prepared face set ``prep``."""
    triangle = _triangulator()
    faces, size = prep.faces, prep.size
    batch, uses, groups, edge_tol = prep.batch, prep.uses, prep.groups, prep.edge_tol
    grids = face_grids(batch, tol, angle_tol, prep.bounds, prep.memo)
    # the compiled kernels (scattered surface evaluation, welds) serve once loaded; a grid point
    # costs the numpy path several evaluations and its share of the triangulation
    work = 4.0 * sum(g.us.size * g.vs.size for g in grids)
    for module in ("splinekit.tessellation._kernels", "splinekit.tessellation._batch_kernels"):
        _kernels.load(module, work=work, min_work=0)
    scales = np.stack([g.scale for g in grids])
    samples = sample_groups(uses, groups, scales, tol, angle_tol, batch, prep.pcurves, prep.memo, prep.affine)
    vid_of_group, edge_xyz = _edge_vertices(samples, size, edge_tol, prep.memo)
    pface, puv, pxyz, pvid, owner, sizes = gather_loops(prep.table, samples, vid_of_group, scales)
    layout = Layout(puv, sizes, prep.table, scales)
    # boundary segments (each loop closed on itself)
    seg_loop = np.repeat(prep.table.loop_index, sizes)
    nb = len(pface)
    after = np.arange(1, nb + 1)
    ends = np.cumsum(sizes)
    after[ends - 1] = ends - sizes  # the last point of a loop is followed by its first
    segs = np.column_stack([np.arange(nb), after])
    # with every edge a straight segment on planar faces the loops are the same at every
    # tolerance: their crossing test (and any untangling) is done once per face set
    fixed = bool(prep.memo["straight"][0].all())
    if not (fixed and "untangled" in prep.memo):
        puv = _without_crossings(faces, prep.index, uses, batch, layout, pface, puv, pxyz, segs, owner)
        if fixed:
            prep.memo["untangled"] = puv
    puv = prep.memo["untangled"] if fixed else puv
    gf, guv = _grid_points(grids, layout, layout.place(pface, puv), segs)
    n_vid = len(edge_xyz)
    # the point after each boundary point in its loop (-1: not a boundary point), grown with the points
    nxt_b = np.full(nb, -1, dtype=np.int64)
    nxt_b[segs[:, 0]] = segs[:, 1]
    pface = np.concatenate([pface, gf])
    puv = np.concatenate([puv, guv])
    pxyz = np.concatenate([pxyz, batch.evaluate(gf, guv[:, 0], guv[:, 1])])
    pvid = np.concatenate([pvid, np.arange(n_vid, n_vid + len(gf))])
    n_vid += len(gf)

    # How far each boundary point lies off its face (edges of a sloppy file are off by up to their
    # own tolerance, 1e-2 in some CAD exports): the flat mesh cannot come closer to the surface than
    # its corners, so a sample may deviate by the tolerance plus its corners' offset. Measuring
    # against the bare tolerance there refined every round without end (millions of triangles).
    # (kept as vectors: on an affine face the surface at a mean of (u, v) is the mean of the
    # surface points, so there the deviation is the mean of the corners' offsets, with no evaluation)
    offv = np.zeros((len(pface), 3))
    offv[:nb] = pxyz[:nb] - batch.evaluate(pface[:nb], puv[:nb, 0], puv[:nb, 1])
    poff = np.linalg.norm(offv, axis=1)
    max_dev = 0.0
    for round_ in range(MAX_ROUNDS):
        nP = len(pface)
        limits.check(2 * nP * BYTES_PER_TRIANGLE, f"tessellation of trimmed faces at tolerance {tol:.3g} ({2 * nP:,} triangles)")
        P = layout.place(pface, puv)
        nxt = np.concatenate([nxt_b, np.full(nP - nb, -1, dtype=np.int64)])
        r = triangle.triangulate({"vertices": P, "segments": segs}, "pnQ")
        if len(r["vertices"]) != nP:  # Triangle split crossing segments at new points
            x = r["vertices"][nP, 0]
            f = int(np.searchsorted(layout.x0, x, side="right") - 1)
            raise ParameterError(f"{_face_name(faces[f], prep.index[f])}: its trimming loops cross or touch each other (or themselves)")
        T = np.asarray(r["triangles"], dtype=np.int64)
        N = np.asarray(r["neighbors"], dtype=np.int64)
        keep, conflict, along = _keep_inside(T, N, nxt)
        if conflict >= 0:
            f = int(pface[T[conflict, 0]])
            raise ParameterError(f"{_face_name(faces[f], prep.index[f])}: its trimming loops cross, overlap or nest wrongly (a hole outside the outer loop?)")
        ha, hb = _half_edges(T)
        if round_ == 0:  # every trim must bound some material on its left
            covered = np.zeros(nb, dtype=bool)
            on = keep[:, None] & (nxt[ha] == hb)
            covered[ha[on]] = True
            if not covered.all():
                k = int(np.flatnonzero(~covered)[0])
                f, l = int(pface[k]), int(seg_loop[k])
                raise ParameterError(f"{_face_name(faces[f], prep.index[f])}: loop {l} bounds no material: it lies outside the outer loop "
                                     "or inside another hole, or the loops cross")
        V = pvid[T]
        live = keep & (V[:, 0] != V[:, 1]) & (V[:, 1] != V[:, 2]) & (V[:, 2] != V[:, 0])  # not collapsed at a pole
        # measure: triangle centres and edge midpoints, each edge once (from its lower live triangle)
        n_side = np.where(N >= 0, N, 0)
        other_live = (N >= 0) & live[n_side]
        own = live[:, None] & (~other_live | (np.arange(len(T))[:, None] < N))
        et, ek = np.nonzero(own)
        ea, eb = ha[et, ek], hb[et, ek]
        tl = np.flatnonzero(live)
        Tl = T[tl]
        fid = np.concatenate([pface[ea], pface[Tl[:, 0]]])
        uv = np.concatenate([0.5 * (puv[ea] + puv[eb]), puv[Tl].mean(axis=1)])
        flat = np.concatenate([0.5 * (pxyz[ea] + pxyz[eb]), pxyz[Tl].mean(axis=1)])
        exact = flat - np.concatenate([0.5 * (offv[ea] + offv[eb]), offv[Tl].mean(axis=1)])
        curved = np.flatnonzero(~prep.affine[fid])
        if curved.size:
            exact[curved] = batch.evaluate(fid[curved], uv[curved, 0], uv[curved, 1])
        dev = np.linalg.norm(exact - flat, axis=1)
        max_dev = float(dev.max()) if dev.size else 0.0
        ne = len(ea)
        bad_edge = (dev[:ne] > tol + np.maximum(poff[ea], poff[eb])) & ~along[et, ek]
        # a triangle's centre is added only when none of its edges is split
        split = np.zeros(len(T), dtype=bool)
        split[et[bad_edge]] = True
        nb_t = N[et[bad_edge], ek[bad_edge]]
        split[nb_t[nb_t >= 0]] = True
        bad_tri = (dev[ne:] > tol + poff[Tl].max(axis=1)) & ~split[tl]
        new = np.concatenate([np.flatnonzero(bad_edge), ne + np.flatnonzero(bad_tri)])
        if new.size == 0 or round_ == MAX_ROUNDS - 1:
            break
        pface = np.concatenate([pface, fid[new]])
        puv = np.concatenate([puv, uv[new]])
        pxyz = np.concatenate([pxyz, exact[new]])
        pvid = np.concatenate([pvid, np.arange(n_vid, n_vid + new.size)])
        poff = np.concatenate([poff, np.zeros(new.size)])
        offv = np.concatenate([offv, np.zeros((new.size, 3))])
        n_vid += new.size
    return _assemble(prep, T[live], pface, puv, pxyz, pvid, n_vid, max_dev, tol)


def _assemble(prep, T, pface, puv, pxyz, pvid, n_vid, max_dev, tol):
    """The :class:`Tessellation` of the final triangles ``T`` (point indices) of the face set
    ``prep``."""
    flip = prep.reversed[pface[T[:, 0]]]
    T = np.where(flip[:, None], T[:, [0, 2, 1]], T)
    used = np.zeros(n_vid, dtype=bool)
    used[pvid[T]] = True
    new_id = np.cumsum(used) - 1
    tri = new_id[pvid[T]]
    # one representative point per vertex (its face, (u, v) and position)
    rep = np.full(n_vid, -1, dtype=np.int64)
    rep[pvid[::-1]] = np.arange(len(pvid))[::-1]
    rep = rep[used]
    V = pxyz[rep]
    UV = puv[rep]
    VP = pface[rep]
    Su, Sv = prep.partials[0][VP], prep.partials[1][VP]
    curved = np.flatnonzero(~prep.affine[VP])
    if curved.size:
        _, Su[curved], Sv[curved] = prep.batch.partials(VP[curved], UV[curved, 0], UV[curved, 1])
    N = np.cross(Su, Sv)
    length = np.linalg.norm(N, axis=1)
    scale = np.einsum("ij,ij->i", Su, Su) + np.einsum("ij,ij->i", Sv, Sv)
    weak = length <= 1e-10 * scale
    N /= np.where(weak, 1.0, length)[:, None]
    N[prep.reversed[VP]] *= -1.0
    if weak.any():  # collapsed points (poles): the mean of the adjacent triangles' normals
        X = V[tri]
        fn = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        acc = np.stack([sum(np.bincount(tri[:, k], fn[:, j], len(V)) for k in range(3)) for j in range(3)], axis=1)
        length = np.linalg.norm(acc, axis=1, keepdims=True)
        N[weak] = (acc / np.where(length > 0, length, 1.0))[weak]
    return Tessellation._build(V, tri, N, UV, VP, pface[T[:, 0]], puv[T], max_dev, tol)
