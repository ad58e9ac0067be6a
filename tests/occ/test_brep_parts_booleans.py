"""Exact booleans and blends of B-rep solids (``splinekit.brep.fuse/cut/common/fillet/chamfer``,
through OCC) and the manifold3d mesh path on solids.

References are closed forms (volumes and areas by hand), OCC's own verdict on the result
(``BRepCheck_Analyzer`` on the solid converted back to OCC) and, for the mesh path, the exact
result with the tessellation's error bound. Volumes and areas of the results are splinekit's
adaptive integrals. The operands are splinekit's native primitives converted to B-spline faces,
so OCC approximates the intersection edges (within 1e-7): results on curved faces agree with the
closed forms to about 1e-8 relative, not to rounding.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.TopAbs import TopAbs_ShapeEnum

import splinekit as sk
from splinekit import brep
from splinekit.errors import BackendError, ParameterError, SplineKitError
from splinekit.interop import blends, exact_booleans

EXACT = 1e-8  # relative: intersection edges of B-spline faces are OCC approximations
ROUNDING = 1e-10  # relative: planar results, limited only by the integrator's requested tolerance


def assert_valid_trimmed(solid, n_faces=None):
    """A Solid that OCC calls valid once converted back, with trimming loops on its faces."""
    assert isinstance(solid, brep.Solid)
    shape = sk.occ.to_occ(solid)
    assert shape.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert BRepCheck_Analyzer(shape).IsValid()
    assert all(face.loops for face in solid.faces)  # every face bounded by its trims
    if n_faces is not None:
        assert len(solid.faces) == n_faces


def rel(a, b):
    return abs(a - b) / abs(b)


@pytest.fixture(scope="module")
def cube():
    """The cube [-10, 10]^3."""
    return brep.box(20.0, 20.0, 20.0, origin=(-10.0, -10.0, -10.0))


@pytest.fixture(scope="module")
def drilled(cube):
    """The cube minus a through cylinder of radius 4 along z (longer than the cube)."""
    return brep.cut(cube, brep.cylinder(4.0, 30.0, origin=(0.0, 0.0, -15.0)))


# -- closed forms -------------------------------------------------------------------------------


def test_box_minus_through_cylinder(drilled):
    assert_valid_trimmed(drilled, 7)  # 6 planes (top and bottom with a hole loop) + the hole's wall
    assert rel(drilled.volume(), 20**3 - math.pi * 4**2 * 20) < EXACT
    assert rel(drilled.area(), 6 * 400 - 2 * math.pi * 16 + 2 * math.pi * 4 * 20) < EXACT
    holed = [f for f in drilled.faces if len(f.loops) == 2]
    assert len(holed) == 2  # the top and the bottom carry the hole as an inner loop
    # the native primitive of the same part agrees
    assert rel(drilled.volume(), brep.box_with_hole(20.0, 4.0).volume()) < EXACT


def test_fuse_overlapping_boxes():
    a = brep.box(20.0, 20.0, 20.0)
    b = brep.box(20.0, 20.0, 20.0, origin=(10.0, 5.0, 0.0))
    out = brep.fuse(a, b)
    # the union's cross-section: two 20 x 20 squares overlapping in 10 x 15, an 8-sided outline
    section, perimeter = 400 + 400 - 150, 80 + 80 - 2 * (10 + 15)
    assert_valid_trimmed(out, 2 + 8)  # coplanar pieces merged: top, bottom and 8 sides
    assert rel(out.volume(), section * 20) < ROUNDING
    assert rel(out.area(), 2 * section + perimeter * 20) < ROUNDING
    unmerged = brep.fuse(a, b, simplify=False)
    assert len(unmerged.faces) > 10 and rel(unmerged.volume(), section * 20) < ROUNDING


def test_common_sphere_and_box(cube):
    R, h = 12.0, 2.0  # the sphere pokes out of each face of the cube by a cap of height 2
    out = brep.common(brep.sphere(R), cube)
    assert_valid_trimmed(out)
    assert sum(1 for f in out.faces if f.loops and len(f.loops) == 1) >= 6  # six disks cut from the planes
    cap_volume = math.pi * h * h * (3 * R - h) / 3
    assert rel(out.volume(), 4 / 3 * math.pi * R**3 - 6 * cap_volume) < EXACT
    disk = math.pi * (R * R - (R - h) ** 2)
    assert rel(out.area(), 4 * math.pi * R * R - 6 * 2 * math.pi * R * h + 6 * disk) < EXACT


def test_several_tools_in_one_run(cube):
    drills = [brep.cylinder(2.0, 30.0, origin=(x, y, -15.0)) for x, y in ((-5, -5), (5, -5), (0, 5))]
    out = brep.cut(cube, drills)
    assert_valid_trimmed(out, 6 + 3)
    assert rel(out.volume(), 8000 - 3 * math.pi * 4 * 20) < EXACT
    stacked = brep.fuse(brep.box(10.0, 10.0, 10.0), [brep.box(10.0, 10.0, 10.0, origin=(0, 0, z)) for z in (10, 20)])
    assert_valid_trimmed(stacked, 6)
    assert rel(stacked.volume(), 3000) < ROUNDING


def test_filleted_and_chamfered_box(cube):
    r, a = 2.0, 16.0  # every edge rounded: the Minkowski sum of a 16-cube and a ball of radius 2
    out = brep.fillet(cube, "all", r)
    assert_valid_trimmed(out, 6 + 12 + 8)
    assert rel(out.volume(), a**3 + 3 * 2 * r * a * a + 3 * math.pi * r * r * a + 4 / 3 * math.pi * r**3) < EXACT
    assert rel(out.area(), 6 * a * a + 3 * 2 * math.pi * r * a + 4 * math.pi * r * r) < EXACT
    d = 3.0
    bevel = brep.chamfer(cube, [(10.0, -10.0, 0.0)], d)  # the vertical edge at x = 10, y = -10
    assert_valid_trimmed(bevel, 7)
    assert rel(bevel.volume(), 8000 - 0.5 * d * d * 20) < ROUNDING
    assert rel(bevel.area(), 2400 - 2 * 0.5 * d * d - 2 * d * 20 + math.sqrt(2) * d * 20) < ROUNDING


def test_fillet_edges_by_use_and_point_agree(cube):
    """An Edge use of a face chooses the same OCC edge as a point on it."""
    top = max(cube.faces, key=lambda f: f.surface.evaluate(np.array([0.5]), np.array([0.5]))[0, 2])
    use = next(e for e in top.outer_loop if e.curve is not None)
    by_use = brep.fillet(cube, [use], 3.0)
    mid = use.curve.evaluate(0.5 * sum(use.curve.domain))
    by_point = brep.fillet(cube, [mid], 3.0)
    expected = 8000 - (1 - math.pi / 4) * 9 * 20
    assert rel(by_use.volume(), expected) < EXACT and rel(by_point.volume(), expected) < EXACT


def test_edge_points_lie_on_edges(cube):
    pts = blends.edge_points(cube)
    assert pts.shape == (12, 3)
    # every edge of the cube has two coordinates at +-10 and its mid point at 0 in the third
    assert np.all(np.sort(np.abs(pts), axis=1) == [0.0, 10.0, 10.0])


# -- results that are not one solid ------------------------------------------------------------


def test_split_result_needs_pieces(cube):
    slab = brep.box(40.0, 2.0, 40.0, origin=(-20.0, -1.0, -20.0))
    with pytest.raises(BackendError, match=r"exact cut gives 2 disjoint solids.*pieces=True"):
        brep.cut(cube, slab)
    parts = brep.cut(cube, slab, pieces=True)
    assert len(parts) == 2
    for part in parts:
        assert_valid_trimmed(part, 6)
        assert rel(part.volume(), 20 * 9 * 20) < ROUNDING


def test_empty_common(cube):
    far = brep.box(1.0, 1.0, 1.0, origin=(50.0, 0.0, 0.0))
    with pytest.raises(BackendError, match="exact common is empty"):
        brep.common(cube, far)
    assert brep.common(cube, far, pieces=True) == []


# -- bad input ------------------------------------------------------------------------------------


def test_bad_operands(cube):
    with pytest.raises(ParameterError, match="second operand of the exact cut must be a splinekit.brep.Solid"):
        brep.cut(cube, "box")
    with pytest.raises(ParameterError, match="first operand of the exact fuse must be"):
        brep.fuse(cube.outer_shell, cube)
    with pytest.raises(ParameterError, match="empty list"):
        brep.common(cube, [])
    with pytest.raises(ParameterError, match="pieces"):
        brep.fuse(cube, cube, pieces="yes")
    with pytest.raises(ParameterError, match="fuzzy"):
        brep.fuse(cube, cube, fuzzy=-1.0)
    open_box = brep.Solid(brep.Shell(cube.faces[:5]))  # a solid whose shell is not closed
    with pytest.raises(SplineKitError):
        brep.fuse(open_box, brep.box(5.0, 5.0, 5.0))


def test_null_operand_is_named_by_occ():
    """OCC's own alert reaches the message when the intersection step fails."""
    from OCP.TopoDS import TopoDS_Shape

    box = sk.occ.to_occ(brep.box(1.0, 1.0, 1.0))
    with pytest.raises(BackendError, match=r"exact fuse failed .*BOPAlgo_AlertNullInputShapes"):
        exact_booleans.boolean_shape(box, TopoDS_Shape(), "fuse")


