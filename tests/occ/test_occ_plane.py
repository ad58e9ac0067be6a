"""Affine patches are written as OCC planes (splinekit.interop.occ_plane through to_occ / export_step).

Independent references: closed-form areas and volumes of the faces and solids, OCC's own evaluation
of the plane and of its pcurves (``Geom_Plane.Value``, ``BRepAdaptor_Curve(edge, face)``) against
splinekit's patch at the same (u, v), and BRepCheck_Analyzer.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")
bd = pytest.importorskip("build123d")

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import splinekit as sk  # noqa: E402
from exporters import export_step, import_step  # noqa: E402
from splinekit.brep import Solid, TrimmedFace  # noqa: E402
from splinekit.interop import occ  # noqa: E402
from splinekit.interop import occ_brep_write  # noqa: E402
from splinekit.interop.occ_plane import plane_frame, plane_to_occ  # noqa: E402

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepAdaptor import BRepAdaptor_Curve  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.Geom import Geom_Plane  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.STEPControl import STEPControl_Reader  # noqa: E402
from OCP.TopAbs import TopAbs_Orientation, TopAbs_ShapeEnum  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402


def _faces(shape):
    out, ex = [], TopExp_Explorer(shape, TopAbs_ShapeEnum.TopAbs_FACE)
    while ex.More():
        out.append(TopoDS.Face_s(ex.Current()))
        ex.Next()
    return out


def _edges(shape):
    out, ex = [], TopExp_Explorer(shape, TopAbs_ShapeEnum.TopAbs_EDGE)
    while ex.More():
        out.append(TopoDS.Edge_s(ex.Current()))
        ex.Next()
    return out


def _gprop(shape, kind, eps=1e-12):
    p = GProp_GProps()
    getattr(BRepGProp, f"{kind}Properties_s")(shape, p, eps)
    return p.Mass()


def _is_plane(face):
    return isinstance(BRep_Tool.Surface_s(face), Geom_Plane)


def _box_with_hole():
    (got,) = occ.from_occ(bd.Box(20, 20, 20) - bd.Cylinder(4, 20))  # a compound: a list
    assert isinstance(got, Solid)
    return got


def _planar_areas(shape):
    return sorted(_gprop(f, "Surface") for f in _faces(shape) if _is_plane(f))


HOLE_AREAS = sorted([400.0 - 16 * np.pi] * 2 + [400.0] * 4)  # two faces with the hole, four walls
HOLE_VOLUME = 8000.0 - 320.0 * np.pi


def test_box_with_a_hole_has_planes_with_exact_areas_and_volume(monkeypatch):
    solid = _box_with_hole()
    shape = occ.to_occ(solid)
    assert BRepCheck_Analyzer(shape).IsValid()
    assert sum(_is_plane(f) for f in _faces(shape)) == 6
    assert _planar_areas(shape) == pytest.approx(HOLE_AREAS, rel=1e-12)
    # the cylinder is a rational B-spline face, on which OCC's GProp drifts by about 1e-9
    assert _gprop(shape, "Volume") == pytest.approx(HOLE_VOLUME, rel=3e-9)
    # the same solid with its planes written as bilinear B-spline patches: nothing else changed
    monkeypatch.setattr(occ_brep_write, "plane_frame", lambda surface: None)
    as_splines = occ.to_occ(solid)
    assert not any(_is_plane(f) for f in _faces(as_splines))
    for kind in ("Surface", "Volume"):
        assert _gprop(shape, kind) == pytest.approx(_gprop(as_splines, kind), rel=1e-12)


def test_box_with_a_hole_is_written_to_step_with_planes(tmp_path):
    solid = _box_with_hole()
    path = tmp_path / "box.step"
    export_step(path, [solid])
    reader = STEPControl_Reader()
    reader.ReadFile(str(path))
    reader.TransferRoots()
    read = reader.OneShape()
    assert BRepCheck_Analyzer(read).IsValid()
    assert sum(_is_plane(f) for f in _faces(read)) == 6
    assert _planar_areas(read) == pytest.approx(HOLE_AREAS, rel=1e-12)
    ours = occ.to_occ(solid)
    for kind in ("Surface", "Volume"):
        assert _gprop(read, kind) == pytest.approx(_gprop(ours, kind), rel=1e-12)
    # and splinekit reads it back with the same counts, area and volume
    (item,) = import_step(path)
    again = occ.to_occ(item.geometry)
    assert [len(x) for x in (_faces(again), _edges(again))] == [len(x) for x in (_faces(ours), _edges(ours))]
    for kind in ("Surface", "Volume"):
        assert _gprop(again, kind) == pytest.approx(_gprop(ours, kind), rel=1e-12)


def _affine_patch(origin, a, b, u_range, v_range):
    """The patch ``origin + u a + v b`` over ``u_range`` x ``v_range`` as one bilinear span."""
    (u0, u1), (v0, v1) = u_range, v_range
    O, A, B = (np.asarray(x, dtype=float) for x in (origin, a, b))
    P = np.array([[O + u * A + v * B for v in (v0, v1)] for u in (u0, u1)])
    return sk.BSplineSurface(1, 1, [u0, u0, u1, u1], [v0, v0, v1, v1], P)


def _circle_2d(center, radius):
    c = sk.circle([center[0], center[1], 0.0], [0.0, 0.0, 1.0], radius)
    return sk.NurbsCurve(c.degree, c.knots, np.asarray(c.control_points)[:, :2], c.weights)


@pytest.mark.parametrize("reversed_", [False, True])
def test_sheared_patch_maps_its_pcurves_exactly(reversed_):
    # a sheared, scaled patch whose parameter starts away from 0: a disc in (u, v) is an ellipse
    a, b = np.array([2.0, 0.5, 0.0]), np.array([0.7, 3.0, 0.0])
    surface = _affine_patch([1.0, -2.0, 5.0], a, b, (2.0, 5.0), (-1.0, 3.0))
    face = TrimmedFace(surface, [[_circle_2d((3.5, 1.0), 1.2)]], reversed_)
    frame = plane_frame(surface)
    assert frame is not None and frame.matrix is not None
    shape = TopoDS.Face_s(occ.to_occ(face))
    assert _is_plane(shape) and BRepCheck_Analyzer(shape).IsValid()
    # closed form: the disc's area times the patch's area element |a x b|
    assert _gprop(shape, "Surface") == pytest.approx(np.pi * 1.2**2 * np.linalg.norm(np.cross(a, b)), rel=1e-12)
    # OCC's pcurve on the plane lands where splinekit's pcurve lands on the patch
    (edge,) = _edges(shape)
    pcurve = face.loops[0][0].pcurve
    on_face = BRepAdaptor_Curve(edge, shape)
    t = np.linspace(*pcurve.domain, 41)
    got = np.array([[p.X(), p.Y(), p.Z()] for p in (on_face.Value(float(x)) for x in t)])
    uv = pcurve.evaluate(t)
    assert np.abs(got - surface.evaluate(uv[:, 0], uv[:, 1])).max() <= 1e-12 * 10
    # the plane's normal is the patch's, so orientation is kept
    normal = BRep_Tool.Surface_s(shape).Pln().Axis().Direction()
    assert np.dot([normal.X(), normal.Y(), normal.Z()], np.cross(a, b)) > 0
    assert (shape.Orientation() == TopAbs_Orientation.TopAbs_REVERSED) == reversed_
    assert occ.from_occ(shape).reversed == reversed_


def test_only_affine_3d_patches_are_planes():
    flat = _affine_patch([0, 0, 0], [1, 0, 0], [0, 1, 0], (0.0, 1.0), (0.0, 1.0))
    assert plane_frame(flat).matrix is None  # already the plane's orthonormal parameter
    P = np.array(flat.control_points)
    P[1, 1, 2] = 1e-3  # a twisted bilinear patch: a hyperbolic paraboloid
    assert plane_frame(sk.BSplineSurface(1, 1, flat.knots_u, flat.knots_v, P)) is None
    assert plane_frame(flat.elevate_degree(direction="u")) is None  # not one bilinear span
    collapsed = _affine_patch([0, 0, 0], [1, 0, 0], [2, 0, 0], (0.0, 1.0), (0.0, 1.0))
    assert plane_frame(collapsed) is None  # a line, not a plane
    flat2d = sk.BSplineSurface(1, 1, flat.knots_u, flat.knots_v, P[:, :, :2])
    assert plane_frame(flat2d) is None


_coord = st.floats(-100, 100, allow_nan=False)
_vec = st.tuples(_coord, _coord, _coord)


@settings(max_examples=60, deadline=None)
@given(origin=_vec, a=_vec, b=_vec, u0=st.floats(-50, 50), v0=st.floats(-50, 50),
       du=st.floats(0.1, 20), dv=st.floats(0.1, 20), s=st.floats(0, 1), t=st.floats(0, 1))
def test_plane_is_the_patch_at_the_mapped_parameter(origin, a, b, u0, v0, du, dv, s, t):
    a, b = np.array(a), np.array(b)
    la, lb = np.linalg.norm(a), np.linalg.norm(b)
    if min(la, lb) < 1e-2 or np.linalg.norm(np.cross(a, b)) < 1e-3 * la * lb:
        return  # (nearly) collapsed or parallel: no plane
    surface = _affine_patch(origin, a, b, (u0, u0 + du), (v0, v0 + dv))
    frame = plane_frame(surface)
    assert frame is not None
    u, v = u0 + s * du, v0 + t * dv
    M = np.eye(2) if frame.matrix is None else frame.matrix
    x, y = M @ [u, v]
    p = plane_to_occ(frame).Value(float(x), float(y))
    size = np.abs(np.asarray(surface.control_points)).max() + 1.0
    assert np.abs(np.array([p.X(), p.Y(), p.Z()]) - surface.evaluate(u, v)).max() <= 1e-12 * size


def test_rectangles_on_planes_are_untrimmed_faces():
    # a face on an unbounded surface is trimmed unless its wire runs along its (u, v) box
    from splinekit.interop.gprop import trimmed_face_count

    assert trimmed_face_count(bd.Box(10, 10, 10).wrapped) == 0
    assert trimmed_face_count(bd.Face(bd.Wire.make_polygon([(0, 0, 0), (4, 0, 0), (0, 3, 0)])).wrapped) == 1
    # build123d's own box with a hole (planes and an infinite cylinder) and ours agree
    part = bd.Box(20, 20, 20) - bd.Cylinder(4, 20)
    assert trimmed_face_count(part.wrapped) == trimmed_face_count(occ.to_occ(_box_with_hole())) == 2
