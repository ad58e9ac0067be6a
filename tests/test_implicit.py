"""Implicit surfaces and SDFs: splinekit.implicit.

Checked against closed forms (distances to boxes, tori, capsules, cones;
lens and sphere volumes; sphere and torus curvature), against trimesh's
signed distance to an exact box mesh, and against the defining properties of a
signed distance (1-Lipschitz, and one gradient step lands on the zero set at
exactly |F| away), which together force |F| to be the distance.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit
import splinekit.implicit as si
from splinekit.errors import (
    ConvergenceError,
    DomainError,
    ParameterError,
    SplineKitError,
)
from splinekit.implicit.base import Implicit
from splinekit.mesh.polymesh import PolyMesh


class NumericOnly(Implicit):
    """The same function without analytic derivatives: the base class's central differences."""

    def __init__(self, f, step_factor=1.0):
        super().__init__(bounds=f.bounds, exact=f.is_exact_sdf)
        self.f, self.step_factor = f, step_factor

    @property
    def step(self):
        return super().step * self.step_factor

    def _value(self, p):
        return self.f._value(p)


def primitives():
    return {
        "sphere": si.sphere((0.1, 0.2, 0.3), 0.8),
        "box": si.box((0.1, 0.0, -0.1), (1.0, 0.6, 0.8)),
        "rounded_box": si.rounded_box((0.0, 0.1, 0.0), (1.0, 0.6, 0.8), 0.15),
        "torus": si.torus((0.0, 0.0, 0.1), 0.7, 0.2, axis=(1.0, 1.0, 0.0)),
        "cylinder": si.cylinder((0.0, 0.0, 0.1), 0.5, 1.2, axis=(0.0, 1.0, 1.0)),
        "capsule": si.capsule((0.0, 0.0, 0.0), (0.5, 0.3, 0.1), 0.3),
        "cone": si.cone((0.0, 0.0, -0.5), (0.0, 0.2, 0.7), 0.6),
        "frustum": si.cone((0.0, 0.0, -0.5), (0.3, 0.0, 0.6), 0.6, 0.2),
        "plane": si.plane((0.0, 0.0, 0.2), (1.0, 2.0, 3.0)),
    }


PRIMS = primitives()


# -- gradients -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(PRIMS))
def test_gradient_is_unit_and_matches_differences(name):
    f = PRIMS[name]
    p = np.random.default_rng(1).uniform(-1.5, 1.5, (3000, 3))
    g = f.gradient(p)
    g1 = NumericOnly(f).gradient(p)
    g2 = NumericOnly(f, 0.5).gradient(p)
    # away from the medial axis F is smooth, and two step sizes give the same difference;
    # a stencil straddling a kink gives a step-dependent blend
    smooth = np.linalg.norm(g1 - g2, axis=1) < 1e-8
    assert smooth.mean() > 0.97
    assert np.allclose(g[smooth], g1[smooth], atol=1e-7)
    assert np.allclose(np.linalg.norm(g[smooth], axis=1), 1.0, atol=1e-12)
    assert f.is_exact_sdf


@pytest.mark.parametrize("name", sorted(PRIMS))
def test_primitives_are_signed_distances(name):
    """1-Lipschitz and ``q = p - F grad F`` has F(q) = 0: then |F(p)| <= dist(p, S)
    (Lipschitz, as F = 0 on S) and dist(p, S) <= |p - q| = |F(p)|."""
    f = PRIMS[name]
    rng = np.random.default_rng(2)
    p = rng.uniform(-1.5, 1.5, (2000, 3))
    q = rng.uniform(-1.5, 1.5, (2000, 3))
    assert np.all(np.abs(f(p) - f(q)) <= np.linalg.norm(p - q, axis=1) * (1 + 1e-12) + 1e-13)
    F = f(p)
    g = f.gradient(p)
    on = p - F[:, None] * g
    assert np.abs(f(on)).max() < 1e-9


def test_box_against_trimesh_exact_mesh():
    import trimesh  # the test extra installs it: no skip
    center, size = np.array([0.2, -0.1, 0.3]), np.array([1.0, 2.0, 0.6])
    mesh = trimesh.creation.box(extents=size)
    mesh.apply_translation(center)
    f = si.box(center, size)
    p = np.random.default_rng(3).uniform(-1.5, 1.5, (500, 3))
    ref = -trimesh.proximity.signed_distance(mesh, p)  # trimesh: positive inside
    assert np.allclose(f(p), ref, atol=1e-9)


