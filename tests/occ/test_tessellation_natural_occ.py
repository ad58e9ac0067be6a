"""Whole spheres and tori (one face bounded by its natural domain, meshed by the patch path)
against OCC's BRepMesh on the same exact face: at OCC's deflection lowered until its measured
deviation (the same yardstick: the surface at the barycentric (u, v) of every triangle's centre
and edge midpoints) is at most splinekit's, splinekit needs fewer triangles; build123d's own
sphere and torus read through from_occ take the same path and enclose OCC's volume (GProp)
within area x tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

import splinekit as sk
from splinekit.brep import primitives

pytest.importorskip("OCP")

BARY = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])


def _deviation(surface, corners_uv, corners_xyz):
    uv = np.einsum("bj,fjd->fbd", BARY, corners_uv).reshape(-1, 2)
    flat = np.einsum("bj,fjd->fbd", BARY, corners_xyz).reshape(-1, 3)
    (u0, u1), (v0, v1) = surface.domain
    uv = np.clip(uv, [u0, v0], [u1, v1])  # OCC's (u, v) may stray by rounding
    return float(np.linalg.norm(surface.evaluate(uv[:, 0], uv[:, 1]) - flat, axis=1).max())


def _occ_mesh(shape, deflection):
    """``(corners_uv, corners_xyz)`` of OCC's mesh of the one face of ``shape``."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    BRepTools.Clean_s(shape)
    BRepMesh_IncrementalMesh(shape, deflection, False, 0.5, False)
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    tri = BRep_Tool.Triangulation_s(TopoDS.Face_s(explorer.Current()), TopLoc_Location())
    n, m = tri.NbNodes(), tri.NbTriangles()
    xyz = np.array([[tri.Node(i).X(), tri.Node(i).Y(), tri.Node(i).Z()] for i in range(1, n + 1)])
    uv = np.array([[tri.UVNode(i).X(), tri.UVNode(i).Y()] for i in range(1, n + 1)])
    T = np.array([tri.Triangle(i).Get() for i in range(1, m + 1)]) - 1
    return uv[T], xyz[T]


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3])
@pytest.mark.parametrize("kind", ["sphere", "torus"])
def test_fewer_triangles_than_brepmesh_at_equal_measured_deviation(kind, rel):
    solid = primitives.sphere(1.0) if kind == "sphere" else primitives.torus(2.0, 0.6)
    surface = solid.faces[0].surface
    mesh = sk.tessellate(solid, rel, relative=True)
    assert mesh.is_closed
    ours = _deviation(surface, mesh.corner_uv, mesh.vertices[np.asarray(mesh.faces)])
    assert ours <= mesh.tolerance * (1 + 1e-9)
    shape = sk.occ.to_occ(solid)
    deflection = mesh.tolerance
    for _ in range(12):  # lower OCC's deflection until its measured deviation is at most ours
        uv, xyz = _occ_mesh(shape, deflection)
        theirs = _deviation(surface, uv, xyz)
        if theirs <= ours:
            break
        deflection *= max(0.3, 0.9 * ours / theirs)
    assert theirs <= ours
    assert mesh.n_faces < len(uv)


@pytest.mark.parametrize("kind", ["sphere", "torus"])
def test_build123d_sphere_and_torus_take_the_natural_path(kind):
    bd = pytest.importorskip("build123d")
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    part = bd.Sphere(5) if kind == "sphere" else bd.Torus(10, 3)
    got = sk.occ.from_occ(part)
    solid = got[0] if isinstance(got, list) else got
    mesh = sk.tessellate(solid, 1e-4, relative=True)
    assert solid.faces[0]._cache["tessellate"].natural is not None
    assert mesh.is_closed
    assert mesh.euler_characteristic == (2 if kind == "sphere" else 0)
    assert _deviation(solid.faces[0].surface, mesh.corner_uv, mesh.vertices[np.asarray(mesh.faces)]) <= mesh.tolerance * (1 + 1e-9)
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(part.wrapped, props, 1e-9)
    assert mesh.volume > 0
    assert abs(mesh.volume - props.Mass()) <= part.area * mesh.tolerance
