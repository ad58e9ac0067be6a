"""Limit normals at boundary vertices against an independent reference: the
normal of the limit-point fan of a finely refined mesh, which converges to the
true normal as the fan shrinks. The exact masks must be what it converges to:
its distance from them shrinks by a constant factor per level.

Darts (one infinitely sharp edge at a smooth-rule vertex): limit points and
normals against deep refinement of the dart's fan alone and against
evaluate(), mask invariants, and the rows of every other vertex unchanged."""

import numpy as np
import pytest

import splinekit as sk
from splinekit.mesh import primitives
from splinekit.mesh.topology import Topology
from splinekit.subdiv.limit import dart_masks, limit_matrix, tangent_matrices
from splinekit.subdiv.refiner import Refinement
from splinekit.subdiv.fans import fan_normals
from splinekit.subdiv.level import Level


def _bent_grid(triangles: bool):
    g = primitives.grid(5, 4)
    V = g.vertices.copy()
    V[:, 2] = np.sin(1.3 * V[:, 0]) + 0.3 * V[:, 1] ** 2
    faces = g.faces
    if triangles:
        faces = np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    return sk.PolyMesh(V, faces)


def _fan_reference(surface, level):
    r = surface.refinement(level)
    L = limit_matrix(r.finest)
    f = fan_normals(r.topology, L @ r.apply(surface.mesh.vertices))[: surface.mesh.n_vertices]
    return f / np.linalg.norm(f, axis=1, keepdims=True)


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_boundary_normals_are_the_limit_of_refined_fans(scheme, boundary):
    mesh = _bent_grid(scheme == "loop")
    s = sk.SubdivisionSurface(mesh, scheme, boundary=boundary)
    n = s.limit_normals()
    b = mesh.boundary_vertices
    errors = [np.linalg.norm(n - _fan_reference(s, lv), axis=1)[b].max() for lv in (3, 5)]
    # the fan error at least halves per level (measured: 2x at valence-3 Loop boundaries, 4x elsewhere)
    assert errors[1] < 0.3 * errors[0]
    assert errors[1] < 2e-3


def test_crease_normals_on_a_creased_cube_average_the_two_sides():
    cube = primitives.box()
    creases = {tuple(e): np.inf for e in cube.edges}
    s = sk.SubdivisionSurface(cube, "catmull-clark", creases=creases)
    # all edges sharp: every vertex is a corner of three flat faces; the sum of the
    # three face normals points along the diagonal
    n = s.limit_normals()
    expected = cube.vertices / np.linalg.norm(cube.vertices, axis=1, keepdims=True)
    np.testing.assert_allclose(n, expected, atol=1e-12)


# -- darts: one infinitely sharp edge at a smooth-rule vertex ------------------------------------


def _fan_submesh(t, X, sharp_pairs, c):
    """The faces at vertex ``c`` as a small mesh: (positions, topology, sharp pairs, centre)."""
    faces = [t.face_indices[t.face_offsets[f]:t.face_offsets[f + 1]] for f in range(t.n_faces)]
    faces = [f for f in faces if c in f]
    verts = np.unique(np.concatenate(faces))
    index = {int(v): i for i, v in enumerate(verts)}
    flat = np.array([index[int(v)] for f in faces for v in f])
    topo = Topology(verts.size, flat, np.concatenate([[0], np.cumsum([len(f) for f in faces])]))
    pairs = [(index[a], index[b]) for a, b in sharp_pairs if a in index and b in index]
    return X[verts], topo, pairs, index[c]


