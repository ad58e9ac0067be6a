"""Deviation of clouds and meshes from parts, against known answers: a sampled surface
perturbed along its normals by a known field, the signed distance of a sphere and the exact
signed distance function of a box."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

import splinekit as sk
from splinekit import limits
from splinekit.analysis import deviation
from splinekit.brep import primitives
from splinekit.errors import ControlPointError, ParameterError, ResourceLimitError
from splinekit.mesh import PolyMesh
from splinekit.mesh import primitives as mesh_primitives


def wavy_patch():
    """A bicubic B-spline height field over [0, 1]^2 (8 x 8 control points)."""
    g = np.linspace(0.0, 1.0, 8)
    X, Y = np.meshgrid(g, g, indexing="ij")
    cp = np.stack([X, Y, 0.1 * np.sin(3 * X) * np.cos(2 * Y)], axis=-1)
    knots = np.r_[[0.0] * 4, np.linspace(0, 1, 6)[1:-1], [1.0] * 4]
    return sk.BSplineSurface(3, 3, knots, knots, cp)


def box_sdf(p, lo, hi):
    """Exact signed distance to the box [lo, hi] (positive outside)."""
    c, h = 0.5 * (lo + hi), 0.5 * (hi - lo)
    q = np.abs(p - c) - h
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def test_a_known_perturbation_along_the_normals_is_recovered():
    s = wavy_patch()
    rng = np.random.default_rng(7)
    u, v = rng.uniform(0.05, 0.95, 20000), rng.uniform(0.05, 0.95, 20000)
    f = 0.01 * np.sin(7 * u) * np.cos(5 * v)  # far below the radii of curvature (> 0.5)
    P = s.evaluate(u, v) + f[:, None] * s.normal(u, v)
    d = deviation(s, P)
    assert d.exact
    assert np.abs(d.distances - f).max() < 1e-12
    assert np.allclose(d.closest, s.evaluate(u, v), atol=1e-10)
    assert d.max == pytest.approx(np.abs(f).max(), abs=1e-12)
    assert d.rms == pytest.approx(np.sqrt(np.mean(f * f)), abs=1e-12)
    assert d.mean == pytest.approx(f.mean(), abs=1e-12)
    assert d.percentile(95) == pytest.approx(np.percentile(np.abs(f), 95), abs=1e-12)


@pytest.mark.parametrize("make", [lambda r: primitives.sphere(r), lambda r: mesh_primitives.icosphere(4, radius=r)],
                         ids=["exact", "mesh"])
def test_sphere_outside_is_positive(make):
    r = 2.0
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(3000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    rho = rng.uniform(1.2, 2.8, len(directions))
    d = deviation(make(r), directions * rho[:, None])
    clear = np.abs(rho - r) > 0.02  # farther from the sphere than the icosphere's facets (~0.002)
    assert np.array_equal(d.distances[clear] > 0, rho[clear] > r)
    if d.exact:  # the mesh's facets lie inside the sphere by up to its chordal error
        assert np.abs(d.distances - (rho - r)).max() < 1e-9


def test_box_deviation_is_the_exact_signed_distance():
    # points all around a box, near faces, edges and corners, inside and out: the closest point
    # may lie on a trim edge, where the sign comes from the pseudo-normals
    lo, hi = np.zeros(3), np.array([2.0, 3.0, 4.0])
    rng = np.random.default_rng(11)
    P = rng.uniform(lo - 1.0, hi + 1.0, size=(20000, 3))
    d = deviation(primitives.box(2, 3, 4), P)
    assert np.abs(d.distances - box_sdf(P, lo, hi)).max() < 1e-9


@settings(max_examples=25, deadline=None)
@given(st.floats(-0.2, 0.2), st.floats(0.1, 0.9), st.floats(0.1, 0.9))
def test_an_offset_along_the_normal_is_measured_with_its_sign(offset, u, v):
    s = wavy_patch()
    P = s.evaluate(np.array([u]), np.array([v])) + offset * s.normal(np.array([u]), np.array([v]))
    d = deviation(s, P)
    assert d.distances[0] == pytest.approx(offset, abs=1e-11)


def test_a_scan_mesh_is_measured_at_its_vertices(tmp_path):
    reference = primitives.sphere(1.0)
    scan = mesh_primitives.icosphere(3, radius=1.05)
    d = deviation(reference, scan)
    assert d.scan is scan and len(d.distances) == scan.n_vertices
    assert np.allclose(d.distances, 0.05, atol=1e-9)
    for name, draw in (("map.png", d.render), ("hist.png", d.histogram)):
        with Image.open(draw(tmp_path / name, size=(400, 300))) as image:
            assert image.size[0] > 100


def test_pictures_of_a_cloud(tmp_path):
    s = wavy_patch()
    rng = np.random.default_rng(5)
    u, v = rng.uniform(0, 1, 5000), rng.uniform(0, 1, 5000)
    P = s.evaluate(u, v) + (0.02 * u)[:, None] * s.normal(u, v)
    d = deviation(s, P)
    path = d.render(tmp_path / "cloud.png", size=(400, 300))
    with Image.open(path) as image:
        rgb = np.asarray(image.convert("RGB"), dtype=float)
    assert rgb.shape == (300, 400, 3)
    red = (rgb[..., 0] > 150) & (rgb[..., 2] < 100)  # the far positive end of the colour map
    assert red.mean() > 0.005
    with Image.open(d.histogram(tmp_path / "h.png", bins=30)) as image:
        assert image.size == (900, 500)


def test_summary_holds_every_statistic():
    P = np.array([[0.5, 0.5, 1.0], [0.2, 0.3, -0.5]])
    d = deviation(wavy_patch(), P)
    assert P.flags.writeable and not d.distances.flags.writeable  # the caller's array is left alone
    s = d.summary()
    assert set(s) == {"count", "max", "max_outside", "max_inside", "mean", "mean_abs", "rms", "std",
                      "p50", "p90", "p95", "p99"}
    assert s["count"] == 2 and s["max_inside"] < 0 < s["max_outside"]


@pytest.mark.parametrize("points, error, fragment", [
    (np.zeros((0, 3)), ControlPointError, "empty"),
    (np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 1.0]]), ControlPointError, r"points\[1\]"),
    (np.zeros((4, 2)), ControlPointError, "shape"),
    ("scan.xyz", ParameterError, "PolyMesh"),
])
def test_bad_clouds_are_named(points, error, fragment):
    with pytest.raises(error, match=fragment):
        deviation(wavy_patch(), points)


def test_the_memory_budget_is_checked_first():
    with limits.budget("1M"), pytest.raises(ResourceLimitError):
        deviation(wavy_patch(), np.zeros((100_000, 3)))


def test_bad_statistics_arguments(tmp_path):
    d = deviation(wavy_patch(), np.array([[0.5, 0.5, 0.1]]))
    with pytest.raises(ParameterError, match="percentage"):
        d.percentile(101)
    with pytest.raises(ParameterError, match="bins"):
        d.histogram(tmp_path / "h.png", bins=1)


def test_a_plain_mesh_reference():
    box = mesh_primitives.box(2.0)
    P = np.array([[0.0, 0.0, 1.5], [0.0, 0.0, 0.5], [1.5, 1.5, 0.0]])
    d = deviation(box, P)
    assert not d.exact
    assert np.allclose(d.distances, [0.5, -0.5, np.sqrt(0.5)], atol=1e-12)
    assert isinstance(d.reference.mesh, PolyMesh)


def test_an_inside_out_mesh_still_measures_outside_positive():
    box = mesh_primitives.box(2.0)
    inverted = PolyMesh(box.vertices, np.asarray(box.faces)[:, ::-1])
    P = np.array([[0.0, 0.0, 1.5], [0.0, 0.0, 0.5], [1.5, 1.5, 1.5]])
    for mesh in (box, inverted):
        assert np.allclose(deviation(mesh, P).distances, [0.5, -0.5, np.sqrt(0.75)], atol=1e-12)


@pytest.mark.parametrize("numba", ["0", "1"])
def test_points_near_a_seam_find_their_foot_across_it(numba, monkeypatch):
    """The compiled and the numpy nearest-triangle searches break ties differently; near the
    sphere's seam the nearest triangle may lie across it, and Newton from there stopped on the
    seam (6e-4 off). An answer stuck on a side where the patch closes on itself is retried from
    across the seam: the distance is |p| - r for every point, whichever search served."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", numba)
    r = 2.0
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(3000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    rho = rng.uniform(1.2, 2.8, len(directions))
    d = deviation(primitives.sphere(r), directions * rho[:, None])
    assert np.abs(d.distances - (rho - r)).max() < 1e-9