def test_box_closed_forms():
    f = si.box((0.0, 0.0, 0.0), (2.0, 4.0, 6.0))  # half extents 1, 2, 3
    p = [[3, 0, 0], [2, 3, 0], [2, 3, 4], [0.5, 0, 0], [0, 0, 0], [0, 1.5, 2.9], [-1, -2, -3]]
    expect = [2.0, np.sqrt(2.0), np.sqrt(3.0), -0.5, -1.0, -0.1, 0.0]
    assert np.allclose(f(p), expect, atol=1e-14)
    assert np.allclose(f.gradient([[2, 3, 4]]), [np.ones(3) / np.sqrt(3)], atol=1e-15)
    assert np.allclose(f.gradient([[0.5, 0.2, -0.1]]), [[1, 0, 0]])


def test_rounded_box_closed_forms():
    f = si.rounded_box((0.0, 0.0, 0.0), (2.0, 2.0, 2.0), 0.5)
    inner_corner = np.full(3, 0.5)
    p = np.array([[3.0, 0, 0], [2.0, 2.0, 2.0], [0.0, 0.0, 0.0], [2.0, 2.0, 0.0]])
    expect = [2.0, np.linalg.norm(p[1] - inner_corner) - 0.5, -1.0, np.hypot(1.5, 1.5) - 0.5]
    assert np.allclose(f(p), expect, atol=1e-14)
    assert np.array_equal(f.bounds[0], [-1, -1, -1]) and np.array_equal(f.bounds[1], [1, 1, 1])


def test_spindle_torus_is_exact_outside_only():
    # R < r: at the centre F = R - r, but the dimples on the axis (on the zero set) are
    # sqrt(r^2 - R^2) away, nearer than |F| allows for a signed distance
    R, r = 0.5, 1.0
    f = si.torus((0, 0, 0), R, r)
    dimple = np.sqrt(r * r - R * R)
    assert np.allclose(f([[0, 0, 0], [0, 0, dimple], [0, 0, -dimple], [R + r, 0, 0]]), [R - r, 0, 0, 0], atol=1e-15)
    assert dimple > abs(R - r)  # so F is not the distance at the centre
    assert not f.is_exact_sdf and si.torus((0, 0, 0), 1.0, 1.0).is_exact_sdf
    # outside it is still the distance: one gradient step lands on the zero set |F| away
    p = np.random.default_rng(21).uniform(-3, 3, (2000, 3))
    p = p[f(p) > 0]
    on = p - f(p)[:, None] * f.gradient(p)
    assert np.abs(f(on)).max() < 1e-12


def test_torus_closed_forms():
    R, r = 2.0, 0.5
    f = si.torus((0, 0, 0), R, r)
    p = [[4, 0, 0], [0, 0, 0], [2, 0, 1], [0, -2, 0], [0, 0, 3], [2.5, 0, 0]]
    expect = [1.5, R - r, 0.5, -0.5, np.hypot(R, 3) - r, 0.0]
    assert np.allclose(f(p), expect, atol=1e-14)
    # the same torus about the x axis, centred elsewhere
    g = si.torus((1, 2, 3), R, r, axis=(-3.0, 0, 0))
    q = np.array(p)[:, [2, 0, 1]] + [1, 2, 3]
    assert np.allclose(g(q), expect, atol=1e-14)
    assert np.allclose(g.bounds[0], [1 - r, 2 - R - r, 3 - R - r])


def test_capsule_cylinder_cone_plane_closed_forms():
    cap = si.capsule((0, 0, 0), (0, 0, 2), 0.5)
    assert np.allclose(cap([[1, 0, 1], [0, 0, 3], [0, 0, -1], [0, 0, 1], [3, 4, 2]]), [0.5, 0.5, 0.5, -0.5, 4.5], atol=1e-14)
    cyl = si.cylinder((0, 0, 0), 1.0, 2.0)
    assert np.allclose(cyl([[2, 0, 0], [0, 0, 3], [2, 0, 2], [0.5, 0, 0], [0, 0, 0.8], [0, 3, 0]]),
                       [1, 2, np.sqrt(2), -0.5, -0.2, 2], atol=1e-14)  # fmt: skip
    cone = si.cone((0, 0, 0), (0, 0, 1), 1.0)  # base radius 1 at z = 0, apex at z = 1
    pts = [[1, 0, 1], [0, 0, -1], [0, 0, 2], [0.1, 0, 0.1], [2, 0, -1], [0, 0.3, 0.5]]
    expect = [1 / np.sqrt(2), 1.0, 1.0, -0.1, np.sqrt(2), -0.2 / np.sqrt(2)]
    assert np.allclose(cone(pts), expect, atol=1e-14)
    frustum = si.cone((0, 0, 0), (0, 0, 2), 1.0, 1.0)  # a cylinder of radius 1
    assert np.allclose(frustum(np.array([[2, 0, 0], [0, 0, 3], [2, 0, 2], [0.5, 0, 0]]) + [0, 0, 1]),
                       [1, 2, np.sqrt(2), -0.5], atol=1e-14)  # fmt: skip
    pl = si.plane((1, 0, 0), (0, 3, 4))
    assert np.allclose(pl([[0, 3, 4], [5, 0, 0]]), [5, 0])
    assert pl.bounds is None


