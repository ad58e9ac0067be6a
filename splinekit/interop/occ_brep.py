"""OpenCascade topology <-> splinekit B-rep: TopoDS faces, shells and solids as
:class:`~splinekit.brep.TrimmedFace`, :class:`~splinekit.brep.Shell` and
:class:`~splinekit.brep.Solid`, and back.

OCC -> splinekit (:func:`brep_from_shape`): the shape is first re-expressed with
``BRepBuilderAPI_NurbsConvert`` on a copy, which turns every analytic surface AND its
pcurves into B-splines consistently (an analytic surface converted alone gets a rational
parametrization that is not the angle, so the pcurves would no longer map onto it). Each
face is then read with FORWARD orientation so its pcurves keep the material on their left;
the face's own orientation becomes ``reversed``. Every edge use keeps its pcurve, its 3-D
curve on the same parameter range and a ``key``: the edge's index in one
``TopTools_IndexedMapOfShape`` of the whole shape, so the two faces of an edge share it.

splinekit -> OCC (:func:`brep_to_shape`): faces are built with ``BRep_Builder`` from their
surfaces and pcurves; each edge is built ONCE per key (both faces' pcurves on one
``TopoDS_Edge``; a seam gets its two pcurves on one face), vertices are shared through the
loops' adjacency, 3-D curves are built where missing (``BRepLib.BuildCurve3d``), and edges
without keys are paired geometrically first. Sewing (``BRepBuilderAPI_Sewing``) is not used:
it may merge or split edges, and the direct build keeps the counts exactly.

OCP is imported inside the functions (through ``occ._ocp``).
"""

from __future__ import annotations

import numpy as np

from ..errors import BackendError, ParameterError
from .occ import _compound, _from_geom, _ocp, _occ_call, _sub_shapes, _xyz, require_ocp, to_occ

__all__ = ["brep_from_shape", "brep_to_shape", "is_brep"]


def is_brep(obj) -> bool:
    """Whether ``obj`` is a splinekit TrimmedFace, Shell or Solid."""
    from ..brep import Shell, Solid, TrimmedFace

    return isinstance(obj, (TrimmedFace, Shell, Solid))


# ----------------------------------------------------------------------------------------
# 2-D curves (pcurves)


def _curve2d_to_occ(curve):
    """An OCP ``Geom2d_BSplineCurve`` for a 2-D splinekit curve."""
    _, _, TColStd, _ = require_ocp()
    Geom2d, TColgp, gp = _ocp("Geom2d", "TColgp", "gp")
    from ..brep.edge import as_pcurve

    curve = as_pcurve(curve)
    P = np.asarray(curve.control_points, dtype=np.float64)
    poles = TColgp.TColgp_Array1OfPnt2d(1, len(P))
    for i, (x, y) in enumerate(P.tolist(), 1):
        poles.SetValue(i, gp.gp_Pnt2d(x, y))
    values, counts = np.unique(curve.knots, return_counts=True)
    knots = TColStd.TColStd_Array1OfReal(1, len(values))
    mults = TColStd.TColStd_Array1OfInteger(1, len(values))
    for i, (k, m) in enumerate(zip(values.tolist(), counts.tolist()), 1):
        knots.SetValue(i, k)
        mults.SetValue(i, int(m))
    if curve.weights is None:
        return Geom2d.Geom2d_BSplineCurve(poles, knots, mults, curve.degree, False)
    weights = TColStd.TColStd_Array1OfReal(1, len(P))
    for i, w in enumerate(np.asarray(curve.weights).tolist(), 1):
        weights.SetValue(i, w)
    return Geom2d.Geom2d_BSplineCurve(poles, weights, knots, mults, curve.degree, False)


def _curve2d_from_occ(handle, first: float, last: float):
    """A 2-D splinekit B-spline / NURBS curve for the OCP ``Geom2d_Curve`` on ``[first, last]``,
    keeping OCC's parameter (a B-spline is cut with ``Segment``, which does not reparametrize)."""
    from ..curves import BSplineCurve, NurbsCurve

    Geom2d, Geom2dConvert = _ocp("Geom2d", "Geom2dConvert")
    if isinstance(handle, Geom2d.Geom2d_TrimmedCurve):
        handle = handle.BasisCurve()
    if isinstance(handle, Geom2d.Geom2d_BezierCurve):
        handle = Geom2dConvert.Geom2dConvert.CurveToBSplineCurve_s(handle)  # same parameter [0, 1]
    if isinstance(handle, Geom2d.Geom2d_Line):  # exactly, on the same parameter
        p, q = handle.Value(first), handle.Value(last)
        return BSplineCurve(1, [first, first, last, last], [[p.X(), p.Y()], [q.X(), q.Y()]])
    if not isinstance(handle, Geom2d.Geom2d_BSplineCurve):
        trimmed = _occ_call("trim a pcurve", Geom2d.Geom2d_TrimmedCurve, handle, first, last)
        handle = _occ_call("convert a pcurve", Geom2dConvert.Geom2dConvert.CurveToBSplineCurve_s, trimmed)
    else:
        handle = handle.Copy()  # OCP returns the derived class
    _segment(handle, first, last)
    n = handle.NbPoles()
    P = [(handle.Pole(i).X(), handle.Pole(i).Y()) for i in range(1, n + 1)]
    U = np.repeat([handle.Knot(i) for i in range(1, handle.NbKnots() + 1)],
                  [handle.Multiplicity(i) for i in range(1, handle.NbKnots() + 1)])
    if handle.IsRational():
        curve = NurbsCurve(handle.Degree(), U, P, [handle.Weight(i) for i in range(1, n + 1)])
    else:
        curve = BSplineCurve(handle.Degree(), U, P)
    return curve.clamp()


