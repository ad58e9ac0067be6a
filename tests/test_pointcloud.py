"""Point clouds (splinekit.pointcloud): sampling, normals, curvature, outliers, reconstruction.

Checked against closed forms (sphere, torus, cylinder normals and curvatures;
Archimedes' hat-box theorem for the area of spherical zones), statistical
bounds (chi-square and Kolmogorov-Smirnov tests with fixed seeds), simple
reference implementations written here (sequential greedy Poisson-disk
selection, point-triangle distance by plane projection and edge distances) and
an independent projection (splinekit.project) for the height-field fits.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

import splinekit as sk
from splinekit.errors import DegreeError, FittingError, SplineKitError
from splinekit.mesh import primitives
from splinekit.pointcloud import (
    MeshDistance,
    closest_points_on_mesh,
    curvature,
    estimate_normals,
    fit_height_field,
    mls_distance,
    orient_normals,
    poisson_disk,
    reconstruct_implicit,
    remove_outliers,
    sample_curve,
    sample_mesh,
    sample_surface,
)
from splinekit.pointcloud._cloud import kd_tree


def sphere_cloud(n, radius=1.0, center=(0.0, 0.0, 0.0), seed=0):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    return np.asarray(center) + radius * u, u


def torus_cloud(n, R=1.0, r=0.35, seed=0):
    """Uniform by area: the angle around the tube is drawn by rejection (density 1 + (r/R) cos v)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2 * np.pi, 4 * n)
    v = rng.uniform(0, 2 * np.pi, 4 * n)
    keep = rng.uniform(0, 1 + r / R, 4 * n) < 1 + (r / R) * np.cos(v)
    u, v = u[keep][:n], v[keep][:n]
    normal = np.column_stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)])
    ring = np.column_stack([R * np.cos(u), R * np.sin(u), np.zeros_like(u)])
    return ring + r * normal, normal


def angles_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", a, b), -1.0, 1.0)))


def nurbs_sphere(radius=1.0):
    half = sk.arc_through_points((0, 0, -radius), (radius, 0, 0), (0, 0, radius))
    return sk.revolve(half, (0, 0, 0), (0, 0, 1))


# ------------------------------------------------------------------------------------------
# normals


def test_pca_normals_on_sphere_are_within_two_degrees_and_outward():
    center = np.array([1.0, -2.0, 5.0])
    P, true = sphere_cloud(30000, radius=3.0, center=center)
    N = estimate_normals(P, 16)
    assert N.shape == P.shape
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0)
    assert angles_deg(N, true).max() < 2.0  # includes orientation: a flipped normal is 180 degrees off


def test_pca_normals_on_torus_are_oriented_outward():
    P, true = torus_cloud(30000)
    N = estimate_normals(P, 16)
    ang = angles_deg(N, true)
    assert ang.max() < 10.0  # every one outward (a flip would be near 180)
    assert np.percentile(ang, 99) < 4.0


def test_unoriented_normals_are_only_defined_up_to_sign():
    P, true = sphere_cloud(5000)
    N = estimate_normals(P, 12, orient=False)
    assert np.abs(np.einsum("nd,nd->n", N, true)).min() > np.cos(np.radians(5))


def test_separate_spheres_are_each_oriented_outward():
    a, na = sphere_cloud(4000, 1.0, (-5.0, 0.0, 0.0), seed=1)
    b, nb = sphere_cloud(4000, 0.5, (4.0, 1.0, 0.0), seed=2)
    N = estimate_normals(np.vstack([a, b]), 12)
    assert np.einsum("nd,nd->n", N, np.vstack([na, nb])).min() > 0.9


def test_open_sheet_is_oriented_consistently():
    rng = np.random.default_rng(3)
    xy = rng.uniform(-1, 1, (5000, 2))
    z = 0.2 * np.sin(2 * xy[:, 0]) * xy[:, 1]
    N = estimate_normals(np.column_stack([xy, z]), 12)
    assert np.abs(N[:, 2]).min() > 0.8
    assert np.all(np.sign(N[:, 2]) == np.sign(N[0, 2]))


def test_orient_normals_repairs_random_flips():
    P, true = torus_cloud(8000, seed=4)
    rng = np.random.default_rng(5)
    flipped = true * rng.choice([-1.0, 1.0], len(P))[:, None] * 2.5  # any length
    N = orient_normals(P, flipped, 12)
    assert np.allclose(N, true, atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(1e-6, 1.0), st.floats(-3, 3))
