"""The comparison of representations (``splinekit.compare``, ``splinekit compare``): the measured
figures agree with their definitions, checked against closed forms (the torus's and sphere's
exact distance functions) and against arrays counted independently of the code under test."""

from __future__ import annotations

import math
import os
import resource
import subprocess
import sys

import numpy as np
import pytest

import splinekit as sk
from splinekit import limits
from splinekit.comparison import REPRESENTATIONS, Reference, Shape, Table, compare, sphere, torus
from splinekit.comparison.holders_implicit import AnalyticImplicit, SDFGrid
from splinekit.comparison.holders_mesh import SubdivisionCage, SubdivisionLimit, TriangleMesh
from splinekit.comparison.holders_surface import ExactPatches, PointCloud, patch_set_genus
from splinekit.comparison.measure import accuracy
from splinekit.errors import NotManifoldError, ParameterError, ResourceLimitError, SplineKitError

R_MAJOR, R_MINOR = 1.0, 0.3


def torus_distance(points):
    """Exact unsigned distance to the torus of radii R_MAJOR, R_MINOR about the z axis."""
    p = np.asarray(points)
    return np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - R_MAJOR, p[:, 2]) - R_MINOR)


@pytest.fixture(scope="module")
def torus_reference():
    return Reference(torus(R_MAJOR, R_MINOR), samples=400)


@pytest.fixture(scope="module")
def mug_shape():
    from models import mug

    model = mug.build()
    return Shape("mug", tuple(model.bodies[0]), subdivision=mug.surface(**model.params))


# -- the table ------------------------------------------------------------------------------------
def test_table_columns_rows_and_markdown():
    t = Table([{"representation": "a", "bytes": 10, "hausdorff": 0.5}, {"representation": "b", "bytes": 2048}],
              units={"bytes": "B"})
    assert t["bytes"] == [10, 2048] and t["hausdorff"] == [0.5, None] and len(t) == 2
    assert t.where(representation="b")[0]["bytes"] == 2048
    md = t.to_markdown().splitlines()
    assert md[0] == "| representation | bytes (B) | hausdorff |" and md[3] == "| b | 2048 | -- |"
    with pytest.raises(ParameterError, match="no column 'nope'"):
        t["nope"]


# -- bytes are the arrays held ----------------------------------------------------------------------
def test_bytes_are_the_arrays_each_representation_holds(torus_reference):
    shape, ref = torus_reference.shape, torus_reference
    mesh = TriangleMesh(shape, ref, 1e-2)
    assert mesh.nbytes == mesh.mesh.vertices.nbytes + mesh.mesh.face_indices.nbytes + mesh.mesh.face_offsets.nbytes
    assert mesh.arrays["vertices"] is mesh.mesh.vertices  # what the queries read is what is counted
    grid = SDFGrid(shape, ref, 16)
    assert grid.nbytes == 8 * math.prod(grid.f.shape) and grid.arrays["values"] is grid.f.values
    cloud = PointCloud(shape, ref, 300)
    assert cloud.nbytes == 2 * 300 * 3 * 8  # points and normals, float64
    patches = ExactPatches(shape, ref, 2)
    counted = sum(p.control_points.nbytes + p.knots_u.nbytes + p.knots_v.nbytes + p.weights.nbytes
                  for p in patches.patches)
    assert patches.nbytes == counted
    analytic = AnalyticImplicit(shape, ref, 1)
    assert analytic.nbytes == 8 * (3 + 3 + 2)  # centre, axis, two radii


# -- accuracy against closed forms ------------------------------------------------------------------
@pytest.mark.parametrize("relative", [1e-2, 2e-3])
def test_mesh_at_tolerance_t_deviates_at_most_t(torus_reference, relative):
    ref = torus_reference
    holder = TriangleMesh(ref.shape, ref, relative)
    t = relative * ref.diagonal
    V = holder.mesh.vertices
    tris = V[np.asarray(holder.mesh.faces)]
    rng = np.random.default_rng(1)
    b = rng.dirichlet(np.ones(3), len(tris))
    inner = np.einsum("nk,nkd->nd", b, tris)
    assert torus_distance(np.vstack([tris.mean(axis=1), inner])).max() <= t
    fig = accuracy(holder, ref, rng, 2000)
    assert fig["hausdorff"] <= t + ref.tolerance and fig["genus"] == 1


