"""Conversions with measured loss (splinekit.convert).

Each conversion's reported ``error`` is compared with an independent
measurement on a shape whose distance function is known in closed form (a
sphere, a graph z = f(x, y)); tests/occ/test_convert_occ.py checks the fitted surface with
OpenCascade's point projection.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import splinekit as sk
from splinekit import convert
from splinekit.errors import SplineKitError
from splinekit.mesh import primitives
from splinekit.pointcloud import sample_mesh


def nurbs_sphere(radius=1.0):
    half = sk.arc_through_points((0, 0, -radius), (radius, 0, 0), (0, 0, radius))
    return sk.revolve(half, (0, 0, 0), (0, 0, 1))


def sphere_gap(points, radius=1.0, center=(0.0, 0.0, 0.0)):
    """Exact distance of points to a sphere."""
    return np.abs(np.linalg.norm(np.asarray(points) - center, axis=1) - radius)


def fibonacci_sphere(n, radius=1.0):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    t = np.pi * (1 + 5**0.5) * i
    s = np.sqrt(1 - z * z)
    return radius * np.column_stack([s * np.cos(t), s * np.sin(t), z])


def test_conversion_is_a_frozen_pair():
    c = convert.explicit_to_implicit(lambda x, y: x * y)
    result, error = c
    assert result is c.result and error == c.error
    assert isinstance(c.method, str) and isinstance(c.measured, str)
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.error = 1.0


def test_nurbs_to_mesh_error_matches_the_true_distance_to_the_sphere():
    tol = 2e-3
    c = convert.nurbs_to_mesh(nurbs_sphere(), tol, samples=3000)
    mesh = c.result
    assert mesh.is_closed
    # independent: mesh -> sphere by the closed form on a dense sample; sphere -> mesh is
    # dominated by the same chordal gaps for a convex mesh with vertices on the sphere
    truth = max(sphere_gap(sample_mesh(mesh, 200000, rng=1)).max(), sphere_gap(mesh.vertices).max())
    assert truth <= tol
    assert 0.8 * truth <= c.error <= 1.2 * truth


def test_sdf_to_mesh_error_matches_the_true_distance_to_the_sphere():
    center = np.array([0.3, -0.2, 0.1])
    from splinekit.implicit import sphere

    c = convert.sdf_to_mesh(sphere(center, 1.5), 0.12, samples=3000)
    assert c.result.is_closed
    truth = max(sphere_gap(sample_mesh(c.result, 200000, rng=2), 1.5, center).max(),
                sphere_gap(c.result.vertices, 1.5, center).max())
    assert 0.8 * truth <= c.error <= 1.2 * truth
    assert c.error < 0.12


def test_mesh_to_sdf_error_against_the_grid_values_on_the_mesh():
    mesh = primitives.icosphere(3)
    c = convert.mesh_to_sdf(mesh, 24, samples=3000)
    sdf = c.result
    # independent: at points of the mesh the exact signed distance is 0, and the grid's
    # interpolated value (gradient norm about 1) is how far its zero set lies from them
    pts = sample_mesh(mesh, 50000, rng=3)
    off = np.abs(sdf(pts)) / np.linalg.norm(sdf.gradient(pts), axis=1)
    assert c.error >= 0.8 * off.max()
    assert c.error <= 2.0 * float(np.linalg.norm(sdf.spacing))  # trilinear error of exact samples


def test_mesh_to_points_reports_the_covering_radius():
    mesh = primitives.icosphere(3)
    c = convert.mesh_to_points(mesh, 2000, rng=4)
    P = c.result
    assert P.shape == (2000, 3)
    assert sphere_gap(P).max() < 1.0  # on the mesh, inside the circumscribed sphere
    # independent: brute-force nearest-sample distances from a fresh dense sample of the mesh
    dense = sample_mesh(mesh, 10000, rng=5)
    d2 = (dense**2).sum(1)[:, None] + (P**2).sum(1)[None, :] - 2 * dense @ P.T
    cover = float(np.sqrt(np.maximum(d2.min(axis=1), 0)).max())
    assert 0.8 * cover <= c.error <= 1.25 * cover


def test_points_to_mesh_reconstructs_a_sphere():
    import trimesh  # the test extra installs it: no skip
    P = fibonacci_sphere(2500)
    c = convert.points_to_mesh(P, P, samples=3000)
    mesh = c.result
    assert mesh.is_closed
    assert sphere_gap(sample_mesh(mesh, 100000, rng=7)).max() < 0.02
    # independent two-sided cloud <-> mesh distance: trimesh for cloud -> mesh, brute-force
    # nearest input point for a fresh dense sample of the mesh
    tm = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=False)
    to_mesh = trimesh.proximity.closest_point(tm, P)[1].max()
    dense = sample_mesh(mesh, 10000, rng=8)
    d2 = (dense**2).sum(1)[:, None] + (P**2).sum(1)[None, :] - 2 * dense @ P.T
    to_cloud = np.sqrt(np.maximum(d2.min(axis=1), 0)).max()
    truth = max(to_mesh, to_cloud)
    assert 0.8 * truth <= c.error <= 1.25 * truth


def test_explicit_to_bspline_error_is_the_vertical_gap():
    def f(x, y):
        return np.exp(-x * x) * np.sin(2 * y)

    dom = ((-1.0, 2.0), (0.0, 1.5))
    coarse = convert.explicit_to_bspline(f, dom, 10)
    fine = convert.explicit_to_bspline(f, dom, 20)
    S = coarse.result
    rng = np.random.default_rng(8)
    x, y = rng.uniform(-1, 2, 20000), rng.uniform(0, 1.5, 20000)
    P = S.evaluate(x, y)
    assert np.allclose(P[:, :2], np.column_stack([x, y]), atol=1e-12)  # (u, v) = (x, y)
    gap = np.abs(P[:, 2] - f(x, y)).max()
    assert 0.8 * gap <= coarse.error <= 1.25 * gap
    # cubic interpolation converges at order 4 in the grid spacing
    assert 8 < coarse.error / fine.error < 32


def test_explicit_to_implicit_is_exact():
    def f(x, y):
        return x * x - 0.5 * y

    c = convert.explicit_to_implicit(f, ((-2, 2), (-1, 1)))
    assert c.error < 1e-14
    F = c.result
    assert np.allclose(F(np.array([[1.0, 1.0, 0.5 - 1.0], [0.0, 0.0, 2.0]])), [1.0, -2.0])


@pytest.mark.parametrize(
    "call",
    [
        lambda: convert.explicit_to_bspline(lambda x, y: x, ((1, 0), (0, 1)), 8),
        lambda: convert.explicit_to_bspline(lambda x, y: np.full_like(x, np.nan), ((0, 1), (0, 1)), 8),
        lambda: convert.explicit_to_bspline(lambda x, y: x, ((0, 1), (0, 1)), 3),
        lambda: convert.explicit_to_bspline("f", ((0, 1), (0, 1)), 8),
        lambda: convert.explicit_to_implicit(lambda x, y: np.ones(3), ((0, 1), (0, 1))),
        lambda: convert.sdf_to_mesh(lambda p: p[:, 0], 0.1),
        lambda: convert.mesh_to_points(primitives.icosphere(1), 0),
        lambda: convert.points_to_surface(np.zeros((0, 3))),
        lambda: convert.points_to_mesh(fibonacci_sphere(100), edge_length=-1.0),
        lambda: convert.nurbs_to_mesh([], 1e-3),
        lambda: convert.nurbs_to_mesh(nurbs_sphere(), 1e-3, samples=0),
        # a domain whose width overflows (linspace would warn and return inf)
        lambda: convert.explicit_to_bspline(lambda x, y: x, ((-1e308, 1e308), (0, 1)), 8),
        lambda: convert.explicit_to_implicit(lambda x, y: x, ((0, 1), (-1e308, 1e308))),
    ],
)
def test_bad_input_raises_a_splinekit_error(call):
    with pytest.raises(SplineKitError):
        call()


def test_sdf_to_mesh_refuses_bad_edge_length():
    from splinekit.implicit import sphere

    with pytest.raises(SplineKitError):
        convert.sdf_to_mesh(sphere((0, 0, 0), 1.0), 0.0)
    with pytest.raises(SplineKitError):
        convert.sdf_to_mesh(sphere((0, 0, 0), 1.0), float("nan"))


def test_explicit_to_bspline_degree_is_checked_as_a_degree():
    from splinekit.errors import DegreeError

    for bad in (0, 200, 1.5):
        with pytest.raises(DegreeError):
            convert.explicit_to_bspline(lambda x, y: x, ((0, 1), (0, 1)), 8, degree=bad)
