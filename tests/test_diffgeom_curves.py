"""Differential geometry of curves (splinekit.diffgeom.curves).

Checked against closed forms (helix, circle, twisted cubic) and against
invariants (orthonormal frames, zero twist of rotation-minimizing frames);
tests/occ/test_diffgeom_curves_occ.py checks random NURBS curves against
OpenCascade's GeomLProp_CLProps.
"""

from __future__ import annotations

import numpy as np
import pytest
from _geometry import random_curve_data
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit import BezierCurve, BSplineCurve, NurbsCurve
from splinekit.diffgeom.curves import (
    ParametricCurve,
    arc_length,
    arc_length_parameters,
    curvature,
    equal_arc_length_parameters,
    frenet_frame,
    reparametrize_by_arc_length,
    rotation_minimizing_frames,
    signed_curvature,
    tangent,
    torsion,
)
from splinekit.errors import DomainError, ParameterError, SplineKitError


# ------------------------------------------------------------------------------------------
# reference curves
# ------------------------------------------------------------------------------------------
def helix(a=2.0, b=0.5, turns=2.0, analytic=True):
    """(a cos t, a sin t, b t) on [0, 2 pi turns]; analytic derivatives written out by hand."""

    def f(t):
        return np.stack([a * np.cos(t), a * np.sin(t), b * t], axis=-1)

    def ders(t, order):
        out = np.empty((order + 1, t.size, 3))
        out[0] = f(t)
        for k in range(1, order + 1):
            # d^k/dt^k cos t = cos(t + k pi / 2), same for sin
            out[k, :, 0] = a * np.cos(t + k * np.pi / 2)
            out[k, :, 1] = a * np.sin(t + k * np.pi / 2)
            out[k, :, 2] = b if k == 1 else 0.0
        return out

    return ParametricCurve(f, ders if analytic else None, domain=(0.0, 2 * np.pi * turns))


def rational_circle(radius=1.0, center=(0.0, 0.0, 0.0)):
    """The full circle as a 9-point rational quadratic NURBS (The NURBS Book, Ex. 7.2), in the xy plane."""
    r = radius
    P = np.array([[r, 0], [r, r], [0, r], [-r, r], [-r, 0], [-r, -r], [0, -r], [r, -r], [r, 0]], float)
    P = np.column_stack([P, np.zeros(9)]) + np.asarray(center)
    w = np.array([1, 1, 1, 1, 1, 1, 1, 1, 1], float)
    w[1::2] = np.sqrt(0.5)
    knots = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    return NurbsCurve(2, knots, P, w)


def rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def random_spline(rng, rational, dim=3, degree=None):
    p, U, P, W = random_curve_data(rng, rational, degree=degree, max_degree=5)
    P = P[:, :dim] if dim <= 3 else np.column_stack([P, rng.uniform(-1, 1, (len(P), dim - 3))])
    return NurbsCurve(p, U, P, W) if rational else BSplineCurve(p, U, P)


def sequential_rmf(X, T, r0):
    """Double reflection (Wang et al. 2008, Algorithm 1) written as the plain loop of the paper."""
    R = [r0]
    for i in range(len(X) - 1):
        v1 = X[i + 1] - X[i]
        c1 = v1 @ v1
        rL = R[-1] - (2 / c1) * (v1 @ R[-1]) * v1
        tL = T[i] - (2 / c1) * (v1 @ T[i]) * v1
        v2 = T[i + 1] - tL
        c2 = v2 @ v2
        R.append(rL - (2 / c2) * (v2 @ rL) * v2)
    return np.array(R)


# ------------------------------------------------------------------------------------------
# rotation-minimizing frames
# ------------------------------------------------------------------------------------------
def test_rmf_helix_matches_closed_form():
    # On a helix the RMF normal is the Frenet normal turned by -tau * s about T
    # (d/ds of cos(th) N + sin(th) B has no N, B part iff th' = -tau).
    a, b = 2.0, 0.5
    H = helix(a, b)
    u = np.linspace(*H.domain, 2001)
    T, N, B = frenet_frame(H, u)
    Tr, Nr, Br = rotation_minimizing_frames(H, u, normal=N[0])
    s = np.hypot(a, b) * u
    tau = b / (a * a + b * b)
    expected = np.cos(tau * s)[:, None] * N - np.sin(tau * s)[:, None] * B
    assert np.abs(Nr - expected).max() < 1e-10
    assert np.abs(Tr - T).max() < 1e-14
    assert np.abs(Br - np.cross(Tr, expected)).max() < 1e-10


