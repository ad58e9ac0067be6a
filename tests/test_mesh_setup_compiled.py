"""The compiled set-up of MeshDistance's grid searches (splinekit/pointcloud/_meshsetup.py and
its kernels) against the numpy builders it replaces: the hierarchy, planes, prisms,
pseudo-normals in the hierarchy's order and the region scan's connectivity must be the same
arrays bit for bit, on fixed meshes and on closed meshes hypothesis shuffles, jitters and
collapses; a mesh that is not closed and consistently oriented falls back to the numpy builders
(open and non-manifold meshes keep their NotManifoldError)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_sdf_grid import star_mesh

from splinekit import limits
from splinekit.errors import NotManifoldError, ResourceLimitError
from splinekit.mesh import primitives
from splinekit.mesh.geometry import triangulate
from splinekit.pointcloud import _gridscan, _meshsetup
from splinekit.pointcloud.meshdistance import MeshDistance

pytest.importorskip("numba")


def arrays(V, T, numba, monkeypatch):
    """Everything the grid searches read, built with compiled code on (``numba`` "1") or off ("0")."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", numba)
    d = MeshDistance(V, T)
    b = d.bvh
    out = {"order": b.order, "tri": b.tri, "tlo": b.tlo, "thi": b.thi, "lo": b.lo, "hi": b.hi}
    out["plane"], out["ball"] = d._bvh_planes
    out["prism"] = d._bvh_prisms
    out["fn"], out["en"], out["vn"] = d._bvh_normals
    for name, a in zip(("V", "T", "ea", "eb", "eh", "ptr", "nbr", "vown"), _gridscan.adjacency(d)):
        out["adj " + name] = a
    return d, out


def assert_same(V, T, monkeypatch, compiled_normals=True):
    d0, numpy_arrays = arrays(V, T, "0", monkeypatch)
    assert "_grid_arrays" not in d0.__dict__ or d0._grid_arrays is None
    d1, compiled = arrays(V, T, "1", monkeypatch)
    assert d1._grid_arrays is not None
    assert (d1._grid_arrays.normals is not None) == compiled_normals
    for name, a in numpy_arrays.items():
        b = compiled[name]
        assert a.shape == b.shape and a.dtype == b.dtype, name
        assert np.array_equal(np.ascontiguousarray(a).view(np.uint8), np.ascontiguousarray(b).view(np.uint8)), name


def tris(mesh):
    return np.asarray(mesh.vertices, dtype=float), np.asarray(triangulate(mesh)[0], dtype=np.int64)


def lumpy(level):
    V, T = tris(primitives.icosphere(level))
    th, ph = np.arctan2(V[:, 1], V[:, 0]), np.arccos(np.clip(V[:, 2], -1, 1))
    return V * (1 + 0.3 * np.sin(3 * th) * np.sin(ph) ** 2 + 0.15 * np.cos(5 * ph))[:, None], T


def octahedron():
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    return V, np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])


def tetrahedron(offset=(0.0, 0.0, 0.0), first=0):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) + offset
    return V, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]) + first


@pytest.mark.parametrize("make", [lambda: lumpy(3), octahedron, tetrahedron, lambda: tris(star_mesh()),
                                  lambda: tris(primitives.torus(24, 12)), lambda: tris(primitives.box(2.0))],
                         ids=["lumpy sphere", "octahedron", "tetrahedron", "star", "torus", "quad box"])
def test_compiled_setup_equals_the_numpy_builders(make, monkeypatch):
    V, T = make()
    assert_same(V, T, monkeypatch)


def test_unused_vertices_and_two_solids_touching_at_a_vertex(monkeypatch):
    # vertex 0 of the second tetrahedron is vertex 3 of the first: a non-manifold vertex, yet
    # every edge has two triangles, one each way; two unused vertices in between
    V1, T1 = tetrahedron()
    V2, T2 = tetrahedron(offset=(0.0, 0.0, 1.0), first=6)
    V = np.concatenate([V1, [[5.0, 5, 5], [6.0, 6, 6]], V2])
    T = np.concatenate([T1, np.where(T2 == 6, 3, T2)])
    assert_same(V, T, monkeypatch)


