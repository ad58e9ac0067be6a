"""Adaptive watertight tessellation (splinekit.tessellate).

Deviations are measured independently of the tessellator's own measure: random
points inside triangles are mapped to (u, v) by barycentric interpolation of
the corners' parameters and the exact surface point there is compared with the
point of the flat triangle. Closed bodies are checked with PolyMesh.is_closed,
the Euler characteristic and manifold3d; volumes against closed forms.
"""

from __future__ import annotations

import itertools
import pickle

import numpy as np
import pytest
from _geometry import random_curve_data, random_surface_data
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit import _kernels
from splinekit.errors import SplineKitError
from splinekit.mesh.primitives import torus
from splinekit.tessellation import Polyline, Tessellation, tessellate

TESS_KERNELS = "splinekit.tessellation._kernels"


@pytest.fixture
def compiled(monkeypatch):
    """Compiled kernels on at every size: thresholds 0 and the tessellation kernels loaded now
    (by default they load only once a large job, or enough work, pays for loading them)."""
    pytest.importorskip("numba")
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    assert _kernels.load(TESS_KERNELS) is not None

S2 = np.sqrt(0.5)


# -- geometry built by hand -------------------------------------------------------------------
def sphere_surface(radius=1.0, center=(0.0, 0.0, 0.0)):
    """The unit sphere as one rational biquadratic NURBS (9 x 5 net): a full circle of
    quarter arcs swept along a half circle; its v = 0 and v = 1 edges collapse to the poles."""
    circle = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]], float)
    cw = np.array([1, S2, 1, S2, 1, S2, 1, S2, 1])
    half = np.array([[0, -1], [1, -1], [1, 0], [1, 1], [0, 1]], float)  # (radius, z)
    hw = np.array([1, S2, 1, S2, 1])
    P = np.empty((9, 5, 3))
    P[..., 0] = circle[:, None, 0] * half[None, :, 0]
    P[..., 1] = circle[:, None, 1] * half[None, :, 0]
    P[..., 2] = np.broadcast_to(half[None, :, 1], (9, 5))
    W = cw[:, None] * hw[None, :]
    ku = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    kv = [0, 0, 0, 0.5, 0.5, 1, 1, 1]
    return sk.NurbsSurface(2, 2, ku, kv, radius * P + np.asarray(center), W)


def sphere_patches(mixed_orientation=False):
    """The sphere as 8 rational Bézier patches; optionally half of them re-parametrized
    (u reversed and u, v swapped: same surface and normal, other edge directions)."""
    patches = [b.to_bspline() for row in sphere_surface().to_bezier() for b in row]
    if mixed_orientation:
        patches = [s.transpose().reverse("v") if i % 2 else s for i, s in enumerate(patches)]
    return patches


def flat_box_patches(size=(1.0, 2.0, 3.0)):
    """Six bilinear patches bounding a box, normals outward."""
    a, b, c = size
    X = np.array([[x, y, z] for x in (0, a) for y in (0, b) for z in (0, c)]).reshape(2, 2, 2, 3)
    faces = [
        X[0, :, :].transpose(1, 0, 2),  # x = 0: (z, y) so that the normal points to -x
        X[1, :, :],
        X[:, 0, :],
        X[:, 1, :].transpose(1, 0, 2),
        X[:, :, 0].transpose(1, 0, 2),
        X[:, :, 1],
    ]
    return [sk.BezierSurface(np.ascontiguousarray(f)) for f in faces]


def random_surface(seed, rational, max_degree=4):
    rng = np.random.default_rng(seed)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, max_degree=max_degree, max_spans=3)
    if rational:
        return sk.NurbsSurface(pu, pv, ku, kv, P, W)
    return sk.BSplineSurface(pu, pv, ku, kv, P)


def sampled_deviation(mesh, patches, rng, count=4000):
    """Largest distance between the exact surface and the flat triangles at random
    barycentric points (uniform in each triangle, triangles drawn uniformly)."""
    F = np.asarray(mesh.faces)
    f = rng.integers(0, len(F), count)
    b = rng.dirichlet([1.0, 1.0, 1.0], count)
    uv = np.einsum("kj,kjd->kd", b, mesh.corner_uv[f])
    flat = np.einsum("kj,kjd->kd", b, mesh.vertices[F[f]])
    which = mesh.face_patch[f]
    out = np.zeros(count)
    for p in np.unique(which):
        sel = which == p
        out[sel] = np.linalg.norm(patches[p].evaluate(uv[sel, 0], uv[sel, 1]) - flat[sel], axis=1)
    return float(out.max())


def manifold_of(mesh):
    manifold3d = pytest.importorskip("manifold3d")
    m64 = manifold3d.Mesh64(
        vert_properties=np.array(mesh.vertices, dtype=np.float64, order="C"),
        tri_verts=np.array(mesh.faces, dtype=np.uint64, order="C"),
    )
    return manifold3d, manifold3d.Manifold(m64)


