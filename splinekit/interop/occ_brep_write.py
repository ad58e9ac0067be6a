"""splinekit B-rep -> OpenCascade topology: a :class:`~splinekit.brep.TrimmedFace`,
:class:`~splinekit.brep.Shell` or :class:`~splinekit.brep.Solid` built as the exact TopoDS face,
shell or solid.

Faces are built with ``BRep_Builder`` from their surfaces and pcurves; each edge is built ONCE per
key (both faces' pcurves on one ``TopoDS_Edge``; a seam gets its two pcurves on one face), vertices
are shared through the loops' adjacency, 3-D curves are built where missing
(``BRepLib.BuildCurve3d``), and edges without keys are paired geometrically first. Sewing
(``BRepBuilderAPI_Sewing``) is not used: it may merge or split edges, and the direct build keeps
the counts exactly.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ..brep import Shell, Solid, TrimmedFace
from ..brep.topology import pair_by_samples
from ..curves.batch import CurveBatch
from ..errors import BackendError, ParameterError
from ..tolerances import OCC_CONFUSION
from .occ_backend import _ocp
from .occ_geometry import _curve2d_to_occ, _same_domain, geom_to_occ
from .occ_shapes import _compound

__all__ = ["brep_to_shape", "brep_list_to_shape"]


_FRACTIONS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])


def _use_points(face, use) -> np.ndarray:
    """``(5, 3)`` points of an edge use at parameter fractions 0, 0.25, 0.5, 0.75, 1 (3-D curve if
    there is one, else the surface at the pcurve)."""
    a, b = use.domain
    t = a + (b - a) * _FRACTIONS
    if use.curve is not None:
        return use.curve.evaluate(t)
    return _on_surface(face, use.pcurve.evaluate(t))


def _end_tangents(uses) -> list:
    """For each Edge of ``uses``: the ``(2, 3)`` unit tangents of its 3-D curve at its start and
    end, or None (no 3-D curve, degenerate, or a zero derivative at an end). The curves are
    differentiated as one :class:`~splinekit.curves.batch.CurveBatch`."""
    out = [None] * len(uses)
    idx = [k for k, e in enumerate(uses) if e.curve is not None and not e.degenerate]
    if not idx:
        return out
    t = np.array([uses[k].domain for k in idx], dtype=np.float64).ravel()
    rows = np.repeat(np.arange(len(idx)), 2)
    d = CurveBatch([uses[k].curve for k in idx]).derivatives(rows, t, 1)[1].reshape(len(idx), 2, -1)
    n = np.linalg.norm(d, axis=2, keepdims=True)
    for k, dk, nk in zip(idx, d, n):
        if np.all(nk > 0.0):
            out[k] = dk / nk
    return out


_RCOND = 1e-2
"""Singular values of a vertex's tangent rows below this fraction of the largest are dropped: along
such a direction the curves barely tell where the vertex lies, and following them would move it far."""


def _vertex_points(centers, owner, P, T):
    """Vertex positions, ``(n, 3)``: each of the ``(n, 3)`` ``centers`` moved the least (least
    squares) so that it lies in the normal plane of every incident 3-D curve end, i.e. projects
    onto that end; then, where those planes do not meet in one point, moved the least onto the
    outer side of all of them (:func:`_past_ends`). ``owner`` ``(m,)`` names the vertex of each
    curve end, ``P`` ``(m, 3)`` its point and ``T`` ``(m, 3)`` its unit tangent pointing out of
    the curve.

    A STEP file carries no edge ranges: OCC's reader sets an edge's range by projecting its vertices
    onto its 3-D curve, and its pcurves' ranges by projecting the curve's ends onto their traces.
    On a loose edge (curve ends a tolerance apart, as read from another CAD system) a vertex at the
    ends' centroid projects inside a curve, so every re-read shortens that edge a little and moves
    its faces' areas; a vertex in every end's normal plane keeps the ranges, and so does one past
    every end (the projection then stops at the end)."""
    M = np.zeros((len(centers), 3, 3))
    r = np.zeros((len(centers), 3))
    np.add.at(M, owner, T[:, :, None] * T[:, None, :])  # normal equations of each vertex's rows
    np.add.at(r, owner, T * np.einsum("ij,ij->i", T, P - centers[owner])[:, None])
    # M's eigenvalues are the squared singular values of the rows
    V = centers + np.einsum("nij,nj->ni", np.linalg.pinv(M, rcond=_RCOND**2, hermitian=True), r)
    return _past_ends(V, owner, P, T)


def _past_ends(V, owner, P, T):
    """``V`` with each vertex that lies inside one of its curve ends (``(V - P) . T < 0``, ``T``
    pointing out of the curve) moved the least onto the outer side of all of them, where such a
    point exists. Four or more curves at a vertex (a ventilator blade's tip in CATIA's file) have
    normal planes that meet nowhere: the least-squares point lies up to 1e-5 mm inside some of
    them, and the reader cut those edges; only the outer sides are needed."""
    inside = np.einsum("ij,ij->i", V[owner] - P, T)
    scale = np.abs(P).max(initial=1.0)
    for n in np.unique(owner[inside < -1e-12 * scale]):
        rows = owner == n
        need = -inside[rows]  # T @ step >= need: how far the vertex must go past each end
        unit = float(need.max())  # the step in units of the worst violation
        # the two uses of an edge give one row twice: once is enough for the enumeration below
        rows_ = np.unique(np.round(np.column_stack([T[rows], need / unit]), 12), axis=0)
        step = _least_step(rows_[:, :3], rows_[:, 3])
        if step is not None:
            V[n] = V[n] + unit * step
    return V


def _least_step(A, c):
    """The shortest ``z`` with ``A @ z >= c`` (``A`` ``(k, 3)``), or None if there is none: the
    nearest point of a polyhedron, found among the points where one, two or three of its planes
    are active (k is a vertex's few curve ends; opposite rows, two edges that continue each other,
    make the active set degenerate, which this enumeration does not mind)."""
    best = None
    for size in (1, 2, 3):
        for S in combinations(range(len(A)), size):
            S = list(S)
            z = np.linalg.lstsq(A[S], c[S], rcond=None)[0]  # the least-norm point on those planes
            if np.abs(A[S] @ z - c[S]).max() > 1e-9 or np.any(A @ z < c - 1e-9):
                continue
            if best is None or z @ z < best @ best:
                best = z
    return best


def _all_use_points(faces, uses) -> list:
    """:func:`_use_points` of every ``(face index, Edge)`` in ``uses``: the 3-D curves evaluated
    as one :class:`~splinekit.curves.batch.CurveBatch`, the uses without one face by face."""
    with_curve = [k for k, (_, e) in enumerate(uses) if e.curve is not None]
    out = [None] * len(uses)
    if with_curve:
        curves = [uses[k][1].curve for k in with_curve]
        ends = np.array([uses[k][1].domain for k in with_curve], dtype=np.float64)  # the pcurve's, as one use
        t = (ends[:, :1] + (ends[:, 1:] - ends[:, :1]) * _FRACTIONS[None]).ravel()
        rows = np.repeat(np.arange(len(curves)), _FRACTIONS.size)
        points = CurveBatch(curves).evaluate(rows, t).reshape(len(curves), _FRACTIONS.size, -1)
        for k, P in zip(with_curve, points):
            out[k] = P
    for k, (i, e) in enumerate(uses):
        if out[k] is None:
            out[k] = _use_points(faces[i], e)
    return out


class _UnionFind:
    def __init__(self):
        self.parent: dict = {}

    def find(self, x):
        parent = self.parent
        parent.setdefault(x, x)
        root = x
        while parent[root] != root:
            root = parent[root]
        while parent[x] != root:
            parent[x], x = root, parent[x]
        return root

    def union(self, a, b):
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[rb] = ra


def _pair_keyless(faces, uses) -> None:
    """Give keys to the uses that have none: keyless uses whose 3-D points (ends and quarter
    points, either direction) agree within ten times their tolerance (plus a rounding of 1e-9 of
    their size) become one edge (:func:`splinekit.brep.topology.pair_by_samples`); the others,
    and degenerate ones, are edges of their own. ``uses`` rows are
    ``[face index, loop, position, Edge, key, points]``."""
    loose = [r for r in uses if r[4] is None]
    for r in loose:
        r[4] = ("free", r[0], r[1], r[2])
    solid = [r for r in loose if not r[3].degenerate]
    if len(solid) < 2:
        return
    P = np.array([r[5] for r in solid])
    sizes = np.maximum(np.linalg.norm(P[:, -1] - P[:, 0], axis=1), np.linalg.norm(P[:, 2] - P[:, 0], axis=1))
    tol = 10.0 * np.array([r[3].tolerance for r in solid]) + 1e-9 * sizes
    first: dict = {}  # label -> the key of its first use
    for r, label in zip(solid, pair_by_samples(P, tol).tolist()):
        r[4] = first.setdefault(label, r[4])


def _same_direction(ref_points, points) -> bool:
    """Whether a use runs the same way as the edge's reference use (compares quarter points,
    which also tells the two directions of a closed edge apart)."""
    same = np.linalg.norm(points[[0, 1, 3]] - ref_points[[0, 1, 3]], axis=1).sum()
    other = np.linalg.norm(points[[0, 1, 3]] - ref_points[[4, 3, 1]], axis=1).sum()
    return bool(same <= other)


def _in_ref_parameter(use, same: bool, ref_domain):
    """The use's pcurve (and 3-D curve) run in the reference direction on the reference domain,
    and whether that took a reparametrization (then SameParameter must be recomputed)."""
    e = use if same else use.reversed()
    pc, cv = e.pcurve, e.curve
    if _same_domain(pc.domain, ref_domain):
        return pc, cv, False
    pc = pc.reparametrize(*ref_domain)
    cv = None if cv is None else cv.reparametrize(*ref_domain)
    return pc, cv, True


_MARGIN = 1.1
"""A measured deviation becomes a tolerance times this (the check samples OCC takes lie between ours)."""


def _spread(uses, curve, domain) -> float:
    """Largest distance, at the same parameter, between the surface-at-pcurve images of ``uses``
    (``(face, pcurve)`` pairs on ``domain``, in one direction) and ``curve`` (3-D, or None: then
    between the images themselves, pairwise), on 17 samples per Bézier span of any of them."""
    a, b = domain
    br = np.unique(np.concatenate([pc.bezier_breakpoints() for _, pc in uses]
                                  + ([curve.bezier_breakpoints()] if curve is not None else [])))
    br = np.union1d(br[(br > a) & (br < b)], [a, b])
    t = (br[:-1, None] + (br[1:] - br[:-1])[:, None] * np.linspace(0.0, 1.0, 17)[None]).ravel()
    images = [_on_surface(face, pc.evaluate(t)) for face, pc in uses]
    if curve is not None:
        ref = curve.evaluate(t)
        return max(float(np.linalg.norm(P - ref, axis=1).max()) for P in images)
    return max((float(np.linalg.norm(P - Q, axis=1).max()) for k, P in enumerate(images) for Q in images[k + 1:]),
               default=0.0)


def _on_surface(face, uv) -> np.ndarray:
    """``face.surface`` at the ``(n, 2)`` parameters ``uv`` (a file's pcurves may overshoot the
    domain by a rounding: clamped)."""
    (u0, u1), (v0, v1) = face.surface.domain
    return face.surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1))


def _faces_of(obj):
    if isinstance(obj, TrimmedFace):
        return [obj]
    if isinstance(obj, Shell):
        return list(obj.faces)
    if isinstance(obj, Solid):
        return list(obj.faces)
    raise ParameterError(f"expected a TrimmedFace, Shell or Solid, got {type(obj).__name__}")


def brep_to_shape(obj, *, tolerance: float = OCC_CONFUSION):
    """An OCC ``TopoDS_Face`` / ``TopoDS_Shell`` / ``TopoDS_Solid`` for a splinekit TrimmedFace,
    Shell or Solid, with every edge shared by its faces built once. No validity check here:
    callers that need one use ``occ._check_valid``."""
    BRep, BRepLib, TopAbs, TopoDS, gp = _ocp("BRep", "BRepLib", "TopAbs", "TopoDS", "gp")
    builder = BRep.BRep_Builder()
    FORWARD, REVERSED = TopAbs.TopAbs_Orientation.TopAbs_FORWARD, TopAbs.TopAbs_Orientation.TopAbs_REVERSED
    faces = _faces_of(obj)

    # every edge use: [face, loop, position, Edge, key, (5, 3) points]
    uses = [[i, j, k, e, e.key] for i, f in enumerate(faces) for j, loop in enumerate(f.boundary_loops())
            for k, e in enumerate(loop)]
    for r, P in zip(uses, _all_use_points(faces, [(r[0], r[3]) for r in uses])):
        r.append(P)
    _pair_keyless(faces, uses)

    # group uses by key; the first use fixes the edge's direction and parameter
    groups: dict = {}
    for r in uses:
        groups.setdefault(r[4], []).append(r)
    same = {}
    for key, rows in groups.items():
        ref = rows[0][5]
        for r in rows:
            same[id(r)] = True if r is rows[0] else _same_direction(ref, r[5])

    # vertices: the end of one use and the start of the next in a loop are one vertex
    def end_node(r, at_end: bool):
        forward = same[id(r)]
        return (r[4], 1 if at_end == forward else 0)

    uf = _UnionFind()
    by_loop: dict = {}
    for r in uses:
        by_loop.setdefault((r[0], r[1]), []).append(r)
    for loop in by_loop.values():
        for a, b in zip(loop, loop[1:] + loop[:1]):
            uf.union(end_node(a, True), end_node(b, False))
    for r in uses:
        if r[3].degenerate:
            uf.union((r[4], 0), (r[4], 1))
    points: dict = {}
    for r in uses:
        forward = same[id(r)]
        for node, p in (((r[4], 0 if forward else 1), r[5][0]), ((r[4], 1 if forward else 0), r[5][-1])):
            points.setdefault(uf.find(node), []).append((p, r[3].tolerance))
    # loops that touch only at a point (no edge between them) share that vertex too: merge the classes
    # whose points coincide within both classes' tolerances
    roots = list(points)
    if len(roots) > 1:
        from scipy.spatial import cKDTree

        centers = np.array([np.mean([p for p, _ in points[r]], axis=0) for r in roots])
        tols = np.array([max(t for _, t in points[r]) for r in roots])
        for a, b in cKDTree(centers).query_pairs(float(tols.max())):
            if np.linalg.norm(centers[a] - centers[b]) <= min(tols[a], tols[b]):
                uf.union(roots[a], roots[b])
        merged: dict = {}
        for r, items in points.items():
            merged.setdefault(uf.find(r), []).extend(items)
        points = merged
    vertices = {}
    roots = list(points)
    centers = np.array([np.mean([p for p, _ in points[root]], axis=0) for root in roots])
    # each 3-D curve end at its vertex: the vertex goes where the STEP reader keeps the edges' ranges
    index = {root: i for i, root in enumerate(roots)}
    owner, end_points, end_tangents = [], [], []
    for r, tangents in zip(uses, _end_tangents([r[3] for r in uses])):
        if tangents is None:
            continue
        forward = same[id(r)]
        owner += [index[uf.find((r[4], 0 if forward else 1))], index[uf.find((r[4], 1 if forward else 0))]]
        end_points += [r[5][0], r[5][-1]]
        end_tangents += [-tangents[0], tangents[1]]  # out of the curve
    moved = centers if not owner else _vertex_points(centers, np.array(owner), np.array(end_points),
                                                     np.array(end_tangents))
    for root, c, m in zip(roots, centers, moved):
        items = points[root]
        P = np.array([p for p, _ in items])
        own = max(t for _, t in items)
        if np.linalg.norm(m - c) <= own:  # never further than the vertex's own tolerance
            c = m
        tol = max(own, float(np.max(np.linalg.norm(P - c, axis=1))) * 1.001)
        v = TopoDS.TopoDS_Vertex()
        builder.MakeVertex(v, gp.gp_Pnt(*c.tolist()), max(tol, tolerance))
        vertices[root] = v

    # faces (unoriented, FORWARD) first: the pcurves are attached to them
    occ_faces = []
    for f in faces:
        F = TopoDS.TopoDS_Face()
        builder.MakeFace(F, geom_to_occ(f.surface), max(f.tolerance, tolerance))
        occ_faces.append(F)

    # edges, one per key
    occ_edges = {}
    redo_same_parameter, no_curve = [], []
    for key, rows in groups.items():
        ref = rows[0][3]
        dom = ref.domain
        E = TopoDS.TopoDS_Edge()
        tol_e = max(max(r[3].tolerance for r in rows), tolerance)
        curve3d, reparam = None, False
        per_face: dict = {}
        for r in rows:
            pc, cv, moved = _in_ref_parameter(r[3], same[id(r)], dom)
            reparam |= moved
            if curve3d is None and cv is not None:
                curve3d = cv
            per_face.setdefault(r[0], []).append((pc, same[id(r)]))
        degenerate = any(r[3].degenerate for r in rows)
        if not degenerate and any(r[3].curve is None for r in rows):
            # a use without a 3-D curve follows the edge only through its own surface and pcurve:
            # the tolerance must cover how far the uses lie from each other (or from the 3-D curve)
            # at the same parameter, or OCC finds a pcurve off the curve it builds from another.
            # Only as far as the uses' own tolerances allow (each within its tolerance of the edge):
            # trims further apart are a bad solid, which OCC is left to refuse
            spread = _spread([(faces[i], pc) for i, pcs in per_face.items() for pc, _ in pcs], curve3d, dom)
            if spread <= 2.0 * tol_e:
                tol_e = max(tol_e, _MARGIN * spread)
        if curve3d is not None and not degenerate:
            builder.MakeEdge(E, geom_to_occ(curve3d), tol_e)
        else:
            builder.MakeEdge(E)
            builder.UpdateEdge(E, tol_e)
        for i, pcs in per_face.items():
            if len(pcs) == 2 and pcs[0][1] != pcs[1][1]:  # a seam: the FORWARD use's pcurve first
                first, second = (pcs[0][0], pcs[1][0]) if pcs[0][1] else (pcs[1][0], pcs[0][0])
                builder.UpdateEdge(E, _curve2d_to_occ(first), _curve2d_to_occ(second), occ_faces[i], tol_e)
            else:
                builder.UpdateEdge(E, _curve2d_to_occ(pcs[0][0]), occ_faces[i], tol_e)
        builder.Range(E, dom[0], dom[1])
        builder.Add(E, vertices[uf.find((key, 0))].Oriented(FORWARD))
        builder.Add(E, vertices[uf.find((key, 1))].Oriented(REVERSED))
        if degenerate:
            builder.Degenerated(E, True)
        elif curve3d is None:
            no_curve.append(E)
        if reparam:
            builder.SameParameter(E, False)
            redo_same_parameter.append(E)
        occ_edges[key] = E

    # wires and oriented faces
    oriented = []
    for i, f in enumerate(faces):
        F = occ_faces[i]
        for j in range(len(f.boundary_loops())):
            W = TopoDS.TopoDS_Wire()
            builder.MakeWire(W)
            for r in by_loop[(i, j)]:
                builder.Add(W, occ_edges[r[4]].Oriented(FORWARD if same[id(r)] else REVERSED))
            W.Closed(True)
            builder.Add(F, W)
        oriented.append(F.Oriented(REVERSED) if f.reversed else F)
    for E in no_curve:
        if not BRepLib.BRepLib.BuildCurve3d_s(E, max(tolerance, 1e-7)):
            raise BackendError("OpenCascade could not build the 3-D curve of an edge from its pcurve")
    for E in redo_same_parameter:
        BRepLib.BRepLib.SameParameter_s(E, max(tolerance, 1e-7))

    def make_shell(face_list):
        S = TopoDS.TopoDS_Shell()
        builder.MakeShell(S)
        for F in face_list:
            builder.Add(S, F)
        S.Closed(BRep.BRep_Tool.IsClosed_s(S))
        return S

    if isinstance(obj, TrimmedFace):
        result = oriented[0]
    elif isinstance(obj, Shell):
        result = make_shell(oriented)
    else:
        solid = TopoDS.TopoDS_Solid()
        builder.MakeSolid(solid)
        start = 0
        for shell in obj.shells:
            builder.Add(solid, make_shell(oriented[start:start + len(shell.faces)]))
            start += len(shell.faces)
        result = solid
    BRepLib.BRepLib.UpdateTolerances_s(result, False)
    return result


def brep_list_to_shape(objects, *, tolerance: float = OCC_CONFUSION):
    """A compound of :func:`brep_to_shape` of each object."""
    return _compound([brep_to_shape(o, tolerance=tolerance) for o in objects])