def test_rmf_converges_at_fourth_order():
    a, b = 1.0, 1.0
    H = helix(a, b, turns=1.0)
    tau = b / (a * a + b * b)
    errors = []
    for n in (40, 80):
        u = np.linspace(*H.domain, n)
        _, N, B = frenet_frame(H, u)
        _, Nr, _ = rotation_minimizing_frames(H, u, normal=N[0])
        th = tau * np.hypot(a, b) * u
        errors.append(np.abs(Nr - (np.cos(th)[:, None] * N - np.sin(th)[:, None] * B)).max())
    assert 12 < errors[0] / errors[1] < 20  # 2**4 = 16


def test_rmf_equals_sequential_double_reflection():
    # the vectorized construction and blocked prefix product reproduce the paper's loop
    rng = np.random.default_rng(7)
    for rational in (False, True):
        for n in (2, 3, 33, 1000):
            c = random_spline(rng, rational, degree=3)
            u = np.sort(rng.uniform(*c.domain, n))
            u = np.linspace(*c.domain, n) if n < 4 else u
            _, N, _ = rotation_minimizing_frames(c, u, normal=[0.3, -0.2, 0.9])
            t0 = c.tangent(u[0])
            r0 = np.array([0.3, -0.2, 0.9]) - (np.array([0.3, -0.2, 0.9]) @ t0) * t0
            ref = sequential_rmf(c.evaluate(u), c.tangent(u), r0 / np.linalg.norm(r0))
            assert np.abs(N - ref).max() < 1e-9


def test_rmf_orthonormal_and_tangent():
    rng = np.random.default_rng(1)
    for rational in (False, True, False, True):
        c = random_spline(rng, rational)
        u = np.sort(np.concatenate([list(c.domain), rng.uniform(*c.domain, 300)]))
        T, N, B = rotation_minimizing_frames(c, u)
        frame = np.stack([T, N, B], axis=-1)  # columns T, N, B
        assert np.abs(np.einsum("nji,njk->nik", frame, frame) - np.eye(3)).max() < 1e-12
        assert np.allclose(np.linalg.det(frame), 1.0, atol=1e-12)
        assert np.abs(T - c.tangent(u)).max() < 1e-12
        assert np.abs(T - tangent(c, u)).max() < 1e-12


def test_rmf_planar_curve_has_fixed_binormal():
    # zero twist: in a plane, the RMF keeps the plane normal exactly
    rng = np.random.default_rng(2)
    for rational in (False, True):
        c2 = random_spline(rng, rational, dim=2, degree=3)
        Rm = rotation(rng)
        P3 = np.column_stack([c2.control_points, np.zeros(len(c2))]) @ Rm.T
        c = NurbsCurve(3, c2.knots, P3, c2.weights) if rational else BSplineCurve(3, c2.knots, P3)
        plane_normal = Rm[:, 2]
        u = np.linspace(*c.domain, 500)
        _, N, _ = rotation_minimizing_frames(c, u, normal=plane_normal)
        assert np.abs(N - plane_normal).max() < 1e-12
        # a tilted start keeps its angle to the plane (its in-plane part turns with T)
        _, N, _ = rotation_minimizing_frames(c, u, normal=plane_normal + 0.3 * Rm[:, 0])
        assert np.abs(N @ plane_normal - N[0] @ plane_normal).max() < 1e-12
        # a 2-D curve is embedded at z = 0, where the default start normal is the
        # axis least aligned with T: e_z, kept throughout
        T2, N2, _ = rotation_minimizing_frames(c2, u)
        assert np.abs(N2 - [0, 0, 1]).max() < 1e-12
        assert np.abs(T2[:, :2] - c2.tangent(u)).max() < 1e-12 and not T2[:, 2].any()


def test_rmf_has_no_angular_velocity_about_tangent():
    # omega_T = (dN/du) . B: ~0 for the RMF, tau * |C'| for the Frenet frame
    a, b = 2.0, 0.5
    H = helix(a, b)
    u = np.linspace(*H.domain, 4001)
    h = u[1] - u[0]
    _, Nr, Br = rotation_minimizing_frames(H, u)
    _, N, B = frenet_frame(H, u)
    w_rmf = np.sum((Nr[2:] - Nr[:-2]) / (2 * h) * Br[1:-1], axis=-1)
    w_frenet = np.sum((N[2:] - N[:-2]) / (2 * h) * B[1:-1], axis=-1)
    assert np.abs(w_rmf).max() < 1e-6
    assert np.allclose(w_frenet, b / np.hypot(a, b), rtol=1e-5)


