"""``splinekit analyze``: pictures and one-line reports of a model, a STEP file or a mesh file,
and the deviation of a scan file; bad input as one-line errors."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import exporters
from splinekit import analysis
from splinekit.brep import primitives
from splinekit.cli import main
from splinekit.mesh import primitives as mesh_primitives


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def picture_size(path):
    with Image.open(path) as image:
        return image.size


def test_maps_of_a_model(here, capsys):
    status = main(["analyze", "teapot", "--zebra", "--isophotes", "--curvature", "mean", "--draft", "0,0,1",
                   "--min-draft", "2", "--size", "320x240", "-o", "maps"])
    out = capsys.readouterr().out
    assert status == 0, out
    for name in ("zebra", "isophotes", "curvature-mean", "draft"):
        assert picture_size(here / "maps" / f"teapot-{name}.png") == (320, 240)
    assert "teapot:" in out and "exact normals" in out
    assert re.search(r"draft for pull 0,0,1: [0-9.]+ % under-cut, [0-9.]+ % below 2 deg", out)


def test_draft_of_a_box_mesh_file(here, capsys):
    exporters.export_stl(here / "box.stl", mesh_primitives.box(2.0))
    assert main(["analyze", "box.stl", "--draft", "0,0,1", "--size", "200x160"]) == 0
    out = capsys.readouterr().out
    assert "mesh normals" in out
    assert (here / "out" / "box-draft.png").is_file()


def test_deviation_of_a_scan_file(here, capsys):
    # the default model's sphere-like teapot is not needed: a STEP box and a scan 0.1 outside its top
    exporters.export_step(here / "box.step", [primitives.box(2, 2, 2)])
    rng = np.random.default_rng(1)
    top = np.column_stack([rng.uniform(0.2, 1.8, 500), rng.uniform(0.2, 1.8, 500), np.full(500, 2.1)])
    np.savetxt(here / "scan.xyz", top, header="x y z")
    assert main(["analyze", "box.step", "--deviation", "scan.xyz", "--size", "240x200"]) == 0
    out = capsys.readouterr().out
    assert "deviation of 500 points: max |d| 0.1," in out and "mean +0.1" in out
    assert (here / "out" / "box-deviation.png").is_file()
    assert (here / "out" / "box-deviation-histogram.png").is_file()


def test_continuity_without_the_edge_analysis_says_so(here, capsys, monkeypatch):
    if hasattr(analysis, "shell_continuity"):
        monkeypatch.delattr(analysis, "shell_continuity")
    assert main(["analyze", "teapot", "--continuity"]) == 1
    err = capsys.readouterr().err
    assert "shell_continuity" in err and len(err.strip().splitlines()) == 1
    assert not (here / "out").exists()  # refused before any work


@pytest.mark.parametrize("args, fragment", [
    (["analyze", "teapot"], "nothing to analyse"),
    (["analyze", "teapot", "--draft", "0,0,0"], "zero length"),
    (["analyze", "teapot", "--draft", "0,1"], "--draft"),
    (["analyze", "teapot", "--draft", "0,0,1", "--min-draft", "95"], "--min-draft"),
    (["analyze", "teapot", "--zebra", "--min-draft", "3"], "--min-draft applies"),
    (["analyze", "teapot", "--isophotes", "--light", "0,0,0"], "zero length"),
    (["analyze", "teapot", "--zebra", "--tolerance", "-1"], "--tolerance"),
    (["analyze", "teapot", "--deviation", "missing.xyz"], "missing.xyz"),
    (["analyze", "teapot", "--deviation", "scan.txt"], "scan"),
    (["analyze", "teapot", "--deviation", "empty.xyz"], "empty"),
    (["analyze", "teapot", "--deviation", "nan.xyz"], "not finite"),
    (["analyze", "teapot", "--deviation", "bad.xyz"], "line 2"),
    (["analyze", "no-such.stl", "--zebra"], "no-such.stl"),
    (["analyze", "teapot", "--zebra", "--stripes", "0"], "stripes"),
])
def test_bad_input_is_one_line(here, capsys, args, fragment):
    (here / "scan.txt").write_text("0 0 0\n")
    (here / "empty.xyz").write_text("# nothing\n")
    (here / "nan.xyz").write_text("0 0 0\nnan 1 2\n")
    (here / "bad.xyz").write_text("0 0 0\n1 2\n")
    assert main(args) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("splinekit: error: ")
    assert fragment in err[0], err[0]


def test_help_lists_analyze():
    result = subprocess.run([sys.executable, "-m", "splinekit.cli", "analyze", "--help"], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0
    for option in ("--zebra", "--isophotes", "--curvature", "--continuity", "--draft", "--min-draft", "--deviation", "-o"):
        assert option in result.stdout


def test_curvature_combs_of_a_part_s_edges(here, capsys):
    """`--combs` draws every edge curve of the part at one scale: the box with a hole (R 4) has
    12 straight edges, the hole's two circles and its seam; the largest curvature is 1/4."""
    exporters.export_step(here / "part.step", [primitives.box_with_hole(20, 4)])
    assert main(["analyze", "part.step", "--combs", "--size", "200x160"]) == 0
    out = capsys.readouterr().out
    m = re.search(r"curvature combs: (\d+) edge curves, largest curvature ([0-9.e+-]+)", out)
    assert m is not None, out
    assert int(m[1]) == 15 and float(m[2]) == pytest.approx(0.25, rel=1e-6)
    assert picture_size(here / "out" / "part-combs.png") == (200, 160)


def test_combs_need_exact_curves(here, capsys):
    exporters.export_stl(here / "box.stl", mesh_primitives.box(2.0))
    assert main(["analyze", "box.stl", "--combs"]) == 1
    assert "a mesh has none" in capsys.readouterr().err


def test_curvature_combs_share_one_scale():
    """Two circles (radius 1 and 2): at one scale the small circle's teeth are twice as long (its
    curvature is twice as large), and the longest tooth is COMB_LENGTH of all samples' diagonal."""
    from splinekit.construct import circle

    small, large = circle((0, 0, 0), (0, 0, 1), 1.0), circle((5, 0, 0), (0, 0, 1), 2.0)
    a, b = analysis.curvature_combs([small, large], samples=64)
    la, lb = (np.linalg.norm(c.comb, axis=1) for c in (a, b))
    assert a.scale == b.scale
    assert la.max() == pytest.approx(2 * lb.max(), rel=1e-9)
    P = np.concatenate([a.points, b.points])
    assert la.max() == pytest.approx(analysis.curves.COMB_LENGTH * np.linalg.norm(np.ptp(P, axis=0)), rel=1e-9)
