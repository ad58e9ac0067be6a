"""Which faces of an OCC shape the B-rep reader converts natively (exactly, without
``BRepBuilderAPI_NurbsConvert``), and the conversion of their surfaces and edge uses.

A face converts natively when its surface is a plane, B-spline, Bézier, cylinder, cone, sphere or
torus and every edge use on it maps exactly (:func:`face_plan`):

- on a plane, B-spline or Bézier face: pcurves that are lines or B-splines on 3-D lines or
  B-splines (OCC's parameter kept); on a plane also circles and ellipses on 3-D circles and ellipses;
- on an elementary surface: pcurves that are lines along one parameter (isolines), on a 3-D
  circle when the parameter is an angle, on a 3-D line or B-spline otherwise; degenerate edges.

Circular edges (3-D circles and ellipses) get a new parameter (:mod:`.occ_analytic`), which every
face using them must share: a face that does not convert natively passes that on to its
neighbours across circular edges (:func:`native_faces`). The others are left to OCC's conversion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..curves import BSplineCurve
from .occ_analytic import AngleMap, circle_meridian, edge_arc, line_meridian, mapped_isoline, plane_patch, revolved_surface
from .occ_backend import _ocp, require_ocp
from .occ_geometry import _curve2d_from_occ, _curve3d_from_occ, _same_domain

__all__ = ["FacePlan", "face_plan", "native_faces", "native_use", "native_surface", "circular_curve"]

_AXIS = 1e-12
"""A pcurve line whose direction has a component below this is an isoline."""


def _xyz(v):
    return np.array([v.X(), v.Y(), v.Z()])


def _xy(v):
    return np.array([v.X(), v.Y()])


def _basis(curve, trimmed_type):
    return curve.BasisCurve() if isinstance(curve, trimmed_type) else curve


def circular_curve(edge):
    """The edge's 3-D ``Geom_Circle`` / ``Geom_Ellipse`` (located), or None."""
    Geom, _, _, _ = require_ocp()
    (BRep,) = _ocp("BRep")
    if BRep.BRep_Tool.Degenerated_s(edge):
        return None
    c = BRep.BRep_Tool.Curve_s(edge, 0.0, 0.0)
    c = None if c is None else _basis(c, Geom.Geom_TrimmedCurve)
    return c if isinstance(c, (Geom.Geom_Circle, Geom.Geom_Ellipse)) else None


def _conic_axes(conic, dim: int):
    """``(center, x axis * radius, y axis * radius)`` of an OCC circle or ellipse (2-D or 3-D)."""
    pos = conic.Position()
    get = _xyz if dim == 3 else _xy
    if hasattr(conic, "MajorRadius"):
        rx, ry = conic.MajorRadius(), conic.MinorRadius()
    else:
        rx = ry = conic.Radius()
    return get(pos.Location()), rx * get(pos.XDirection()), ry * get(pos.YDirection())


@dataclass
class FacePlan:
    """How one face converts: ``kind`` ("plane", "spline" or an elementary surface's name), the
    located OCC surface, and for elementary surfaces the angle maps of u and v (None: linear)."""

    kind: str
    surface: object
    u_map: AngleMap | None = None
    v_map: AngleMap | None = None
    v_range: tuple | None = None  # OCC's v range of an elementary face

    def map_uv(self, uv):
        """OCC's ``(u, v)`` (``(n, 2)``) in the converted surface's parameters."""
        uv = np.array(uv, dtype=np.float64, copy=True)
        for k, m in enumerate((self.u_map, self.v_map)):
            if m is not None:
                uv[:, k] = m(uv[:, k])
        return uv


def _line2d(pc):
    """``(location (2,), direction (2,))`` of a 2-D line pcurve, or None."""
    (Geom2d,) = _ocp("Geom2d")
    pc = _basis(pc, Geom2d.Geom2d_TrimmedCurve)
    if not isinstance(pc, Geom2d.Geom2d_Line):
        return None
    ax = pc.Position()
    return _xy(ax.Location()), _xy(ax.Direction())


def _elementary(surf):
    """``(kind, angle coordinates)`` of an elementary surface, or None."""
    Geom, _, _, _ = require_ocp()
    for cls, kind, angles in ((Geom.Geom_CylindricalSurface, "cylinder", (0,)), (Geom.Geom_ConicalSurface, "cone", (0,)),
                              (Geom.Geom_SphericalSurface, "sphere", (0, 1)), (Geom.Geom_ToroidalSurface, "torus", (0, 1))):
        if isinstance(surf, cls):
            return kind, angles
    return None


