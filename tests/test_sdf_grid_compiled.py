"""The compiled mesh -> SDF grid (MeshDistance.grid_signed, used by from_mesh) against
independent references: brute-force distances over every (sample, triangle) pair and the
generalized winding number for the sign (both from test_sdf_grid), on grids small enough for
brute force, with the compiled path forced at every size."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from _compiled import compiled_or_skip
from test_sdf_grid import brute_distance, star_mesh, winding_number

from splinekit import _kernels, limits
from splinekit.errors import ResourceLimitError
from splinekit.implicit.frommesh import from_mesh
from splinekit.mesh import PolyMesh, primitives
from splinekit.mesh.geometry import triangulate
from splinekit.pointcloud import meshdistance
from splinekit.pointcloud.meshdistance import MeshDistance

pytest.importorskip("numba")
from numba import njit  # noqa: E402

from splinekit.pointcloud._gridsdf_bounds import tangent  # noqa: E402


@contextlib.contextmanager
def forced():
    """Compiled kernels for every job size (the loader leaves small grids to numpy)."""
    compiled_or_skip(meshdistance.GRID_KERNELS)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SPLINEKIT_NUMBA", "1")
        mp.setattr(_kernels, "MIN_WORK", 0)
        yield


@pytest.fixture
def compiled():
    with forced():
        yield


def check_against_brute_force(mesh, sdf):
    V = np.asarray(mesh.vertices)
    T, _ = triangulate(mesh)
    P = sdf.points().reshape(-1, 3)
    vals = sdf.values.ravel()
    scale = np.abs(V).max()
    assert np.allclose(np.abs(vals), brute_distance(P, V, T), atol=1e-12 * scale, rtol=0)
    clear = np.abs(vals) > 1e-9 * scale
    assert np.array_equal((vals < 0)[clear], (winding_number(P, V, T) > 0.5)[clear])
    assert (vals < 0).any() and (vals > 0).any()


@pytest.mark.parametrize(
    "make",
    [lambda: primitives.icosphere(2), lambda: primitives.torus(nu=16, nv=8, R=1.0, r=0.3), star_mesh],
    ids=["icosphere", "torus", "star"],
)
@pytest.mark.parametrize("res", [9, 18])  # blocks cut by the grid end; far blocks at 18
def test_compiled_grid_against_brute_force(compiled, make, res):
    mesh = make()
    check_against_brute_force(mesh, from_mesh(mesh, res))


def test_the_far_blocks_are_taken_and_agree_with_per_point_queries(compiled):
    # a coarse mesh in a grid padded widely: most blocks are far from the surface, where the
    # candidate lists (not per-sample walks) answer; compare with the per-point walk of signed()
    mesh = star_mesh()
    sdf = from_mesh(mesh, 24, padding=1.5)
    dist = MeshDistance.of_mesh(mesh)
    P = sdf.points().reshape(-1, 3)
    d, found = dist.signed(P)
    assert found.all()
    assert np.allclose(sdf.values.ravel(), d, atol=1e-12, rtol=0)
    # a 4^3 block has half-diagonal 1.5 voxel diagonals; beyond FAR = 2 of those it is far
    far = np.abs(d) > 3 * np.linalg.norm(sdf.spacing) + 1.5 * np.linalg.norm(sdf.spacing)
    assert far.mean() > 0.3


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    res=st.integers(6, 16),
    bumps=st.floats(0.0, 0.45),
    scale=st.sampled_from([1e-3, 1.0, 1e4]),
)
def test_random_lumpy_spheres_against_brute_force(seed, res, bumps, scale):
    rng = np.random.default_rng(seed)
    m = primitives.icosphere(2)
    V = np.asarray(m.vertices)
    a, b = rng.integers(1, 5, 2)
    th = np.arctan2(V[:, 1], V[:, 0])
    ph = np.arccos(np.clip(V[:, 2], -1, 1))
    r = 1 + bumps * np.sin(a * th + rng.uniform(0, 6)) * np.sin(ph) ** 2 * np.cos(b * ph)
    mesh = PolyMesh(V * r[:, None] * scale + rng.uniform(-5, 5, 3) * scale, m.faces)
    with forced():
        sdf = from_mesh(mesh, res, padding=float(rng.uniform(0.05, 0.8)))
    check_against_brute_force(mesh, sdf)


def test_compiled_narrow_band_matches_the_dense_grid(compiled):
    mesh = star_mesh()
    dense = from_mesh(mesh, 20)
    band = 3.0 * float(np.linalg.norm(dense.spacing))
    nb = from_mesh(mesh, 20, band=band)
    dv = dense.values
    assert nb.n_stored == int((np.abs(dv) < band).sum())
    assert np.allclose(nb.values, np.where(np.abs(dv) < band, dv, np.sign(dv) * band), atol=1e-12)


def lumpy_sphere(level):
    """The benchmark's case: an icosphere with radius 1 + 0.3 sin(3 theta) sin^2(phi) + 0.15 cos(5 phi)."""
    m = primitives.icosphere(level)
    V = np.asarray(m.vertices)
    th = np.arctan2(V[:, 1], V[:, 0])
    ph = np.arccos(np.clip(V[:, 2], -1, 1))
    r = 1 + 0.3 * np.sin(3 * th) * np.sin(ph) ** 2 + 0.15 * np.cos(5 * ph)
    return PolyMesh(V * r[:, None], m.faces)


