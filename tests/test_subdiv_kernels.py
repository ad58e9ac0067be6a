"""The compiled Catmull-Clark and Loop kernels (splinekit.subdiv._kernels) against the numpy path.

The numpy/scipy construction (``catmull_clark.refine_numpy``, ``loop.refine_numpy``) is the
reference. With ``_kernels.MIN_WORK`` lowered to 0 every level goes through the kernels; with
``SPLINEKIT_NUMBA=0`` none does. Compared per level: the stencil matrix (same sparsity once
explicit zeros are dropped, values within 1e-15), the child connectivity and edge tables (equal),
the crease data (equal); and at the end the refined vertices.

Meshes: random patches with boundaries (faces deleted at random, which also leaves vertices with
two separate fans), mixed polygons (triangles, quads, hexagons) for Catmull-Clark, creases of
sharpness inf / 2 / 1.5 / 1 / 0.5, corners, both boundary modes, isolated vertices, a high-valence
fan (rows longer than the insertion-sort limit) and "pillows" (two faces sharing every edge, so
columns repeat within a row).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from splinekit import PolyMesh, Refinement, subdivide, subdivision_matrix
from splinekit import _kernels
from splinekit.errors import ParameterError
from splinekit.mesh import Topology
from splinekit.mesh.primitives import box, icosphere, torus
from splinekit.subdiv import catmull_clark, loop
from splinekit.subdiv.creases import edge_sharpness, vertex_sharpness

pytest.importorskip("numba")

SHARPNESS = np.array([np.inf, 2.0, 1.5, 1.0, 0.5])


@pytest.fixture
def compiled(monkeypatch):
    """Every refinement level through the kernels (LOAD_WORK = 0 too: without it the kernels
    were loaded only once earlier tests had served enough work, so a test run alone failed)."""
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)


@pytest.fixture
def numpy_only(monkeypatch):
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")


# ---------------------------------------------------------------------------------------------
# meshes
# ---------------------------------------------------------------------------------------------
def _grid_vertices(nx, ny, rng):
    i, j = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), indexing="ij")
    z = 0.2 * rng.standard_normal(i.shape)
    return np.column_stack([i.ravel(), j.ravel(), z.ravel()]).astype(float)


def mixed_patch(seed, nx=6, ny=5, drop=0.15, isolated=2):
    """Quads of a bumpy grid, some split into triangles, some pairs merged into hexagons, some
    deleted; plus isolated vertices."""
    rng = np.random.default_rng(seed)
    X = _grid_vertices(nx, ny, rng)

    def v(i, j):
        return i * (ny + 1) + j

    faces, used = [], set()
    for i in range(nx):
        for j in range(ny):
            if (i, j) in used:
                continue
            u = rng.uniform()
            if u < 0.2 and i + 1 < nx and (i + 1, j) not in used:
                used.add((i + 1, j))
                faces.append([v(i, j), v(i + 1, j), v(i + 2, j), v(i + 2, j + 1), v(i + 1, j + 1), v(i, j + 1)])
            elif u < 0.45:
                faces.append([v(i, j), v(i + 1, j), v(i + 1, j + 1)])
                faces.append([v(i, j), v(i + 1, j + 1), v(i, j + 1)])
            else:
                faces.append([v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)])
    keep = rng.uniform(size=len(faces)) >= drop
    keep[0] = True
    faces = [f for f, k in zip(faces, keep) if k]
    X = np.vstack([X, rng.standard_normal((isolated, 3))])
    return PolyMesh(X, faces)


def tri_patch(seed, n=6, drop=0.15, isolated=1):
    rng = np.random.default_rng(seed)
    X = _grid_vertices(n, n, rng)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + n + 1, a + n + 2, a + 1
    F = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    keep = rng.uniform(size=len(F)) >= drop
    keep[0] = True
    X = np.vstack([X, rng.standard_normal((isolated, 3))])
    return PolyMesh(X, F[keep])


def fan(n, closed, quads=False):
    """A cone (``closed``: capped by a second apex) with ``n`` sectors around apex 0."""
    t = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(t), np.sin(t), 0.1 * np.sin(3 * t)])
    X = np.vstack([[0.0, 0.0, 1.0], ring, [0.0, 0.0, -1.0]])
    r = 1 + np.arange(n)
    r1 = 1 + (np.arange(n) + 1) % n
    if quads:
        # quads (apex, r, mid, r1) would need mid points: use pentagon-free quads via a second ring
        X = np.vstack([X, 0.5 * ring + [0, 0, 0.5]])
        m = n + 2 + np.arange(n)
        m1 = n + 2 + (np.arange(n) + 1) % n
        F = [np.column_stack([np.zeros(n, int), m, m1]), np.column_stack([m, r, r1, m1])]
    else:
        F = [np.column_stack([np.zeros(n, int), r, r1])]
    if closed:
        F.append(np.column_stack([np.full(n, n + 1), r1, r]))
    faces = [f for block in F for f in block.tolist()]
    return PolyMesh(X, faces)


def pillow(k):
    """Two ``k``-gons glued along every edge (a closed disk pair)."""
    t = 2 * np.pi * np.arange(k) / k
    X = np.column_stack([np.cos(t), np.sin(t), 0.1 * np.cos(2 * t)])
    return PolyMesh(X, [list(range(k)), list(range(k))[::-1]])


def random_creases(mesh, seed, fraction=0.3):
    rng = np.random.default_rng(seed)
    t = mesh.topology
    pick = np.flatnonzero(rng.uniform(size=t.n_edges) < fraction)
    s = rng.choice(SHARPNESS, size=pick.size)
    creases = {tuple(int(x) for x in t.edges[e]): float(v) for e, v in zip(pick, s)}
    corners = {int(c): float(rng.choice([np.inf, 1.5, 0.5])) for c in rng.choice(t.n_vertices, 2, replace=False)}
    return creases, corners


CC_MESHES = {
    "mixed-0": lambda: mixed_patch(0),
    "mixed-1": lambda: mixed_patch(1, drop=0.3),
    "mixed-2": lambda: mixed_patch(2, drop=0.0, isolated=0),
    "box": box,
    "torus": lambda: torus(6, 5, 2.0, 0.7),
    "tri-patch": lambda: tri_patch(3),
    "fan-40": lambda: fan(40, closed=True),
    "fan-quads-37": lambda: fan(37, closed=False, quads=True),
    "pillow-4": lambda: pillow(4),
    "pillow-5": lambda: pillow(5),
}
LOOP_MESHES = {
    "tri-patch-0": lambda: tri_patch(0),
    "tri-patch-1": lambda: tri_patch(1, drop=0.3, isolated=3),
    "icosphere": lambda: icosphere(1),
    "fan-40": lambda: fan(40, closed=True),
    "fan-open-35": lambda: fan(35, closed=False),
    "pillow-3": lambda: pillow(3),
}
CASES = [("catmull-clark", name) for name in CC_MESHES] + [("loop", name) for name in LOOP_MESHES]
OPTIONS = [
    dict(),
    dict(boundary="edge-only"),
    dict(crease_seed=5),
    dict(crease_seed=6, boundary="edge-only"),
]


def make(scheme, name):
    return (CC_MESHES if scheme == "catmull-clark" else LOOP_MESHES)[name]()


def options(mesh, opts):
    out = {"boundary": opts.get("boundary", "edge-and-corner")}
    if "crease_seed" in opts:
        out["creases"], out["corners"] = random_creases(mesh, opts["crease_seed"])
    return out


# ---------------------------------------------------------------------------------------------
# comparisons
# ---------------------------------------------------------------------------------------------
def canonical(S):
    S = sp.csr_matrix(S, copy=True)
    S.eliminate_zeros()
    S.sort_indices()
    return S


def assert_same_stencil(ref, fast):
    assert fast.shape == ref.shape
    assert fast.format == "csr"
    A, B = canonical(ref), canonical(fast)
    assert B.nnz == fast.nnz, "the compiled stencil stores explicit zeros"
    np.testing.assert_array_equal(np.diff(fast.indptr), np.diff(B.indptr))
    np.testing.assert_array_equal(fast.indices, B.indices)  # already sorted
    np.testing.assert_array_equal(A.indptr, B.indptr)
    np.testing.assert_array_equal(A.indices, B.indices)
    assert np.abs(A.data - B.data).max(initial=0.0) <= 1e-15


def assert_same_topology(a: Topology, b: Topology):
    assert a.n_vertices == b.n_vertices
    np.testing.assert_array_equal(a.face_indices, b.face_indices)
    np.testing.assert_array_equal(a.face_offsets, b.face_offsets)
    np.testing.assert_array_equal(a.edges, b.edges)
    np.testing.assert_array_equal(a.halfedge_edge, b.halfedge_edge)
    np.testing.assert_array_equal(a.edge_halfedges, b.edge_halfedges)
    assert b.edges.dtype == b.halfedge_edge.dtype == b.edge_halfedges.dtype == np.int64


def check_topology(t: Topology):
    """The refined edge tables agree with a validated rebuild from the faces."""
    f = Topology(t.n_vertices, t.face_indices, t.face_offsets, check=True)
    assert {tuple(e) for e in t.edges.tolist()} == {tuple(e) for e in f.edges.tolist()}
    assert len(t.edges) == len(f.edges)
    src, dst = t.face_indices, t.halfedge_dst
    np.testing.assert_array_equal(t.edges[t.halfedge_edge], np.column_stack([np.minimum(src, dst), np.maximum(src, dst)]))
    np.testing.assert_array_equal(t.twin, f.twin)
    np.testing.assert_array_equal(t.valence, f.valence)


# ---------------------------------------------------------------------------------------------
# one level, refine() against refine_numpy()
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scheme,name", CASES)
@pytest.mark.parametrize("opts", OPTIONS, ids=["plain", "edge-only", "creases", "creases-edge-only"])
def test_one_level_matches_numpy(scheme, name, opts, compiled):
    mesh = make(scheme, name)
    module = catmull_clark if scheme == "catmull-clark" else loop
    kw = options(mesh, opts)
    t = mesh.topology
    edge_s = edge_sharpness(t, kw.get("creases"))
    vertex_s = vertex_sharpness(t, kw.get("corners"), kw["boundary"])
    ref = module.refine_numpy(t, edge_s, vertex_s)
    fast = module.refine(t, edge_s, vertex_s)  # dispatches to the kernels (MIN_WORK = 0)
    assert "_uniform_size" in fast[0].__dict__, "the kernel path was not taken"
    assert_same_stencil(ref[1], fast[1])
    assert_same_topology(ref[0], fast[0])
    for a, b in zip(ref[2:], fast[2:]):
        np.testing.assert_array_equal(a, b)


# ---------------------------------------------------------------------------------------------
# several levels: Refinement with and without the kernels
# ---------------------------------------------------------------------------------------------
def both_paths(monkeypatch, make_refinement):
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    ref = make_refinement()
    monkeypatch.delenv("SPLINEKIT_NUMBA")
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    fast = make_refinement()
    return ref, fast


def test_a_large_job_refines_its_small_first_levels_with_the_kernels(monkeypatch):
    """The job's size (its finest level) decides the path once, at the default thresholds: the
    first levels of icosphere -> level 5 (80 ... 20,480 faces, below MIN_WORK until the last)
    take the kernels too, and the result equals the numpy path's (same topology, stencils to rounding)."""
    mesh = icosphere(0)
    levels = 5
    assert 20 * 4 ** (levels - 1) < _kernels.MIN_WORK <= 20 * 4**levels
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    ref = Refinement(mesh, "loop", levels)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    fast = Refinement(mesh, "loop", levels)
    assert all("_uniform_size" in lv.topology.__dict__ for lv in fast.hierarchy[1:]), "a level took the numpy rules"
    for a, b in zip(ref.hierarchy[1:], fast.hierarchy[1:]):
        assert_same_topology(a.topology, b.topology)
        assert_same_stencil(a.stencil, b.stencil)
    np.testing.assert_allclose(fast.apply(mesh.vertices), ref.apply(mesh.vertices), rtol=0, atol=1e-14)
    small = Refinement(mesh, "loop", 2)  # a small job stays on the numpy rules
    assert not any("_uniform_size" in lv.topology.__dict__ for lv in small.hierarchy[1:])


