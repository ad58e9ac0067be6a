"""Closest points (splinekit.closest): closed forms (exact NURBS circle and sphere, implicit
sphere and torus), point inversion, brute-force sampling, and bad input. The cross-checks
against OpenCascade's point projection are in tests/occ/test_closest_occ.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _geometry import random_curve_data
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit import (
    BezierCurve,
    BezierSurface,
    BSplineCurve,
    BSplineSurface,
    NurbsCurve,
    NurbsSurface,
)
from splinekit.basis.knots import clamped_uniform
from splinekit.closest import Projection, distance, project
from splinekit.errors import (
    ConvergenceError,
    DomainError,
    ParameterError,
    SplineKitError,
)

S2 = math.sqrt(0.5)
UNIT_CIRCLE = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]], float)
CIRCLE_WEIGHTS = np.array([1, S2, 1, S2, 1, S2, 1, S2, 1])
CIRCLE_KNOTS = np.array([0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1], float)


# --------------------------------------------------------------------------------------
# geometry helpers


def make_curve(p, U, P, W):
    return BSplineCurve(p, U, P) if W is None else NurbsCurve(p, U, P, W)


def make_surface(pu, pv, ku, kv, P, W):
    return BSplineSurface(pu, pv, ku, kv, P) if W is None else NurbsSurface(pu, pv, ku, kv, P, W)


def smooth_surface(rng, rational, degrees=(3, 3), n=(8, 7)):
    """A CAD-like patch: a wavy height field over a grid, random knots, mild weights."""
    pu, pv = degrees
    ku, kv = clamped_uniform(pu, n[0]), clamped_uniform(pv, n[1])
    x, y = np.meshgrid(np.linspace(0, 4, n[0]), np.linspace(0, 3, n[1]), indexing="ij")
    z = rng.uniform(-0.6, 0.6, x.shape)
    P = np.stack([x + rng.uniform(-0.1, 0.1, x.shape), y + rng.uniform(-0.1, 0.1, x.shape), z], axis=-1)
    W = rng.uniform(0.5, 2.0, x.shape) if rational else None
    return make_surface(pu, pv, ku, kv, P, W)


def points_around(rng, P, count, inflate=0.3):
    """Random points in the control net's bounding box inflated by ``inflate`` of its size."""
    flat = np.asarray(P).reshape(-1, P.shape[-1])
    lo, hi = flat.min(0), flat.max(0)
    pad = inflate * (hi - lo) + 1e-3
    return rng.uniform(lo - pad, hi + pad, (count, flat.shape[1]))


def nurbs_circle(center, radius, rotation):
    P = np.column_stack([UNIT_CIRCLE * radius, np.zeros(9)]) @ rotation.T + center
    return NurbsCurve(2, CIRCLE_KNOTS, P, CIRCLE_WEIGHTS)


def nurbs_sphere(center, radius):
    """The revolved half circle: degree (2, 2), 5 x 9 net, poles collapsed at u = 0, 1."""
    prof_rz = np.array([[0, -1], [1, -1], [1, 0], [1, 1], [0, 1]], float) * radius
    prof_w = np.array([1, S2, 1, S2, 1])
    P = np.empty((5, 9, 3))
    P[..., 0] = prof_rz[:, None, 0] * UNIT_CIRCLE[None, :, 0]
    P[..., 1] = prof_rz[:, None, 0] * UNIT_CIRCLE[None, :, 1]
    P[..., 2] = prof_rz[:, None, 1]
    W = prof_w[:, None] * CIRCLE_WEIGHTS[None, :]
    ku = np.array([0, 0, 0, 0.5, 0.5, 1, 1, 1], float)
    return NurbsSurface(2, 2, ku, CIRCLE_KNOTS, P + center, W)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def brute_force(evaluate_grid_points, Q):
    """Distance from each point to a dense sample set ``(S, dim)`` (an upper bound of the true distance)."""
    d2 = ((Q[:, None, :] - evaluate_grid_points[None]) ** 2).sum(-1)
    return np.sqrt(d2.min(1))