def test_gradients_on_the_surface_are_outward_normals():
    cone = si.cone((0, 0, 0), (0, 0, 1), 1.0)
    on = [[0.5, 0, 0.5], [0.2, 0, 0], [0, -0.3, 0.7]]
    expect = [[1, 0, 1], [0, 0, -1], [0, -1, 1]]
    expect = np.array(expect) / np.linalg.norm(expect, axis=1)[:, None]
    assert np.allclose(cone(on), 0, atol=1e-15) and np.allclose(cone.gradient(on), expect, atol=1e-12)
    cyl = si.cylinder((0, 0, 0), 1.0, 2.0)
    on = [[1, 0, 0], [0, 0.5, 1], [0.3, 0, -1], [0, -1, 0.2]]
    assert np.allclose(cyl(on), 0, atol=1e-15)
    assert np.allclose(cyl.gradient(on), [[1, 0, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0]])
    box = si.box((0, 0, 0), 2.0)
    assert np.allclose(box.gradient([[1, 0.2, 0.3], [0.1, -1, 0.3]]), [[1, 0, 0], [0, -1, 0]])


def test_empty_point_sets():
    e = np.zeros((0, 3))
    tree = si.smooth_union(si.sphere(), si.box((0.5, 0, 0), 1.0), 0.1).rotate((0, 0, 1), 1.0)
    for f in list(PRIMS.values()) + [tree, NumericOnly(si.torus())]:
        assert f(e).shape == (0,) and f.gradient(e).shape == (0, 3) and f.hessian(e).shape == (0, 3, 3)
        assert f.normal(e).shape == (0, 3) and f.closest_points(e).shape == (0, 3)


# -- curvature and closest points ------------------------------------------------------------
def test_sphere_curvature():
    c0 = np.array([0.3, -0.2, 0.5])
    f = si.sphere(c0, 2.0)
    d = np.random.default_rng(4).normal(size=(50, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    rho = np.linspace(0.5, 4.0, 50)
    curv = splinekit.curvature(f, c0 + rho[:, None] * d)  # level sets are spheres of radius rho
    # the shape operator is -P Hess P / |grad F|: k = -1 / rho for the outward normal
    assert np.allclose(curv.k1, -1 / rho, rtol=1e-8) and np.allclose(curv.k2, -1 / rho, rtol=1e-8)
    assert np.allclose(curv.gaussian, 1 / rho**2, rtol=1e-8)
    assert np.allclose(curv.normal, d, atol=1e-12)


def test_torus_curvature():
    R, r = 2.0, 0.5
    f = si.torus((0, 0, 0), R, r)
    rng = np.random.default_rng(5)
    theta, phi = rng.uniform(0, 2 * np.pi, (2, 40))  # tube angle, angle about the axis
    rho = R + r * np.cos(theta)
    p = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), r * np.sin(theta)])
    curv = splinekit.curvature(f, p)
    # principal curvatures 1 / r (tube) and cos(theta) / rho (about the axis), signs as for the sphere
    expect = np.sort(np.column_stack([-np.full(40, 1 / r), -np.cos(theta) / rho]), axis=1)
    got = np.sort(np.column_stack([curv.k1, curv.k2]), axis=1)
    assert np.allclose(got, expect, atol=1e-6)
    assert np.allclose(curv.gaussian, np.cos(theta) / (r * rho), atol=1e-6)


@pytest.mark.parametrize("name", ["sphere", "box", "torus", "cone", "capsule"])
def test_closest_points_of_exact_sdfs(name):
    f = PRIMS[name]
    p = np.random.default_rng(6).uniform(-1.5, 1.5, (500, 3))
    q = f.closest_points(p)
    assert np.abs(f(q)).max() < 1e-9
    assert np.allclose(np.linalg.norm(p - q, axis=1), np.abs(f(p)), atol=1e-9)
    proj = splinekit.project(f, p)  # the shared projection accepts every implicit
    assert np.allclose(proj.points, q, atol=1e-8)


