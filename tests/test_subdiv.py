"""Subdivision (splinekit.subdiv) against independent references.

References used, none of them read off splinekit's subdivision output:

- Regular Catmull-Clark is the uniform bicubic B-spline and regular Doo-Sabin
  the uniform biquadratic one: checked against splinekit's own tensor-product
  ``BSplineSurface`` (an independent evaluator) built on the wrapped control
  grid of a closed quad torus, including the knot-insertion identity (one
  step of the scheme gives exactly the control net of the same surface on the
  halved knot vector).
- Limit masks are derived here from the hand-written subdivision rules: the
  rules restricted to the rotationally symmetric averages around a vertex of
  valence n form a small matrix (2 x 2 for Loop on (v, ring mean), 3 x 3 for
  Catmull-Clark on (v, mean edge neighbour, mean diagonal)); its left
  eigenvector for eigenvalue 1 is the limit mask, and its second eigenvalue
  is the exact per-level contraction of ``vertex - limit``.
- Closed forms: unit cube corner limit (-1/4, -1/4, -1/4), face-centre limit
  (0, 0, -34/81) (the face point after one step has the regular mask
  (1, 4, 1) x (1, 4, 1) / 36), octahedron Loop limit 24/55 v, normals by
  symmetry.
- Creases and boundaries: the cubic B-spline (``BSplineCurve``) of the crease
  or boundary polygon; interpolated ends = phantom points ``2 P0 - P1``.

Measured (numpy 2.4, float64) with the meshes of these tests:

- CC torus 6 x 5 (perturbed): max |vertex - limit| at levels 1..6
  1.5e-1, 3.7e-2, 9.2e-3, 2.3e-3, 5.8e-4, 1.4e-4 (ratio -> 4.00).
- CC unit cube corner: |vertex - limit| = 6^-(k+1) per coordinate exactly
  (1/36, 1/216, ...; 3.57e-6 after 6 levels); ratio 6 = 1 / lambda_2(n = 3).
- Loop perturbed icosphere: |vertex - limit| shrinks by exactly
  5/8 - n beta(n) per level (1/4 at valence 6, 0.2046 at valence 5);
  max |vertex - limit| 3.5e-5 after 6 levels.
- Limit normals vs the fan normal of the refined 1-ring: Loop icosphere
  2.3e-6 after 6 levels (ratio 4), CC perturbed cube 4.4e-5 after 7 levels
  (ratio ~2.7).
- CC perturbed cube: ``evaluate`` normals at extraordinary corners (bilinear
  fallback) differ from the exact ``limit_normals`` by 5.4e-2, 1.0e-2, 1.7e-3
  at max_level 4, 6, 8.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit import BSplineCurve, BSplineSurface, PolyMesh, Refinement, SubdivisionSurface, subdivide, subdivision_matrix
from splinekit.errors import DomainError, MeshTopologyError, ParameterError
from splinekit.mesh import Topology
from splinekit.mesh.primitives import box, grid, icosphere, torus

FEW = settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
TOL = 1e-12
CORNER_UV = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


# ---------------------------------------------------------------------------------------------
# meshes
# ---------------------------------------------------------------------------------------------
def perturbed(mesh, scale, seed):
    rng = np.random.default_rng(seed)
    faces = mesh.faces
    return PolyMesh(mesh.vertices + scale * rng.standard_normal(mesh.vertices.shape), faces)


def quad_torus(nu, nv, seed, scale=0.1):
    """Closed regular quad grid: vertex ``i nv + j``; face ``i nv + j`` is
    ``(ij, (i+1)j, (i+1)(j+1), i(j+1))`` (indices mod nu, nv), so its u runs along +i
    and its v along +j."""
    return perturbed(torus(nu, nv, 2.0, 0.7), scale, seed)


def tri_torus(nu, nv, seed, scale=0.05):
    """The quad torus with every quad split along the same diagonal: valence 6 everywhere."""
    q = torus(nu, nv, 2.0, 0.7)
    F = q.faces
    return perturbed(PolyMesh(q.vertices, np.concatenate([F[:, [0, 1, 2]], F[:, [0, 2, 3]]])), scale, seed)


def octahedron():
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return PolyMesh(V, F)


def tetrahedron():
    T = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    return PolyMesh(T, [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])


def bipyramid(n):
    """Closed triangle mesh: an n-gon ring and two apexes of valence n."""
    a = 2 * np.pi * np.arange(n) / n
    V = np.vstack([np.column_stack([np.cos(a), np.sin(a), np.zeros(n)]), [[0, 0, 1.2], [0, 0, -1.1]]])
    F = [[i, (i + 1) % n, n] for i in range(n)] + [[(i + 1) % n, i, n + 1] for i in range(n)]
    return PolyMesh(V, F)


def mixed_mesh():
    """Closed pentagonal prism with one side quad split in two: pentagons, quads, triangles."""
    ang = 2 * np.pi * np.arange(5) / 5
    V = np.vstack([np.column_stack([np.cos(ang), np.sin(ang), -np.ones(5)]),
                   np.column_stack([np.cos(ang), np.sin(ang), np.ones(5)])])
    faces = [[4, 3, 2, 1, 0], [5, 6, 7, 8, 9], [0, 1, 6], [0, 6, 5]]
    faces += [[i, i + 1, i + 6, i + 5] for i in range(1, 4)] + [[4, 0, 5, 9]]
    return PolyMesh(V, faces)


def tri_grid(nx, ny, seed):
    g = grid(nx, ny)
    F = g.faces
    X = g.vertices.copy()
    rng = np.random.default_rng(seed)
    X[:, 2] = 0.3 * rng.random(len(X))
    return PolyMesh(X, np.concatenate([F[:, [0, 1, 2]], F[:, [0, 2, 3]]]))


def bumpy_grid(nx, ny, seed):
    g = grid(nx, ny)
    X = g.vertices.copy()
    rng = np.random.default_rng(seed)
    X[:, 2] = 0.3 * rng.random(len(X))
    X[:, :2] += 0.03 * rng.standard_normal((len(X), 2))
    return PolyMesh(X, g.faces)


def grid_boundary(nx, ny):
    """Boundary loop of ``grid(nx, ny)`` (counter-clockwise) and its four corners."""
    idx = lambda i, j: i * (ny + 1) + j  # noqa: E731
    loop = ([idx(i, 0) for i in range(nx)] + [idx(nx, j) for j in range(ny)]
            + [idx(i, ny) for i in range(nx, 0, -1)] + [idx(0, j) for j in range(ny, 0, -1)])
    sides = [[idx(i, 0) for i in range(nx + 1)], [idx(nx, j) for j in range(ny + 1)],
             [idx(i, ny) for i in range(nx, -1, -1)], [idx(0, j) for j in range(ny, -1, -1)]]
    corners = [idx(0, 0), idx(nx, 0), idx(nx, ny), idx(0, ny)]
    return np.array(loop), [np.array(s) for s in sides], np.array(corners)


# ---------------------------------------------------------------------------------------------
# independent references
# ---------------------------------------------------------------------------------------------
def periodic_cubic_surface(G, h=1.0):
    """Closed uniform bicubic B-spline of the ``(nu, nv, dim)`` control grid ``G``:
    the limit point of ``G[a, b]`` is at ``(a h, b h)`` (``a = 0`` at ``nu h``);
    domain ``[h, (nu + 1) h] x [h, (nv + 1) h]``."""
    nu, nv = G.shape[:2]
    W = G[np.arange(nu + 3) % nu][:, np.arange(nv + 3) % nv]
    return BSplineSurface(3, 3, (np.arange(nu + 7) - 2.0) * h, (np.arange(nv + 7) - 2.0) * h, W)


def periodic_cubic_curve(P, h=1.0):
    """Closed uniform cubic B-spline of polygon ``P``; vertex ``a`` has its limit at ``a h``."""
    n = len(P)
    return BSplineCurve(3, (np.arange(n + 7) - 2.0) * h, P[np.arange(n + 3) % n])


def natural_cubic_curve(P, h=1.0):
    """Uniform cubic B-spline of polygon ``P`` with interpolated ends (phantom points
    ``2 P0 - P1``, ``2 Pn - Pn-1``); vertex ``i`` has its limit at ``i h``, domain ``[0, n h]``."""
    ext = np.vstack([2 * P[0] - P[1], P, 2 * P[-1] - P[-2]])
    return BSplineCurve(3, (np.arange(len(ext) + 4) - 3.0) * h, ext)


def edge_index(topology):
    return {(int(a), int(b)): k for k, (a, b) in enumerate(topology.edges)}


def refine_chain(topology, chain, closed):
    """The chain of child vertices along a vertex chain after one Catmull-Clark or Loop
    step: every vertex keeps its index and edge ``e = (a, b)`` inserts ``V + e``."""
    lookup = edge_index(topology)
    nxt = np.roll(chain, -1) if closed else chain[1:]
    cur = chain if closed else chain[:-1]
    e = np.array([lookup[(min(a, b), max(a, b))] for a, b in zip(cur.tolist(), nxt.tolist())])
    out = np.empty(len(chain) + len(e), dtype=np.int64)
    out[0::2] = chain
    out[1::2] = topology.n_vertices + e
    return out


def loop_beta(n):
    """Loop's smooth-vertex weight (Loop 1987)."""
    return (5 / 8 - (3 / 8 + np.cos(2 * np.pi / n) / 4) ** 2) / n


def loop_symmetric_matrix(n):
    """Loop rules on (v, ring mean): v' = (1 - n b) v + n b r, e_j' = 3/8 v + 3/8 e_j + 1/8 (e_j-1 + e_j+1)."""
    b = loop_beta(n)
    return np.array([[1 - n * b, n * b], [3 / 8, 5 / 8]])


def cc_symmetric_matrix(n):
    """Catmull-Clark rules on (v, mean edge neighbour, mean diagonal) of a quad-mesh vertex:
    f_j = (v + e_j + e_j+1 + d_j) / 4, e_j' = (v + e_j + f_j-1 + f_j) / 4,
    v' = (n - 2) / n v + (1 / n) mean(e) + (1 / n) mean(f), d_j' = f_j."""
    return np.array([
        [(4 * n - 7) / (4 * n), 6 / (4 * n), 1 / (4 * n)],
        [3 / 8, 1 / 2, 1 / 8],
        [1 / 4, 1 / 2, 1 / 4],
    ])


def limit_weights(M):
    """Left eigenvector of eigenvalue 1, normalized to sum 1, and the second eigenvalue."""
    w, vl = np.linalg.eig(M.T)
    order = np.argsort(-np.abs(w))
    assert abs(w[order[0]] - 1) < 1e-12
    l = np.real(vl[:, order[0]])
    return l / l.sum(), float(np.real(w[order[1]]))