def test_inconsistently_oriented_mesh_falls_back_to_the_numpy_builders(monkeypatch):
    V, T = octahedron()
    T = T.copy()
    T[0] = T[0, ::-1]  # every edge keeps two triangles, but three now run the same way
    assert_same(V, T, monkeypatch, compiled_normals=False)


def test_open_and_non_manifold_meshes_keep_their_error(monkeypatch):
    V, T = octahedron()
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    with pytest.raises(NotManifoldError, match="not closed"):
        MeshDistance(V, T[1:])._bvh_normals
    # two tetrahedra sharing an edge: four triangles on it
    V1, T1 = tetrahedron()
    V = np.concatenate([V1, [[1.0, 1.0, -1.0], [0.2, 0.2, -1.0]]])
    T2 = np.array([[0, 1, 4], [1, 5, 4], [0, 4, 5], [0, 5, 1]])
    d = MeshDistance(V, np.concatenate([T1, T2]))
    assert d._grid_arrays.normals is None
    with pytest.raises(NotManifoldError, match="4 triangles"):
        d._bvh_normals


def test_a_degenerate_triangle_falls_back(monkeypatch):
    V, T = octahedron()
    T = np.concatenate([T, [[0, 0, 1]]])
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    d = MeshDistance(V, T)
    assert d._grid_arrays.normals is None and d._grid_arrays.adjacency is None


@pytest.mark.parametrize("extra", [0, 1])
def test_a_vertex_of_many_triangles_falls_back(extra, monkeypatch):
    # a closed cone: apex and base centre each in as many triangles as the compiled twin search takes, and one more
    n = _meshsetup.MAX_VALENCE + extra
    a = 2 * np.pi * np.arange(n) / n
    V = np.concatenate([np.column_stack([np.cos(a), np.sin(a), np.zeros(n)]), [[0, 0, 1.0], [0, 0, 0]]])
    i, j = np.arange(n), (np.arange(n) + 1) % n
    T = np.concatenate([np.column_stack([i, j, np.full(n, n)]), np.column_stack([j, i, np.full(n, n + 1)])])
    assert_same(V, T, monkeypatch, compiled_normals=not extra)


def test_the_setup_is_checked_against_the_memory_budget(monkeypatch):
    V, T = lumpy(2)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    need = _meshsetup.SETUP_BYTES * len(T)
    with limits.budget(need - 1), pytest.raises(ResourceLimitError, match="grid set-up"):
        MeshDistance(V, T)._grid_arrays
    with limits.budget(need):
        assert MeshDistance(V, T)._grid_arrays.normals is not None


@settings(max_examples=40, deadline=None)
@given(level=st.integers(0, 2), seed=st.integers(0, 2**32 - 1), jitter=st.sampled_from([0.0, 1e-9, 0.2]),
       collapse=st.integers(0, 3), scale=st.sampled_from([1e-6, 1.0, 3e5]), unused=st.integers(0, 3))
def test_shuffled_jittered_and_collapsed_meshes(level, seed, jitter, collapse, scale, unused):
    """Vertices and triangles in random order, each triangle's corners rotated (orientation
    kept), coordinates jittered, some vertices moved onto a neighbour (zero-area and thin
    triangles), unused vertices mixed in."""
    rng = np.random.default_rng(seed)
    V, T = tris(primitives.icosphere(level))
    V = V + jitter * rng.standard_normal(V.shape)
    for _ in range(collapse):
        t = rng.integers(len(T))
        V[T[t, 0]] = V[T[t, 1]]
    V = np.concatenate([V, rng.standard_normal((unused, 3))]) * scale
    perm = rng.permutation(len(V))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(V))
    V, T = V[perm], inv[T]
    T = T[rng.permutation(len(T))]
    shift = rng.integers(0, 3, len(T))
    T = np.stack([T[np.arange(len(T)), (shift + k) % 3] for k in range(3)], axis=1)
    with pytest.MonkeyPatch.context() as mp:
        assert_same(V, T, mp)