def test_closest_points_of_blends_land_on_the_surface():
    f = si.smooth_union(si.sphere((0, 0, 0), 1.0), si.box((1.0, 0, 0), (1.0, 0.5, 0.5)), 0.3)
    f = f - si.cylinder((0, 0, 0), 0.3, 4.0, axis=(1, 0, 0))
    p = np.random.default_rng(7).uniform(-2, 2, (500, 3))
    p = p[np.linalg.norm(f.gradient(p), axis=1) > 0.1]
    q = f.closest_points(p, tol=1e-10)
    assert np.abs(f(q)).max() < 1e-9


# -- CSG and meshing ------------------------------------------------------------------------------
def lens_volume(r, d):
    """Intersection of two balls of radius r whose centres are d apart."""
    return np.pi * (4 * r + d) * (2 * r - d) ** 2 / 12


def max_edge(mesh):
    V, T = mesh.vertices, np.asarray(mesh.faces)
    return float(np.linalg.norm(V[T] - V[np.roll(T, 1, axis=1)], axis=2).max())


def test_sphere_mesh_volume_within_edge_length_bound():
    R, h = 1.0, 0.06
    mesh = si.sphere((0.2, 0.1, -0.3), R).to_mesh(h)
    assert isinstance(mesh, PolyMesh) and mesh.is_closed and mesh.euler_characteristic == 2
    # bound: vertices interpolate |p| - R linearly along tetrahedron edges of length <= sqrt(3) h
    # (error <= 3 h^2 / (8R)); every point of a triangle lies within e_max / sqrt(3) of a vertex,
    # where the sphere has fallen away from the vertex's tangent plane by at most
    # (e_max^2 / 3) / (2R). The triangles lie in grid cells, so e_max <= sqrt(3) h (checked).
    e = max_edge(mesh)
    assert e <= np.sqrt(3) * h
    bound = mesh.area * (3 * h**2 / (8 * R) + e**2 / (6 * R))
    assert abs(mesh.volume - 4 / 3 * np.pi * R**3) <= bound
    assert mesh.deviation <= 3 * h**2 / (8 * R) + e**2 / (6 * R)
    assert abs(mesh.volume - 4 / 3 * np.pi * R**3) <= mesh.deviation * mesh.area
    # the mesh is outward-facing: positive volume, normals agree with the gradient
    assert mesh.volume > 0
    V = mesh.vertices
    assert np.min(np.einsum("ij,ij->i", mesh.vertex_normals, si.sphere((0.2, 0.1, -0.3), R).normal(V))) > 0.9


@pytest.mark.parametrize("d", [0.6, 1.2])
def test_lens_and_union_volumes(d):
    r, h = 1.0, 0.07
    a = si.sphere((-d / 2, 0, 0), r)
    b = si.sphere((d / 2, 0, 0), r)
    lens = (a & b).to_mesh(h)
    union = (a | b).to_mesh(h)
    v_lens = lens_volume(r, d)
    v_union = 2 * 4 / 3 * np.pi * r**3 - v_lens
    # every point of the mesh is within `deviation` of the surface, so the volumes differ by at
    # most deviation * area
    for mesh, v in ((lens, v_lens), (union, v_union)):
        assert mesh.is_closed
        assert 0 < mesh.deviation < h
        assert abs(mesh.volume - v) <= mesh.deviation * mesh.area
    # the difference is the union minus the other ball
    diff = (a - b).to_mesh(h)
    assert abs(diff.volume - (4 / 3 * np.pi - v_lens)) <= diff.deviation * diff.area


@pytest.mark.parametrize("h", [0.1, 0.05])
def test_torus_mesh_is_watertight_of_genus_one_with_closed_form_area_and_volume(h):
    R, r = 1.0, 0.35
    torus = si.torus((0.1, -0.2, 0.3), R, r, axis=(1, 1, 0))
    mesh = torus.to_mesh(h)
    assert mesh.is_closed and mesh.euler_characteristic == 0
    # manifold3d's own check of the raw arrays: an oriented, edge-manifold closed surface
    import manifold3d

    T = np.array(mesh.faces, dtype=np.uint64, order="C")
    m = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.array(mesh.vertices, order="C"), tri_verts=T))
    assert m.status() == manifold3d.Error.NoError and m.genus() == 1
    # the true distance of the vertices to the torus is below the measured deviation, and the
    # closed forms 4 pi^2 R r (area) and 2 pi^2 R r^2 (volume) are met within deviation * area
    # (volume) and the O(h^2) chordal loss (area; the second-order term of a sphere-like patch)
    V = np.asarray(mesh.vertices) - (0.1, -0.2, 0.3)
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    along = V @ axis
    rho = np.linalg.norm(V - along[:, None] * axis, axis=1)
    true = np.abs(np.hypot(rho - R, along) - r)
    assert true.max() <= mesh.deviation * (1 + 1e-9)
    assert abs(mesh.volume - 2 * np.pi**2 * R * r**2) <= mesh.deviation * mesh.area
    assert abs(mesh.area / (4 * np.pi**2 * R * r) - 1) <= h**2 / (R - r) / r
    assert max_edge(mesh) <= np.sqrt(3) * h


