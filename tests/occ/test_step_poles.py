"""STEP round trip of build123d parts with degenerated edges at a pole or an apex: import_step ->
export_step -> import_step keeps the faces, the edges (degenerated ones among them), the vertices,
the area and the volume.

OCC's STEP writer writes a loop made only of a seam and pole edges (a sphere's face that keeps
both poles) as a VERTEX_LOOP; beside other loops (a hole, a plane's cut) its reader rebuilds such
a face wrongly when it is a B-spline, as every face splinekit writes is (see
``splinekit.interop.occ_step_poles``). References: OCC's own reading of the file build123d writes
(TopExp counts; GProp at eps 1e-10 on the shapes before and after), closed forms for the sphere
cut by two planes, and OCC's reader on the file we write (without splinekit's reader in the
loop). Switching the fix off (monkeypatch) makes the sphere tests fail.
"""

from __future__ import annotations

import math

import pytest

bd = pytest.importorskip("build123d")

from _gprop import volume_area  # noqa: E402
from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.STEPControl import STEPControl_Reader  # noqa: E402

from exporters import export_step, import_step  # noqa: E402
from exporters import step as step_module  # noqa: E402
from splinekit.interop.occ_brep import brep_list_to_shape  # noqa: E402
from splinekit.interop.occ_shapes import _sub_shapes  # noqa: E402
from splinekit.interop.occ_step_poles import pole_edges_as_points  # noqa: E402

# each part: how to make it, and whether one of its faces keeps both poles of a sphere beside
# another loop (the case OCC's writer turns into a VERTEX_LOOP)
PARTS = {
    "sphere cut by two planes": (lambda: bd.Sphere(10) & bd.Box(12, 30, 30), True),
    "sphere cut by one plane": (lambda: bd.Sphere(10) & bd.Pos(4, 0, 0) * bd.Box(20, 30, 30), True),
    "sphere with a side hole": (lambda: bd.Sphere(10) - bd.Rot(0, 90, 0) * bd.Cylinder(3, 30), True),
    "sphere with its top cut off": (lambda: bd.Sphere(10) - bd.Pos(0, 0, 8) * bd.Box(30, 30, 6), False),
    "cone apex with a side hole": (
        lambda: bd.Solid.make_cone(8, 0, 12) - bd.Pos(0, 0, 4) * bd.Rot(0, 90, 0) * bd.Cylinder(1, 30), False),
}


def _counts(shape):
    """``[faces, edges, degenerated edges, vertices]`` of an OCC shape (TopExp)."""
    edges = _sub_shapes(shape, "EDGE")
    degenerated = sum(bool(BRep_Tool.Degenerated_s(e)) for e in edges)
    return [len(_sub_shapes(shape, "FACE")), len(edges), degenerated, len(_sub_shapes(shape, "VERTEX"))]


def _occ_read(path):
    reader = STEPControl_Reader()
    reader.ReadFile(str(path))
    reader.TransferRoots()
    return reader.OneShape()


def _round_trip(name, tmp_path):
    """``(OCC's shape of build123d's file, splinekit's import of it, the file splinekit writes,
    splinekit's import of that)``."""
    first, again = tmp_path / "build123d.step", tmp_path / "again.step"
    export_step(first, PARTS[name][0]())  # an OCC shape: written as it is
    solids = [it.geometry for it in import_step(first)]
    export_step(again, solids)
    return _occ_read(first), solids, again, [it.geometry for it in import_step(again)]


@pytest.mark.parametrize("name", list(PARTS))
def test_round_trip_keeps_pole_edges(name, tmp_path):
    occ, solids, again, reread = _round_trip(name, tmp_path)
    counts = _counts(occ)
    assert counts[2] >= 1  # the part has a degenerated edge (a pole or an apex)
    before = brep_list_to_shape(solids)
    assert _counts(before) == counts  # the import keeps OCC's counts
    assert _counts(_occ_read(again)) == counts  # OCC's reader alone on the file we write
    after = brep_list_to_shape(reread)
    assert _counts(after) == counts
    (v0, a0), (v1, a1) = volume_area(before), volume_area(after)
    assert v1 == pytest.approx(v0, rel=1e-9)
    assert a1 == pytest.approx(a0, rel=1e-9)
    if PARTS[name][1]:  # the loop of seam and poles is written as an EDGE_LOOP
        assert "VERTEX_LOOP" not in again.read_text()


def test_sphere_cut_by_two_planes_against_closed_forms(tmp_path):
    # the zone between x = -6 and 6 of a sphere of radius 10: volume pi * (2 * 6 * 100 - 2 * 6**3 / 3),
    # area 2 pi r h of the zone plus two discs of radius 8
    *_, reread = _round_trip("sphere cut by two planes", tmp_path)
    (solid,) = reread
    assert solid.volume() == pytest.approx(1056 * math.pi, rel=1e-9)
    assert solid.area() == pytest.approx(240 * math.pi + 2 * 64 * math.pi, rel=1e-9)


@pytest.mark.parametrize("name", [n for n, (_, both_poles) in PARTS.items() if both_poles])
def test_without_the_fix_the_round_trip_loses_the_sphere(name, tmp_path, monkeypatch):
    monkeypatch.setattr(step_module, "pole_edges_as_points", lambda shape: 0)
    occ, _, again, reread = _round_trip(name, tmp_path)
    assert "VERTEX_LOOP" in again.read_text()
    assert _counts(brep_list_to_shape(reread)) != _counts(occ)


def test_only_seam_and_pole_loops_beside_others_change(tmp_path):
    # a whole sphere (its one loop a seam and two poles) is left alone: OCC's VERTEX_LOOP, when it
    # is a face's only bound, reads back as the surface's natural bounds; the zone of a sphere
    # between two planes, as read from STEP (its seam and poles one loop, each cut another), has
    # its two poles changed
    def imported(part):
        export_step(tmp_path / "part.step", part)
        return brep_list_to_shape([it.geometry for it in import_step(tmp_path / "part.step")])

    whole = imported(bd.Sphere(3))
    assert pole_edges_as_points(whole) == 0
    assert _counts(whole)[2] == 2
    zone = imported(bd.Sphere(10) & bd.Box(12, 30, 30))
    assert pole_edges_as_points(zone) == 2
    assert _counts(zone) == [3, 6, 0, 5]
