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
# re-reading our own export of these three does not give the same counts or a valid solid yet (see README)
REIMPORT_KNOWN = {"cadds_s1_revolution_11solids.stp", "inventor2013_part_11752.stp", "onshape_abc_0_13.step"}


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
    # export -> re-import keeps the counts
    if name in REIMPORT_KNOWN:
        return
    export_step(tmp_path / "again.step", solids)
    again = import_step(tmp_path / "again.step")
    assert _counts(brep_list_to_shape([it.geometry for it in again])) == counts
    # names come back, except those STEP cannot carry intact (long non-ASCII names are not written;
    # unnamed products get OCC's default name, their shape type)
    kept = [it.name for it in items if it.name and it.name.isascii()]
    assert [it.name for it in again if it.name in kept] == kept
