"""OpenCascade topology -> splinekit B-rep: TopoDS faces, shells and solids read as
:class:`~splinekit.brep.TrimmedFace`, :class:`~splinekit.brep.Shell` and :class:`~splinekit.brep.Solid`.

Planes, B-spline and Bézier faces, and cylinders, cones, spheres and tori whose pcurves are
isolines, are converted natively and exactly (:mod:`.occ_native_faces`); a circular edge then gets
a rational parameter shared by all its faces. The other faces are re-expressed together with
``BRepBuilderAPI_NurbsConvert`` on a copy (:mod:`.occ_nurbs`), which turns an analytic surface AND
its pcurves into B-splines consistently (an analytic surface converted alone gets a rational
parametrization that is not the angle, so the pcurves would no longer map onto it). Each face is
read with FORWARD orientation so its pcurves keep the material on their left; the face's own
orientation becomes ``reversed``. Every edge use keeps its pcurve, its 3-D curve on the same
parameter range and a ``key``: the edge's index in one ``TopTools_IndexedMapOfShape`` of the
whole shape, so the two faces of an edge share it; a pcurve that follows its 3-D curve at another
parameter is put onto the curve's parameter (:mod:`.occ_same_parameter`).
"""

from __future__ import annotations

import numpy as np

from ..brep import Edge, Shell, Solid, TrimmedFace
from ..curves import BSplineCurve, NurbsCurve
from ..curves.batch import CurveBatch
from ..errors import BackendError, ParameterError
from .occ_backend import _ocp, _occ_call, require_ocp
from .occ_geometry import _curve2d_from_occ, _curve3d_from_occ, _edge_to_curve, _from_geom, _same_domain
from .occ_native_faces import native_faces, native_surface, native_use
from .occ_nurbs import _nurbs_converted
from .occ_same_parameter import same_parameter
from .occ_shapes import _children, _sub_shapes

__all__ = ["brep_from_shape"]