def test_rmf_repeated_parameters_and_single_point():
    H = helix()
    u = np.array([0.0, 0.5, 0.5, 0.5, 1.0, 2.0, 2.0])
    _, N, _ = rotation_minimizing_frames(H, u)
    assert np.array_equal(N[1], N[2]) or np.abs(N[1] - N[2]).max() < 1e-15
    assert np.abs(N[5] - N[6]).max() < 1e-15
    ref = rotation_minimizing_frames(H, np.array([0.0, 0.5, 1.0, 2.0]))[1]
    assert np.abs(N[[0, 1, 4, 5]] - ref).max() < 1e-12
    T1, N1, B1 = rotation_minimizing_frames(H, [1.0], normal=[0, 0, 1])
    assert T1.shape == N1.shape == B1.shape == (1, 3)
    assert abs(N1[0] @ T1[0]) < 1e-15


def test_rmf_bad_input():
    H = helix()
    with pytest.raises(ParameterError, match=r"u\[1\]"):
        rotation_minimizing_frames(H, [0.0, 1.0, 0.5])
    with pytest.raises(ParameterError, match="1-D"):
        rotation_minimizing_frames(H, [[0.0, 1.0]])
    with pytest.raises(ParameterError, match="1-D"):
        rotation_minimizing_frames(H, [])
    with pytest.raises(ParameterError, match="parallel"):
        rotation_minimizing_frames(H, [0.0, 1.0], normal=H.derivatives(0.0, 1)[1])
    with pytest.raises(ParameterError, match="normal"):
        rotation_minimizing_frames(H, [0.0, 1.0], normal=[1.0, 0.0])
    with pytest.raises(ParameterError, match="normal"):
        rotation_minimizing_frames(H, [0.0, 1.0], normal=[np.nan, 0.0, 1.0])
    with pytest.raises(DomainError):
        rotation_minimizing_frames(H, [0.0, 100.0])
    with pytest.raises(DomainError):
        rotation_minimizing_frames(H, [0.0, np.nan])
    with pytest.raises(ParameterError, match="dim=4"):
        c4 = random_spline(np.random.default_rng(0), False, dim=4)
        rotation_minimizing_frames(c4, c4.domain)
    with pytest.raises(DomainError, match="tangent"):
        rotation_minimizing_frames(BSplineCurve(1, [0, 0, 1, 1], [[1, 2, 3], [1, 2, 3]]), [0.0, 1.0])
    with pytest.raises(ParameterError, match="derivatives"):
        rotation_minimizing_frames(object(), [0.0, 1.0])


def test_rmf_start_normal_of_any_length():
    # only the direction of the start normal matters, down to subnormal and up to huge lengths
    H = helix()
    u = np.linspace(*H.domain, 9)
    ref = rotation_minimizing_frames(H, u, normal=[1.0, 0.0, 0.2])
    for scale in (1e-300, 1e300):
        got = rotation_minimizing_frames(H, u, normal=np.array([1.0, 0.0, 0.2]) * scale)
        for a, b in zip(ref, got):
            assert np.abs(a - b).max() <= 1e-15


# ------------------------------------------------------------------------------------------
# ParametricCurve
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "turns, bounds",
    [(1.0, (1e-12, 1e-9, 3e-8, 2e-6)), (2.0, (2e-10, 4e-8, 2e-6, 7e-5))],
)
def test_numeric_derivatives_match_analytic(turns, bounds):
    # the accuracy stated in the ParametricCurve docstring, with a 10x margin
    exact, numeric = helix(turns=turns), helix(turns=turns, analytic=False)
    a, b = exact.domain
    u = np.concatenate([np.linspace(a, b, 301), a + np.array([1e-9, 1e-3]), b - np.array([1e-9, 1e-3])])
    A, E = exact.derivatives(u, 4), numeric.derivatives(u, 4)
    assert np.array_equal(A[0], E[0])
    for k in range(1, 5):
        assert np.abs(E[k] - A[k]).max() <= bounds[k - 1] * np.abs(A[k]).max()


