"""The region scan of MeshDistance.grid_signed (splinekit/pointcloud/_gridsdf_scan.py) against
brute force: every sample's distance over all (sample, triangle) pairs and its sign by the
generalized winding number (test_sdf_grid), on meshes with sharp, flat and spiky features and
samples on faces, edges and vertices; and the same checks failing when a kind of region is
dropped or the cuts are shortened, so that they test what the argument needs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from _compiled import compiled_or_skip
from test_sdf_grid import brute_distance, star_mesh, winding_number

from splinekit import _kernels, limits
from splinekit.errors import ResourceLimitError
from splinekit.mesh import primitives
from splinekit.mesh.geometry import triangulate
from splinekit.pointcloud import _gridscan
from splinekit.pointcloud.meshdistance import MeshDistance

pytest.importorskip("numba")


@pytest.fixture(scope="module")
def kern():
    return compiled_or_skip(_gridscan.SCAN_KERNELS)


def grid_points(origin, step, shape):
    step = np.broadcast_to(np.asarray(step, dtype=float), (3,))
    axes = [origin[k] + step[k] * np.arange(shape[k]) for k in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def scanned(kern, V, T, origin, step, shape, limit=np.inf, tamper=None):
    """The scan's signed distances (model units, flat) on the grid; ``tamper(mesh, R, kind,
    box)`` may change the regions first."""
    dist = MeshDistance(V, T)
    o = (np.asarray(origin, dtype=float) - dist._shift) / dist._scale
    h = np.broadcast_to(np.asarray(step, dtype=float), (3,)) / dist._scale
    reg = _gridscan.regions(dist, kern, o, h, shape, limit / dist._scale**2)
    assert reg is not None  # no triangle too thin for a plane here
    if tamper is not None:
        tamper(*reg)
    return _gridscan.scan(dist, kern, reg, o, h, shape, limit / dist._scale**2) * dist._scale


def references(V, T, P):
    """Brute-force distances and winding numbers at the points ``P``."""
    exact = np.concatenate([brute_distance(P[s : s + 2000], V, T) for s in range(0, len(P), 2000)])
    w = np.concatenate([winding_number(P[s : s + 2000], V, T) for s in range(0, len(P), 2000)])
    return exact, w


def mismatches(V, T, P, d, refs=None):
    """Samples whose distance differs from brute force (beyond 1e-12 of the mesh's size) or,
    clear of the surface, whose sign differs from the winding number's (``refs``: the
    :func:`references`, when already known)."""
    exact, w = references(V, T, P) if refs is None else refs
    scale = np.abs(V).max()
    wrong = ~(np.abs(np.abs(d) - exact) <= 1e-12 * scale)
    clear = exact > 1e-9 * scale
    wrong |= clear & ((d < 0) != (w > 0.5))
    return int(wrong.sum())


def octahedron():
    V = 2.0 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    T = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return V, T


def sharp_tetrahedron():
    # a nearly flat tetrahedron: knife edges (dihedral angles of about 1 degree), whose wedges
    # and cones open to nearly a half-space
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, 0.01]])
    T = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    return V, T


def of(mesh):
    return np.asarray(mesh.vertices, dtype=float), np.asarray(triangulate(mesh)[0])


CASES = {
    "octahedron on its features": (octahedron, np.full(3, -3.0), 0.25),
    "knife-edged tetrahedron": (sharp_tetrahedron, np.array([-0.4, -0.4, -0.5]), 0.09),
    # coplanar triangles: flat edges and vertices, whose regions lie in the prisms
    "box": (lambda: of(primitives.box(2.0)), np.full(3, -1.6), 0.16),
    "torus": (lambda: of(primitives.torus(24, 12, 1.0, 0.3)), np.array([-1.5, -1.5, -0.6]), 0.12),
    "star": (lambda: of(star_mesh()), np.full(3, -1.9), 0.17),
    "star, steps unequal": (lambda: of(star_mesh()), np.array([-1.9, -1.6, -2.4]), np.array([0.17, 0.13, 0.2])),
}


@pytest.mark.parametrize("name", list(CASES))
def test_scan_against_brute_force(kern, name):
    make, origin, step = CASES[name]
    V, T = make()
    shape = (25, 25, 25) if name != "torus" else (26, 26, 11)
    d = scanned(kern, V, T, origin, step, shape)
    P = grid_points(origin, step, shape)
    assert mismatches(V, T, P, d) == 0
    assert (d > 0).any() and ((d < 0).any() or name == "knife-edged tetrahedron")  # 0.01 thick


def test_knife_edges_get_regions_spanning_the_grid(kern):
    V, T = sharp_tetrahedron()
    dist = MeshDistance(V, T)
    o = (np.array([-0.4, -0.4, -0.5]) - dist._shift) / dist._scale
    _, R, kind, box = _gridscan.regions(dist, kern, o, np.full(3, 0.09) / dist._scale, (25, 25, 25), np.inf)
    wide = kind == 2
    assert 0 < wide.sum() <= _gridscan.WIDE_REGIONS  # so the scan serves it
    assert (box[wide, :3] == 0).all() and (box[wide, 3:] == 25).all()


def test_many_knife_edges_go_to_the_block_kernel(kern, monkeypatch):
    V, T = sharp_tetrahedron()
    dist = MeshDistance(V, T)
    args = (kern, np.zeros(3), np.full(3, 0.05), (9, 9, 9), np.inf)
    assert _gridscan.scan_grid(dist, *args) is not None
    monkeypatch.setattr(_gridscan, "WIDE_REGIONS", 0)
    assert _gridscan.scan_grid(dist, *args) is None


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), level=st.sampled_from([1, 2]), spread=st.sampled_from([0.3, 0.7, 0.95]))
def test_spiky_meshes_against_brute_force(kern, seed, level, spread):
    # a random radius per vertex: spikes and pits side by side, saddle vertices, regions that
    # cross the medial axis and must be cut by the coarse bound, grids off the mesh's centre
    rng = np.random.default_rng(seed)
    m = primitives.icosphere(level)
    V = np.asarray(m.vertices) * rng.uniform(1 - spread, 1 + spread, (len(m.vertices), 1))
    T = np.asarray(triangulate(m)[0])
    step = float(rng.uniform(0.05, 0.15))
    shape = tuple(int(n) for n in rng.integers(14, 26, 3))
    origin = -0.5 * step * (np.array(shape) - 1) + rng.uniform(-0.3, 0.3, 3)
    d = scanned(kern, V, T, origin, step, shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        assert mismatches(V, T, grid_points(origin, step, shape), d) == 0


def test_band_keeps_what_the_dense_grid_has_within_it(kern):
    V, T = of(star_mesh())
    origin, step, shape = np.full(3, -1.9), 0.17, (23, 24, 25)
    dense = scanned(kern, V, T, origin, step, shape)
    band = 2.5 * step
    nb = scanned(kern, V, T, origin, step, shape, limit=band**2)
    inside = np.abs(dense) <= band * (1 - 1e-9)
    assert np.array_equal(nb[inside], dense[inside])
    assert np.isinf(nb[np.abs(dense) > band * (1 + 1e-9)]).all()
    assert inside.mean() > 0.05


SPIKY_GRID = (np.full(3, -1.7), 0.16, (22, 22, 22))


@pytest.fixture(scope="module")
def spiky():
    """A spiky mesh, its grid's points and their references (computed once for the module)."""
    rng = np.random.default_rng(7)
    m = primitives.icosphere(2)
    V = np.asarray(m.vertices) * rng.uniform(0.4, 1.6, (len(m.vertices), 1))
    T = np.asarray(triangulate(m)[0])
    P = grid_points(*SPIKY_GRID)
    with np.errstate(divide="ignore", invalid="ignore"):
        return V, T, P, references(V, T, P)