def _segment(handle, first: float, last: float) -> None:
    """Cut the B-spline ``handle`` (a copy; 2-D or 3-D) to ``[first, last]`` in place."""
    a, b = handle.FirstParameter(), handle.LastParameter()
    scale = max(1.0, abs(b - a))
    if handle.IsPeriodic():
        handle.Segment(first, last)  # a periodic segment may cross the knot origin
        handle.SetNotPeriodic()
        return
    if abs(first - a) <= 1e-13 * scale and abs(last - b) <= 1e-13 * scale:
        return
    # STEP rounding can put a range a hair past the curve's ends: clamp it to the natural range
    first, last = max(first, a), min(last, b)
    if last - first > 1e-12 * scale:
        handle.Segment(first, last)


def _curve3d_from_occ(edge):
    """The 3-D curve of ``edge`` on its own range (OCC's parameter kept), or None."""
    Geom, _, _, _ = require_ocp()
    (BRep, GeomConvert) = _ocp("BRep", "GeomConvert")
    curve = BRep.BRep_Tool.Curve_s(edge, 0.0, 0.0)  # a located copy when the edge is moved
    if curve is None:
        return None
    first, last = BRep.BRep_Tool.Range_s(edge)
    if isinstance(curve, Geom.Geom_TrimmedCurve):
        curve = curve.BasisCurve()
    if isinstance(curve, Geom.Geom_BezierCurve):
        curve = GeomConvert.GeomConvert.CurveToBSplineCurve_s(curve)
    if isinstance(curve, Geom.Geom_Line):  # exactly, on the same parameter
        from ..curves import BSplineCurve

        return BSplineCurve(1, [first, first, last, last], [_xyz(curve.Value(first)), _xyz(curve.Value(last))])
    if not isinstance(curve, Geom.Geom_BSplineCurve):
        return None  # anything else is left to BRepLib.BuildCurve3d on export
    curve = curve.Copy()
    _segment(curve, first, last)
    return _from_geom(curve)


# ----------------------------------------------------------------------------------------
# OCC -> splinekit