def test_numeric_derivatives_of_polynomials_near_the_ends():
    # a stencil of 2r + 1 nodes differentiates polynomials of degree <= 2r exactly (up to
    # rounding), central or shifted: check against the monomial derivatives
    def f(t):
        return np.stack([t**3 - 2 * t, 0.5 * t**4, np.ones_like(t)], axis=-1)

    c = ParametricCurve(f, domain=(-1.0, 2.0))
    u = np.array([-1.0, -0.999, 0.3, 1.999, 2.0])
    d = c.derivatives(u, 3)
    assert np.allclose(d[1], np.stack([3 * u**2 - 2, 2 * u**3, 0 * u], -1), rtol=0, atol=1e-11)
    assert np.allclose(d[2], np.stack([6 * u, 6 * u**2, 0 * u], -1), rtol=0, atol=1e-8)
    assert np.allclose(d[3], np.stack([6 + 0 * u, 12 * u, 0 * u], -1), rtol=0, atol=1e-6)


def test_parametric_curve_shapes():
    H = helix()
    assert H.dim == 3 and H.domain == (0.0, 4 * np.pi)
    assert H.evaluate(1.0).shape == (3,)
    assert H.derivatives(np.ones((2, 5)), 2).shape == (3, 2, 5, 3)
    assert curvature(H, np.ones((2, 5))).shape == (2, 5)
    assert curvature(H, []).shape == (0,)
    assert tangent(H, 0.5).shape == (3,)
    assert all(x.shape == (4, 3) for x in frenet_frame(H, np.ones(4)))
    with pytest.raises(AttributeError):
        H.domain = (0, 1)


# ------------------------------------------------------------------------------------------
# curvature, torsion, Frenet frame: closed forms
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scale", [1e60, 1e120, 1e200, 1e300])
def test_helix_curvature_and_torsion_in_huge_units(scale):
    # |C' x C''| and |C'|**3 overflow far below the float limit; closed forms scale as 1 / scale
    a, b = 2.0 * scale, 0.5 * scale
    H = helix(a, b)
    u = np.linspace(*H.domain, 11)
    c2 = (a / scale) ** 2 + (b / scale) ** 2
    assert np.allclose(curvature(H, u) * scale, (a / scale) / c2, rtol=1e-12, atol=0)
    assert np.allclose(torsion(H, u) * scale, (b / scale) / c2, rtol=1e-12, atol=0)
    T, N, B = frenet_frame(H, u)
    ref = frenet_frame(helix(a / scale, b / scale), u)
    for got, want in zip((T, N, B), ref):
        assert np.abs(got - want).max() <= 1e-14
    circle_2d = ParametricCurve(lambda t: scale * np.stack([np.cos(t), np.sin(t)], -1), domain=(0.0, 6.0))
    assert np.allclose(signed_curvature(circle_2d, u[:5]) * scale, 1.0, rtol=1e-6)


@pytest.mark.parametrize("a, b", [(2.0, 0.5), (1.0, 3.0), (0.3, -0.7)])
def test_helix_curvature_torsion_frenet(a, b):
    H = helix(a, b)
    u = np.linspace(*H.domain, 101)
    c2 = a * a + b * b
    assert np.allclose(curvature(H, u), abs(a) / c2, rtol=1e-12, atol=0)
    assert np.allclose(torsion(H, u), b / c2, rtol=1e-12, atol=0)
    T, N, B = frenet_frame(H, u)
    c = np.sqrt(c2)
    st, ct = np.sin(u), np.cos(u)
    assert np.allclose(T, np.stack([-a * st, a * ct, b + 0 * u], -1) / c, rtol=0, atol=1e-14)
    assert np.allclose(N, np.stack([-ct, -st, 0 * u], -1) * np.sign(a), rtol=0, atol=1e-14)
    assert np.allclose(B, np.stack([b * st, -b * ct, a + 0 * u], -1) * np.sign(a) / c, rtol=0, atol=1e-14)


def test_helix_with_numeric_derivatives():
    a, b = 2.0, 0.5
    H = helix(a, b, turns=1.0, analytic=False)
    u = np.linspace(*H.domain, 101)
    assert np.allclose(curvature(H, u), a / (a * a + b * b), rtol=1e-9, atol=0)
    assert np.allclose(torsion(H, u), b / (a * a + b * b), rtol=1e-7, atol=0)