def assert_closed_manifold(mesh, genus):
    assert mesh.is_triangle_mesh
    assert mesh.is_closed
    assert mesh.euler_characteristic == 2 - 2 * genus
    manifold3d, m = manifold_of(mesh)
    assert m.status() == manifold3d.Error.NoError
    assert m.genus() == genus
    # no degenerate triangles
    assert mesh.face_areas.min() > 0


# -- deviation ----------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("relative", [1e-2, 1e-3])
def test_random_surface_deviation_within_tolerance(seed, relative):
    S = random_surface(seed, rational=seed % 2 == 1)
    mesh = tessellate(S, relative, relative=True, angle_tolerance=None)
    diag = np.linalg.norm(np.ptp(S.control_points.reshape(-1, 3), axis=0))
    assert mesh.tolerance == pytest.approx(relative * diag)
    assert 0 < mesh.max_deviation <= mesh.tolerance
    rng = np.random.default_rng(100 + seed)
    assert sampled_deviation(mesh, [S], rng) <= mesh.tolerance
    # vertices lie on the surface at their parameters
    F = np.asarray(mesh.faces)
    on = S.evaluate(mesh.corner_uv[..., 0].ravel(), mesh.corner_uv[..., 1].ravel())
    assert np.abs(on - mesh.vertices[F].reshape(-1, 3)).max() <= 1e-9 * diag


def test_absolute_and_relative_tolerance_agree():
    S = random_surface(3, rational=True)
    diag = np.linalg.norm(np.ptp(S.control_points.reshape(-1, 3), axis=0))
    a = tessellate(S, 2e-3 * diag, angle_tolerance=None)
    b = tessellate(S, 2e-3, relative=True, angle_tolerance=None)
    c = tessellate(S, angle_tolerance=None)  # default: 1e-3 of the diagonal
    assert a.n_faces == b.n_faces and np.allclose(a.vertices, b.vertices)
    assert c.tolerance == pytest.approx(1e-3 * diag)
    assert c.n_faces > a.n_faces


def test_angle_tolerance_adds_triangles_on_a_coarse_tolerance():
    S = sphere_surface()
    coarse = tessellate(S, 0.05, angle_tolerance=None)
    fine = tessellate(S, 0.05, angle_tolerance=0.1)
    assert fine.n_faces > coarse.n_faces
    # angle between the exact normals at the ends of every edge (poles are fans: skip them)
    E = fine.edges
    n0, n1 = fine.normals[E[:, 0]], fine.normals[E[:, 1]]
    ang = np.arccos(np.clip(np.einsum("ij,ij->i", n0, n1), -1, 1))
    assert ang.max() <= 0.1 + 1e-9


# -- adaptivity ---------------------------------------------------------------------------------
def test_triangle_count_grows_like_inverse_tolerance():
    S = sphere_surface()
    counts = [tessellate(S, tol, angle_tolerance=None).n_faces for tol in (1e-2, 1e-3, 1e-4)]
    for coarse, fine in itertools.pairwise(counts):
        assert 5 < fine / coarse < 20


def test_flat_patches_get_few_triangles_curved_many():
    flat = sk.BezierSurface([[[0, 0, 0], [0, 1, 0]], [[2, 0, 0], [2, 1, 0]]])
    assert tessellate(flat, 1e-6).n_faces == 2
    # a bicubic plane with a linear parametrization: second differences vanish
    g = np.linspace(0, 1, 4)
    P = np.stack([*np.meshgrid(3 * g, 2 * g, indexing="ij"), np.zeros((4, 4))], axis=-1)
    plane = sk.BSplineSurface(3, 3, [0] * 4 + [1] * 4, [0] * 4 + [1] * 4, P)
    assert tessellate(plane, 1e-6).n_faces == 2
    curved = sphere_patches()[0]
    assert tessellate(curved, 1e-4).n_faces > 500


def test_refinement_concentrates_where_curvature_is():
    # a long flat strip with one bump in the middle: control points at the Greville
    # abscissae make x(u) = u exactly, so the flat end spans need no refinement at all
    knots = np.concatenate([[0] * 4, np.arange(1, 10), [10] * 4]).astype(float)
    greville = np.array([knots[i + 1 : i + 4].mean() for i in range(13)])
    P = np.zeros((13, 2, 3))
    P[:, :, 0] = greville[:, None]
    P[:, 1, 1] = 1.0
    P[6, :, 2] = 2.0  # influences spans 3..6 only
    S = sk.BSplineSurface(3, 1, knots, [0, 0, 1, 1], P)
    mesh = tessellate(S, 1e-3, angle_tolerance=None)
    u = mesh.corner_uv[:, :, 0].mean(axis=1)
    in_flat_spans = np.count_nonzero((u < 3) | (u > 7))
    assert in_flat_spans == 2 * 6  # one quad (two triangles) per flat span
    assert mesh.n_faces > 10 * in_flat_spans
    assert sampled_deviation(mesh, [S], np.random.default_rng(1)) <= 1e-3