def test_closed_form_eigenpairs_match_lapack(seed, thinness, log_scale):
    from splinekit.pointcloud._cloud import smallest_eigenpairs

    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(200, 3, 3)))
    lam = np.sort(rng.uniform(0.2, 1.0, (200, 3)), axis=1) * 10.0**log_scale
    lam[:, 0] *= thinness  # from isotropic-ish to nearly flat neighbourhoods
    C = np.einsum("mij,mj,mkj->mik", Q, lam, Q)
    values, v = smallest_eigenpairs(C)
    w, V = np.linalg.eigh(C)
    # the trigonometric solution is conditioned like the cubic's roots: an eigenvalue only
    # delta away from another carries a rounding error of order eps * lambda_max^2 / delta
    # (about 3e-12 for a gap of 7e-6); well separated ones are good to 1e-12 * lambda_max
    gap = np.min(np.abs(w[:, :, None] - w[:, None, :]) + np.diag([np.inf] * 3), axis=2)
    top = w[:, 2:]
    tol = 1e-12 * top + 4 * np.finfo(float).eps * top**2 / gap
    assert np.all(np.abs(values - w) <= tol)
    sep = (w[:, 1] - w[:, 0]) / w[:, 2]
    ok = sep > 1e-3
    assert np.allclose(np.abs(np.einsum("md,md->m", v, V[:, :, 0]))[ok], 1.0, atol=1e-9)


# ------------------------------------------------------------------------------------------
# curvature and outliers


def test_curvature_of_sphere_cylinder_and_plane():
    P, _ = sphere_cloud(20000, radius=2.0, seed=6)
    c = curvature(P, 20)
    assert np.allclose(np.median(c.mean), -0.5, rtol=0.01)  # H = -1/R with outward normals
    assert np.allclose(np.median(c.gaussian), 0.25, rtol=0.02)
    assert np.percentile(np.abs(c.mean + 0.5), 95) < 0.05
    # reversing the normals flips the mean curvature, not the Gaussian
    c2 = curvature(P, 20, normals=-c.normals)
    assert np.allclose(c2.mean, -c.mean) and np.allclose(c2.gaussian, c.gaussian)

    rng = np.random.default_rng(7)
    t, z = rng.uniform(0, 2 * np.pi, 20000), rng.uniform(-3, 3, 20000)
    C = np.column_stack([np.cos(t), np.sin(t), z])
    cc = curvature(C, 20)
    inner = np.abs(z) < 2.5
    assert np.allclose(np.median(cc.mean[inner]), -0.5, rtol=0.02)
    assert np.percentile(np.abs(cc.gaussian[inner]), 95) < 0.02

    xy = rng.uniform(-1, 1, (3000, 2))
    plane = np.column_stack([xy, 0.3 * xy[:, 0] - 0.2 * xy[:, 1]])
    cp = curvature(plane, 12)
    assert np.abs(cp.surface_variation).max() < 1e-12
    assert np.abs(cp.mean).max() < 1e-6 and np.abs(cp.gaussian).max() < 1e-6
    assert c.surface_variation.max() < 1.0 / 3.0


def test_remove_outliers_keeps_an_evenly_spaced_cloud():
    # every point alike (equal neighbour distances by symmetry, up to rounding): nothing is an outlier
    t = 2 * np.pi * np.arange(40) / 40
    ring = np.column_stack([np.cos(t), np.sin(t), np.full(40, 0.3)]) * 7.1
    ico = primitives.icosphere(0, radius=3.0).vertices
    for cloud, k in ((ring, 7), (ico, 6)):
        _, mask = remove_outliers(cloud, k, 0.5)
        assert mask.all()


def test_remove_outliers_removes_injected_outliers():
    P, _ = sphere_cloud(5000, seed=8)
    rng = np.random.default_rng(9)
    d = rng.normal(size=(40, 3))
    far = d / np.linalg.norm(d, axis=1)[:, None] * rng.uniform(1.5, 3.0, (40, 1))
    cloud = np.vstack([P, far])
    order = rng.permutation(len(cloud))
    kept, mask = remove_outliers(cloud[order], 16, 2.0)
    is_outlier = order >= len(P)
    assert not mask[is_outlier].any()
    assert mask[~is_outlier].mean() > 0.99
    assert np.array_equal(kept, cloud[order][mask])


# ------------------------------------------------------------------------------------------
# sampling


