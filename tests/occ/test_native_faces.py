"""Faces read natively (planes, cylinders, cones, spheres, tori in exact rational form, their
pcurves carried over exactly) against OCC's own geometry and GProp: surface points, face areas,
volumes and face counts, on build123d solids and on the foreign STEP files.

The angle maps are checked against the closed forms of the circle: the rational arc at
``Psi(theta)`` must be ``(cos theta, sin theta)``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("OCP")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepTools import BRepTools  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE  # noqa: E402
from OCP.TopExp import TopExp  # noqa: E402
from OCP.TopTools import TopTools_IndexedMapOfShape  # noqa: E402

from exporters.step import read_step_shape  # noqa: E402
from splinekit.interop.gprop import occ_area, occ_volume  # noqa: E402
from splinekit.interop.occ_analytic import AngleMap, edge_arc, mapped_isoline  # noqa: E402
from splinekit.interop.occ_brep_read import brep_from_shape  # noqa: E402
from splinekit.interop.occ_native_faces import face_plan, native_faces  # noqa: E402
from splinekit.interop.occ_shapes import _sub_shapes  # noqa: E402

STEP_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "step"


@settings(max_examples=60, deadline=None)
@given(st.floats(-10.0, 10.0), st.floats(0.05, 2 * math.pi), st.floats(0.0, 1.0))
def test_rational_arc_at_the_mapped_angle_is_the_circle(start, sweep, frac):
    m = AngleMap(start, start + sweep)
    theta = start + frac * sweep
    t = m(np.array([theta]))
    assert m.inverse(t)[0] == pytest.approx(theta, abs=1e-12 * max(1.0, abs(theta)))
    arc = edge_arc([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], m.start, m.end)
    np.testing.assert_allclose(arc.evaluate(t)[0], [math.cos(theta), math.sin(theta)], rtol=0, atol=1e-14)
    np.testing.assert_allclose(m(m.knots), m.knots, rtol=0, atol=1e-13 * max(1.0, abs(start) + sweep))


@settings(max_examples=60, deadline=None)
@given(st.floats(-4.0, 4.0), st.sampled_from([1.0, -1.0]), st.floats(-3.0, 3.0), st.floats(0.1, 6.2), st.floats(0.0, 1.0))
def test_isoline_pcurve_is_the_composed_angle_map(c, sigma, a, sweep, frac):
    """The pcurve in the edge's new parameter s equals Psi_face(c + sigma Psi_edge^-1(s))."""
    b = a + sweep
    edge_map = AngleMap(a, b)
    angles = np.sort([c + sigma * a, c + sigma * b])
    face_map = AngleMap(angles[0] - 0.3, angles[1] + 0.2)  # the face reaches past the edge
    pc = mapped_isoline(0, c, sigma, 7.0, (a, b), face_map, edge_map)
    s = np.array([a + frac * sweep])
    expected = face_map(c + sigma * edge_map.inverse(s))
    got = pc.evaluate(s)[0]
    assert got[1] == pytest.approx(7.0, rel=1e-15)  # the constant coordinate, up to the rational rounding
    assert got[0] == pytest.approx(expected[0], abs=1e-12 * max(1.0, abs(expected[0])))


def _plans(shape):
    """``(faces map, plans of the faces read natively)`` of an OCC shape."""
    faces, edges = TopTools_IndexedMapOfShape(), TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
    return faces, native_faces(shape, faces, edges)[0]


def _filleted_box(bd):
    box = bd.Box(30, 20, 10)
    return bd.fillet(box.edges(), 3)


def _parts():
    bd = pytest.importorskip("build123d")
    return {
        "box with a hole": lambda: bd.Box(20, 20, 20) - bd.Cylinder(4, 20),
        "sphere": lambda: bd.Sphere(7),
        "torus": lambda: bd.Torus(10, 3),
        "cone": lambda: bd.Cone(6, 2, 9),
        "filleted box": lambda: _filleted_box(bd),
        "cut sphere": lambda: bd.Sphere(8) - bd.Box(20, 20, 20, align=(bd.Align.MIN, bd.Align.CENTER, bd.Align.CENTER)),
    }


@pytest.mark.parametrize("name", ["box with a hole", "sphere", "torus", "cone", "filleted box", "cut sphere"])
def test_native_faces_agree_with_occ_face_by_face(name):
    shape = _parts()[name]().wrapped
    faces, plans = _plans(shape)
    assert len(plans) == faces.Extent(), "every face of these parts converts natively"
    got = brep_from_shape(shape)
    (solid,) = got if isinstance(got, list) else [got]
    occ_faces = _sub_shapes(shape, "FACE")
    assert len(solid.faces) == len(occ_faces)
    assert solid.check() == []
    rng = np.random.default_rng(1)
    for ours, theirs in zip(solid.faces, occ_faces):
        # area of the trimmed face: splinekit's integrator on the rational form vs OCC's GProp on
        # the original analytic face, both at raised precision
        assert ours.area(1e-12) == pytest.approx(occ_area(theirs, 1e-12), rel=1e-9)
        # the surface: OCC's point at (u, v) is ours at the mapped parameters
        plan = face_plan(theirs)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(theirs)
        uv = np.column_stack([rng.uniform(u0, u1, 20), rng.uniform(v0, v1, 20)])
        surf = BRep_Tool.Surface_s(theirs)
        expected = np.array([[p.X(), p.Y(), p.Z()] for p in (surf.Value(float(u), float(v)) for u, v in uv)])
        mapped = plan.map_uv(uv)
        got = ours.surface.evaluate(mapped[:, 0], mapped[:, 1])
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * max(1.0, float(np.abs(expected).max())))
    assert solid.volume(1e-12) == pytest.approx(occ_volume(shape, 1e-12), rel=1e-9)


_FILES = ["catiav4_4solids_sphere_torus_cone.stp", "euclid_screw.step", "sw2013_two_spheres.stp", "ug19_io1_analytic.stp"]


@pytest.mark.parametrize("name", _FILES)
def test_foreign_natively_read_faces_match_occ_areas(name):
    """Each face the reader converted natively has OCC's area (GProp at 1e-12 on the file's own
    face) to 1e-9; the face count is the file's."""
    if not (STEP_DIR / "reference.json").exists():
        pytest.skip(f"{STEP_DIR} is absent")
    ref = json.loads((STEP_DIR / "reference.json").read_text())[name]
    shape = read_step_shape(STEP_DIR / name, isolated=False)
    faces, plans = _plans(shape)
    got = brep_from_shape(shape)
    got = got if isinstance(got, list) else [got]
    ours = [f for obj in got for f in (obj.faces if hasattr(obj, "faces") else [obj])]
    assert len(ours) == faces.Extent() == ref["faces"]
    assert plans, "some faces convert natively"
    for i, f in enumerate(ours, 1):
        if i in plans:
            assert f.area(1e-12) == pytest.approx(occ_area(faces.FindKey(i), 1e-12), rel=1e-9), i
