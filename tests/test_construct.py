"""Geometric construction (splinekit.construct): conics, compatibility, and surfaces from curves.

References are independent of the code under test: closed forms (radii of
circles, spheres, tori, cones; the ellipse's implicit equation; the bilinear
Coons formula), OpenCascade (in tests/occ/test_construct_occ.py), and invariants
(interpolation of the input curves, reproduction of polynomial surfaces).

Tolerances: conics and surfaces of revolution 1e-14 relative to the radius
(a few ulps of the rational evaluation); compatibility and Boolean sums 1e-12
relative to the size of the control nets; skinning (a linear solve) 1e-10
relative; sweeps to the tolerance they were built for.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _geometry import random_curve_data, random_points
from hypothesis import given, settings
from hypothesis import strategies as st
from splinekit import BezierSurface, BSplineCurve, BSplineSurface, NurbsCurve
from splinekit.construct import (
    arc,
    arc_through_points,
    bicubic_coons,
    circle,
    coons,
    ellipse,
    extrude,
    gordon,
    line,
    loft,
    make_compatible,
    polyline,
    revolve,
    ruled,
    sweep,
)
from splinekit.construct.sweep import sweep_deviation
from splinekit.errors import SplineKitError

SALT = 4047
RADIUS_RTOL = 1e-14


def rng_for(*key):
    return np.random.default_rng([SALT, *key])


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def random_direction(rng):
    return unit(rng.normal(size=3))


def random_curve(rng, rational, dim=3, max_degree=5):
    p, U, P, W = random_curve_data(rng, rational, max_degree=max_degree)
    P = random_points(rng, (len(P),), dim)
    return NurbsCurve(p, U, P, W) if rational else BSplineCurve(p, U, P)


def dense(n=201):
    return np.linspace(0.0, 1.0, n)


def grid_uv(surface, n=31):
    (a, b), (c, d) = surface.domain
    U, V = np.meshgrid(np.linspace(a, b, n), np.linspace(c, d, n), indexing="ij")
    return U.ravel(), V.ravel()


# == curves ========================================================================================
@pytest.mark.parametrize("seed", range(30))
def test_arc_radius_plane_and_angles(seed):
    rng = rng_for(1, seed)
    center = rng.uniform(-50, 50, 3)
    normal = rng.normal(size=3)
    x_axis = rng.normal(size=3)
    radius = 10.0 ** rng.uniform(-2, 3)
    start = rng.uniform(-7, 7)
    sweep_angle = rng.choice([-1.0, 1.0]) * rng.uniform(0.01, 2 * math.pi)
    c = arc(center, normal, radius, start, start + sweep_angle, x_axis=x_axis)
    P = c.evaluate(dense(401))
    n = unit(normal)
    X = unit(x_axis - np.dot(x_axis, n) * n)
    Y = np.cross(n, X)
    d = P - center
    scale = radius + np.abs(center).max()
    assert np.abs(np.linalg.norm(d, axis=1) - radius).max() <= RADIUS_RTOL * 8 * scale
    assert np.abs(d @ n).max() <= 1e-14 * 8 * scale
    # the angle grows monotonically from start to start + sweep
    theta = np.unwrap(np.arctan2(d @ Y, d @ X))
    theta += 2 * math.pi * round((start - theta[0]) / (2 * math.pi))
    assert abs(theta[0] - start) < 1e-9
    assert abs(theta[-1] - (start + sweep_angle)) < 1e-9
    steps = np.diff(theta) * np.sign(sweep_angle)
    assert (steps > 0).all()
    # A7.1: segments of at most 90 degrees
    assert len(c) == 2 * math.ceil(abs(sweep_angle) / (math.pi / 2) - 1e-9) + 1


def test_2d_circle_and_arc_through_points():
    c = circle([1.0, -2.0], None, 3.0)
    assert c.dim == 2
    P = c.evaluate(dense())
    assert np.abs(np.linalg.norm(P - [1.0, -2.0], axis=1) - 3.0).max() <= 3 * 8 * RADIUS_RTOL
    # clockwise 2-D arc through three points
    p0, p1, p2 = np.array([2.0, 0.0]), np.array([0.0, -2.0]), np.array([-2.0, 0.0])
    a = arc_through_points(p0, p1, p2)
    assert a.dim == 2
    Q = a.evaluate(dense())
    assert np.abs(np.linalg.norm(Q, axis=1) - 2.0).max() <= 1e-14 * 16
    assert (Q[:, 1] <= 1e-14).all()  # the lower half: the arc runs through p1
    assert np.array_equal(a.evaluate(0.0), p0) and np.array_equal(a.evaluate(1.0), p2)


@pytest.mark.parametrize("scale", [1e-200, 1e-60, 1.0, 1e60, 1e200, 1e300])
def test_arc_through_points_at_extreme_scales(scale):
    # three points of the circle of centre (1, 0, 0) and radius 1, scaled: closed form
    p0, p1, p2 = (np.array(p) * scale for p in ([0.0, 0, 0], [1.0, 1, 0], [2.0, 0, 0]))
    a = arc_through_points(p0, p1, p2)
    P = a.evaluate(dense()) / scale
    assert np.isfinite(P).all()
    assert np.abs(np.linalg.norm(P - [1.0, 0.0, 0.0], axis=1) - 1.0).max() <= 1e-14 * 16
    assert (P[:, 1] >= -1e-14).all()  # the upper half: the arc runs through p1
    assert np.array_equal(a.evaluate(0.0), p0) and np.array_equal(a.evaluate(1.0), p2)


def test_line_and_polyline():
    ln = line([0.0, 1.0, 2.0], [3.0, 5.0, 2.0])
    assert np.allclose(ln.evaluate(0.25), [0.75, 2.0, 2.0], rtol=0, atol=1e-15)
    pts = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 10.0]])
    pl = polyline(pts)
    # chord-length knots: the corner at 5 / 11 of the length
    assert pl.degree == 1
    assert np.allclose(pl.evaluate(5.0 / 11.0), pts[1], rtol=0, atol=1e-14)
    assert np.allclose(pl.evaluate(np.array([0.0, 1.0])), pts[[0, 2]], rtol=0, atol=0)


# == compatibility ================================================================================
def _check_compatible(curves, out):
    assert len(out) == len(curves)
    first = out[0]
    for c in out:
        assert c.degree == max(x.degree for x in curves)
        assert np.array_equal(c.knots, first.knots)
        assert c.is_rational == any(x.is_rational for x in curves)
    a, b = first.domain
    s = np.linspace(0.0, 1.0, 101)
    for old, new in zip(curves, out):
        a0, b0 = old.domain
        scale = max(1.0, np.abs(old.control_points).max())
        diff = new.evaluate(a + s * (b - a)) - old.evaluate(a0 + s * (b0 - a0))
        assert np.abs(diff).max() <= 1e-11 * scale


@pytest.mark.parametrize("seed", range(20))
def test_make_compatible_keeps_geometry(seed):
    rng = rng_for(5, seed)
    k = int(rng.integers(2, 5))
    curves = [random_curve(rng, bool(rng.integers(0, 2)), max_degree=5) for _ in range(k)]
    _check_compatible(curves, make_compatible(curves))


def test_make_compatible_on_a_given_domain_and_in_2d():
    rng = rng_for(17)
    curves = [random_curve(rng, r, dim=2) for r in (False, True, False)]
    out = make_compatible(curves, domain=(-1.0, 2.0))
    assert all(c.domain == (-1.0, 2.0) for c in out)
    _check_compatible(curves, out)
    # a 2-D extrusion is a planar patch: S(u, v) = C(u) + v * vector
    S = extrude(curves[0], [0.5, -1.0])
    (a, b), _ = S.domain
    u = np.linspace(a, b, 7)
    assert np.abs(S.evaluate(u, np.full(7, 0.5)) - (curves[0].evaluate(u) + [0.25, -0.5])).max() <= 1e-12 * 100


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 4))
def test_make_compatible_is_idempotent(seed, k):
    rng = np.random.default_rng(seed)
    curves = [random_curve(rng, bool(rng.integers(0, 2)), dim=2, max_degree=4) for _ in range(k)]
    once = make_compatible(curves)
    twice = make_compatible(once)
    for x, y in zip(once, twice):
        assert x.almost_equal(y, 0.0)


# == extrude and ruled =============================================================================
@pytest.mark.parametrize("rational", [False, True])
def test_extrude_and_ruled(rational):
    rng = rng_for(6, rational)
    c0 = random_curve(rng, rational)
    c1 = random_curve(rng, not rational)
    vec = rng.normal(size=3) * 5
    S = extrude(c0, vec)
    (a, b), _ = S.domain
    u = rng.uniform(a, b, 200)
    v = rng.uniform(0, 1, 200)
    scale = np.abs(S.control_points).max()
    assert np.abs(S.evaluate(u, v) - (c0.evaluate(u) + v[:, None] * vec)).max() <= 1e-12 * scale
    R = ruled(c0, c1)
    (a, b), _ = R.domain
    a1, b1 = c1.domain
    s = rng.uniform(0, 1, 200)
    uu = a + s * (b - a)
    p0, p1 = c0.evaluate(uu), c1.evaluate(a1 + s * (b1 - a1))
    scale = max(np.abs(p0).max(), np.abs(p1).max())
    assert np.abs(R.evaluate(uu, np.zeros(200)) - p0).max() <= 1e-12 * scale
    assert np.abs(R.evaluate(uu, np.ones(200)) - p1).max() <= 1e-12 * scale
    # every v-line is the straight segment between the two curves' points
    X = R.evaluate(uu, v)
    cross = np.cross(X - p0, p1 - p0)
    assert np.abs(cross).max() <= 1e-10 * scale**2


# == revolve =======================================================================================
def test_revolved_semicircle_is_a_sphere():
    rng = rng_for(7)
    for _ in range(5):
        center = rng.uniform(-3, 3, 3)
        axis = random_direction(rng)
        r = rng.uniform(0.5, 5)
        x = unit(np.cross(axis, rng.normal(size=3)))
        # a half circle in a plane containing the axis, from pole to pole
        semi = arc(center, np.cross(x, axis), r, -math.pi / 2, math.pi / 2, x_axis=x)
        S = revolve(semi, center, axis)
        P = S.evaluate(*grid_uv(S, 41))
        assert np.abs(np.linalg.norm(P - center, axis=1) - r).max() <= RADIUS_RTOL * 8 * (r + 3)


def test_revolved_lines_are_cylinder_and_cone():
    axis = unit([1.0, 2.0, 2.0])
    origin = np.array([0.5, -1.0, 2.0])
    side = unit(np.cross(axis, [0.0, 0.0, 1.0]))
    # parallel to the axis at distance 2: a cylinder
    cyl = revolve(line(origin + 2 * side, origin + 2 * side + 3 * axis), origin, axis)
    P = cyl.evaluate(*grid_uv(cyl))
    d = P - origin
    radial = np.linalg.norm(d - np.outer(d @ axis, axis), axis=1)
    assert np.abs(radial - 2.0).max() <= 1e-14 * 16
    # oblique, meeting the axis at the origin: a cone of half angle atan(1/2)
    cone = revolve(line(origin, origin + 1 * side + 2 * axis), origin, axis, angle=4.0)
    P = cone.evaluate(*grid_uv(cone))
    d = P - origin
    h = d @ axis
    radial = np.linalg.norm(d - np.outer(h, axis), axis=1)
    assert np.abs(radial - 0.5 * h).max() <= 1e-14 * 16


def test_revolved_circle_is_a_torus_and_partial_angles():
    R, r = 3.0, 0.7
    profile = circle([R, 0.0, 0.0], [0.0, 1.0, 0.0], r)
    for angle in (2 * math.pi, 1.0, -2.5, math.pi / 2):
        T = revolve(profile, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], angle)
        P = T.evaluate(*grid_uv(T))
        rho = np.hypot(P[:, 0], P[:, 1])
        assert np.abs(np.hypot(rho - R, P[:, 2]) - r).max() <= 1e-14 * 16 * (R + r)
        # the end of the sweep: the profile turned by angle
        end = T.isocurve(u=1.0).evaluate(dense(11))
        start = profile.evaluate(dense(11))
        c, s = math.cos(angle), math.sin(angle)
        turned = start @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
        assert np.abs(end - turned).max() <= 1e-13 * (R + r)


def _arc_angle(knots, u, angle):
    """Angle of the A7.1 arc of sweep ``angle`` at parameters ``u`` (closed form:
    tan(phi / 2) = tan(alpha / 2) (2 t - 1) on a segment of half-angle alpha)."""
    n_seg = (knots.size - 4) // 2
    alpha = angle / n_seg / 2
    k = np.minimum((u * n_seg).astype(int), n_seg - 1)
    t = u * n_seg - k
    return 2 * alpha * k + alpha + 2 * np.arctan(math.tan(alpha / 2) * (2 * t - 1))


# == loft ==========================================================================================
@pytest.mark.parametrize("seed", range(8))
def test_loft_passes_through_sections(seed):
    rng = rng_for(9, seed)
    k = int(rng.integers(2, 6))
    rational = seed % 2 == 1
    # sections: different random curves, shrunk and stacked along z so that they do not cross
    sections = []
    for i in range(k):
        c = random_curve(rng, False, max_degree=4)
        P = 0.2 * (c.control_points - c.control_points.mean(0)) / np.abs(c.control_points).max()
        P = P + [0.0, 0.0, 1.0 * i]
        if rational:
            # weights in [0.8, 1.25]: interpolating zigzagging weights across sections can leave
            # non-positive control weights (a FittingError, tested below)
            sections.append(NurbsCurve(c.degree, c.knots, P, rng.uniform(0.8, 1.25, len(P))))
        else:
            sections.append(BSplineCurve(c.degree, c.knots, P))
    params = 1.5 * np.arange(k) + rng.uniform(0, 1, k) - 4.0
    S = loft(sections, 3, parameters=params)
    assert S.degree_v == min(3, k - 1)
    assert S.is_rational == rational
    assert S.domain[1] == (params[0], params[-1])
    s = np.linspace(0, 1, 50)
    (a, b), _ = S.domain
    for t, c in zip(params, sections):
        got = S.evaluate(a + s * (b - a), np.full(50, t))
        assert np.abs(got - _at(c, s)).max() <= 1e-10 * 5
    # default parameters: the end sections are the v-boundaries
    D = loft(sections)
    (a, b), (c0, c1) = D.domain
    assert np.abs(D.evaluate(a + s * (b - a), np.full(50, c0)) - _at(sections[0], s)).max() <= 1e-10 * 5
    assert np.abs(D.evaluate(a + s * (b - a), np.full(50, c1)) - _at(sections[-1], s)).max() <= 1e-10 * 5


def test_loft_default_parameters_pass_through_sections():
    # equally spaced parallel circles: the centripetal parameters are uniform
    sections = [circle([0, 0, 2.0 * i], [0, 0, 1], 1.0 + 0.3 * i) for i in range(5)]
    S = loft(sections)
    for i, c in enumerate(sections):
        got = S.evaluate(dense(), np.full(201, i / 4))
        assert np.abs(got - c.evaluate(dense())).max() <= 1e-12 * 4
    # between sections the skin of coaxial circles stays a surface of revolution
    P = S.evaluate(*grid_uv(S))
    rho = np.hypot(P[:, 0], P[:, 1])
    expected = 1.0 + 0.3 * P[:, 2] / 2.0
    assert np.abs(rho - expected).max() <= 1e-12 * 4


def test_loft_refuses_rational_sections_whose_weights_cannot_be_interpolated():
    # the middle control weight zigzags 1, 50, 1, 50, 1 across the sections: the interpolating cubic
    # of the homogeneous weights has negative control weights
    sections = []
    for i in range(5):
        w = [1.0, 50.0 if i % 2 else 1.0 / 50.0, 1.0]
        sections.append(NurbsCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, i], [1, 1, i], [2, 0, i]], w))
    with pytest.raises(SplineKitError, match="non-positive weight"):
        loft(sections)


# == sweep =========================================================================================
def test_sweep_along_a_line_is_a_cylinder():
    d = unit([1.0, 2.0, 3.0])
    S = sweep(circle([0.0, 0.0], None, 0.3), line([1, 1, 1], np.array([1, 1, 1]) + 4 * d))
    P = S.evaluate(*grid_uv(S)) - 1.0
    radial = np.linalg.norm(P - np.outer(P @ d, d), axis=1)
    assert np.abs(radial - 0.3).max() <= 1e-13
    # a polynomial profile (a square) gives a prism: every point at the same (x, y) offset in the frame
    square = polyline([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]])
    path = line([0, 0, 0], [0, 0, 5])
    S = sweep(square, path, n_sections=4, normal=[1, 0, 0])
    assert not S.is_rational
    s = dense(41)
    for v in (0.0, 0.37, 1.0):
        P = S.evaluate(s, np.full_like(s, v))
        assert np.abs(P[:, :2] - square.evaluate(s)).max() <= 1e-14 * 8
        assert np.abs(P[:, 2] - 5 * v).max() <= 1e-14 * 8


@pytest.mark.parametrize("tolerance", [1e-4, 1e-8])
def test_sweep_along_an_arc_is_a_torus_section(tolerance):
    R, r = 2.0, 0.3
    path = arc([0, 0, 0], [0, 0, 1], R, 0.0, 2.5)
    for profile in (circle([0, 0], None, r), circle([R, 0, 0], [0, 1, 0], r)):
        S = sweep(profile, path, tolerance=tolerance)
        P = S.evaluate(*grid_uv(S, 101))
        rho = np.hypot(P[:, 0], P[:, 1])
        assert np.abs(np.hypot(rho - R, P[:, 2]) - r).max() <= tolerance
        # the sweep ends in the plane at angle 2.5, on the tube circle there
        end = S.isocurve(v=1.0).evaluate(dense(21))
        assert np.abs(end @ [-math.sin(2.5), math.cos(2.5), 0.0]).max() <= tolerance
        assert sweep_deviation(profile, path, S, samples=np.linspace(0, 1, 1001)) <= tolerance


def test_sweep_with_fixed_sections_and_random_path():
    rng = rng_for(10)
    path = BSplineCurve.uniform(3, rng.normal(size=(7, 3)) * 3)
    profile = ellipse([0, 0], None, 0.2, 0.1)
    S = sweep(profile, path, n_sections=13)
    assert S.shape[1] >= 13
    S2 = sweep(profile, path, tolerance=1e-6)
    assert sweep_deviation(profile, path, S2, samples=np.linspace(0, 1, 2001)) <= 1e-6
    # every station section is the profile placed exactly: the surface's u-curves at the path's knots
    # are congruent to the profile (same distances between their points)
    prof_pts = profile.evaluate(dense(9))
    sec = S2.isocurve(v=path.bezier_breakpoints()[1]).evaluate(dense(9))
    dp = np.linalg.norm(prof_pts[:, None] - prof_pts[None], axis=-1)
    ds = np.linalg.norm(sec[:, None] - sec[None], axis=-1)
    assert np.abs(dp - ds).max() <= 1e-9


# == Coons =========================================================================================
def _boundary_curves(rng, rational=False):
    P00, P10, P01, P11 = rng.uniform(-3, 3, (4, 3))

    def crv(a, b):
        p = int(rng.integers(1, 5))
        n = p + 1 + int(rng.integers(0, 4))
        pts = np.linspace(a, b, n) + 0.5 * rng.normal(size=(n, 3))
        pts[0], pts[-1] = a, b
        lo = rng.uniform(-2, 2)
        knots = np.concatenate([[lo] * (p + 1), np.sort(rng.uniform(lo, lo + 3, n - p - 1)), [lo + 3] * (p + 1)])
        if rational:
            w = rng.uniform(0.5, 2.0, n)
            w[0] = w[-1] = 1.0  # equal end weights: the corners agree in homogeneous space
            return NurbsCurve(p, knots, pts, w)
        return BSplineCurve(p, knots, pts)

    return crv(P00, P10), crv(P01, P11), crv(P00, P01), crv(P10, P11)


def _at(curve, s):
    a, b = curve.domain
    return curve.evaluate(a + s * (b - a))


@pytest.mark.parametrize("seed", range(10))
def test_coons_boundaries_and_closed_form(seed):
    rng = rng_for(11, seed)
    c0, c1, d0, d1 = _boundary_curves(rng, rational=seed % 2 == 1)
    S = coons(c0, c1, d0, d1)
    (a, b), (c, d) = S.domain
    s = np.linspace(0, 1, 101)
    u, v = a + s * (b - a), c + s * (d - c)
    zeros, ones = np.zeros_like(s), np.ones_like(s)
    tol = 1e-12 * 8
    assert np.abs(S.evaluate(u, c + 0 * s) - _at(c0, s)).max() <= tol
    assert np.abs(S.evaluate(u, d + 0 * s) - _at(c1, s)).max() <= tol
    assert np.abs(S.evaluate(a + 0 * s, v) - _at(d0, s)).max() <= tol
    assert np.abs(S.evaluate(b + 0 * s, v) - _at(d1, s)).max() <= tol
    if seed % 2 == 1:
        return  # rational boundaries are blended in homogeneous space: only the boundaries are the formula's
    # interior: the bilinearly blended Coons formula
    x, y = rng.uniform(0, 1, 200), rng.uniform(0, 1, 200)
    P00, P10, P01, P11 = (_at(c0, zeros[:1])[0], _at(c0, ones[:1])[0], _at(c1, zeros[:1])[0], _at(c1, ones[:1])[0])
    ref = ((1 - y)[:, None] * _at(c0, x) + y[:, None] * _at(c1, x) + (1 - x)[:, None] * _at(d0, y) + x[:, None] * _at(d1, y)
           - ((1 - x) * (1 - y))[:, None] * P00 - (x * (1 - y))[:, None] * P10 - ((1 - x) * y)[:, None] * P01
           - (x * y)[:, None] * P11)
    assert np.abs(S.evaluate(a + x * (b - a), c + y * (d - c)) - ref).max() <= tol


def test_coons_of_four_arcs_keeps_the_circles():
    # an annulus sector: two concentric arcs and two radial lines
    S = coons(arc([0, 0, 0], [0, 0, 1], 1, 0, 2), arc([0, 0, 0], [0, 0, 1], 2, 0, 2),
              line([1, 0, 0], [2, 0, 0]), line([math.cos(2), math.sin(2), 0], [2 * math.cos(2), 2 * math.sin(2), 0]))
    assert S.is_rational
    s = dense()
    assert np.abs(np.linalg.norm(S.evaluate(s, 0 * s), axis=1) - 1).max() <= 1e-14 * 8
    assert np.abs(np.linalg.norm(S.evaluate(s, 0 * s + 1), axis=1) - 2).max() <= 1e-14 * 8


def test_coons_rational_end_weights_are_rescaled_or_refused():
    inner = arc([0, 0, 0], [0, 0, 1], 1, 0, 2)
    outer = arc([0, 0, 0], [0, 0, 1], 2, 0, 2)
    left = line([1, 0, 0], [2, 0, 0])
    right = line([math.cos(2), math.sin(2), 0], [2 * math.cos(2), 2 * math.sin(2), 0])
    # the same curve with all weights times 3: rescaled, the patch keeps the circles
    heavy = NurbsCurve(2, inner.knots, inner.control_points, 3 * inner.weights)
    S = coons(heavy, outer, left, right)
    s = dense()
    assert np.abs(np.linalg.norm(S.evaluate(s, 0 * s), axis=1) - 1).max() <= 1e-14 * 8
    assert np.abs(S.evaluate(0 * s, s) - left.evaluate(s)).max() <= 1e-14 * 8
    # end weights 1 and 2 on one boundary only: no per-curve scaling makes all corners agree
    w = inner.weights.copy()
    w[-1] = 2.0
    lopsided = NurbsCurve(2, inner.knots, inner.control_points, w)
    with pytest.raises(SplineKitError, match="end weights"):
        coons(lopsided, outer, left, right)


def test_coons_corner_tolerance():
    c0, c1 = line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0])
    d0, d1 = line([0, 0, 0], [0, 1, 0]), line([1, 0, 0], [1, 1 + 1e-6, 0])
    with pytest.raises(SplineKitError, match="corner"):
        coons(c0, c1, d0, d1)
    S = coons(c0, c1, d0, d1, tol=1e-5)
    s = dense(11)
    assert np.abs(S.evaluate(s, 0 * s + 1) - c1.evaluate(s)).max() <= 1e-15
    assert np.abs(S.evaluate(0 * s + 1, s) - d1.evaluate(s)).max() <= 1e-6


def _bezier_data(rng):
    """A random bicubic patch on [0, 1]^2 with its boundaries, cross derivatives and twists as curves."""
    P = rng.uniform(-2, 2, (4, 4, 3))
    F = BSplineSurface(3, 3, [0] * 4 + [1] * 4, [0] * 4 + [1] * 4, P)
    K = [0.0] * 4 + [1.0] * 4

    def bound(pts):
        return BSplineCurve(3, K, pts)

    c0, c1, d0, d1 = bound(P[:, 0]), bound(P[:, 3]), bound(P[0]), bound(P[3])
    # dS/dv along v = 0, 1 and dS/du along u = 0, 1 (derivative of a cubic Bézier: 3 * differences)
    g0, g1 = bound(3 * (P[:, 1] - P[:, 0])), bound(3 * (P[:, 3] - P[:, 2]))
    f0, f1 = bound(3 * (P[1] - P[0])), bound(3 * (P[3] - P[2]))
    return F, (c0, c1, d0, d1), (g0, g1, f0, f1)


@pytest.mark.parametrize("seed", range(6))
def test_bicubic_coons_reproduces_a_bicubic_patch(seed):
    rng = rng_for(13, seed)
    F, (c0, c1, d0, d1), (g0, g1, f0, f1) = _bezier_data(rng)
    u, v = rng.uniform(0, 1, 100), rng.uniform(0, 1, 100)
    full = bicubic_coons(c0, c1, d0, d1, c0_cross=g0, c1_cross=g1, d0_cross=f0, d1_cross=f1)
    assert np.abs(full.evaluate(u, v) - F.evaluate(u, v)).max() <= 1e-12 * 8
    # one pair of cross derivatives: still exact on the cross derivatives it was given
    half = bicubic_coons(c0, c1, d0, d1, c0_cross=g0, c1_cross=g1)
    s = dense(51)
    dS = half.derivatives(s, np.zeros_like(s), 1)[0, 1]
    assert np.abs(dS - g0.evaluate(s)).max() <= 1e-11 * 8
    # default: cross derivative along v = 0 is the Hermite blend of the side curves' end tangents
    plain = bicubic_coons(c0, c1, d0, d1)
    H0, H1 = 1 - 3 * s**2 + 2 * s**3, 3 * s**2 - 2 * s**3
    expect = H0[:, None] * d0.derivatives(0.0, 1)[1] + H1[:, None] * d1.derivatives(0.0, 1)[1]
    assert np.abs(plain.derivatives(s, np.zeros_like(s), 1)[0, 1] - expect).max() <= 1e-11 * 8


def test_bicubic_coons_refuses_inconsistent_cross_derivatives():
    rng = rng_for(14)
    _, (c0, c1, d0, d1), (g0, g1, f0, f1) = _bezier_data(rng)
    with pytest.raises(SplineKitError, match="c0_cross"):
        bicubic_coons(c0, c1, d0, d1, c0_cross=g0.transform(2 * np.eye(3)), c1_cross=g1)
    with pytest.raises(SplineKitError, match="together"):
        bicubic_coons(c0, c1, d0, d1, c0_cross=g0)
    bad_twist = BSplineCurve(3, [0] * 4 + [1] * 4, f0.control_points + [[0, 0, 0], [1, 1, 1], [0, 0, 0], [0, 0, 0]])
    with pytest.raises(SplineKitError, match="twist"):
        bicubic_coons(c0, c1, d0, d1, c0_cross=g0, c1_cross=g1, d0_cross=bad_twist, d1_cross=f1)


# == Gordon ========================================================================================
@pytest.mark.parametrize("seed", range(6))
def test_gordon_reproduces_a_bicubic_patch_and_passes_through_the_network(seed):
    rng = rng_for(15, seed)
    F, *_ = _bezier_data(rng)
    us = np.concatenate([[0.0], np.sort(rng.uniform(0.1, 0.9, 2 + seed % 3)), [1.0]])
    vs = np.concatenate([[0.0], np.sort(rng.uniform(0.1, 0.9, 2)), [1.0]])
    u_curves = [F.isocurve(v=float(v)) for v in vs]
    v_curves = [F.isocurve(u=float(u)) for u in us]
    for params in ({}, {"u_parameters": us, "v_parameters": vs}):
        G = gordon(u_curves, v_curves, **params)
        x, y = rng.uniform(0, 1, 100), rng.uniform(0, 1, 100)
        assert np.abs(G.evaluate(x, y) - F.evaluate(x, y)).max() <= 1e-10
        s = dense(41)
        for v, c in zip(vs, u_curves):
            assert np.abs(G.evaluate(s, np.full_like(s, v)) - c.evaluate(s)).max() <= 1e-10
        for u, c in zip(us, v_curves):
            assert np.abs(G.evaluate(np.full_like(s, u), s) - c.evaluate(s)).max() <= 1e-10


def test_gordon_network_of_parabolas():
    # z = x^2 + y^2 sampled by exact parabolas; the network has unequal counts
    def par_u(y):
        return BSplineCurve(2, [-1, -1, -1, 1, 1, 1], [[-1, y, 1 + y * y], [0, y, -1 + y * y], [1, y, 1 + y * y]])

    def par_v(x):
        return BSplineCurve(2, [-1, -1, -1, 1, 1, 1], [[x, -1, 1 + x * x], [x, 0, -1 + x * x], [x, 1, 1 + x * x]])

    ys, xs = [-1, -0.3, 0.4, 1], [-1, -0.5, 0.2, 0.6, 1]
    G = gordon([par_u(y) for y in ys], [par_v(x) for x in xs])
    U, V = np.meshgrid(np.linspace(-1, 1, 31), np.linspace(-1, 1, 31))
    P = G.evaluate(U.ravel(), V.ravel())
    assert np.abs(P[:, 2] - P[:, 0] ** 2 - P[:, 1] ** 2).max() <= 1e-13


def test_gordon_refuses_a_network_that_does_not_intersect():
    rng = rng_for(16)
    F, *_ = _bezier_data(rng)
    u_curves = [F.isocurve(v=v) for v in (0.0, 0.5, 1.0)]
    v_curves = [F.isocurve(u=u) for u in (0.0, 0.5, 1.0)]
    moved = v_curves[1].transform(np.array([[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    with pytest.raises(SplineKitError, match="does not intersect"):
        gordon(u_curves, [v_curves[0], moved, v_curves[2]], u_parameters=[0, 0.5, 1], v_parameters=[0, 0.5, 1])
    with pytest.raises(SplineKitError, match="increase"):
        gordon(u_curves, v_curves, u_parameters=[0, 0, 1], v_parameters=[0, 0.5, 1])
    with pytest.raises(SplineKitError, match="at least 2"):
        gordon(u_curves[:1], v_curves)


# == bad input =====================================================================================
Z = [0.0, 0.0, 1.0]


@pytest.mark.parametrize(
    "call",
    [
        lambda: circle([0, 0, 0], Z, 0.0),
        lambda: circle([0, 0, 0], Z, -1.0),
        lambda: circle([0, 0, 0], Z, float("nan")),
        lambda: circle([0, 0, 0], [0, 0, 0], 1.0),
        lambda: circle([0, 0, 0], None, 1.0),
        lambda: circle([0, 0], Z, 1.0),
        lambda: circle([0, 0, 0, 0], Z, 1.0),
        lambda: circle("abc", Z, 1.0),
        lambda: arc([0, 0, 0], Z, 1.0, 0.5, 0.5),
        lambda: arc([0, 0, 0], Z, 1.0, 0.0, 7.0),
        lambda: arc([0, 0, 0], Z, 1.0, 0.0, 1.0, x_axis=[0, 0, 2]),
        lambda: arc([0, 0, 0], Z, 1.0, 0.0, float("inf")),
        lambda: ellipse([0, 0, 0], Z, 1.0, 2.0),
        lambda: ellipse([0, 0, 0], Z, 1.0, 0.0),
        lambda: arc_through_points([0, 0, 0], [1, 1, 1], [2, 2, 2]),
        lambda: arc_through_points([0, 0, 0], [0, 0, 0], [2, 2, 2]),
        lambda: arc_through_points([0, 0], [1, 0, 0], [2, 2, 2]),
        lambda: line([0, 0], [0, 0]),
        lambda: line([0, 0], [0, 0, 1]),
        lambda: polyline([[0, 0], [1, 1], [1, 1]]),
        lambda: polyline([[0, 0]]),
        lambda: make_compatible([]),
        lambda: make_compatible([line([0, 0], [1, 1]), line([0, 0, 0], [1, 1, 1])]),
        lambda: make_compatible([line([0, 0], [1, 1]), "curve"]),
        lambda: make_compatible([line([0, 0], [1, 1])], domain=(1, 0)),
        lambda: extrude(line([0, 0, 0], [1, 0, 0]), [0, 0, 0]),
        lambda: extrude(line([0, 0, 0], [1, 0, 0]), [0, 1]),
        lambda: ruled(line([0, 0, 0], [1, 0, 0]), line([0, 0], [1, 0])),
        lambda: revolve(line([1, 0, 0], [1, 0, 1]), [0, 0, 0], [0, 0, 0]),
        lambda: revolve(line([1, 0, 0], [1, 0, 1]), [0, 0, 0], Z, 0.0),
        lambda: revolve(line([1, 0, 0], [1, 0, 1]), [0, 0, 0], Z, 7.0),
        lambda: revolve(line([1, 0], [1, 1]), [0, 0, 0], Z),
        lambda: revolve([[1, 0, 0], [1, 0, 1]], [0, 0, 0], Z),
        lambda: loft([line([0, 0, 0], [1, 0, 0])]),
        lambda: loft([]),
        lambda: loft([line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0])], degree=0),
        lambda: loft([line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0])], parameters=[1, 0]),
        lambda: loft([line([0, 0, 0], [1, 0, 0]), line([0, 0, 0], [1, 0, 0])]),
        lambda: coons(line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0]), line([0, 0, 0], [0, 1, 0]),
                      line([1, 0, 0], [1, 1.5, 0])),
        lambda: coons(line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0]), line([0, 0, 0], [0, 1, 0]), None),
        lambda: bicubic_coons(arc([0, 0, 0], Z, 1, 0, 1), arc([0, 0, 0], Z, 2, 0, 1),
                              line([1, 0, 0], [2, 0, 0]), line([math.cos(1), math.sin(1), 0], [2 * math.cos(1), 2 * math.sin(1), 0])),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0], [1, 1])),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0, 0], [1, 1, 1]), tolerance=0.0),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0, 0], [1, 1, 1]), n_sections=1),
        lambda: gordon([line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0])],
                       [line([0, 0, 0], [0, 1, 0]), arc([0, 0, 0], Z, 1.0, 0, 1)]),
        # overflow and malformed numbers: refused by name, never a RuntimeWarning or a numpy error
        lambda: polyline([[0, 0], [1e308, 0], [-1e308, 0]]),
        lambda: circle([1e308, 0, 0], Z, 1e308),
        lambda: extrude(line([0, 0, 0], [1e308, 0, 0]), [1e308, 0, 0]),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0, 0], [1, 1, 1]), n_sections=10**9),
        lambda: revolve(line([1, 0, 0], [1, 0, 1]), [1e308, 0, 0], [0, 1, 0]),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0, 0], [1, 1, 1]), tolerance="abc"),
        lambda: sweep(circle([0, 0], None, 1.0), line([0, 0, 0], [1, 1, 1]), tolerance=float("nan")),
        lambda: gordon([line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0])],
                       [line([0, 0, 0], [0, 1, 0]), line([1, 0, 0], [1, 1, 0])], u_parameters=["a", "b"]),
    ],
)
def test_bad_input_raises_splinekit_error(call):
    with pytest.raises(SplineKitError):
        call()


def test_error_messages_name_the_problem():
    with pytest.raises(SplineKitError, match="radius"):
        circle([0, 0, 0], Z, 0.0)
    with pytest.raises(SplineKitError, match="normal"):
        circle([0, 0, 0], [0, 0, 0], 1.0)
    with pytest.raises(SplineKitError, match="axis_direction"):
        revolve(line([1, 0, 0], [1, 0, 1]), [0, 0, 0], [0, 0, 0])
    with pytest.raises(SplineKitError, match="corner"):
        coons(line([0, 0, 0], [1, 0, 0]), line([0, 1, 0], [1, 1, 0]), line([0, 0, 0], [0, 1, 0]),
              line([1, 0, 0], [1, 1.5, 0]))
    with pytest.raises(SplineKitError, match="collinear"):
        arc_through_points([0, 0], [1, 1], [2, 2])
    with pytest.raises(SplineKitError, match=r"points\[1\] and points\[2\]"):
        polyline([[0, 0], [1, 1], [1, 1]])


def test_sweep_deviation_checks_its_samples():
    profile, path = circle([0, 0], None, 0.2), line([0, 0, 0], [0, 0, 2])
    S = sweep(profile, path, n_sections=4)
    with pytest.raises(SplineKitError, match="samples"):
        sweep_deviation(profile, path, S, samples=["a"])
    with pytest.raises(SplineKitError, match="samples"):
        sweep_deviation(profile, path, S, samples=[float("nan")])
    with pytest.raises(SplineKitError, match="samples"):
        sweep_deviation(profile, path, S, samples=[])


def test_results_are_bezier_decomposable_and_immutable():
    S = revolve(circle([2, 0, 0], [0, 1, 0], 0.5), [0, 0, 0], Z)
    patches = S.to_bezier()
    assert isinstance(patches[0][0], BezierSurface)
    with pytest.raises(ValueError):
        S.control_points[0, 0, 0] = 1.0
