"""The fast B-rep tessellation path against OpenCascade: no more triangles than BRepMesh at the
same measured deviation, and build123d parts (fast, general and mixed) closed and within tolerance.

OCC meshes the same exact solid (``splinekit.occ.to_occ``: the same surfaces and pcurves, so its
triangles' (u, v) are in splinekit's parameters); both meshes are measured with the same code
(the surface at the barycentric (u, v) of every triangle's centre and edge midpoints against the
flat point), and OCC's linear deflection is lowered until its deviation is at most splinekit's.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_tessellation_brep import measured_deviation
from test_tessellation_fast import _check

import splinekit as sk
from splinekit.brep import primitives


def _occ_mesh(shape, deflection, faces):
    """``(triangles, measured deviation)`` of BRepMesh on ``shape`` (its faces in the order of
    ``faces``, as to_occ builds them), angular deflection 0.5 rad as splinekit's default."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedMapOfShape

    BRepTools.Clean_s(shape)
    BRepMesh_IncrementalMesh(shape, deflection, False, 0.5, False)
    fmap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, fmap)
    assert fmap.Extent() == len(faces)
    worst, count = 0.0, 0
    bary = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])
    for k in range(1, fmap.Extent() + 1):
        tri = BRep_Tool.Triangulation_s(TopoDS.Face_s(fmap.FindKey(k)), TopLoc_Location())
        xyz = np.array([[tri.Node(i).X(), tri.Node(i).Y(), tri.Node(i).Z()] for i in range(1, tri.NbNodes() + 1)])
        uv = np.array([[tri.UVNode(i).X(), tri.UVNode(i).Y()] for i in range(1, tri.NbNodes() + 1)])
        T = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)]) - 1
        s = faces[k - 1].surface
        (u0, u1), (v0, v1) = s.domain
        q = np.clip(np.einsum("bj,tjd->tbd", bary, uv[T]).reshape(-1, 2), [u0, v0], [u1, v1])
        flat = np.einsum("bj,tjd->tbd", bary, xyz[T]).reshape(-1, 3)
        worst = max(worst, float(np.linalg.norm(s.evaluate(q[:, 0], q[:, 1]) - flat, axis=1).max()))
        count += len(T)
    return count, worst


def occ_triangles_at(solid, ours, floor=0.0):
    """BRepMesh's triangle count on ``solid`` once its measured deviation is at most ``ours``:
    OCC's deflection starts at ``max(2 ours, floor)`` and is lowered until it gets there."""
    shape = sk.occ.to_occ(solid)
    deflection = max(2.0 * ours, floor)
    for _ in range(12):
        count, theirs = _occ_mesh(shape, deflection, solid.faces)
        if theirs <= ours * (1 + 1e-9):
            return count
        deflection *= 0.7
    pytest.fail(f"BRepMesh did not reach splinekit's deviation {ours:.3g}")


def _z_filleted_plate():
    # planes and quarter cylinders only (the vertical edges rounded), and two through holes
    bd = pytest.importorskip("build123d")
    from splinekit.interop.occ_brep import brep_from_shape

    plate = bd.Box(40, 30, 5) - bd.Pos(5, 3, 0) * bd.Cylinder(4, 5) - bd.Pos(-8, -6, 0) * bd.Cylinder(2, 5)
    part = bd.fillet(plate.edges().filter_by(bd.Axis.Z), 3)
    got = brep_from_shape(part.wrapped)
    return got[0] if isinstance(got, list) else got


PARTS = {
    "z-filleted plate with holes": _z_filleted_plate,
    "box_with_hole": lambda: primitives.box_with_hole(20.0, 4.0),
    "plate_with_holes": lambda: primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4), (28, 20, 5), (33, 8, 2.5)]),
    "cylinder": lambda: primitives.cylinder(1.0, 3.0),
    "box": lambda: primitives.box(20.0, 30.0, 10.0),
}


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4])
@pytest.mark.parametrize("name", sorted(PARTS))
def test_no_more_triangles_than_brepmesh_at_equal_deviation(name, rel):
    solid = PARTS[name]()
    mesh = sk.tessellate(solid, rel, relative=True)
    assert solid.faces[0]._cache["tessellate"].memo.get("fast") is not None
    # (planes: rounding only, so both are compared at the model's rounding level)
    ours = max(measured_deviation(mesh, solid.faces), 1e-9 * mesh.tolerance / rel)
    # (OCC refuses deflections under 1e-7)
    assert mesh.n_faces <= occ_triangles_at(solid, ours, floor=1e-6 * mesh.tolerance / rel)