class _Reader:
    """Reads the faces of an OCC shape through its NURBS-converted copy, walked in parallel.

    The converted copy gives every surface as a B-spline and, where the original geometry is
    analytic, the pcurves and 3-D curves re-expressed on it. Where the original is already
    B-spline, Bézier, a plane or a line (face surface, pcurve and 3-D curve alike), the original
    pcurve and 3-D curve are kept: they are exact, share the converted edge's parameter, and
    OCC's conversion re-approximates some of them (on files with loose tolerances the
    re-approximated pcurves can even cross each other). Edge keys are indices in one
    ``TopTools_IndexedMapOfShape`` of the original shape.
    """

    def __init__(self, shape):
        TopAbs, TopExp, TopTools = _ocp("TopAbs", "TopExp", "TopTools")
        self.edge_map = TopTools.TopTools_IndexedMapOfShape()
        TopExp.TopExp.MapShapes_s(shape, TopAbs.TopAbs_ShapeEnum.TopAbs_EDGE, self.edge_map)
        self.curves: dict = {}  # (edge key, native) -> 3-D curve in the edge's own direction

    def face(self, face, conv, index: int, name=None):
        """The TrimmedFace of the original ``face`` whose converted twin is ``conv``."""
        from ..brep import Edge, TrimmedFace

        BRep, BRepTools, TopAbs, TopExp, TopoDS = _ocp("BRep", "BRepTools", "TopAbs", "TopExp", "TopoDS")
        orient = TopAbs.TopAbs_Orientation
        reversed_ = face.Orientation() == orient.TopAbs_REVERSED
        fwd = TopoDS.TopoDS.Face_s(face.Oriented(orient.TopAbs_FORWARD))
        cfwd = TopoDS.TopoDS.Face_s(conv.Oriented(orient.TopAbs_FORWARD))
        native_face = _native_surface(fwd)
        tol_face = max(BRep.BRep_Tool.Tolerance_s(fwd), 1e-7)
        outer = BRepTools.BRepTools.OuterWire_s(fwd)
        loops = []
        wires, cwires = (TopExp.TopExp_Explorer(f, TopAbs.TopAbs_ShapeEnum.TopAbs_WIRE) for f in (fwd, cfwd))
        while wires.More() and cwires.More():
            wire = TopoDS.TopoDS.Wire_s(wires.Current())
            # the wire's stored edges, original and converted, pair up in order; the wire explorer
            # (which follows the loop, in an order that depends on hashing) runs on the original only
            stored, twins = _children(wire), _children(cwires.Current())
            if len(stored) != len(twins):
                raise BackendError(f"face {index}: the NURBS-converted wire does not match the original")
            edges = []
            walk = BRepTools.BRepTools_WireExplorer(wire, fwd)
            while walk.More():
                e = walk.Current()
                j = next((j for j, x in enumerate(stored) if x.IsEqual(e)), None)
                if j is None:
                    j = next(j for j, x in enumerate(stored) if x.IsSame(e))
                twin = TopoDS.TopoDS.Edge_s(twins[j].Oriented(e.Orientation()))
                edges.append(self._edge_use(e, fwd, twin, cfwd, native_face, index, Edge))
                walk.Next()
            if edges:
                _close_at_poles(edges)
                if wire.IsSame(outer):
                    loops.insert(0, edges)
                else:
                    loops.append(edges)
            wires.Next()
            cwires.Next()
        if not loops:
            raise BackendError(f"face {index}: OpenCascade gives it no wire (an unbounded face cannot be converted)")
        uv = np.concatenate([e.pcurve.evaluate(np.linspace(*e.domain, 17)) for lp in loops for e in lp])
        surface = self._surface(cfwd, index, uv.min(axis=0), uv.max(axis=0))
        loops = [[_same_parameter(surface, use) for use in lp] for lp in loops]
        return TrimmedFace(surface, loops, reversed=reversed_, tolerance=tol_face, name=name)

    def _surface(self, fwd, index, lo, hi):
        """The face's B-spline surface; ``lo``, ``hi``: the (u, v) bounding box of its pcurves."""
        Geom, _, _, _ = require_ocp()
        BRep, BRepTools = _ocp("BRep", "BRepTools")
        surf = BRep.BRep_Tool.Surface_s(fwd)  # a located copy when the face is moved
        if isinstance(surf, Geom.Geom_RectangularTrimmedSurface):
            surf = surf.BasisSurface()
        if not isinstance(surf, (Geom.Geom_BSplineSurface, Geom.Geom_BezierSurface)):
            raise BackendError(
                f"face {index}: OpenCascade's NURBS conversion left a {type(surf).__name__}; it cannot be converted exactly"
            )
        if isinstance(surf, Geom.Geom_BSplineSurface) and (surf.IsUPeriodic() or surf.IsVPeriodic()):
            # a face may straddle a periodic surface's knot origin: cut the periodic surface to the face's
            # bounds (the cut keeps the parameter), so every pcurve lies inside the splinekit domain
            (u0, v0), (u1, v1) = lo, hi  # not UVBounds, which clips to the periodic surface's bounds
            U0, U1, V0, V1 = surf.Bounds()
            eps = 1e-9 * max(1.0, U1 - U0, V1 - V0)
            outside_u = surf.IsUPeriodic() and (u0 < U0 - eps or u1 > U1 + eps)
            outside_v = surf.IsVPeriodic() and (v0 < V0 - eps or v1 > V1 + eps)
            if outside_u or outside_v:
                surf = surf.Copy()
                su = (u0, min(u1, u0 + surf.UPeriod())) if outside_u else (U0, U1)
                sv = (v0, min(v1, v0 + surf.VPeriod())) if outside_v else (V0, V1)
                _occ_call(f"cut the periodic surface of face {index}", surf.Segment, su[0], su[1], sv[0], sv[1])
                out = _from_geom(surf)
                # OCC may return the segment a whole period away from the requested range: shift it back
                (a0, a1), (b0, b1) = out.domain
                return out.reparametrize((su[0], su[0] + a1 - a0), (sv[0], sv[0] + b1 - b0))
        out = _from_geom(surf)
        if out is None:
            raise BackendError(f"face {index}: cannot read its {type(surf).__name__}")
        return out

    def _edge_use(self, edge, fwd, cedge, cfwd, native_face, index, Edge):
        BRep, TopAbs = _ocp("BRep", "TopAbs")
        tool = BRep.BRep_Tool
        key = self.edge_map.FindIndex(edge)
        degenerate = bool(tool.Degenerated_s(edge))
        native = native_face and _native_edge(edge, fwd)
        src_edge, src_face = (edge, fwd) if native else (cedge, cfwd)
        pc = tool.CurveOnSurface_s(src_edge, src_face, 0.0, 0.0)
        if pc is None:
            raise BackendError(f"face {index}: edge {key} has no pcurve on the face")
        first, last = tool.Range_s(src_edge, src_face)
        pcurve = _curve2d_from_occ(pc, first, last)
        conv_tolerance = tool.Tolerance_s(cedge)
        if not native and not degenerate and conv_tolerance > 10.0 * max(tool.Tolerance_s(edge), 1e-7):
            better = _isoline_pcurve(edge, fwd, cedge, cfwd, pcurve)
            if better is not pcurve:  # OCC's widened tolerance covered the stray pcurve only
                pcurve, conv_tolerance = better, 0.0
        curve = None
        if not degenerate:
            if (key, native) not in self.curves:
                self.curves[(key, native)] = _curve3d_from_occ(src_edge)
            curve = self.curves[(key, native)]
            if curve is not None and not _same_domain(curve.domain, pcurve.domain):
                curve = None  # not SameRange: keep the trim only, the 3-D curve is rebuilt on export
        # the conversion may widen the tolerance to cover its approximations: keep the larger. OCC's
        # vertex tolerances may exceed the edge's (an edge's end lies within its VERTEX's tolerance of
        # the vertex, not its own): fold them in, or two edges meeting there look like an open loop
        TopExp = _ocp("TopExp")[0]
        ends = [TopExp.TopExp.FirstVertex_s(edge), TopExp.TopExp.LastVertex_s(edge)]
        tolerance = max([tool.Tolerance_s(edge), conv_tolerance, 1e-7]
                        + [tool.Tolerance_s(v) for v in ends if not v.IsNull()])
        use = Edge(pcurve, curve, key=key, degenerate=degenerate, tolerance=tolerance)
        # the wire runs the edge backwards: reverse the pcurve (and 3-D curve) so the material stays left
        return use.reversed() if edge.Orientation() == TopAbs.TopAbs_Orientation.TopAbs_REVERSED else use