def check_random_samples(mesh, sdf, n, seed=0, per=200):
    """Brute-force distance and winding-number sign at ``n`` random samples of the grid (in
    chunks: the references hold every (sample, triangle) pair)."""
    V = np.asarray(mesh.vertices)
    T, _ = triangulate(mesh)
    pick = np.random.default_rng(seed).choice(sdf.values.size, n, replace=False)
    P = sdf.points().reshape(-1, 3)[pick]
    vals = sdf.values.ravel()[pick]
    with np.errstate(divide="ignore", invalid="ignore"):  # a sliver's barycentric solve
        d = np.concatenate([brute_distance(P[s : s + per], V, T) for s in range(0, n, per)])
    w = np.concatenate([winding_number(P[s : s + per], V, T) for s in range(0, n, per)])
    scale = np.abs(V).max()
    assert np.allclose(np.abs(vals), d, atol=1e-12 * scale, rtol=0)
    clear = np.abs(vals) > 1e-9 * scale
    assert np.array_equal((vals < 0)[clear], (w > 0.5)[clear])
    return vals


def test_lumpy_sphere_random_samples_against_brute_force(compiled):
    # 5,120 triangles at 40^3: far blocks (candidate lists), blocks near the surface split in
    # eight, blocks cut by the grid end
    mesh = lumpy_sphere(4)
    vals = check_random_samples(mesh, from_mesh(mesh, 40), 1200)
    assert (vals < 0).mean() > 0.1 and (vals > 0).mean() > 0.1


@pytest.mark.slow
def test_benchmark_case_random_samples_against_brute_force(compiled):
    # the issue-17 case itself: 81,920 triangles at 128^3
    mesh = lumpy_sphere(6)
    check_random_samples(mesh, from_mesh(mesh, 128), 3000, per=20)


def test_a_sliver_triangle_gets_no_plane_and_the_grid_stays_exact(compiled):
    # split the edge (a, b) of two neighbouring triangles at a point m a hair off its midpoint:
    # the triangle (b, m, a) closing the mesh is a sliver whose normal rounding could turn, so
    # the kernel's bounds must not use its plane (it is always measured exactly)
    m = primitives.icosphere(1)
    V = np.asarray(m.vertices, dtype=float)
    T = np.asarray(triangulate(m)[0])
    a, b, c = T[0]
    mid = 0.5 * (V[a] + V[b]) * (1 + 1e-9)
    k = len(V)
    T2 = np.concatenate([[[a, k, c], [k, b, c], [b, k, a]], T[1:]])
    mesh = PolyMesh(np.vstack([V, mid]), T2)
    plane, _ = MeshDistance(mesh.vertices, T2)._bvh_planes
    assert int((np.abs(plane).sum(axis=1) == 0).sum()) == 1
    check_random_samples(mesh, from_mesh(mesh, 24), 1500)


def test_the_kernels_work_arrays_are_checked_against_the_memory_budget(compiled, monkeypatch):
    monkeypatch.setattr(meshdistance, "GRID_SCAN", False)  # the block kernel's arrays
    dist = MeshDistance.of_mesh(star_mesh())
    need = meshdistance.GRID_WORK_BYTES * len(dist.tris)
    with limits.budget(need // 2), pytest.raises(ResourceLimitError, match="work arrays"):
        dist.grid_signed(np.full(3, -2.0), np.full(3, 0.2), (20, 20, 20))
    with limits.budget(1 << 30):
        assert np.isfinite(dist.grid_signed(np.full(3, -2.0), np.full(3, 0.2), (20, 20, 20))).all()


def prism_bound(prism, P):
    """The grid kernel's lower bound of the distance from points ``P`` (n, 3) to each triangle
    (rows of ``prism``, unit-box coordinates), in numpy: plane part and in-plane part (edge lines,
    bounding disk), each lowered by the kernel's margin."""
    from splinekit.pointcloud._gridsdf_bounds import TOL

    n, off = prism[:, :3], prism[:, 3]
    p = P @ n.T - off
    edges = np.stack([P @ prism[:, 4 + 4 * k : 7 + 4 * k].T - prism[:, 7 + 4 * k] for k in range(3)])
    v = P[:, None, :] - prism[None, :, 16:19] - p[..., None] * n[None]
    with np.errstate(invalid="ignore"):  # inf - inf of a triangle without a disk
        disk = np.linalg.norm(v, axis=2) - prism[:, 19]
    lateral = np.maximum(np.nanmax(np.concatenate([edges, disk[None]]), axis=0) - TOL, 0.0)
    return np.hypot(np.maximum(np.abs(p) - TOL, 0.0), lateral)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), thin=st.sampled_from([1.0, 1e-3, 1e-7]),
       spread=st.sampled_from([1e-3, 0.1, 1.0, 10.0]))