def test_sample_mesh_is_uniform_by_area():
    rng = np.random.default_rng(10)
    g = primitives.grid(6, 6, (2.0, 1.0))
    V = np.array(g.vertices, dtype=float)
    V[:, :2] += rng.uniform(-0.08, 0.08, (len(V), 2))
    V[:, 2] = rng.uniform(-0.3, 0.3, len(V))
    mesh = sk.PolyMesh(V, g.faces)
    n = 60000
    pts, face = sample_mesh(mesh, n, rng, return_faces=True)
    expected = mesh.face_areas / mesh.face_areas.sum() * n
    observed = np.bincount(face, minlength=mesh.n_faces)
    assert stats.chisquare(observed, expected).pvalue > 1e-3
    # each point lies in its face (quads are planar only approximately: check the distance to the mesh)
    d, _, _ = closest_points_on_mesh(mesh, pts[:2000])
    assert d.max() < 1e-12


def test_sample_surface_is_uniform_by_area_on_a_rational_sphere():
    # Archimedes: the area of a spherical zone is proportional to its height, so z is uniform
    R = 2.0
    pts = sample_surface(nurbs_sphere(R), 20000, rng=11)
    assert np.abs(np.linalg.norm(pts, axis=1) - R).max() < 1e-12
    assert stats.kstest(pts[:, 2] / R, stats.uniform(loc=-1, scale=2).cdf).pvalue > 1e-3
    lon = np.arctan2(pts[:, 1], pts[:, 0])
    assert stats.kstest(lon, stats.uniform(loc=-np.pi, scale=2 * np.pi).cdf).pvalue > 1e-3


def test_sample_surface_of_a_patch_set_splits_by_area():
    a = sk.extrude(sk.line((0, 0, 0), (1, 0, 0)), (0, 0, 1))  # area 1
    b = sk.extrude(sk.line((3, 0, 0), (6, 0, 0)), (0, 0, 1))  # area 3
    pts, patch, uv = sample_surface([a, b], 40000, rng=12, return_parameters=True)
    assert stats.binomtest(int((patch == 0).sum()), 40000, 0.25).pvalue > 1e-3
    assert np.allclose(pts[patch == 0], a.evaluate(uv[patch == 0, 0], uv[patch == 0, 1]))


def test_sample_curve_has_equal_chords_on_a_circle():
    c = sk.circle((1, 2, 3), (0, 0, 1), 2.0)
    P = sample_curve(c, 17)
    chords = np.linalg.norm(np.diff(P, axis=0), axis=1)
    assert np.allclose(chords, 2 * 2.0 * np.sin(np.pi / 16), rtol=1e-9)
    assert np.allclose(P[0], P[-1])


def _sequential_greedy(P, r, order):
    kept = []
    for i in order:
        if all(np.linalg.norm(P[i] - P[j]) >= r for j in kept):
            kept.append(i)
    return np.sort(kept)


def test_poisson_disk_equals_the_sequential_greedy_selection():
    rng = np.random.default_rng(13)
    P = rng.uniform(0, 1, (400, 3))
    r = 0.15
    got = poisson_disk(P, r, rng=14)
    order = np.argsort(np.random.default_rng(14).permutation(len(P)))  # rank -> visiting order
    ref = P[_sequential_greedy(P, r, order)]
    assert sorted(map(tuple, got)) == sorted(map(tuple, ref))


def test_poisson_disk_on_a_mesh_is_separated_and_covers():
    mesh = primitives.icosphere(3)
    r = 0.1
    pts = poisson_disk(mesh, r, rng=15)
    dist, _ = kd_tree(pts).query(pts, 2)
    assert dist[:, 1].min() >= r
    d, _, _ = closest_points_on_mesh(mesh, pts)
    assert d.max() < 1e-12
    cover = kd_tree(pts).query(sample_mesh(mesh, 50000, 16))[0].max()
    assert cover < 1.5 * r
    # about the packing density of a maximal disk set: between hexagonal-packing bounds
    area = mesh.area
    assert area / (np.pi * r**2) < len(pts) < area / (np.pi * (r / 2) ** 2)


# ------------------------------------------------------------------------------------------
# exact distance to a mesh, against a reference written differently


