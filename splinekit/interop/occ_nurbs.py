"""An OCC shape re-expressed in B-splines (``BRepBuilderAPI_NurbsConvert``), on a copy prepared
so that the conversion is exact: faces on periodic analytic surfaces are first turned so their u
range starts at 0 (:func:`_normalized_copy`)."""

from __future__ import annotations

from ..errors import BackendError
from .occ_backend import _ocp, _occ_call, require_ocp
from .occ_shapes import _sub_shapes


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