def cc_rings(mesh):
    """Per vertex of a closed quad mesh: (edge neighbours, diagonal corners)."""
    t = mesh.topology
    nb = [set() for _ in range(t.n_vertices)]
    dg = [[] for _ in range(t.n_vertices)]
    for f in mesh.faces:
        for k in range(4):
            v = f[k]
            nb[v].update((int(f[(k + 1) % 4]), int(f[(k - 1) % 4])))
            dg[v].append(int(f[(k + 2) % 4]))
    return [sorted(s) for s in nb], dg


def fan_normals(mesh, vertices):
    """Normalized sum of the corner cross products around each vertex (the 1-ring's normal)."""
    t = mesh.topology
    P = mesh.vertices
    out = np.zeros((len(vertices), 3))
    for k, v in enumerate(vertices):
        for c in np.flatnonzero(t.face_indices == v):
            a = P[t.halfedge_dst[c]] - P[v]
            b = P[t.face_indices[t.prev_corner[c]]] - P[v]
            out[k] += np.cross(a, b)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def unit(x):
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def fresh(t):
    """The same faces, connectivity rebuilt from scratch with full validation."""
    return Topology(t.n_vertices, np.array(t.face_indices), np.array(t.face_offsets), check=True)


# ---------------------------------------------------------------------------------------------
# 1. Catmull-Clark on a regular closed quad mesh = bicubic uniform B-spline
# ---------------------------------------------------------------------------------------------
def torus_grid_params(nu, nv):
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    # vertex (i, j) has its limit at (i, j); i = 0 is the same point as nu
    return np.where(i == 0, nu, i).ravel().astype(float), np.where(j == 0, nv, j).ravel().astype(float)


@FEW
@given(seed=st.integers(0, 2**31), nu=st.integers(4, 6), nv=st.integers(4, 6))
def test_cc_torus_limit_points_are_bicubic_bspline(seed, nu, nv):
    mesh = quad_torus(nu, nv, seed)
    S = periodic_cubic_surface(mesh.vertices.reshape(nu, nv, 3))
    pu, pv = torus_grid_params(nu, nv)
    np.testing.assert_allclose(SubdivisionSurface(mesh, "catmull-clark").limit_points(), S.evaluate(pu, pv), atol=TOL)


@FEW
@given(seed=st.integers(0, 2**31), nu=st.integers(4, 6), nv=st.integers(4, 6))
def test_cc_torus_evaluate_matches_bspline(seed, nu, nv):
    mesh = quad_torus(nu, nv, seed)
    S = periodic_cubic_surface(mesh.vertices.reshape(nu, nv, 3))
    rng = np.random.default_rng(seed)
    face = np.repeat(np.arange(nu * nv), 4)
    u, v = rng.random(face.size), rng.random(face.size)
    u[:4], v[:4] = CORNER_UV[:, 0], CORNER_UV[:, 1]  # exact corners too
    P, Du, Dv, N = SubdivisionSurface(mesh, "catmull-clark").evaluate(face, u, v)
    i, j = face // nv, face % nv
    # face (i, j) spans [i, i + 1] x [j, j + 1]; i = 0 is [nu, nu + 1]
    uu = np.where(i == 0, nu, i) + u
    vv = np.where(j == 0, nv, j) + v
    d = S.derivatives(uu, vv, 1)
    np.testing.assert_allclose(P, d[0, 0], atol=TOL)
    np.testing.assert_allclose(Du, d[1, 0], atol=TOL)
    np.testing.assert_allclose(Dv, d[0, 1], atol=TOL)
    np.testing.assert_allclose(N, unit(np.cross(d[1, 0], d[0, 1])), atol=1e-11)


def test_cc_torus_to_bsplines_are_the_bspline_patches():
    nu, nv = 5, 4
    mesh = quad_torus(nu, nv, 11)
    S = periodic_cubic_surface(mesh.vertices.reshape(nu, nv, 3))
    patches, info = SubdivisionSurface(mesh, "catmull-clark").to_bsplines()
    assert info["exact"] == nu * nv and info["approximate"] == 0 and info["max_deviation"] == 0.0
    assert len(patches) == nu * nv
    g = np.linspace(0, 1, 7)
    s, t = [a.ravel() for a in np.meshgrid(g, g, indexing="ij")]
    for k, patch in enumerate(patches):
        f = int(info["face"][k])
        assert info["kind"][k] == "exact" and info["level"][k] == 0
        uv = np.column_stack([s, t]) @ info["axes"][k].T + info["origin"][k]
        i, j = f // nv, f % nv
        ref = S.evaluate(np.where(i == 0, nu, i) + uv[:, 0], np.where(j == 0, nv, j) + uv[:, 1])
        np.testing.assert_allclose(patch.evaluate(s, t), ref, atol=TOL)


def test_cc_torus_one_step_is_knot_insertion():
    """The whole level-1 net (vertex, edge and face points laid out on the doubled grid)
    is the control net of the same bicubic surface on the halved knot vector."""
    nu, nv = 5, 4
    mesh = quad_torus(nu, nv, 3)
    X = mesh.vertices
    r = Refinement(mesh, "catmull-clark", 1)
    Y = r.apply(X)
    t0 = mesh.topology
    V, E = t0.n_vertices, t0.n_edges
    lookup = edge_index(t0)
    vid = lambda i, j: (i % nu) * nv + (j % nv)  # noqa: E731
    G = np.empty((2 * nu, 2 * nv, 3))
    for i in range(nu):
        for j in range(nv):
            a, bu, bv = vid(i, j), vid(i + 1, j), vid(i, j + 1)
            G[2 * i, 2 * j] = Y[a]
            G[2 * i + 1, 2 * j] = Y[V + lookup[(min(a, bu), max(a, bu))]]
            G[2 * i, 2 * j + 1] = Y[V + lookup[(min(a, bv), max(a, bv))]]
            G[2 * i + 1, 2 * j + 1] = Y[V + E + a]  # face a = i nv + j
    coarse = periodic_cubic_surface(X.reshape(nu, nv, 3))
    fine = periodic_cubic_surface(G, h=0.5)
    rng = np.random.default_rng(0)
    u, v = 1 + rng.random(300) * (nu - 1), 1 + rng.random(300) * (nv - 1)
    np.testing.assert_allclose(fine.evaluate(u, v), coarse.evaluate(u, v), atol=TOL)


def test_cc_torus_vertices_converge_4x_per_level():
    nu, nv = 6, 5
    mesh = quad_torus(nu, nv, 0)
    S = periodic_cubic_surface(mesh.vertices.reshape(nu, nv, 3))
    limit = S.evaluate(*torus_grid_params(nu, nv))
    surf = SubdivisionSurface(mesh, "catmull-clark")
    err = [np.abs(surf.refine(k).vertices[: nu * nv] - limit).max() for k in range(1, 7)]
    ratios = np.array(err[:-1]) / np.array(err[1:])
    # vertex - limit = 4^-k a + 16^-k b (second differences in u, v and the mixed fourth one)
    assert err[-1] < 1.6e-4
    assert np.all(ratios[1:] > 3.95) and np.all(ratios[1:] < 4.1), ratios
    assert abs(ratios[-1] - 4) < 0.01


def test_cc_torus_limit_normals_are_bspline_normals():
    nu, nv = 6, 5
    mesh = quad_torus(nu, nv, 1)
    S = periodic_cubic_surface(mesh.vertices.reshape(nu, nv, 3))
    d = S.derivatives(*torus_grid_params(nu, nv), 1)
    ref = unit(np.cross(d[1, 0], d[0, 1]))
    N = SubdivisionSurface(mesh, "catmull-clark").limit_normals()
    np.testing.assert_allclose(N, ref, atol=1e-12)
    # outward: the torus is counter-clockwise seen from outside
    centre_of_tube = np.column_stack([unit(mesh.vertices[:, :2]) * 2.0, np.zeros(nu * nv)])
    assert (np.einsum("ij,ij->i", N, mesh.vertices - centre_of_tube) > 0).all()


