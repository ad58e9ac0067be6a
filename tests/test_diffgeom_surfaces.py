"""Surface curvature and geodesics against closed forms (OpenCascade: tests/occ/test_diffgeom_surfaces_occ.py).

Sign convention under test (stated in splinekit.diffgeom.curvature): curvature
is measured against the unit normal Su x Sv (grad F / |grad F| for implicit
surfaces), as in OCC: a sphere with outward normals has K = 1/R^2, H = -1/R.
"""

from __future__ import annotations

import numpy as np
import pytest
from _geometry import random_surface_data

import splinekit as sk
from splinekit.diffgeom.curvature import curvature
from splinekit.diffgeom.geodesics import christoffel_symbols, geodesic, trace_geodesic
from splinekit.diffgeom.protocol import (
    ExplicitSurface,
    ImplicitSurface,
    ParametricSurface,
    SubdivisionPatch,
)
from splinekit.errors import (
    ConvergenceError,
    DomainError,
    ParameterError,
    SplineKitError,
)
from splinekit.mesh.primitives import torus as torus_cage

W = np.sqrt(0.5)
CIRCLE = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]], float)
CIRCLE_W = np.array([1, W, 1, W, 1, W, 1, W, 1])
CIRCLE_KNOTS = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]


def nurbs_sphere(R):
    """The revolved semicircle (Piegl-Tiller's 9 x 5 net), poles at v = 0, 1;
    Su x Sv points outward."""
    semi = np.array([[0, -1], [1, -1], [1, 0], [1, 1], [0, 1]], float)
    semi_w = np.array([1, W, 1, W, 1])
    P = np.stack([CIRCLE[:, None, 0] * semi[None, :, 0], CIRCLE[:, None, 1] * semi[None, :, 0],
                  np.broadcast_to(semi[None, :, 1], (9, 5))], -1)  # fmt: skip
    return sk.NurbsSurface(2, 2, CIRCLE_KNOTS, [0, 0, 0, 0.5, 0.5, 1, 1, 1], R * P, np.outer(CIRCLE_W, semi_w))


def nurbs_torus(R, r):
    """Torus as the product of two exact circles: tube angle along v."""
    P = np.empty((9, 9, 3))
    rho = R + r * CIRCLE[None, :, 0]  # the tube circle's control radii, revolved (A8.1)
    P[..., 0] = CIRCLE[:, None, 0] * rho
    P[..., 1] = CIRCLE[:, None, 1] * rho
    P[..., 2] = r * CIRCLE[None, :, 1]
    return sk.NurbsSurface(2, 2, CIRCLE_KNOTS, CIRCLE_KNOTS, P, np.outer(CIRCLE_W, CIRCLE_W))


def trig_sphere(R, analytic=True):
    """x(u, v) = R (cos u cos v, sin u cos v, sin v): outward normal Su x Sv."""

    def f(u, v):
        return R * np.stack([np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)], -1)

    def ders(u, v, order):
        out = np.zeros((order + 1, order + 1, u.size, 3))
        for k in range(order + 1):
            for l in range(order + 1):  # d^k/du^k of cos u is cos(u + k pi/2)
                cu, su = np.cos(u + k * np.pi / 2), np.sin(u + k * np.pi / 2)
                cv, sv = np.cos(v + l * np.pi / 2), np.sin(v + l * np.pi / 2)
                out[k, l] = R * np.stack([cu * cv, su * cv, sv * (k == 0)], -1)
        return out

    return ParametricSurface(f, ders if analytic else None, domain=((0, 2 * np.pi), (-np.pi / 2, np.pi / 2)))


def cylinder(R):
    """x(t, z) = (R cos t, R sin t, z), outward normal Su x Sv."""

    def f(t, z):
        return np.stack([R * np.cos(t), R * np.sin(t), z], -1)

    return ParametricSurface(f, domain=((0, 2 * np.pi), (-3, 3)))