def test_to_mesh_with_explicit_bounds_and_empty_result():
    half = si.plane((0, 0, 0), (0, 0, 1))
    mesh = half.to_mesh(0.1, bounds=((-1, -1, -1), (1, 1, 1)))
    assert mesh.is_closed and mesh.volume == pytest.approx(4.0, rel=1e-9)  # a clipped half-cube
    far = si.sphere((5, 5, 5), 0.5)
    empty = far.to_mesh(0.1, bounds=((-1, -1, -1), (1, 1, 1)))
    assert empty.n_faces == 0 and empty.deviation == 0.0
    clone = pickle.loads(pickle.dumps(mesh))
    assert clone == mesh and clone.deviation == mesh.deviation


def test_csg_values_and_bounds():
    a = si.sphere((0, 0, 0), 1.0)
    b = si.box((1, 0, 0), 1.0)
    p = np.random.default_rng(8).uniform(-2, 2, (1000, 3))
    assert np.array_equal((a | b)(p), np.minimum(a(p), b(p)))
    assert np.array_equal((a & b)(p), np.maximum(a(p), b(p)))
    assert np.array_equal((a - b)(p), np.maximum(a(p), -b(p)))
    assert np.array_equal((-a)(p), -a(p)) and si.complement(-a) is a
    assert np.allclose(a.offset(0.25)(p), a(p) - 0.25)
    assert np.allclose(a.shell(0.2)(p), np.abs(a(p)) - 0.1)
    assert not (a | b).is_exact_sdf and not (a & b).is_exact_sdf and (-a).is_exact_sdf
    assert a.offset(0.3).is_exact_sdf and not si.torus().offset(0.1).is_exact_sdf
    lo, hi = (a | b).bounds
    assert np.allclose(lo, [-1, -1, -1]) and np.allclose(hi, [1.5, 1, 1])
    lo, hi = (a & b).bounds
    assert np.allclose(lo, [0.5, -0.5, -0.5]) and np.allclose(hi, [1, 0.5, 0.5])
    assert (-a).bounds is None
    # the box is conservative: outside it every built-in tree is positive
    tree = si.smooth_union(a, b, 0.4).offset(0.1).shell(0.05)
    lo, hi = tree.bounds
    far = np.random.default_rng(9).uniform(-4, 4, (4000, 3))
    out = ((far < lo) | (far > hi)).any(axis=1)
    assert np.all(tree(far[out]) > 0)


def test_offsets_of_rotated_intersections_stay_in_their_boxes():
    # two crossing slabs: max(a, b) is far below the distance to the overlap box near its
    # diagonal, so an offset grows the solid by more than r there once rotated
    x = si.box((0, 0, 0), (8.0, 1.0, 1.0))
    y = si.box((0, 0, 0), (1.0, 8.0, 1.0))
    tree = (x & y).rotate((0, 0, 1), np.pi / 4).offset(1.5).rotate((1, 0, 0), 0.7).shell(0.4)
    lo, hi = tree.bounds
    p = np.random.default_rng(16).uniform(lo - 3, hi + 3, (20000, 3))
    out = ((p < lo) | (p > hi)).any(axis=1)
    assert out.sum() > 1000 and np.all(tree(p[out]) > 0)
    assert tree._growth == pytest.approx(np.sqrt(2) * (np.cos(0.7) + np.sin(0.7)))  # max row sums of |R|


def test_csg_gradients_match_differences():
    a = si.sphere((0, 0, 0), 1.0)
    b = si.torus((0.5, 0, 0), 0.8, 0.3, axis=(0, 1, 0))
    trees = [a | b, a & b, a - b, -b, si.smooth_union(a, b, 0.3), si.smooth_intersection(a, b, 0.3),
             si.smooth_difference(a, b, 0.3), b.shell(0.1), a.offset(-0.2)]  # fmt: skip
    p = np.random.default_rng(10).uniform(-1.5, 1.5, (2000, 3))
    for f in trees:
        g1, g2 = NumericOnly(f).gradient(p), NumericOnly(f, 0.5).gradient(p)
        smooth = np.linalg.norm(g1 - g2, axis=1) < 1e-8
        assert smooth.mean() > 0.9, f
        assert np.allclose(f.gradient(p)[smooth], g1[smooth], atol=1e-7), f


