"""The compiled k-nearest-neighbour search and PCA normals (splinekit.pointcloud._pointtree)
against independent references: brute-force distances (scipy's cdist over every pair), LAPACK's
eigh of the brute-force neighbourhoods' covariances, and the numpy path (cKDTree) end to end.
Both compiled searches are checked: the cell grid (with its wide-block and hierarchy fallbacks)
and the Morton hierarchy alone."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from _compiled import compiled_or_skip
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from splinekit import _kernels
from splinekit.errors import ControlPointError, FittingError
from splinekit.pointcloud import _pointtree, estimate_normals, orient_normals
from splinekit.pointcloud._cloud import smallest_eigenpairs

pytest.importorskip("numba")


@pytest.fixture
def compiled(monkeypatch):
    """The compiled path at every size (the loader would leave small clouds to numpy)."""
    kernels = compiled_or_skip(_pointtree.KERNELS)
    monkeypatch.setattr(_pointtree, "_kernels_for", lambda n, k: kernels)
    return kernels


def cloud(kind, n, rng):
    if kind == "uniform":
        return rng.uniform(-1, 1, (n, 3))
    if kind == "clusters":  # a few tight blobs far apart: leaves of very different sizes
        centres = rng.uniform(-100, 100, (4, 3))
        return centres[rng.integers(0, 4, n)] + rng.normal(scale=1e-3, size=(n, 3))
    if kind == "sheet":  # a plane, with exact duplicates (distance ties at 0)
        P = np.column_stack([rng.uniform(-1, 1, (n, 2)), np.zeros(n)])
        P[n // 2 :: 7] = P[: len(P[n // 2 :: 7])]
        return P
    if kind == "line-ish":  # far larger along x than across
        return rng.normal(size=(n, 3)) * [1e3, 1e-2, 1e-2] + 5e6
    if kind == "mixed":  # a dense curved sheet in a sparse haze: the grid's cells suit only the sheet
        m = n - n // 8
        uv = rng.uniform(-1, 1, (m, 2))
        sheet = np.column_stack([uv, 0.2 * np.sin(2 * uv[:, 0])])
        return np.vstack([sheet, rng.uniform(-3, 3, (n - m, 3))])
    raise AssertionError(kind)


KINDS = ["uniform", "clusters", "sheet", "line-ish", "mixed"]

PATHS = {"grid": 1e300, "hierarchy": 0.0}  # _pointtree.CROWDING: the grid always fits / never does


def brute_knn_distances(P, k):
    D = cdist(P, P)
    return np.sort(D, axis=1)[:, :k], D


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), path=st.sampled_from([None, *PATHS]), n=st.integers(1, 300),
       k=st.integers(1, 24), seed=st.integers(0, 2**32 - 1))
def test_knn_matches_brute_force(kind, path, n, k, seed):
    kernels = compiled_or_skip(_pointtree.KERNELS)
    k = min(k, n)
    P = cloud(kind, n, np.random.default_rng(seed))
    original = _pointtree._kernels_for, _pointtree.CROWDING
    _pointtree._kernels_for = lambda n, k: kernels
    if path is not None:
        _pointtree.CROWDING = PATHS[path]
    try:
        d, idx = _pointtree.compiled_knn(P, k)
    finally:
        _pointtree._kernels_for, _pointtree.CROWDING = original
    ref, D = brute_knn_distances(P, k)
    scale = 1e-12 * (1 + np.abs(P).max())
    assert np.allclose(d, ref, rtol=1e-12, atol=scale)
    assert np.array_equal(idx[:, 0], np.arange(n))  # the point itself first, even among duplicates
    # the returned indices are at the returned distances, and distinct
    assert np.allclose(D[np.arange(n)[:, None], idx], d, rtol=1e-12, atol=scale)
    assert all(len(set(row)) == k for row in idx.tolist())


@pytest.mark.parametrize("path", [None, *PATHS])
@pytest.mark.parametrize("kind", ["uniform", "sheet", "clusters", "mixed"])
def test_compiled_normals_match_lapack_on_brute_force_neighbourhoods(compiled, monkeypatch, kind, path):
    if path is not None:
        monkeypatch.setattr(_pointtree, "CROWDING", PATHS[path])
    rng = np.random.default_rng(11)
    P = cloud(kind, 400, rng)
    if kind == "sheet":  # a curved sheet without duplicates: every neighbourhood has a normal
        P = np.column_stack([P[:, :2], 0.3 * np.sin(3 * P[:, 0])]) + rng.normal(scale=1e-6, size=P.shape)
    k = 12
    values, N, kth, idx = _pointtree.compiled_normals(P, k, want_indices=True)
    ref, D = brute_knn_distances(P, k)
    assert np.allclose(kth, ref[:, -1], rtol=1e-12, atol=1e-14)
    # LAPACK on the covariance of the brute-force neighbourhood (its k nearest by cdist)
    near = np.argsort(D, axis=1, kind="stable")[:, :k]
    X = P[near] - P[near].mean(axis=1)[:, None]
    w, V = np.linalg.eigh(np.einsum("nki,nkj->nij", X, X) / k)
    assert np.allclose(values, w, rtol=1e-9, atol=1e-12 * w[:, 2:])
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0)
    separated = (w[:, 1] - w[:, 0]) > 1e-6 * w[:, 2]
    assert separated.mean() > 0.9
    assert np.allclose(np.abs(np.einsum("nd,nd->n", N, V[:, :, 0]))[separated], 1.0, atol=1e-8)


def sym3(kernels, C):
    out = np.empty(6)
    kernels.sym3_smallest(C[0, 0], C[1, 1], C[2, 2], C[0, 1], C[1, 2], C[0, 2], out)
    return out[:3], out[3:]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), thinness=st.floats(1e-6, 1.0), log_scale=st.floats(-3, 3))
def test_scalar_eigen_solve_is_the_vectorized_one(seed, thinness, log_scale):
    kernels = compiled_or_skip(_pointtree.KERNELS)
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    lam = np.sort(rng.uniform(0.2, 1.0, 3)) * 10.0**log_scale
    lam[0] *= thinness
    C = Q @ np.diag(lam) @ Q.T
    C = (C + C.T) / 2
    values, v = sym3(kernels, C)
    ref_values, ref_v = smallest_eigenpairs(C[None])
    assert np.allclose(values, ref_values[0], rtol=1e-12, atol=1e-14 * lam[2])
    w, V = np.linalg.eigh(C)
    if (w[1] - w[0]) > 1e-3 * w[2]:
        assert abs(abs(v @ V[:, 0]) - 1.0) < 1e-9


@pytest.mark.parametrize("seed", range(5))
def test_eigen_solve_of_a_double_smallest_eigenvalue_stays_in_its_eigenspace(compiled, seed):
    # lambda_0 = lambda_1 < lambda_2: every vector orthogonal to the top eigenvector is right,
    # but the cross products of the rows of C - lambda_0 I are only rounding noise
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    C = Q @ np.diag([0.5, 0.5, 2.0]) @ Q.T
    values, v = sym3(compiled, C)
    assert np.allclose(values, [0.5, 0.5, 2.0], atol=1e-12)
    assert abs(np.linalg.norm(v) - 1.0) < 1e-12
    assert abs(v @ Q[:, 2]) < 1e-6
    assert np.allclose(C @ v, 0.5 * v, atol=1e-6)
    values, v = sym3(compiled, np.zeros((3, 3)))
    assert np.allclose(values, 0.0) and abs(np.linalg.norm(v) - 1.0) < 1e-12


def torus(n, seed):
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 2 * np.pi, (2, n))
    normal = np.column_stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)])
    return np.column_stack([np.cos(u), np.sin(u), np.zeros(n)]) + 0.35 * normal, normal


@pytest.mark.parametrize("orient", [False, True])
def test_estimate_normals_gives_the_same_answer_on_both_paths(monkeypatch, orient):
    P, true = torus(8000, seed=3)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    ref = estimate_normals(P, 16, orient=orient)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")  # 8000 points x k = 16 is above MIN_WORK
    assert _kernels.load(_pointtree.KERNELS, work=8000 * 16 / 4) is not None or pytest.skip("no numba")
    N = estimate_normals(P, 16, orient=orient)
    if orient:
        assert np.allclose(N, ref, atol=1e-9)  # same neighbourhoods: the same tree and signs
        assert (np.einsum("nd,nd->n", N, true) > 0).all()
        flipped = true * np.where(np.arange(len(P)) % 3 == 0, -1.0, 1.0)[:, None]
        assert np.allclose(orient_normals(P, flipped, 12), true, atol=1e-12)
    else:
        assert np.allclose(np.abs(np.einsum("nd,nd->n", N, ref)), 1.0, atol=1e-9)


def test_compiled_path_refuses_what_the_numpy_path_refuses(compiled):
    line = np.column_stack([np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)])
    with pytest.raises(FittingError, match="collinear"):
        estimate_normals(line, 8)
    huge = np.random.default_rng(1).uniform(-1, 1, (50, 3)) * 1e300
    with pytest.raises(ControlPointError, match="overflow"):
        estimate_normals(huge, 8)
    with pytest.raises(ControlPointError, match="overflow"):
        orient_normals(huge, np.ones_like(huge), 8)


def test_vectorized_eigen_solve_of_a_double_smallest_eigenvalue_stays_in_its_eigenspace():
    rng = np.random.default_rng(4)
    Q, _ = np.linalg.qr(rng.normal(size=(50, 3, 3)))
    C = np.einsum("mij,j,mkj->mik", Q, [0.5, 0.5, 2.0], Q)
    values, v = smallest_eigenpairs(np.concatenate([C, np.zeros((1, 3, 3))]))
    assert np.allclose(np.linalg.norm(v, axis=1), 1.0)
    assert np.abs(np.einsum("md,md->m", v[:-1], Q[:, :, 2])).max() < 1e-6
    assert np.allclose(values[:-1], [0.5, 0.5, 2.0], atol=1e-12)


def grid_search(kernels, P, k):
    """The grid pass alone: ``(grid, unsettled (n,) bool in original order, kth distance (n,))``."""
    grid = _pointtree._Grid(kernels, P, k, *kernels.bounds(P))
    n = len(P)
    unsettled = np.zeros(n, dtype=np.uint8)
    kth = np.full(n, np.nan)
    none = np.empty((0, k)), np.empty((0, k), dtype=np.int64)
    kernels.search(*grid.args(k), *none, kth, np.empty((0, 3)), np.empty((0, 3)), unsettled)
    return grid, unsettled[np.argsort(grid.order)].astype(bool), np.sqrt(kth)


def test_grid_settles_an_evenly_sampled_surface_itself(compiled):
    # the fast path must serve the clouds normals are estimated on: a torus sampled evenly
    P, _ = torus(20_000, seed=5)
    grid, unsettled, kth = grid_search(compiled, P, 16)
    assert grid.fits
    assert unsettled.mean() < 0.01
    ref, _ = cKDTree(P).query(P, 16)
    assert np.allclose(kth[~unsettled], ref[~unsettled, -1], rtol=1e-12, atol=0)


def test_grid_hands_what_it_cannot_settle_to_the_hierarchy(compiled):
    # a dense sheet and a sparse haze: the haze's neighbourhoods reach past two rings of cells
    P = cloud("mixed", 4000, np.random.default_rng(2))
    grid, unsettled, _ = grid_search(compiled, P, 10)
    assert grid.fits and 0 < unsettled.sum() < len(P) // 4
    assert unsettled[-500:].mean() > 0.5  # mostly the haze
    d, idx = _pointtree.compiled_knn(P, 10)
    ref, _ = cKDTree(P).query(P, 10)
    assert np.allclose(d, ref, rtol=1e-12, atol=1e-15)
    assert np.array_equal(idx[:, 0], np.arange(len(P)))


def test_a_grid_does_not_fit_a_blob_a_billion_times_smaller_than_the_cloud(compiled):
    # cells are at least a millionth of the extent: the blob falls into a single cell
    rng = np.random.default_rng(3)
    P = np.vstack([rng.normal(scale=1e-9, size=(3000, 3)), [[1e3, 0, 0], [-1e3, 0, 0]]])
    assert not _pointtree._Grid(compiled, P, 16, *compiled.bounds(P)).fits
    d, idx = _pointtree.compiled_knn(P, 16)  # the hierarchy serves it
    ref, _ = cKDTree(P).query(P, 16)
    assert np.allclose(d, ref, rtol=1e-12, atol=0)


def test_clusters_far_apart_are_served_by_the_grid(compiled):
    # empty space between clusters costs no cells: the cell side suits the clusters
    P = cloud("clusters", 3000, np.random.default_rng(3))
    grid, unsettled, kth = grid_search(compiled, P, 16)
    assert grid.fits and unsettled.mean() < 0.05
    ref, _ = cKDTree(P).query(P, 16)
    assert np.allclose(kth[~unsettled], ref[~unsettled, -1], rtol=1e-12, atol=0)