# ---------------------------------------------------------------------------------------------
# 2. Doo-Sabin = biquadratic uniform B-spline; Loop regular masks
# ---------------------------------------------------------------------------------------------
def doo_sabin_grid(nu, nv):
    """Child index of each cell of the doubled grid after one Doo-Sabin step of the quad torus:
    corner k of face (i, j) (child 4 f + k) sits at (2 i, 2 j) + (0,0), (1,0), (1,1), (0,1)."""
    C = np.empty((2 * nu, 2 * nv), dtype=np.int64)
    f = np.arange(nu * nv)
    for k, (a, b) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
        C[2 * (f // nv) + a, 2 * (f % nv) + b] = 4 * f + k
    return C


def test_doo_sabin_step_is_biquadratic_knot_insertion():
    """Chaikin in each direction: corner (i, j) of face (i..i+1, j..j+1) becomes
    (3/4, 1/4) x (3/4, 1/4); on knots tau_k = k - 2 the new points are the control net on
    sigma_k = (k - 2) / 2 (midpoint of d_2a, d_2a+1 is the curve at tau_a+2 = sigma_2a+2)."""
    nu, nv = 5, 4
    mesh = quad_torus(nu, nv, 7)
    Y = subdivide(mesh, "doo-sabin", 1).vertices
    C = doo_sabin_grid(nu, nv)

    def biquadratic(G, h):
        n, m = G.shape[:2]
        W = G[np.arange(n + 2) % n][:, np.arange(m + 2) % m]
        return BSplineSurface(2, 2, (np.arange(n + 5) - 2.0) * h, (np.arange(m + 5) - 2.0) * h, W)

    coarse = biquadratic(mesh.vertices.reshape(nu, nv, 3), 1.0)
    fine = biquadratic(Y[C], 0.5)
    assert coarse.domain == fine.domain == ((0.0, nu), (0.0, nv))
    rng = np.random.default_rng(1)
    u, v = rng.random(400) * nu, rng.random(400) * nv
    np.testing.assert_allclose(fine.evaluate(u, v), coarse.evaluate(u, v), atol=TOL)


def test_doo_sabin_child_of_regular_torus_is_the_doubled_grid():
    """The child connectivity is the doubled periodic grid (so the identity above
    applies again at every level)."""
    nu, nv = 5, 4
    child = Refinement(quad_torus(nu, nv, 0), "doo-sabin", 1).topology
    C = doo_sabin_grid(nu, nv)
    expected = set()
    for i in range(2 * nu):
        for j in range(2 * nv):
            q = [C[i, j], C[(i + 1) % (2 * nu), j], C[(i + 1) % (2 * nu), (j + 1) % (2 * nv)], C[i, (j + 1) % (2 * nv)]]
            k = int(np.argmin(q))
            expected.add(tuple(q[k:] + q[:k]))
    got = set()
    for f in np.split(child.face_indices, child.face_offsets[1:-1]):
        f = f.tolist()
        k = int(np.argmin(f))
        got.add(tuple(f[k:] + f[:k]))
    assert got == expected


def test_doo_sabin_rules_by_hand():
    """Any n-gon: the corner weights form a circulant with rows summing to 1, so the
    children of a face keep its centroid; on quads they are (9, 3, 1, 3) / 16."""
    mesh = perturbed(mixed_mesh(), 0.1, 2)
    t = mesh.topology
    r = Refinement(mesh, "doo-sabin", 1)
    Y = r.apply(mesh.vertices)
    for f in range(t.n_faces):
        c = np.arange(t.face_offsets[f], t.face_offsets[f + 1])
        np.testing.assert_allclose(Y[c].mean(axis=0), mesh.vertices[t.face_indices[c]].mean(axis=0), atol=TOL)
    quad = int(np.flatnonzero(t.face_sizes == 4)[0])
    c0 = int(t.face_offsets[quad])
    q = mesh.vertices[t.face_indices[c0 : c0 + 4]]
    np.testing.assert_allclose(Y[c0], (9 * q[0] + 3 * q[1] + q[2] + 3 * q[3]) / 16, atol=TOL)
    tri = int(np.flatnonzero(t.face_sizes == 3)[0])
    c0 = int(t.face_offsets[tri])
    p = mesh.vertices[t.face_indices[c0 : c0 + 3]]
    # n = 3: own (3 + 5) / 12 = 2/3, others (3 + 2 cos(2 pi / 3)) / 12 = 1/6
    np.testing.assert_allclose(Y[c0], (4 * p[0] + p[1] + p[2]) / 6, atol=TOL)


def test_doo_sabin_open_grid_boundary_is_chaikin():
    """A corner beside one boundary edge (v, w) moves to 3/4 v + 1/4 w; a corner between
    two boundary edges stays."""
    mesh = bumpy_grid(3, 2, 5)
    t = mesh.topology
    X = mesh.vertices
    Y = subdivide(mesh, "doo-sabin", 1).vertices
    b = t.boundary_edges
    nxt_b = b[t.halfedge_edge]
    prv_b = b[t.halfedge_edge[t.prev_corner]]
    v = X[t.face_indices]
    both = nxt_b & prv_b
    np.testing.assert_array_equal(Y[both], v[both])
    only_n = nxt_b & ~prv_b
    np.testing.assert_allclose(Y[only_n], 0.75 * v[only_n] + 0.25 * X[t.halfedge_dst[only_n]], atol=TOL)
    only_p = prv_b & ~nxt_b
    w = X[t.face_indices[t.prev_corner[only_p]]]
    np.testing.assert_allclose(Y[only_p], 0.75 * v[only_p] + 0.25 * w, atol=TOL)
    assert both.sum() == 4 and only_n.sum() > 0 and only_p.sum() > 0


def test_loop_regular_limit_mask_is_half_plus_twelfths():
    """Valence 6: the symmetric part [[5/8, 3/8], [3/8, 5/8]] (beta(6) = 1/16) has left
    eigenvector (1/2, 1/2), so the limit is v / 2 + (1/12) sum of the six neighbours."""
    assert abs(loop_beta(6) - 1 / 16) < 1e-15
    l, lam = limit_weights(loop_symmetric_matrix(6))
    np.testing.assert_allclose(l, [0.5, 0.5], atol=1e-14)
    assert abs(lam - 0.25) < 1e-14
    mesh = tri_torus(6, 5, 4)
    t = mesh.topology
    assert (t.valence == 6).all()
    X = mesh.vertices
    nb_sum = np.zeros_like(X)
    np.add.at(nb_sum, t.edges[:, 0], X[t.edges[:, 1]])
    np.add.at(nb_sum, t.edges[:, 1], X[t.edges[:, 0]])
    L = SubdivisionSurface(mesh, "loop").limit_points()
    np.testing.assert_allclose(L, X / 2 + nb_sum / 12, atol=TOL)


def loop_limit_reference(mesh):
    t = mesh.topology
    X = mesh.vertices
    out = np.empty_like(X)
    lam = np.empty(t.n_vertices)
    for v in range(t.n_vertices):
        nb = np.concatenate([t.edges[t.edges[:, 0] == v, 1], t.edges[t.edges[:, 1] == v, 0]])
        l, lam[v] = limit_weights(loop_symmetric_matrix(len(nb)))
        out[v] = l[0] * X[v] + l[1] * X[nb].mean(axis=0)
    return out, lam


def test_loop_limit_points_and_exact_contraction():
    """Irregular (valence 5) and regular vertices of a perturbed icosphere: limit points
    from the eigen-analysis of the hand rules; vertex - limit shrinks by exactly
    lambda_2 = 5/8 - n beta(n) per level (the symmetric part is 2 x 2)."""
    mesh = perturbed(icosphere(1), 0.05, 6)
    ref, lam = loop_limit_reference(mesh)
    surf = SubdivisionSurface(mesh, "loop")
    np.testing.assert_allclose(surf.limit_points(), ref, atol=TOL)
    V0 = mesh.n_vertices
    prev = np.linalg.norm(mesh.vertices - ref, axis=1)
    for k in range(1, 7):
        err = np.linalg.norm(surf.refine(k).vertices[:V0] - ref, axis=1)
        np.testing.assert_allclose(err, lam * prev, rtol=1e-7, atol=1e-14)
        prev = err
    assert prev.max() < 4e-5  # measured 3.5e-5
    assert set(np.round(lam, 12)) == {0.25, round(5 / 8 - 5 * loop_beta(5), 12)}


def test_loop_limit_points_high_valence():
    mesh = perturbed(bipyramid(7), 0.05, 1)
    ref, lam = loop_limit_reference(mesh)
    assert set(mesh.valence.tolist()) == {4, 7}
    np.testing.assert_allclose(SubdivisionSurface(mesh, "loop").limit_points(), ref, atol=TOL)


def test_tetrahedron_closed_forms():
    """Regular tetrahedron centred at 0 (the three neighbours of v sum to -v).
    Loop: beta(3) = 3/16, weights (3 / (3 + 8 n beta), ...) = (2/5, 3/5): limit v / 5.
    Catmull-Clark: face points -v_opp / 3, edge points (a + b) / 3, vertex points 7/27 v;
    then the valence-3 weights (3, 4, 1) / 8 on (7/27 v, mean edge point 2/9 v, mean face
    point v / 9) give 2/9 v. Normals are v / |v| by symmetry, outward."""
    tet = tetrahedron()
    V = tet.vertices
    assert abs(loop_beta(3) - 3 / 16) < 1e-15
    np.testing.assert_allclose(SubdivisionSurface(tet, "loop").limit_points(), V / 5, atol=1e-15)
    np.testing.assert_allclose(SubdivisionSurface(tet, "catmull-clark").limit_points(), 2 * V / 9, atol=1e-15)
    once = subdivide(tet, "catmull-clark", 1).vertices
    np.testing.assert_allclose(once[:4], 7 * V / 27, atol=1e-15)
    for scheme in ("loop", "catmull-clark"):
        np.testing.assert_allclose(SubdivisionSurface(tet, scheme).limit_normals(), unit(V), atol=1e-14)


def test_loop_regular_torus_converges_4x():
    mesh = tri_torus(6, 5, 8)
    X = mesh.vertices
    surf = SubdivisionSurface(mesh, "loop")
    L = surf.limit_points()
    e = [np.linalg.norm(surf.refine(k).vertices[: len(X)] - L, axis=1) for k in range(0, 5)]
    for a, b in zip(e[:-1], e[1:]):
        np.testing.assert_allclose(b, a / 4, rtol=1e-8, atol=1e-15)


def test_loop_octahedron_closed_form():
    """Valence 4: beta = 31/256, limit = 3 / (3 + 8 n beta) v + ... = 24/55 v (the
    neighbours sum to 0); normals are the vertex directions by symmetry."""
    surf = SubdivisionSurface(octahedron(), "loop")
    V = octahedron().vertices
    np.testing.assert_allclose(surf.limit_points(), 24 / 55 * V, atol=1e-15)
    np.testing.assert_allclose(surf.limit_normals(), V, atol=1e-14)


# ---------------------------------------------------------------------------------------------
# 3. Catmull-Clark closed forms on the cube
# ---------------------------------------------------------------------------------------------
def test_cc_symmetric_matrix_gives_the_classical_mask():
    """The eigen-derived weights are (n v + 4 mean(e) + mean(d)) / (n + 5), i.e. the mask
    (n^2 v + 4 sum e + sum d) / (n (n + 5)); lambda_2 = 1/6 at n = 3, 1/4 at n = 4."""
    for n in range(3, 9):
        l, lam = limit_weights(cc_symmetric_matrix(n))
        np.testing.assert_allclose(l, np.array([n, 4, 1]) / (n + 5), atol=1e-13)
    assert abs(limit_weights(cc_symmetric_matrix(3))[1] - 1 / 6) < 1e-14
    assert abs(limit_weights(cc_symmetric_matrix(4))[1] - 1 / 4) < 1e-14


def test_cc_cube_corner_and_face_centre_closed_forms():
    """Corner: (9 v + 4 sum e + sum d) / 24 = -1/4 per coordinate. Face centre: after one
    step the face point (0, 0, -1/2) has edge neighbours (0, -3/8, -3/8) etc. and diagonals
    the vertex points (+-5/18, +-5/18, -5/18); the regular mask gives z = -34/81."""
    cube = box()
    surf = SubdivisionSurface(cube, "catmull-clark")
    V = cube.vertices
    np.testing.assert_allclose(surf.limit_points(), V / 2, atol=1e-15)
    # evaluate at every face corner is the corner's limit point
    t = cube.topology
    P, _, _, _ = surf.evaluate(t.corner_face, CORNER_UV[t.corner_index, 0], CORNER_UV[t.corner_index, 1])
    np.testing.assert_allclose(P, V[t.face_indices] / 2, atol=1e-15)
    # face centres
    P, Du, Dv, N = surf.evaluate(np.arange(6), 0.5, 0.5)
    centroid = np.array([V[f].mean(axis=0) for f in cube.faces])
    np.testing.assert_allclose(P, centroid * 2 * 34 / 81, atol=1e-15)
    np.testing.assert_allclose(N, centroid * 2, atol=1e-14)
    # the level-1 limit points of the face points say the same
    fine = SubdivisionSurface(subdivide(cube, "catmull-clark", 1), "catmull-clark").limit_points()
    np.testing.assert_allclose(fine[8 + 12 :], centroid * 2 * 34 / 81, atol=1e-15)


def test_cc_cube_refined_corners_converge_by_lambda2():
    """vertex - limit = 6^-(k+1) per coordinate after k levels: lambda_2(3) = 1/6 and the
    third symmetric eigenvalue is 0. After 6 levels: 6^-7 = 3.57e-6."""
    cube = box()
    limit = cube.vertices / 2
    lam = limit_weights(cc_symmetric_matrix(3))[1]
    for k in range(1, 7):
        Y = subdivide(cube, "catmull-clark", k).vertices[:8]
        np.testing.assert_allclose(np.abs(Y - limit), (1 / lam) ** -(k + 1), rtol=1e-9)
    assert np.abs(Y - limit).max() < 3.6e-6


def test_cc_limit_points_of_irregular_quad_meshes():
    """Valences 3 to 7 (a perturbed cube, a refined 7-bipyramid and the once-refined mixed
    mesh whose pentagon centres have valence 5): limit points from the eigen-derived weights."""
    for mesh in (perturbed(box(), 0.1, 1), subdivide(perturbed(bipyramid(7), 0.05, 1), "catmull-clark", 1),
                 subdivide(perturbed(mixed_mesh(), 0.1, 2), "catmull-clark", 1)):
        nb, dg = cc_rings(mesh)
        X = mesh.vertices
        ref = np.empty_like(X)
        for v in range(mesh.n_vertices):
            l, _ = limit_weights(cc_symmetric_matrix(len(nb[v])))
            ref[v] = l[0] * X[v] + l[1] * X[nb[v]].mean(axis=0) + l[2] * X[dg[v]].mean(axis=0)
        np.testing.assert_allclose(SubdivisionSurface(mesh, "catmull-clark").limit_points(), ref, atol=TOL)
    assert set(mesh.valence.tolist()) == {3, 4, 5}


def test_cc_mixed_mesh_limit_is_limit_of_first_refinement():
    mesh = perturbed(mixed_mesh(), 0.1, 3)
    once = subdivide(mesh, "catmull-clark", 1)
    a = SubdivisionSurface(mesh, "catmull-clark").limit_points()
    b = SubdivisionSurface(once, "catmull-clark").limit_points()[: mesh.n_vertices]
    np.testing.assert_allclose(a, b, atol=TOL)


def dyadic_corners(t_levels, face, levels):
    """(vertex, u, v): every corner of the level-``levels`` quads inside base ``face`` with its
    parameters in the base face (child quad c of quad q is q's corner c; its corners are
    corner c, the midpoint of edge c, the centre and the midpoint of edge c - 1)."""
    quads = [(face, CORNER_UV.copy())]
    for _ in range(levels):
        new = []
        for q, P in quads:
            for c in range(4):
                Q = np.array([P[c], (P[c] + P[(c + 1) % 4]) / 2, P.mean(axis=0), (P[c] + P[(c - 1) % 4]) / 2])
                new.append((4 * q + c, Q))
        quads = new
    t = t_levels[levels]
    out = {}
    for q, P in quads:
        for c in range(4):
            out[int(t.face_indices[4 * q + c])] = P[c]
    verts = np.array(sorted(out))
    uv = np.array([out[v] for v in verts])
    return verts, uv


@pytest.mark.parametrize("mesh,base", [(perturbed(box(), 0.08, 4), 0), (perturbed(mixed_mesh(), 0.08, 4), 1)])
def test_cc_evaluate_descends_to_the_limit_at_dyadic_points(mesh, base):
    """On the perturbed cube (every face irregular) and the mixed mesh (faces = the quads
    of its first refinement, one per corner) ``evaluate`` at the corners of the quads
    three levels down equals the limit points of that level's mesh."""
    surf = SubdivisionSurface(mesh, "catmull-clark")
    r = Refinement(mesh, "catmull-clark", base + 3)
    fine = SubdivisionSurface(r.mesh(mesh.vertices), "catmull-clark").limit_points()
    for face in range(r.topologies[base].n_faces):
        verts, uv = dyadic_corners(r.topologies[base:], face, 3)
        P, _, _, _ = surf.evaluate(face, uv[:, 0], uv[:, 1])
        np.testing.assert_allclose(P, fine[verts], atol=TOL)


def test_cc_evaluate_derivatives_are_derivatives():
    """Central differences of the evaluated points away from the extraordinary corners
    match du, dv (checks the quadrant Jacobians of the descent)."""
    mesh = perturbed(box(), 0.08, 5)
    surf = SubdivisionSurface(mesh, "catmull-clark")
    rng = np.random.default_rng(0)
    face = np.repeat(np.arange(6), 20)
    u, v = 0.1 + 0.8 * rng.random(face.size), 0.1 + 0.8 * rng.random(face.size)
    h = 1e-6
    P, Du, Dv, _ = surf.evaluate(face, u, v)
    fd_u = (surf.evaluate(face, u + h, v)[0] - surf.evaluate(face, u - h, v)[0]) / (2 * h)
    fd_v = (surf.evaluate(face, u, v + h)[0] - surf.evaluate(face, u, v - h)[0]) / (2 * h)
    np.testing.assert_allclose(Du, fd_u, atol=1e-7)
    np.testing.assert_allclose(Dv, fd_v, atol=1e-7)


# ---------------------------------------------------------------------------------------------
# 4. counts and topology
# ---------------------------------------------------------------------------------------------
CLOSED_CASES = [
    ("catmull-clark", "cube"), ("catmull-clark", "torus"), ("catmull-clark", "icosphere"), ("catmull-clark", "mixed"),
    ("doo-sabin", "cube"), ("doo-sabin", "torus"), ("doo-sabin", "icosphere"), ("doo-sabin", "mixed"),
    ("loop", "icosphere"), ("loop", "octahedron"), ("loop", "tri-torus"),
]
MESHES = {
    "cube": lambda: box(),
    "torus": lambda: torus(5, 4),
    "icosphere": lambda: icosphere(0),
    "mixed": mixed_mesh,
    "octahedron": octahedron,
    "tri-torus": lambda: tri_torus(5, 4, 0, 0.0),
    "grid": lambda: bumpy_grid(3, 2, 0),
    "tri-grid": lambda: tri_grid(3, 2, 0),
}


def check_topology(t):
    """Rebuild from the faces with full validation (orientation included) and compare the
    refined edge tables with the rebuilt ones."""
    f = fresh(t)
    assert {tuple(e) for e in t.edges.tolist()} == {tuple(e) for e in f.edges.tolist()}
    assert len(t.edges) == len(f.edges)
    assert (t.edges[:, 0] < t.edges[:, 1]).all()
    src, dst = t.face_indices, t.halfedge_dst
    np.testing.assert_array_equal(t.edges[t.halfedge_edge], np.column_stack([np.minimum(src, dst), np.maximum(src, dst)]))
    np.testing.assert_array_equal(t.twin, f.twin)
    np.testing.assert_array_equal(t.boundary_edges[t.halfedge_edge], f.boundary_edges[f.halfedge_edge])
    np.testing.assert_array_equal(t.boundary_vertices, f.boundary_vertices)
    np.testing.assert_array_equal(t.valence, f.valence)
    return f


@pytest.mark.parametrize("scheme,name", CLOSED_CASES)
def test_euler_characteristic_and_counts_closed(scheme, name):
    mesh = MESHES[name]()
    r = Refinement(mesh, scheme, 3)
    chi = mesh.euler_characteristic
    for k in range(1, 4):
        parent, child = r.topologies[k - 1], r.topologies[k]
        check_topology(child)
        assert child.is_closed
        assert child.euler_characteristic == chi
        assert r.stencils[k - 1].shape == (child.n_vertices, parent.n_vertices)
        V, E, F, H = parent.n_vertices, parent.n_edges, parent.n_faces, parent.n_halfedges
        if scheme == "catmull-clark":
            assert (child.n_vertices, child.n_faces, child.n_edges) == (V + E + F, H, 2 * E + H)
            assert (child.face_sizes == 4).all()
        elif scheme == "loop":
            assert (child.n_vertices, child.n_faces, child.n_edges) == (V + E, 4 * F, 2 * E + 3 * F)
            assert (child.face_sizes == 3).all()
        else:
            assert (child.n_vertices, child.n_faces, child.n_edges) == (H, F + E + V, 2 * E * 2)
    assert r.topology is r.topologies[-1] and r.levels == 3


@pytest.mark.parametrize("scheme,name", [("catmull-clark", "grid"), ("doo-sabin", "grid"), ("loop", "tri-grid"),
                                         ("catmull-clark", "tri-grid"), ("doo-sabin", "tri-grid")])
def test_euler_characteristic_open(scheme, name):
    mesh = MESHES[name]()
    r = Refinement(mesh, scheme, 3)
    for t in r.topologies[1:]:
        check_topology(t)
        assert t.euler_characteristic == 1
        assert not t.is_closed


def test_doo_sabin_open_face_count():
    mesh = bumpy_grid(3, 2, 0)
    t = mesh.topology
    child = Refinement(mesh, "doo-sabin", 1).topology
    interior_edges = int((~t.boundary_edges).sum())
    fan = int((t.vertex_face_count >= 3).sum())
    assert child.n_faces == t.n_faces + interior_edges + fan == 6 + 7 + 2
    assert child.n_vertices == t.n_halfedges


def test_cc_first_level_face_count_is_sum_of_face_sizes():
    mesh = mixed_mesh()
    assert subdivide(mesh, "catmull-clark", 1).n_faces == int(mesh.topology.face_sizes.sum()) == 32
    assert subdivide(mesh, "catmull-clark", 3).n_faces == 32 * 16
    assert subdivide(icosphere(0), "loop", 2).n_faces == 20 * 16


def test_subdivision_matrix_matches_refinement():
    mesh = mixed_mesh()
    t, S = subdivision_matrix(mesh, "catmull-clark", 2)
    r = Refinement(mesh, "catmull-clark", 2)
    np.testing.assert_array_equal(t.face_indices, r.topology.face_indices)
    assert abs(S - r.stencils[1] @ r.stencils[0]).max() < 1e-15


# ---------------------------------------------------------------------------------------------
# 5. creases, corners, boundaries
# ---------------------------------------------------------------------------------------------
def torus_ring(nu, nv, j0=0):
    ring = np.arange(nu) * nv + j0
    return ring, {(int(a), int(b)): np.inf for a, b in zip(ring, np.roll(ring, -1))}


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_sharp_crease_loop_is_cubic_bspline(scheme):
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 2) if scheme == "catmull-clark" else tri_torus(nu, nv, 2)
    ring, creases = torus_ring(nu, nv)
    X = mesh.vertices
    curve = periodic_cubic_curve(X[ring])
    levels = 4
    r = Refinement(mesh, scheme, levels, creases=creases)
    chain = ring
    chains = [ring]
    for k in range(levels):
        chain = refine_chain(r.topologies[k], chain, closed=True)
        chains.append(chain)
    Y = r.apply(X)
    # the level-k crease polygon is the control polygon of the same curve on knots 2^-k apart
    fine = periodic_cubic_curve(Y[chains[-1]], 2.0**-levels)
    s = 1 + np.linspace(0, nu - 1, 200)
    np.testing.assert_allclose(fine.evaluate(s), curve.evaluate(s), atol=TOL)
    # limit points of the crease vertices: (a + 4 v + b) / 6 = the curve at the vertex parameters
    L = SubdivisionSurface(mesh, scheme, creases=creases).limit_points()
    a, b = X[np.roll(ring, 1)], X[np.roll(ring, -1)]
    np.testing.assert_allclose(L[ring], (a + 4 * X[ring] + b) / 6, atol=TOL)
    params = np.where(np.arange(nu) == 0, nu, np.arange(nu)).astype(float)
    np.testing.assert_allclose(L[ring], curve.evaluate(params), atol=TOL)
    # refined crease vertices approach the curve at their dyadic parameters, 4x per level
    err = []
    for k in range(1, levels + 1):
        rk = Refinement(mesh, scheme, k, creases=creases)
        pts = rk.apply(X)[chains[k]]
        h = 2.0**-k
        par = np.arange(len(chains[k])) * h
        par = np.where(par < 1, par + nu, par)  # the curve's domain is [1, nu + 1]
        err.append(np.abs(pts - curve.evaluate(par)).max())
    ratios = np.array(err[:-1]) / np.array(err[1:])
    np.testing.assert_allclose(ratios, 4, rtol=1e-9)


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
@pytest.mark.parametrize("s", [1, 2, 3])
def test_semi_sharp_crease_is_sharp_for_s_levels(scheme, s):
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 2) if scheme == "catmull-clark" else tri_torus(nu, nv, 2)
    ring, sharp = torus_ring(nu, nv)
    semi = {k: float(s) for k in sharp}
    a = Refinement(mesh, scheme, s + 1, creases=semi)
    b = Refinement(mesh, scheme, s + 1, creases=sharp)
    c = Refinement(mesh, scheme, s + 1)
    for k in range(s):
        assert abs(a.stencils[k] - b.stencils[k]).max() == 0
    # then the crease has expired: exactly the smooth rules (the rule change at level s - 1
    # has parent sharpness 1, so the vertex blend weight is 1 = the crease rule)
    assert abs(a.stencils[s] - c.stencils[s]).max() == 0
    assert abs(a.stencils[s] - b.stencils[s]).max() > 0.05
    # after the crease expired, the edges are smooth
    assert (a.edge_sharpness[s + 1] == 0).all()
    assert np.isinf(b.edge_sharpness[s + 1]).sum() == nu * 2 ** (s + 1)


