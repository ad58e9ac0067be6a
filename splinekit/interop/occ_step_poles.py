"""Pole edges of a B-rep shape prepared for OpenCascade's STEP writer.

STEP has no degenerated edges. OCC's writer leaves them out of a face's loops, and where what is
left of a loop is only seam edges (a sphere's outer loop: seam, north pole, seam back, south pole)
it writes the loop as a single VERTEX_LOOP at one pole (TopoDSToStep_MakeStepWire, written for
whole spheres). Its reader turns a VERTEX_LOOP back into the surface's natural bounds only when it
is the face's one bound; beside other loops (a sphere with a hole, or cut by a plane, keeping both
poles) it makes a lone degenerated edge with no pcurve, and on a B-spline surface the shape
healing that follows rebuilds the face wrongly: a sphere cut by two planes came back with four
faces and three edges instead of three and six (OCC's own write and read of the NURBS-converted
shape does the same; on its analytic sphere the reader copes).

:func:`pole_edges_as_points` gives each degenerated edge of such a loop a 3-D curve of zero length
at its vertex and clears its degenerated flag, so the writer keeps the loop as an EDGE_LOOP of its
seam and these point edges. The reader drops an edge of zero length whose two ends are one vertex
(StepToTopoDS_TranslateEdge, "NULL EDGE, SKIPPED") and puts a degenerated edge back where the
loop's seam ends meet at a pole (ShapeFix_Wire::FixDegenerated), as it does for any pole edge.
"""

from __future__ import annotations

from .occ_backend import _ocp
from .occ_shapes import _sub_shapes

__all__ = ["pole_edges_as_points"]


def _seam_only_loops(face):
    """The wires of ``face`` (one with more than one wire) whose edges are degenerated edges and
    seam edges (two pcurves on ``face``) only, with at least one of each: the loops OCC's STEP
    writer would write as a VERTEX_LOOP beside the others."""
    (BRep,) = _ocp("BRep")
    tool = BRep.BRep_Tool
    wires = _sub_shapes(face, "WIRE")
    if len(wires) < 2:
        return []
    out = []
    for wire in wires:
        edges = _sub_shapes(wire, "EDGE")
        degenerate = [e for e in edges if tool.Degenerated_s(e)]
        seams = [e for e in edges if not tool.Degenerated_s(e)]
        if degenerate and seams and all(tool.IsClosed_s(e, face) for e in seams):
            out.append(degenerate)
    return out


def pole_edges_as_points(shape) -> int:
    """Give each degenerated edge of a seam-only loop (see :func:`_seam_only_loops`) of every face
    of ``shape`` a degree-1 B-spline 3-D curve with both poles at its vertex, on the edge's
    parameter range, and clear its degenerated flag; returns how many edges changed.

    ``shape`` is changed in place (its edges are shared with every copy of it): call this on a
    shape built for writing only, never on one a caller owns."""
    BRep, Geom, TColgp, TColStd, TopExp = _ocp("BRep", "Geom", "TColgp", "TColStd", "TopExp")
    tool, builder = BRep.BRep_Tool, BRep.BRep_Builder()
    changed = 0
    for face in _sub_shapes(shape, "FACE"):
        for edges in _seam_only_loops(face):
            for edge in edges:
                point = tool.Pnt_s(TopExp.TopExp.FirstVertex_s(edge))
                first, last = tool.Range_s(edge)
                poles = TColgp.TColgp_Array1OfPnt(1, 2)
                poles.SetValue(1, point)
                poles.SetValue(2, point)
                knots, mults = TColStd.TColStd_Array1OfReal(1, 2), TColStd.TColStd_Array1OfInteger(1, 2)
                knots.SetValue(1, first)
                knots.SetValue(2, last)
                mults.SetValue(1, 2)
                mults.SetValue(2, 2)
                builder.Degenerated(edge, False)
                builder.UpdateEdge(edge, Geom.Geom_BSplineCurve(poles, knots, mults, 1), tool.Tolerance_s(edge))
                builder.Range(edge, first, last)
                changed += 1
    return changed
