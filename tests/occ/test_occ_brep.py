"""OCC topology <-> splinekit B-rep (splinekit.interop.occ_brep through from_occ / to_occ).

Every figure is checked against OpenCascade on the ORIGINAL (analytic) shape: its TopExp
face/edge/vertex counts, its face normals (BRepGProp_Face, which applies the face orientation),
its 3-D edge curves (point projection) and its GProp area and volume; the rebuilt shape must
pass BRepCheck_Analyzer.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")
bd = pytest.importorskip("build123d")

import splinekit as sk  # noqa: E402
from splinekit.brep import Shell, Solid, TrimmedFace  # noqa: E402
from splinekit.interop import occ  # noqa: E402

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepGProp import BRepGProp, BRepGProp_Face  # noqa: E402
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve, GeomAPI_ProjectPointOnSurf  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.TopAbs import TopAbs_ShapeEnum  # noqa: E402
from OCP.TopExp import TopExp, TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402
from OCP.TopTools import TopTools_IndexedMapOfShape  # noqa: E402
from OCP.gp import gp_Pnt, gp_Vec  # noqa: E402


def _parts():
    profile = bd.Polygon((1, 0), (3, 0), (3, 2), (2, 3), (1, 2), align=None).rotate(bd.Axis.X, 90)
    return {
        "box minus cylinder": bd.Box(20, 20, 20) - bd.Cylinder(4, 20),
        "filleted box": bd.fillet(bd.Box(10, 10, 10).edges(), 1),
        "chamfered block": bd.chamfer(bd.Box(10, 8, 6).edges(), 1),
        "sphere": bd.Pos(1, 2, 3) * bd.Sphere(3),
        "torus": bd.Torus(5, 1),
        "revolved": bd.revolve(profile, bd.Axis.Z),
        "lofted": bd.loft([bd.Circle(3).face(), bd.Pos(0, 0, 5) * bd.Rectangle(4, 4).face(),
                           bd.Pos(0, 0, 10) * bd.Circle(2).face()]),
    }


PARTS = _parts()


def _map(shape, kind):
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, getattr(TopAbs_ShapeEnum, f"TopAbs_{kind}"), m)
    return m


def _counts(shape):
    return tuple(_map(shape, k).Extent() for k in ("FACE", "EDGE", "VERTEX"))


def _gprop(shape, kind, eps):
    p = GProp_GProps()
    getattr(BRepGProp, f"{kind}Properties_s")(shape, p, eps)
    return p.Mass()


def _faces_in_order(shape):
    out, ex = [], TopExp_Explorer(shape, TopAbs_ShapeEnum.TopAbs_FACE)
    while ex.More():
        out.append(TopoDS.Face_s(ex.Current()))
        ex.Next()
    return out


def _solid_of(part):
    got = occ.from_occ(part)
    if isinstance(got, list):
        assert len(got) == 1
        got = got[0]
    assert isinstance(got, Solid)
    return got


@pytest.mark.parametrize("name", list(PARTS))
def test_from_occ_keeps_counts_trims_and_orientation(name):
    shape = PARTS[name].wrapped
    solid = _solid_of(PARTS[name])
    n_faces, n_edges, _ = _counts(shape)
    assert len(solid.faces) == n_faces
    keys = {e.key for f in solid.faces for e in f.edges}
    assert len(keys) == n_edges and None not in keys
    # a closed solid: every edge has two uses (a seam's two are on one face), a pole one
    uses: dict = {}
    for f in solid.faces:
        for e in f.edges:
            uses.setdefault(e.key, []).append(e.degenerate)
    assert all(len(v) == (1 if v[0] else 2) for v in uses.values())

    edge_map = _map(shape, "EDGE")
    for face, occ_face in zip(solid.faces, _faces_in_order(shape)):
        surf = BRep_Tool.Surface_s(occ_face)
        props = BRepGProp_Face(occ_face)
        for e in face.edges:
            a, b = e.domain
            t = a + (b - a) * np.array([0.1, 0.37, 0.5, 0.81])
            uv = e.pcurve.evaluate(t)
            pts = face.surface.evaluate(uv[:, 0], uv[:, 1])
            # the pcurve maps onto OCC's own 3-D edge
            if not e.degenerate:
                occ_edge = TopoDS.Edge_s(edge_map.FindKey(e.key))
                curve, f0, f1 = BRep_Tool.Curve_s(occ_edge, 0.0, 0.0), *BRep_Tool.Range_s(occ_edge)
                for p in pts:
                    d = GeomAPI_ProjectPointOnCurve(gp_Pnt(*p), curve, f0, f1).LowerDistance()
                    assert d < 1e-7, (name, e.key, d)
                assert e.curve is not None
                assert np.abs(e.curve.evaluate(t) - pts).max() < 1e-7  # same parameter as the pcurve
            # our outward normal agrees with OCC's (BRepGProp_Face applies the face orientation)
            inside = uv + 1e-3 * (b - a) * np.c_[-e.pcurve.derivatives(t, 1)[1][:, 1], e.pcurve.derivatives(t, 1)[1][:, 0]]
            ours = face.normals(inside[:, 0], inside[:, 1])
            q = face.surface.evaluate(inside[:, 0], inside[:, 1])
            for p, n in zip(q, ours):
                if not np.any(n):
                    continue
                uu, vv = GeomAPI_ProjectPointOnSurf(gp_Pnt(*p), surf).LowerDistanceParameters()
                P, N = gp_Pnt(), gp_Vec()
                props.Normal(uu, vv, P, N)
                if N.Magnitude() < 1e-9:
                    continue
                theirs = np.array([N.X(), N.Y(), N.Z()]) / N.Magnitude()
                assert np.dot(theirs, n) > 0.99, (name, face)


@pytest.mark.parametrize("name", list(PARTS))
def test_to_occ_round_trip_is_valid_with_the_same_counts_area_and_volume(name):
    shape = PARTS[name].wrapped
    solid = _solid_of(PARTS[name])
    back = occ.to_occ(solid)
    assert back.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert BRepCheck_Analyzer(back).IsValid()
    assert _counts(back) == _counts(shape)
    # OCC's GProp on the analytic original vs on our B-spline solid: GProp itself drifts by about
    # 1e-9 on rational B-spline faces at precision 1e-12 (measured), so the bound is 3e-9
    for kind in ("Volume", "Surface"):
        ref, ours = _gprop(shape, kind, 1e-12), _gprop(back, kind, 1e-12)
        assert ours == pytest.approx(ref, rel=3e-9), kind
    assert isinstance(occ.to_build123d(solid), bd.Solid)
    import cadquery as cq

    assert isinstance(occ.to_cadquery(solid), cq.Solid)


def test_round_trip_is_exact_against_occs_own_nurbs_form():
    # to_occ(from_occ(x)) rebuilds exactly the NURBS form OCC makes of x: bit-equal volumes
    from splinekit.interop.occ_brep import _nurbs_converted

    shape = PARTS["filleted box"].wrapped
    back = occ.to_occ(_solid_of(PARTS["filleted box"]))
    assert _gprop(back, "Volume", 1e-10) == pytest.approx(_gprop(_nurbs_converted(shape), "Volume", 1e-10), rel=1e-14)


def test_faces_and_shells_round_trip():
    solid = _solid_of(PARTS["box minus cylinder"])
    top = next(f for f in solid.faces if len(f.loops) == 2)  # a face with a hole
    assert len(top.inner_loops) == 1
    face = occ.to_occ(top)
    assert face.ShapeType() == TopAbs_ShapeEnum.TopAbs_FACE and BRepCheck_Analyzer(face).IsValid()
    assert _gprop(face, "Surface", 1e-12) == pytest.approx(400 - np.pi * 16, rel=1e-12)
    flipped = occ.to_occ(top.flipped())
    assert flipped.Orientation() != face.Orientation()
    back = occ.from_occ(face)
    assert isinstance(back, TrimmedFace) and back.reversed == top.reversed and len(back.loops) == 2
    assert isinstance(occ.to_build123d(top), bd.Face)
    # an open shell: five faces of a box
    shell = Shell(solid.faces[:-1])
    occ_shell = occ.to_occ(shell)
    assert occ_shell.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL and BRepCheck_Analyzer(occ_shell).IsValid()
    assert isinstance(occ.from_occ(occ_shell), Shell)


def test_edges_without_keys_are_paired_geometrically():
    shape = PARTS["filleted box"].wrapped
    solid = _solid_of(PARTS["filleted box"])
    keyless = Solid(Shell([TrimmedFace(f.surface, [[e.with_key(None) for e in lp] for lp in f.loops], f.reversed)
                           for f in solid.faces]))
    back = occ.to_occ(keyless)
    assert BRepCheck_Analyzer(back).IsValid()
    assert _counts(back) == _counts(shape)
    assert _gprop(back, "Volume", 1e-10) == pytest.approx(_gprop(occ.to_occ(solid), "Volume", 1e-10), rel=1e-12)


def test_compounds_give_lists():
    got = occ.from_occ(bd.Compound(children=[bd.Box(1, 1, 1), bd.Pos(3, 0, 0) * bd.Sphere(1)]))
    assert [type(g) for g in got] == [Solid, Solid]
    compound = occ.to_shape(got)
    assert compound.ShapeType() == TopAbs_ShapeEnum.TopAbs_COMPOUND
    assert _map(compound, "SOLID").Extent() == 2


def test_invalid_brep_is_refused():
    from splinekit.errors import SplineKitError

    solid = _solid_of(PARTS["chamfered block"])
    f = solid.faces[0]
    # shrink one face's outer loop inside the face: the rebuilt solid no longer closes
    (u0, u1), (v0, v1) = f.domain
    c = np.array([u0 + u1, v0 + v1]) / 2
    shrink = np.array([[0.9, 0, 0.1 * c[0]], [0, 0.9, 0.1 * c[1]], [0, 0, 1]])
    moved = [[sk.brep.Edge(e.pcurve.transform(shrink), key=e.key) for e in f.loops[0]]]
    bad = Solid(Shell([TrimmedFace(f.surface, moved, f.reversed)] + list(solid.faces[1:])))
    with pytest.raises(SplineKitError, match="BRepCheck"):
        occ.to_occ(bad)