@pytest.mark.parametrize("scheme,name", CASES)
@pytest.mark.parametrize("opts", OPTIONS, ids=["plain", "edge-only", "creases", "creases-edge-only"])
def test_refinement_matches_numpy(scheme, name, opts, monkeypatch):
    mesh = make(scheme, name)
    kw = options(mesh, opts)
    levels = 3
    ref, fast = both_paths(monkeypatch, lambda: Refinement(mesh, scheme, levels, **kw))
    assert fast.levels == ref.levels == levels
    for k in range(levels):
        assert_same_stencil(ref.stencils[k], fast.stencils[k])
    for k in range(levels + 1):
        assert_same_topology(ref.topologies[k], fast.topologies[k])
        np.testing.assert_array_equal(ref.edge_sharpness[k], fast.edge_sharpness[k])
        np.testing.assert_array_equal(ref.vertex_sharpness[k], fast.vertex_sharpness[k])
    if not name.startswith("pillow"):  # a refined triangle pillow has edges in four faces
        check_topology(fast.topology)
    X = mesh.vertices
    scale = np.abs(X).max()
    np.testing.assert_allclose(fast.apply(X), ref.apply(X), rtol=0, atol=1e-13 * scale)


@pytest.mark.parametrize("scheme,name", CASES)
@pytest.mark.parametrize("opts", OPTIONS[::3], ids=["plain", "creases-edge-only"])
def test_subdivide_unchanged(scheme, name, opts, monkeypatch):
    """subdivide (kernels, vertices refined level by level without storing S) equals the numpy
    path to rounding, and exactly the compiled stencils applied in turn."""
    mesh = make(scheme, name)
    kw = options(mesh, opts)
    levels = 3
    ref, fast = both_paths(monkeypatch, lambda: subdivide(mesh, scheme, levels, **kw))
    np.testing.assert_array_equal(fast.face_indices, ref.face_indices)
    np.testing.assert_array_equal(fast.face_offsets, ref.face_offsets)
    assert_same_topology(ref.topology, fast.topology)  # the finest edges, built on first use
    scale = np.abs(mesh.vertices).max()
    np.testing.assert_allclose(fast.vertices, ref.vertices, rtol=0, atol=1e-13 * scale)
    r = Refinement(mesh, scheme, levels, **kw)  # still compiled (monkeypatched)
    np.testing.assert_array_equal(fast.vertices, r.apply(mesh.vertices))
    assert not fast.vertices.flags.writeable