def test_fractional_crease_blends_rules():
    """Sharpness 0.5: the edge point is the 50/50 blend of the smooth rule
    (v0 + v1 + f0 + f1) / 4 and the midpoint; the crease vertex the 50/50 blend of the
    smooth rule and the crease rule 3/4 v + 1/8 (a + b) (rule changes, weight = sharpness)."""
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 3, scale=0.05)
    X = mesh.vertices
    t = mesh.topology
    ring, sharp = torus_ring(nu, nv)
    half = {k: 0.5 for k in sharp}
    Y = subdivide(mesh, "catmull-clark", 1, creases=half).vertices
    pairs = np.array(list(sharp))
    e = np.array([edge_index(t)[(min(p), max(p))] for p in pairs.tolist()])
    centroid = np.array([X[f].mean(axis=0) for f in mesh.faces])
    ef = t.edge_faces[e]
    smooth_e = (X[pairs[:, 0]] + X[pairs[:, 1]] + centroid[ef[:, 0]] + centroid[ef[:, 1]]) / 4
    sharp_e = (X[pairs[:, 0]] + X[pairs[:, 1]]) / 2
    np.testing.assert_allclose(Y[t.n_vertices + e], (smooth_e + sharp_e) / 2, atol=TOL)
    nb, _ = cc_rings(mesh)
    for i, v in enumerate(ring):
        faces_v = [f for f in range(t.n_faces) if v in mesh.faces[f]]
        n = len(nb[v])
        smooth_v = (n - 2) / n * X[v] + X[nb[v]].sum(axis=0) / n**2 + centroid[faces_v].sum(axis=0) / n**2
        crease_v = 0.75 * X[v] + (X[ring[i - 1]] + X[ring[(i + 1) % nu]]) / 8
        np.testing.assert_allclose(Y[v], (smooth_v + crease_v) / 2, atol=TOL)