class _Reader:
    """Reads the faces of an OCC shape natively or through their NURBS-converted twins, walked in
    parallel.

    The converted copy gives every surface as a B-spline and, where the original geometry is
    analytic, the pcurves and 3-D curves re-expressed on it. Where the original is already
    B-spline, Bézier, a plane or a line (face surface, pcurve and 3-D curve alike), the original
    pcurve and 3-D curve are kept: they are exact, share the converted edge's parameter, and
    OCC's conversion re-approximates some of them (on files with loose tolerances the
    re-approximated pcurves can even cross each other). Edge keys are indices in one
    ``TopTools_IndexedMapOfShape`` of the original shape.
    """

    def __init__(self, edge_map, converted=frozenset()):
        self.edge_map = edge_map  # TopTools_IndexedMapOfShape of the shape's edges: their keys
        self.converted = converted  # keys of the circular edges read on OCC's parameter
        self.curves: dict = {}  # (edge key, native) -> 3-D curve in the edge's own direction
        self.native_curves: dict = {}  # edge key -> 3-D curve of a natively read edge (a rational arc if circular)

    def face(self, face, conv, index: int, name=None, plan=None):
        """The TrimmedFace of the original ``face``: read through its converted twin ``conv``, or
        natively by ``plan`` (:func:`.occ_native_faces.face_plan`), or both: a native plane or
        B-spline face reads its edges in ``self.converted`` from its twin."""
        BRep, BRepTools, TopAbs, TopExp, TopoDS = _ocp("BRep", "BRepTools", "TopAbs", "TopExp", "TopoDS")
        orient = TopAbs.TopAbs_Orientation
        reversed_ = face.Orientation() == orient.TopAbs_REVERSED
        fwd = TopoDS.TopoDS.Face_s(face.Oriented(orient.TopAbs_FORWARD))
        cfwd = None if conv is None else TopoDS.TopoDS.Face_s(conv.Oriented(orient.TopAbs_FORWARD))
        native_face = _native_surface(fwd)
        tol_face = max(BRep.BRep_Tool.Tolerance_s(fwd), 1e-7)
        outer = BRepTools.BRepTools.OuterWire_s(fwd)
        loops = []
        wires = TopExp.TopExp_Explorer(fwd, TopAbs.TopAbs_ShapeEnum.TopAbs_WIRE)
        cwires = None if cfwd is None else TopExp.TopExp_Explorer(cfwd, TopAbs.TopAbs_ShapeEnum.TopAbs_WIRE)
        while wires.More() and (cwires is None or cwires.More()):
            wire = TopoDS.TopoDS.Wire_s(wires.Current())
            # the wire's stored edges, original and converted, pair up in order; the wire explorer
            # (which follows the loop, in an order that depends on hashing) runs on the original only
            stored = _children(wire)
            twins = None if cwires is None else _children(cwires.Current())
            if twins is not None and len(stored) != len(twins):
                raise BackendError(f"face {index}: the NURBS-converted wire does not match the original")
            edges = []
            walk = BRepTools.BRepTools_WireExplorer(wire, fwd)
            while walk.More():
                e = walk.Current()
                walk.Next()
                if plan is not None and (twins is None or self.edge_map.FindIndex(e) not in self.converted):
                    edges.append(self._native_use(e, fwd, plan))
                    continue
                j = next((j for j, x in enumerate(stored) if x.IsEqual(e)), None)
                if j is None:
                    j = next(j for j, x in enumerate(stored) if x.IsSame(e))
                twin = TopoDS.TopoDS.Edge_s(twins[j].Oriented(e.Orientation()))
                edges.append(self._edge_use(e, fwd, twin, cfwd, native_face, index))
            _add_loop(loops, edges, wire.IsSame(outer))
            wires.Next()
            if cwires is not None:
                cwires.Next()
        if not loops:
            raise BackendError(f"face {index}: OpenCascade gives it no wire (an unbounded face cannot be converted)")
        if plan is None or plan.kind == "spline":
            uv = _loop_samples(loops)
            surface = self._surface(fwd if plan is not None else cfwd, index, uv.min(axis=0), uv.max(axis=0))
        else:  # a rational pcurve lies in its control points' hull: the plane's box holds it whole
            P = np.concatenate([np.asarray(e.pcurve.control_points) for lp in loops for e in lp])
            lo, hi = P.min(axis=0), P.max(axis=0)
            if plan.kind == "plane" and not (hi - lo > 1e-12 * max(1.0, float(np.abs(P).max()))).all():
                raise BackendError(f"face {index}: its edges bound no area (their (u, v) box is {lo.tolist()} to {hi.tolist()})")
            surface = native_surface(plan, (lo, hi))
        loops = same_parameter(surface, loops)
        return TrimmedFace(surface, loops, reversed=reversed_, tolerance=tol_face, name=name)

    def _native_use(self, edge, fwd, plan):
        """The Edge of one use of ``edge`` (as the wire holds it) on a natively converted face."""
        BRep, TopAbs, TopExp = _ocp("BRep", "TopAbs", "TopExp")
        tool = BRep.BRep_Tool
        key = self.edge_map.FindIndex(edge)
        degenerate = bool(tool.Degenerated_s(edge))
        pcurve, curve = native_use(edge, fwd, plan, self.native_curves, key)
        if curve is not None and not _same_domain(curve.domain, pcurve.domain):
            curve = None  # not SameRange: keep the trim only, the 3-D curve is rebuilt on export
        ends = [TopExp.TopExp.FirstVertex_s(edge), TopExp.TopExp.LastVertex_s(edge)]
        tolerance = max([tool.Tolerance_s(edge), 1e-7] + [tool.Tolerance_s(v) for v in ends if not v.IsNull()])
        use = Edge(pcurve, curve, key=key, degenerate=degenerate, tolerance=tolerance)
        return use.reversed() if edge.Orientation() == TopAbs.TopAbs_Orientation.TopAbs_REVERSED else use

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

    def _edge_use(self, edge, fwd, cedge, cfwd, native_face, index):
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


def _add_loop(loops: list, edges: list, outer: bool) -> None:
    """Add the loop ``edges`` (closed at its poles) to ``loops``, the outer loop first."""
    if edges:
        _close_at_poles(edges)
        loops.insert(0, edges) if outer else loops.append(edges)


def _loop_samples(loops) -> np.ndarray:
    """``(n, 2)`` points of every pcurve of a face's ``loops``: 17 each, evenly spread over its
    domain (the pcurves evaluated as one :class:`~splinekit.curves.batch.CurveBatch`)."""
    pcurves = [e.pcurve for lp in loops for e in lp]
    batch = CurveBatch(pcurves)
    t = np.linspace(batch.domains[:, 0], batch.domains[:, 1], 17, axis=1).ravel()
    return batch.evaluate(np.repeat(np.arange(len(pcurves)), 17), t)


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