# -- closed bodies ------------------------------------------------------------------------------
def test_sphere_single_nurbs_is_closed_and_has_the_right_volume():
    S = sphere_surface()
    for tol in (3e-3, 3e-4):
        mesh = tessellate(S, tol)
        assert isinstance(mesh, Tessellation)
        assert_closed_manifold(mesh, genus=0)
        exact = 4.0 / 3.0 * np.pi
        # vertices are on the sphere, so the polyhedron is inscribed: volume below the exact one
        assert exact - mesh.area * tol <= mesh.volume < exact
        assert np.abs(np.linalg.norm(mesh.vertices, axis=1) - 1.0).max() < 1e-12


@pytest.mark.parametrize("mixed", [False, True])
def test_sphere_patch_set_is_watertight(mixed):
    patches = sphere_patches(mixed)
    mesh = tessellate(patches, 2e-3)
    assert_closed_manifold(mesh, genus=0)
    exact = 4.0 / 3.0 * np.pi
    assert abs(mesh.volume - exact) <= mesh.area * 2e-3
    assert set(np.unique(mesh.face_patch)) == set(range(8))
    assert sampled_deviation(mesh, patches, np.random.default_rng(7)) <= 2e-3


def test_multi_span_patch_stitched_to_bezier_patches():
    # bottom half: one multi-span NURBS (its own tensor grid); top half: four Bézier patches
    bottom, top = sphere_surface().split(0.5, direction="v")
    patches = [bottom] + [b.to_bspline() for row in top.to_bezier() for b in row]
    mesh = tessellate(patches, 1e-3)
    assert_closed_manifold(mesh, genus=0)
    assert abs(mesh.volume - 4.0 / 3.0 * np.pi) <= mesh.area * 1e-3
    assert sampled_deviation(mesh, patches, np.random.default_rng(5)) <= 1e-3


def test_translated_scaled_sphere_volume():
    S = sphere_surface(radius=250.0, center=(1e3, -2e3, 5e2))
    mesh = tessellate(S, 1e-3, relative=True)
    assert_closed_manifold(mesh, genus=0)
    exact = 4.0 / 3.0 * np.pi * 250.0**3
    assert abs(mesh.volume - exact) <= mesh.area * mesh.tolerance


def test_flat_box_of_six_patches():
    mesh = tessellate(flat_box_patches(), 1e-3)
    assert mesh.n_faces == 12 and mesh.n_vertices == 8
    assert_closed_manifold(mesh, genus=0)
    assert mesh.volume == pytest.approx(6.0, rel=1e-12)


def test_catmull_clark_torus_limit_surface():
    cage = torus(8, 6, R=2.0, r=0.7)
    surface = sk.SubdivisionSurface(cage, "catmull-clark")
    patches, _ = surface.to_bsplines(0)
    mesh = tessellate(surface, 1e-3, relative=True, levels=0)
    assert len(np.unique(mesh.face_patch)) == len(patches) == 48
    assert_closed_manifold(mesh, genus=1)
    assert mesh.max_deviation <= mesh.tolerance
    assert sampled_deviation(mesh, patches, np.random.default_rng(3)) <= mesh.tolerance
    # the limit surface lies inside the cage's hull: volume below the cage's
    assert 0 < mesh.volume < cage.volume


# -- normals ------------------------------------------------------------------------------------
def test_normals_are_exact_on_the_sphere_including_poles():
    mesh = tessellate(sphere_surface(), 1e-3)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    # outward normal of the unit sphere is the position itself
    assert np.abs(mesh.normals - mesh.vertices).max() < 1e-9
    # and the triangles face the same way
    centroid_dirs = mesh.vertices[np.asarray(mesh.faces)].mean(axis=1)
    assert (np.einsum("ij,ij->i", mesh.face_normals, centroid_dirs) > 0).all()


def test_normals_match_surface_normal_on_random_surfaces():
    for seed in (0, 1, 2):
        S = random_surface(seed, rational=seed == 1)
        mesh = tessellate(S, 1e-2, relative=True, angle_tolerance=None)
        expected = S.normal(mesh.uv[:, 0], mesh.uv[:, 1])
        # on an inner knot line the surface may be only C0 (two normals): skip those vertices
        bu, bv = S.bezier_breakpoints()
        on_knot = np.isin(mesh.uv[:, 0], bu[1:-1]) | np.isin(mesh.uv[:, 1], bv[1:-1])
        good = (np.linalg.norm(expected, axis=1) > 0.5) & ~on_knot
        assert good.mean() > 0.8
        assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
        assert np.abs(mesh.normals[good] - expected[good]).max() < 1e-8
        assert np.abs(S.evaluate(mesh.uv[:, 0], mesh.uv[:, 1]) - mesh.vertices).max() < 1e-9 * np.abs(mesh.vertices).max()