def test_large_mesh_uses_kernels_by_default(monkeypatch):
    """Above _kernels.MIN_WORK the kernels serve without any setting; results as the numpy path."""
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
    mesh = PolyMesh(torus(60, 40, 2.0, 0.7).vertices + 0.01, torus(60, 40, 2.0, 0.7).faces)
    assert catmull_clark.SCHEME.child_faces(mesh.topology) < _kernels.MIN_WORK
    fast = subdivide(mesh, "catmull-clark", 2)  # level 2 has 38,400 faces: compiled
    t_fast, S_fast = subdivision_matrix(mesh, "catmull-clark", 2)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    ref = subdivide(mesh, "catmull-clark", 2)
    t_ref, S_ref = subdivision_matrix(mesh, "catmull-clark", 2)
    np.testing.assert_array_equal(fast.face_indices, ref.face_indices)
    np.testing.assert_allclose(fast.vertices, ref.vertices, rtol=0, atol=1e-13)
    assert_same_topology(t_ref, t_fast)
    assert abs(S_fast - S_ref).max() < 1e-14


# ---------------------------------------------------------------------------------------------
# keep_levels, dispatch
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kernels", [False, True])
def test_keep_levels_false(kernels, monkeypatch):
    if kernels:
        monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    mesh = mixed_patch(4)
    full = Refinement(mesh, "catmull-clark", 3)
    lean = Refinement(mesh, "catmull-clark", 3, keep_levels=False)
    assert lean.levels == 3 and not lean.keep_levels and full.keep_levels
    assert len(lean.topologies) == 2 and lean.topologies[0] is mesh.topology and lean.stencils == []
    assert_same_topology(full.topology, lean.topology)
    np.testing.assert_array_equal(full.edge_sharpness[-1], lean.edge_sharpness[-1])
    np.testing.assert_array_equal(full.vertex_sharpness[-1], lean.vertex_sharpness[-1])
    np.testing.assert_array_equal(lean.vertices, full.apply(mesh.vertices))
    assert full.vertices is None
    with pytest.raises(ParameterError, match="keep_levels"):
        lean.apply(mesh.vertices)
    with pytest.raises(ParameterError, match="keep_levels"):
        lean.matrix
    topo_only = Refinement(mesh.topology, "catmull-clark", 2, keep_levels=False)
    assert topo_only.vertices is None and topo_only.topology.n_faces == 4 * mesh.topology.n_halfedges


