"""The value types of subdivision (Level, RefinementStep), the per-scheme rules (Scheme), the
composition of stencils, and the subpackage's structure (no import circles, no in-function
project imports, modules under about 500 lines).

References are independent of the code under test: dense products of the stored stencils,
affine invariance (stencil rows sum to 1), closed-form face counts, Loop's beta formula, and the
child edges located by vertex pairs.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import splinekit as sk
from splinekit.mesh.geometry import triangulate
from splinekit.mesh.primitives import box, grid, icosphere, torus
from splinekit.subdiv import SCHEMES, Level, Refinement, RefinementStep, catmull_clark, doo_sabin, loop
from splinekit.subdiv.creases import edge_sharpness, vertex_sharpness



def _level(mesh, scheme, creases=None):
    t = mesh.topology
    return Level(t, edge_sharpness(t, creases), vertex_sharpness(t, None, "edge-and-corner"), scheme)


def _open_box():
    """A box without its top face: boundary edges and corners."""
    b = box()
    return sk.PolyMesh(b.vertices, b.faces[1:])


# -- Level, RefinementStep ----------------------------------------------------------------------
def test_level_is_frozen_and_its_sharpness_read_only():
    edge_s = np.zeros(box().topology.n_edges)
    lv = Level(box().topology, edge_s, np.zeros(8), "catmull-clark")
    with pytest.raises(dataclasses.FrozenInstanceError):
        lv.scheme = "loop"
    with pytest.raises(ValueError):
        lv.edge_sharpness[0] = 1.0
    edge_s[0] = 2.0  # the caller's array stays writable
    assert lv.stencil is None and lv.n_vertices == 8


@pytest.mark.parametrize("module,mesh", [(catmull_clark, _open_box()), (loop, icosphere(1)), (doo_sabin, _open_box())])
def test_refinement_step_unpacks_as_the_former_tuple(module, mesh):
    t = mesh.topology
    e = t.edges[np.flatnonzero(t.edge_halfedges[:, 1] >= 0)[0]]  # an interior edge
    creases = {(int(e[0]), int(e[1])): 2.5}
    lv = _level(mesh, module.NAME, creases)
    step = module.refine(t, lv.edge_sharpness, lv.vertex_sharpness)
    assert isinstance(step, RefinementStep) and len(step) == 5
    child, S, pairs, parent_s, child_vs = step
    assert child is step.topology is step.level.topology and S is step.stencil is step[1]
    assert pairs is step.crease_pairs and parent_s is step.crease_sharpness and child_vs is step.level.vertex_sharpness
    assert S.shape == (child.n_vertices, t.n_vertices)
    # the child edges named by the crease pairs carry the parent sharpness minus one, the
    # child's boundary edges are infinitely sharp, every other edge is smooth
    expected = np.zeros(child.n_edges)
    expected[child.find_edges(pairs)] = np.maximum(parent_s - 1.0, 0.0)
    expected[child.boundary_edges] = np.inf
    np.testing.assert_array_equal(step.level.edge_sharpness, expected)
    assert (step.level.edge_sharpness == 1.5).sum() == 2  # two child edges follow the crease


def test_hierarchy_holds_levels_with_their_stencils():
    r = Refinement(torus(6, 5, 2.0, 0.7), "catmull-clark", 3, creases=None)
    assert len(r.hierarchy) == 4 and r.hierarchy[0].stencil is None and r.finest is r.hierarchy[-1]
    for k in range(1, 4):
        lv = r.hierarchy[k]
        assert lv.scheme == "catmull-clark"
        assert lv.stencil.shape == (lv.n_vertices, r.hierarchy[k - 1].n_vertices)
        assert r.stencils[k - 1] is lv.stencil and r.topologies[k] is lv.topology
        np.testing.assert_allclose(np.asarray(lv.stencil.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-14)
    lean = Refinement(torus(6, 5, 2.0, 0.7), "catmull-clark", 3, keep_levels=False)
    assert len(lean.hierarchy) == 2 and lean.finest.stencil is None and lean.stencils == []


# -- the schemes' own rules -------------------------------------------------------------------------
def test_each_scheme_describes_itself():
    assert set(SCHEMES) == {"catmull-clark", "loop", "doo-sabin"}
    for name, rules in SCHEMES.items():
        assert rules.name == name
    assert SCHEMES["loop"].valence_weights is loop.loop_beta and SCHEMES["catmull-clark"].valence_weights is None
    assert SCHEMES["doo-sabin"].kernel is None and SCHEMES["doo-sabin"].limit_mask is None
    # Loop's beta: (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n; 3/16 at valence 3, 1/16 at valence 6
    np.testing.assert_allclose(loop.loop_beta(np.array([3, 6])), [3 / 16, 1 / 16], rtol=0, atol=1e-16)


@pytest.mark.parametrize("scheme,mesh", [("catmull-clark", box()), ("catmull-clark", _open_box()), ("loop", icosphere(1)),
                                         ("doo-sabin", box())])
def test_estimated_faces_is_the_face_count(scheme, mesh):
    """Exact for Catmull-Clark and Loop (F -> corners -> 4x per level; F -> 4F); for Doo-Sabin exact
    after one step of a closed mesh (F + E + V faces) and an upper bound after more (the memory
    budget is checked with it)."""
    rules = SCHEMES[scheme]
    for levels in range(4):
        estimate = rules.estimated_faces(mesh.topology, levels)
        actual = Refinement(mesh, scheme, levels).topology.n_faces
        if scheme == "doo-sabin" and levels > 1:
            assert actual <= estimate <= 1.1 * actual
        else:
            assert estimate == actual


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_smooth_limit_masks_reproduce_affine_functions(scheme):
    """Limit and tangent masks of the schemes: rows of the limit mask sum to 1, tangent rows to 0."""
    mesh = torus(8, 6, 2.0, 0.7) if scheme == "catmull-clark" else icosphere(2)
    t = mesh.topology
    L = SCHEMES[scheme].limit_mask(t)
    np.testing.assert_allclose(np.asarray(L.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-14)
    for k in (2, 3, 5):
        A = SCHEMES[scheme].sector_matrix(k)
        np.testing.assert_allclose(A.sum(axis=1), 1.0, rtol=0, atol=1e-15)


# -- composition -------------------------------------------------------------------------------------
@pytest.mark.parametrize("scheme,mesh", [("catmull-clark", _open_box()), ("loop", icosphere(0)), ("doo-sabin", box())])
def test_composed_matrix_is_the_product_of_the_stencils(scheme, mesh):
    r = Refinement(mesh, scheme, 3)
    dense = np.eye(mesh.n_vertices)
    for S in r.stencils:
        dense = S.toarray() @ dense
    M = r.matrix
    assert M.format == "csr" and M.shape == dense.shape
    np.testing.assert_allclose(M.toarray(), dense, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.asarray(M.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(r.apply(mesh.vertices, composed=True), r.apply(mesh.vertices), rtol=0, atol=1e-14)
    assert Refinement(mesh, scheme, 0).matrix.shape == (mesh.n_vertices, mesh.n_vertices)


def test_regular_faces_keeps_its_former_signature():
    from splinekit.subdiv.surface import regular_faces

    lv = _level(torus(6, 5, 2.0, 0.7), "catmull-clark")
    with pytest.warns(DeprecationWarning):
        old = regular_faces(lv.topology, lv.edge_sharpness, lv.vertex_sharpness)
    np.testing.assert_array_equal(old, regular_faces(lv))
    assert old.all()  # a torus of quads with valence-4 vertices only


def _grid_case(scheme, nx, ny, seed):
    """An open grid (boundary) in the scheme's face type, bumped, with random semi-sharp creases
    (sharpness 0.5 - 3.5: they decay over the levels) and one corner."""
    rng = np.random.default_rng(seed)
    mesh = grid(nx, ny)
    if scheme == "loop":
        mesh = sk.PolyMesh(mesh.vertices, triangulate(mesh)[0])
    V = mesh.vertices + rng.normal(scale=0.05, size=mesh.vertices.shape)
    mesh = mesh.with_vertices(V)
    edges = mesh.topology.edges
    pick = rng.choice(len(edges), size=max(1, len(edges) // 5), replace=False)
    creases = {(int(a), int(b)): float(s) for (a, b), s in zip(edges[pick], rng.uniform(0.5, 3.5, pick.size))}
    corners = {int(rng.integers(mesh.n_vertices)): float("inf")}
    return mesh, creases, corners


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop", "doo-sabin"])
@pytest.mark.parametrize("seed", [0, 1])
def test_composed_matrix_with_boundaries_and_creases_matches_level_by_level_refinement(scheme, seed):
    """``Refinement.matrix`` (composed stencils) against two references that never compose:
    ``subdivide`` (vertices refined level by level, compiled kernels where they exist, no stencil
    kept) and the dense product of the level stencils."""
    mesh, creases, corners = _grid_case(scheme, 5, 4, seed)
    for levels in (1, 2, 3):
        r = Refinement(mesh, scheme, levels, creases=creases, corners=corners)
        M = r.matrix
        assert M.format == "csr" and M.shape == (r.topology.n_vertices, mesh.n_vertices)
        fine = sk.subdivide(mesh, scheme, levels, creases=creases, corners=corners)
        np.testing.assert_allclose(M @ mesh.vertices, fine.vertices, rtol=0, atol=1e-13)
        dense = np.eye(mesh.n_vertices)
        for S in r.stencils:
            dense = S.toarray() @ dense
        np.testing.assert_allclose(M.toarray(), dense, rtol=0, atol=1e-15)
        np.testing.assert_allclose(np.asarray(M.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-13)
