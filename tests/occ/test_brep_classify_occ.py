"""Point classification of B-rep solids (Solid.contains) against OpenCascade's
BRepClass3d_SolidClassifier on the same solids built by build123d.
"""

from __future__ import annotations

import numpy as np
import pytest

from splinekit.brep import box_with_hole, cone, sphere, torus
from splinekit.brep.classify import INSIDE, ON, OUTSIDE


def test_solid_contains_agrees_with_occ_classifier():
    bd = pytest.importorskip("build123d")
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN, TopAbs_ON, TopAbs_OUT

    pairs = [
        (box_with_hole(20.0, 4.0), bd.Box(20, 20, 20) - bd.Cylinder(4, 20), 11.0),
        (torus(5.0, 1.5), bd.Torus(5, 1.5), 7.0),
        (cone(4.0, 1.0, 6.0, origin=(0, 0, -3)), bd.Cone(4, 1, 6), 5.0),
        (sphere(3.0), bd.Sphere(3), 4.0),
    ]
    rng = np.random.default_rng(5)
    code = {TopAbs_IN: INSIDE, TopAbs_OUT: OUTSIDE, TopAbs_ON: ON}
    for ours, theirs, half in pairs:
        p = rng.uniform(-half, half, (400, 3))
        occ = []
        for x, y, z in p:
            c = BRepClass3d_SolidClassifier(theirs.wrapped, gp_Pnt(float(x), float(y), float(z)), 1e-7)
            occ.append(code[c.State()])
        occ = np.array(occ)
        assert np.array_equal(ours.contains(p), occ), ours.name


def test_solid_contains_on_a_filleted_box_from_occ():
    """26 faces (planes, cylinders, sphere corners) converted from OCC: points spread over the
    box, many of them in the rounded corners' and edges' regions, classified as OCC does."""
    bd = pytest.importorskip("build123d")
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN, TopAbs_ON, TopAbs_OUT

    from splinekit.interop.occ_brep import brep_from_shape

    b = bd.Box(10, 10, 10)
    shape = b.fillet(2, b.edges())
    solid = brep_from_shape(shape.wrapped)
    rng = np.random.default_rng(6)
    p = rng.uniform(-5.2, 5.2, (300, 3))
    p[:150] = np.sign(p[:150]) * rng.uniform(3.0, 5.2, (150, 3))  # corner regions: the fillets' spheres
    code = {TopAbs_IN: INSIDE, TopAbs_OUT: OUTSIDE, TopAbs_ON: ON}
    occ = np.array([code[BRepClass3d_SolidClassifier(shape.wrapped, gp_Pnt(*map(float, q)), 1e-7).State()] for q in p])
    assert np.array_equal(solid.contains(p), occ)
    assert (occ == INSIDE).sum() > 50 and (occ == OUTSIDE).sum() > 50
