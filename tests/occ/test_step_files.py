"""STEP files written by fifteen other CAD systems: import_step gives valid solids with OCC's counts.

The files live outside the project (``../shared/data/step`` relative to the repository root, with
their sources and OCC's reference figures in ``reference.json``); the tests skip when the folder is
absent. Independent references: OCC's own reading of each file (TopExp counts of solids, faces,
edges and vertices) and ``reference.json`` (OCC's GProp volume; ``volume_best`` where the MANIFEST
says the raw figure is wrong). Four small files run by default, all fifteen under ``-m slow``.
"""

from __future__ import annotations

import json
import pathlib

import pytest

pytest.importorskip("OCP")

from exporters import export_step, import_step  # noqa: E402
from splinekit.brep import Solid  # noqa: E402
from splinekit.interop.occ import _sub_shapes  # noqa: E402
from splinekit.interop.occ_brep import brep_list_to_shape  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "step"
FAST = ["sw2013_two_spheres.stp", "ug19_io1_analytic.stp", "euclid_screw.step", "catiav4_4solids_sphere_torus_cone.stp"]
# relative volume tolerance per file: OCC's GProp at eps 1e-9 on rational B-spline faces moves by
# about 2e-7 (measured on a sphere against 4/3 pi r^3), so 1e-6 by default; the MANIFEST's
# drifting files get 1e-4 (ventilator, Pro/E against volume_best, Onshape's revolutions) and 1e-5
VOLUME_RTOL = {"catiav5r18_ventilator.stp": 1e-4, "proe2001_k1_extrusion.stp": 1e-4,
               "onshape_abc_0_13.step": 1e-4, "ideas_io1_allbspline.stp": 1e-5}
# re-reading our own export keeps the counts, except where OCC's reader cannot bring an edge back
# from a file of B-spline faces (measured):
# - cadds: faces 70, 71 and their copies 93, 94 each hold a degenerated edge that lies at no pole.
#   OCC's reader made it to close a gap of 5.2e-8 in u (5.2e-7 mm) where a meridian ends short of
#   the circle it meets (ShapeFix_Wire::FixLacking); its pcurve runs along that gap. STEP has no
#   degenerated edges (OCC's writer leaves them out) and the reader puts one back at a singularity of
#   the surface, or at a gap that looks degenerate by the surface's resolution bound: the (u, v) gap
#   over the resolution more than ten times the 3-D gap (ShapeAnalysis_Surface::IsDegenerated). On
#   OCC's surface of revolution the bound makes that 10.0000002 times (a speed bound of 100 on a
#   radius of 10); on the same surface as a B-spline, as splinekit writes every face, 2.5 times,
#   and the reader closes the gap by bending the two pcurves instead: 440 edges (24 degenerated)
#   instead of 444 (28); faces, vertices, area and volume are kept. OCC's own write and read of its
#   NURBS-converted shape loses the same four (checked below). Writing them as short ordinary edges
#   keeps the count but leaves each an edge of one face only (the shells no longer close).
REIMPORT_EDGES_LOST = {"cadds_s1_revolution_11solids.stp": 4}
# relative (area, volume) change over import -> export -> import (OCC's GProp, eps 1e-9, on the same
# objects): 1e-9 for every file. A STEP file carries neither edge ranges nor per-edge tolerances. OCC's
# reader (a) sets an edge's range by projecting its vertices onto its 3-D curve, and its pcurves' ranges
# by projecting the curve's ends onto their traces; where a pcurve's range then differs from the curve's,
# or (b) where a pcurve lies further than twice the file's uncertainty from its curve, it re-fits the
# pcurve by projecting the curve (XSAlgo_ShapeProcessor::CheckPCurve), and its wire repair
# (ShapeFix_Wire::FixLacking) bends the next pcurve of the loop to meet the new end half way. Against (a)
# the writer places each vertex in the normal plane of every incident curve end, or, where those planes
# meet nowhere, at the nearest point past every end; against (b) it writes the part's greatest
# tolerance as the file's uncertainty (tests/occ/test_step_loose_roundtrip.py); and import_step pulls
# back a pcurve whose trace runs past its curve's end, which no vertex can cure when another edge
# continues the curve tangentially (exporters/_step_corners.py, tests/occ/test_step_corner_settle.py).
# Area / volume before -> after: SolidWorks 2012 1.9e-9 / 1.0e-9 -> 2.7e-15 / 4.8e-15; Inventor
# 5.1e-8 / 6.6e-7 -> 2.2e-12 / 1.9e-11; Onshape (whose face 11 OCC's reader split in three, 101 faces)
# -> counts kept, 2e-16 / 4e-16; NX 1.1e-9 / 3.7e-8 -> 9.4e-9 / 4.8e-9 -> 2.3e-11 / 2.8e-11 (face 30: the trace of
# an arc's pcurve ran 7.8e-5 mm past the arc's end, where a straight edge of two other faces continues
# the arc; the reader re-fitted it and bent the 34 mm pcurve after it; the settled first import is
# 1.9e-8 / 9.7e-9 from OCC's own reading); ventilator 6.5e-6 / 4.8e-6 -> 6.2e-9 / 4.8e-9 -> 8.4e-13 / 6.2e-12
# (the blade tips' small faces and face 13: vertices of four curve ends, the least-squares point up to 1e-5 mm
# inside some of them, so the reader cut those edges).
ROUNDTRIP_RTOL: dict = {}