# -- closed forms ------------------------------------------------------------------
@pytest.mark.parametrize("analytic", [True, False])
def test_sphere_parametric(analytic):
    R = 2.5
    rng = np.random.default_rng(1)
    u, v = rng.uniform(0, 2 * np.pi, 200), rng.uniform(-1.4, 1.4, 200)
    c = curvature(trig_sphere(R, analytic), u, v)
    tol = 1e-12 if analytic else 1e-8
    assert np.allclose(c.gaussian, 1 / R**2, rtol=tol, atol=0)
    assert np.allclose(c.mean, -1 / R, rtol=tol, atol=0)
    assert np.allclose(c.k1, -1 / R, rtol=tol) and np.allclose(c.k2, -1 / R, rtol=tol)
    assert np.allclose(c.normal, c.points / R, atol=1e-9)  # outward
    # the shape operator of a sphere is -1/R times the identity
    assert np.allclose(c.shape_operator, -np.eye(2) / R, atol=tol * 10)


def test_nurbs_sphere_including_poles():
    R = 3.0
    s = nurbs_sphere(R)
    us = np.linspace(0, 1, 41)
    c = curvature(s, us, np.linspace(0, 1, 33), grid=True)
    assert c.singular[:, 0].all() and c.singular[:, -1].all() and not c.singular[:, 1:-1].any()
    # outward normal: H = -1/R; at the poles the values are extrapolated limits
    assert np.allclose(c.gaussian, 1 / R**2, rtol=1e-7)
    assert np.allclose(c.mean, -1 / R, rtol=1e-7)
    assert np.allclose(c.normal, c.points / R, atol=1e-6)
    inner = ~c.singular
    assert np.allclose(c.gaussian[inner], 1 / R**2, rtol=1e-11)


def test_cylinder():
    R = 0.7
    rng = np.random.default_rng(2)
    c = curvature(cylinder(R), rng.uniform(0, 6, 100), rng.uniform(-2, 2, 100))
    assert np.allclose(c.gaussian, 0, atol=1e-8)
    assert np.allclose(c.mean, -1 / (2 * R), rtol=1e-8)
    assert np.allclose(c.k1, 0, atol=1e-8) and np.allclose(c.k2, -1 / R, rtol=1e-8)
    # the k1 = 0 direction is the axis, the k2 direction the circle
    assert np.allclose(np.abs(c.directions[:, 0, 2]), 1, atol=1e-7)
    assert np.allclose(c.directions[:, 1, 2], 0, atol=1e-7)


def test_torus_equators():
    R, r = 3.0, 1.0
    t = nurbs_torus(R, r)
    # v = 0: outer equator (tube angle 0), v = 0.5: inner equator
    c = curvature(t, np.linspace(0, 1, 9), np.zeros(9))
    assert np.allclose(np.abs(c.gaussian), 1 / (r * (R + r)), rtol=1e-12)
    assert (c.gaussian > 0).all()
    c = curvature(t, np.linspace(0, 1, 9), np.full(9, 0.5))
    assert np.allclose(c.gaussian, -1 / (r * (R - r)), rtol=1e-12)
    # everywhere: K = cos(phi) / (r (R + r cos(phi))) with phi the tube angle
    rng = np.random.default_rng(3)
    c = curvature(t, rng.uniform(0, 1, 200), rng.uniform(0, 1, 200))
    rho = np.hypot(c.points[:, 0], c.points[:, 1])
    cos_phi = (rho - R) / r
    assert np.allclose(c.gaussian, cos_phi / (r * (R + r * cos_phi)), rtol=1e-10, atol=1e-12)