def test_numpy_switch(monkeypatch):
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    assert catmull_clark.SCHEME.kernels(box().topology) is None
    t = box().topology
    child = catmull_clark.refine(t, edge_sharpness(t, None), vertex_sharpness(t, None, "edge-and-corner"))[0]
    assert "_uniform_size" not in child.__dict__  # the numpy path built it
    monkeypatch.delenv("SPLINEKIT_NUMBA")
    assert catmull_clark.SCHEME.kernels(t) is not None
    monkeypatch.setattr(_kernels, "MIN_WORK", 25)
    assert catmull_clark.SCHEME.kernels(t) is None  # 24 child faces



def test_small_subdivision_does_not_import_numba():
    code = (
        "import sys, splinekit as sk\n"
        "from splinekit.mesh.primitives import box, icosphere\n"
        "sk.subdivide(box(), 'catmull-clark', 3); sk.subdivide(icosphere(1), 'loop', 2)\n"
        "print('numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_lazy_edge_tables_match_eager(compiled):
    """The finest level defers its edge tables; built later they equal the eager ones."""
    mesh = mixed_patch(7)
    creases, corners = random_creases(mesh, 8)
    lean = Refinement(mesh, "catmull-clark", 2, creases=creases, corners=corners, keep_levels=False).topology
    assert "_edge_table" not in lean.__dict__
    full = Refinement(mesh, "catmull-clark", 3, creases=creases, corners=corners)
    assert "_edge_table" in full.topologies[2].__dict__ and "_edge_table" not in full.topologies[3].__dict__
    h0, h1 = lean._edge_halfedge_pairs  # either table triggers the build
    assert "_edge_table" in lean.__dict__
    assert_same_topology(full.topologies[2], lean)
    check_topology(lean)
