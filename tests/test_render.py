"""Pictures: splinekit.plot.render_patches / render_mesh and the ``render`` command.

A picture is judged by image statistics read back with matplotlib.image.imread:
the requested size, an object covering a reasonable share of the frame, many
distinct colours; and, where geometry fixes the sign of a curvature (a
sphere: K > 0 and H > 0 everywhere; a torus: K > 0 outside, K < 0 inside),
which end of the diverging colour map shows up.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from matplotlib.image import imread

import splinekit as sk
from splinekit.errors import ParameterError, SplineKitError
from splinekit.mesh import PolyMesh, primitives
from splinekit.plot import COLOR_MODES, render_mesh, render_patches

SMALL = (480, 400)


def sphere(radius=1.0):
    profile = sk.arc([0, 0, 0], [0, -1, 0], radius, -math.pi / 2, math.pi / 2, x_axis=[1, 0, 0])
    return sk.revolve(profile, [0, 0, 0], [0, 0, 1])


def stats(path, size=SMALL):
    """``(coverage, distinct colours, reddish share, bluish share)`` of the PNG at ``path``."""
    img = imread(path)
    assert img.shape[:2] == (size[1], size[0])
    rgb = img[..., :3].astype(float)
    if img.shape[-1] == 4:
        assert np.all(img[..., 3] == 1.0)  # opaque
    # object pixels: away from the white background (the colour bar is part of the frame too)
    ink = (rgb < 0.94).any(axis=-1)
    coverage = float(ink.mean())
    distinct = np.unique((rgb[ink] * 31).round().astype(int) @ np.array([1024, 32, 1])).size
    body = rgb[:, : size[0] - 140]  # left of the colour bar, which takes the rightmost 135 pixels
    red = (body[..., 0] > body[..., 2] + 0.15).mean()
    blue = (body[..., 2] > body[..., 0] + 0.15).mean()
    return coverage, distinct, float(red), float(blue)


def assert_good_picture(path, size=SMALL, min_coverage=0.1):
    coverage, distinct, _, _ = stats(path, size)
    assert min_coverage < coverage < 0.9, coverage
    assert distinct > 40, distinct


@pytest.mark.parametrize("color", COLOR_MODES)
def test_sphere_in_every_color_mode(tmp_path, color):
    path = render_patches(sphere(2.0), tmp_path / f"s-{color}.png", color=color, size=SMALL, title=color)
    assert path == str(tmp_path / f"s-{color}.png")
    assert_good_picture(path)


def test_sphere_gaussian_curvature_is_positive_and_mean_curvature_negative(tmp_path):
    """K = 1/r^2 > 0: the warm end of the map only; with outward normals H = -1/r
    (OCC's sign, splinekit's everywhere): the cool end only."""
    _, _, red, blue = stats(render_patches(sphere(3.0), tmp_path / "gaussian.png", color="gaussian", size=SMALL))
    assert red > 0.1 and blue < 0.001, (red, blue)
    _, _, red, blue = stats(render_patches(sphere(3.0), tmp_path / "mean.png", color="mean", size=SMALL))
    assert blue > 0.1 and red < 0.001, (red, blue)
    _, _, red, blue = stats(render_mesh(primitives.icosphere(3, radius=3.0), tmp_path / "mesh-mean.png", color="mean", size=SMALL))
    assert blue > 0.1 and red < 0.001, (red, blue)


def test_torus_gaussian_curvature_changes_sign(tmp_path):
    mesh = primitives.torus(48, 24, R=1.0, r=0.35)
    path = render_mesh(mesh, tmp_path / "torus.png", color="gaussian", size=SMALL, view=(40, -60))
    _, _, red, blue = stats(path)
    assert red > 0.05 and blue > 0.03, (red, blue)
    assert_good_picture(render_mesh(mesh, tmp_path / "torus-log.png", color="gaussian", scale="symlog", size=SMALL))


@pytest.mark.parametrize("color", COLOR_MODES)
def test_mesh_in_every_color_mode(tmp_path, color):
    mesh = primitives.icosphere(3, radius=5.0)
    assert_good_picture(render_mesh(mesh, tmp_path / f"m-{color}.png", color=color, size=SMALL))


def test_mixed_polygon_mesh_and_patch_ids_by_component(tmp_path):
    # a quad-based pyramid (one quad, four triangles) beside a box: mixed valences, two components
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]], float)
    faces = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    box = primitives.box(0.8, center=(2.0, 0.5, 0.4))
    V2 = np.concatenate([V, box.vertices])
    faces2 = faces + [list(np.asarray(f) + len(V)) for f in box.faces]
    mesh = PolyMesh(V2, faces2)
    path = render_mesh(mesh, tmp_path / "mixed.png", color="patch", size=SMALL)
    coverage, distinct, _, _ = stats(path)
    assert coverage > 0.05 and distinct > 5


def test_size_and_an_existing_file_is_replaced_atomically(tmp_path):
    target = tmp_path / "pic.png"
    target.write_bytes(b"old")
    render_patches(sphere(), target, size=(300, 200), color="normal")
    assert imread(target).shape[:2] == (200, 300)
    assert os.listdir(tmp_path) == ["pic.png"]  # no temporary file left behind


@pytest.mark.parametrize("size", [(64, 64), (64, 400), (400, 64), (120, 120)])
@pytest.mark.parametrize("color", ["curvature", "patch"])
def test_small_pictures_render_without_bar_or_title(tmp_path, size, color):
    """Down to the smallest size accepted (64 pixels a side) the object is drawn; the colour bar
    (135 pixels wide) and a title that would not fit are left out rather than the object."""
    path = render_patches(sphere(), tmp_path / "small.png", size=size, color=color, title="a sphere " * 4)
    img = imread(path)[..., :3]
    assert img.shape[:2] == (size[1], size[0])
    ink = (img < 0.94).any(axis=-1)
    assert 0.05 < ink.mean() < 0.9, ink.mean()  # the object, not an empty or smeared frame
    rows, cols = np.nonzero(ink)
    # no bar or title beside the object: the ink is one blob about as wide as it is high
    assert abs(np.ptp(cols) - np.ptp(rows)) <= 0.2 * min(size) + 2


def test_unwritable_target_leaves_nothing(tmp_path):
    with pytest.raises(OSError):
        render_patches(sphere(), tmp_path / "missing" / "pic.png", size=SMALL)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    "kwargs",
    [dict(color="rainbow"), dict(scale="linear"), dict(size=(10, 10)), dict(size=(100.5, 200)), dict(size="big"),
     dict(size=(float("inf"), 300)),
     dict(view=(float("nan"), 0)), dict(view=(1,)), dict(resolution=1), dict(resolution=10**5)],
)
def test_bad_options_raise(tmp_path, kwargs):
    with pytest.raises(ParameterError):
        render_patches(sphere(), tmp_path / "x.png", **kwargs)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("resolution", [0, 1, -3, 2.5, "80", 10**5])
def test_render_surface_checks_its_resolution(tmp_path, resolution):
    from splinekit.plot import render_surface

    with pytest.raises(ParameterError, match="resolution"):
        render_surface(sphere(), tmp_path / "x.png", resolution=resolution)
    assert os.listdir(tmp_path) == []


def test_bad_geometry_raises(tmp_path):
    flat = sk.BSplineSurface.uniform(1, 1, np.random.default_rng(0).random((2, 2, 2)))
    with pytest.raises(ParameterError, match="patch 0"):
        render_patches([flat], tmp_path / "x.png")
    with pytest.raises(ParameterError, match="patch 1"):
        render_patches([sphere(), "not a surface"], tmp_path / "x.png")
    with pytest.raises(ParameterError):
        render_patches([], tmp_path / "x.png")
    with pytest.raises(SplineKitError):
        render_mesh(sphere(), tmp_path / "x.png")
    assert os.listdir(tmp_path) == []


def _model_names():
    """The registered models (the package must import and register some: no silent skip)."""
    import models

    return list(models.MODELS)


def test_models_are_registered():
    assert len(_model_names()) >= 6  # teapot, vase, mug, bracket, wing, block


@pytest.mark.parametrize("name", _model_names())
def test_each_model_renders(tmp_path, name):
    import models

    model = models.build_model(name)
    path = tmp_path / f"{name}.png"
    if model.bodies:
        patches = [p for body in model.bodies for p in body]
        render_patches(patches, path, size=SMALL, title=name)
    elif model.solids:  # exact B-rep solids are drawn as their tessellation
        from splinekit.cli import model_mesh

        render_mesh(model_mesh(model, 0.1)[0], path, size=SMALL, title=name)
    else:
        render_mesh(model.mesh, path, size=SMALL, title=name)
    assert_good_picture(path, min_coverage=0.05)


def test_render_command_on_a_written_mesh_file(tmp_path):
    """The installed command end to end: a mesh file in, a PNG of the asked size out."""
    import subprocess

    from test_cli import _command

    import exporters

    mesh = primitives.torus(32, 16)
    stl = exporters.export_stl(tmp_path / "torus.stl", mesh)
    result = subprocess.run(_command() + ["render", stl, "-o", str(tmp_path / "t.png"), "--size", "400x300",
                                          "--color", "mean"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "wrote" in result.stdout and "t.png" in result.stdout
    assert_good_picture(tmp_path / "t.png", size=(400, 300))