# --------------------------------------------------------------------------------------
# point inversion


def test_point_inversion_surfaces():
    rng = np.random.default_rng(6)
    for trial in range(10):
        s = smooth_surface(rng, rational=trial % 2 == 0, degrees=[(3, 3), (2, 4), (1, 3)][trial % 3])
        (a, b), (c, d) = s.domain
        u, v = rng.uniform(a, b, 50), rng.uniform(c, d, 50)
        u[:4], v[:4] = [a, b, a, b], [c, c, d, d]  # the corners too
        res = project(s, s.evaluate(u, v))
        size = float(np.abs(s.control_points).max())
        assert res.distances.max() <= 1e-12 * size
        np.testing.assert_allclose(res.parameters[:, 0], u, atol=1e-9 * (b - a))
        np.testing.assert_allclose(res.parameters[:, 1], v, atol=1e-9 * (d - c))


def test_point_inversion_curves():
    rng = np.random.default_rng(7)
    for trial in range(10):
        p, U, P, W = random_curve_data(rng, rational=trial % 2 == 1, max_degree=6, max_spans=4)
        c = make_curve(p, U, P, W)
        t = rng.uniform(*c.domain, 40)
        res = project(c, c.evaluate(t))
        size = max(1.0, float(np.abs(P).max()))
        assert res.distances.max() <= 1e-12 * size
        # a random curve may pass through one point twice; compare parameters where the
        # curve does not come back near the point elsewhere
        far = np.abs(res.parameters - t) > 1e-6 * (c.domain[1] - c.domain[0])
        assert np.all(res.distances[far] <= 1e-12 * size)
        assert far.mean() < 0.1
        np.testing.assert_allclose(res.parameters[~far], t[~far], atol=1e-9 * (c.domain[1] - c.domain[0]))


# --------------------------------------------------------------------------------------
# closed forms


def test_nurbs_circle_closed_form():
    rng = np.random.default_rng(8)
    R, center, rot = 2.5, np.array([1.0, -2.0, 0.5]), random_rotation(rng)
    c = nurbs_circle(center, R, rot)
    Q = center + rng.normal(0, 3.0, (300, 3))
    local = (Q - center) @ rot  # circle frame: plane z = 0
    rho, z = np.hypot(local[:, 0], local[:, 1]), local[:, 2]
    res = project(c, Q)
    np.testing.assert_allclose(res.distances, np.hypot(rho - R, z), rtol=0, atol=1e-10)
    foot = center + (np.column_stack([local[:, :2] * (R / rho)[:, None], np.zeros(len(Q))]) @ rot.T)
    np.testing.assert_allclose(res.points, foot, atol=1e-9)


@pytest.mark.parametrize("scale", [1e-200, 1e80, 1e140, 1e300])
def test_closed_forms_at_extreme_scales(scale):
    """Geometry far beyond 1e60 is searched in scaled units: the Newton system
    multiplies squared lengths, which would overflow in model units."""
    rng = np.random.default_rng(12)
    R, center = 1.5 * scale, np.array([1.0, -2.0, 0.5]) * scale
    c = nurbs_circle(center, R, np.eye(3))
    Q = center + rng.normal(0, 2.0, (50, 3)) * scale
    local = Q / scale - center / scale  # the closed forms in units of scale (no under/overflow)
    rho, z, r = np.hypot(local[:, 0], local[:, 1]), local[:, 2], np.linalg.norm(local, axis=1)
    res = project(c, Q)
    assert np.isfinite(res.points).all()
    np.testing.assert_allclose(res.distances / scale, np.hypot(rho - 1.5, z), rtol=0, atol=1e-10)
    s = nurbs_sphere(center, R)
    res = project(s, Q)
    np.testing.assert_allclose(res.distances / scale, np.abs(r - 1.5), rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.points / scale - center / scale, local * (1.5 / r)[:, None], atol=1e-8)