def test_the_kernels_triangle_bound_never_exceeds_the_distance(seed, thin, spread):
    # the bound only decides which triangles are measured: above the distance it would skip the
    # nearest one. Random triangles (some slivers, down to 1e-10 wide, which get no bound), points
    # near their vertices and edges, and far away, against the brute-force distance
    md, P = random_triangles_and_points(seed, thin, spread)
    bound = prism_bound(md._bvh_prisms, P)
    assert (bound <= distances_to_each(md, P) * (1 + 1e-12) + 1e-15).all()


def random_triangles_and_points(seed, thin, spread):
    """Ten random triangles (half of them slivers ``thin`` wide, down to 1e-10, which get no
    bound) and points near their vertices and edges and at random (scale ``spread``)."""
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(30, 3))
    T = rng.integers(0, 30, (10, 3))
    T[:, 1] = (T[:, 0] + 1 + T[:, 1] % 29) % 30
    V[T[:5, 2]] = V[T[:5, 0]] + thin * (V[T[:5, 1]] - V[T[:5, 0]]) + thin * 1e-3 * rng.normal(size=(5, 3))
    T = T[(T[:, 0] != T[:, 2]) & (T[:, 1] != T[:, 2])]
    md = MeshDistance(V, T)
    corners = md.bvh.tri.reshape(-1, 3)
    P = np.concatenate([
        corners + 1e-9 * rng.normal(size=corners.shape),
        0.5 * (corners + np.roll(corners, 1, axis=0)) + 1e-6 * rng.normal(size=corners.shape),
        rng.normal(size=(200, 3)) * spread,
    ])
    return md, P


def distances_to_each(md, P):
    """Brute-force distances ``(n, T)`` from points ``P`` to each triangle of ``md`` (unit box)."""
    T = len(md.bvh.tri)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.stack([brute_distance(P, md.bvh.tri.reshape(-1, 3), np.arange(3 * T).reshape(-1, 3)[[t]])
                         for t in range(T)], axis=1)


@njit
def tangents_at(cv, e, P):
    """The compiled bound of candidate ``e`` and its gradient at each point of ``P``: ``(n, 4)``."""
    out = np.empty((len(P), 4))
    for i in range(len(P)):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = tangent(cv, e, P[i, 0], P[i, 1], P[i, 2])
    return out


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), thin=st.sampled_from([1.0, 1e-3, 1e-7]),
       spread=st.sampled_from([1e-3, 0.1, 1.0]), step=st.sampled_from([1e-3, 0.05, 0.5]))
def test_the_bounds_tangent_plane_stays_below_the_distance_and_touches_the_bound(seed, thin, spread, step):
    # the block test linearizes each bound at a block's centre p (tangent): b + g . (x - p) must
    # stay below the distance at every x (the bound is convex), b must be the bound at p and g
    # its gradient (a wrong gradient leaves a first-order gap beside p, which the last check sees)
    md, P = random_triangles_and_points(seed, thin, spread)
    prism = md._bvh_prisms
    cv = np.ascontiguousarray(prism.T)
    rng = np.random.default_rng(seed + 1)
    X = P + step * rng.normal(size=P.shape)
    exact = distances_to_each(md, X)
    at_p = prism_bound(prism, P)
    eps = 1e-6
    U = rng.normal(size=P.shape)
    U /= np.linalg.norm(U, axis=1)[:, None]
    beside = np.stack([prism_bound(prism, P + sgn * eps * U) for sgn in (1.0, -1.0)])
    for e in range(len(prism)):
        tg = tangents_at(cv, e, P)
        lin = tg[:, 0] + np.einsum("ij,ij->i", tg[:, 1:], X - P)
        assert (lin <= exact[:, e] * (1 + 1e-12) + 1e-12).all()
        assert np.allclose(tg[:, 0], at_p[:, e], rtol=1e-12, atol=1e-14)
        slope = np.einsum("ij,ij->i", tg[:, 1:], U)
        gap = beside[:, :, e] - (tg[None, :, 0] + np.array([1.0, -1.0])[:, None] * eps * slope[None])
        # convex: above its tangent plane on both sides (a gradient off by d leaves a gap of
        # -eps |d . u| on one side, so this check catches it)
        assert (gap >= -1e-12).all()
        # and touching it to second order: on one side at least, as a step may cross a kink
        # (where another edge line or the disk takes over) on the other
        smooth = tg[:, 0] > 1e-3  # away from the prism, where the bound has a kink at zero
        assert (gap[:, smooth].min(axis=0) <= 1e-9).all()


