"""Sampled SDF grids: interpolation, mesh -> SDF (distances against brute force,
signs against the generalized winding number), narrow band, meshing, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from splinekit.errors import NotManifoldError, ParameterError, SplineKitError
from splinekit.implicit import grid
from splinekit.implicit.frommesh import from_mesh
from splinekit.implicit.marching import grid_mesh
from splinekit.implicit.narrowband import NarrowBandSDF
from splinekit.implicit.sampled import MAX_GRID_POINTS, SampledSDF, sample
from splinekit.mesh import PolyMesh, primitives
from splinekit.mesh.geometry import triangulate


# -- independent references ------------------------------------------------------------------------------------
def brute_distance(P, V, T):
    """Distance of each point to the triangle set, by a formulation unlike the
    code under test: the plane distance when the projection falls inside the
    triangle (barycentrics from a 2x2 solve), else the least of the three
    segment distances. All (point, triangle) pairs."""
    A, B, C = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    e0, e1 = B - A, C - A
    G = np.stack([np.einsum("ij,ij->i", e0, e0), np.einsum("ij,ij->i", e0, e1), np.einsum("ij,ij->i", e1, e1)], 1)
    det = G[:, 0] * G[:, 2] - G[:, 1] ** 2
    D = P[:, None, :] - A[None]
    r0, r1 = np.einsum("ptk,tk->pt", D, e0), np.einsum("ptk,tk->pt", D, e1)
    s = (G[:, 2] * r0 - G[:, 1] * r1) / det
    t = (G[:, 0] * r1 - G[:, 1] * r0) / det
    inside = (s >= 0) & (t >= 0) & (s + t <= 1)
    proj = A[None] + s[..., None] * e0[None] + t[..., None] * e1[None]
    d_face = np.where(inside, np.linalg.norm(P[:, None] - proj, axis=2), np.inf)

    def seg(a, b):
        ab = b - a
        u = np.clip(np.einsum("ptk,tk->pt", P[:, None] - a[None], ab) / np.einsum("tk,tk->t", ab, ab), 0, 1)
        return np.linalg.norm(P[:, None] - (a[None] + u[..., None] * ab[None]), axis=2)

    d = np.minimum.reduce([d_face, seg(A, B), seg(B, C), seg(C, A)])
    return d.min(axis=1)


def winding_number(P, V, T):
    """Generalized winding number (van Oosterom & Strackee solid angles) / 4 pi."""
    a = V[T[:, 0]][None] - P[:, None]
    b = V[T[:, 1]][None] - P[:, None]
    c = V[T[:, 2]][None] - P[:, None]
    la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
    num = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ptk,ptk->pt", a, b) * lc + np.einsum("ptk,ptk->pt", b, c) * la + np.einsum("ptk,ptk->pt", c, a) * lb
    return (2 * np.arctan2(num, den)).sum(axis=1) / (4 * np.pi)


def star_mesh():
    """A closed non-convex mesh: an icosphere with radius 1 + 0.45 sin(3 theta) cos(2 phi)."""
    m = primitives.icosphere(2)
    V = np.asarray(m.vertices)
    th = np.arctan2(V[:, 1], V[:, 0])
    ph = np.arccos(np.clip(V[:, 2], -1, 1))
    r = 1 + 0.45 * np.sin(3 * th) * np.sin(ph) ** 2
    return PolyMesh(V * r[:, None], m.faces)


def box_sdf(P, half):
    q = np.abs(P) - half
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def components(mesh):
    E = np.asarray(mesh.edges)
    n = mesh.n_vertices
    g = coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)[0]


SPHERE = lambda p: np.linalg.norm(p, axis=1) - 1.0


# -- interpolation ---------------------------------------------------------------------------------------
def test_trilinear_reproduces_trilinear_functions_and_gradients():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=3), rng.normal()
    f = lambda p: p @ a + b + 0.7 * p[:, 0] * p[:, 1] * p[:, 2]
    g = sample(f, ((-1, -2, 0), (1, 1, 2)), (7, 9, 5))
    P = rng.uniform((-1, -2, 0), (1, 1, 2), (300, 3))
    assert np.allclose(g(P), f(P), atol=1e-12, rtol=0)
    affine = sample(lambda p: p @ a + b, ((-1, -2, 0), (1, 1, 2)), (7, 9, 5))
    assert np.allclose(affine.gradient(P), np.broadcast_to(a, P.shape), atol=1e-12)


def test_cubic_reproduces_quadratics_inside():
    rng = np.random.default_rng(2)
    Q = rng.normal(size=(3, 3))
    f = lambda p: np.einsum("ni,ij,nj->n", p, Q, p) + p[:, 0]
    g = sample(f, ((-1,) * 3, (1,) * 3), 11, interpolation="cubic")
    # away from the border, where Catmull-Rom uses true central slopes
    P = rng.uniform(-0.75, 0.75, (300, 3))
    assert np.allclose(g(P), f(P), atol=1e-12)
    grad = P @ (Q + Q.T) + np.array([1.0, 0, 0])
    assert np.allclose(g.gradient(P), grad, atol=1e-11)


@settings(max_examples=30, deadline=None)
@given(
    shape=st.tuples(*[st.integers(2, 6)] * 3),
    seed=st.integers(0, 2**32 - 1),
    interp=st.sampled_from(["linear", "cubic"]),
)
def test_interpolants_pass_through_the_samples_and_reproduce_affine_functions(shape, seed, interp):
    rng = np.random.default_rng(seed)
    origin, spacing = rng.uniform(-2, 2, 3), rng.uniform(0.1, 2.0, 3)
    vals = rng.normal(size=shape)
    g = SampledSDF(vals, origin, spacing, interp)
    assert np.allclose(g(g.points().reshape(-1, 3)), vals.ravel(), atol=1e-12)
    a, b = rng.normal(size=3), rng.normal()
    P = g.points().reshape(-1, 3)
    lin = SampledSDF((P @ a + b).reshape(shape), origin, spacing, interp)
    hi = origin + (np.array(shape) - 1) * spacing
    Q = rng.uniform(origin, hi, (50, 3))
    scale = 1 + np.abs(Q @ a).max() + abs(b)
    assert np.allclose(lin(Q), Q @ a + b, atol=1e-12 * scale)
    assert np.allclose(lin.gradient(Q), np.broadcast_to(a, Q.shape), atol=1e-11 * scale / spacing.min())


@pytest.mark.parametrize("interp, order", [("linear", 2), ("cubic", 3)])
def test_convergence_order_on_sphere(interp, order):
    rng = np.random.default_rng(3)
    d = rng.normal(size=(400, 3))
    P = d / np.linalg.norm(d, axis=1)[:, None] * rng.uniform(0.6, 1.3, (400, 1))
    errs = []
    for n in (17, 33, 65):
        g = sample(SPHERE, ((-1.6,) * 3, (1.6,) * 3), n, interpolation=interp)
        errs.append(np.abs(g(P) - SPHERE(P)).max())
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert rates[-1] > order - 0.4, (errs, rates)


@pytest.mark.parametrize("interp", ["linear", "cubic"])
def test_gradient_is_the_derivative_of_the_interpolant(interp):
    rng = np.random.default_rng(4)
    g = sample(lambda p: np.sin(p @ [1.0, 2.0, -1.0]) + p[:, 2] ** 2, ((0,) * 3, (1,) * 3), 9, interpolation=interp)
    h = g.spacing[0]
    cells = rng.integers(0, 8, (200, 3))
    P = (cells + rng.uniform(0.2, 0.8, (200, 3))) * h  # away from cell faces (kinks of the linear one)
    P = np.vstack([P, rng.uniform(-0.5, 1.5, (100, 3))])  # and outside the box
    P = P[np.all(np.abs(P - np.round(P / h) * h) > 0.05 * h, axis=1)]
    eps = 1e-6
    fd = np.stack([(g(P + eps * e) - g(P - eps * e)) / (2 * eps) for e in np.eye(3)], axis=1)
    assert np.allclose(g.gradient(P), fd, atol=1e-6)


def test_outside_the_box_adds_the_distance_to_it():
    g = sample(SPHERE, ((-1.5,) * 3, (1.5,) * 3), 13)
    P = np.array([[3.0, 0.2, 0.1], [-2.0, -2.5, 0.0]])
    C = np.clip(P, -1.5, 1.5)
    assert np.allclose(g(P), g(C) + np.linalg.norm(P - C, axis=1), atol=1e-14)
    assert np.allclose(g.bounds[0], -1.5) and np.allclose(g.bounds[1], 1.5)
    assert not g.is_exact_sdf


def test_sample_matches_the_implicit_at_the_samples():
    from splinekit.implicit import sphere

    s = sphere((0.1, 0.2, -0.1), 0.8)
    g = sample(s, ((-1,) * 3, (1, 1, 0.5)), 12)
    assert g.shape[0] == 12 and g.shape[2] < 12
    assert np.allclose(g.values.ravel(), s(g.points().reshape(-1, 3)), atol=1e-15)
    assert np.allclose(g(g.points().reshape(-1, 3)), g.values.ravel(), atol=1e-14)
    with pytest.raises(ValueError):
        g.values[0, 0, 0] = 1.0


# -- mesh -> SDF --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make",
    [lambda: primitives.icosphere(1), lambda: primitives.torus(nu=12, nv=6, R=1.0, r=0.4), star_mesh],
    ids=["icosphere", "torus", "star"],
)
def test_from_mesh_distances_and_signs_against_brute_force(make):
    mesh = make()
    V = np.asarray(mesh.vertices)
    T, _ = triangulate(mesh)
    sdf = from_mesh(mesh, 14)
    P = sdf.points().reshape(-1, 3)
    vals = sdf.values.ravel()
    assert np.allclose(np.abs(vals), brute_distance(P, V, T), atol=1e-12, rtol=0)
    w = winding_number(P, V, T)
    clear = np.abs(vals) > 1e-9
    assert np.array_equal((vals < 0)[clear], (w > 0.5)[clear])
    assert (vals < 0).any() and (vals > 0).any()
    # arbitrary points: the interpolant between exact samples has the right sign off the surface
    rng = np.random.default_rng(5)
    Q = rng.uniform(V.min(0), V.max(0), (300, 3))
    dq = brute_distance(Q, V, T)
    far = dq > 2 * np.linalg.norm(sdf.spacing)
    assert np.array_equal((sdf(Q) < 0)[far], (winding_number(Q, V, T) > 0.5)[far])


def test_from_mesh_of_a_quad_box_is_the_box_sdf():
    mesh = primitives.box((2.0, 1.0, 0.6))
    sdf = from_mesh(mesh, 17, padding=0.3)
    P = sdf.points().reshape(-1, 3)
    assert np.allclose(sdf.values.ravel(), box_sdf(P, np.array([1.0, 0.5, 0.3])), atol=1e-12)


def test_from_mesh_handles_many_points_per_chunk_consistently():
    # a grid large enough for several parallel chunks: every sample against brute force on a subset
    mesh = primitives.icosphere(2)
    V, (T, _) = np.asarray(mesh.vertices), triangulate(mesh)
    sdf = from_mesh(mesh, 30)
    P = sdf.points().reshape(-1, 3)
    pick = np.random.default_rng(6).choice(len(P), 600, replace=False)
    assert np.allclose(np.abs(sdf.values.ravel()[pick]), brute_distance(P[pick], V, T), atol=1e-12)


def test_narrow_band_agrees_with_the_dense_grid():
    mesh = star_mesh()
    dense = from_mesh(mesh, 24)
    h = float(np.linalg.norm(dense.spacing))
    band = 3.5 * h
    nb = from_mesh(mesh, 24, band=band)
    assert isinstance(nb, NarrowBandSDF) and nb.shape == dense.shape
    dv = dense.values
    assert nb.n_stored == int((np.abs(dv) < band).sum()) < 0.8 * dv.size
    expect = np.where(np.abs(dv) < band, dv, np.sign(dv) * band)
    assert np.allclose(nb.values, expect, atol=1e-12)
    rng = np.random.default_rng(7)
    P = rng.uniform(dense.bounds[0], dense.bounds[1], (500, 3))
    near = np.abs(dense(P)) < band - h
    assert np.allclose(nb(P)[near], dense(P)[near], atol=1e-12)
    assert np.array_equal(np.sign(nb(P)), np.sign(dense(P)))
    cubic = from_mesh(mesh, 24, band=band, interpolation="cubic")
    near = np.abs(dense(P)) < band - 2 * h  # the cubic stencil reaches one cell further
    assert near.sum() > 50
    assert np.allclose(cubic(P)[near], dense.with_interpolation("cubic")(P)[near], atol=1e-12)


def test_open_mesh_is_refused_naming_an_edge():
    with pytest.raises(NotManifoldError, match=r"edge \(\d+, \d+\)"):
        from_mesh(primitives.grid(3, 3), 10)
    m = primitives.icosphere(1)
    holed = PolyMesh(m.vertices, np.asarray(m.faces)[1:])
    with pytest.raises(NotManifoldError, match="open"):
        from_mesh(holed, 10)


# -- meshing from the samples ---------------------------------------------------------------------------------
def test_grid_mesh_is_a_closed_outward_manifold():
    g = sample(SPHERE, ((-1.3,) * 3, (1.3,) * 3), 27)
    m = g.to_mesh()
    checked = PolyMesh(m.vertices, m.faces)  # the checked constructor: manifold, consistently oriented
    assert checked.is_closed and checked.euler_characteristic == 2
    h = g.spacing[0]
    r = np.linalg.norm(m.vertices, axis=1)
    # vertices are linear interpolations along grid edges of length up to sqrt(3) h:
    # for |x| - 1 the error is at most (sqrt(3) h)^2 / 8 (curvature 1)
    assert np.abs(r - 1).max() < 3 / 8 * h * h
    vol = checked.volume
    assert abs(vol - 4 / 3 * np.pi) < 4 * np.pi * 0.5 * h * h and vol > 0  # outward faces: positive volume
    # the measured deviation from the trilinear interpolant's zero set: O(h^2)
    dev_ref = np.abs(g(m.vertices)).max()
    assert dev_ref <= m.deviation * 1.5 + 1e-15 and 0 < m.deviation < 0.5 * h * h
    torus = lambda p: np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.35
    mt = sample(torus, ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5)), 40).to_mesh()
    assert PolyMesh(mt.vertices, mt.faces).euler_characteristic == 0 and components(mt) == 1


def test_grid_mesh_caps_a_solid_cut_by_the_border_and_handles_empty():
    g = sample(SPHERE, ((0.0, -1.3, -1.3), (1.3, 1.3, 1.3)), 20)  # half a ball
    m = PolyMesh(g.to_mesh().vertices, g.to_mesh().faces)
    assert m.is_closed and m.euler_characteristic == 2
    empty = grid_mesh(np.ones((3, 3, 3)), (0, 0, 0), 1.0)
    assert empty.n_faces == 0


def test_to_mesh_with_an_edge_length_resamples_the_interpolant():
    g = sample(SPHERE, ((-1.3,) * 3, (1.3,) * 3), 27, interpolation="cubic")
    m = g.to_mesh(0.15)
    assert m.is_closed and m.euler_characteristic == 2
    assert np.abs(np.linalg.norm(m.vertices, axis=1) - 1).max() < 0.03


def test_the_old_grid_module_path_still_names_the_same_objects():
    assert (grid.SampledSDF, grid.NarrowBandSDF, grid.sample, grid.from_mesh, grid.grid_mesh, grid.MAX_GRID_POINTS) == (
        SampledSDF, NarrowBandSDF, sample, from_mesh, grid_mesh, MAX_GRID_POINTS
    )


# -- bad input ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("res", [0, 1, -3, 2.5, "8", (4, 4), (4, 4, 0)])
def test_bad_resolution(res):
    with pytest.raises(ParameterError):
        sample(SPHERE, ((-1,) * 3, (1,) * 3), res)


def test_huge_grids_are_refused_before_allocating():
    with pytest.raises(ParameterError, match="MAX_GRID_POINTS"):
        sample(SPHERE, ((-1,) * 3, (1,) * 3), 10**6)
    with pytest.raises(ParameterError, match="MAX_GRID_POINTS"):
        from_mesh(primitives.icosphere(0), round(MAX_GRID_POINTS ** (1 / 3)) + 5)
    with pytest.raises(ParameterError, match="MAX_GRID_POINTS"):
        NarrowBandSDF([], [], np.zeros((2, 2, 2), bool), (10**5, 10**5, 10**5), (0, 0, 0), 1.0, 1.0)


def test_bad_arguments():
    ok = np.zeros((3, 3, 3))
    cases = [
        lambda: SampledSDF(np.zeros((3, 3)), (0, 0, 0), 1.0),
        lambda: SampledSDF(np.zeros((1, 3, 3)), (0, 0, 0), 1.0),
        lambda: SampledSDF(np.full((3, 3, 3), np.nan), (0, 0, 0), 1.0),
        lambda: SampledSDF(ok, (0, 0, 0), 0.0),
        lambda: SampledSDF(ok, (0, 0, 0), (1, -1, 1)),
        lambda: SampledSDF(ok, (0, np.inf, 0), 1.0),
        lambda: SampledSDF(ok, (0, 0, 0), 1.0, interpolation="quintic"),
        lambda: sample(SPHERE, None, 10),
        lambda: sample(SPHERE, ((0, 0, 0), (1, 1, 1)), (3, 3, 3), interpolation="nearest"),
        lambda: sample(SPHERE, ((0, 0, 0), (0, 1, 1)), (3, 3, 3)),
        lambda: sample(42, ((0, 0, 0), (1, 1, 1)), 5),
        lambda: sample(lambda p: np.full(len(p), np.nan), ((0, 0, 0), (1, 1, 1)), 5),
        lambda: sample(lambda p: np.zeros(3), ((0, 0, 0), (1, 1, 1)), 5),
        lambda: from_mesh(primitives.icosphere(1), 10, padding=-0.1),
        lambda: from_mesh(primitives.icosphere(1), 10, band=1e-3),
        lambda: from_mesh("mesh", 10),
        lambda: from_mesh(primitives.icosphere(1), 10, interpolation="spline"),
        lambda: NarrowBandSDF([0, 0], [0.1, 0.2], np.zeros((2, 2, 2), bool), (2, 2, 2), (0, 0, 0), 1.0, 1.0),
        lambda: NarrowBandSDF([9], [0.1], np.zeros((2, 2, 2), bool), (2, 2, 2), (0, 0, 0), 1.0, 1.0),
        lambda: NarrowBandSDF([1], [2.0], np.zeros((2, 2, 2), bool), (2, 2, 2), (0, 0, 0), 1.0, 1.0),
        lambda: grid_mesh(np.zeros((2, 2)), (0, 0, 0), 1.0),
    ]
    for i, case in enumerate(cases):
        with pytest.raises(SplineKitError):
            case()
            pytest.fail(f"case {i} did not raise")
    g = SampledSDF(ok, (0, 0, 0), 1.0)
    with pytest.raises(SplineKitError):
        g(np.array([[np.nan, 0, 0]]))
    with pytest.raises(SplineKitError):
        g(np.zeros((4, 2)))


def test_from_mesh_signs_on_the_mug_model():
    """A real, non-convex genus-1 model: the Catmull-Clark mug's limit mesh
    (the Newell teapot's body is open at the lid, so it has no inside).
    Signs agree with the generalized winding number wherever the sample is
    clear of the surface, inside the wall and in the handle's hole alike."""
    import models.mug

    mesh = models.mug.limit_mesh(levels=1)
    V = np.asarray(mesh.vertices)
    T, _ = triangulate(mesh)
    sdf = from_mesh(mesh, 24)
    P = sdf.points().reshape(-1, 3)
    vals = sdf.values.ravel()
    w = winding_number(P, V, T)
    clear = np.abs(vals) > 1e-6 * np.abs(V).max()
    assert np.array_equal((vals < 0)[clear], (w > 0.5)[clear])
    assert (vals < 0).sum() > 50 and (vals > 0).sum() > 50
    # the exact distances of a few samples against brute force
    pick = np.random.default_rng(8).choice(len(P), 200, replace=False)
    assert np.allclose(np.abs(vals[pick]), brute_distance(P[pick], V, T), atol=1e-9 * np.abs(V).max(), rtol=0)


def test_grid_mesh_level_and_grid_extent_are_checked():
    with pytest.raises(ParameterError, match="level must be finite"):
        grid_mesh(np.zeros((3, 3, 3)), (0, 0, 0), 1.0, level=np.nan)
    with pytest.raises(ParameterError, match="single number"):
        grid_mesh(np.zeros((3, 3, 3)), (0, 0, 0), 1.0, level=[0.0, 1.0])
    with pytest.raises(ParameterError, match="overflows"):
        grid_mesh(np.full((3, 3, 3), -1e308), (0, 0, 0), 1.0, level=1e308)
    with pytest.raises(ParameterError, match="float range"):
        SampledSDF(np.zeros((4, 4, 4)), (0, 0, 0), 1e308)
    # a level other than 0: the mesh of v - level, the same as shifting the samples
    v = np.linalg.norm(np.stack(np.meshgrid(*[np.linspace(-1, 1, 9)] * 3, indexing="ij"), -1), axis=-1)
    a, b = grid_mesh(v, (-1, -1, -1), 0.25, level=0.5), grid_mesh(v - 0.5, (-1, -1, -1), 0.25)
    assert a.n_faces > 0 and np.allclose(a.vertices, b.vertices, atol=1e-15)
    # chords of the sphere of radius 0.5 (curvature 2) along edges up to sqrt(3) h: (sqrt(3) h)^2 * 2 / 8
    assert np.abs(np.linalg.norm(a.vertices, axis=1) - 0.5).max() < 0.75 * 0.25**2


@pytest.mark.parametrize("scale", [1e-120, 1e120])
def test_from_mesh_is_exact_at_any_scale(scale):
    # the closest-point tests and pseudo-normals involve length^4: unscaled they overflow
    # (or underflow to wrong signs) for meshes of size ~1e77 (~1e-77)
    mesh = primitives.icosphere(2)
    ref = from_mesh(mesh, 12)
    big = from_mesh(PolyMesh(mesh.vertices * scale, mesh.faces), 12)
    assert big.shape == ref.shape
    assert np.allclose(big.values / scale, ref.values, rtol=0, atol=1e-14)

