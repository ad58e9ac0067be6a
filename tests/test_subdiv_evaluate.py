"""Catmull-Clark evaluation on irregular faces of a mesh larger than the
neighbourhoods it refines: the local (one-ring union) path must give what
refining the whole mesh gives, and limit points at the control vertices."""

import numpy as np
import pytest

import splinekit as sk
import splinekit.subdiv.surface as surface_module
from splinekit.errors import SplineKitError
from splinekit.mesh import primitives


def test_local_neighbourhood_evaluation_equals_whole_mesh_refinement():
    big = sk.subdivide(primitives.box(), "catmull-clark", 4)  # 1536 quads, 8 valence-3 vertices
    s = sk.SubdivisionSurface(big, "catmull-clark")
    rng = np.random.default_rng(1)
    f = rng.integers(0, big.n_faces, 3000)
    u, v = rng.uniform(0, 1, 3000), rng.uniform(0, 1, 3000)
    local = s.evaluate(f, u, v)
    level = min(8, s._level_budget())
    whole = s._evaluate(f, u, v, level, 0, local=False)
    for a, b in zip(local[:3], whole):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13)


def test_corners_of_irregular_faces_are_limit_points():
    big = sk.subdivide(primitives.box(), "catmull-clark", 3)
    s = sk.SubdivisionSurface(big, "catmull-clark")
    limit = s.limit_points()
    faces = np.arange(big.n_faces)
    corner_uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    for k in range(4):
        p = s.evaluate(faces, np.full(faces.size, corner_uv[k, 0]), np.full(faces.size, corner_uv[k, 1]))[0]
        np.testing.assert_allclose(p, limit[big.faces[:, k]], rtol=0, atol=1e-13)


# -- the descent refines only around the queries -------------------------------------------------
# A query at an extraordinary vertex stays irregular down to max_level. Refining the
# whole mesh for it costs 4**max_level times the mesh (a cube cage refined 9 times
# for the Coons limit points: 1.5 million faces, seconds for one to_bsplines call).
# The descent must instead go on in the neighbourhoods of the queries still
# irregular, so that the refined area does not grow with the depth.


@pytest.fixture
def refined_sizes(monkeypatch):
    """Face counts of every Refinement the subdivision surfaces build."""
    sizes = []

    class Recording(surface_module.Refinement):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            sizes.append(self.topology.n_faces)

    monkeypatch.setattr(surface_module, "Refinement", Recording)
    return sizes


def _extraordinary_corner_sizes(sizes, max_level):
    sizes.clear()
    s = sk.SubdivisionSurface(primitives.box(), "catmull-clark")
    p = s.evaluate([0], [0.0], [0.0], max_level=max_level)[0]
    # the corner of the face is a limit point (limit masks: independent of the descent)
    np.testing.assert_allclose(p[0], s.limit_points()[primitives.box().faces[0, 0]], rtol=0, atol=1e-14)
    return list(sizes)


def test_deep_descent_at_an_extraordinary_vertex_refines_a_bounded_area(refined_sizes):
    shallow = _extraordinary_corner_sizes(refined_sizes, 4)
    deep = _extraordinary_corner_sizes(refined_sizes, 8)
    # four more levels: the whole cube would grow 256-fold; the neighbourhoods do not grow
    assert max(deep) <= max(shallow)
    assert sum(deep) < 2 * sum(shallow)
    assert max(deep) < 6 * 4**4


def test_to_bsplines_deviation_check_refines_a_bounded_area(refined_sizes):
    s = sk.SubdivisionSurface(primitives.box(), "catmull-clark")
    patches, info = s.to_bsplines()
    assert info["approximate"] == 24  # the three level-2 quads at each of the 8 valence-3 corners
    assert 0 < info["max_deviation"] < 0.01
    # the deviation check descends to level 8 (+1 for the Coons limit points) at the 8 corners:
    # the whole cube refined that far has 6 * 4**9 faces
    assert max(refined_sizes) <= 6 * 4**5
    assert sum(refined_sizes) <= 6 * 4**6


