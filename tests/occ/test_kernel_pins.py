"""Guard the OCC dependency pins: cadquery 2.8 and build123d 0.12 in one process, on one OCP.

Both packages ship (through cadquery-ocp / cadquery-ocp-novtk) a top-level
``OCP`` package. Unpinned, pip resolves build123d 0.13 (OCP 8.0) beside
cadquery 2.7 (OCP 7.8), one overwrites the other and ``import build123d``
fails. pyproject.toml pins ``cadquery==2.8.*`` and ``build123d>=0.12,<0.13``,
which put both on OCP 7.9.3.1.1; these tests fail if that drifts.
"""

from __future__ import annotations

import importlib.metadata as md
import sys

import pytest


def _major_minor(version: str) -> tuple[int, int]:
    major, minor = version.split(".")[:2]
    return int(major), int(minor)


def test_both_import_in_one_process():
    import build123d  # noqa: F401
    import cadquery  # noqa: F401

    assert "OCP" in sys.modules


def test_pinned_versions():
    assert _major_minor(md.version("cadquery")) == (2, 8)
    assert _major_minor(md.version("build123d")) == (0, 12)


def test_one_ocp_version_installed():
    import OCP

    # Every distribution that installs a top-level OCP package (cadquery-ocp for
    # cadquery, cadquery-ocp-novtk for build123d) must be the same build, since
    # they write into the same directory.
    providers = md.packages_distributions().get("OCP", [])
    assert providers, "no installed distribution provides the OCP package"
    versions = {name: md.version(name) for name in set(providers)}
    assert len(set(versions.values())) == 1, f"OCP provided by different builds: {versions}"
    (version,) = set(versions.values())
    assert _major_minor(version) == (7, 9), versions
    assert version.startswith(OCP.__version__), (version, OCP.__version__)


def test_box_with_build123d():
    import build123d as bd

    box = bd.Box(1, 2, 3)
    assert box.volume == pytest.approx(6.0, rel=1e-12)


def test_box_with_cadquery():
    import cadquery as cq

    box = cq.Workplane("XY").box(1, 2, 3).val()
    assert box.Volume() == pytest.approx(6.0, rel=1e-12)


def test_same_ocp_in_both():
    import build123d as bd
    import build123d.topology.shape_core as bd_core
    import cadquery as cq
    import cadquery.occ_impl.shapes as cq_shapes
    import OCP
    from OCP.TopoDS import TopoDS_Shape

    # both libraries bind the very same OCP classes (one extension module) ...
    assert cq_shapes.TopoDS_Shape is bd_core.TopoDS_Shape is TopoDS_Shape
    assert cq_shapes.GProp_GProps is bd_core.GProp_GProps
    assert sys.modules["OCP"] is OCP
    assert sys.modules["OCP.OCP"].__file__.startswith(OCP.__path__[0])

    # ... so a shape built by one is a valid OCP shape for the other
    bd_box = bd.Box(1, 2, 3)
    cq_box = cq.Workplane("XY").box(1, 2, 3).val()
    assert isinstance(bd_box.wrapped, TopoDS_Shape) and isinstance(cq_box.wrapped, TopoDS_Shape)
    assert cq.Shape.cast(bd_box.wrapped).Volume() == pytest.approx(6.0, rel=1e-12)
    assert bd.Solid(cq_box.wrapped).volume == pytest.approx(6.0, rel=1e-12)
    fused = cq_box.fuse(cq.Shape.cast(bd_box.wrapped).translate(cq.Vector(0.5, 0, 0)))  # boxes are centred: overlap 3
    assert fused.Volume() == pytest.approx(9.0, rel=1e-9)