@pytest.mark.parametrize("radius", [1.0, 3.7, 1e-3, 250.0])
def test_rational_circle(radius):
    rng = np.random.default_rng(int(radius * 1000))
    c = rational_circle(radius)
    Rm = rotation(rng)
    # the offset is a few radii: far off, rounding in the control points alone would cost
    # |offset| / radius * eps of relative curvature
    offset = radius * rng.uniform(-5, 5, (3, 1))
    moved = c.transform(np.block([[Rm, offset], [np.zeros((1, 3)), np.ones((1, 1))]]))
    u = np.concatenate([np.linspace(0, 1, 201), rng.uniform(0, 1, 100)])
    for curve in (c, moved):
        assert np.allclose(curvature(curve, u), 1 / radius, rtol=1e-12, atol=0)
        assert np.abs(torsion(curve, u)).max() <= 1e-12 / radius
        _, N, B = frenet_frame(curve, u)
        centre = curve.evaluate(u) + radius * N  # the normal points at the centre
        assert np.abs(centre - centre[0]).max() <= 1e-13 * radius
    assert np.abs(B - Rm[:, 2]).max() < 1e-12  # counter-clockwise in the rotated xy plane
    assert np.allclose(arc_length(c), 2 * np.pi * radius, rtol=1e-12)


def test_signed_curvature_of_planar_circle():
    c3 = rational_circle(2.5)
    c = NurbsCurve(2, c3.knots, c3.control_points[:, :2], c3.weights)
    u = np.linspace(0, 1, 50)
    assert np.allclose(signed_curvature(c, u), 0.4, rtol=1e-12)
    assert np.allclose(signed_curvature(c.reverse(), u), -0.4, rtol=1e-12)
    assert np.allclose(curvature(c, u), 0.4, rtol=1e-12)


def test_signed_curvature_of_ellipse_with_numeric_derivatives():
    a, b = 3.0, 1.2
    E = ParametricCurve(lambda t: np.stack([a * np.cos(t), b * np.sin(t)], -1), domain=(0.0, 2 * np.pi))
    t = np.linspace(0, 2 * np.pi, 97)
    expected = a * b / (a**2 * np.sin(t) ** 2 + b**2 * np.cos(t) ** 2) ** 1.5
    assert np.allclose(signed_curvature(E, t), expected, rtol=1e-8, atol=0)
    assert np.allclose(curvature(E, t), expected, rtol=1e-8, atol=0)


def test_twisted_cubic_bezier():
    # (t, t^2, t^3) in Bezier form (monomial to Bernstein conversion by hand)
    c = BezierCurve([[0, 0, 0], [1 / 3, 0, 0], [2 / 3, 1 / 3, 0], [1, 1, 1]])
    t = np.linspace(0, 1, 101)
    assert np.allclose(c.evaluate(t), np.stack([t, t**2, t**3], -1), atol=1e-15)
    q = 9 * t**4 + 9 * t**2 + 1  # |C' x C''|^2 / 4 with C' x C'' = (6t^2, -6t, 2)
    speed2 = 1 + 4 * t**2 + 9 * t**4
    assert np.allclose(curvature(c, t), 2 * np.sqrt(q) / speed2**1.5, rtol=1e-12, atol=0)
    assert np.allclose(torsion(c, t), 3 / q, rtol=1e-12, atol=0)
    T, _, B = frenet_frame(c, t)
    assert np.allclose(B, np.stack([6 * t**2, -6 * t, 2 + 0 * t], -1) / (2 * np.sqrt(q))[:, None], atol=1e-14)
    assert np.allclose(T, np.stack([1 + 0 * t, 2 * t, 3 * t**2], -1) / np.sqrt(speed2)[:, None], atol=1e-14)


def test_curvature_in_higher_dimension_and_under_similarity():
    # an isometric embedding into 5-D keeps curvature; scaling by k divides it by k
    rng = np.random.default_rng(3)
    for rational in (False, True):
        c = random_spline(rng, rational)
        u = np.linspace(*c.domain, 200)
        k3 = curvature(c, u)
        Q, _ = np.linalg.qr(rng.normal(size=(5, 5)))
        P5 = np.column_stack([c.control_points, np.zeros((len(c), 2))]) @ Q.T * 3.0
        c5 = NurbsCurve(c.degree, c.knots, P5, c.weights) if rational else BSplineCurve(c.degree, c.knots, P5)
        assert np.allclose(curvature(c5, u), k3 / 3.0, rtol=1e-8, atol=1e-12 * k3.max())
        # planar: |signed| equals curvature, and matches the 3-D formula of the z = 0 embedding
        P2 = c.control_points[:, :2]
        c2 = NurbsCurve(c.degree, c.knots, P2, c.weights) if rational else BSplineCurve(c.degree, c.knots, P2)
        k2 = curvature(c2, u)
        assert np.allclose(np.abs(signed_curvature(c2, u)), k2, rtol=1e-12, atol=0)
        c2in3 = BSplineCurve(c.degree, c.knots, np.column_stack([P2, np.zeros(len(c))])) if not rational else \
            NurbsCurve(c.degree, c.knots, np.column_stack([P2, np.zeros(len(c))]), c.weights)
        assert np.allclose(curvature(c2in3, u), k2, rtol=1e-10, atol=1e-12 * k2.max())