def test_every_built_in_implicit_has_analytic_gradients():
    a, b = si.sphere(), si.box((0.5, 0, 0), 1.0)
    objects = list(PRIMS.values()) + [a | b, a & b, a - b, -a, si.smooth_union(a, b, 0.1),
               si.smooth_intersection(a, b, 0.1), si.smooth_difference(a, b, 0.1), a.offset(0.1),
               b.shell(0.1), b.translate((1, 0, 0)), si.rounded_box((0, 0, 0), 1.0, 0.1)]  # fmt: skip
    for f in objects:
        assert type(f)._gradient is not Implicit._gradient, type(f).__name__


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-2, 2), min_size=8, max_size=8),
    st.floats(0.05, 1.0),
)
def test_smooth_min_properties(vals, k):
    a = si.sphere(vals[0:3], 0.3 + abs(vals[6]))
    b = si.box(vals[3:6], 0.3 + abs(vals[7]))
    p = np.random.default_rng(11).uniform(-3, 3, (300, 3))
    m = np.minimum(a(p), b(p))
    s = si.smooth_union(a, b, k)(p)
    assert np.all(s <= m + 1e-12) and np.all(s >= m - k / 4 - 1e-12)
    far = np.abs(a(p) - b(p)) >= k
    assert np.allclose(s[far], m[far], atol=1e-12)
    assert np.allclose(si.smooth_intersection(a, b, k)(p), -si.smooth_union(-a, -b, k)(p), atol=1e-12)
    # De Morgan holds exactly for min / max
    assert np.array_equal((-(a | b))(p), ((-a) & (-b))(p))


# -- transforms -----------------------------------------------------------------------------------
def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_transforms_against_direct_constructions():
    rng = np.random.default_rng(12)
    p = rng.uniform(-3, 3, (1000, 3))
    R, t, s = random_rotation(rng), rng.normal(size=3), 1.7
    # sphere: scaled about the origin, then moved
    c = np.array([0.3, -0.2, 0.1])
    assert np.allclose(si.sphere(c, 0.5).scale(s).translate(t)(p), si.sphere(s * c + t, s * 0.5)(p), atol=1e-12)
    # torus and cylinder rotated: same as built with the rotated axis and centre
    tor = si.torus(c, 0.8, 0.2).rotate(R).translate(t)
    assert np.allclose(tor(p), si.torus(R @ c + t, 0.8, 0.2, axis=R[:, 2])(p), atol=1e-12)
    cyl = si.cylinder(c, 0.4, 1.1).scale(s).rotate(R)
    assert np.allclose(cyl(p), si.cylinder(R @ (s * c), s * 0.4, s * 1.1, axis=R[:, 2])(p), atol=1e-12)
    a, b = np.array([0.0, 0.1, 0.2]), np.array([0.5, -0.4, 0.3])
    cap = si.capsule(a, b, 0.25).translate(t).rotate(R).scale(s)
    assert np.allclose(cap(p), si.capsule(s * R @ (a + t), s * R @ (b + t), s * 0.25)(p), atol=1e-12)
    # axis + angle: a quarter turn about z takes x to y
    box = si.box((1, 0, 0), (1.0, 0.2, 0.2)).rotate((0, 0, 1), np.pi / 2)
    assert np.allclose(box(p), si.box((0, 1, 0), (0.2, 1.0, 0.2))(p), atol=1e-12)
    # gradients and Hessians transform with the map
    assert np.allclose(tor.gradient(p), si.torus(R @ c + t, 0.8, 0.2, axis=R[:, 2]).gradient(p), atol=1e-9)
    sph = si.sphere(c, 0.5).rotate(R).scale(s)
    assert np.allclose(sph.hessian(p), si.sphere(s * R @ c, s * 0.5).hessian(p), atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-2, 2), min_size=6, max_size=6),
    st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    st.floats(-4, 4),
    st.floats(0.2, 5.0),
)
def test_merged_transforms_equal_the_chain(t, axis, angle, s):
    """translate / rotate / scale merge into one Transformed; the merged map must
    equal the chain of separate maps applied one after another."""
    from splinekit.implicit.csg import Transformed, rotation_matrix

    f = si.torus((0.2, -0.1, 0.3), 0.7, 0.2, axis=(1, 0, 1)) - si.box((0, 0, 0), (0.4, 2.0, 0.4))
    R = rotation_matrix(axis, angle)
    eye, zero = np.eye(3), np.zeros(3)
    chain = Transformed(Transformed(Transformed(f, eye, np.array(t[:3]), 1.0), R, zero, 1.0), eye, zero, s)
    chain = Transformed(chain, eye, np.array(t[3:]), 1.0)
    merged = f.translate(t[:3]).rotate(axis, angle).scale(s).translate(t[3:])
    assert isinstance(merged, Transformed) and merged.a is f
    p = np.random.default_rng(15).uniform(-4, 4, (200, 3))
    assert np.allclose(merged(p), chain(p), atol=1e-10)
    assert np.allclose(merged.gradient(p), chain.gradient(p), atol=1e-10)
    # one rotation of the box's corners is tighter than rotating an already rotated box
    assert np.all(merged.bounds[0] >= chain.bounds[0] - 1e-9) and np.all(merged.bounds[1] <= chain.bounds[1] + 1e-9)
    lo, hi = merged.bounds
    out = ((p < lo) | (p > hi)).any(axis=1)
    assert np.all(merged(p[out]) > 0)