def test_circle_2d_near_seam():
    """A closed curve: points near the seam (u = 0 = 1) find the seam side that is nearer."""
    rng = np.random.default_rng(9)
    c = NurbsCurve(2, CIRCLE_KNOTS, UNIT_CIRCLE, CIRCLE_WEIGHTS)
    ang = rng.uniform(-0.05, 0.05, 100)
    r = rng.uniform(0.2, 3.0, 100)
    Q = np.column_stack([r * np.cos(ang), r * np.sin(ang)])
    res = project(c, Q)
    np.testing.assert_allclose(res.distances, np.abs(r - 1.0), atol=1e-12)
    np.testing.assert_allclose(res.points, np.column_stack([np.cos(ang), np.sin(ang)]), atol=1e-9)


def test_nurbs_sphere_closed_form():
    rng = np.random.default_rng(10)
    R, center = 1.7, np.array([0.3, 0.2, -1.0])
    s = nurbs_sphere(center, R)
    dirs = rng.normal(size=(300, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    dirs[:4] = [[0, 0, 1], [0, 0, -1], [0.01, 0, 0.9999], [1, 0, 0]]  # poles and the seam
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    radii = rng.uniform(0.1, 4.0, 300) * R
    Q = center + dirs * radii[:, None]
    res = project(s, Q)
    np.testing.assert_allclose(res.distances, np.abs(radii - R), atol=1e-9 * R)
    np.testing.assert_allclose(res.points, center + R * dirs, atol=1e-7 * R)


# --------------------------------------------------------------------------------------
# implicit surfaces


class SphereSDF:
    def __init__(self, center, radius):
        self.c, self.r = np.asarray(center, float), float(radius)

    def __call__(self, p):
        return np.linalg.norm(p - self.c, axis=1) - self.r

    def gradient(self, p):
        d = p - self.c
        return d / np.linalg.norm(d, axis=1, keepdims=True)


class SpherePolynomial:
    """|p - c|^2 - r^2: the zero set is the sphere but the values are not distances."""

    def __init__(self, center, radius):
        self.c, self.r = np.asarray(center, float), float(radius)

    def __call__(self, p):
        return ((p - self.c) ** 2).sum(1) - self.r**2

    def gradient(self, p):
        return 2.0 * (p - self.c)


class TorusSDF:
    """Torus about the z axis: major radius R, minor radius r."""

    def __init__(self, R, r):
        self.R, self.r = float(R), float(r)

    def __call__(self, p):
        q = np.hypot(p[:, 0], p[:, 1]) - self.R
        return np.hypot(q, p[:, 2]) - self.r

    def gradient(self, p):
        rho = np.hypot(p[:, 0], p[:, 1])
        q = rho - self.R
        n = np.hypot(q, p[:, 2])
        return np.column_stack([q / n * p[:, 0] / rho, q / n * p[:, 1] / rho, p[:, 2] / n])


def test_implicit_sphere():
    rng = np.random.default_rng(12)
    c, r = np.array([1.0, 2.0, -0.5]), 1.3
    Q = c + rng.normal(0, 2.0, (200, 3))
    dist = np.abs(np.linalg.norm(Q - c, axis=1) - r)
    foot = c + r * (Q - c) / np.linalg.norm(Q - c, axis=1, keepdims=True)
    for implicit in (SphereSDF(c, r), SpherePolynomial(c, r)):
        res = project(implicit, Q, tolerance=1e-13)
        assert res.parameters is None
        np.testing.assert_allclose(res.distances, dist, atol=1e-12)
        np.testing.assert_allclose(res.points, foot, atol=1e-12)


def test_implicit_torus():
    rng = np.random.default_rng(13)
    R, r = 2.0, 0.5
    Q = rng.uniform(-3, 3, (200, 3))
    Q = Q[np.hypot(Q[:, 0], Q[:, 1]) > 0.1]  # the axis is equidistant from the whole core circle
    rho = np.hypot(Q[:, 0], Q[:, 1])
    core = np.column_stack([R * Q[:, 0] / rho, R * Q[:, 1] / rho, np.zeros(len(Q))])
    to_core = Q - core
    d_core = np.linalg.norm(to_core, axis=1)
    keep = d_core > 1e-3
    Q, core, to_core, d_core = Q[keep], core[keep], to_core[keep], d_core[keep]
    res = project(TorusSDF(R, r), Q)
    np.testing.assert_allclose(res.distances, np.abs(d_core - r), atol=1e-9)
    np.testing.assert_allclose(res.points, core + r * to_core / d_core[:, None], atol=1e-9)
    np.testing.assert_allclose(distance(TorusSDF(R, r), Q), np.abs(d_core - r), atol=1e-9)


def test_implicit_zero_gradient_names_point():
    Q = np.array([[3.0, 0, 0], [1.0, 2.0, -0.5], [0.0, 1.0, 0.0]])
    with pytest.raises(SplineKitError, match="point 1"):
        project(SpherePolynomial([1.0, 2.0, -0.5], 1.0), Q)


def test_implicit_without_zero_set_raises():
    class NoZero:
        def __call__(self, p):
            return (p**2).sum(1) + 1.0

        def gradient(self, p):
            return 2 * p

    with pytest.raises(ConvergenceError):
        project(NoZero(), np.array([[1.0, 1.0, 1.0]]))


# --------------------------------------------------------------------------------------
# boundaries, other dimensions, other geometry types


def test_curve_end_points_and_higher_dimensions():
    rng = np.random.default_rng(14)
    for dim in (1, 2, 4):
        P = np.cumsum(rng.uniform(0.5, 1.0, (6, dim)), axis=0)  # monotone: the ends are extreme
        c = BSplineCurve.uniform(3, P)
        beyond = np.vstack([P[0] - 1.0, P[-1] + 1.0])
        res = project(c, beyond)
        np.testing.assert_allclose(res.parameters, [0.0, 1.0], atol=0)
        np.testing.assert_allclose(res.points, [P[0], P[-1]], atol=1e-14)
        Q = points_around(rng, P, 50)
        dense = c.evaluate(np.linspace(0, 1, 20001))
        res = project(c, Q)
        assert np.all(res.distances <= brute_force(dense, Q) + 1e-12)


def test_surface_corner_and_edge():
    x, y = np.meshgrid(np.linspace(0, 2, 4), np.linspace(0, 1, 3), indexing="ij")
    s = BSplineSurface.uniform(2, 2, np.stack([x, y, np.zeros_like(x)], axis=-1))  # flat, symmetric in u
    Q = np.array([[-1.0, -1.0, 0.5], [3.0, 0.5, -2.0], [1.0, 2.0, 0.0]])
    res = project(s, Q)
    np.testing.assert_allclose(res.points, [[0, 0, 0], [2, 0.5, 0], [1, 1, 0]], atol=1e-12)
    np.testing.assert_allclose(res.parameters, [[0, 0], [1, 0.5], [0.5, 1]], atol=1e-12)
    np.testing.assert_allclose(res.distances, [math.sqrt(2.25), math.sqrt(5.0), 1.0], atol=1e-12)


def test_bezier_and_duck_typed_geometry():
    rng = np.random.default_rng(15)
    bs = BezierSurface(rng.uniform(-1, 1, (4, 3, 3)), rng.uniform(0.5, 2, (4, 3)))
    bc = BezierCurve(rng.uniform(-1, 1, (5, 3)))

    class Wrapped:  # an outside surface type with domain_u / domain_v
        def __init__(self, s):
            self.s = s
            self.domain_u = (0.0, 1.0)
            self.domain_v = (0.0, 1.0)

        def evaluate(self, u, v):
            return self.s.evaluate(u, v)

        def derivatives(self, u, v, order):
            return self.s.derivatives(u, v, order)

    Q = rng.uniform(-1.5, 1.5, (80, 3))
    ref = project(bs.to_bspline(), Q).distances
    np.testing.assert_allclose(project(bs, Q).distances, ref, atol=1e-12)
    np.testing.assert_allclose(project(Wrapped(bs), Q).distances, ref, atol=1e-12)
    g = np.linspace(0, 1, 301)
    dense = bs.evaluate_grid(g, g).reshape(-1, 3)
    assert np.all(ref <= brute_force(dense, Q) + 1e-12)
    np.testing.assert_allclose(project(bc, Q).distances, project(bc.to_bspline(), Q).distances, atol=1e-12)


def test_seeds_give_local_projection():
    c = NurbsCurve(2, CIRCLE_KNOTS, UNIT_CIRCLE, CIRCLE_WEIGHTS)
    Q = np.array([[0.0, 0.0]])  # the centre: every point of the circle is nearest
    res = project(c, Q, seeds=[0.3])
    assert res.parameters.shape == (1,)
    np.testing.assert_allclose(res.distances, [1.0], atol=1e-12)
    s = nurbs_sphere(np.zeros(3), 1.0)
    Q = np.array([[0.0, 0.0, 2.0], [2.0, 0.0, 0.0]])
    res = project(s, Q, seeds=[[[0.9, 0.1], [0.5, 0.5]], [[0.5, 0.0], [0.5, 0.5]]])
    np.testing.assert_allclose(res.distances, [1.0, 1.0], atol=1e-9)


def test_shapes_single_point_and_empty():
    c = BSplineCurve.uniform(2, [[0, 0, 0], [1, 1, 0], [2, 0, 0]])
    res = project(c, [1.0, 3.0, 0.0])
    assert res.parameters.shape == () and res.points.shape == (3,) and res.distances.shape == ()
    res = project(c, np.zeros((0, 3)))
    assert res.parameters.shape == (0,) and res.points.shape == (0, 3) and res.distances.shape == (0,)
    res = project(c, np.zeros((2, 5, 3)))
    assert res.parameters.shape == (2, 5) and res.distances.shape == (2, 5)
    assert isinstance(res, Projection)
    with pytest.raises(AttributeError):
        res.points = None  # frozen


# --------------------------------------------------------------------------------------
# properties


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), rational=st.booleans())
def test_properties_surface(seed, rational):
    """Never farther than a dense sample; idempotent; invariant under rigid motions."""
    rng = np.random.default_rng(seed)
    s = smooth_surface(rng, rational, degrees=tuple(int(x) for x in rng.integers(1, 5, 2)))
    Q = points_around(rng, s.control_points, 20)
    res = project(s, Q)
    g = np.linspace(0, 1, 121)
    dense = s.evaluate_grid(g, g).reshape(-1, 3)
    assert np.all(res.distances <= brute_force(dense, Q) + 1e-12)
    again = project(s, res.points)
    assert again.distances.max() <= 1e-9 * float(np.abs(s.control_points).max())
    M = np.eye(4)
    M[:3, :3] = random_rotation(rng)
    M[:3, 3] = rng.uniform(-5, 5, 3)
    moved = project(s.transform(M), Q @ M[:3, :3].T + M[:3, 3])
    np.testing.assert_allclose(moved.distances, res.distances, atol=1e-8)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_properties_curve(seed):
    rng = np.random.default_rng(seed)
    p, U, P, W = random_curve_data(rng, rational=bool(rng.integers(2)), max_degree=5, max_spans=4)
    c = make_curve(p, U, P, W)
    Q = points_around(rng, P, 20)
    res = project(c, Q)
    dense = c.evaluate(np.linspace(*c.domain, 20001))
    size = max(1.0, float(np.abs(P).max()))
    assert np.all(res.distances <= brute_force(dense, Q) + 1e-9 * size)


