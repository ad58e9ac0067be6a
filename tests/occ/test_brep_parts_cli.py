"""``splinekit build`` and ``splinekit check`` on the models made of exact B-rep solids
(bracket: holes, bosses, fillets; block: rounded edges, a pocket with a filleted floor).

The STEP file is judged by OCC's own reader (one valid solid, the face count the model states,
the closed-form volume at raised precision), the STL by splinekit's mesh reader (closed, the
genus of the part).
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_ShapeEnum
from OCP.TopExp import TopExp
from OCP.TopTools import TopTools_IndexedMapOfShape

import exporters
import models

pytestmark = pytest.mark.slow  # each build runs several OCC booleans and fillets

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def splinekit(*args, cwd):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [ROOT, os.environ.get("PYTHONPATH")])))
    return subprocess.run([sys.executable, "-m", "splinekit.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=600)


def count(shape, kind):
    found = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, getattr(TopAbs_ShapeEnum, f"TopAbs_{kind}"), found)
    return found.Extent()


@pytest.mark.parametrize("name, genus", [("bracket", 4), ("block", 0)])
def test_build_writes_exact_step_and_stl(name, genus, tmp_path):
    result = splinekit("build", name, "-o", tmp_path, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(tmp_path)) == [f"{name}.step", f"{name}.stl"]
    assert "1 exact solid" in result.stdout and "splinekit.brep mass properties" in result.stdout
    checks = models.build_model(name).checks
    reader = STEPControl_Reader()
    assert reader.ReadFile(str(tmp_path / f"{name}.step")) == IFSelect_ReturnStatus.IFSelect_RetDone
    reader.TransferRoots()
    shape = reader.OneShape()
    assert BRepCheck_Analyzer(shape).IsValid()
    assert count(shape, "SOLID") == 1 and count(shape, "FACE") == checks["faces"][0]
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-10)
    expected, tolerance = checks["volume"]
    assert abs(props.Mass() - expected) <= tolerance
    mesh = exporters.import_stl(tmp_path / f"{name}.stl")
    assert mesh.is_closed and mesh.euler_characteristic == 2 - 2 * genus


def test_check_passes(tmp_path):
    result = splinekit("check", "bracket", cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    for row in ("OCC calls it a valid solid", "volume: splinekit vs OCC", "tessellation is closed", "faces"):
        assert row in result.stdout
    assert "FAIL" not in result.stdout