def test_sdf_grid_error_is_at_most_its_spacing(torus_reference):
    ref = torus_reference
    for n in (16, 32):
        holder = SDFGrid(ref.shape, ref, n)
        zero_set = holder.surface_points(3000, np.random.default_rng(2))
        assert np.abs(holder.f(zero_set)).max() < 1e-6 * ref.diagonal  # they are on the zero set
        assert torus_distance(zero_set).max() <= holder.spacing
        assert accuracy(holder, ref, np.random.default_rng(3), 1000)["hausdorff"] <= holder.spacing


def test_refined_patches_are_the_same_surface(torus_reference):
    ref = torus_reference
    holder = ExactPatches(ref.shape, ref, 4)
    (p,), (q,) = ref.shape.patches, holder.patches
    assert q.control_points.shape[0] > p.control_points.shape[0]
    u, v = np.random.default_rng(4).random((2, 500))
    assert np.abs(p.evaluate(u, v) - q.evaluate(u, v)).max() < 1e-12
    assert torus_distance(holder.surface_points(500, np.random.default_rng(5))).max() < 1e-12


def test_analytic_implicit_is_exact_and_queries_agree_with_closed_forms(torus_reference):
    ref = torus_reference
    holder = AnalyticImplicit(ref.shape, ref, 1)
    q = ref.points[:200] + 0.01 * ref.normals[:200] * np.where(np.arange(200) % 2, 1, -1)[:, None]
    assert torus_distance(holder.closest(q)).max() < 1e-12
    assert np.array_equal(holder.inside(q), np.arange(200) % 2 == 0)  # even points moved inward
    assert np.abs(holder.distance(ref.points) - torus_distance(ref.points)).max() < 1e-12


def test_reference_volume_and_genus_match_closed_forms():
    ref = Reference(sphere(2.0), samples=200)
    assert ref.volume == pytest.approx(4 / 3 * math.pi * 8) and ref.genus == 0
    assert abs(ref.mesh.volume - ref.volume) / ref.volume < 1e-3
    area = 4 * math.pi * 4
    assert ref.weights.sum() == pytest.approx(area, rel=1e-2)  # the samples' area weights cover the surface
    np.testing.assert_allclose(ref.mean_curvature, 0.5, rtol=1e-9)  # |H| = 1/r


def test_genus_of_the_mug_is_one(mug_shape):
    assert patch_set_genus(mug_shape.patches, 1e-6) == 1
    assert sk.mesh.components.genus(mug_shape.subdivision.mesh) == 1


def test_subdivision_rows_converge_to_the_mug(mug_shape):
    ref = Reference(mug_shape, samples=600)
    rng = np.random.default_rng(6)
    cage = [accuracy(SubdivisionCage(mug_shape, ref, L), ref, rng, 600) for L in (0, 1)]
    limit = accuracy(SubdivisionLimit(mug_shape, ref, 1), ref, rng, 600)
    assert cage[1]["hausdorff"] < cage[0]["hausdorff"] and limit["hausdorff"] < cage[0]["hausdorff"]
    assert cage[1]["genus"] == limit["genus"] == 1