def test_transformed_box_is_still_a_signed_distance():
    rng = np.random.default_rng(13)
    f = si.box((0.2, 0, 0), (1.0, 0.5, 0.7)).rotate(random_rotation(rng)).scale(0.6).translate((1, 2, 3))
    assert f.is_exact_sdf
    p = rng.uniform(-1, 1, (2000, 3)) + [1, 2, 3]
    q = rng.uniform(-1, 1, (2000, 3)) + [1, 2, 3]
    assert np.all(np.abs(f(p) - f(q)) <= np.linalg.norm(p - q, axis=1) * (1 + 1e-12) + 1e-13)
    assert np.abs(f(p - f(p)[:, None] * f.gradient(p))).max() < 1e-9
    lo, hi = f.bounds
    out = ((p < lo) | (p > hi)).any(axis=1)
    assert np.all(f(p[out]) > 0)


# -- bad input --------------------------------------------------------------------------------------
def test_zero_gradient_normal_names_the_point():
    f = si.sphere((1.0, 2.0, 3.0), 1.0)
    with pytest.raises(DomainError, match=r"1\.0, 2\.0, 3\.0"):
        f.normal([[0, 0, 0], [1.0, 2.0, 3.0]])
    with pytest.raises(DomainError, match="gradient vanishes"):
        f.closest_points([[1.0, 2.0, 3.0]])
    with pytest.raises(DomainError, match="not finite"):
        splinekit.curvature(f, np.array([[1.0, 2.0, 3.0]]))


@pytest.mark.parametrize(
    "call",
    [
        lambda: si.sphere((0, 0, 0), -1.0),
        lambda: si.sphere((0, 0, 0), 0.0),
        lambda: si.sphere((0, 0), 1.0),
        lambda: si.sphere((0, np.nan, 0), 1.0),
        lambda: si.box((0, 0, 0), (1, -1, 1)),
        lambda: si.rounded_box((0, 0, 0), 1.0, 0.6),
        lambda: si.torus((0, 0, 0), 1.0, -0.1),
        lambda: si.torus((0, 0, 0), 1.0, 0.1, axis=(0, 0, 0)),
        lambda: si.cylinder((0, 0, 0), 1.0, 0.0),
        lambda: si.capsule((0, 0, 0), (1, 0, 0), -0.1),
        lambda: si.cone((0, 0, 0), (0, 0, 0), 1.0),
        lambda: si.cone((0, 0, 0), (0, 0, 1), 0.0, 0.0),
        lambda: si.cone((0, 0, 0), (0, 0, 1), -1.0),
        lambda: si.plane((0, 0, 0), (0, 0, 0)),
        lambda: si.sphere().scale(-2.0),
        lambda: si.sphere().scale(0.0),
        lambda: si.sphere().translate((1, 2)),
        lambda: si.sphere().rotate(np.diag([1.0, 1.0, 2.0])),
        lambda: si.sphere().rotate(np.diag([1.0, 1.0, -1.0])),
        lambda: si.sphere().rotate((0, 0, 0), 1.0),
        lambda: si.sphere().rotate((0, 0, 1), np.inf),
        lambda: si.sphere() | 3.0,
        lambda: si.sphere() & "box",
        lambda: si.smooth_union(si.sphere(), si.box(), -0.1),
        lambda: si.sphere().shell(0.0),
        lambda: si.sphere().offset(np.nan),
        lambda: si.sphere()([[0, 0]]),
        lambda: si.sphere()(np.zeros((2, 3, 3))),
        lambda: si.sphere()([[0, 0, np.inf]]),
        lambda: si.sphere().gradient([[np.nan, 0, 0]]),
        lambda: si.sphere()("abc"),
        lambda: si.sphere()([[1e308, 1e308, 0]]),
        lambda: si.sphere().closest_points([[2, 0, 0]], tol=-1.0),
        lambda: si.sphere().closest_points([[2, 0, 0]], max_iter=0),
        lambda: si.sphere().to_mesh(0.0),
        lambda: si.sphere().to_mesh(-0.1),
        lambda: si.sphere().to_mesh(np.nan),
        lambda: si.sphere().to_mesh(1e-4),
        lambda: si.plane().to_mesh(0.1),
        lambda: si.sphere().to_mesh(0.1, bounds=((1, 1, 1), (0, 0, 0))),
        lambda: si.sphere().to_mesh(0.1, bounds=((0, 0), (1, 1))),
        lambda: si.plane().to_mesh(5.0, bounds=((-1, -1, -1), (1, 1, 1))),
        lambda: si.plane().to_mesh(0.1, bounds=((-1, -1, -1), (1, 1, np.inf))),
        # grid counts beyond int64 (wrapped to a negative total before) and beyond the float range
        lambda: si.sphere().to_mesh(1e-7),
        lambda: si.sphere().to_mesh(1e-320),
        lambda: si.plane().to_mesh(0.5, bounds=((-1e308,) * 3, (1e308,) * 3)),
    ],
)
def test_bad_input_raises_splinekit_error(call):
    with pytest.raises(SplineKitError):
        call()