def _drop(part):
    def tamper(mesh, R, kind, box):
        m, ne = len(mesh[1]), len(mesh[5])
        span = {"faces, outer side": slice(0, m), "faces, inner side": slice(m, 2 * m),
                "edges": slice(2 * m, 2 * m + ne), "vertices": slice(2 * m + ne, None)}[part]
        kind[span] = 0
    return tamper


def _shorten(mesh, R, kind, box):
    R[kind == 1] *= 0.6


@pytest.mark.parametrize("tamper", [_drop("faces, outer side"), _drop("faces, inner side"), _drop("edges"),
                                    _drop("vertices"), _shorten],
                         ids=["no outer prisms", "no inner prisms", "no wedges", "no cones", "cuts at 0.6"])
def test_each_kind_of_region_and_the_cut_length_are_needed(kern, spiky, tamper):
    # the brute-force check above would notice: with any kind of region left out, or the cuts
    # shortened, some sample loses its nearest feature
    V, T, P, refs = spiky
    assert mismatches(V, T, P, scanned(kern, V, T, *SPIKY_GRID), refs) == 0
    assert mismatches(V, T, P, scanned(kern, V, T, *SPIKY_GRID, tamper=tamper), refs) > 0


def test_the_cuts_shorten_regions_that_cross_the_inside(kern):
    # the inner prisms of a sphere meet at its centre: cut there, not at the grid's far side
    V, T = of(primitives.icosphere(2))
    dist = MeshDistance(V, T)
    shape = (30, 30, 30)
    o = (np.full(3, -1.5) - dist._shift) / dist._scale
    h = np.full(3, 0.1) / dist._scale
    mesh, R, kind, box = _gridscan.regions(dist, kern, o, h, shape, np.inf)
    m = len(T)
    inner = R[m : 2 * m] * dist._scale
    assert (kind[m : 2 * m] == 1).all()
    assert np.median(inner) < 1.6  # the radius plus a coarse cell's slack, not the grid's 3


def test_the_scans_work_arrays_are_checked_against_the_memory_budget(kern):
    dist = MeshDistance.of_mesh(star_mesh())
    dist._grid_arrays  # noqa: B018 -- the set-up before the scan has its own check (test_mesh_setup_compiled)
    shape = (20, 20, 20)
    n_regions = 2 * len(dist.tris) + 3 * len(dist.tris) // 2 + len(dist.unit_vertices)
    need = _gridscan.SAMPLE_BYTES * 8000 + _gridscan.REGION_BYTES * n_regions
    args = (dist, kern, np.full(3, -0.5), np.full(3, 0.05), shape, np.inf)
    with limits.budget(need - 1), pytest.raises(ResourceLimitError, match="region scan"):
        _gridscan.regions(*args)
    with limits.budget(need):
        assert _gridscan.regions(*args) is not None


def test_the_scan_gives_the_block_kernels_values_to_the_last_bit(kern, monkeypatch):
    # both measure the true nearest triangle with the same closest-point routine; an edge's two
    # triangles may round the distance to it 1 ulp apart, and the scan measures both
    from splinekit.pointcloud import meshdistance

    compiled_or_skip(meshdistance.GRID_KERNELS)
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    V, T = of(star_mesh())
    dist = MeshDistance(V, T)
    args = (np.array([-1.9, -1.8, -1.7]), np.full(3, 0.11), (35, 34, 33))
    scan = dist.grid_signed(*args)
    monkeypatch.setattr(meshdistance, "GRID_SCAN", False)
    block = dist.grid_signed(*args)
    assert np.array_equal(scan, block)