def _isoline_pcurve(edge, fwd, cedge, cfwd, pcurve):
    """A better pcurve than OCC's re-approximated ``pcurve`` of the converted edge ``cedge``, or
    ``pcurve`` itself.

    The NURBS conversion re-approximates every pcurve of an analytic or revolved face, and on some
    files the result strays far (OCC then raises the edge's tolerance to cover it: 0.056 on a CADDS
    meridian, whose pcurve leaves the surface's domain). When the original pcurve is an isoline
    (one coordinate constant, a meridian or a seam), the converted surface keeps the other
    coordinate and maps the isoline to an isoline: the converted pcurve with that coordinate set
    to the constant (read at one of its ends, which sit on exact vertices) follows the 3-D curve.
    It is kept only if it lies closer to the 3-D curve, measured through OCC. (The 3-D curve and
    the original pcurve may disagree in parameter, as on that CADDS meridian: the conversion's
    pcurve follows the 3-D curve's parameter, so its other coordinate is kept.)"""
    from ..curves import BSplineCurve, NurbsCurve

    (BRep,) = _ocp("BRep")
    tool = BRep.BRep_Tool
    opc = tool.CurveOnSurface_s(edge, fwd, 0.0, 0.0)
    if opc is None:
        return pcurve
    orig = _curve2d_from_occ(opc, *tool.Range_s(edge, fwd))
    if not _same_domain(orig.domain, pcurve.domain):
        return pcurve
    P = np.array(orig.control_points, dtype=np.float64)
    span = np.ptp(P, axis=0)
    const = np.flatnonzero(span <= 1e-12 * max(1.0, float(np.abs(P).max())))
    if len(const) != 1:
        return pcurve
    k = int(const[0])
    surf, c3 = tool.Surface_s(cfwd), tool.Curve_s(cedge, 0.0, 0.0)
    if c3 is None:
        return pcurve
    t = np.linspace(*pcurve.domain, 33)

    def deviation(c):
        uv = c.evaluate(t)
        return max(surf.Value(float(u), float(v)).Distance(c3.Value(float(x))) for (u, v), x in zip(uv, t))

    best, best_dev = pcurve, deviation(pcurve)
    # the constant at either end (one end may sit on a pole, where that coordinate is free)
    Q = np.array(pcurve.control_points, dtype=np.float64)
    for c in np.unique(pcurve.evaluate(np.array(pcurve.domain))[:, k]):
        Q[:, k] = c
        cand = (BSplineCurve(pcurve.degree, pcurve.knots, Q) if pcurve.weights is None
                else NurbsCurve(pcurve.degree, pcurve.knots, Q, pcurve.weights))
        dev = deviation(cand)
        if dev < best_dev:
            best, best_dev = cand, dev
    return best


def _same_parameter(surface, use):
    """``use`` (an Edge on ``surface``) with its tolerance covering how far its 3-D curve is from
    the surface at its pcurve at the same parameter (the data model's SameParameter).

    OCC measures that deviation on its own samples and the NURBS conversion re-approximates
    curves, so the figure read from OCC can fall short of the one the curves really have.
    Where the two curves are the same point set within a much smaller distance (only their
    parameters disagree), the 3-D curve is dropped instead (the surface at the pcurve is then the
    edge's geometry, as for a use without a 3-D curve) and the tolerance covers that distance."""
    from ..brep import Edge
    from ..closest import project

    if use.curve is None or use.degenerate:
        return use
    a, b = use.domain
    br = np.union1d(use.pcurve.bezier_breakpoints(), use.curve.bezier_breakpoints())
    br = np.union1d(br[(br > a) & (br < b)], [a, b])
    t = (br[:-1, None] + (br[1:] - br[:-1])[:, None] * np.linspace(0.0, 1.0, 17)[None]).ravel()
    uv = use.pcurve.evaluate(t)
    (u0, u1), (v0, v1) = surface.domain
    on_surface = surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1))
    dev = float(np.linalg.norm(on_surface - use.curve.evaluate(t), axis=1).max())
    if dev <= use.tolerance:
        return use
    apart = float(project(use.curve, on_surface).distances.max())
    margin = 1.1  # the check samples the same parameters; the margin covers rounding only
    if apart < 0.5 * dev:
        return Edge(use.pcurve, None, key=use.key, tolerance=max(use.tolerance, margin * apart))
    return Edge(use.pcurve, use.curve, key=use.key, tolerance=margin * dev)