def test_numpy_path_matches_compiled_kernel(compiled, monkeypatch):
    cases = [(sphere_surface(), 1e-3), (sphere_patches(), 1e-3), (random_surface(4, rational=True), 1e-2)]
    fast = [tessellate(s, t, relative=True) for s, t in cases]
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    for (s, t), a in zip(cases, fast):
        b = tessellate(s, t, relative=True)
        assert np.array_equal(np.asarray(a.faces), np.asarray(b.faces))
        assert np.allclose(a.vertices, b.vertices, rtol=0, atol=1e-12 * np.abs(a.vertices).max())
        assert np.allclose(a.normals, b.normals, atol=1e-12)
        assert a.max_deviation == pytest.approx(b.max_deviation, rel=1e-9)


# -- invariance (hypothesis) --------------------------------------------------------------------
@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    angles=st.tuples(*[st.floats(-np.pi, np.pi)] * 3),
    scale=st.floats(0.01, 100.0),
    shift=st.tuples(*[st.floats(-100.0, 100.0)] * 3),
)
def test_tessellation_commutes_with_similarity_transforms(seed, angles, scale, shift):
    S = random_surface(seed, rational=seed % 2 == 0, max_degree=3)
    a, b, c = angles
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    M = np.eye(4)
    M[:3, :3] = scale * Rz @ Ry @ Rx
    M[:3, 3] = shift
    base = tessellate(S, 1e-2, relative=True, angle_tolerance=None)
    # an absolute tolerance scaled with the model (the bounding box is not rotation invariant)
    moved = tessellate(S.transform(M), scale * base.tolerance, angle_tolerance=None)
    # counts come from deviations, which scale exactly: equal up to rounding at thresholds
    assert abs(moved.n_faces - base.n_faces) <= 0.1 * base.n_faces
    assert moved.max_deviation <= moved.tolerance
    assert moved.max_deviation == pytest.approx(scale * base.max_deviation, rel=0.3)


# -- curves -------------------------------------------------------------------------------------
def circle_curve(radius=2.0):
    P = radius * np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]], float)
    W = [1, S2, 1, S2, 1, S2, 1, S2, 1]
    knots = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    return sk.NurbsCurve(2, knots, np.column_stack([P, np.zeros(9)]), W)


def test_circle_polyline_sagitta_closed_form():
    r = 2.0
    C = circle_curve(r)
    for tol in (1e-2, 1e-4):
        line = tessellate(C, tol, angle_tolerance=None)
        assert isinstance(line, Polyline)
        assert np.allclose(np.linalg.norm(line.points, axis=1), r, atol=1e-12)
        # a chord of angle theta has sagitta r (1 - cos(theta / 2)); all must be <= tol
        chords = np.linalg.norm(np.diff(line.points, axis=0), axis=1)
        theta = 2 * np.arcsin(np.clip(chords / (2 * r), 0, 1))
        assert (r * (1 - np.cos(theta / 2))).max() <= tol
        fewest = 2 * np.pi / (2 * np.arccos(1 - tol / r))
        assert fewest <= len(line) - 1 <= 3 * fewest
        assert line.params[0] == 0.0 and line.params[-1] == 1.0 and (np.diff(line.params) > 0).all()


@pytest.mark.parametrize("seed", range(8))
def test_random_curve_polyline_within_tolerance(seed):
    rng = np.random.default_rng(seed)
    p, U, P, W = random_curve_data(rng, rational=seed % 2 == 1, max_degree=6)
    C = sk.NurbsCurve(p, U, P, W) if W is not None else sk.BSplineCurve(p, U, P)
    tol = 1e-3 * np.linalg.norm(np.ptp(P, axis=0))
    line = tessellate(C, tol, angle_tolerance=None)
    assert line.max_deviation <= tol
    # random points inside random segments against the chord
    k = rng.integers(0, len(line) - 1, 3000)
    s = rng.random(3000)
    t = line.params[k] + s * (line.params[k + 1] - line.params[k])
    chord = line.points[k] + s[:, None] * (line.points[k + 1] - line.points[k])
    assert np.linalg.norm(C.evaluate(t) - chord, axis=1).max() <= tol
    assert np.allclose(C.evaluate(line.params), line.points)


def test_bezier_curve_and_straight_line():
    B = sk.BezierCurve([[0, 0], [1, 2], [3, 2], [4, 0]])
    line = tessellate(B, 1e-3)
    assert line.max_deviation <= line.tolerance
    straight = sk.BezierCurve([[0, 0, 0], [1, 1, 1]])
    assert len(tessellate(straight, 1e-9)) == 2