def test_cc_evaluate_along_a_sharp_crease():
    """Faces along a sharp crease never become regular: ``evaluate`` uses the bilinear
    fallback, exact at dyadic parameters and within 4^-level of the crease's cubic
    B-spline elsewhere (measured 5.0e-3 at max_level 3, about 4x less per level,
    1.9e-5 at the level cap of this 24-face mesh, 7)."""
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 2)
    ring, sharp = torus_ring(nu, nv)
    curve = periodic_cubic_curve(mesh.vertices[ring])
    surf = SubdivisionSurface(mesh, "catmull-clark", creases=sharp)
    face = np.repeat(np.arange(nu) * nv, 9)  # face (i, 0): its first edge runs ring[i] -> ring[i + 1]
    u = np.tile(np.linspace(0, 1, 9), nu)
    i = face // nv
    ref = curve.evaluate(np.where(i == 0, nu, i) + u)
    P = surf.evaluate(face, u, 0 * u, max_level=3)[0]
    np.testing.assert_allclose(P, ref, atol=1e-14)  # u = k / 8: corners of level-3 sub-faces
    w = np.tile(np.linspace(0.05, 0.95, 7), nu)
    face = np.repeat(np.arange(nu) * nv, 7)
    ref = curve.evaluate(np.where(face == 0, nu, face // nv) + w)
    errs = [np.abs(surf.evaluate(face, w, 0 * w, max_level=ml)[0] - ref).max() for ml in (3, 4, 5, 6)]
    # second order in the sub-face size: measured 5.0e-3, 1.1e-3, 3.1e-4, 6.9e-5
    assert all(e < 6e-3 * 4.0**-k for k, e in enumerate(errs)), errs
    assert errs[0] / errs[-1] > 50
    assert np.abs(surf.evaluate(face, w, 0 * w)[0] - ref).max() < 2.5e-5


def test_fractional_crease_lies_between_smooth_and_sharp():
    """The ring at the outer equator is a ridge: its refined radius grows with sharpness."""
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 3, scale=0.05)
    ring, sharp = torus_ring(nu, nv, j0=0)
    radius = {}
    for s in (0.0, 0.5, 1.0, np.inf):
        Y = subdivide(mesh, "catmull-clark", 3, creases={k: s for k in sharp}).vertices
        radius[s] = np.linalg.norm(Y[ring, :2], axis=1)
        L = SubdivisionSurface(mesh, "catmull-clark", creases={k: s for k in sharp}).limit_points()
        radius[("limit", s)] = np.linalg.norm(L[ring, :2], axis=1)
    for key in (lambda s: s, lambda s: ("limit", s)):
        assert (radius[key(0.0)] < radius[key(0.5)]).all()
        assert (radius[key(0.5)] < radius[key(1.0)]).all()
        assert (radius[key(1.0)] < radius[key(np.inf)]).all()


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
@pytest.mark.parametrize("m", [0, 1, 2])
def test_fractional_sharpness_blends_one_level(scheme, m):
    """Sharpness m + 1/4: m levels of the sharp rules, then one level whose stencil is
    exactly 1/4 sharp + 3/4 smooth (edges by their sharpness, crease vertices by the
    average sharpness of their fading edges), then the smooth rules."""
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 2) if scheme == "catmull-clark" else tri_torus(nu, nv, 2)
    _, sharp = torus_ring(nu, nv)

    def R(s):
        return Refinement(mesh, scheme, m + 2, creases={k: s for k in sharp})

    frac, inf, smooth = R(m + 0.25), R(np.inf), R(float(m))
    for k in range(m):
        assert abs(frac.stencils[k] - inf.stencils[k]).max() == 0
    assert abs(frac.stencils[m] - (0.25 * inf.stencils[m] + 0.75 * smooth.stencils[m])).max() < 1e-15
    assert abs(frac.stencils[m] - smooth.stencils[m]).max() > 0.01
    assert abs(frac.stencils[m + 1] - smooth.stencils[m + 1]).max() == 0


@pytest.mark.parametrize("scheme,mesh,on_surface", [
    ("catmull-clark", box(), lambda Y: np.abs(np.abs(Y).max(axis=1) - 0.5)),
    ("doo-sabin", box(), lambda Y: np.abs(np.abs(Y).max(axis=1) - 0.5)),
    ("loop", octahedron(), lambda Y: np.abs(np.abs(Y).sum(axis=1) - 1)),
    ("doo-sabin", octahedron(), lambda Y: np.abs(np.abs(Y).sum(axis=1) - 1)),
])
def test_all_edges_sharp_keeps_the_polyhedron(scheme, mesh, on_surface):
    """Every edge infinitely sharp: vertices with three or more sharp edges are corners,
    edges are straight crease curves and every face stays planar: the limit is the
    polyhedron (|x|_inf = 1/2 for the cube, |x|_1 = 1 for the octahedron)."""
    creases = {tuple(e): np.inf for e in mesh.edges.tolist()}
    Y = subdivide(mesh, scheme, 3, creases=creases).vertices
    assert on_surface(Y).max() < 1e-15
    if scheme != "doo-sabin":
        assert on_surface(SubdivisionSurface(mesh, scheme, creases=creases).limit_points()).max() < 1e-15


def chaikin(P):
    """One closed Chaikin step: 3/4 p + 1/4 q and 1/4 p + 3/4 q on every edge (p, q)."""
    Q = np.empty((2 * len(P), P.shape[1]))
    Pn = np.roll(P, -1, axis=0)
    Q[0::2] = 0.75 * P + 0.25 * Pn
    Q[1::2] = 0.25 * P + 0.75 * Pn
    return Q


def contains_points(Y, P, tol=1e-14):
    return np.linalg.norm(P[:, None, :] - Y[None, :, :], axis=2).min(axis=1).max() < tol