def _reference_triangle_distance(p, a, b, c):
    """Distance by projection onto the plane (if the foot is inside) or to the three edges."""
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = np.einsum("md,md->m", p - a, n)
    foot = p - h[:, None] * n
    inside = np.ones(len(p), dtype=bool)
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("md,md->m", np.cross(y - x, foot - x), n) >= 0
    best = np.where(inside, np.abs(h), np.inf)
    for x, y in ((a, b), (b, c), (c, a)):
        t = np.clip(np.einsum("md,md->m", p - x, y - x) / np.einsum("md,md->m", y - x, y - x), 0, 1)
        best = np.minimum(best, np.linalg.norm(p - (x + t[:, None] * (y - x)), axis=1))
    return best


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_mesh_distance_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(30, 3))
    T = np.array([rng.choice(30, 3, replace=False) for _ in range(40)])
    area = np.linalg.norm(np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]), axis=1)
    T = T[area > 1e-3]
    P = rng.normal(size=(50, 3)) * rng.uniform(0.1, 3.0)
    d, q, t = MeshDistance(V, T).query(P)
    m = len(T)
    ref = _reference_triangle_distance(np.repeat(P, m, 0), *(np.tile(V[T[:, j]], (len(P), 1)) for j in range(3)))
    ref = ref.reshape(len(P), m).min(axis=1)
    assert np.allclose(d, ref, rtol=1e-9, atol=1e-12)
    assert np.allclose(np.linalg.norm(q - P, axis=1), d)
    own = _reference_triangle_distance(P, V[T[t, 0]], V[T[t, 1]], V[T[t, 2]])
    assert np.allclose(own, d, rtol=1e-9, atol=1e-12)


def test_numpy_mesh_distance_certifies_in_bounded_groups(monkeypatch):
    # points deep inside a fine closed mesh have nearly every triangle within their certification
    # radius; the numpy search measures those pairs in groups (it once asked for 18.6 GB at once)
    import splinekit.pointcloud.meshdistance as md
    from splinekit.mesh.geometry import triangulate

    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    mesh = primitives.torus(32, 16, 1.0, 0.4)
    tris, _ = triangulate(mesh)
    V = np.asarray(mesh.vertices)
    rng = np.random.default_rng(5)
    ang = rng.uniform(0, 2 * np.pi, 200)
    P = np.stack([np.cos(ang), np.sin(ang), np.zeros(200)], axis=1) * rng.uniform(0.95, 1.05, (200, 1))  # on the core circle
    ref = _reference_triangle_distance(np.repeat(P, len(tris), 0), *(np.tile(V[tris[:, j]], (len(P), 1)) for j in range(3)))
    ref = ref.reshape(len(P), len(tris)).min(axis=1)
    groups = []
    certify = md.MeshDistance._certify
    monkeypatch.setattr(md, "EXHAUSTIVE_PAIRS", 2000)
    monkeypatch.setattr(md.MeshDistance, "_certify", lambda self, *a: (groups.append(len(a[2])), certify(self, *a))[1])
    d, _, _ = md.MeshDistance(V, tris).query(P)
    assert np.allclose(d, ref, rtol=1e-9, atol=1e-12)
    assert len(groups) > 1 and sum(groups) <= len(P)