# -- results ------------------------------------------------------------------------------------
def test_result_attributes_shapes_and_pickle():
    mesh = tessellate(sphere_patches(), 1e-2)
    n, f = mesh.n_vertices, mesh.n_faces
    assert mesh.normals.shape == (n, 3) and mesh.uv.shape == (n, 2)
    assert mesh.vertex_patch.shape == (n,) and mesh.face_patch.shape == (f,)
    assert mesh.corner_uv.shape == (f, 3, 2)
    assert not mesh.vertices.flags.writeable and not mesh.normals.flags.writeable
    with pytest.raises(AttributeError):
        mesh.max_deviation = 0.0
    again = pickle.loads(pickle.dumps(mesh))
    assert isinstance(again, Tessellation) and again == mesh
    assert np.array_equal(again.corner_uv, mesh.corner_uv) and again.max_deviation == mesh.max_deviation


# -- bad input ----------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [0.0, -1.0, float("nan"), float("inf"), "abc", [1e-3, 1e-3], 1j])
def test_bad_tolerance(tol):
    with pytest.raises(SplineKitError, match="tolerance"):
        tessellate(sphere_surface(), tol)


@pytest.mark.parametrize("angle", [0.0, -0.1, 4.0, float("nan")])
def test_bad_angle_tolerance(angle):
    with pytest.raises(SplineKitError, match="angle_tolerance"):
        tessellate(sphere_surface(), 1e-3, angle_tolerance=angle)


@pytest.mark.parametrize(
    "obj",
    [None, 3, "sphere", {"a": 1}, [], np.zeros((3, 3)), sk.PolyMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])],
)
def test_unsupported_objects(obj):
    with pytest.raises(SplineKitError):
        tessellate(obj, 1e-3)


def test_bad_patch_lists():
    with pytest.raises(SplineKitError, match="patch 1"):
        tessellate([sphere_surface(), circle_curve()], 1e-3)
    flat2d = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 2)) + [[[0, 0], [0, 1]], [[1, 0], [1, 1]]])
    with pytest.raises(SplineKitError, match="3-D"):
        tessellate(flat2d, 1e-3)
    with pytest.raises(SplineKitError, match="relative"):
        tessellate(sphere_surface(), 1e-3, relative="yes")


def test_too_small_tolerance_is_refused_not_hung():
    with pytest.raises(SplineKitError, match="triangles"):
        tessellate(sphere_surface(), 1e-13)


def test_inward_facing_closed_body_is_turned_outward():
    """A half circle revolved the other way round gives patches whose Su x Sv
    points into the ball; the tessellation of the closed body faces outward
    anyway (positive volume, normals along the position), like OCC's solids."""
    half = sk.arc([0, 0, 0], [0, 1, 0], 1.0, -np.pi / 2, np.pi / 2)
    ball = sk.revolve(half, [0, 0, 0], [0, 0, 1])
    inward = ball.normal(np.array([0.3]), np.array([0.4]))[0] @ ball.evaluate(0.3, 0.4)
    assert inward < 0  # the construction really faces inward
    m = sk.tessellate([ball], 1e-3)
    assert m.is_closed and m.volume > 0
    assert np.allclose(np.einsum("ij,ij->i", m.normals, m.vertices), 1.0, atol=1e-9)
    # corner parameters follow the flipped winding: the centre of each triangle's
    # corner (u, v) maps next to the flat triangle's centre
    centre_uv = m.corner_uv.mean(axis=1)
    gap = np.linalg.norm(ball.evaluate(centre_uv[:, 0], centre_uv[:, 1]) - m.vertices[m.faces].mean(axis=1), axis=1)
    assert gap.max() <= 2 * m.max_deviation


def test_utah_teapot_is_stitched_along_every_shared_patch_edge():
    """The 32 Bezier patches of the Utah teapot: the tessellation may only have
    boundary edges on the patch edges that no other patch shares (the rim, the
    spout and handle ends, found here from the control nets alone); every
    shared edge is stitched, so no boundary vertex lies anywhere else."""
    import models

    patches = models.build_model("teapot").bodies[0]
    mesh = sk.tessellate(patches, 1e-3, relative=True)
    assert mesh.max_deviation <= mesh.tolerance

    def key(row):
        return tuple(map(tuple, np.round(row, 9)))

    count = {}
    for p in patches:
        C = np.asarray(p.control_points)
        for side in (C[0], C[-1], C[:, 0], C[:, -1]):
            k = min(key(side), key(side[::-1]))
            count[k] = count.get(k, 0) + 1
    open_edges = [np.array(k) for k, c in count.items() if c == 1 and np.ptp(np.array(k), axis=0).max() > 0]
    assert 0 < len(open_edges) < len(count)
    boundary = np.unique(mesh.edges[mesh.boundary_edges])
    assert boundary.size > 0
    X = mesh.vertices[boundary]
    nearest = np.min([sk.project(sk.BezierCurve(e), X).distances for e in open_edges], axis=0)
    assert nearest.max() <= 1e-9 * np.abs(mesh.vertices).max()