def _deep_fan(mesh, scheme, sharp_pairs, c, levels):
    """Refine only the fan of vertex ``c`` ``levels`` times (the child fan depends on the
    parent fan alone): ``(centre position, unit normal of the final fan)``. The fan is
    kept centred and rescaled for the normal (affine maps commute with both)."""
    t, X = mesh.topology, mesh.vertices
    Y = X - X[c]
    pairs = [tuple(map(int, p)) for p in sharp_pairs]
    for _ in range(levels):
        X, topo, local, cc = _fan_submesh(t, X, pairs, c)
        Y = _fan_submesh(t, Y, pairs, c)[0]
        es = np.zeros(topo.n_edges)
        if local:
            es[topo.find_edges(np.array(local))] = np.inf
        r = Refinement(topo, scheme, 1, creases=es, boundary="edge-only")
        assert r.stencils[0][cc, cc] > 0.3  # the vertex point keeps its parent's index
        t, X, Y, c = r.topology, r.apply(X), r.apply(Y), cc
        Y = (Y - Y[c]) / np.abs(Y - Y[c]).max()
        pairs = [tuple(map(int, e)) for e in t.edges[np.isinf(r.edge_sharpness[-1])]]
    n = fan_normals(t, Y)[c]
    return X[c], n / np.linalg.norm(n)


def _dart_surfaces():
    """(surface, sharp pairs, dart vertices): valence 3 and 4 Catmull-Clark darts, a
    triangle mesh under Catmull-Clark (darts settle after one level, valence 5), Loop
    darts of valence 5 and 6; vertices jittered so nothing is symmetric."""
    rng = np.random.default_rng(7)
    box = primitives.box()
    V = box.vertices + 0.08 * rng.standard_normal(box.vertices.shape)
    yield sk.SubdivisionSurface(sk.PolyMesh(V, box.faces), "catmull-clark", creases={(2, 6): np.inf}), [(2, 6)]
    tor = primitives.torus(8, 6)
    V = tor.vertices + 0.03 * rng.standard_normal(tor.vertices.shape)
    yield sk.SubdivisionSurface(sk.PolyMesh(V, tor.faces), "catmull-clark", creases={(0, 1): np.inf}), [(0, 1)]
    ico = primitives.icosphere(1)
    V = ico.vertices + 0.03 * rng.standard_normal(ico.vertices.shape)
    edges = sk.SubdivisionSurface(ico, "loop").refinement(0).topology.edges
    pairs = [tuple(map(int, e)) for e in edges[[0, 40, 90]]]
    ico = sk.PolyMesh(V, ico.faces)
    yield sk.SubdivisionSurface(ico, "loop", creases={p: np.inf for p in pairs}), pairs
    yield sk.SubdivisionSurface(ico, "catmull-clark", creases={p: np.inf for p in pairs}), pairs


def _darts(surface, pairs):
    t = surface.refinement(0).topology
    ends = np.array(pairs).ravel()
    once = np.unique(ends)[np.bincount(ends)[np.unique(ends)] == 1]
    return once[~t.boundary_vertices[once]]


def test_dart_limit_masks_give_the_same_point_at_every_level():
    for s, pairs in _dart_surfaces():
        darts = _darts(s, pairs)
        assert darts.size >= 2
        first = 1 if not s.mesh.is_quad_mesh and s.scheme == "catmull-clark" else 0
        reference = s.limit_points()[darts]
        for k in range(first, 6 if s.scheme == "catmull-clark" and s.mesh.is_quad_mesh else 5):
            r = s.refinement(k)
            L = limit_matrix(r.finest)
            np.testing.assert_allclose((L @ r.apply(s.mesh.vertices))[darts], reference, rtol=0, atol=1e-12)


def test_dart_limits_and_normals_are_those_of_deep_local_refinement():
    # the fan converges geometrically: points by the subdominant eigenvalue per level
    # (< 0.6), normals by the ratio of the next eigenvalue to the tangent ones (up to
    # 0.8 at valence-6 Catmull-Clark darts: 100 levels leave about 4e-11)
    for s, pairs in _dart_surfaces():
        darts = _darts(s, pairs)
        points, normals = s.limit_points(), s.limit_normals()
        np.testing.assert_allclose(np.linalg.norm(normals[darts], axis=1), 1.0, atol=1e-14)
        for c in darts:
            p, n = _deep_fan(s.mesh, s.scheme, pairs, int(c), 100)
            assert np.linalg.norm(points[c] - p) < 1e-12
            assert np.linalg.norm(normals[c] - n) < 1e-9