def brep_from_shape(shape, *, name=None, on_error=None):
    """splinekit B-rep objects for the OCC ``shape``.

    A face gives a TrimmedFace, a shell a Shell, a solid a Solid; a compound (or compsolid) gives
    a list of its solids, shells, faces and free curves, in OCC's order (nested compounds
    flattened). ``name`` labels the returned object(s).

    A face that cannot be converted raises BackendError naming it (``face i``: its number in
    reading order). With ``on_error(index, message)`` given instead, the face is left out and
    reported through the callback; a solid that lost faces comes back as its shells (open).
    """
    TopAbs, TopoDS, BRepTools, TopExp, TopTools = _ocp("TopAbs", "TopoDS", "BRepTools", "TopExp", "TopTools")
    for face in _sub_shapes(shape, "FACE"):
        bounds = BRepTools.BRepTools.UVBounds_s(face)
        if not all(abs(x) < 1e100 for x in bounds):  # OCC's "infinite" is 2e100
            raise ParameterError(f"cannot convert an unbounded face (UV bounds {list(bounds)}): bound it with edges first")
    faces, edges = TopTools.TopTools_IndexedMapOfShape(), TopTools.TopTools_IndexedMapOfShape()
    TopExp.TopExp.MapShapes_s(shape, TopAbs.TopAbs_ShapeEnum.TopAbs_FACE, faces)
    TopExp.TopExp.MapShapes_s(shape, TopAbs.TopAbs_ShapeEnum.TopAbs_EDGE, edges)
    plans, converted, mixed = native_faces(shape, faces, edges)
    try:
        twins = _converted_twins(faces, [i for i in range(1, faces.Extent() + 1) if i not in plans or i in mixed])
    except BackendError as exc:
        return _unconvertible(shape, exc, name, on_error)
    reader = _Reader(edges, converted)
    kinds = TopAbs.TopAbs_ShapeEnum
    counter = iter(range(1 << 62))  # face numbers in error messages, in reading order
    BRepClass3d = _ocp("BRepClass3d")[0]

    def children(s, kind=None):
        """The children (or the ``kind`` sub-shapes, orientations composed) of ``s``."""
        if kind is None:
            return _children(s)
        out, explorer = [], TopExp.TopExp_Explorer(s, kind)
        while explorer.More():
            out.append(explorer.Current())
            explorer.Next()
        return out

    lost = []  # faces left out (on_error given)

    def face(s, label=None):
        index = next(counter)
        try:
            i = faces.FindIndex(s)
            return reader.face(TopoDS.TopoDS.Face_s(s), twins.get(i), index, label, plans.get(i))
        except Exception as exc:  # SplineKitError, or an OCC Standard_Failure (no common base)
            message = str(exc) if isinstance(exc, BackendError) else f"face {index}: {type(exc).__name__}: {exc}"
            if on_error is None:
                raise BackendError(message) from None
            on_error(index, message)
            lost.append(index)
            return None

    def shell(s, label=None):
        # faces explored with their orientations composed with the shell's (and solid's)
        got = [f for f in (face(f) for f in children(s, kinds.TopAbs_FACE)) if f is not None]
        return Shell(got, name=label) if got else None

    def solid(s):
        outer = BRepClass3d.BRepClass3d.OuterShell_s(TopoDS.TopoDS.Solid_s(s))
        shells, before = [], len(lost)
        for sh in children(s, kinds.TopAbs_SHELL):
            if outer is not None and not outer.IsNull() and sh.IsSame(outer):
                shells.insert(0, shell(sh, name))
            else:
                shells.append(shell(sh, name))
        if len(lost) > before:  # faces were left out: the shells no longer close
            return [x for x in shells if x is not None]
        if not shells:
            raise BackendError("the OCC solid has no shell")
        return [Solid(shells, name=name)]

    def convert(s):
        kind = s.ShapeType()
        if kind == kinds.TopAbs_FACE:
            return [x for x in [face(s, name)] if x is not None]
        if kind == kinds.TopAbs_SHELL:
            return [x for x in [shell(s, name)] if x is not None]
        if kind == kinds.TopAbs_SOLID:
            return solid(s)
        if kind in (kinds.TopAbs_EDGE, kinds.TopAbs_WIRE):
            curves = (_edge_to_curve(e) for e in _sub_shapes(s, "EDGE"))
            return [cv for cv in curves if cv is not None]
        if kind in (kinds.TopAbs_COMPOUND, kinds.TopAbs_COMPSOLID):
            return [item for child in children(s) for item in convert(child)]
        return []  # vertices

    out = convert(shape)
    if on_error is None and shape.ShapeType() in (kinds.TopAbs_FACE, kinds.TopAbs_SHELL, kinds.TopAbs_SOLID):
        return out[0]
    return out


def _converted_twins(faces, indices) -> dict:
    """``{index: converted face}`` for the faces (indices in the ``TopTools_IndexedMapOfShape``
    ``faces``) that are left to OCC's NURBS conversion, converted together in one compound so
    that the edges they share stay shared."""
    if not indices:
        return {}
    BRep, TopoDS = _ocp("BRep", "TopoDS")
    builder, compound = BRep.BRep_Builder(), TopoDS.TopoDS_Compound()
    builder.MakeCompound(compound)
    for i in indices:
        builder.Add(compound, faces.FindKey(i))
    converted = _children(_nurbs_converted(compound))
    if len(converted) != len(indices):
        raise BackendError("the NURBS-converted faces do not match the originals")
    return dict(zip(indices, converted))


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