def _reference():
    path = DATA / "reference.json"
    if not path.is_file():
        pytest.skip(f"the foreign STEP files are not here ({DATA})")
    return json.loads(path.read_text())


def _all_files():
    path = DATA / "reference.json"
    return sorted(json.loads(path.read_text())) if path.is_file() else FAST


def _params():
    return [pytest.param(f, marks=() if f in FAST else pytest.mark.slow) for f in _all_files()]


def _occ_shape(path):
    from OCP.STEPControl import STEPControl_Reader

    reader = STEPControl_Reader()
    reader.ReadFile(str(path))
    reader.TransferRoots()
    return reader.OneShape()


def _nurbs_twin(shape):
    """OCC's copy of ``shape`` with every surface and curve a B-spline (BRepBuilderAPI_NurbsConvert)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert

    return BRepBuilderAPI_NurbsConvert(shape, True).Shape()


def _occ_round_trip(shape, path):
    """``shape`` written by OCC's STEP writer to ``path`` and read back by its reader."""
    from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer

    writer = STEPControl_Writer()
    writer.Transfer(shape, STEPControl_StepModelType.STEPControl_AsIs)
    writer.Write(str(path))
    return _occ_shape(path)


def _counts(shape):
    return [len(_sub_shapes(shape, k)) for k in ("SOLID", "FACE", "EDGE", "VERTEX")]


def _volume(shape):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    total = 0.0
    for solid in _sub_shapes(shape, "SOLID"):
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(solid, props, 1e-9)
        total += props.Mass()
    return total


def _area(shape):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, props, 1e-9)
    return props.Mass()


@pytest.mark.parametrize("name", _params())
def test_foreign_step_file_imports_as_valid_solids(name, tmp_path, request):
    if name not in FAST and "slow" not in (request.config.getoption("markexpr") or ""):
        pytest.skip("the eleven larger files (up to a minute each) run with -m slow")
    reference = _reference()[name]
    path = DATA / name
    items = import_step(path)  # strict: every object was rebuilt and checked valid
    assert items.problems == []
    solids = [it.geometry for it in items]
    assert all(isinstance(s, Solid) for s in solids)
    assert len(solids) == reference["solids"]
    occ = _occ_shape(path)
    ours = brep_list_to_shape(solids)
    counts, theirs = _counts(ours), _counts(occ)
    assert counts == theirs  # solids, faces, edges, vertices
    assert sum(len(s.faces) for s in solids) == reference["faces"]
    key = "volume_best" if "volume_best" in reference else "volume"
    assert _volume(ours) == pytest.approx(reference[key], rel=VOLUME_RTOL.get(name, 1e-6))
    # export -> re-import keeps the counts, the area and the volume
    export_step(tmp_path / "again.step", solids)
    again = import_step(tmp_path / "again.step")
    reread = brep_list_to_shape([it.geometry for it in again])
    solids_, faces, edges, vertices = counts
    lost = REIMPORT_EDGES_LOST.get(name, 0)
    assert _counts(reread) == [solids_, faces, edges - lost, vertices]
    if lost:  # OCC's reader loses them from its own file of the same shape as B-splines too
        assert _counts(_occ_round_trip(_nurbs_twin(occ), tmp_path / "twin.step"))[2] == edges - lost
    area_rtol, volume_rtol = ROUNDTRIP_RTOL.get(name, (1e-9, 1e-9))
    assert _volume(reread) == pytest.approx(_volume(ours), rel=volume_rtol)
    assert _area(reread) == pytest.approx(_area(ours), rel=area_rtol)
    # names come back, except those STEP cannot carry intact (long non-ASCII names are not written;
    # unnamed products get OCC's default name, their shape type)
    kept = [it.name for it in items if it.name and it.name.isascii()]
    assert [it.name for it in again if it.name in kept] == kept
