"""B-rep topology of splinekit's primitives: vertex, edge and face counts against OCC's (TopExp) on the
same primitives built by build123d.
"""

from __future__ import annotations

import pytest
from test_brep_topology import _counts

from splinekit.brep import box, box_with_hole, cone, cylinder, sphere, torus


def _occ_counts(shape):
    """Vertices, non-degenerate edges and faces of an OCC shape, counted by OCC."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedMapOfShape

    out = []
    for kind in (TopAbs_VERTEX, TopAbs_EDGE, TopAbs_FACE):
        m = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(shape, kind, m)
        if kind == TopAbs_EDGE:
            out.append(sum(not BRep_Tool.Degenerated_s(TopoDS.Edge_s(m.FindKey(i))) for i in range(1, m.Extent() + 1)))
        else:
            out.append(m.Extent())
    return tuple(out)


def test_counts_match_occ_primitives():
    bd = pytest.importorskip("build123d")
    pairs = [
        (box(20, 20, 20), bd.Box(20, 20, 20)),
        (cylinder(4, 20), bd.Cylinder(4, 20)),
        (cone(4, 2, 5), bd.Cone(4, 2, 5)),
        (cone(4, 0, 5), bd.Cone(4, 0, 5)),
        (sphere(3), bd.Sphere(3)),
        (torus(5, 1.5), bd.Torus(5, 1.5)),
        (box_with_hole(20, 4), bd.Box(20, 20, 20) - bd.Cylinder(4, 20)),
    ]
    for ours, theirs in pairs:
        assert _counts(ours) == _occ_counts(theirs.wrapped), ours.name