def test_doo_sabin_crease_and_closed_boundary_are_chaikin():
    """A sharp ring of the torus and the two boundary loops of an open tube (every
    boundary vertex with two faces) refine as Chaikin's corner cutting, so they converge
    to the quadratic B-spline of their polygon."""
    nu, nv = 6, 4
    mesh = quad_torus(nu, nv, 2, scale=0.05)
    ring, sharp = torus_ring(nu, nv)
    P = mesh.vertices[ring]
    for k in range(1, 4):
        P = chaikin(P)
        assert contains_points(subdivide(mesh, "doo-sabin", k, creases=sharp).vertices, P)
    faces = mesh.faces[np.arange(nu * nv) % nv != nv - 1]
    tube = PolyMesh(mesh.vertices, faces)
    loops = [np.arange(nu) * nv, np.arange(nu) * nv + nv - 1]
    assert tube.boundary_vertices.sum() == 2 * nu
    Ps = [tube.vertices[lp] for lp in loops]
    for k in range(1, 4):
        Ps = [chaikin(P) for P in Ps]
        r = Refinement(tube, "doo-sabin", k)
        Y = r.apply(tube.vertices)
        bnd = Y[r.topology.boundary_vertices]
        assert len(bnd) == 2 * nu * 2**k
        for P in Ps:
            assert contains_points(bnd, P)


@pytest.mark.parametrize("scheme,mesh", [("catmull-clark", perturbed(box(), 0.1, 0)),
                                         ("loop", perturbed(icosphere(1), 0.05, 0)),
                                         ("catmull-clark", perturbed(mixed_mesh(), 0.1, 0))])
def test_infinitely_sharp_corners_stay(scheme, mesh):
    X = mesh.vertices
    corners = {0: np.inf, 3: np.inf}
    r = Refinement(mesh, scheme, 4, corners=corners)
    Y = r.apply(X)
    np.testing.assert_array_equal(Y[[0, 3]], X[[0, 3]])
    for k in range(1, 5):
        np.testing.assert_array_equal(r.stencils[k - 1][[0, 3]].toarray(), np.eye(r.topologies[k - 1].n_vertices)[[0, 3]])
    np.testing.assert_array_equal(SubdivisionSurface(mesh, scheme, corners=corners).limit_points()[[0, 3]], X[[0, 3]])
    assert np.abs(subdivide(mesh, scheme, 1).vertices[[0, 3]] - X[[0, 3]]).min() > 1e-3


@pytest.mark.parametrize("scheme,mesh", [("catmull-clark", perturbed(box(), 0.1, 1)),
                                         ("loop", perturbed(icosphere(0), 0.05, 1))])
def test_semi_sharp_corner_holds_for_its_levels(scheme, mesh):
    """Vertex sharpness 2 decays like edge sharpness (2, 1, 0): the corner rule for two
    levels, then the smooth rule (DeRose et al. 1998; OpenSubdiv)."""
    r = Refinement(mesh, scheme, 3, corners={0: 2.0})
    smooth = Refinement(mesh, scheme, 3)
    for k in range(2):
        row = r.stencils[k][0].toarray().ravel()
        np.testing.assert_array_equal(row, np.eye(len(row))[0])
    assert [float(vs[0]) for vs in r.vertex_sharpness] == [2.0, 1.0, 0.0, 0.0]
    np.testing.assert_array_equal(r.stencils[2][0].toarray(), smooth.stencils[2][0].toarray())


def test_doo_sabin_sharp_corner_is_on_the_surface():
    """A sharp vertex keeps every child corner at the vertex, so the degenerate vertex
    face reproduces it at every later level."""
    mesh = perturbed(box(), 0.1, 2)
    Y = subdivide(mesh, "doo-sabin", 4, corners={0: np.inf}).vertices
    assert np.linalg.norm(Y - mesh.vertices[0], axis=1).min() < 1e-14
    Y = subdivide(mesh, "doo-sabin", 4).vertices
    assert np.linalg.norm(Y - mesh.vertices[0], axis=1).min() > 1e-2


def test_cc_boundary_modes_on_grid_corners():
    nx, ny = 4, 3
    mesh = bumpy_grid(nx, ny, 4)
    X = mesh.vertices
    loop, sides, corners = grid_boundary(nx, ny)
    Y = subdivide(mesh, "catmull-clark", 3).vertices
    np.testing.assert_array_equal(Y[corners], X[corners])
    np.testing.assert_array_equal(SubdivisionSurface(mesh, "catmull-clark").limit_points()[corners], X[corners])
    # edge-only: corners follow the crease rule 3/4 v + 1/8 (a + b) along the boundary
    Y = subdivide(mesh, "catmull-clark", 1, boundary="edge-only").vertices
    pos = [int(np.flatnonzero(loop == c)[0]) for c in corners]
    a, b = X[loop[[p - 1 for p in pos]]], X[loop[[(p + 1) % len(loop) for p in pos]]]
    np.testing.assert_allclose(Y[corners], 0.75 * X[corners] + (a + b) / 8, atol=TOL)
    assert np.linalg.norm(Y[corners] - X[corners], axis=1).min() > 1e-3


def test_loop_boundary_modes_on_grid_corners():
    """Triangulated grid: two corners have one triangle (interpolated with
    edge-and-corner), two have two triangles (boundary crease vertices in both modes)."""
    nx, ny = 4, 3
    mesh = tri_grid(nx, ny, 4)
    X = mesh.vertices
    _, _, corners = grid_boundary(nx, ny)
    single = corners[mesh.topology.vertex_face_count[corners] == 1]
    double = corners[mesh.topology.vertex_face_count[corners] == 2]
    assert len(single) == len(double) == 2
    Y = subdivide(mesh, "loop", 2).vertices
    np.testing.assert_array_equal(Y[single], X[single])
    assert np.linalg.norm(Y[double] - X[double], axis=1).min() > 1e-3
    Y = subdivide(mesh, "loop", 2, boundary="edge-only").vertices
    assert np.linalg.norm(Y[corners] - X[corners], axis=1).min() > 1e-3


def boundary_case(scheme):
    nx, ny = 4, 3
    mesh = bumpy_grid(nx, ny, 9) if scheme == "catmull-clark" else tri_grid(nx, ny, 9)
    return mesh, grid_boundary(nx, ny)


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_open_boundary_edge_only_is_closed_cubic_bspline(scheme):
    mesh, (loop, _, _) = boundary_case(scheme)
    X = mesh.vertices
    levels = 3
    r = Refinement(mesh, scheme, levels, boundary="edge-only")
    chain = loop
    for k in range(levels):
        chain = refine_chain(r.topologies[k], chain, closed=True)
    Y = r.apply(X)
    curve = periodic_cubic_curve(X[loop])
    fine = periodic_cubic_curve(Y[chain], 2.0**-levels)
    s = 1 + np.linspace(0, len(loop) - 1, 300)
    np.testing.assert_allclose(fine.evaluate(s), curve.evaluate(s), atol=TOL)
    L = SubdivisionSurface(mesh, scheme, boundary="edge-only").limit_points()
    par = np.arange(len(loop), dtype=float)
    par[0] = len(loop)
    np.testing.assert_allclose(L[loop], curve.evaluate(par), atol=TOL)


def split_at(loop, fixed):
    """The closed vertex loop cut into chains running from one fixed vertex to the next."""
    pos = sorted(int(np.flatnonzero(loop == f)[0]) for f in fixed)
    rolled = np.roll(loop, -pos[0])
    cuts = [p - pos[0] for p in pos] + [len(loop)]
    return [np.append(rolled[a:b], rolled[b % len(loop)]) for a, b in zip(cuts[:-1], cuts[1:])]


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_open_boundary_edge_and_corner_is_natural_cubic(scheme):
    """With the single-face corners interpolated, the boundary between two of them is the
    cubic B-spline of that chain with the phantom end points 2 P0 - P1 (the corner stays,
    the next vertex follows the crease rule = the uniform rule on the extended polygon).
    For CC these are the four sides; for the triangulated grid two corners have two
    triangles and are ordinary boundary (crease) vertices."""
    mesh, (loop, _, corners) = boundary_case(scheme)
    X = mesh.vertices
    fixed = corners[mesh.topology.vertex_face_count[corners] == 1]
    chains0 = split_at(loop, fixed)
    assert len(chains0) == (4 if scheme == "catmull-clark" else 2)
    levels = 3
    r = Refinement(mesh, scheme, levels)
    Y = r.apply(X)
    L = SubdivisionSurface(mesh, scheme).limit_points()
    for side in chains0:
        chain = side
        for k in range(levels):
            chain = refine_chain(r.topologies[k], chain, closed=False)
        curve = natural_cubic_curve(X[side])
        fine = natural_cubic_curve(Y[chain], 2.0**-levels)
        s = np.linspace(0, len(side) - 1, 200)
        np.testing.assert_allclose(fine.evaluate(s), curve.evaluate(s), atol=TOL)
        np.testing.assert_allclose(L[side], curve.evaluate(np.arange(len(side), dtype=float)), atol=TOL)