def test_saddle_and_explicit_closed_forms():
    e = ExplicitSurface(lambda x, y: x * y, gradient=lambda x, y: np.stack([y, x], -1),
                        hessian=lambda x, y: np.stack([0 * x, 1 + 0 * x, 0 * x], -1))  # fmt: skip
    c = curvature(e, 0.0, 0.0)
    assert c.gaussian == pytest.approx(-1.0, abs=1e-15)
    assert c.mean == pytest.approx(0.0, abs=1e-15)
    assert c.k1 == pytest.approx(1.0) and c.k2 == pytest.approx(-1.0)
    # principal directions of z = xy at the origin bisect the axes
    assert np.allclose(np.abs(c.directions[..., :2]), W, atol=1e-12)
    rng = np.random.default_rng(4)
    x, y = rng.uniform(-2, 2, 100), rng.uniform(-2, 2, 100)
    for surface, tol in ((e, 1e-13), (ExplicitSurface(lambda x, y: x * y), 1e-8)):
        c = curvature(surface, x, y)
        w2 = 1 + x**2 + y**2
        assert np.allclose(c.gaussian, -1 / w2**2, rtol=tol)
        assert np.allclose(c.mean, -x * y / w2**1.5, rtol=tol, atol=tol)
        assert np.allclose(surface.gaussian_curvature(x, y), -1 / w2**2, rtol=tol)
        assert np.allclose(surface.mean_curvature(x, y), -x * y / w2**1.5, rtol=tol, atol=tol)


def test_paraboloid_numeric_matches_closed_form():
    e = ExplicitSurface(lambda x, y: 0.5 * (x**2 + 3 * y**2), domain=((-1, 1), (-1, 1)))
    c = curvature(e, 0.0, 0.0)
    assert c.k1 == pytest.approx(3.0, rel=1e-8) and c.k2 == pytest.approx(1.0, rel=1e-8)
    assert np.allclose(np.abs(c.directions[0]), [0, 1, 0], atol=1e-8)


@pytest.mark.parametrize("analytic", [True, False])
def test_implicit_sphere_and_torus(analytic):
    R = 1.7
    grad = (lambda p: p / np.linalg.norm(p, axis=1, keepdims=True)) if analytic else None
    sphere = ImplicitSurface(lambda p: np.linalg.norm(p, axis=1) - R, grad)
    rng = np.random.default_rng(5)
    d = rng.normal(size=(100, 3))
    p = R * d / np.linalg.norm(d, axis=1, keepdims=True)
    c = curvature(sphere, p)
    assert np.allclose(c.gaussian, 1 / R**2, rtol=1e-7)
    assert np.allclose(c.mean, -1 / R, rtol=1e-7)  # = -div(n)/2 with the outward normal
    assert np.allclose(c.normal, p / R, atol=1e-9)
    # the shape operator annihilates the normal and is -1/R on the tangent plane
    assert np.allclose(np.einsum("nij,nj->ni", c.shape_operator, c.normal), 0, atol=1e-7)
    Rt, rt = 2.0, 0.5
    torus = ImplicitSurface(lambda q: np.hypot(np.hypot(q[:, 0], q[:, 1]) - Rt, q[:, 2]) - rt)
    q = np.array([[Rt + rt, 0, 0], [0, Rt - rt, 0], [-(Rt + rt) * W, (Rt + rt) * W, 0]])
    c = curvature(torus, q)
    assert c.gaussian == pytest.approx([1 / (rt * (Rt + rt)), -1 / (rt * (Rt - rt)), 1 / (rt * (Rt + rt))], rel=1e-6)


def test_curvature_agrees_between_representations():
    """The same paraboloid as explicit, implicit and parametric surface."""
    f = lambda x, y: 0.3 * x**2 - 0.2 * x * y + 0.5 * y**2
    e = ExplicitSurface(f)
    rng = np.random.default_rng(6)
    x, y = rng.uniform(-1, 1, 50), rng.uniform(-1, 1, 50)
    ce = curvature(e, x, y)
    ci = curvature(e.to_implicit(), np.column_stack([x, y, f(x, y)]))
    # F = f - z has the downward normal: K agrees, H and k flip sign
    assert np.allclose(ci.gaussian, ce.gaussian, rtol=1e-6)
    assert np.allclose(ci.mean, -ce.mean, rtol=1e-6)
    assert np.allclose(ci.k1, -ce.k2, rtol=1e-6)