def _children(shape) -> list:
    """The sub-shapes ``shape`` stores directly, in stored order (orientations composed)."""
    (TopoDS,) = _ocp("TopoDS")
    out, it = [], TopoDS.TopoDS_Iterator(shape)
    while it.More():
        out.append(it.Value())
        it.Next()
    return out


def _native_surface(face) -> bool:
    """Whether the face's surface keeps its parameter through NURBS conversion (B-spline,
    Bézier or plane, possibly trimmed)."""
    Geom, _, _, _ = require_ocp()
    (BRep,) = _ocp("BRep")
    surf = BRep.BRep_Tool.Surface_s(face)
    if isinstance(surf, Geom.Geom_RectangularTrimmedSurface):
        surf = surf.BasisSurface()
    if isinstance(surf, Geom.Geom_SurfaceOfLinearExtrusion):  # a B-spline or line swept straight: u, v kept
        basis = surf.BasisCurve()
        if isinstance(basis, Geom.Geom_TrimmedCurve):
            basis = basis.BasisCurve()
        return isinstance(basis, (Geom.Geom_BSplineCurve, Geom.Geom_BezierCurve, Geom.Geom_Line))
    return isinstance(surf, (Geom.Geom_BSplineSurface, Geom.Geom_BezierSurface, Geom.Geom_Plane))


def _native_edge(edge, face) -> bool:
    """Whether the edge's pcurve on ``face`` and its 3-D curve are B-splines, Béziers or lines
    (an exact conversion that keeps the parameter)."""
    Geom, _, _, _ = require_ocp()
    BRep, Geom2d = _ocp("BRep", "Geom2d")
    pc = BRep.BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    if isinstance(pc, Geom2d.Geom2d_TrimmedCurve):
        pc = pc.BasisCurve()
    if not isinstance(pc, (Geom2d.Geom2d_BSplineCurve, Geom2d.Geom2d_BezierCurve, Geom2d.Geom2d_Line)):
        return False
    if BRep.BRep_Tool.Degenerated_s(edge):
        return True
    c = BRep.BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if c is None:
        return False
    if isinstance(c, Geom.Geom_TrimmedCurve):
        c = c.BasisCurve()
    return isinstance(c, (Geom.Geom_BSplineCurve, Geom.Geom_BezierCurve, Geom.Geom_Line))


def _close_at_poles(edges: list) -> None:
    """Replace, in place, the pcurve of each degenerate edge (a pole: its 3-D image is a point, so
    its pcurve is free) by the straight segment from the previous use's end to the next use's start.
    OCC's conversion leaves gaps there: a meridian's re-approximated pcurve drifts in u near the
    pole, and the loop no longer closes in (u, v)."""
    from ..brep import Edge
    from ..curves import BSplineCurve

    n = len(edges)
    for k, e in enumerate(edges):
        if not e.degenerate or n < 2:
            continue
        a, b = edges[k - 1].end_uv, edges[(k + 1) % n].start_uv
        if np.allclose(a, e.start_uv, rtol=0, atol=1e-12) and np.allclose(b, e.end_uv, rtol=0, atol=1e-12):
            continue
        t0, t1 = e.domain
        pc = BSplineCurve(1, [t0, t0, t1, t1], [a, b])
        edges[k] = Edge(pc, None, key=e.key, degenerate=True, tolerance=e.tolerance)


def _same_domain(a, b) -> bool:
    scale = max(1.0, abs(a[1] - a[0]))
    return abs(a[0] - b[0]) <= 1e-9 * scale and abs(a[1] - b[1]) <= 1e-9 * scale


