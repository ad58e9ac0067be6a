"""Catmull-Clark evaluation on irregular faces of a mesh larger than the
neighbourhoods it refines: the local (one-ring union) path must give what
refining the whole mesh gives, and limit points at the control vertices."""

import numpy as np
import pytest

import splinekit as sk
import splinekit.subdiv.fans as fans_module
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
    monkeypatch.setattr(fans_module, "Refinement", Recording)  # the fans' local refinements
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


# -- semi-sharp creases: limits from the fans of the vertices, not the whole mesh ----------------
# A crease of sharpness s changes the rules for ceil(s) levels, and the limit masks apply
# only after that. Refining the whole mesh that far for the Coons corner limits cost 4**s
# times the mesh (the cube with sharpness 10: 6 million faces). The limit of a vertex
# depends only on its fan, so refining the fans of the vertices that need it gives the
# same limits with a cost linear in s.


def _whole_mesh_limits(s, level, extra):
    """Limit points of the level-``level`` vertices, from the whole mesh refined ``extra``
    more levels (past every finite sharpness) and the limit masks there."""
    from splinekit.subdiv.limit import limit_matrix

    fine = s.refinement(level + extra)
    L = limit_matrix(fine.finest)
    # the vertex points of a level keep their indices at every finer level
    return (L @ fine.apply(s.mesh.vertices))[: s.refinement(level).topology.n_vertices]


def _whole_mesh_normals(s, extra):
    """Unit limit normals of the control vertices from the tangent masks and crease
    sectors of the whole mesh refined ``extra`` levels."""
    from splinekit.subdiv.limit import crease_normals, tangent_matrices

    fine = s.refinement(extra)
    X = fine.apply(s.mesh.vertices)
    T1, T2, ok = tangent_matrices(fine.finest)
    n = np.cross(T1 @ X, T2 @ X)
    cn, covered = crease_normals(fine.finest, X)
    n[~ok] = cn[~ok]
    assert (ok | covered)[: s.mesh.n_vertices].all()
    n = n[: s.mesh.n_vertices]
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _mug_cage():
    from models.mug import cage

    return cage(size=1.0)


def _creased_surfaces(method):
    """(surface, levels past its largest finite sharpness): semi-sharp creases (fractional,
    varying along a crease, ending in darts), a sharp vertex, boundaries, n-gons, Loop."""
    box = primitives.box()
    yield sk.SubdivisionSurface(box, "catmull-clark", creases=(box.edges[:4], [2.5, 0.7, 1.0, 3.2]),
                                corners={6: 1.4}, crease_method=method), 4
    mug, rim = _mug_cage()
    sharp = np.linspace(0.4, 2.6, len(rim))
    yield sk.SubdivisionSurface(mug, "catmull-clark", creases=(rim, sharp), crease_method=method), 3
    grid = primitives.grid(4, 3)
    edges = sk.SubdivisionSurface(grid, "catmull-clark").refinement(0).topology.edges
    yield sk.SubdivisionSurface(grid, "catmull-clark", creases=(edges[3:9], np.linspace(0.3, 2.2, 6)),
                                crease_method=method), 3
    ico = primitives.icosphere(1)
    edges = sk.SubdivisionSurface(ico, "loop").refinement(0).topology.edges
    creases = (edges[::7], np.linspace(0.2, 2.9, len(edges[::7])))
    yield sk.SubdivisionSurface(ico, "loop", creases=creases, crease_method=method), 3
    yield sk.SubdivisionSurface(ico, "catmull-clark", creases=creases, crease_method=method), 3


@pytest.mark.parametrize("method", ["uniform", "chaikin"])
def test_semi_sharp_limit_points_and_normals_equal_whole_mesh_refinement(method):
    for s, extra in _creased_surfaces(method):
        np.testing.assert_allclose(s.limit_points(), _whole_mesh_limits(s, 0, extra), rtol=0, atol=1e-13)
        n = s.limit_normals()
        np.testing.assert_allclose(n, _whole_mesh_normals(s, extra), rtol=0, atol=1e-12)
        if s.scheme != "catmull-clark":
            continue
        # the Coons corners of to_bsplines(1) are limit points of the level their faces belong to
        patches, info = s.to_bsplines(1)
        for level in np.unique(info["level"][info["kind"] == "coons"]):
            pick = np.flatnonzero((info["kind"] == "coons") & (info["level"] == level))
            corners = np.array([patches[i].control_points[[0, 3, 3, 0], [0, 0, 3, 3]] for i in pick]).reshape(-1, 3)
            reference = _whole_mesh_limits(s, int(level), extra)
            gap = np.linalg.norm(corners[:, None, :] - reference[None, :, :], axis=2).min(axis=1)
            assert gap.max() < 1e-13


def _cube_with_creased_loop(sharpness):
    """The cube with the four edges of one face creased (a closed crease: no darts)."""
    box = primitives.box()
    loop = np.stack([box.faces[0], np.roll(box.faces[0], -1)], axis=1)
    return sk.SubdivisionSurface(box, "catmull-clark", creases=(loop, np.full(4, float(sharpness))))


def test_to_bsplines_with_high_crease_sharpness_refines_a_bounded_area(refined_sizes):
    totals = {}
    for sharpness in (3.0, 10.0, 30.0):
        refined_sizes.clear()
        _patches, info = _cube_with_creased_loop(sharpness).to_bsplines(1)
        assert info["approximate"] > 0 and np.isfinite(info["max_deviation"])
        # the whole cube refined 10 (30) times has 6 * 4**10 (6 * 4**30) faces
        assert max(refined_sizes) <= 6 * 4**6
        totals[sharpness] = sum(refined_sizes)
    # each further unit of sharpness refines the crease fans one more level: linear growth
    assert totals[30.0] < 4 * totals[10.0]


def test_limit_points_with_high_sharpness_refine_only_the_fans(refined_sizes):
    s = _cube_with_creased_loop(40.0)
    refined_sizes.clear()
    limits = s.limit_points()
    # 40 levels of the four crease vertices' fans (3 quads each, 12 after refinement)
    assert len(refined_sizes) <= 41
    assert max(refined_sizes) <= 4 * 3 * 4
    # the crease stays sharp for 40 levels, so the limit is the sharp crease's to ~2**-40
    sharp = _cube_with_creased_loop(np.inf).limit_points()
    np.testing.assert_allclose(limits, sharp, rtol=0, atol=1e-10)
    assert np.abs(limits - sharp).max() > 0  # and not the same surface


def test_huge_finite_sharpness_is_the_sharp_limit_and_terminates():
    huge = _cube_with_creased_loop(1e300)
    sharp = _cube_with_creased_loop(np.inf)
    np.testing.assert_allclose(huge.limit_points(), sharp.limit_points(), rtol=0, atol=1e-14)
    np.testing.assert_allclose(huge.limit_normals(), sharp.limit_normals(), rtol=0, atol=1e-12)