# -- the whole run ------------------------------------------------------------------------------------
def test_compare_on_the_sphere_reports_every_representation():
    table = compare(sphere(), resolutions={"triangle mesh": (1e-2, 3e-3), "SDF grid": (16, 24),
                                           "point cloud": (300, 1200), "exact patches": (1, 2)},
                    samples=200)
    names = list(dict.fromkeys(table["representation"]))
    assert names == list(REPRESENTATIONS)
    cage = table.where(representation="subdivision cage")[0]
    assert cage.get("bytes") is None and "no subdivision cage" in cage["note"]
    analytic = table.where(representation="analytic implicit")[0]
    assert analytic["hausdorff"] <= 2 * table.reference.tolerance and analytic["genus"] == 0
    growth = {r["representation"]: r for r in table.growth}
    assert growth["point cloud"]["memory_slope"] == pytest.approx(2.0)  # bytes ~ n = N^2
    assert 2.5 < growth["SDF grid"]["memory_slope"] < 3.5 and growth["SDF grid"]["memory_class"] == "O(N^3)"
    ops = table.operations
    assert ops["operation"] == ["render", "boolean", "bend", "curvature", "closest point"]
    assert ops[0]["point cloud"].startswith("n/a: the renderer draws surfaces")
    assert "error" in ops[1]["triangle mesh"] and "OpenCascade" in ops[1]["exact patches"]


# -- bad input ----------------------------------------------------------------------------------------
def test_unknown_representation_and_bad_resolutions_are_refused():
    with pytest.raises(ParameterError, match="unknown representation 'voxels'"):
        compare(sphere(), representations=["voxels"])
    with pytest.raises(ParameterError, match="resolution -1 of 'SDF grid'"):
        compare(sphere(), representations=["SDF grid"], resolutions={"SDF grid": [-1]})
    with pytest.raises(ParameterError, match="resolution nan"):
        compare(sphere(), representations=["point cloud"], resolutions={"point cloud": [float("nan")]})
    with pytest.raises(ParameterError, match="cannot compare str"):
        compare("mug")


def test_resolution_over_the_memory_budget_is_refused_before_any_work():
    with limits.budget("64M"):
        with pytest.raises(ResourceLimitError, match="SDF grid at resolution 2000"):
            compare(sphere(), representations=["SDF grid"], resolutions={"SDF grid": [32, 2000]})


def test_an_open_shape_is_refused():
    half = sk.brep.sphere(1.0).faces[0].surface.split(0.5, "u")[0]
    with pytest.raises(NotManifoldError, match="is open"):
        compare([half])
    assert issubclass(NotManifoldError, SplineKitError)


def test_splinekit_compare_is_the_function_and_the_package_is_separate():
    assert sk.compare is compare
    assert sk.comparison.compare is compare  # importing the package did not replace it
    assert callable(sk.compare)


# -- the command ----------------------------------------------------------------------------------------
def _child_cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def test_command_writes_tables_and_chart(tmp_path):
    """Timed in CPU seconds of the command's process: on the shared 2-core test machine the wall
    time measures the other jobs as much as this one."""
    out = tmp_path / "cmp"
    cpu0 = _child_cpu_seconds()
    result = subprocess.run([sys.executable, "-m", "splinekit.cli", "compare", "sphere", "--quick", "--samples", "200",
                             "--only", "triangle mesh,analytic implicit", "-o", str(out)],
                            capture_output=True, text=True, timeout=600)
    cpu = _child_cpu_seconds() - cpu0
    assert result.returncode == 0, result.stderr
    assert cpu < 60, f"the small comparison took {cpu:.0f} CPU seconds"
    text = (out / "compare.md").read_text()
    assert "## Memory, queries and topology" in text and "## Operations" in text and text.strip() in result.stdout
    png = (out / "accuracy.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_command_refuses_unknown_model_with_one_line(tmp_path):
    result = subprocess.run([sys.executable, "-m", "splinekit.cli", "compare", "nosuch", "-o", str(tmp_path)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode != 0 and "unknown model 'nosuch'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_default_command_on_the_mug_runs_in_under_a_minute(tmp_path):
    cpu0 = _child_cpu_seconds()
    result = subprocess.run([sys.executable, "-m", "splinekit.cli", "compare", "-q", "-o", str(tmp_path)],
                            capture_output=True, text=True, timeout=1800)
    assert result.returncode == 0, result.stderr
    assert _child_cpu_seconds() - cpu0 < 60
    assert os.path.exists(tmp_path / "accuracy.png")