def _normalized_copy(shape):
    """A copy of ``shape`` prepared for an exact NURBS conversion.

    OCC's ``BRepBuilderAPI_NurbsConvert`` re-expresses the pcurves of a face on a periodic analytic
    surface exactly only when the face's u range starts at 0 (measured on a cylinder face over
    [a, a + 2 pi]: exact for a = 0, 5e-8 off for a = pi/2, a construction error for a = -1; on a
    STEP assembly whose cylinder faces sit on rectangular trims [pi/2, 5 pi/2], 0.19 mm off). So
    each such face gets a copy of its surface with the frame turned about the axis by the face's
    first u (same points, u shifted), its pcurves are translated by -u, and the rectangular trim is
    dropped (the pcurves bound the face)."""
    Geom, _, _, gp = require_ocp()
    BRep, BRepBuilderAPI, BRepTools, TopAbs, TopExp, TopLoc, TopoDS, TopTools = _ocp(
        "BRep", "BRepBuilderAPI", "BRepTools", "TopAbs", "TopExp", "TopLoc", "TopoDS", "TopTools")
    tool = BRep.BRep_Tool
    copy = _occ_call("copy the shape", BRepBuilderAPI.BRepBuilderAPI_Copy, shape, True, False).Shape()
    builder = BRep.BRep_Builder()
    done = TopTools.TopTools_MapOfShape()  # a face shared by several placements is changed once
    elementary = (Geom.Geom_CylindricalSurface, Geom.Geom_ConicalSurface, Geom.Geom_SphericalSurface,
                  Geom.Geom_ToroidalSurface)
    FORWARD, REVERSED = TopAbs.TopAbs_Orientation.TopAbs_FORWARD, TopAbs.TopAbs_Orientation.TopAbs_REVERSED
    for face in _sub_shapes(copy, "FACE"):
        bare = TopoDS.TopoDS.Face_s(face.Located(TopLoc.TopLoc_Location()).Oriented(FORWARD))
        if not done.Add(bare):
            continue
        loc = TopLoc.TopLoc_Location()
        surf = tool.Surface_s(bare, loc)
        basis = surf.BasisSurface() if isinstance(surf, Geom.Geom_RectangularTrimmedSurface) else surf
        if not isinstance(basis, elementary + (Geom.Geom_SurfaceOfRevolution,)):
            continue
        u0 = BRepTools.BRepTools.UVBounds_s(bare)[0]
        if abs(u0) <= 1e-12 and basis is surf:
            continue
        turned = basis.Copy()  # a surface of this face's own: pcurves are stored per surface
        if abs(u0) > 1e-12:
            turned = _turned(basis, u0, elementary)
            if turned is None:
                continue
        # each edge's pcurve(s) in THIS face (two for a seam the face uses both ways); read before the
        # surface changes: pcurves are stored per surface, and two faces may share one surface
        uses: dict = {}
        explorer = TopExp.TopExp_Explorer(bare, TopAbs.TopAbs_ShapeEnum.TopAbs_EDGE)
        while explorer.More():
            e = TopoDS.TopoDS.Edge_s(explorer.Current())
            pc = tool.CurveOnSurface_s(e, bare, 0.0, 0.0)
            key = e.Oriented(FORWARD)
            entry = next((u for u in uses.values() if u[0].IsSame(key)), None)
            if entry is None:
                uses[len(uses)] = entry = [TopoDS.TopoDS.Edge_s(key), {}]
            entry[1][e.Orientation()] = pc
            explorer.Next()
        if any(pc is None for _, pcs in uses.values() for pc in pcs.values()):
            continue
        if surf is not basis and not (basis.IsUPeriodic() and basis.IsVPeriodic()):
            # keep the trim along the non-periodic direction (a line swept around an axis is infinite)
            _, _, v0, v1 = surf.Bounds()
            turned = Geom.Geom_RectangularTrimmedSurface(turned, v0, v1, False)
        builder.UpdateFace(bare, turned, loc, tool.Tolerance_s(bare))
        shift = gp.gp_Vec2d(-u0, 0.0)
        for e, pcs in uses.values():
            tol = tool.Tolerance_s(e)
            if len(pcs) == 2:
                builder.UpdateEdge(e, pcs[FORWARD].Translated(shift), pcs[REVERSED].Translated(shift), bare, tol)
            else:
                builder.UpdateEdge(e, next(iter(pcs.values())).Translated(shift), bare, tol)
    return copy


def _turned(basis, u0, elementary):
    """A copy of the periodic ``basis`` surface whose u = 0 is the old u = ``u0`` (same points), or None."""
    Geom, _, _, gp = require_ocp()
    if isinstance(basis, elementary):
        turned = basis.Copy()
        ax3 = turned.Position()
        for sign in (1.0, -1.0):  # the frame's handedness decides which way u runs
            frame = ax3.Rotated(gp.gp_Ax1(ax3.Location(), ax3.Direction()), sign * u0)
            turned.SetPosition(frame)
            if _same_points(basis, turned, u0):
                return turned
        return None
    axis = basis.Axis()
    for sign in (1.0, -1.0):
        curve = basis.BasisCurve().Rotated(axis, sign * u0)
        turned = Geom.Geom_SurfaceOfRevolution(curve, axis)
        if _same_points(basis, turned, u0):
            return turned
    return None


def _same_points(old, new, u0) -> bool:
    """Whether ``new(u, v) == old(u + u0, v)`` at a few sample parameters."""
    v0, v1 = old.Bounds()[2:]
    v0, v1 = max(v0, -1.0), min(v1, 1.0)
    for u in (0.3, 1.7, 4.1):
        for v in (v0 + 0.25 * (v1 - v0), v0 + 0.75 * (v1 - v0)):
            if old.Value(u + u0, v).Distance(new.Value(u, v)) > 1e-9 * max(1.0, old.Value(u + u0, v).Distance(
                    old.Value(u + u0 + 3.0, v))):
                return False
    return True


def _nurbs_converted(shape):
    """A copy of ``shape`` whose surfaces, 3-D curves and pcurves are all B-splines."""
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    shape = _normalized_copy(shape)
    converter = _occ_call("convert the shape to NURBS", BRepBuilderAPI.BRepBuilderAPI_NurbsConvert, shape, False)
    if not converter.IsDone():
        raise BackendError("OpenCascade could not convert the shape to NURBS (BRepBuilderAPI_NurbsConvert)")
    return converter.Shape()