def test_bad_input_messages_name_the_value():
    with pytest.raises(ParameterError, match=r"points\[1\] = \[0\.0, 0\.0, inf\]"):
        si.sphere()([[0, 0, 0], [0, 0, np.inf]])
    with pytest.raises(ParameterError, match="radius must be > 0, got -1.0"):
        si.sphere((0, 0, 0), -1.0)
    with pytest.raises(ParameterError, match=r"size\[1\] = -1.0"):
        si.box((0, 0, 0), (1, -1, 1))
    with pytest.raises(ParameterError, match="pass bounds"):
        si.plane().to_mesh(0.1)
    with pytest.raises(ParameterError, match="edge length"):
        si.sphere().to_mesh(1e-4)


def test_non_convergence_is_reported():
    # F = |p|^3 - 1 style growth: a user implicit whose Newton steps cannot converge in one step
    class Cubic(Implicit):
        def __init__(self):
            super().__init__(bounds=((-1, -1, -1), (1, 1, 1)))

        def _value(self, p):
            return np.sum(p**2, axis=1) ** 1.5 - 1.0

    with pytest.raises(ConvergenceError, match="did not reach"):
        Cubic().closest_points([[30.0, 0, 0]], max_iter=2)
    q = Cubic().closest_points([[30.0, 0, 0]])
    assert np.allclose(q, [[1, 0, 0]], atol=1e-9)


def test_user_subclass_numeric_derivatives_and_nan_values():
    class Bad(Implicit):
        def _value(self, p):
            return np.where(p[:, 0] > 0, np.nan, 1.0)

    with pytest.raises(DomainError, match=r"points\[1\]"):
        Bad()([[-1, 0, 0], [1, 0, 0]])

    class Ellipsoid(Implicit):
        def __init__(self):
            super().__init__(bounds=((-2, -1, -1), (2, 1, 1)))

        def _value(self, p):
            return (p[:, 0] / 2) ** 2 + p[:, 1] ** 2 + p[:, 2] ** 2 - 1

    e = Ellipsoid()
    p = np.random.default_rng(14).uniform(-1, 1, (100, 3))
    assert e.step == pytest.approx(4e-3)
    assert np.allclose(e.gradient(p), p * [0.5, 2, 2], atol=1e-10)
    assert np.allclose(e.hessian(p), np.diag([0.5, 2, 2]), atol=1e-7)
    mesh = e.to_mesh(0.08)
    assert abs(mesh.volume - 4 / 3 * np.pi * 2) <= mesh.deviation * mesh.area


def test_project_uses_the_implicits_own_closest_points_across_csg_seams():
    """splinekit.project on a splinekit.implicit object goes through its
    closest_points, which steps across CSG seams (a plain gradient iteration
    zig-zags there and runs out of steps)."""
    f = si.smooth_union(si.sphere((0, 0, 0), 1.0), si.box((1.0, 0, 0), (1.0, 0.5, 0.5)), 0.3) - si.cylinder(
        (0, 0, 0), 0.3, 4.0, axis=(1, 0, 0)
    )
    p = np.array([[1.668671092771409, 0.5169050179640418, 0.05647058639805547]])
    r = splinekit.project(f, p)
    assert abs(f(r.points)[0]) <= 1e-9
    assert np.allclose(r.points, f.closest_points(p))
    assert r.distances[0] == pytest.approx(np.linalg.norm(r.points[0] - p[0]))