def _b123d(name):
    bd = pytest.importorskip("build123d")
    from splinekit.interop.occ_brep import brep_from_shape

    part = {
        "box - cylinder": lambda: bd.Box(20, 20, 20) - bd.Cylinder(4, 20),
        "filleted box": lambda: bd.fillet(bd.Box(20, 20, 20).edges(), 3),
        "chamfered block": lambda: bd.chamfer(bd.Box(20, 20, 20).edges(), 3),
        "z-filleted box": lambda: bd.fillet(bd.Box(30, 20, 10).edges().filter_by(bd.Axis.Z), 4),
    }[name]()
    got = brep_from_shape(part.wrapped)
    return (got[0] if isinstance(got, list) else got), part


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-4])
@pytest.mark.parametrize(("name", "fast"), [("box - cylinder", True), ("chamfered block", True), ("z-filleted box", True),
                                            ("filleted box", True)])  # fmt: skip
def test_build123d_parts_closed_within_tolerance(name, fast, rel):
    # the filleted box mixes planes with cylinder fillets and sphere corners (faces of
    # revolution: latitude strips); the others are planes and cylinders
    solid, part = _b123d(name)
    mesh = sk.tessellate(solid, rel, relative=True)
    assert (solid.faces[0]._cache["tessellate"].memo.get("fast") is not None) == fast
    assert mesh.is_closed and mesh.euler_characteristic == (0 if name == "box - cylinder" else 2)
    assert measured_deviation(mesh, solid.faces) <= mesh.tolerance * (1 + 1e-9)
    if name == "box - cylinder":
        volume, area = 20**3 - math.pi * 16 * 20, 6 * 400 + 2 * math.pi * 4 * 20 - 2 * math.pi * 16
    else:
        volume, area = part.volume, part.area
    assert 0 < mesh.volume and abs(mesh.volume - volume) <= area * mesh.tolerance
    if fast:  # every guarantee, against the faces' own evaluators and normals
        _check(solid, mesh, volume, area)


def _stepped_block_with_hole():
    """A block 20 x 20 x 20 whose top half is two boxes fused without merging their faces, with
    a through hole of radius 4 on the seam between them: the hole's top circle is cut into two
    arcs where the top faces meet, its bottom circle only at the seam, so the cylinder's two
    circles are sampled at different angles (the strip must merge two unrelated chains)."""
    bd = pytest.importorskip("build123d")
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse

    from splinekit.interop.occ_brep import brep_from_shape

    base = bd.Box(20, 20, 10, align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MAX))
    left = bd.Box(10, 20, 10, align=(bd.Align.MAX, bd.Align.CENTER, bd.Align.MIN))
    right = bd.Box(10, 20, 10, align=(bd.Align.MIN, bd.Align.CENTER, bd.Align.MIN))
    top = BRepAlgoAPI_Fuse(left.wrapped, right.wrapped)
    top.Build()
    block = BRepAlgoAPI_Fuse(top.Shape(), base.wrapped)
    block.Build()
    cut = BRepAlgoAPI_Cut(block.Shape(), bd.Cylinder(4, 20).wrapped)
    cut.Build()
    got = brep_from_shape(cut.Shape())
    return got[0] if isinstance(got, list) else got


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4])
def test_fast_path_merges_circles_cut_differently(rel):
    solid = _stepped_block_with_hole()
    mesh = sk.tessellate(solid, rel, relative=True)
    assert solid.faces[0]._cache["tessellate"].memo.get("fast") is not None
    # the hole's wall: its bottom and top rows of vertices are at different angles
    hole = [i for i, f in enumerate(solid.faces) if np.ptp(f.surface.control_points[..., 2]) > 15
            and np.ptp(f.surface.control_points[..., 0]) < 9]  # fmt: skip
    assert len(hole) == 1
    uv = mesh.corner_uv[mesh.face_patch == hole[0]].reshape(-1, 2)
    v0, v1 = uv[:, 1].min(), uv[:, 1].max()
    rows = [np.unique(np.round(uv[np.isclose(uv[:, 1], v), 0], 9)) for v in (v0, v1)]
    assert len(np.intersect1d(*rows)) < min(len(r) for r in rows) - 2
    volume = 20**3 - math.pi * 16 * 20
    area = 6 * 400 + 2 * math.pi * 4 * 20 - 2 * math.pi * 16
    _check(solid, mesh, volume, area)
    assert mesh.euler_characteristic == 0