def brep_from_shape(shape, *, name=None, on_error=None):
    """splinekit B-rep objects for the OCC ``shape``.

    A face gives a TrimmedFace, a shell a Shell, a solid a Solid; a compound (or compsolid) gives
    a list of its solids, shells, faces and free curves, in OCC's order (nested compounds
    flattened). ``name`` labels the returned object(s).

    A face that cannot be converted raises BackendError naming it (``face i``: its number in
    reading order). With ``on_error(index, message)`` given instead, the face is left out and
    reported through the callback; a solid that lost faces comes back as its shells (open).
    """
    TopAbs, TopoDS, BRepTools = _ocp("TopAbs", "TopoDS", "BRepTools")
    for face in _sub_shapes(shape, "FACE"):
        bounds = BRepTools.BRepTools.UVBounds_s(face)
        if not all(abs(x) < 1e100 for x in bounds):  # OCC's "infinite" is 2e100
            raise ParameterError(f"cannot convert an unbounded face (UV bounds {list(bounds)}): bound it with edges first")
    try:
        converted = _nurbs_converted(shape)
    except BackendError as exc:
        return _unconvertible(shape, exc, name, on_error)
    reader = _Reader(shape)
    kinds = TopAbs.TopAbs_ShapeEnum
    counter = iter(range(1 << 62))  # face numbers in error messages, in reading order
    TopExp, BRepClass3d = _ocp("TopExp", "BRepClass3d")

    def pairs(s, c, kind=None):
        """The children (or the ``kind`` sub-shapes) of the original ``s`` and its converted twin ``c``."""
        if kind is None:
            its = TopoDS.TopoDS_Iterator(s), TopoDS.TopoDS_Iterator(c)
            more, value = (lambda it: it.More()), (lambda it: it.Value())
        else:
            its = TopExp.TopExp_Explorer(s, kind), TopExp.TopExp_Explorer(c, kind)
            more, value = (lambda it: it.More()), (lambda it: it.Current())
        while more(its[0]) and more(its[1]):
            yield value(its[0]), value(its[1])
            its[0].Next()
            its[1].Next()
        if more(its[0]) or more(its[1]):
            raise BackendError("the NURBS-converted shape does not match the original's structure")

    lost = []  # faces left out (on_error given)

    def face(s, c, label=None):
        index = next(counter)
        try:
            return reader.face(TopoDS.TopoDS.Face_s(s), TopoDS.TopoDS.Face_s(c), index, label)
        except Exception as exc:  # SplineKitError, or an OCC Standard_Failure (no common base)
            message = str(exc) if isinstance(exc, BackendError) else f"face {index}: {type(exc).__name__}: {exc}"
            if on_error is None:
                raise BackendError(message) from None
            on_error(index, message)
            lost.append(index)
            return None

    def shell(s, c, label=None):
        from ..brep import Shell

        # faces explored with their orientations composed with the shell's (and solid's)
        faces = [f for f in (face(f, fc) for f, fc in pairs(s, c, kinds.TopAbs_FACE)) if f is not None]
        return Shell(faces, name=label) if faces else None

    def solid(s, c):
        from ..brep import Solid

        outer = BRepClass3d.BRepClass3d.OuterShell_s(TopoDS.TopoDS.Solid_s(s))
        shells, before = [], len(lost)
        for sh, shc in pairs(s, c, kinds.TopAbs_SHELL):
            if outer is not None and not outer.IsNull() and sh.IsSame(outer):
                shells.insert(0, shell(sh, shc, name))
            else:
                shells.append(shell(sh, shc, name))
        if len(lost) > before:  # faces were left out: the shells no longer close
            return [x for x in shells if x is not None]
        if not shells:
            raise BackendError("the OCC solid has no shell")
        return [Solid(shells, name=name)]

    def convert(s, c):
        kind = s.ShapeType()
        if kind == kinds.TopAbs_FACE:
            return [x for x in [face(s, c, name)] if x is not None]
        if kind == kinds.TopAbs_SHELL:
            return [x for x in [shell(s, c, name)] if x is not None]
        if kind == kinds.TopAbs_SOLID:
            return solid(s, c)
        if kind in (kinds.TopAbs_EDGE, kinds.TopAbs_WIRE):
            from .occ import _edge_to_curve

            curves = (_edge_to_curve(e) for e in _sub_shapes(s, "EDGE"))
            return [cv for cv in curves if cv is not None]
        if kind in (kinds.TopAbs_COMPOUND, kinds.TopAbs_COMPSOLID):
            return [item for child, twin in pairs(s, c) for item in convert(child, twin)]
        return []  # vertices

    out = convert(shape, converted)
    if on_error is None and shape.ShapeType() in (kinds.TopAbs_FACE, kinds.TopAbs_SHELL, kinds.TopAbs_SOLID):
        return out[0]
    return out


def _unconvertible(shape, exc, name, on_error):
    """What :func:`brep_from_shape` does when OCC cannot NURBS-convert ``shape`` as a whole: the
    faces that fail alone are named (BackendError, or ``on_error`` for each); with ``on_error``, a
    compound's children are then converted one by one, so the good ones are still read."""
    TopAbs, TopoDS = _ocp("TopAbs", "TopoDS")
    kinds = TopAbs.TopAbs_ShapeEnum
    if on_error is not None and shape.ShapeType() in (kinds.TopAbs_COMPOUND, kinds.TopAbs_COMPSOLID):
        out = []
        for child in _children(shape):
            got = brep_from_shape(child, name=name, on_error=on_error)
            out.extend(got if isinstance(got, list) else [got])
        return out
    bad = []
    for index, face in enumerate(_sub_shapes(shape, "FACE")):
        try:
            _nurbs_converted(face)
        except BackendError as err:
            bad.append((index, f"face {index}: {err}"))
    if not bad:
        bad = [(-1, str(exc))]
    if on_error is None:
        raise BackendError("; ".join(msg for _, msg in bad[:5])) from None
    for index, msg in bad:
        on_error(index, msg)
    return []