def test_dart_normals_match_finite_differences_of_evaluate():
    """Near a dart, evaluate() descends into exact bicubic patches. The normals it gives
    at (h, h) from the corner converge linearly in h (Richardson-extrapolated, faster) to
    the limit normal, and the secants to the points at (h, 0) and (0, h) span the tangent
    plane as h -> 0. The smooth masks missed these darts' normals by about 0.2."""
    rng = np.random.default_rng(3)
    box = primitives.box()
    V = box.vertices + 0.08 * rng.standard_normal(box.vertices.shape)
    s = sk.SubdivisionSurface(sk.PolyMesh(V, box.faces), "catmull-clark", creases={(2, 6): np.inf})
    points, normals = s.limit_points(), s.limit_normals()
    t = s.refinement(0).topology
    corner_uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    for c in (2, 6):
        for corner in np.flatnonzero(t.face_indices == c):
            f = int(t.corner_face[corner])
            uv = corner_uv[corner - t.face_offsets[f]]
            step = np.where(uv == 0, 1.0, -1.0)
            h = 2.0 ** -np.arange(4, 8)  # above 2**-max_level: exact patches, no Coons fallback
            nn = s.evaluate(np.full(h.size, f), uv[0] + h * step[0], uv[1] + h * step[1])[3]
            rich = 2 * nn[1:] - nn[:-1]
            err = np.linalg.norm(rich / np.linalg.norm(rich, axis=1, keepdims=True) - normals[c], axis=1)
            assert err[-1] < 5e-3 and err[-1] < 0.6 * err[-2], err
            for hh in (2.0**-5, 2.0**-6):
                q = s.evaluate([f, f], [uv[0] + hh * step[0], uv[0]], [uv[1], uv[1] + hh * step[1]])[0]
                fd = np.cross(q[0] - points[c], q[1] - points[c]) * step[0] * step[1]
                assert np.linalg.norm(fd / np.linalg.norm(fd) - normals[c]) < 1.5e-2


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
@pytest.mark.parametrize("n", [3, 4, 5, 7, 10])
def test_dart_masks_are_affine_invariant_and_mirror_symmetric(scheme, n):
    limit, t1, t2 = dart_masks(scheme, n)
    # a translation moves the limit point with it and no tangent
    assert abs(limit.sum() - 1) < 1e-14 and (limit > 0).all()
    assert abs(t1.sum()) < 1e-13 and abs(t2.sum()) < 1e-13
    # mirroring the fan at the sharp edge: e_j <-> e_-j (and d_j <-> d_-1-j) fixes the limit point
    j = np.arange(n)
    perm = np.concatenate([[0], 1 + (-j) % n] + ([1 + n + (-1 - j) % n] if scheme == "catmull-clark" else []))
    np.testing.assert_allclose(limit[perm], limit, atol=1e-14)
    np.testing.assert_allclose(t1[perm], t1, atol=1e-13)
    np.testing.assert_allclose(t2[perm], -t2, atol=1e-13)


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_dart_masks_leave_every_other_vertex_unchanged(scheme):
    """The masks of a vertex depend on its own rule: adding an infinitely sharp edge
    changes exactly the rows of its two ends (darts), bit for bit nothing else."""
    mesh = primitives.box() if scheme == "catmull-clark" else primitives.icosphere(1)
    t = mesh.topology
    vs = np.zeros(t.n_vertices)
    plain = np.zeros(t.n_edges)
    creased = plain.copy()
    creased[5] = np.inf
    before, after = ([limit_matrix(lv).toarray(), *[m.toarray() for m in tangent_matrices(lv)[:2]]]
                     for lv in (Level(t, plain, vs, scheme), Level(t, creased, vs, scheme)))
    darts = np.zeros(t.n_vertices, dtype=bool)
    darts[t.edges[5]] = True
    for b, a in zip(before, after):
        assert (b[~darts] == a[~darts]).all()
        assert (np.abs(b[darts] - a[darts]).max(axis=1) > 1e-3).all()