def test_mesh_distance_matches_trimesh_on_a_torus():
    import trimesh  # the test extra installs it: no skip
    mesh = primitives.torus(24, 12, 1.0, 0.3)
    from splinekit.mesh.geometry import triangulate

    tris, _ = triangulate(mesh)
    P = np.random.default_rng(22).uniform(-1.6, 1.6, (3000, 3))
    d, _, _ = closest_points_on_mesh(mesh, P)
    tm = trimesh.Trimesh(np.asarray(mesh.vertices), tris, process=False)
    ref = trimesh.proximity.closest_point(tm, P)[1]
    assert np.allclose(d, ref, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy k-d tree", "compiled BVH"])
def test_both_mesh_distance_searches_match_trimesh_with_signs(compiled, monkeypatch):
    # the one MeshDistance has two searches for the nearest triangle (module notes): each one is
    # checked against trimesh, unsigned and signed (trimesh: positive inside)
    trimesh = pytest.importorskip("trimesh")
    from splinekit import _kernels
    from splinekit.errors import NotManifoldError
    from splinekit.mesh.geometry import triangulate

    if compiled:
        pytest.importorskip("numba")
        monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    mesh = primitives.torus(24, 12, 1.0, 0.3)
    tris, _ = triangulate(mesh)
    P = np.random.default_rng(23).uniform(-1.6, 1.6, (3000, 3))
    md = MeshDistance.of_mesh(mesh)
    d, q, _ = md.query(P)
    tm = trimesh.Trimesh(np.asarray(mesh.vertices), tris, process=False)
    ref = trimesh.proximity.signed_distance(tm, P)
    assert np.allclose(d, np.abs(ref), rtol=1e-9, atol=1e-12)
    assert np.allclose(np.linalg.norm(q - P, axis=1), d, rtol=1e-12, atol=1e-15)
    signed, found = md.signed(P)
    assert found.all() and np.allclose(signed, -ref, rtol=1e-9, atol=1e-12)
    near, found = md.signed(P, max_distance=0.1)
    assert np.array_equal(found, d <= 0.1) and np.isinf(near[~found]).all()
    assert np.allclose(near[found], signed[found])
    with pytest.raises(NotManifoldError, match="not closed"):
        MeshDistance(np.asarray(mesh.vertices), tris[:-1]).signed(P)


# ------------------------------------------------------------------------------------------
# reconstruction


def test_height_field_fit_meets_the_tolerance():
    rng = np.random.default_rng(17)
    xy = rng.uniform(-1, 1, (4000, 2))
    Q = np.column_stack([xy, 0.4 * np.sin(2 * xy[:, 0]) * np.cos(3 * xy[:, 1])])
    for tol in (1e-2, 1e-3):
        s = fit_height_field(Q, tol)
        assert sk.project(s, Q).distances.max() <= tol
    fixed = fit_height_field(Q, n_control=(6, 5))
    assert fixed.control_points.shape == (6, 5, 3)


def test_height_field_fit_refuses_a_tolerance_below_the_noise():
    rng = np.random.default_rng(18)
    xy = rng.uniform(-1, 1, (3000, 2))
    Q = np.column_stack([xy, 0.01 * rng.normal(size=3000)])
    with pytest.raises(FittingError, match="residual"):
        fit_height_field(Q, 1e-4, max_control=20)


def test_mls_distance_is_a_signed_distance_near_a_sphere_with_exact_gradient():
    P, N = sphere_cloud(6000, seed=19)
    tree = kd_tree(P)
    rng = np.random.default_rng(20)
    d = rng.normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    for radius in (0.7, 1.0, 1.3):
        F = mls_distance(P, N, tree, 16, radius * d, gradient=False)
        assert np.abs(F - (radius - 1.0)).max() < 0.01
    q = 1.02 * d
    F, G = mls_distance(P, N, tree, 16, q)
    h = 1e-6
    fd = np.column_stack([
        (mls_distance(P, N, tree, 16, q + h * e, False) - mls_distance(P, N, tree, 16, q - h * e, False)) / (2 * h)
        for e in np.eye(3)
    ])
    assert np.abs(G - fd).max() < 1e-6
    assert np.abs(np.linalg.norm(G, axis=1) - 1).max() < 0.01
    # without a tree one is built over the points: the same field
    F0, G0 = mls_distance(P, N, None, 16, q)
    assert np.array_equal(F0, F) and np.array_equal(G0, G)


def test_implicit_reconstruction_of_a_sphere_meshes_close_to_it():
    from splinekit.implicit import Implicit

    P, _ = sphere_cloud(3000, radius=1.0, seed=21)
    imp = reconstruct_implicit(P)  # normals estimated and oriented
    assert isinstance(imp, Implicit)
    assert imp(np.zeros((1, 3)))[0] < 0 < imp(np.array([[2.0, 0.0, 0.0]]))[0]
    mesh = imp.to_mesh(0.08)
    assert mesh.is_closed and mesh.euler_characteristic == 2
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert np.abs(r - 1.0).max() < 0.02  # stated distance for 3000 samples of the unit sphere
    assert abs(mesh.volume / (4 / 3 * np.pi) - 1) < 0.02


# ------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    "call",
    [
        lambda: estimate_normals(np.zeros((0, 3))),
        lambda: estimate_normals(np.random.default_rng(0).normal(size=(10, 3)), 11),
        lambda: estimate_normals(np.random.default_rng(0).normal(size=(10, 3)), 2),
        lambda: estimate_normals(np.random.default_rng(0).normal(size=(10, 3)), 2.5),
        lambda: estimate_normals([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0], [0, 1, 0]], 3),
        lambda: estimate_normals(np.zeros((10, 2)), 3),
        lambda: estimate_normals(np.column_stack([np.arange(10.0), 2 * np.arange(10.0), np.zeros(10)]), 4),
        lambda: orient_normals(np.eye(3), np.zeros((3, 3)), 2),
        lambda: orient_normals(np.eye(3), np.eye(3)[:2], 2),
        lambda: curvature(np.random.default_rng(0).normal(size=(10, 3)), 5),
        lambda: curvature(np.zeros((0, 3))),
        lambda: remove_outliers(np.random.default_rng(0).normal(size=(10, 3)), 16),
        lambda: remove_outliers(np.random.default_rng(0).normal(size=(10, 3)), 4, -1.0),
        lambda: remove_outliers(np.full((5, 3), np.inf), 2),
        lambda: poisson_disk(np.random.default_rng(0).normal(size=(10, 3)), 0.0),
        lambda: poisson_disk(np.zeros((0, 3)), 0.1),
        lambda: poisson_disk(primitives.icosphere(1), 0.1, oversampling=0.5),
        lambda: sample_mesh(primitives.icosphere(1), 0),
        lambda: sample_mesh(primitives.icosphere(1), 10, rng="seed"),
        lambda: sample_surface([], 10),
        lambda: sample_surface(sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 2))), 10),
        lambda: sample_mesh(primitives.icosphere(1), 10, rng=-1),
        lambda: sample_surface(nurbs_sphere(), -1),
        lambda: sample_curve(sk.circle((0, 0, 0), (0, 0, 1), 1.0), 1),
        lambda: fit_height_field(np.zeros((2, 3))),
        lambda: fit_height_field(np.random.default_rng(0).normal(size=(50, 3)), -1.0),
        lambda: reconstruct_implicit(np.random.default_rng(0).normal(size=(50, 3)), np.zeros((50, 3))),
        lambda: reconstruct_implicit(np.random.default_rng(0).normal(size=(50, 3)), k=51),
        lambda: MeshDistance(np.eye(3), [[0, 1, 3]]),
        lambda: closest_points_on_mesh(primitives.icosphere(1), [[np.nan, 0, 0]]),
        # not a curve or a mesh: named, not an AttributeError
        lambda: sample_curve(3, 10),
        lambda: sample_mesh(np.zeros((3, 3)), 10),
        lambda: closest_points_on_mesh(np.zeros((3, 3)), [[0, 0, 0]]),
        # a radius so small the sample count is beyond any budget (and beyond int64)
        lambda: poisson_disk(primitives.icosphere(1), 1e-300),
        # squared distances beyond the float range: the tree finds no neighbours
        lambda: estimate_normals(np.random.default_rng(0).normal(size=(50, 3)) * 1e200),
        lambda: curvature(np.random.default_rng(0).normal(size=(50, 3)) * 1e200),
        lambda: remove_outliers(np.random.default_rng(0).normal(size=(50, 3)) * 1e307),
        lambda: reconstruct_implicit(*sphere_cloud(200))([[1e300, 0, 0]]),
        lambda: MeshDistance([[-1e308, 0, 0], [1e308, 0, 0], [0, 1, 0]], [[0, 1, 2]]),  # wider than the floats
        lambda: MeshDistance(np.eye(3), [[0, 1, 2]]).query([[1e300, 0, 0]]),
        lambda: closest_points_on_mesh(primitives.icosphere(2), [[2.0, 0, 0], [1e200, 0, 0]]),
    ],
)
def test_bad_input_raises_a_splinekit_error(call):
    with pytest.raises(SplineKitError):
        call()


def test_height_field_degree_is_checked_as_a_degree():
    P = np.random.default_rng(0).uniform(-1, 1, (50, 3))
    for bad in (0, 200, 2.5):
        with pytest.raises(DegreeError):
            fit_height_field(P, degree=bad)


@pytest.mark.parametrize("scale", [1e-200, 1e-80, 3.0, 1e80, 1e200])
def test_mesh_distance_is_exact_at_any_scale(scale):
    # the Voronoi tests multiply dot products (length^4): unscaled they overflow beyond
    # ~1e77 and underflow below ~1e-77; distances must simply scale with the mesh
    mesh = primitives.icosphere(2)
    q = np.random.default_rng(23).uniform(-2, 2, (500, 3))
    d, c, _ = closest_points_on_mesh(mesh, q)
    ds, cs, _ = closest_points_on_mesh(sk.PolyMesh(mesh.vertices * scale, mesh.faces), q * scale)
    assert np.allclose(ds / scale, d, rtol=0, atol=1e-14) and np.allclose(cs / scale, c, rtol=0, atol=1e-14)