# ----------------------------------------------------------------------------------------
# splinekit -> OCC


def _use_points(face, use) -> np.ndarray:
    """``(5, 3)`` points of an edge use at parameter fractions 0, 0.25, 0.5, 0.75, 1 (3-D curve if
    there is one, else the surface at the pcurve)."""
    a, b = use.domain
    t = a + (b - a) * np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    if use.curve is not None:
        return use.curve.evaluate(t)
    uv = use.pcurve.evaluate(t)
    (u0, u1), (v0, v1) = face.surface.domain  # a file's pcurves may overshoot by a rounding
    return face.surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1))


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
    """Give keys to the uses that have none: two keyless uses whose 3-D points (ends and
    quarter points, either direction) agree within their tolerance become one edge; the others
    are edges of their own. ``uses`` rows are ``[face index, loop, position, Edge, key, points]``."""
    from scipy.spatial import cKDTree

    loose = [r for r in uses if r[4] is None]
    if not loose:
        return
    sizes = np.array([max(np.linalg.norm(r[5][-1] - r[5][0]), np.linalg.norm(r[5][2] - r[5][0])) for r in loose])
    mids = np.array([r[5][2] for r in loose])
    tree = cKDTree(mids)
    taken = np.zeros(len(loose), bool)
    for i, r in enumerate(loose):
        r[4] = ("free", r[0], r[1], r[2])
    for i, r in enumerate(loose):
        if taken[i] or r[3].degenerate:
            continue
        tol_i = 10 * r[3].tolerance + 1e-9 * sizes[i]
        for j in tree.query_ball_point(mids[i], tol_i + 10 * max(rr[3].tolerance for rr in loose)):
            if j == i or taken[j] or loose[j][3].degenerate:
                continue
            tol = 10 * max(r[3].tolerance, loose[j][3].tolerance) + 1e-9 * max(sizes[i], sizes[j])
            p, q = r[5], loose[j][5]
            if np.max(np.linalg.norm(p - q, axis=1)) <= tol or np.max(np.linalg.norm(p - q[::-1], axis=1)) <= tol:
                loose[j][4] = r[4]
                taken[i] = taken[j] = True
                break


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


def _faces_of(obj):
    from ..brep import Shell, Solid, TrimmedFace

    if isinstance(obj, TrimmedFace):
        return [obj]
    if isinstance(obj, Shell):
        return list(obj.faces)
    if isinstance(obj, Solid):
        return list(obj.faces)
    raise ParameterError(f"expected a TrimmedFace, Shell or Solid, got {type(obj).__name__}")


def brep_to_shape(obj, *, tolerance: float = 1e-7):
    """An OCC ``TopoDS_Face`` / ``TopoDS_Shell`` / ``TopoDS_Solid`` for a splinekit TrimmedFace,
    Shell or Solid, with every edge shared by its faces built once. No validity check here:
    callers that need one use ``occ._check_valid``."""
    from ..brep import Shell, Solid, TrimmedFace

    BRep, BRepLib, TopAbs, TopoDS, gp = _ocp("BRep", "BRepLib", "TopAbs", "TopoDS", "gp")
    builder = BRep.BRep_Builder()
    FORWARD, REVERSED = TopAbs.TopAbs_Orientation.TopAbs_FORWARD, TopAbs.TopAbs_Orientation.TopAbs_REVERSED
    faces = _faces_of(obj)

    # every edge use: [face, loop, position, Edge, key, (5, 3) points]
    uses = []
    for i, f in enumerate(faces):
        for j, loop in enumerate(f.boundary_loops()):
            for k, e in enumerate(loop):
                uses.append([i, j, k, e, e.key, _use_points(f, e)])
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
    for root, items in points.items():
        P = np.array([p for p, _ in items])
        c = P.mean(axis=0)
        tol = max(max(t for _, t in items), float(np.max(np.linalg.norm(P - c, axis=1))) * 1.001)
        v = TopoDS.TopoDS_Vertex()
        builder.MakeVertex(v, gp.gp_Pnt(*c.tolist()), max(tol, tolerance))
        vertices[root] = v

    # faces (unoriented, FORWARD) first: the pcurves are attached to them
    occ_faces = []
    for f in faces:
        F = TopoDS.TopoDS_Face()
        builder.MakeFace(F, to_occ(f.surface), max(f.tolerance, tolerance))
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
        if curve3d is not None and not degenerate:
            builder.MakeEdge(E, to_occ(curve3d), tol_e)
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


def brep_list_to_shape(objects, *, tolerance: float = 1e-7):
    """A compound of :func:`brep_to_shape` of each object."""
    return _compound([brep_to_shape(o, tolerance=tolerance) for o in objects])