def test_straight_line_and_inflection_conventions():
    line = BSplineCurve(1, [0, 0, 0.5, 1, 1], [[0, 0, 0], [1, 2, 3], [2, 4, 6]])
    u = np.linspace(0, 1, 11)
    assert not curvature(line, u).any()
    assert not torsion(line, u).any()
    T, N, B = frenet_frame(line, u)
    assert np.isfinite(N).all() and np.allclose(np.linalg.norm(N, axis=1), 1)
    assert np.abs(np.sum(T * N, axis=1)).max() < 1e-15
    assert np.abs(N - N[0]).max() < 1e-15  # the same default everywhere
    # planar S-curve, point-symmetric about its middle: an inflection at t = 0.5
    s = BezierCurve([[0, 0, 0], [1, 1, 0], [2, -1, 0], [3, 0, 0]])
    t = np.array([0.2, 0.45, 0.5, 0.7])
    k = curvature(s, t)
    assert k[2] < 1e-15 and (k[[0, 1, 3]] > 0.1).all()
    assert not torsion(s, np.linspace(0, 1, 33)).any()
    T, N, B = frenet_frame(s, t)
    # the normal at the inflection is carried from the nearest parameter (0.45)
    carried = N[1] - (N[1] @ T[2]) * T[2]
    assert np.allclose(N[2], carried / np.linalg.norm(carried), atol=1e-15)
    assert N[1] @ N[2] > 0.9
    assert np.allclose(np.einsum("ni,ni->n", np.cross(T, N), B), 1)


def test_cusp_of_the_parametrization():
    # P0 = P1: C'(0) = 0; the tangent falls back to C'' (direction P2 - P0)
    c = BezierCurve([[0, 0, 0], [0, 0, 0], [1, 2, 0], [3, 1, 1]])
    assert np.allclose(tangent(c, 0.0), np.array([1, 2, 0]) / np.sqrt(5), atol=1e-15)
    assert np.allclose(tangent(c, [0.0, 0.3]), c.tangent([0.0, 0.3]), atol=1e-15)
    for f in (curvature, torsion, frenet_frame):
        with pytest.raises(DomainError, match="u = 0.0"):
            f(c, [0.5, 0.0])
    assert np.isfinite(curvature(c, [1e-3, 0.5])).all()
    assert not tangent(BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[1, 1]] * 3), [0.0, 0.5]).any()


def test_tangent_matches_spline_tangent():
    rng = np.random.default_rng(4)
    for rational in (False, True) * 3:
        c = random_spline(rng, rational)
        u = np.linspace(*c.domain, 50)
        assert np.abs(tangent(c, u) - c.tangent(u)).max() < 1e-14