# -- internal helpers of the patch tessellator, against independent references --------------
def test_close_pairs_match_a_kd_tree():
    """The sweep that finds the vertices to weld returns exactly the pairs of a k-d tree
    query (scipy), on clouds with planted near-duplicates, axis-aligned planar grids and a
    plane across the sweep direction (which takes the k-d tree fallback)."""
    from scipy.spatial import cKDTree

    from splinekit.tessellation.welding import SWEEP, close_pairs

    rng = np.random.default_rng(3)
    g = np.stack(np.meshgrid(np.arange(30.0), np.arange(30.0), indexing="ij"), axis=-1).reshape(-1, 2)
    e1 = np.cross(SWEEP, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(SWEEP, e1)
    clouds = [
        rng.random((500, 3)),
        np.column_stack([g, np.zeros(len(g))]),  # a plane z = 0
        np.column_stack([np.ones(len(g)), g]),  # a plane x = 1
        g[:, :1] * e1 + g[:, 1:] * e2,  # a plane across the sweep
    ]
    r = 1e-6
    for X in clouds:
        k = rng.choice(len(X), len(X) // 3, replace=False)
        X = np.concatenate([X, X[k] + rng.uniform(-0.5, 0.5, (k.size, 3)) * r, X[k[:20]] + 3 * r])
        X = X[rng.permutation(len(X))]
        got = {tuple(sorted(map(int, p))) for p in close_pairs(X, r)}
        want = {tuple(sorted(map(int, p))) for p in cKDTree(X).query_pairs(r)}
        assert got == want and len(want) >= len(k) // 2


def test_components_match_scipy_connected_components():
    """Connected components of random sparse graphs (chains in shuffled order included)
    partition the nodes like scipy's, each labelled with its smallest node."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from splinekit.tessellation.welding import components

    rng = np.random.default_rng(5)
    for n, m in [(1, 0), (10, 0), (50, 30), (400, 390), (1000, 600)]:
        a, b = rng.integers(0, n, m), rng.integers(0, n, m)
        if n == 400:  # one long chain through a random permutation
            perm = rng.permutation(n)
            a, b = perm[:-1][:m], perm[1:][:m]
        lab = components(n, a, b)
        _, ref = connected_components(coo_matrix((np.ones(m), (a, b)), shape=(n, n)), directed=False)
        assert (lab[a] == lab[b]).all()
        # same partition: the map ref -> lab is one-to-one
        pairs = set(zip(ref.tolist(), lab.tolist()))
        assert len(pairs) == len(set(ref.tolist())) == len(set(lab.tolist()))
        smallest = np.full(n, n)
        np.minimum.at(smallest, ref, np.arange(n))
        assert (lab == smallest[ref]).all()


def test_cells_of_a_mixed_patch_list_reproduce_their_patches():
    """Rational and polynomial Bezier patches mixed with a multi-span patch of the same
    degrees: every Bezier cell's net, evaluated at interior points, gives the patch's own
    point at the mapped parameters, and the cells keep the order of their patches."""
    from splinekit.basis.bernstein import all_bernstein
    from splinekit.tessellation.cells import cells_of_patches

    rng = np.random.default_rng(11)
    bez = sk.BSplineSurface(2, 3, [0, 0, 0, 1, 1, 1], [0, 0, 0, 0, 2, 2, 2, 2], rng.random((3, 4, 3)))
    rat = sk.NurbsSurface(2, 3, [0, 0, 0, 1, 1, 1], [0, 0, 0, 0, 1, 1, 1, 1], rng.random((3, 4, 3)), rng.uniform(0.5, 2, (3, 4)))
    multi = sk.NurbsSurface(
        2, 3, [0, 0, 0, 0.4, 1, 1, 1], [0, 0, 0, 0, 0.5, 1, 1, 1, 1], rng.random((4, 5, 3)), rng.uniform(0.5, 2, (4, 5))
    )
    other = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], rng.random((2, 2, 3)))
    patches = [rat, multi, other, bez, rat]
    sets = cells_of_patches(patches)
    assert [(cs.p, cs.q) for cs in sets] == [(1, 1), (2, 3)]
    cs = sets[1]
    assert cs.patch.tolist() == [0, 1, 1, 1, 1, 3, 4]
    s, t = np.array([0.2, 0.7]), np.array([0.6, 0.1])
    Bu, Bv = all_bernstein(cs.p, s), all_bernstein(cs.q, t)  # (p + 1, 2)
    for k in range(len(cs)):
        h = np.einsum("ia,jb,ijc->abc", Bu, Bv, cs.nets[k])
        got = h[..., :3] / h[..., 3:]
        u0, u1, v0, v1 = cs.box[k]
        want = patches[cs.patch[k]].evaluate_grid(u0 + (u1 - u0) * s, v0 + (v1 - v0) * t)
        assert np.allclose(got, want, atol=1e-12)


@pytest.mark.parametrize("flip", [False, True])
def test_open_patch_keeps_the_winding_of_its_parametrization(flip):
    """An open cap (a bump over the unit square, once with u and v swapped so that
    Su x Sv points down): the mesh is open, so no orientation fix applies, and every
    triangle winds like the exact normal (surface.normal) at its parametric centre."""
    rng = np.random.default_rng(8)
    g = np.linspace(0.0, 1.0, 5)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, 0.3 * np.sin(np.pi * X) * np.sin(np.pi * Y) + 0.05 * rng.random((5, 5))], axis=-1)
    if flip:
        P = P.transpose(1, 0, 2)
    k = [0, 0, 0, 0, 0.5, 1, 1, 1, 1]
    s = sk.BSplineSurface(3, 3, k, k, P)
    m = tessellate(s, 1e-3, relative=True)
    assert not m.is_closed
    T = m.vertices[m.faces]
    face_n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    c = m.corner_uv.mean(axis=1)
    exact = s.normal(c[:, 0], c[:, 1])
    assert (np.einsum("ij,ij->i", face_n, exact) > 0).all()
    assert ((exact[:, 2] < 0) == flip).all()  # the swapped cap really faces down


# -- compiled assembly and weld kernels against references and the numpy path ------------------
@pytest.fixture(params=["0", "1"], ids=["numpy", "numba"])
def kernel_path(request, monkeypatch):
    """Runs a test once on the numpy path and once on the compiled kernels."""
    if request.param == "1":
        request.getfixturevalue("compiled")
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    return request.param


def test_weld_helpers_match_their_references_on_both_paths(kernel_path):
    test_close_pairs_match_a_kd_tree()
    test_components_match_scipy_connected_components()


def _weld_reference(E0, FE, rep, NI):
    """Plain-loop reference of the post-weld triangle remap (one triangle at a time)."""
    seen, tris, faces, pre = set(), [], [], []
    for f, tri in enumerate(E0.tolist()):
        t = [x if x < NI else NI + int(rep[x - NI]) for x in tri]
        if len(set(t)) < 3:
            continue
        k = t.index(min(t))
        canon = tuple(t[k:] + t[:k])
        if canon in seen:
            continue
        seen.add(canon)
        tris.append(t)
        faces.append(int(FE[f]))
        pre.append(tri)
    kept = sorted({x - NI for t in tris for x in t if x >= NI})
    new = {r: NI + i for i, r in enumerate(kept)}
    tris = [[x if x < NI else new[x - NI] for x in t] for t in tris]
    return np.array(tris, dtype=np.int64).reshape(-1, 3), np.array(faces, dtype=np.int64), np.array(pre).reshape(-1, 3), np.array(kept)


def test_weld_triangles_match_a_plain_loop_reference(kernel_path):
    """Random ring triangles with merged vertices (collapsed and repeated triangles in
    both windings): the survivors, their patches, their pre-weld corners and the kept
    ring vertices are those of a one-triangle-at-a-time reference."""
    from splinekit.tessellation.assembly import _weld_triangles

    rng = np.random.default_rng(11)
    for NI, NR, t in [(0, 3, 1), (5, 8, 40), (20, 30, 200), (0, 50, 300), (100, 6, 50)]:
        E0 = np.column_stack([rng.integers(0, NI + NR, t) for _ in range(3)]).astype(np.int64)
        E0 = np.concatenate([E0, E0[: t // 4], E0[: t // 4, ::-1], np.roll(E0[: t // 5], 1, axis=1)])
        FE = rng.integers(0, 7, len(E0)).astype(np.int64)
        rep = np.arange(NR)
        merged = rng.random(NR) < 0.4
        rep[merged] = rng.integers(0, NR, merged.sum())
        rep = rep[rep]  # (representatives of representatives: any map into the ring)
        n_in = 9
        T = np.full((n_in + len(E0), 3), -7, dtype=np.int64)
        FP = np.full(n_in + len(E0), -7, dtype=np.int64)
        jit = _kernels.get(TESS_KERNELS)
        if jit is None:
            T, FP, pre, kept = _weld_triangles(E0, FE, rep, NI, NR, T, FP, n_in)
        else:
            count, pre, kept = jit.weld_triangles(E0, FE, rep, NI, NR, T[n_in:], FP[n_in:])
            T, FP = T[: n_in + count], FP[: n_in + count]
        want_T, want_F, want_pre, want_kept = _weld_reference(E0, FE, rep, NI)
        assert (T[:n_in] == -7).all() and (FP[:n_in] == -7).all()  # rows before n_in untouched
        assert np.array_equal(T[n_in:], want_T)
        assert np.array_equal(FP[n_in:], want_F)
        assert np.array_equal(pre, want_pre)
        assert np.array_equal(kept, want_kept)


def test_volume_sign_test_on_both_paths(kernel_path):
    """The cheap orientation test: a closed outward sphere (volume about 4/3 pi) is clearly
    positive; the same mesh with every triangle flipped is not, nor is a flat mesh of zero
    volume."""
    from splinekit.tessellation.assembly import _clearly_positive_volume

    mesh = tessellate(sphere_patches(), 1e-3)
    V, F = np.array(mesh.vertices), np.array(mesh.faces)
    # every point within the tolerance of the sphere: the volume within tolerance x area
    assert mesh.volume == pytest.approx(4 / 3 * np.pi, abs=1e-3 * 4 * np.pi)
    assert _clearly_positive_volume(V, F)
    assert not _clearly_positive_volume(V, F[:, ::-1])
    # a flat (zero-volume) pair of opposite triangles: no clear sign
    assert not _clearly_positive_volume(np.eye(3), np.array([[0, 1, 2], [0, 2, 1]]))


def test_rational_second_derivative_bounds_agree_on_both_paths(compiled, monkeypatch):
    """The compiled sampler of |S_uu|, |S_uv|, |S_vv| of rational cells reproduces the
    numpy one bit for bit (the sample counts derive from it)."""
    from splinekit.tessellation.cells import _sampled_second_derivatives, cells_of_patches

    patches = [random_surface(s, rational=True) for s in range(6)] + sphere_patches()
    for cs in cells_of_patches(patches):
        nets = cs.nets[cs.rational]
        got = []
        for env in ("0", "1"):
            monkeypatch.setenv("SPLINEKIT_NUMBA", env)
            got.append(np.stack(_sampled_second_derivatives(nets, cs.p, cs.q)))
        assert np.array_equal(got[0], got[1])
        assert np.isfinite(got[1]).all() and (got[1] >= 0).all()


def test_pole_normals_are_exact_and_equal_on_both_paths(compiled, monkeypatch):
    """The limit normals at the sphere's poles (collapsed patch edges) are (0, 0, +-1) on
    both paths, bit for bit the same; every other mesh array also agrees exactly."""
    meshes = []
    for env in ("0", "1"):
        monkeypatch.setenv("SPLINEKIT_NUMBA", env)
        meshes.append(tessellate(sphere_patches(), 1e-3))
    a, b = meshes
    for name in ("faces", "vertices", "uv", "corner_uv", "face_patch", "vertex_patch"):
        assert np.array_equal(np.asarray(getattr(a, name)), np.asarray(getattr(b, name))), name
    assert a.max_deviation == b.max_deviation
    poles = np.flatnonzero(np.abs(np.abs(a.vertices[:, 2]) - 1.0) < 1e-12)
    assert poles.size >= 2
    assert np.array_equal(a.normals[poles], b.normals[poles])
    assert np.allclose(a.normals[poles], a.vertices[poles], atol=1e-12)


@pytest.mark.parametrize("levels", [0, 1, 2])
def test_subdivision_surface_with_extraordinary_vertices_tessellates_closed(levels):
    """The mug's Catmull-Clark cage (genus 1, extraordinary vertices next to
    regular faces, a creased rim): refining only around irregular faces would
    leave T-junctions; tessellate refines uniformly, so the mesh is closed at
    every level and the limit surface's genus survives."""
    import models.mug

    cage, rim = models.mug.cage()
    surface = sk.SubdivisionSurface(cage, "catmull-clark", creases=(rim, np.full(len(rim), 2.0)))
    m = sk.tessellate(surface, 1e-3, relative=True, levels=levels)
    assert m.max_deviation <= m.tolerance
    assert_closed_manifold(m, genus=1)


def test_cached_patch_preparation_matches_a_fresh_one():
    """The tolerance-independent preparation of a patch set is cached on its first patch: a
    repeated call, and a call at another tolerance, give the meshes that copies of the same
    patches (no cache) give, and another patch set sharing the first patch does not reuse it."""
    patches = sphere_patches()
    for tol in (1e-2, 1e-3, 1e-2):
        cached = tessellate(patches, tol)
        fresh = tessellate([pickle.loads(pickle.dumps(p)) for p in patches], tol)
        np.testing.assert_array_equal(cached.vertices, fresh.vertices)
        np.testing.assert_array_equal(np.asarray(cached.faces), np.asarray(fresh.faces))
        assert cached.is_closed
    part = tessellate(patches[:3], 1e-2)
    assert part.n_faces < cached.n_faces and not part.is_closed
    again = tessellate(patches, 1e-2)
    np.testing.assert_array_equal(np.asarray(again.faces), np.asarray(cached.faces))