def test_grid_equals_pointwise_and_uv_directions_map_to_space():
    rng = np.random.default_rng(7)
    pu, pv, ku, kv, P, Wt = random_surface_data(rng, True, degrees=(3, 3))
    s = sk.NurbsSurface(pu, pv, ku, kv, P, Wt)
    (a, b), (c0, d0) = s.domain
    us, vs = np.linspace(a, b, 13), np.linspace(c0, d0, 11)
    g = curvature(s, us, vs, grid=True)
    U, V = np.meshgrid(us, vs, indexing="ij")
    p = curvature(s, U, V)
    assert g.gaussian.shape == (13, 11)
    scale = np.abs(p.k1).max() + np.abs(p.k2).max()
    assert np.allclose(g.k1, p.k1, atol=1e-9 * scale) and np.allclose(g.k2, p.k2, atol=1e-9 * scale)
    d = s.derivatives(U, V, 1)
    for k in (0, 1):
        du, dv = p.directions_uv[..., k, 0:1], p.directions_uv[..., k, 1:2]
        assert np.allclose(du * d[1, 0] + dv * d[0, 1], p.directions[..., k, :], atol=1e-8)
    # orthonormal principal frame (d1, d2, n)
    assert np.allclose(np.einsum("...i,...i->...", p.directions[..., 0, :], p.directions[..., 1, :]), 0, atol=1e-10)
    assert np.allclose(np.cross(p.directions[..., 0, :], p.directions[..., 1, :]), p.normal, atol=1e-10)
    # Euler: the normal curvature along d1 is k1 (II(d1, d1) / I(d1, d1) with (u, v) components)
    x = p.directions_uv[..., 0, :]
    II = p.second_form
    kn = np.einsum("...i,...ij,...j->...", x, II, x) / np.einsum("...i,...ij,...j->...", x, p.first_form, x)
    assert np.allclose(kn, p.k1, atol=1e-8 * scale)