def test_bad_fillets(cube):
    with pytest.raises(ParameterError, match=r"edge point 0 .* lies on no edge .* 14.1 away"):
        brep.fillet(cube, [(0.0, 0.0, 0.0)], 1.0)
    with pytest.raises(ParameterError, match="radius"):
        brep.fillet(cube, "all", 0.0)
    with pytest.raises(ParameterError, match="'all'"):
        brep.fillet(cube, "some", 1.0)
    with pytest.raises(ParameterError, match=r"\(n, 3\)"):
        brep.fillet(cube, [[0.0, 0.0]], 1.0)
    # more than half the edge length: OCC reports success but builds self-intersecting wires,
    # which BRepCheck_Analyzer catches
    with pytest.raises(BackendError, match=r"rejects the result of the fillet .*SelfIntersectingWire"):
        brep.fillet(cube, "all", 15.0)


# -- layers --------------------------------------------------------------------------------------


def test_lazy_exposure_keeps_brep_free_of_occ():
    """``splinekit.brep`` resolves the OCC operations on first use: importing it loads no OCP."""
    code = (
        "import sys; import splinekit.brep as b; assert 'OCP' not in sys.modules; "
        "assert {'fuse', 'cut', 'common', 'fillet', 'chamfer'} <= set(dir(b)); "
        "f = b.fuse; from splinekit.interop.exact_booleans import fuse; assert f is fuse; "
        "from splinekit.interop.blends import fillet; assert b.fillet is fillet; print('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr
    with pytest.raises(AttributeError, match="no attribute 'unite'"):
        brep.unite  # noqa: B018


# -- the mesh path ---------------------------------------------------------------------------


def test_mesh_booleans_accept_solids(cube, drilled):
    """manifold3d on the tessellated solids: closed, and within the tessellations' bound of the
    exact cut (each operand's mesh volume is within area x max deviation of its exact volume)."""
    tol = 0.01
    drill = brep.cylinder(4.0, 30.0, origin=(0.0, 0.0, -15.0))
    mesh = sk.difference(cube, drill, tolerance=tol)
    assert mesh.is_closed and mesh.euler_characteristic == 0  # genus 1
    bound = sum(float(m.area) * float(m.max_deviation) for m in (sk.tessellate(cube, tol), sk.tessellate(drill, tol)))
    assert 0 < bound < 50.0
    assert abs(mesh.volume - drilled.volume()) <= bound
    # the chords lie inside the drill, so the mesh removes less than the exact cut
    assert mesh.volume >= drilled.volume() - 1e-9 * drilled.volume()
    fused = sk.union(cube, brep.box(20.0, 20.0, 20.0, origin=(0.0, -5.0, -10.0)), tolerance=tol)
    assert fused.is_closed and abs(fused.volume - (800 - 150) * 20) < 1e-9 * 13000


# -- property: boxes against inclusion-exclusion ---------------------------------------------------

_corner = st.tuples(*[st.integers(-4, 4).map(lambda k: 2.5 * k)] * 3)
_size = st.tuples(*[st.integers(1, 6).map(lambda k: 2.5 * k)] * 3)


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_corner, _size, _corner, _size)
def test_box_booleans_inclusion_exclusion(oa, sa, ob, sb):
    """Any two axis-aligned boxes on a 2.5 mm grid (so faces often coincide or touch): the volumes
    of the pieces of fuse, cut and common follow from the overlap of the two boxes."""
    a, b = brep.box(*sa, origin=oa), brep.box(*sb, origin=ob)
    lo = np.maximum(oa, ob)
    hi = np.minimum(np.add(oa, sa), np.add(ob, sb))
    overlap = float(np.prod(np.clip(hi - lo, 0.0, None)))
    va, vb = float(np.prod(sa)), float(np.prod(sb))
    for op, expected in ((brep.fuse, va + vb - overlap), (brep.cut, va - overlap), (brep.common, overlap)):
        parts = op(a, b, pieces=True)
        for part in parts:
            assert_valid_trimmed(part)
        assert sum(p.volume() for p in parts) == pytest.approx(expected, rel=ROUNDING, abs=1e-9), op.__name__
