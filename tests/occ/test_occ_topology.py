"""OCC topology interop: splinekit geometry -> edges, faces, sewn shells and solids,
build123d / cadquery wrappers, and OCC shapes (analytic or not) -> splinekit.

Independent references:

* faces and edges are read back through ``BRep_Tool`` and evaluated by OCC
  itself, then compared with splinekit's evaluation (relative 1e-9 of the net);
* closed bodies: a box of bilinear (and of refined bicubic) patches and a sphere
  of eight rational quadratic octants built by hand; OCC's ``BRepGProp`` volume
  must equal the closed form ``a*b*c`` / ``4/3 pi r^3`` to 1e-6 relative and
  ``BRepCheck_Analyzer`` must accept the solid;
* build123d primitives (analytic planes, cylinders, spheres) converted with
  ``from_occ``: sampled points must satisfy the primitive's implicit equation.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from _geometry import interior_params, random_curve_data, random_surface_data
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineCurve, Geom_Line, Geom_Plane
from OCP.gp import gp_Dir, gp_Lin, gp_Pln, gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopAbs import TopAbs_ShapeEnum
from OCP.TopExp import TopExp_Explorer

import splinekit as sk
from splinekit.errors import BackendError, MissingDependencyError, ParameterError
from splinekit.interop import occ

RATIONAL = pytest.mark.parametrize("rational", [False, True], ids=["poly", "rational"])
EVAL_RTOL = 1e-9
VOLUME_RTOL = 1e-6


# ----------------------------------------------------------------------------------------
# geometry built by hand


def box_patches(a=1.0, b=2.0, c=3.0, outward=True):
    """The six faces of the box [0,a]x[0,b]x[0,c] as bilinear patches.

    With ``outward=True`` every patch has ``Su x Sv`` pointing out of the box.
    """
    P = {(i, j, k): np.array([i * a, j * b, k * c], float) for i in (0, 1) for j in (0, 1) for k in (0, 1)}
    quads = [  # each [[P00, P01], [P10, P11]]: u along the first index, v along the second
        [[P[0, 0, 0], P[1, 0, 0]], [P[0, 1, 0], P[1, 1, 0]]],  # z = 0, normal -z
        [[P[0, 0, 1], P[0, 1, 1]], [P[1, 0, 1], P[1, 1, 1]]],  # z = c, normal +z
        [[P[0, 0, 0], P[0, 0, 1]], [P[1, 0, 0], P[1, 0, 1]]],  # y = 0, normal -y
        [[P[0, 1, 0], P[1, 1, 0]], [P[0, 1, 1], P[1, 1, 1]]],  # y = b, normal +y
        [[P[0, 0, 0], P[0, 1, 0]], [P[0, 0, 1], P[0, 1, 1]]],  # x = 0, normal -x
        [[P[1, 0, 0], P[1, 0, 1]], [P[1, 1, 0], P[1, 1, 1]]],  # x = a, normal +x
    ]
    patches = [sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.array(q)) for q in quads]
    return patches if outward else [p.reverse("u") for p in patches]


def sphere_octants(r=1.0, center=(0.0, 0.0, 0.0)):
    """A sphere as eight rational biquadratic patches (quarter meridian x quarter parallel).

    Each patch is the tensor product of two exact quarter circles (weights 1, sqrt(2)/2, 1);
    the pole row collapses to one point.
    """
    s = math.sqrt(0.5)
    meridian = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # (radius, height), equator -> pole
    parallel = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # quarter of the unit circle
    w = np.array([1.0, s, 1.0])
    out = []
    for zsign in (1.0, -1.0):
        for k in range(4):
            c, sn = math.cos(k * math.pi / 2), math.sin(k * math.pi / 2)
            xy = parallel @ np.array([[c, sn], [-sn, c]])
            P = np.empty((3, 3, 3))
            P[..., 0] = r * meridian[:, 0, None] * xy[None, :, 0]
            P[..., 1] = r * meridian[:, 0, None] * xy[None, :, 1]
            P[..., 2] = r * zsign * meridian[:, 1, None]
            out.append(sk.NurbsSurface(2, 2, [0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1], P + center, np.outer(w, w)))
    return out


def make_surface(rng, rational):
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, max_degree=5, max_spans=3)
    return sk.NurbsSurface(pu, pv, ku, kv, P, W) if rational else sk.BSplineSurface(pu, pv, ku, kv, P)


def make_curve(rng, rational):
    p, U, P, W = random_curve_data(rng, rational, max_degree=6)
    return sk.NurbsCurve(p, U, P, W) if rational else sk.BSplineCurve(p, U, P)


def volume(shape) -> float:
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-10)
    return props.Mass()


def area(shape) -> float:
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, props, 1e-10)
    return props.Mass()


def count(shape, kind) -> int:
    exp, n = TopExp_Explorer(shape, kind), 0
    while exp.More():
        n += 1
        exp.Next()
    return n


# ----------------------------------------------------------------------------------------
# single faces and edges


@RATIONAL
@pytest.mark.parametrize("seed", range(6))
def test_surface_to_face_evaluates_like_splinekit(seed, rational):
    rng = np.random.default_rng([501, seed, rational])
    surf = make_surface(rng, rational)
    face = occ.to_shape(surf)
    assert face.ShapeType() == TopAbs_ShapeEnum.TopAbs_FACE
    assert BRepCheck_Analyzer(face).IsValid()
    (u0, u1), (v0, v1) = surf.domain
    bounds = BRepTools.UVBounds_s(face)
    assert np.allclose(bounds, (u0, u1, v0, v1), rtol=0, atol=1e-12 * max(1.0, np.abs(bounds).max()))
    geom = BRep_Tool.Surface_s(face)
    us = interior_params(rng, surf.knots_u, surf.degree_u, 20)
    vs = interior_params(rng, surf.knots_v, surf.degree_v, 20)
    theirs = np.array([[geom.Value(u, v).X(), geom.Value(u, v).Y(), geom.Value(u, v).Z()] for u, v in zip(us, vs)])
    net = max(1.0, np.abs(surf.control_points).max())
    assert np.abs(surf.evaluate(us, vs) - theirs).max() <= EVAL_RTOL * net


@RATIONAL
@pytest.mark.parametrize("seed", range(6))
def test_curve_to_edge_evaluates_like_splinekit(seed, rational):
    rng = np.random.default_rng([502, seed, rational])
    curve = make_curve(rng, rational)
    edge = occ.to_shape(curve)
    assert edge.ShapeType() == TopAbs_ShapeEnum.TopAbs_EDGE
    first, last = BRep_Tool.Range_s(edge)
    assert (first, last) == pytest.approx(curve.domain, abs=1e-12)
    geom = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    us = interior_params(rng, curve.knots, curve.degree, 20)
    theirs = np.array([[geom.Value(u).X(), geom.Value(u).Y(), geom.Value(u).Z()] for u in us])
    net = max(1.0, np.abs(curve.control_points).max())
    assert np.abs(curve.evaluate(us) - theirs).max() <= EVAL_RTOL * net


# ----------------------------------------------------------------------------------------
# sewn bodies


@pytest.mark.parametrize("outward", [True, False], ids=["outward", "inward"])
def test_box_patches_sew_into_a_valid_outward_solid(outward):
    a, b, c = 1.5, 2.0, 0.75
    solid = occ.to_shape(box_patches(a, b, c, outward))
    assert solid.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert BRepCheck_Analyzer(solid).IsValid()
    assert count(solid, TopAbs_ShapeEnum.TopAbs_FACE) == 6
    # positive whichever way the patches faced: to_shape orients the solid outward
    assert volume(solid) == pytest.approx(a * b * c, rel=VOLUME_RTOL)
    assert area(solid) == pytest.approx(2 * (a * b + b * c + a * c), rel=VOLUME_RTOL)


def test_refined_bicubic_box_sews_into_a_solid():
    a, b, c = 2.0, 1.0, 3.0
    patches = [p.elevate_degree(2, "u").elevate_degree(2, "v").refine([0.3, 0.7], "u").refine([0.5], "v") for p in box_patches(a, b, c)]
    assert all((p.degree_u, p.degree_v) == (3, 3) for p in patches)
    solid = occ.to_shape(patches)
    assert solid.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert BRepCheck_Analyzer(solid).IsValid()
    assert volume(solid) == pytest.approx(a * b * c, rel=VOLUME_RTOL)


@pytest.mark.parametrize("r", [1.0, 2.5])
def test_rational_sphere_octants_sew_into_a_solid(r):
    center = np.array([0.5, -1.0, 2.0])
    patches = sphere_octants(r, center)
    # the hand-built net is the sphere itself (a check of the test geometry, not of OCC)
    t = np.linspace(0, 1, 9)
    uu, vv = (x.ravel() for x in np.meshgrid(t, t))
    for p in patches:
        assert np.abs(np.linalg.norm(p.evaluate(uu, vv) - center, axis=1) - r).max() < 1e-12 * r
    solid = occ.to_shape(patches)
    assert solid.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert BRepCheck_Analyzer(solid).IsValid()
    assert count(solid, TopAbs_ShapeEnum.TopAbs_FACE) == 8
    assert volume(solid) == pytest.approx(4.0 / 3.0 * math.pi * r**3, rel=VOLUME_RTOL)
    assert area(solid) == pytest.approx(4.0 * math.pi * r**2, rel=VOLUME_RTOL)


def test_open_patch_set_gives_a_shell_not_a_solid():
    shell = occ.to_shape(box_patches()[:5])
    assert shell.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL
    assert not BRep_Tool.IsClosed_s(shell)
    assert count(shell, TopAbs_ShapeEnum.TopAbs_FACE) == 5
    single = occ.to_shape(box_patches()[:1])
    assert single.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL


def test_disjoint_patch_sets_give_a_compound_of_pieces():
    far = [p.transform(np.array([[1, 0, 0, 10.0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])) for p in box_patches()]
    shape = occ.to_shape(box_patches() + far[:5])
    assert shape.ShapeType() == TopAbs_ShapeEnum.TopAbs_COMPOUND
    assert count(shape, TopAbs_ShapeEnum.TopAbs_SOLID) == 1
    assert count(shape, TopAbs_ShapeEnum.TopAbs_FACE) == 11
    exp = TopExp_Explorer(shape, TopAbs_ShapeEnum.TopAbs_SOLID)
    assert volume(exp.Current()) == pytest.approx(6.0, rel=VOLUME_RTOL)


def test_invalid_shapes_raise_backend_error_naming_the_problem():
    # a planar face bounded by a wire that leaves its plane: BRepCheck rejects it
    wire = BRepBuilderAPI_MakePolygon(gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0), gp_Pnt(1, 1, 0.5), gp_Pnt(0, 1, 0), True).Wire()
    face = BRepBuilderAPI_MakeFace(gp_Pln(), wire, True).Face()
    with pytest.raises(BackendError, match=r"BRepCheck_Analyzer.*face 0: BRepCheck_"):
        occ._check_valid(face, "test face")


# ----------------------------------------------------------------------------------------
# build123d and cadquery


def test_build123d_and_cadquery_wrappers_report_the_same_volume():
    import build123d as bd
    import cadquery as cq

    r = 1.25
    expected = 4.0 / 3.0 * math.pi * r**3
    solid = occ.to_build123d(sphere_octants(r))
    assert isinstance(solid, bd.Solid) and solid.is_valid
    assert solid.volume == pytest.approx(expected, rel=VOLUME_RTOL)
    cq_solid = occ.to_cadquery(sphere_octants(r))
    assert isinstance(cq_solid, cq.Solid) and cq_solid.isValid()
    assert cq_solid.Volume() == pytest.approx(expected, rel=VOLUME_RTOL)
    wp = occ.to_cadquery(box_patches(), workplane=True)
    assert isinstance(wp, cq.Workplane)
    assert wp.val().Volume() == pytest.approx(6.0, rel=VOLUME_RTOL)
    # and they mean the same body as the raw OCC shape
    assert volume(solid.wrapped) == pytest.approx(expected, rel=VOLUME_RTOL)


def test_wrapper_types_follow_the_input():
    import build123d as bd
    import cadquery as cq

    rng = np.random.default_rng(503)
    assert isinstance(occ.to_build123d(make_curve(rng, True)), bd.Edge)
    assert isinstance(occ.to_build123d(make_surface(rng, False)), bd.Face)
    assert isinstance(occ.to_build123d(box_patches()[:3]), bd.Shell)
    assert isinstance(occ.to_cadquery(make_curve(rng, False)), cq.Edge)
    assert isinstance(occ.to_cadquery(make_surface(rng, True)), cq.Face)
    assert isinstance(occ.to_cadquery(box_patches()[:3]), cq.Shell)
    # and back: a cadquery Workplane and a build123d ShapeList are accepted by from_occ
    wp = occ.to_cadquery(box_patches(), workplane=True)
    assert len(occ.from_occ(wp, surfaces=True)) == 6
    assert len(occ.from_occ(occ.to_build123d(box_patches()).faces(), surfaces=True)) == 6
    # by default they come back as B-rep objects: one closed solid, six separate faces
    (solid,) = occ.from_occ(wp)
    assert isinstance(solid, sk.brep.Solid) and len(solid.faces) == 6
    assert len(occ.from_occ(occ.to_build123d(box_patches()).faces())) == 6


# ----------------------------------------------------------------------------------------
# OCC -> splinekit


def _sample(surface, n=25):
    (u0, u1), (v0, v1) = surface.domain
    uu, vv = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n))
    return surface.evaluate(uu.ravel(), vv.ravel())


def test_from_occ_sphere_primitive_lies_on_the_sphere():
    import build123d as bd

    r, c = 2.0, np.array([1.0, 2.0, 3.0])
    surfaces = sk.occ.from_occ(bd.Pos(*c) * bd.Sphere(r), surfaces=True)
    assert len(surfaces) == 1
    (s,) = surfaces
    assert isinstance(s, sk.NurbsSurface)
    pts = _sample(s)
    assert np.abs(np.linalg.norm(pts - c, axis=1) - r).max() < 1e-9
    # the whole sphere is covered: poles and the equator are reached
    assert pts[:, 2].min() == pytest.approx(c[2] - r, abs=1e-9)
    assert pts[:, 2].max() == pytest.approx(c[2] + r, abs=1e-9)


def test_from_occ_cylinder_primitive_lies_on_the_cylinder():
    import build123d as bd

    r, h = 1.5, 4.0
    surfaces = sk.occ.from_occ(bd.Cylinder(r, h), surfaces=True)
    assert len(surfaces) == 3
    lateral = [s for s in surfaces if np.ptp(_sample(s)[:, 2]) > 1e-9]
    assert len(lateral) == 1
    pts = _sample(lateral[0])
    assert np.abs(np.hypot(pts[:, 0], pts[:, 1]) - r).max() < 1e-9
    assert pts[:, 2].min() == pytest.approx(-h / 2, abs=1e-12) and pts[:, 2].max() == pytest.approx(h / 2, abs=1e-12)
    for cap in (s for s in surfaces if s is not lateral[0]):
        # the caps come back as their planes' UV bounding squares (trimming loops are not kept)
        z = _sample(cap)[:, 2]
        assert np.ptp(z) < 1e-12 and abs(abs(z[0]) - h / 2) < 1e-12


def test_from_occ_box_primitive_gives_its_six_planes():
    import build123d as bd

    a, b, c = 1.0, 2.0, 3.0
    surfaces = sk.occ.from_occ(bd.Box(a, b, c), surfaces=True)
    assert len(surfaces) == 6 and all(isinstance(s, sk.BSplineSurface) for s in surfaces)
    half = np.array([a, b, c]) / 2
    faces_hit = set()
    for s in surfaces:
        pts = _sample(s, 7)
        assert np.all(np.abs(pts) <= half + 1e-12)
        on = np.isclose(np.abs(pts), half, rtol=0, atol=1e-12).all(axis=0)  # the axis this face is flat in
        assert on.sum() == 1
        axis = int(np.argmax(on))
        faces_hit.add((axis, float(np.sign(pts[0, axis]))))
    assert len(faces_hit) == 6


def test_from_occ_edges_and_wires():
    import build123d as bd

    circle = sk.occ.from_occ(bd.Edge.make_circle(2.0))
    assert isinstance(circle, sk.NurbsCurve)
    pts = circle.evaluate(np.linspace(*circle.domain, 101))
    assert np.abs(np.linalg.norm(pts, axis=1) - 2.0).max() < 1e-12
    assert np.allclose(pts[0], pts[-1], atol=1e-12)  # the whole circle
    edges = sk.occ.from_occ(bd.Box(1, 1, 1).edges())
    assert len(edges) == 12 and all(isinstance(e, sk.BSplineCurve) and e.degree == 1 for e in edges)
    lengths = [np.linalg.norm(e.control_points[-1] - e.control_points[0]) for e in edges]
    assert np.allclose(lengths, 1.0, atol=1e-12)


def test_from_occ_of_a_compound_gives_faces_then_only_the_free_edges():
    import build123d as bd

    # a box (6 faces, 12 edges that bound them) with a loose segment and a loose two-segment wire
    loose = [((5.0, 0.0, 0.0), (6.0, 1.0, 2.0)), ((0.0, 0.0, 9.0), (1.0, 0.0, 9.0)), ((1.0, 0.0, 9.0), (1.0, 3.0, 9.0))]
    wire = bd.Wire([bd.Edge.make_line(*loose[1]), bd.Edge.make_line(*loose[2])])
    shapes = occ.from_occ(bd.Compound(children=[bd.Box(1, 2, 3), bd.Edge.make_line(*loose[0]), wire]), surfaces=True)
    assert len(shapes) == 6 + 3
    assert all(isinstance(s, sk.BSplineSurface) for s in shapes[:6])
    ends = sorted(
        tuple(map(tuple, np.round(c.evaluate(np.array(c.domain)), 12))) for c in shapes[6:]
    )
    assert ends == sorted(loose)


def test_from_occ_round_trips_faces_and_edges_exactly():
    rng = np.random.default_rng(504)
    for rational in (False, True):
        surf = make_surface(rng, rational)
        back = occ.from_occ(occ.to_shape(surf), surfaces=True)
        assert back.almost_equal(surf, 1e-14)
        curve = make_curve(rng, rational)
        back = occ.from_occ(occ.to_build123d(curve))
        assert back.almost_equal(curve, 1e-14)


def test_from_occ_unperiodizes_periodic_bsplines():
    # a periodic cubic through 6 poles, built directly in OCC
    angles = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    P = np.c_[np.cos(angles), np.sin(angles), 0.3 * np.sin(2 * angles)]
    poles = TColgp_Array1OfPnt(1, 6)
    for i, x in enumerate(P):
        poles.SetValue(i + 1, gp_Pnt(*x))
    knots, mults = TColStd_Array1OfReal(1, 7), TColStd_Array1OfInteger(1, 7)
    for i in range(7):
        knots.SetValue(i + 1, float(i))
        mults.SetValue(i + 1, 1)
    handle = Geom_BSplineCurve(poles, knots, mults, 3, True)
    assert handle.IsPeriodic()
    curve = occ.from_occ(handle)
    assert handle.IsPeriodic()  # the caller's handle is untouched
    a, b = curve.domain
    assert (a, b) == pytest.approx((handle.FirstParameter(), handle.LastParameter()), abs=1e-12)
    assert np.all(curve.knots[: curve.degree + 1] == a) and np.all(curve.knots[-curve.degree - 1 :] == b)  # clamped
    us = np.linspace(a, b, 37)
    theirs = np.array([[handle.Value(u).X(), handle.Value(u).Y(), handle.Value(u).Z()] for u in us])
    assert np.abs(curve.evaluate(us) - theirs).max() < 1e-12


def test_from_occ_oriented_surfaces_point_outward():
    center = np.array([0.5, 1.0, 1.5])
    solid = occ.to_shape(box_patches(outward=False))
    for oriented, sign in ((True, 1.0), (False, -1.0)):
        for s in occ.from_occ(solid, oriented=oriented, surfaces=True):
            n = s.normal(np.array([0.5]), np.array([0.5]))[0]
            p = s.evaluate(np.array([0.5]), np.array([0.5]))[0]
            assert sign * np.dot(n, p - center) > 0


# ----------------------------------------------------------------------------------------
# bad input


def test_bad_input_to_shape():
    rng = np.random.default_rng(505)
    with pytest.raises(ParameterError, match="dim=2"):
        occ.to_shape(sk.BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [1, 1]]))
    with pytest.raises(ParameterError, match="str"):
        occ.to_shape("box")
    with pytest.raises(ParameterError, match="empty"):
        occ.to_shape([])
    with pytest.raises(ParameterError, match="patch 1 is a BSplineCurve"):
        occ.to_shape([make_surface(rng, False), make_curve(rng, False)])
    for bad in (0.0, -1e-7, float("nan"), "x"):
        with pytest.raises(ParameterError, match="tolerance"):
            occ.to_shape(make_surface(rng, False), tolerance=bad)
    with pytest.raises(ParameterError):
        occ.to_build123d(object())


def test_bad_input_from_occ():
    with pytest.raises(ParameterError, match="unbounded surface Geom_Plane"):
        occ.from_occ(Geom_Plane(gp_Pln()))
    with pytest.raises(ParameterError, match="unbounded curve Geom_Line"):
        occ.from_occ(Geom_Line(gp_Lin(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0))))
    with pytest.raises(ParameterError, match="object"):
        occ.from_occ(object())
    with pytest.raises(ParameterError, match="item 1"):
        occ.from_occ([occ.to_shape(box_patches()[0]), 3])
    from OCP.TopoDS import TopoDS_Shape

    with pytest.raises(ParameterError, match="null"):
        occ.from_occ(TopoDS_Shape())
    # topology without bounds: an infinite planar face and an infinite straight edge
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge

    with pytest.raises(ParameterError, match="unbounded face"):
        occ.from_occ(BRepBuilderAPI_MakeFace(gp_Pln()).Face())
    with pytest.raises(ParameterError, match="unbounded edge"):
        occ.from_occ(BRepBuilderAPI_MakeEdge(gp_Lin(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0))).Edge())
    for flag in ("yes", 1, None):
        with pytest.raises(ParameterError, match="oriented must be True or False"):
            occ.from_occ(occ.to_shape(box_patches()[0]), oriented=flag)
        with pytest.raises(ParameterError, match="workplane must be True or False"):
            occ.to_cadquery(box_patches()[0], workplane=flag)


def test_missing_ocp_names_the_package(monkeypatch):
    surf = box_patches()[0]
    monkeypatch.setitem(sys.modules, "OCP", None)
    for call in (lambda: occ.to_shape(surf), lambda: occ.to_build123d([surf]), lambda: occ.from_occ(object())):
        with pytest.raises(MissingDependencyError, match="pip install .*cadquery.*build123d"):
            call()