# ------------------------------------------------------------------------------------------
# invariants (hypothesis)
# ------------------------------------------------------------------------------------------
@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), rational=st.booleans())
def test_invariance_under_motion_reversal_and_reparametrization(seed, rational):
    rng = np.random.default_rng(seed)
    c = random_spline(rng, rational, degree=int(rng.integers(3, 6)))
    a, b = c.domain
    u = rng.uniform(a + 0.01 * (b - a), b - 0.01 * (b - a), 20)
    k, tau = curvature(c, u), torsion(c, u)
    kscale = k.max()
    # rigid motion with a reflection: curvature kept, torsion negated
    M = rotation(rng) @ np.diag([1.0, 1.0, -1.0])
    m = c.transform(np.block([[M, rng.uniform(-3, 3, (3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))
    assert np.allclose(curvature(m, u), k, rtol=1e-8, atol=1e-10 * kscale)
    ok = k > 1e-3 * kscale  # torsion is ill-conditioned near inflections
    assert np.allclose(torsion(m, u)[ok], -tau[ok], rtol=1e-6, atol=1e-8 * np.abs(tau).max())
    # reversal: tangent flips, curvature and torsion stay
    r = c.reverse()
    ur = a + b - u
    assert np.allclose(tangent(r, ur), -tangent(c, u), atol=1e-10)
    assert np.allclose(curvature(r, ur), k, rtol=1e-8, atol=1e-10 * kscale)
    assert np.allclose(torsion(r, ur)[ok], tau[ok], rtol=1e-6, atol=1e-8 * np.abs(tau).max())
    # affine reparametrization onto [2, 7]: the geometry's invariants do not change
    p = c.reparametrize(2.0, 7.0)
    up = 2.0 + (u - a) * 5.0 / (b - a)
    assert np.allclose(curvature(p, up), k, rtol=1e-8, atol=1e-10 * kscale)
    assert np.allclose(arc_length(p, 2.0, up), arc_length(c, a, u), rtol=1e-10)


# ------------------------------------------------------------------------------------------
# arc length
# ------------------------------------------------------------------------------------------
def test_arc_length_of_circle_and_helix():
    R = 2.5
    c = rational_circle(R, center=(1.0, -2.0, 0.5))
    s = np.linspace(0, 2 * np.pi * R, 41)
    u = arc_length_parameters(c, s)
    expected = np.stack([R * np.cos(s / R) + 1.0, R * np.sin(s / R) - 2.0, 0.5 + 0 * s], -1)
    assert np.abs(c.evaluate(u) - expected).max() < 1e-11 * R
    assert np.allclose(arc_length(c, 0.0, u), s, rtol=0, atol=1e-12 * 2 * np.pi * R)
    a, b = 2.0, 0.5
    H = helix(a, b)
    s = np.linspace(0, arc_length(H), 77)
    assert np.allclose(arc_length(H), 4 * np.pi * np.hypot(a, b), rtol=1e-13)
    assert np.allclose(arc_length_parameters(H, s), s / np.hypot(a, b), rtol=0, atol=1e-11)
    assert np.allclose(arc_length(H, 1.0, [2.0, 3.0, 0.0]), np.hypot(a, b) * np.array([1.0, 2.0, -1.0]), rtol=1e-13)


def test_arc_length_agrees_with_curve_arc_length():
    rng = np.random.default_rng(6)
    for rational in (False, True) * 3:
        c = random_spline(rng, rational)
        a, b = c.domain
        x, y = np.sort(rng.uniform(a, b, 2))
        assert np.isclose(arc_length(c), c.arc_length(), rtol=1e-11)
        assert np.isclose(arc_length(c, x, y), c.arc_length(x, y), rtol=1e-11)
        assert np.isclose(arc_length(c, y, x), -c.arc_length(x, y), rtol=1e-11)
        assert arc_length(c, x, x) == 0.0
    bez = BezierCurve(rng.uniform(-1, 1, (6, 3)), weights=rng.uniform(0.5, 2, 6))
    assert np.isclose(arc_length(bez), bez.arc_length(), rtol=1e-11)


def test_arc_length_parameters_random_splines():
    rng = np.random.default_rng(8)
    for rational in (False, True) * 3:
        c = random_spline(rng, rational)
        L = c.arc_length()
        s = np.concatenate([[0.0, L], rng.uniform(0, L, 60)])
        u = arc_length_parameters(c, s)
        assert np.allclose([c.arc_length(c.domain[0], x) for x in u[:12]], s[:12], rtol=0, atol=1e-10 * L)
        assert u[0] == c.domain[0] and abs(u[1] - c.domain[1]) < 1e-9 * (c.domain[1] - c.domain[0])
        e = equal_arc_length_parameters(c, 9)
        assert e[0] == c.domain[0] and e[-1] == c.domain[1]
        assert np.all(np.diff(e) > 0)
        assert np.allclose(arc_length(c, e[:-1], e[1:]), L / 8, rtol=1e-10)


def test_reparametrize_by_arc_length():
    a, b = 2.0, 0.5
    H = helix(a, b)
    c = np.hypot(a, b)
    A = reparametrize_by_arc_length(H)
    assert np.isclose(A.domain[1], 4 * np.pi * c, rtol=1e-13)
    s = np.linspace(*A.domain, 57)
    d = A.derivatives(s, 3)
    ref = H.derivatives(s / c, 3)
    for k in range(4):
        assert np.abs(d[k] - ref[k] / c**k).max() < 1e-10
    # a random rational spline: unit speed, and curvature / torsion are those of the original
    rng = np.random.default_rng(9)
    sp = random_spline(rng, True, degree=4)
    A = reparametrize_by_arc_length(sp)
    s = np.linspace(*A.domain, 40)[1:-1]
    u = arc_length_parameters(sp, s)
    assert np.allclose(np.linalg.norm(A.derivatives(s, 1)[1], axis=-1), 1.0, rtol=1e-13)
    assert np.allclose(curvature(A, s), curvature(sp, u), rtol=1e-9)
    k = curvature(sp, u)
    ok = k > 1e-3 * k.max()
    assert np.allclose(torsion(A, s)[ok], torsion(sp, u)[ok], rtol=1e-7)
    with pytest.raises(ParameterError, match="order"):
        A.derivatives(s, 4)
    with pytest.raises(DomainError, match="zero length"):
        reparametrize_by_arc_length(BSplineCurve(1, [0, 0, 1, 1], [[1, 2], [1, 2]]))


# ------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------
def test_bad_input():
    H = helix()
    Hn = helix(analytic=False)
    c2 = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0], [1, 1], [2, 0]])
    with pytest.raises(ParameterError, match="order = 5"):
        Hn.derivatives([0.1], 5)
    for order in (-1, 2.5, True):
        with pytest.raises(ParameterError, match="order"):
            H.derivatives([0.1], order)
    with pytest.raises(ParameterError, match="dim=2"):
        torsion(c2, [0.5])
    with pytest.raises(ParameterError, match="dim=3"):
        signed_curvature(H, [0.5])
    with pytest.raises(DomainError, match="outside"):
        curvature(H, [1.0, 20.0])
    with pytest.raises(DomainError, match="not finite"):
        tangent(H, [np.inf])
    with pytest.raises(DomainError, match="not finite"):
        torsion(rational_circle(), [np.nan])
    with pytest.raises(ParameterError, match="derivatives"):
        curvature(np.zeros(3), [0.5])
    # ParametricCurve construction and misbehaving callables
    with pytest.raises(ParameterError, match="domain"):
        ParametricCurve(lambda t: np.stack([t, t], -1), domain=(1.0, 1.0))
    with pytest.raises(ParameterError, match="domain"):
        ParametricCurve(lambda t: np.stack([t, t], -1), domain=(0.0, np.inf))
    with pytest.raises(ParameterError, match="callable"):
        ParametricCurve(np.zeros(3))
    with pytest.raises(ParameterError, match=r"f\(u\) must return shape"):
        ParametricCurve(lambda t: t)
    with pytest.raises(DomainError, match=r"f\(u\) is not finite at u = 1.0"):
        ParametricCurve(lambda t: np.stack([t, np.where(t < 1, 0.0, np.inf)], -1))
    bad_ders = ParametricCurve(lambda t: np.stack([t, t], -1), derivatives=lambda t, k: np.zeros((k, t.size, 2)))
    with pytest.raises(ParameterError, match="must return shape"):
        curvature(bad_ders, [0.5])
    sq = ParametricCurve(lambda t: np.stack([t, np.sqrt(t)], -1), domain=(0.0, 1.0))
    assert np.isfinite(sq.derivatives([1e-3, 0.5, 1.0], 2)).all()  # stencils stay inside the domain
    # arc length arguments
    with pytest.raises(DomainError, match="s = "):
        arc_length_parameters(H, [1e3])
    with pytest.raises(DomainError, match="s = "):
        arc_length_parameters(H, [-1.0])
    with pytest.raises(ParameterError, match="n must be >= 2"):
        equal_arc_length_parameters(H, 1)
    with pytest.raises(ParameterError, match="n = 1000000000000 exceeds"):
        equal_arc_length_parameters(H, 10**12)  # 8 TB of output: refused, not a MemoryError
    with pytest.raises(ParameterError, match="n must be an integer"):
        equal_arc_length_parameters(H, 3.5)
    with pytest.raises(ParameterError, match="tol"):
        arc_length(H, tol=-1.0)
    with pytest.raises(DomainError, match="u1"):
        arc_length(H, 0.0, 100.0)
    with pytest.raises(ParameterError, match="domain"):

        class NoDomain:
            def derivatives(self, u, order):
                return np.zeros((order + 1, np.size(u), 3))

        arc_length(NoDomain())
    for exc in (ParameterError, DomainError):
        assert issubclass(exc, SplineKitError)