# --------------------------------------------------------------------------------------
# bad input


def test_bad_input():
    c = BSplineCurve.uniform(2, [[0, 0, 0], [1, 1, 0], [2, 0, 0]])
    s = smooth_surface(np.random.default_rng(0), False)
    with pytest.raises(ParameterError, match=r"points\[1\]"):
        project(c, [[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ParameterError, match=r"points\[0\]"):
        project(s, [[np.inf, 0, 0]])
    with pytest.raises(ParameterError, match=r"\(n, 3\)"):
        project(c, [[0, 0]])
    with pytest.raises(ParameterError, match=r"\(n, 3\)"):
        project(s, np.zeros((4, 2)))
    with pytest.raises(ParameterError):
        project(c, 1.0)
    with pytest.raises(ParameterError):
        project(c, [["a", "b", "c"]])
    with pytest.raises(ParameterError, match="cannot project"):
        project("a circle", [[0, 0, 0]])
    with pytest.raises(ParameterError, match="tolerance"):
        project(c, [[0, 0, 0]], tolerance=-1.0)
    with pytest.raises(ParameterError, match="tolerance"):
        project(c, [[0, 0, 0]], tolerance=float("nan"))
    with pytest.raises(ParameterError, match="seeds"):
        project(c, [[0, 0, 0]], seeds=[[[0.5]]])
    with pytest.raises(ParameterError, match="seeds"):
        project(s, [[0, 0, 0]], seeds=[0.5])
    with pytest.raises(DomainError, match="seeds"):
        project(c, [[0, 0, 0]], seeds=[2.0])
    with pytest.raises(ParameterError, match="seeds"):
        project(SphereSDF([0, 0, 0], 1), [[0, 0, 2.0]], seeds=[0.5])
    with pytest.raises(ParameterError, match=r"points\[0\]"):
        project(SphereSDF([0, 0, 0], 1), [[0, np.nan, 2.0]])
    for bad in ([np.nan, 0.0, 0.0], [0.0, 1.0]):
        with pytest.raises(SplineKitError):
            distance(c, [bad])
    # squared distances of such points overflow: refused by name, not an IndexError from the k-d tree
    for geometry in (c, s, SphereSDF([0, 0, 0], 1)):
        with pytest.raises(ParameterError, match=r"points\[1\].*beyond"):
            project(geometry, [[0, 0, 0], [1e300, 1e300, 0]])


def test_newton_failure_raises_convergence_error(monkeypatch):
    """With no iteration budget Newton cannot reach a stationary point away from the
    geometry: a ConvergenceError names the point instead of a silent wrong answer."""
    from splinekit.closest import newton

    s = smooth_surface(np.random.default_rng(1), rational=True)
    Q = np.array([[2.0, 1.5, 0.0], [2.13, 1.37, 3.0]])
    monkeypatch.setattr(newton, "MAX_ITERATIONS", 0)
    with pytest.raises(ConvergenceError, match=r"points\[\d\]"):
        project(s, Q)


def test_duck_typed_curve():
    rng = np.random.default_rng(16)
    c = NurbsCurve(3, clamped_uniform(3, 8), rng.uniform(-1, 1, (8, 2)), rng.uniform(0.5, 2, 8))

    class Wrapped:  # no knots: sampled on 16 equal pieces of the domain
        domain = c.domain

        def evaluate(self, u):
            return c.evaluate(u)

        def derivatives(self, u, order):
            return c.derivatives(u, order)

    Q = rng.uniform(-1.5, 1.5, (100, 2))
    np.testing.assert_allclose(project(Wrapped(), Q).distances, project(c, Q).distances, atol=1e-12)


def test_chunks_give_the_same_result(monkeypatch):
    from splinekit.closest import projection

    rng = np.random.default_rng(17)
    s = smooth_surface(rng, rational=True)
    Q = points_around(rng, s.control_points, 50)
    seeds = rng.uniform(0, 1, (50, 2, 2))
    whole, local = project(s, Q), project(s, Q, seeds=seeds)
    monkeypatch.setattr(projection, "CHUNK", 7)
    np.testing.assert_array_equal(project(s, Q).distances, whole.distances)
    np.testing.assert_array_equal(project(s, Q, seeds=seeds).parameters, local.parameters)
