"""Tessellation of parts made by build123d (OCC), read through from_occ: closed meshes of the right
genus, within tolerance of the faces, enclosing OCC's volume (GProp) within area x tolerance.
"""

from __future__ import annotations

import pytest
from test_tessellation_brep import measured_deviation

import splinekit as sk
from splinekit.brep import Solid


def _build123d_parts():
    bd = pytest.importorskip("build123d")
    box = bd.Box(20, 20, 20)
    plate = bd.Box(40, 30, 5) - bd.Pos(-10, -5, 0) * bd.Cylinder(4, 5) - bd.Pos(8, 6, 0) * bd.Cylinder(5, 5)
    return {
        "box - cylinder": (box - bd.Cylinder(4, 20), 1),
        "plate with two holes": (plate, 2),
        "filleted box": (bd.fillet(box.edges(), 3), 0),
        "chamfered block": (bd.chamfer(bd.Box(30, 20, 10).edges().group_by(bd.Axis.Z)[-1], 2), 0),
        "sphere": (bd.Sphere(5), 0),
        "torus": (bd.Torus(10, 3), 1),
        "revolved part": (bd.Cone(5, 2, 8) + bd.Pos(0, 0, 4) * bd.Cylinder(3, 12), 0),
    }


def _occ_volume(shape):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-9)
    return props.Mass()


@pytest.mark.parametrize("name", ["box - cylinder", "plate with two holes", "filleted box", "chamfered block", "sphere",
                                  "torus", "revolved part"])  # fmt: skip
def test_build123d_parts(name):
    part, genus = _build123d_parts()[name]
    got = sk.occ.from_occ(part)
    solids = got if isinstance(got, list) else [got]  # a boolean's result comes as a compound
    assert len(solids) == 1 and isinstance(solids[0], Solid)
    mesh = sk.tessellate(solids, 1e-3, relative=True)
    assert mesh.is_closed
    assert mesh.euler_characteristic == 2 - 2 * genus
    assert measured_deviation(mesh, solids[0].faces) <= mesh.tolerance * (1 + 1e-9)
    volume = _occ_volume(part.wrapped)
    assert mesh.volume > 0
    assert abs(mesh.volume - volume) <= part.area * mesh.tolerance