def face_plan(face) -> FacePlan | None:
    """The plan for converting ``face`` (FORWARD) natively, or None when it cannot be."""
    Geom, _, _, _ = require_ocp()
    BRep, Geom2d, TopAbs, TopExp, TopoDS = _ocp("BRep", "Geom2d", "TopAbs", "TopExp", "TopoDS")
    tool = BRep.BRep_Tool
    surf = tool.Surface_s(face)
    if isinstance(surf, Geom.Geom_RectangularTrimmedSurface):
        surf = surf.BasisSurface()
    elementary = _elementary(surf)
    if isinstance(surf, Geom.Geom_Plane):
        kind = "plane"
    elif isinstance(surf, (Geom.Geom_BSplineSurface, Geom.Geom_BezierSurface)):
        kind = "spline"
    elif elementary is not None:
        kind = elementary[0]
    else:
        return None
    plain3d = (Geom.Geom_Line, Geom.Geom_BSplineCurve, Geom.Geom_BezierCurve)
    plain2d = (Geom2d.Geom2d_Line, Geom2d.Geom2d_BSplineCurve, Geom2d.Geom2d_BezierCurve)
    ends = []  # OCC (u, v) of pcurve ends, for the box of an elementary face
    explorer = TopExp.TopExp_Explorer(face, TopAbs.TopAbs_ShapeEnum.TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.TopoDS.Edge_s(explorer.Current())
        explorer.Next()
        pc = tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pc is None:
            return None
        first, last = tool.Range_s(edge, face)
        degenerate = bool(tool.Degenerated_s(edge))
        c3 = None if degenerate else tool.Curve_s(edge, 0.0, 0.0)
        if not degenerate:
            if c3 is None or not _same_domain(tool.Range_s(edge), (first, last)):
                return None
            c3 = _basis(c3, Geom.Geom_TrimmedCurve)
        circular = isinstance(c3, (Geom.Geom_Circle, Geom.Geom_Ellipse))
        pc = _basis(pc, Geom2d.Geom2d_TrimmedCurve)
        if kind in ("plane", "spline"):
            if isinstance(pc, plain2d) and (degenerate or isinstance(c3, plain3d)):
                continue
            if kind == "plane" and circular and isinstance(pc, (Geom2d.Geom2d_Circle, Geom2d.Geom2d_Ellipse)) and (
                    isinstance(pc, Geom2d.Geom2d_Circle) == isinstance(c3, Geom.Geom_Circle)):
                continue
            return None
        line = _line2d(pc)
        if line is None:
            return None
        loc, d = line
        along = np.flatnonzero(np.abs(d) > _AXIS)
        if len(along) != 1:
            return None  # a helix or any slanted line: not an isoline
        k = int(along[0])
        if k in elementary[1]:
            if not (degenerate or circular):
                return None
        elif not (degenerate or isinstance(c3, plain3d)):
            return None
        ends.extend([loc + first * d, loc + last * d])
    if kind in ("plane", "spline"):
        return FacePlan(kind, surf)
    if not ends:
        return None
    P = np.array(ends)
    (u0, v0), (u1, v1) = P.min(axis=0), P.max(axis=0)
    u1 = min(u1, u0 + 2.0 * math.pi)  # rounding past one turn
    v_map = None
    if elementary[0] == "sphere":
        v0, v1 = max(v0, -0.5 * math.pi), min(v1, 0.5 * math.pi)  # STEP-rounded bounds past the poles
    if 1 in elementary[1]:
        v1 = min(v1, v0 + 2.0 * math.pi)
        v_map = AngleMap(v0, v1)
    return FacePlan(elementary[0], surf, AngleMap(u0, u1), v_map, (v0, v1))


def native_surface(plan: FacePlan, box=None):
    """The converted surface of an elementary or plane face (``box``: the plane's ``(lo, hi)`` in
    (u, v), from its converted pcurves)."""
    s = plan.surface
    pos = s.Position()
    O, X, Y, Z = _xyz(pos.Location()), _xyz(pos.XDirection()), _xyz(pos.YDirection()), _xyz(pos.Direction())
    if plan.kind == "plane":
        return plane_patch(O, X, Y, box)
    v0, v1 = plan.v_range
    if plan.kind == "cylinder":
        R = s.Radius()
        meridian = line_meridian(R, v0, R, v1, v0, v1)
    elif plan.kind == "cone":
        R, a = s.RefRadius(), s.SemiAngle()
        meridian = line_meridian(R + v0 * math.sin(a), v0 * math.cos(a), R + v1 * math.sin(a), v1 * math.cos(a), v0, v1)
    elif plan.kind == "sphere":
        meridian = circle_meridian(0.0, 0.0, s.Radius(), plan.v_map)
    else:
        meridian = circle_meridian(s.MajorRadius(), 0.0, s.MinorRadius(), plan.v_map)
    return revolved_surface(O, X, Y, Z, plan.u_map, meridian)


def native_use(edge, face, plan: FacePlan, curves: dict, key):
    """``(pcurve, 3-D curve or None)`` of the edge use (``edge`` as the wire holds it) on the
    natively converted ``face``, on the edge's parameter (new for circular edges). ``curves``:
    a cache of the edges' 3-D curves by ``key`` (both uses of an edge share one)."""
    (BRep,) = _ocp("BRep")
    tool = BRep.BRep_Tool
    pc = tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    first, last = tool.Range_s(edge, face)
    degenerate = bool(tool.Degenerated_s(edge))
    conic = None if degenerate else circular_curve(edge)
    curve = None
    if not degenerate:
        if key not in curves:
            curves[key] = edge_arc(*_conic_axes(conic, 3), first, last) if conic is not None else _curve3d_from_occ(edge)
        curve = curves[key]
    if plan.kind in ("plane", "spline"):
        if conic is not None:  # a plane's circle or ellipse, on the edge's new parameter
            (Geom2d,) = _ocp("Geom2d")
            return edge_arc(*_conic_axes(_basis(pc, Geom2d.Geom2d_TrimmedCurve), 2), first, last), curve
        return _curve2d_from_occ(pc, first, last), curve
    loc, d = _line2d(pc)
    k = int(np.argmax(np.abs(d)))
    maps = (plan.u_map, plan.v_map)
    if maps[k] is None:  # along the linear coordinate: a straight segment between the mapped ends
        ends = plan.map_uv(np.array([loc + first * d, loc + last * d]))
        return BSplineCurve(1, [first, first, last, last], ends), curve
    other = float(plan.map_uv(loc[None])[0, 1 - k])
    sigma = 1.0 if d[k] > 0 else -1.0
    edge_map = None if degenerate else AngleMap(first, last)
    return mapped_isoline(k, float(loc[k]), sigma, other, (first, last), maps[k], edge_map), curve


def native_faces(shape, faces, edges) -> tuple[dict, set, set]:
    """Which faces of ``shape`` convert natively: ``(plans, converted, mixed)``.

    ``faces``, ``edges``: ``TopTools_IndexedMapOfShape`` of the shape's faces and edges.
    ``plans``: ``{face index: FacePlan}`` of the faces read natively. ``converted``: the edge
    indices of the circular edges left on OCC's parameter, because a face that OCC converts uses
    them (their parameter must be one on every face). An elementary face with such an edge is
    left to OCC too, which may pass the same on across its own circular edges; a plane, B-spline
    or Bézier face keeps its parameter through OCC's conversion, so it stays native and reads
    those edges from its converted twin: ``mixed`` holds those faces' indices."""
    TopAbs, TopExp, TopTools, TopoDS = _ocp("TopAbs", "TopExp", "TopTools", "TopoDS")
    kinds = TopAbs.TopAbs_ShapeEnum
    FORWARD = TopAbs.TopAbs_Orientation.TopAbs_FORWARD
    plans = {}
    for i in range(1, faces.Extent() + 1):
        plan = face_plan(TopoDS.TopoDS.Face_s(faces.FindKey(i).Oriented(FORWARD)))
        if plan is not None:
            plans[i] = plan
    converted: set = set()
    if len(plans) == faces.Extent():
        return plans, converted, set()
    ancestors = TopTools.TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.TopExp.MapShapesAndAncestors_s(shape, kinds.TopAbs_EDGE, kinds.TopAbs_FACE, ancestors)
    touched: set = set()  # native faces with a converted edge

    def circular_edges(i):
        explorer = TopExp.TopExp_Explorer(faces.FindKey(i), kinds.TopAbs_EDGE)
        while explorer.More():
            edge = explorer.Current()
            explorer.Next()
            if circular_curve(TopoDS.TopoDS.Edge_s(edge)) is not None:
                yield edge

    todo = [i for i in range(1, faces.Extent() + 1) if i not in plans]
    while todo:
        for edge in circular_edges(todo.pop()):
            key = edges.FindIndex(edge)
            if key in converted:
                continue
            converted.add(key)
            for other in ancestors.FindFromKey(edge):
                j = faces.FindIndex(other)
                if j not in plans:
                    continue
                if plans[j].kind in ("plane", "spline"):
                    touched.add(j)
                else:
                    del plans[j]
                    touched.discard(j)
                    todo.append(j)
    return plans, converted, touched
