"""Catmull-Clark evaluation on irregular faces of a mesh larger than the
neighbourhoods it refines: the local (one-ring union) path must give what
refining the whole mesh gives, and limit points at the control vertices."""

import numpy as np

import splinekit as sk
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
