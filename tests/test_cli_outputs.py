"""What the ``splinekit`` command writes and says it wrote: the picture format named by the
suffix, the default output folder ``out/``, the contents of each written file (read back
independently: STEP through OCC's own reader, meshes through the mesh readers), error lines that
name no temporary file, ``info``'s two measurements of an exact file, ``check``'s tolerances, and
the deprecated names of the former single-module CLI. The fake registry and the fixtures come
from ``test_cli``."""

from __future__ import annotations

import math
import os
import re
import warnings

import numpy as np
import pytest
from test_cli import assert_one_line_error, fake_env, in_process, run  # noqa: F401  (fixtures)

import exporters
import splinekit as sk

PNG_MAGIC, JPEG_MAGIC = b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff"


def _occ_counts(path) -> dict:
    """Solids, shells and faces of a STEP file as OCC's plain reader sees them."""
    pytest.importorskip("OCP")
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_ShapeEnum
    from OCP.TopExp import TopExp
    from OCP.TopTools import TopTools_IndexedMapOfShape

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_ReturnStatus.IFSelect_RetDone
    reader.TransferRoots()
    shape = reader.OneShape()
    counts = {}
    for kind in ("SOLID", "SHELL", "FACE"):
        found = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(shape, getattr(TopAbs_ShapeEnum, f"TopAbs_{kind}"), found)
        counts[kind] = found.Extent()
    return counts


def _wrote_line(out: str, name: str) -> str:
    return next(line for line in out.splitlines() if line.strip().startswith("wrote") and line.split()[1].endswith(name))


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


# -- build: what each file holds --------------------------------------------------------------

def test_build_says_what_each_file_holds(in_process, capsys, tmp_path):
    assert in_process(["build", "ball", "--format", "step,stl,obj", "-o", "o"]) == 0
    out = capsys.readouterr().out
    counts = _occ_counts(tmp_path / "o" / "ball.step")
    assert counts == {"SOLID": 1, "SHELL": 1, "FACE": 1}  # a sphere: one closed face, one solid
    assert (f"{_plural(counts['SOLID'], 'solid')}, {_plural(counts['SHELL'], 'shell')}, "
            f"{_plural(counts['FACE'], 'face')}") in _wrote_line(out, "ball.step")
    for fmt in ("stl", "obj"):
        mesh = exporters.import_mesh(tmp_path / "o" / f"ball.{fmt}")
        assert mesh.is_triangle_mesh
        assert re.search(rf": {mesh.n_faces} triangles \(max deviation [0-9.e-]+\)$", _wrote_line(out, f"ball.{fmt}"))


def test_build_of_a_quad_mesh_counts_triangles_where_the_format_holds_triangles(in_process, capsys, tmp_path):
    assert in_process(["build", "cube", "--format", "stl,obj,ply", "-o", "o"]) == 0
    out = capsys.readouterr().out
    stl = exporters.import_mesh(tmp_path / "o" / "cube.stl")
    assert stl.n_faces == 12 and _wrote_line(out, "cube.stl").endswith(": 12 triangles")
    for fmt in ("obj", "ply"):  # these keep the quads
        mesh = exporters.import_mesh(tmp_path / "o" / f"cube.{fmt}")
        assert mesh.is_quad_mesh and mesh.n_faces == 6
        assert _wrote_line(out, f"cube.{fmt}").endswith(": 6 quads")