def test_subdivision_patch_matches_the_bspline_patch():
    """A face of an all-valence-4 Catmull-Clark mesh is a uniform bicubic
    B-spline patch: its curvature at the centre must be that patch's."""
    nu, nv, R, r = 12, 8, 2.0, 0.6
    mesh = torus_cage(nu, nv, R, r)
    sub = sk.SubdivisionSurface(mesh, "catmull-clark")
    X = mesh.vertices.reshape(nu, nv, 3)
    net = np.concatenate([X, X[:3]], 0)
    net = np.concatenate([net, net[:, :3]], 1)
    # unclamped uniform knots: the periodic spline, domain [3, n + 3]
    spline = sk.BSplineSurface(3, 3, np.arange(nu + 7.0), np.arange(nv + 7.0), net)
    (a, b), (c0, d0) = spline.domain
    # face (i, j) lies between vertices i, i+1 and j, j+1: the spline's span
    # ((i - 1) mod nu, (j - 1) mod nv), whose controls are i-1..i+2, j-1..j+2
    faces = np.array([0, 13, 50])
    ki, kj = (faces // nv - 1) % nu, (faces % nv - 1) % nv
    cs = curvature(spline, a + (b - a) * (ki + 0.5) / nu, c0 + (d0 - c0) * (kj + 0.5) / nv)
    for k, f in enumerate(faces):
        cp = curvature(SubdivisionPatch(sub, f), 0.5, 0.5)
        assert cp.gaussian == pytest.approx(cs.gaussian[k], rel=1e-6)
        assert abs(cp.mean) == pytest.approx(abs(cs.mean[k]), rel=1e-6)


# -- geodesics ---------------------------------------------------------------------------
def _great_circle_angle(p, q):
    return np.arctan2(np.linalg.norm(np.cross(p, q)), p @ q)


@pytest.mark.parametrize("surface_kind", ["trig", "nurbs"])
def test_sphere_shortest_path_is_a_great_circle(surface_kind):
    R = 2.0
    s = trig_sphere(R) if surface_kind == "trig" else nurbs_sphere(R)
    rng = np.random.default_rng(8)
    (a, b), (c0, d0) = s.domain
    for _ in range(4):
        uv0 = [rng.uniform(a, b), c0 + (d0 - c0) * rng.uniform(0.2, 0.8)]
        uv1 = [rng.uniform(a, b), c0 + (d0 - c0) * rng.uniform(0.2, 0.8)]
        g = geodesic(s, uv0, uv1)
        p, q = g.points[0], g.points[-1]
        assert g.length == pytest.approx(R * _great_circle_angle(p, q), rel=1e-9)
        plane = np.cross(p, q) / np.linalg.norm(np.cross(p, q))
        # collocation (smooth parametrization) or the discrete energy minimum
        # (the NURBS sphere is only C1 at its knots): see geodesic's docstring
        assert np.abs(g.points @ plane).max() < (1e-7 if surface_kind == "trig" else 1e-4) * R
        assert np.allclose(np.linalg.norm(g.points, axis=1), R, rtol=1e-12)
        assert np.allclose(g.uv[0], uv0) and np.allclose(g.uv[-1], uv1)


def test_sphere_initial_value_geodesic_stays_on_a_great_circle():
    R = 1.3
    g = trace_geodesic(trig_sphere(R), [0.4, 0.1], [0.3, 1.0], 2.0)
    n = np.cross(g.points[0], g.points[len(g.points) // 2])
    assert np.abs(g.points @ (n / np.linalg.norm(n))).max() < 1e-9
    assert g.length == pytest.approx(2.0)
    chords = np.linalg.norm(np.diff(g.points, axis=0), axis=1)
    assert chords.sum() == pytest.approx(2.0, rel=1e-4)  # polyline of 201 samples
    assert R * _great_circle_angle(g.points[0], g.points[-1]) == pytest.approx(2.0, rel=1e-9)


def test_cylinder_geodesics_are_helices():
    R = 0.8
    s = cylinder(R)
    g = trace_geodesic(s, [0.5, -1.0], [1.0, 0.4], 3.0)  # (dt, dz) in parameters
    t, z = g.uv[:, 0], g.uv[:, 1]
    # a helix: z grows linearly with the unrolled angle, at slope dz / (R dt)
    angle = np.unwrap(t)
    assert np.allclose(np.diff(z) / np.diff(angle), 0.4 / 1.0, rtol=1e-8)
    assert np.allclose(np.hypot(g.points[:, 0], g.points[:, 1]), R)
    # shortest path between two points: the unrolled straight line
    uv0, uv1 = np.array([0.3, -1.0]), np.array([5.9, 1.5])
    h = geodesic(s, uv0, uv1)
    dt = (uv1[0] - uv0[0]) - 2 * np.pi  # across the seam is shorter
    assert h.length == pytest.approx(np.hypot(R * dt, uv1[1] - uv0[1]), rel=1e-7)


def test_geodesic_stops_at_an_open_boundary():
    flat = sk.BSplineSurface.uniform(1, 1, np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float))
    g = trace_geodesic(flat, [0.5, 0.5], [1.0, 0.0], 5.0)
    assert g.stopped and g.length == pytest.approx(0.5, rel=1e-9)
    h = geodesic(flat, [0.1, 0.2], [0.9, 0.7])
    assert h.length == pytest.approx(np.hypot(0.8, 0.5), rel=1e-9)


def test_christoffel_symbols_of_polar_coordinates():
    """The plane in polar coordinates: Gamma^r_tt = -r, Gamma^t_rt = 1/r."""
    plane = ParametricSurface(lambda r, t: np.stack([r * np.cos(t), r * np.sin(t), 0 * r], -1), domain=((0.5, 2), (0, 6)))
    r = np.array([0.7, 1.5])
    G = christoffel_symbols(plane.derivatives(r, np.array([1.0, 2.0]), 2))
    assert np.allclose(G[:, 0, 1, 1], -r, rtol=1e-8)
    assert np.allclose(G[:, 1, 0, 1], 1 / r, rtol=1e-8) and np.allclose(G[:, 1, 1, 0], 1 / r, rtol=1e-8)
    assert np.allclose(G[:, 0, 0, 0], 0, atol=1e-8)


# -- bad input -----------------------------------------------------------------------------
def test_bad_input():
    sphere = ImplicitSurface(lambda p: np.sum(p**2, axis=1) - 1.0)
    with pytest.raises(DomainError, match="gradient vanishes at point 1"):
        curvature(sphere, [[1.0, 0, 0], [0, 0, 0]])
    with pytest.raises(ParameterError, match=r"\(n, 3\)"):
        curvature(sphere, [[1.0, 0]])
    with pytest.raises(ParameterError, match="parametric surface"):
        curvature(object(), 0.0, 0.0)
    plane2d = sk.BSplineSurface.uniform(1, 1, np.zeros((2, 2, 2)) + np.arange(2)[:, None, None])
    with pytest.raises(ParameterError, match="3-D"):
        curvature(plane2d, 0.5, 0.5)
    s = trig_sphere(1.0)
    with pytest.raises(DomainError):
        curvature(s, 7.0, 0.0)
    with pytest.raises(SplineKitError):
        ParametricSurface(lambda u, v: np.zeros((u.size, 3))).derivatives(0.5, 0.5, order=3)
    with pytest.raises(ParameterError, match="raised"):
        curvature(ParametricSurface(lambda u, v: 1 / 0), 0.5, 0.5)
    with pytest.raises(DomainError, match="not finite"):
        curvature(ParametricSurface(lambda u, v: np.full((u.size, 3), np.nan)), 0.5, 0.5)
    with pytest.raises(ParameterError, match="length"):
        trace_geodesic(s, [1, 0], [1, 0], -1.0)
    with pytest.raises(ParameterError, match="tangent plane"):
        trace_geodesic(s, [1, 0], [0, 0, 0], 1.0)
    with pytest.raises(DomainError):
        geodesic(s, [1, 0], [1, 3])
    with pytest.raises(DomainError, match="singular"):
        trace_geodesic(s, [1, 0], [0, 1], 3.0)  # runs into the pole
    with pytest.raises(ParameterError, match="rtol"):
        trace_geodesic(s, [1, 0], [1, 0], 1.0, rtol=0.0)  # below DOP853's floor (scipy would only warn)
    with pytest.raises(ParameterError, match="samples"):
        trace_geodesic(s, [1, 0], [1, 0], 1.0, samples=10**10)
    with pytest.raises(ParameterError, match="samples"):
        geodesic(s, [1, 0.1], [1.2, 0.3], samples=10**10)
    with pytest.raises(ParameterError, match=r"\(2,\) and \(3,\)"):
        curvature(s, [0.5, 0.6], [0.1, 0.2, 0.3])
    with pytest.raises(ParameterError, match="needs both u and v"):
        curvature(s, [0.5], grid=True)
    with pytest.raises(ParameterError, match="shape"):
        christoffel_symbols(np.zeros((2, 2)))
    with pytest.raises(ParameterError, match="finite"):
        christoffel_symbols(np.full((3, 3, 1, 3), np.nan))
    line_like = np.zeros((3, 3, 1, 3))
    line_like[1, 0, 0] = line_like[0, 1, 0] = [1.0, 0.0, 0.0]  # S_u parallel to S_v
    with pytest.raises(ParameterError, match="singular at point"):
        christoffel_symbols(line_like)


def test_long_geodesics_are_bounded_not_hanging(monkeypatch):
    import splinekit.diffgeom.geodesics as geo

    s = trig_sphere(1.0)
    # a great circle 1e300 long would never finish: the evaluation budget stops it
    monkeypatch.setattr(geo, "MAX_EVALUATIONS", 500)
    with pytest.raises(ConvergenceError, match="gave up after 500 evaluations"):
        trace_geodesic(s, [1.0, 0.0], [1.0, 0.0], 1e300)  # the equator, round and round
    with pytest.raises(ParameterError, match="grid"):
        geodesic(s, [1, 0.1], [1.2, 0.3], grid=10**9)  # would need 1e18 nodes


@pytest.mark.parametrize("kind", ["nurbs", "bspline", "sphere", "bezier"])
def test_compiled_grid_kernel_matches_numpy_path(kind, monkeypatch):
    """Large grids run one fused compiled kernel (loaded here at once: by default only a
    large job, or enough work, loads it); it must agree with the numpy path (forced by
    SPLINEKIT_NUMBA=0) everywhere, including the poles of a sphere, which it hands back
    to the numpy path."""
    from splinekit import _kernels

    pytest.importorskip("numba")
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    MIN_POINTS = _kernels.MIN_WORK

    rng = np.random.default_rng(9)
    if kind == "sphere":
        s = nurbs_sphere(1.5)
    elif kind == "bezier":
        s = sk.BezierSurface(rng.normal(size=(5, 4, 3)), rng.uniform(0.5, 2, (5, 4)))
    else:
        pu, pv, ku, kv, P, Wt = random_surface_data(rng, kind == "nurbs", degrees=(3, 2))
        s = sk.NurbsSurface(pu, pv, ku, kv, P, Wt) if kind == "nurbs" else sk.BSplineSurface(pu, pv, ku, kv, P)
    (a, b), (c0, d0) = s.domain
    n = int(np.ceil(np.sqrt(MIN_POINTS))) + 1
    us, vs = np.linspace(a, b, n), np.linspace(c0, d0, n)
    fast = curvature(s, us, vs, grid=True)
    assert _kernels.get("splinekit.diffgeom._kernels") is not None
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    slow = curvature(s, us, vs, grid=True)
    assert np.array_equal(fast.singular, slow.singular)
    scale = max(np.abs(slow.k1).max(), np.abs(slow.k2).max())
    names = ("points", "normal", "E", "F", "G", "L", "M", "N", "directions", "directions_uv")
    for name in names[:-2] if kind == "sphere" else names:  # a sphere is all umbilics: any direction is principal
        ref = getattr(slow, name)
        assert np.allclose(getattr(fast, name), ref, atol=1e-10 * max(1.0, np.abs(ref).max())), name
    for name in ("mean", "k1", "k2", "shape_operator"):
        assert np.allclose(getattr(fast, name), getattr(slow, name), atol=1e-9 * scale), name
    assert np.allclose(fast.gaussian, slow.gaussian, atol=1e-9 * scale**2)


def test_implicit_numeric_derivatives_of_no_points():
    s = ImplicitSurface(lambda p: p[:, 0] ** 2 + p[:, 1])
    assert s.gradient(np.zeros((0, 3))).shape == (0, 3)
    assert s.hessian(np.zeros((0, 3))).shape == (0, 3, 3)


@pytest.mark.parametrize("numba", ["0", "1"])
def test_normals_where_an_iso_line_collapses_agree_on_grid_and_pointwise(monkeypatch, numba):
    """Degree 1 in u: at the interior knot u = 1 only the middle row of the net counts, and it is
    one repeated point, so S(1, v) is a point and Sv vanishes exactly; computed, Sv is round-off
    whose sign is arbitrary. Both paths must take the limit normal there, not the round-off's
    direction (before, 29 of these 200 surfaces gave opposite normals on the grid and pointwise)."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", numba)
    monkeypatch.setattr("splinekit._kernels.MIN_WORK", 0)
    rng = np.random.default_rng(1)
    for _ in range(200):
        P = np.full((3, 6, 3), 1.75)
        P[2, rng.integers(0, 6), rng.integers(0, 3)] = rng.uniform(-2, 2)
        kv = np.concatenate([[0, 0, 0, 0], np.sort(rng.uniform(0, 1, 2)), [1, 1, 1, 1]])
        s = sk.BSplineSurface(1, 3, [0, 0, 1, 2, 3], kv, P)
        vs = rng.uniform(0, 1, 50)
        grid = s.normal_grid(np.array([1.0]), vs)[0]
        pointwise = s.normal(np.ones_like(vs), vs)
        np.testing.assert_allclose(grid, pointwise, rtol=0, atol=1e-9)
        length = np.linalg.norm(grid, axis=-1)
        assert np.all((np.abs(length - 1) < 1e-12) | (length == 0))