def affine_grid(nx, ny, seed, triangulate=False):
    """A planar uniform grid under a random affine map into 3-D: every rule reproduces
    affine functions on the regular lattice (and the boundary/corner rules on its
    border), so the limit surface is the affine image of the parameter plane."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((3, 2))
    b = rng.standard_normal(3)
    g = grid(nx, ny, size=(nx, ny))
    F = g.faces
    if triangulate:
        F = np.concatenate([F[:, [0, 1, 2]], F[:, [0, 2, 3]]])
    return PolyMesh(g.vertices[:, :2] @ A.T + b, F), A, b


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_flat_affine_grid_limit_is_the_plane(scheme):
    mesh, A, b = affine_grid(4, 3, 0, triangulate=scheme == "loop")
    # the triangulated grid has two corners with two triangles: boundary crease vertices
    # whose limit cuts the corner, (a + 4 v + b) / 6; make them sharp to keep the plane's
    # own border
    _, _, corners = grid_boundary(4, 3)
    double = corners[mesh.topology.vertex_face_count[corners] == 2]
    assert len(double) == (2 if scheme == "loop" else 0)
    surf = SubdivisionSurface(mesh, scheme, corners={int(c): np.inf for c in double})
    np.testing.assert_allclose(surf.limit_points(), mesh.vertices, atol=TOL)
    n = unit(np.cross(A[:, 0], A[:, 1]))  # grid normals are +z before the map
    np.testing.assert_allclose(surf.limit_normals(), np.tile(n, (mesh.n_vertices, 1)), atol=1e-12)


def test_cc_flat_affine_grid_evaluate_and_patches():
    """Closed form on an open mesh: face (i, j) of the affine grid at (u, v) is
    A (i + u, j + v) + b with du = A e1, dv = A e2, including the boundary faces
    (fallback) and the Coons patches of to_bsplines."""
    nx, ny = 4, 3
    mesh, A, b = affine_grid(nx, ny, 1)
    surf = SubdivisionSurface(mesh, "catmull-clark")
    rng = np.random.default_rng(2)
    face = np.repeat(np.arange(nx * ny), 6)
    u, v = rng.random(face.size), rng.random(face.size)
    i, j = face // ny, face % ny
    P, Du, Dv, N = surf.evaluate(face, u, v)
    np.testing.assert_allclose(P, np.column_stack([i + u, j + v]) @ A.T + b, atol=1e-12)
    np.testing.assert_allclose(Du, np.tile(A[:, 0], (face.size, 1)), atol=1e-11)
    np.testing.assert_allclose(Dv, np.tile(A[:, 1], (face.size, 1)), atol=1e-11)
    patches, info = surf.to_bsplines(2)
    assert info["approximate"] > 0
    assert info["max_deviation"] < 1e-12
    g = np.linspace(0, 1, 5)
    s, t = [a.ravel() for a in np.meshgrid(g, g, indexing="ij")]
    for k, patch in enumerate(patches):
        f = int(info["face"][k])
        uv = np.column_stack([s, t]) @ info["axes"][k].T + info["origin"][k]
        ref = np.column_stack([f // ny + uv[:, 0], f % ny + uv[:, 1]]) @ A.T + b
        np.testing.assert_allclose(patch.evaluate(s, t), ref, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# 6. stencils
# ---------------------------------------------------------------------------------------------
STENCIL_CASES = [
    ("catmull-clark", lambda: perturbed(mixed_mesh(), 0.1, 0), {(0, 1): 2.5, (5, 6): np.inf}, {7: 1.5}, "edge-and-corner"),
    ("catmull-clark", lambda: bumpy_grid(3, 3, 1), {(5, 6): 0.5}, None, "edge-only"),
    ("loop", lambda: perturbed(icosphere(1), 0.05, 1), {tuple(icosphere(1).edges[5].tolist()): 1.3}, {3: np.inf}, "edge-and-corner"),
    ("loop", lambda: tri_grid(3, 3, 2), None, None, "edge-and-corner"),
    ("doo-sabin", lambda: perturbed(mixed_mesh(), 0.1, 3), {(0, 1): 1.5}, {7: np.inf}, "edge-and-corner"),
    ("doo-sabin", lambda: bumpy_grid(3, 3, 1), None, None, "edge-only"),
]


@pytest.mark.parametrize("scheme,make,creases,corners,boundary", STENCIL_CASES)
def test_stencils_apply_and_affine_invariance(scheme, make, creases, corners, boundary):
    mesh = make()
    r = Refinement(mesh, scheme, 3, creases=creases, corners=corners, boundary=boundary)
    for S in r.stencils + [r.matrix]:
        np.testing.assert_allclose(np.asarray(S.sum(axis=1)).ravel(), 1.0, atol=1e-13)
    rng = np.random.default_rng(0)
    V0 = mesh.n_vertices
    data = rng.standard_normal((V0, 7))  # positions, rgb, uv
    M = r.matrix
    np.testing.assert_allclose(r.apply(data), M @ data, atol=1e-12)
    np.testing.assert_allclose(r.apply(data, composed=True), M @ data, atol=1e-12)
    np.testing.assert_allclose(r.apply(data[:, 0]), M @ data[:, 0], atol=1e-12)
    frames = rng.standard_normal((V0, 2, 3))  # any trailing shape
    np.testing.assert_allclose(r.apply(frames), (M @ frames.reshape(V0, 6)).reshape(-1, 2, 3), atol=1e-12)
    # channels are independent: refining columns separately is refining them together
    np.testing.assert_allclose(np.column_stack([r.apply(data[:, k]) for k in range(7)]), r.apply(data), atol=1e-12)
    # rigid motion + scaling commutes with subdivision
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    q[:, 0] *= np.sign(np.linalg.det(q))  # a rotation (a reflection would flip the normals)
    A = 1.7 * q
    b = np.array([3.0, -1.0, 2.0])
    X = mesh.vertices
    moved = PolyMesh(X @ A.T + b, mesh.faces)
    out = subdivide(moved, scheme, 3, creases=creases, corners=corners, boundary=boundary)
    ref = subdivide(mesh, scheme, 3, creases=creases, corners=corners, boundary=boundary)
    np.testing.assert_allclose(out.vertices, ref.vertices @ A.T + b, atol=1e-11)
    np.testing.assert_array_equal(out.face_indices, ref.face_indices)
    if scheme != "doo-sabin":
        sa = SubdivisionSurface(moved, scheme, creases=creases, corners=corners, boundary=boundary)
        sb = SubdivisionSurface(mesh, scheme, creases=creases, corners=corners, boundary=boundary)
        np.testing.assert_allclose(sa.limit_points(), sb.limit_points() @ A.T + b, atol=1e-11)
        np.testing.assert_allclose(np.asarray(sb.limit_stencil.sum(axis=1)).ravel(), 1.0, atol=1e-13)
        np.testing.assert_allclose(sa.limit_normals(), sb.limit_normals() @ q.T, atol=1e-9)


@FEW
@given(seed=st.integers(0, 2**31), shift=st.tuples(*[st.floats(-100, 100)] * 3))
def test_cc_evaluate_commutes_with_translation(seed, shift):
    mesh = perturbed(box(), 0.1, seed)
    moved = PolyMesh(mesh.vertices + np.array(shift), mesh.faces)
    rng = np.random.default_rng(seed)
    f, u, v = rng.integers(0, 6, 10), rng.random(10), rng.random(10)
    a = SubdivisionSurface(mesh, "catmull-clark").evaluate(f, u, v)
    b = SubdivisionSurface(moved, "catmull-clark").evaluate(f, u, v)
    np.testing.assert_allclose(b[0], a[0] + np.array(shift), atol=1e-12 * (1 + np.abs(shift).max()))
    np.testing.assert_allclose(b[1], a[1], atol=1e-9)
    np.testing.assert_allclose(b[2], a[2], atol=1e-9)


def test_stencils_by_hand_on_one_level():
    """Catmull-Clark and Loop rows for one vertex, edge and face of small meshes."""
    cube = perturbed(box(), 0.1, 6)
    X = cube.vertices
    t = cube.topology
    Y = subdivide(cube, "catmull-clark", 1).vertices
    centroid = np.array([X[f].mean(axis=0) for f in cube.faces])
    np.testing.assert_allclose(Y[8 + 12 :], centroid, atol=TOL)
    for e, (a, b) in enumerate(t.edges):
        f0, f1 = t.edge_faces[e]
        np.testing.assert_allclose(Y[8 + e], (X[a] + X[b] + centroid[f0] + centroid[f1]) / 4, atol=TOL)
    nb, _ = cc_rings(cube)
    for v in range(8):
        fs = [f for f in range(6) if v in cube.faces[f]]
        np.testing.assert_allclose(Y[v], X[v] / 3 + X[nb[v]].sum(axis=0) / 9 + centroid[fs].sum(axis=0) / 9, atol=TOL)
    ico = perturbed(icosphere(0), 0.05, 6)
    X = ico.vertices
    t = ico.topology
    Y = subdivide(ico, "loop", 1).vertices
    for e, (a, b) in enumerate(t.edges):
        opp = [int(np.setdiff1d(ico.faces[f], [a, b])[0]) for f in t.edge_faces[e]]
        np.testing.assert_allclose(Y[12 + e], 3 / 8 * (X[a] + X[b]) + (X[opp[0]] + X[opp[1]]) / 8, atol=TOL)
    beta = loop_beta(5)
    for v in range(12):
        nbv = np.concatenate([t.edges[t.edges[:, 0] == v, 1], t.edges[t.edges[:, 1] == v, 0]])
        np.testing.assert_allclose(Y[v], (1 - 5 * beta) * X[v] + beta * X[nbv].sum(axis=0), atol=TOL)


# ---------------------------------------------------------------------------------------------
# 7. limit normals
# ---------------------------------------------------------------------------------------------
def test_cc_cube_normals_closed_form_and_outward():
    cube = box()
    N = SubdivisionSurface(cube, "catmull-clark").limit_normals()
    np.testing.assert_allclose(N, unit(cube.vertices), atol=1e-14)
    pc = perturbed(box(), 0.1, 3)
    N = SubdivisionSurface(pc, "catmull-clark").limit_normals()
    assert (np.einsum("ij,ij->i", N, pc.vertices) > 0.5).all()
    # reversing every face flips the normals
    rev = PolyMesh(pc.vertices, pc.faces[:, ::-1])
    np.testing.assert_allclose(SubdivisionSurface(rev, "catmull-clark").limit_normals(), -N, atol=1e-13)


def test_loop_normals_outward_and_reversible():
    mesh = perturbed(icosphere(1), 0.05, 5)
    N = SubdivisionSurface(mesh, "loop").limit_normals()
    assert (np.einsum("ij,ij->i", N, mesh.vertices) > 0.8).all()
    rev = PolyMesh(mesh.vertices, mesh.faces[:, ::-1])
    np.testing.assert_allclose(SubdivisionSurface(rev, "loop").limit_normals(), -N, atol=1e-13)


@pytest.mark.parametrize("scheme,mesh,levels,bound", [
    ("loop", perturbed(icosphere(1), 0.05, 5), 6, 2.6e-6),
    ("catmull-clark", perturbed(box(), 0.05, 7), 7, 5.0e-5),
])
def test_limit_normals_are_the_limit_of_refined_ring_normals(scheme, mesh, levels, bound):
    """The normal of the refined control 1-ring around a control vertex converges to the
    tangent plane of the limit surface (measured: 2.3e-6 Loop / 6 levels, 4.4e-5 CC / 7)."""
    surf = SubdivisionSurface(mesh, scheme)
    N = surf.limit_normals()
    V0 = mesh.n_vertices
    errs = [np.abs(fan_normals(surf.refine(k), np.arange(V0)) - N).max() for k in (levels - 2, levels - 1, levels)]
    assert errs[-1] < bound
    assert errs[0] > errs[1] > errs[2]


def test_cc_evaluate_normals_at_extraordinary_corners():
    """``evaluate`` at a face corner that is an extraordinary vertex falls back to the
    bilinear interpolant of tiny sub-face corner limit points: its point is exact, its
    normal approaches the exact limit normal (5.4e-2, 1.0e-2, 1.7e-3 at max_level 4, 6, 8)."""
    mesh = perturbed(box(), 0.05, 7)
    surf = SubdivisionSurface(mesh, "catmull-clark")
    t = mesh.topology
    u, v = CORNER_UV[t.corner_index, 0], CORNER_UV[t.corner_index, 1]
    N = surf.limit_normals()[t.face_indices]
    errs = []
    for ml in (4, 6, 8):
        P, _, _, Ne = surf.evaluate(t.corner_face, u, v, max_level=ml)
        np.testing.assert_allclose(P, surf.limit_points()[t.face_indices], atol=TOL)
        errs.append(np.abs(Ne - N).max())
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 2.5e-3


def test_cc_regular_vertex_normals_agree_with_evaluate():
    """Valence-4 vertices of the once-refined cube (edge and face points): the tangent
    masks and the bicubic patches agree exactly."""
    mesh = subdivide(perturbed(box(), 0.05, 8), "catmull-clark", 1)
    surf = SubdivisionSurface(mesh, "catmull-clark")
    t = mesh.topology
    N = surf.limit_normals()
    regular = t.valence[t.face_indices] == 4
    c = np.flatnonzero(regular)
    P, _, _, Ne = surf.evaluate(t.corner_face[c], CORNER_UV[t.corner_index[c], 0], CORNER_UV[t.corner_index[c], 1])
    np.testing.assert_allclose(Ne, N[t.face_indices[c]], atol=1e-12)


# ---------------------------------------------------------------------------------------------
# 8. conversion to bicubic patches
# ---------------------------------------------------------------------------------------------
def side_points(side, x):
    """(u, v) of parameter x along half-edge ``side`` of a quad (corner side -> side + 1)."""
    return {0: (x, 0 * x), 1: (0 * x + 1, x), 2: (1 - x, 0 * x + 1), 3: (0 * x, 1 - x)}[side]


def across_edge(t, face, u, v):
    """The same limit point in the neighbouring face's parameters, for points on the face's border."""
    out = []
    for side, x in ((0, u), (1, v), (2, 1 - u), (3, 1 - v)):
        on = {0: v == 0, 1: u == 1, 2: v == 1, 3: u == 0}[side]
        if not on:
            continue
        h = t.face_offsets[face] + side
        g = t.twin[h]
        fg = int(t.corner_face[g])
        out.append((fg, *side_points(int(g - t.face_offsets[fg]), 1 - x)))
    return out


@pytest.mark.parametrize("levels", [2, 3])
def test_cc_cube_to_bsplines_watertight_and_exact(levels):
    mesh = perturbed(box(), 0.08, 9)
    t = mesh.topology
    surf = SubdivisionSurface(mesh, "catmull-clark")
    patches, info = surf.to_bsplines(levels)
    n = len(patches)
    assert info["exact"] + info["approximate"] == n
    assert info["approximate"] == 24  # one sub-quad at every cube corner of every face
    A, b, root = info["axes"], info["origin"], info["face"]
    Ainv = np.linalg.inv(A)
    x = np.linspace(0, 1, 9)
    queries = []  # (root face, u, v, point, source patch, sample)
    sample = 0
    for k, patch in enumerate(patches):
        for side in range(4):
            s, tt = side_points(side, x)
            pts = patch.evaluate(s, tt)
            uv = np.column_stack([s, tt]) @ A[k].T + b[k]
            uv = np.round(uv, 14)
            for q in range(len(x)):
                queries.append((root[k], uv[q, 0], uv[q, 1], pts[q], k, sample))
                for fg, ug, vg in across_edge(t, root[k], uv[q, 0], uv[q, 1]):
                    queries.append((fg, ug, vg, pts[q], k, sample))
                sample += 1
    qf = np.array([q[0] for q in queries])
    quv = np.array([[q[1], q[2]] for q in queries])
    qp = np.array([q[3] for q in queries])
    qs = np.array([q[4] for q in queries])
    qid = np.array([q[5] for q in queries])
    hits = np.zeros(len(queries), dtype=int)
    worst = 0.0
    for k, patch in enumerate(patches):
        st_ = (quv - b[k]) @ Ainv[k].T
        inside = (qf == root[k]) & (qs != k) & (st_ >= -1e-12).all(axis=1) & (st_ <= 1 + 1e-12).all(axis=1)
        if inside.any():
            p = patch.evaluate(np.clip(st_[inside, 0], 0, 1), np.clip(st_[inside, 1], 0, 1))
            worst = max(worst, float(np.abs(p - qp[inside]).max()))
            hits[inside] += 1
    found = np.bincount(qid, weights=hits, minlength=sample)
    assert (found >= 1).all()
    assert worst < 1e-12, worst
    # exact patches are the limit surface
    g = np.linspace(0, 1, 5)
    s, tt = [a.ravel() for a in np.meshgrid(g, g, indexing="ij")]
    for k in np.flatnonzero(info["kind"] == "exact"):
        uv = np.column_stack([s, tt]) @ A[k].T + b[k]
        P = surf.evaluate(np.full(s.size, root[k]), uv[:, 0], uv[:, 1])[0]
        np.testing.assert_allclose(patches[k].evaluate(s, tt), P, atol=TOL)


def test_cc_to_bsplines_deviation_decreases():
    surf = SubdivisionSurface(perturbed(box(), 0.08, 9), "catmull-clark")
    dev = [surf.to_bsplines(levels)[1]["max_deviation"] for levels in (0, 1, 2, 3, 4)]
    assert all(a > b for a, b in zip(dev[:-1], dev[1:])), dev
    assert dev[0] > 0


# ---------------------------------------------------------------------------------------------
# 9. errors
# ---------------------------------------------------------------------------------------------
def test_loop_needs_triangles():
    with pytest.raises(MeshTopologyError, match="triangle"):
        subdivide(box(), "loop", 1)
    with pytest.raises(MeshTopologyError, match="triangle"):
        SubdivisionSurface(box(), "loop")


def test_loop_needs_triangles_even_for_zero_levels():
    """Refinement(quads, "loop", 0) should refuse the quads as every other Loop entry point does."""
    with pytest.raises(MeshTopologyError):
        subdivide(box(), "loop", 0)


@pytest.mark.parametrize("call", [
    lambda: subdivide(box(), "butterfly"),
    lambda: Refinement(box(), "sqrt3", 1),
    lambda: SubdivisionSurface(box(), "bilinear"),
    lambda: subdivide(box(), "catmull-clark", 1, boundary="none"),
    lambda: subdivide(box(), "catmull-clark", 1, creases={(0, 1): -1.0}),
    lambda: subdivide(box(), "catmull-clark", 1, creases={(0, 1): float("nan")}),
    lambda: subdivide(box(), "doo-sabin", 1, creases={(0, 1): -0.5}),
    lambda: subdivide(box(), "catmull-clark", 1, creases={(0, 1): "sharp"}),
    lambda: subdivide(box(), "catmull-clark", 1, creases=np.zeros(5)),
    lambda: subdivide(box(), "catmull-clark", 1, corners={0: -1.0}),
    lambda: subdivide(box(), "catmull-clark", 1, corners={0: float("nan")}),
    lambda: subdivide(box(), "catmull-clark", 13),
    lambda: subdivide(box(), "catmull-clark", -1),
    lambda: subdivide(box(), "catmull-clark", 1.5),
    # (levels whose face count exceeds the memory budget raise ResourceLimitError: tests/test_limits.py)
    lambda: subdivide(box().topology, "catmull-clark"),
    lambda: Refinement(box(), "catmull-clark", 1).apply(np.zeros((7, 3))),
    lambda: SubdivisionSurface(box(), "doo-sabin").limit_points(),
    lambda: SubdivisionSurface(box(), "doo-sabin").limit_normals(),
    lambda: SubdivisionSurface(box(), "doo-sabin").evaluate(0, 0.5, 0.5),
    lambda: SubdivisionSurface(icosphere(0), "loop").evaluate(0, 0.5, 0.5),
    lambda: SubdivisionSurface(icosphere(0), "loop").to_bsplines(),
    lambda: SubdivisionSurface(box(), "catmull-clark").evaluate(6, 0.5, 0.5),
    lambda: SubdivisionSurface(box(), "catmull-clark").evaluate(-1, 0.5, 0.5),
    lambda: SubdivisionSurface(box(), "catmull-clark").evaluate(0.5, 0.5, 0.5),
    lambda: SubdivisionSurface(box(), "catmull-clark").evaluate([0, 1], [0.1, 0.2, 0.3], 0.5),
    lambda: SubdivisionSurface(box(), "catmull-clark").evaluate(0, 0.5, 0.5, max_level=-1),
    lambda: SubdivisionSurface(mixed_mesh(), "catmull-clark").evaluate(32, 0.5, 0.5),
    lambda: SubdivisionSurface(PolyMesh(box().vertices[:, :2], box().faces), "catmull-clark").limit_normals(),
])
def test_parameter_errors(call):
    with pytest.raises(ParameterError):
        call()


@pytest.mark.parametrize("u,v", [(1.5, 0.5), (0.5, -0.1), (np.nan, 0.5), (0.5, np.inf), (1 + 1e-12, 0.0)])
def test_evaluate_outside_unit_square(u, v):
    with pytest.raises(DomainError):
        SubdivisionSurface(box(), "catmull-clark").evaluate(0, u, v)


@pytest.mark.parametrize("creases", [{(0, 7): 1.0}, {(0, 0): 1.0}, {(0, 100): np.inf}, {(0, -1): 1.0}])
def test_crease_edge_not_in_mesh(creases):
    with pytest.raises(MeshTopologyError, match="not an edge"):
        subdivide(box(), "catmull-clark", 1, creases=creases)


@pytest.mark.parametrize("pair", [(0, 11), (-1, 9)])
def test_crease_with_vertex_out_of_range_is_refused(pair):
    """Vertex 11 does not exist in the 8-vertex cube; (0, 11) must not be taken for the
    edge (1, 3) (nor (-1, 9) for (0, 1)), which share its key lo * V + hi."""
    with pytest.raises(MeshTopologyError):
        subdivide(box(), "catmull-clark", 1, creases={pair: np.inf})


def test_corner_vertex_out_of_range():
    with pytest.raises(MeshTopologyError):
        subdivide(box(), "catmull-clark", 1, corners={8: 1.0})
    with pytest.raises(MeshTopologyError):
        subdivide(box(), "catmull-clark", 1, corners={-1: 1.0})


def test_errors_are_value_errors():
    with pytest.raises(ValueError):
        subdivide(box(), "loop", 1)
    assert issubclass(MeshTopologyError, sk.SplineKitError)