def test_the_teapot_is_said_to_be_open_shells_as_its_step_file_holds(tmp_path):
    """The issue's case: the teapot's STEP holds no solid and four shells; the summary says so."""
    models = pytest.importorskip("models")
    if "teapot" not in getattr(models, "MODELS", {}):
        pytest.skip("no teapot model in the registry")
    env = {k: v for k, v in os.environ.items() if k != "SPLINEKIT_MODELS"}
    result = run(["build", "teapot", "--format", "step"], env, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    counts = _occ_counts(tmp_path / "out" / "teapot.step")
    assert counts["SOLID"] == 0 and counts["SHELL"] == 4 and counts["FACE"] == 32
    assert "0 solids, 4 shells, 32 faces" in _wrote_line(result.stdout, "teapot.step")
    assert "body" not in result.stdout


# -- the default output folder ----------------------------------------------------------------

def test_build_render_and_demo_write_into_out_by_default(in_process, capsys, tmp_path):
    assert in_process(["-q", "build", "--format", "stl"]) == 0
    assert in_process(["-q", "render", "ball", "--size", "200x160"]) == 0
    assert in_process(["-q", "demo"]) == 0
    assert os.listdir(tmp_path) == ["out"]
    assert sorted(os.listdir(tmp_path / "out")) == ["ball.png", "ball.stl", "splinekit-demo.png"]
    assert (tmp_path / "out" / "ball.png").read_bytes().startswith(PNG_MAGIC)


def test_render_at_the_smallest_size(in_process, capsys, tmp_path):
    from matplotlib.image import imread

    assert in_process(["-q", "render", "ball", "--size", "64x64", "-o", "small.png"]) == 0
    assert imread(tmp_path / "small.png").shape[:2] == (64, 64)


def test_gitignore_ignores_the_default_output_folder():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with open(os.path.join(root, ".gitignore")) as fh:
        assert "out/" in fh.read().split()


# -- render: the format the suffix names ------------------------------------------------------

@pytest.mark.parametrize("name, magic, pil_format", [("p.png", PNG_MAGIC, "PNG"), ("p.jpg", JPEG_MAGIC, "JPEG"),
                                                     ("P.JPEG", JPEG_MAGIC, "JPEG")])
def test_render_writes_the_format_its_suffix_names(in_process, capsys, tmp_path, name, magic, pil_format):
    Image = pytest.importorskip("PIL.Image")
    assert in_process(["render", "ball", "--size", "200x160", "-o", name]) == 0
    assert os.listdir(tmp_path) == [name]  # no intermediate file beside it
    data = (tmp_path / name).read_bytes()
    assert data.startswith(magic)
    with Image.open(tmp_path / name) as image:
        assert image.format == pil_format


@pytest.mark.parametrize("name", ["p.gif", "p.pdf", "picture"])
def test_render_refuses_a_picture_format_it_does_not_write(in_process, capsys, tmp_path, name):
    assert in_process(["render", "ball", "-o", name]) == 1
    err = capsys.readouterr().err
    assert err.startswith("splinekit: error: ") and len(err.strip().splitlines()) == 1
    assert name in err and ".png" in err and ".jpg" in err
    assert os.listdir(tmp_path) == []


# -- errors name the target, never the temporary file -----------------------------------------

def test_a_failed_write_names_the_target_not_the_temporary_file(in_process, capsys, monkeypatch, tmp_path):
    def refuse(src, dst):
        raise PermissionError(13, "Permission denied", src, dst)

    monkeypatch.setattr(os, "replace", refuse)  # the rename onto the target fails
    assert in_process(["build", "--format", "stl", "-o", "o"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("splinekit: error: ") and len(err.strip().splitlines()) == 1
    assert "ball.stl" in err and ".splinekit-" not in err
    assert os.listdir(tmp_path / "o") == []  # the temporary file is gone too


def test_an_unwritable_folder_is_one_line_without_a_temporary_name(fake_env, tmp_path):
    folder = "/sys"  # read-only even for root in a container or on a host
    if not os.path.isdir(folder) or os.access(folder, os.W_OK) and _can_create(folder):
        pytest.skip("no read-only folder to write into")
    result = run(["build", "--format", "stl", "-o", folder], fake_env, cwd=tmp_path)
    assert_one_line_error(result, "ball.stl", status=1)
    assert ".splinekit-" not in result.stderr


def _can_create(folder) -> bool:
    try:
        with open(os.path.join(folder, ".splinekit-probe"), "x"):
            pass
    except OSError:
        return False
    os.unlink(os.path.join(folder, ".splinekit-probe"))
    return True


# -- info: OCC's and splinekit's measures of an exact file ------------------------------------

def test_info_of_a_step_file_reports_occ_and_splinekit_measures(in_process, capsys, tmp_path):
    r = 10.0
    assert in_process(["build", "--format", "step"]) == 0
    capsys.readouterr()
    assert in_process(["info", "out/ball.step"]) == 0
    out = capsys.readouterr().out
    for label, exact in (("area", 4 * math.pi * r**2), ("volume", 4 / 3 * math.pi * r**3)):
        line = next(x for x in out.splitlines() if x.strip().startswith(label))
        m = re.search(rf"{label}\s+(\S+)\s+\(OCC GProp 1e-10\); splinekit.brep (\S+) \(relative difference (\S+)\)", line)
        assert m, line
        occ, ours, difference = map(float, m.groups())
        assert occ == pytest.approx(exact, rel=1e-9) and ours == pytest.approx(exact, rel=1e-9)
        # the printed values have 10 digits: their difference agrees with the one printed to that
        assert abs(abs(ours - occ) / exact - difference) < 1e-9 and difference < 1e-9


# -- check: tolerances the geometry allows ----------------------------------------------------

def test_check_compares_points_with_occ_to_1e_12_of_the_coordinates(in_process, capsys):
    assert in_process(["check", "ball", "--set", "radius=10"]) == 0
    out = capsys.readouterr().out
    row = next(x for x in out.splitlines() if x.startswith("point deviation vs OCC"))
    measured, expected, tolerance, result = row.split(")", 1)[1].split()[:4]
    assert result == "PASS" and float(expected) == 0.0
    assert float(tolerance) == pytest.approx(1e-12 * 10.0)  # the largest coordinate of the net is the radius
    assert float(measured) <= float(tolerance)
    row = next(x for x in out.splitlines() if x.startswith("tessellation volume vs"))
    measured, expected, tolerance = map(float, row.split()[4:7])
    assert expected == pytest.approx(4 / 3 * math.pi * 1000, rel=1e-9)
    assert abs(measured - expected) <= tolerance < 0.01 * expected  # the mesh's own bound, not a percentage


# -- the former names ---------------------------------------------------------------------------

def test_the_former_library_names_of_the_cli_still_resolve_with_a_deprecation_warning():
    import splinekit.cli as cli
    from exporters.step import read_step_shape
    from splinekit.interop import gprop
    from splinekit.mesh import primitives

    for name, new in (("occ_area", gprop.occ_area), ("occ_volume", gprop.occ_volume), ("occ_bbox", gprop.occ_bbox),
                      ("point_deviation", gprop.point_deviation), ("read_step_shape", read_step_shape)):
        with pytest.warns(DeprecationWarning, match=name):
            assert getattr(cli, name) is new
    with pytest.warns(DeprecationWarning, match="mesh_genus"):
        mesh_genus = cli.mesh_genus
    assert mesh_genus(primitives.torus(8, 4)) == (1, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        surface = cli.demo_surface()  # public names that stay, without a warning
        assert callable(cli.main) and callable(cli.model_mesh)
    with pytest.warns(DeprecationWarning, match="_area"):
        area = cli._area
    a = 0.5  # a bilinear patch spanning a square of side a: area a^2
    flat = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.array([[[0, 0, 0], [0, a, 0]], [[a, 0, 0], [a, a, 0]]], float))
    assert area(flat) == pytest.approx(a * a, rel=1e-13)
    assert area(surface) > 4.0  # the wavy roof spans [-1, 1]^2 and is not flat
    with pytest.raises(AttributeError):
        cli.no_such_name  # noqa: B018
    assert set(cli.COMMANDS) == {"list", "build", "info", "render", "check", "demo", "sweep", "analyze", "compare", "neural"}


def test_render_creates_a_missing_folder_but_not_below_a_file(in_process, capsys, tmp_path):
    assert in_process(["-q", "render", "ball", "--size", "200x160", "-o", "new/folder/p.jpg"]) == 0
    assert (tmp_path / "new" / "folder" / "p.jpg").read_bytes().startswith(JPEG_MAGIC)
    (tmp_path / "a-file").write_text("x")
    assert in_process(["render", "ball", "-o", "a-file/below/p.png"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("splinekit: error: ") and "a-file" in err and "not a folder" in err