def _query_grid(n_faces, rng, n_random=200):
    """Corners, edge points and a lattice of every face, plus random points."""
    g = np.array([0.0, 1 / 8, 0.25, 0.5, 0.75, 1.0])
    f = np.repeat(np.arange(n_faces), g.size**2)
    u = np.tile(np.repeat(g, g.size), n_faces)
    v = np.tile(np.tile(g, g.size), n_faces)
    return (np.concatenate([f, rng.integers(0, n_faces, n_random)]),
            np.concatenate([u, rng.uniform(0, 1, n_random)]), np.concatenate([v, rng.uniform(0, 1, n_random)]))


@pytest.mark.parametrize("kind", ["box", "creased", "grid", "triangles"])
def test_neighbourhood_descent_equals_whole_mesh_descent(kind):
    box = primitives.box()
    if kind == "box":
        s = sk.SubdivisionSurface(box, "catmull-clark")
    elif kind == "creased":
        edges = sk.SubdivisionSurface(box, "catmull-clark").refinement(0).topology.edges
        s = sk.SubdivisionSurface(box, "catmull-clark", creases={tuple(edges[0]): 1.5, tuple(edges[5]): 2.5},
                                  corners={3: 2.0}, crease_method="chaikin")
    elif kind == "grid":  # boundary faces never become regular
        s = sk.SubdivisionSurface(primitives.grid(4, 3), "catmull-clark")
    else:
        s = sk.SubdivisionSurface(primitives.icosphere(1), "catmull-clark")
    base = s._eval_base_level
    f, u, v = _query_grid(s._level_data(base)[0].n_faces, np.random.default_rng(3))
    # the whole-mesh reference refines 4**level times the mesh: keep the triangles' 240 quads shallower
    for level in (0, 1, 3 if kind == "triangles" else 5):
        local = s._evaluate(f, u, v, level, base, local=True)
        whole = s._evaluate(f, u, v, level, base, local=False)
        np.testing.assert_allclose(local[0], whole[0], rtol=0, atol=1e-14)
        # partials scale with 2**level through the chain rule
        np.testing.assert_allclose(local[1], whole[1], rtol=0, atol=1e-14 * 2**level)
        np.testing.assert_allclose(local[2], whole[2], rtol=0, atol=1e-14 * 2**level)


@pytest.mark.parametrize("max_level", [0, 2])
def test_neighbourhoods_of_a_large_mesh_keep_chaikin_creases_and_level_zero_edges(max_level):
    # a few queries on a large mesh go to the neighbourhoods right at the control level:
    # these must keep the crease method (Chaikin averaging) and, with no level left,
    # the exact edges of regular neighbours (which are border faces of the union)
    mesh = sk.subdivide(primitives.box(), "catmull-clark", 2)
    edges = sk.SubdivisionSurface(mesh, "catmull-clark").refinement(0).topology.edges
    rng = np.random.default_rng(0)
    pick = rng.choice(len(edges), 60, replace=False)
    creases = {tuple(edges[i]): float(x) for i, x in zip(pick, rng.uniform(0.3, 3.5, pick.size))}
    s = sk.SubdivisionSurface(mesh, "catmull-clark", creases=creases, crease_method="chaikin")
    f, u, v = rng.integers(0, mesh.n_faces, 8), rng.uniform(0, 1, 8), rng.uniform(0, 1, 8)
    local = s._evaluate(f, u, v, max_level, 0, local=True)
    whole = s._evaluate(f, u, v, max_level, 0, local=False)
    for a, b in zip(local, whole):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13)
    # and the level-0 Coons patches are those of to_bsplines(levels=0)
    if max_level == 0:
        patches, info = s.to_bsplines(levels=0)
        assert (info["level"] == 0).all()  # one patch per face, in the face's own parameters
        for k in range(f.size):
            patch = patches[int(np.flatnonzero(info["face"] == f[k])[0])]
            np.testing.assert_allclose(patch.evaluate([u[k]], [v[k]])[0], local[0][k], rtol=0, atol=1e-13)


@pytest.mark.parametrize("bad", [-1, 1.5, "deep"])
def test_evaluate_rejects_bad_max_level(bad):
    s = sk.SubdivisionSurface(primitives.box(), "catmull-clark")
    with pytest.raises(SplineKitError, match="max_level"):
        s.evaluate([0], [0.5], [0.5], max_level=bad)