def test_samples_on_vertices_edges_and_far_blocks_at_every_level(compiled):
    # the octahedron |x| + |y| + |z| = 2 on a grid of step 0.25 from -7 to 7: samples lie on its
    # vertices, on its edges and on its faces, and the far corners are far even for 8^3 blocks
    V = 2.0 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    T = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    dist = MeshDistance(V, T)
    shape = (57, 57, 57)
    d = dist.grid_signed(np.full(3, -7.0), np.full(3, 0.25), shape)
    axis = -7.0 + 0.25 * np.arange(57)
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    exact = np.concatenate([brute_distance(P[s : s + 20000], V, T) for s in range(0, len(P), 20000)])
    assert np.allclose(np.abs(d.ravel()), exact, atol=1e-12, rtol=0)
    on = exact == 0.0
    assert on.sum() > 100  # vertices, edges and faces all carry samples
    inside = np.abs(P).sum(axis=1) < 2.0
    assert np.array_equal(d.ravel()[~on] < 0, inside[~on])
    # an 8^3 block's half-diagonal is 3.5 sqrt(3) steps; beyond FAR of those it is far
    assert (exact > 2 * 3.5 * np.sqrt(3) * 0.25 + 3.5 * np.sqrt(3) * 0.25).mean() > 0.2


@pytest.mark.parametrize("block", [2, 4, 16])
def test_the_answer_does_not_depend_on_the_block_size(compiled, block, monkeypatch):
    # one level (2: the leaf blocks open the root), two, four: the same exact grid
    mesh = lumpy_sphere(2)
    dist = MeshDistance.of_mesh(mesh)
    args = (np.full(3, -2.5), np.full(3, 0.13), (39, 40, 41))
    ref = dist.grid_signed(*args)
    monkeypatch.setattr(meshdistance, "GRID_BLOCK", block)
    monkeypatch.setattr(meshdistance, "GRID_SCAN", False)  # the block kernel (the regions' scan has no blocks)
    assert np.allclose(dist.grid_signed(*args), ref, atol=1e-12, rtol=0)
    check_random_samples(mesh, from_mesh(mesh, 30), 600, seed=block)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), block=st.sampled_from([2, 4, 8, 16, 32]),
       open_ratio=st.sampled_from([0.25, 1.0, 4.0]), level=st.sampled_from([1, 2]))
def test_spiky_meshes_any_block_and_node_size_against_brute_force(seed, block, open_ratio, level):
    # star-shaped meshes with a random radius per vertex (spikes and pits next to each other): the
    # nearest triangle jumps between distant parts of the surface, so the blocks' lists (hierarchy
    # nodes kept or opened, near and far blocks at every level) are tested where they are tight
    rng = np.random.default_rng(seed)
    m = primitives.icosphere(level)
    V = np.asarray(m.vertices) * rng.uniform(0.3, 1.6, (len(m.vertices), 1))
    T = np.asarray(triangulate(m)[0])
    step = float(rng.uniform(0.04, 0.12))
    shape = tuple(int(n) for n in rng.integers(16, 28, 3))
    origin = -0.5 * step * (np.array(shape) - 1) + rng.uniform(-0.2, 0.2, 3)
    dist = MeshDistance(V, T)
    with forced(), pytest.MonkeyPatch.context() as mp:
        mp.setattr(meshdistance, "GRID_BLOCK", block)
        mp.setattr(meshdistance, "GRID_OPEN", open_ratio)
        mp.setattr(meshdistance, "GRID_SCAN", False)  # the block kernel
        d = dist.grid_signed(origin, np.full(3, step), shape).ravel()
    axes = [origin[k] + step * np.arange(shape[k]) for k in range(3)]
    P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = np.concatenate([brute_distance(P[s : s + 4000], V, T) for s in range(0, len(P), 4000)])
    assert np.allclose(np.abs(d), exact, atol=1e-12, rtol=0)
    clear = exact > 1e-9
    w = np.concatenate([winding_number(P[s : s + 4000], V, T) for s in range(0, len(P), 4000)])
    assert np.array_equal((d < 0)[clear], (w > 0.5)[clear])
