"""Fitting (splinekit.fit): interpolation, least squares, scattered fits.

Checked against invariants (the fit passes through its data, reproduces a
spline sampled on its own knots), closed forms (parameters of simple point
sets); tests/occ/test_fit_occ.py checks against OpenCascade (GeomAPI_Interpolate,
GeomAPI_PointsToBSpline) and measures approximation errors with OCC's point projection.
"""

from __future__ import annotations

import numpy as np
import pytest
from _geometry import random_curve_data, random_points, random_surface_data
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit.basis import design_matrix
from splinekit.curves import BSplineCurve
from splinekit.errors import ConvergenceError, FittingError, SplineKitError
from splinekit.fit import (
    approximate_curve,
    approximate_surface,
    approximation_knots,
    averaged_knots,
    fit_surface,
    grid_parameters,
    interpolate_curve,
    interpolate_surface,
    parametrize,
)
from splinekit.surfaces import BSplineSurface

METHODS = ("uniform", "chord", "centripetal")


def size_of(points):
    points = np.asarray(points)
    return float(np.ptp(points.reshape(-1, points.shape[-1]), axis=0).max())


def wavy_points(rng, m, dim=3, noise=0.0):
    """A smooth random curve sampled at ``m`` increasing, well-separated positions."""
    s = np.sort(rng.uniform(0.0, 1.0, m))
    s = 0.5 * s + 0.5 * np.linspace(0.0, 1.0, m)  # keeps neighbours apart
    freq = rng.uniform(0.5, 2.0, dim)
    phase = rng.uniform(0, 2 * np.pi, dim)
    pts = np.sin(2 * np.pi * freq * s[:, None] + phase) + 3.0 * s[
        :, None
    ] * rng.uniform(-1, 1, dim)
    pts = pts * 10.0 ** rng.uniform(-1, 2)
    if noise:
        pts = pts + noise * size_of(pts) * rng.normal(size=pts.shape)
    return pts


# ---------------------------------------------------------------- parametrization


def test_parametrize_closed_forms():
    P = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 4.0], [1.0, 13.0]])  # chords 1, 4, 9
    assert np.allclose(
        parametrize(P, "uniform"), [0, 1 / 3, 2 / 3, 1], rtol=0, atol=1e-15
    )
    assert np.allclose(
        parametrize(P, "chord"), [0, 1 / 14, 5 / 14, 1], rtol=0, atol=1e-15
    )
    assert np.allclose(
        parametrize(P, "centripetal"), [0, 1 / 6, 3 / 6, 1], rtol=0, atol=1e-15
    )


def test_averaged_knots_closed_form():
    t = np.array([0.0, 0.1, 0.3, 0.6, 0.8, 1.0])
    U = averaged_knots(t, 3)  # eq. 9.8: interior u_4 = (t1+t2+t3)/3, u_5 = (t2+t3+t4)/3
    assert np.allclose(
        U,
        [0, 0, 0, 0, (0.1 + 0.3 + 0.6) / 3, (0.3 + 0.6 + 0.8) / 3, 1, 1, 1, 1],
        rtol=0,
        atol=1e-15,
    )
    U2 = averaged_knots(t, 3, start_derivative=True, end_derivative=True)
    assert U2.size == t.size + 2 + 4
    assert np.allclose(
        U2[4:-4],
        [
            (0 + 0.1 + 0.3) / 3,
            (0.1 + 0.3 + 0.6) / 3,
            (0.3 + 0.6 + 0.8) / 3,
            (0.6 + 0.8 + 1) / 3,
        ],
    )


def test_approximation_knots_placement():
    rng = np.random.default_rng(5)
    for _ in range(50):
        m = int(rng.integers(6, 60))
        t = np.sort(rng.uniform(0, 1, m))
        t[0], t[-1] = 0.0, 1.0
        p = int(rng.integers(1, 5))
        n = int(rng.integers(p + 1, m))
        U = approximation_knots(
            t, p, n, method="book"
        )  # eqs. 9.68-9.69: every span holds data
        assert U.size == n + p + 1 and np.all(np.diff(U) >= 0)
        assert np.histogram(t, bins=np.unique(U))[0].min() >= 1
        # subsampled averaging: full column rank at any count, up to n == m
        n = int(rng.integers(p + 1, m + 1))
        U = approximation_knots(t, p, n, method="subsample")
        N = design_matrix(p, U, t).toarray()
        assert U.size == n + p + 1 and np.linalg.matrix_rank(N) == n


# ---------------------------------------------------------------- interpolation


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("dim", [1, 2, 3, 4])
def test_interpolate_curve_passes_through_points(method, dim):
    rng = np.random.default_rng(dim * 7 + len(method))
    for p in (1, 2, 3, 4, 5):
        m = int(rng.integers(p + 1, p + 25))
        P = random_points(rng, (m,), dim)
        c = interpolate_curve(P, p, method)
        assert isinstance(c, BSplineCurve) and c.degree == p and c.dim == dim
        t = parametrize(P, method)
        assert np.abs(c.evaluate(t) - P).max() <= 1e-12 * size_of(P)
        # the explicit parameters and knots give the same curve
        c2 = interpolate_curve(P, p, parameters=t, knots=c.knots)
        assert np.abs(c2.control_points - c.control_points).max() <= 1e-12 * size_of(P)


def test_interpolate_curve_wide_and_long_data():
    # the loft use: rows are flattened control nets (m, k * dim), parameters and knots given
    rng = np.random.default_rng(17)
    nets = random_points(rng, (6, 5 * 3), 1).reshape(6, 15)
    t = np.array([0.0, 0.1, 0.35, 0.5, 0.8, 1.0])
    U = averaged_knots(t, 3)
    c = interpolate_curve(nets, 3, parameters=t, knots=U)
    assert c.control_points.shape == (6, 15)
    assert np.abs(c.evaluate(t) - nets).max() <= 1e-12 * size_of(nets)
    # many points: the banded solve stays accurate
    P = wavy_points(rng, 20000, dim=2)
    c = interpolate_curve(P, 3, "chord")
    assert np.abs(c.evaluate(parametrize(P, "chord")) - P).max() <= 1e-12 * size_of(P)


@pytest.mark.parametrize("dim", [1, 2, 3, 4])
def test_interpolate_curve_end_tangents(dim):
    rng = np.random.default_rng(100 + dim)
    for p in (2, 3, 4, 5):
        m = int(rng.integers(max(2, p - 1), p + 15))
        P = random_points(rng, (m,), dim)
        d0, d1 = random_points(rng, (2,), dim)
        for start, end in ((d0, d1), (d0, None), (None, d1)):
            if m + (start is not None) + (end is not None) < p + 1:
                continue
            c = interpolate_curve(P, p, start_tangent=start, end_tangent=end)
            t = parametrize(P)
            scale = size_of(P)
            assert np.abs(c.evaluate(t) - P).max() <= 1e-12 * scale
            D = c.derivatives(np.array([0.0, 1.0]), 1)[1]
            dscale = max(scale, np.abs(d0).max(), np.abs(d1).max())
            if start is not None:
                assert np.abs(D[0] - start).max() <= 1e-10 * dscale
            if end is not None:
                assert np.abs(D[1] - end).max() <= 1e-10 * dscale


def test_interpolate_curve_reproduces_polynomial():
    # a cubic polynomial is a cubic spline on any knots: interpolation must return it exactly
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 1, 12))
    coef = rng.normal(size=(4, 2))
    f = lambda x: np.stack([np.polyval(coef[:, k], x) for k in range(2)], axis=-1)
    c = interpolate_curve(f(t), 3, parameters=t)
    x = np.linspace(t[0], t[-1], 200)
    assert np.abs(c.evaluate(x) - f(x)).max() <= 1e-11 * np.abs(f(x)).max()


def test_interpolate_curve_reproduces_spline_on_its_knots():
    rng = np.random.default_rng(11)
    for _ in range(30):
        p, U, Pc, _ = random_curve_data(rng, False, max_degree=5)
        n = len(Pc)
        # Greville abscissae satisfy the Schoenberg-Whitney condition
        t = np.array([U[i + 1 : i + p + 1].mean() for i in range(n)])
        Q = BSplineCurve(p, U, Pc).evaluate(t)
        c = interpolate_curve(Q, p, parameters=t, knots=U)
        assert np.abs(c.control_points - Pc).max() <= 1e-9 * size_of(Pc)


@pytest.mark.parametrize("method", METHODS)
def test_interpolate_surface_passes_through_grid(method):
    rng = np.random.default_rng(len(method))
    for pu, pv, dim in ((3, 3, 3), (1, 2, 3), (2, 5, 1), (4, 1, 4)):
        nu, nv = int(rng.integers(pu + 1, pu + 9)), int(rng.integers(pv + 1, pv + 9))
        G = random_points(rng, (nu, nv), dim)
        s = interpolate_surface(G, pu, pv, method)
        assert isinstance(s, BSplineSurface) and (s.degree_u, s.degree_v) == (pu, pv)
        tu, tv = grid_parameters(G, method)
        assert np.abs(s.evaluate_grid(tu, tv) - G).max() <= 1e-12 * size_of(G)


def test_grid_parameters_average_rows():
    # rows parametrized on their own then averaged (A9.3), collapsed rows skipped
    G = np.zeros((3, 3, 2))
    G[:, :, 0] = [[0, 0, 0], [1, 2, 1], [2, 3, 4]]
    G[:, :, 1] = np.arange(3)[None, :]
    tu, tv = grid_parameters(G, "chord")
    assert np.allclose(tu, [0, np.mean([1 / 2, 2 / 3, 1 / 4]), 1], atol=1e-15)
    pole = random_points(np.random.default_rng(0), (4, 5))
    pole[0] = pole[0, 0]  # first u-row collapsed to one point (a pole)
    s = interpolate_surface(pole, 2, 2)
    tu, tv = grid_parameters(pole)
    assert np.abs(s.evaluate_grid(tu, tv) - pole).max() <= 1e-12 * size_of(pole)


def test_interpolate_surface_explicit_parameters_and_knots():
    rng = np.random.default_rng(21)
    for _ in range(10):
        pu, pv, ku, kv, Pc, _ = random_surface_data(rng, False, max_degree=4)
        nu, nv = Pc.shape[:2]
        tu = np.array([ku[i + 1 : i + pu + 1].mean() for i in range(nu)])
        tv = np.array([kv[i + 1 : i + pv + 1].mean() for i in range(nv)])
        G = BSplineSurface(pu, pv, ku, kv, Pc).evaluate_grid(tu, tv)
        s = interpolate_surface(
            G, pu, pv, parameters_u=tu, parameters_v=tv, knots_u=ku, knots_v=kv
        )
        assert np.abs(s.control_points - Pc).max() <= 1e-9 * size_of(Pc)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), method=st.sampled_from(METHODS))
def test_interpolation_commutes_with_similarity_transforms(seed, method):
    # all three parametrizations are invariant under rotation, uniform scaling and translation
    rng = np.random.default_rng(seed)
    P = wavy_points(rng, int(rng.integers(4, 20)))
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0] * rng.uniform(0.1, 10.0)
    shift = rng.normal(size=3) * 10
    a = interpolate_curve(P, 3, method)
    b = interpolate_curve(P @ R.T + shift, 3, method)
    assert np.allclose(b.knots, a.knots, rtol=0, atol=1e-12)
    assert np.abs(
        b.control_points - (a.control_points @ R.T + shift)
    ).max() <= 1e-9 * size_of(b.control_points)


# ---------------------------------------------------------------- least squares


def test_least_squares_reproduces_spline_with_same_knots():
    rng = np.random.default_rng(41)
    for _ in range(30):
        p, U, Pc, _ = random_curve_data(rng, False, max_degree=5)
        a, b = U[p], U[-p - 1]
        # dense data: every basis function is pinned down by many points
        t = np.concatenate([[a, b], rng.uniform(a, b, 40 * len(Pc))])
        t = np.unique(t)
        Q = BSplineCurve(p, U, Pc).evaluate(t)
        c = approximate_curve(Q, degree=p, parameters=t, knots=U)
        assert np.abs(c.control_points - Pc).max() <= 1e-9 * size_of(Pc)


def test_least_squares_matches_dense_lstsq():
    # fixed ends, the rest minimises the squared residuals: compare with a dense solver on the same matrix
    rng = np.random.default_rng(43)
    for _ in range(20):
        m = int(rng.integers(10, 80))
        P = wavy_points(rng, m, noise=0.01)
        p = int(rng.integers(1, 5))
        n = int(rng.integers(p + 1, m + 1))
        c = approximate_curve(P, n, p)
        t = parametrize(P)
        N = design_matrix(p, c.knots, t).toarray()
        rhs = P[1:-1] - np.outer(N[1:-1, 0], P[0]) - np.outer(N[1:-1, -1], P[-1])
        ref = np.linalg.lstsq(N[1:-1, 1:-1], rhs, rcond=None)[0]
        assert np.allclose(
            c.control_points[[0, -1]], P[[0, -1]], rtol=0, atol=1e-15 * size_of(P)
        )
        assert np.abs(c.control_points[1:-1] - ref).max() <= 1e-8 * size_of(P)


def test_least_squares_with_all_control_points_interpolates():
    rng = np.random.default_rng(47)
    P = wavy_points(rng, 25)
    c = approximate_curve(P, 25, 3)
    assert np.abs(c.evaluate(parametrize(P)) - P).max() <= 1e-10 * size_of(P)


def test_approximation_tolerance_unreachable_raises():
    rng = np.random.default_rng(59)
    P = wavy_points(rng, 100, noise=1e-2)
    with pytest.raises(ConvergenceError, match="tolerance"):
        approximate_curve(P, tolerance=1e-6 * size_of(P), max_control=12)


def per_span_samples(knots, count):
    """``count`` evenly spaced parameters in every knot span (shared ends once): data in every span."""
    br = np.unique(knots)
    s = np.linspace(0.0, 1.0, count + 1)[None, :]
    return np.unique(br[:-1, None] * (1.0 - s) + br[1:, None] * s)


def test_approximate_surface_reproduces_spline_with_same_knots():
    rng = np.random.default_rng(61)
    for _ in range(8):
        pu, pv, ku, kv, Pc, _ = random_surface_data(
            rng, False, max_degree=4, max_spans=3
        )
        nu, nv = Pc.shape[:2]
        tu, tv = per_span_samples(ku, pu + 2), per_span_samples(kv, pv + 2)
        G = BSplineSurface(pu, pv, ku, kv, Pc).evaluate_grid(tu, tv)
        s = approximate_surface(
            G, nu, nv, pu, pv, parameters_u=tu, parameters_v=tv, knots_u=ku, knots_v=kv
        )
        assert np.abs(s.control_points - Pc).max() <= 1e-9 * size_of(Pc)


def test_approximate_surface_residual_and_corners():
    rng = np.random.default_rng(67)
    u, v = np.meshgrid(np.linspace(0, 1, 40), np.linspace(0, 1, 30), indexing="ij")
    G = np.stack([u, v, 0.3 * np.sin(3 * u) * np.cos(2 * v)], axis=-1)
    G = G + 1e-4 * rng.normal(size=G.shape)
    errs = []
    for n in (5, 8, 12):
        s = approximate_surface(G, n, n)
        tu, tv = grid_parameters(G)
        errs.append(np.linalg.norm(s.evaluate_grid(tu, tv) - G, axis=-1).max())
        corners = s.evaluate_grid(np.array([0.0, 1.0]), np.array([0.0, 1.0]))
        assert np.abs(corners - G[np.ix_([0, -1], [0, -1])]).max() <= 1e-12
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-3


# ---------------------------------------------------------------- scattered data


def test_fit_surface_reproduces_spline_from_scattered_samples():
    rng = np.random.default_rng(71)
    for pu, pv, nu, nv in ((3, 3, 6, 7), (2, 3, 5, 4), (1, 2, 3, 5)):
        from splinekit.basis import clamped_uniform

        Pc = random_points(rng, (nu, nv), 3)
        S = BSplineSurface(pu, pv, clamped_uniform(pu, nu), clamped_uniform(pv, nv), Pc)
        uv = rng.uniform(0, 1, (30 * nu * nv, 2))
        Q = S.evaluate(uv[:, 0], uv[:, 1])
        F = fit_surface(Q, nu, nv, pu, pv, parameters=uv)
        assert np.abs(F.control_points - Pc).max() <= 1e-9 * size_of(Pc)


def test_fit_surface_default_parameters_height_field():
    # a tilted, turned height field: PCA plane + smallest rectangle recover the patch
    rng = np.random.default_rng(73)
    xy = rng.uniform(-1, 1, (3000, 2))
    z = 0.1 * np.sin(2 * xy[:, :1]) * np.cos(3 * xy[:, 1:])
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q = np.concatenate([xy, z], axis=1) @ R.T + rng.normal(size=3)
    F = fit_surface(Q, 12, 12, smoothing=1e-8)
    from splinekit.fit.scattered import plane_parameters

    uv = plane_parameters(Q)
    assert uv.min() == 0.0 and uv.max() == 1.0
    assert (
        np.histogram2d(uv[:, 0], uv[:, 1], bins=4)[0].min() > 0
    )  # the whole square is covered
    assert np.linalg.norm(
        F.evaluate(uv[:, 0], uv[:, 1]) - Q, axis=1
    ).max() <= 1e-3 * size_of(Q)


def test_fit_surface_smoothing_fills_holes_and_tends_to_affine_fit():
    from splinekit.basis import clamped_uniform
    from splinekit.fit.scattered import thin_plate_energy

    rng = np.random.default_rng(79)
    uv = rng.uniform(0, 1, (3000, 2))
    uv = uv[np.linalg.norm(uv - 0.5, axis=1) > 0.3]  # a hole in the middle
    affine = np.column_stack([uv, 1.0 + 2.0 * uv[:, 0] - 3.0 * uv[:, 1]])
    with pytest.raises(FittingError, match="smoothing"):
        fit_surface(affine, 15, 15, parameters=uv)
    # affine surfaces have zero thin-plate energy: reproduced exactly, across the hole too
    F = fit_surface(affine, 15, 15, parameters=uv, smoothing=1e-3)
    g = np.linspace(0.3, 0.7, 9)
    inside = F.evaluate_grid(g, g)
    gu, gv = np.meshgrid(g, g, indexing="ij")
    expect = np.stack([gu, gv, 1.0 + 2.0 * gu - 3.0 * gv], axis=-1)
    assert np.abs(inside - expect).max() <= 1e-9
    # noisy data: smoothing trades fidelity for smoothness
    Q = np.column_stack(
        [uv, 0.2 * np.sin(3 * uv[:, 0]) + 0.05 * rng.normal(size=len(uv))]
    )
    E = thin_plate_energy(3, 3, clamped_uniform(3, 10), clamped_uniform(3, 10))
    res, energy = [], []
    for lam in (1e-6, 1e-3, 1.0):
        F = fit_surface(Q, 10, 10, parameters=uv, smoothing=lam)
        z = F.control_points[..., 2].ravel()
        res.append(np.linalg.norm(F.evaluate(uv[:, 0], uv[:, 1]) - Q))
        energy.append(z @ (E @ z))
    assert res[0] < res[1] < res[2] and energy[0] > energy[1] > energy[2]
    # with overwhelming smoothing the surface becomes the least-squares affine function of (u, v)
    A = np.column_stack([np.ones(len(uv)), uv])
    best_affine = A @ np.linalg.lstsq(A, Q, rcond=None)[0]
    F = fit_surface(Q, 8, 8, parameters=uv, smoothing=1e9)
    assert np.abs(F.evaluate(uv[:, 0], uv[:, 1]) - best_affine).max() <= 1e-4


def test_fit_surface_matches_dense_normal_equations_with_empty_cells():
    # the cell-block assembly of A^T A (only cells holding data) against a dense
    # design matrix built row by row from the 1-D collocation matrices
    from splinekit.basis import clamped_uniform
    from splinekit.fit.scattered import thin_plate_energy

    rng = np.random.default_rng(81)
    uv = rng.uniform(0, 1, (400, 2))
    uv = uv[(uv[:, 0] < 0.4) | (uv[:, 1] > 0.6)]  # a quarter of the square without data
    Q = np.column_stack([uv, np.cos(2 * uv[:, 0]) * uv[:, 1]])
    pu, pv, nu, nv, lam = 3, 2, 7, 6, 1e-4
    Ku, Kv = clamped_uniform(pu, nu), clamped_uniform(pv, nv)
    Au = design_matrix(pu, Ku, uv[:, 0]).toarray()
    Av = design_matrix(pv, Kv, uv[:, 1]).toarray()
    A = (Au[:, :, None] * Av[:, None, :]).reshape(len(uv), nu * nv)
    E = thin_plate_energy(pu, pv, Ku, Kv).toarray()
    M = A.T @ A
    M = M + lam * np.trace(M) / np.trace(E) * E
    expect = np.linalg.solve(M, A.T @ Q).reshape(nu, nv, 3)
    F = fit_surface(Q, nu, nv, pu, pv, parameters=uv, smoothing=lam)
    assert np.abs(F.control_points - expect).max() <= 1e-9 * np.abs(expect).max()


# ---------------------------------------------------------------- bad input


def test_bad_input_scattered_fit_sizes_and_knots():
    from splinekit.fit.scattered import MAX_NET, thin_plate_energy

    rng = np.random.default_rng(5)
    Q = rng.normal(size=(50, 3))
    with pytest.raises(FittingError, match="control points, more than"):
        fit_surface(Q, 10**6, 10**6, smoothing=1.0)
    assert MAX_NET < 10**12
    with pytest.raises(SplineKitError, match=r"smoothing = 1e\+308 is too large"):
        fit_surface(Q, 4, 4, smoothing=1e308)
    with pytest.raises(SplineKitError, match="too large"):
        fit_surface(Q, 4, 4, smoothing=1e13)
    with pytest.raises(SplineKitError, match="knots_u"):
        thin_plate_energy(3, 3, [0.0, 0.0, 1.0, 1.0], [0, 0, 0, 0, 1, 1, 1, 1])
    with pytest.raises(SplineKitError, match=r"knots_v\[4\] = nan"):
        thin_plate_energy(3, 3, [0, 0, 0, 0, 1, 1, 1, 1], [0, 0, 0, 0, np.nan, 1, 1, 1, 1])
    with pytest.raises(SplineKitError, match="degree_u"):
        thin_plate_energy(0, 3, [0, 1], [0, 0, 0, 0, 1, 1, 1, 1])



def test_bad_input_coincident_points():
    P = np.array([[0.0, 0], [1, 0], [1, 0], [2, 1], [3, 0]])
    for call in (
        lambda: parametrize(P),
        lambda: parametrize(P, "chord"),
        lambda: interpolate_curve(P, 2),
        lambda: approximate_curve(P, 4, 2),
    ):
        with pytest.raises(FittingError, match=r"points\[1\] and points\[2\]"):
            call()
    G = np.zeros((4, 4, 3))
    G[..., 0] = np.arange(4)[None, :]
    G[..., 1] = np.array([0, 1, 1, 2])[:, None]  # grid rows 1 and 2 coincide
    with pytest.raises(FittingError, match="rows 1 and 2"):
        interpolate_surface(G, 2, 2)


def test_bad_input_too_few_points():
    P = np.random.default_rng(0).normal(size=(3, 2))
    with pytest.raises(FittingError, match="too few points for the degree"):
        interpolate_curve(P, 3)
    with pytest.raises(FittingError, match="too few points"):
        approximate_curve(P, 3, degree=3)
    with pytest.raises(FittingError, match="at least 2"):
        interpolate_curve(P[:1], 1)
    with pytest.raises(FittingError, match="too few"):
        interpolate_surface(np.zeros((3, 5, 3)) + np.arange(5)[None, :, None], 3, 3)
    with pytest.raises(FittingError, match="too few points"):
        fit_surface(np.random.default_rng(0).normal(size=(10, 3)), 4, 4)
    with pytest.raises(FittingError, match="degree >= 2"):
        interpolate_curve(P, 1, start_tangent=[1.0, 0.0])


def test_bad_input_shapes():
    rng = np.random.default_rng(1)
    P = rng.normal(size=(8, 3))
    cases = [
        lambda: interpolate_curve(P[:, 0], 3),  # 1-D array: shape (m, dim) expected
        lambda: interpolate_curve(P, 3, parameters=np.linspace(0, 1, 7)),
        lambda: interpolate_curve(P, 3, knots=np.linspace(0, 1, 10)),
        lambda: interpolate_curve(P, 3, start_tangent=[1.0, 0.0]),
        lambda: interpolate_surface(P, 3, 3),
        lambda: interpolate_surface(
            rng.normal(size=(5, 5, 3)), 2, 2, parameters_u=np.linspace(0, 1, 4)
        ),
        lambda: approximate_curve(P, 5, 3, knots=[0, 0, 0, 0, 0.5, 1, 1, 1, 1, 1]),
        lambda: approximate_surface(rng.normal(size=(6, 6)), 4, 4),
        lambda: fit_surface(
            rng.normal(size=(50, 3)), 4, 4, parameters=rng.uniform(size=(49, 2))
        ),
    ]
    for call in cases:
        with pytest.raises(SplineKitError, match="shape|knots give|must have"):
            call()


def test_bad_input_non_finite_and_out_of_range():
    rng = np.random.default_rng(2)
    P = rng.normal(size=(8, 3))
    bad = P.copy()
    bad[4, 1] = np.nan
    for call in (
        lambda: interpolate_curve(bad),
        lambda: approximate_curve(bad, 5),
        lambda: parametrize(bad),
    ):
        with pytest.raises(SplineKitError, match=r"\[4\] is not finite"):
            call()
    t = np.linspace(0, 1, 8)
    t[3] = np.inf
    with pytest.raises(SplineKitError, match=r"parameters\[3\]"):
        interpolate_curve(P, 3, parameters=t)
    with pytest.raises(SplineKitError, match="increase strictly"):
        interpolate_curve(P, 3, parameters=[0, 0.1, 0.2, 0.2, 0.5, 0.6, 0.9, 1])
    with pytest.raises(SplineKitError, match="start_tangent"):
        interpolate_curve(P, 3, start_tangent=[1.0, np.inf, 0.0])
    with pytest.raises(SplineKitError, match="tolerance must be >= 0"):
        approximate_curve(P, tolerance=-1e-3)
    with pytest.raises(SplineKitError, match="tolerance"):
        approximate_curve(P, tolerance=np.nan)
    with pytest.raises(SplineKitError, match="correct_parameters = 1000000000 exceeds"):
        approximate_curve(P, 5, correct_parameters=10**9)  # a billion refits: refused, not a hang
    with pytest.raises(SplineKitError, match="smoothing must be >= 0"):
        fit_surface(rng.normal(size=(100, 3)), 4, 4, smoothing=-1)
    with pytest.raises(SplineKitError, match="exceeds the number of points"):
        approximate_curve(P, 9, 3)
    with pytest.raises(SplineKitError, match="parametrization must be one of"):
        interpolate_curve(P, 3, "arc")
    with pytest.raises(SplineKitError, match="n_control, knots or tolerance"):
        approximate_curve(P)
    with pytest.raises(SplineKitError, match=r"parameters\[12\]"):
        fit_surface(
            rng.normal(size=(20, 3)),
            4,
            4,
            parameters=np.vstack(
                [rng.uniform(size=(12, 2)), [[0.5, 1.5]], rng.uniform(size=(7, 2))]
            ),
        )
    with pytest.raises(FittingError, match="n_control_u = 3 is too small"):
        fit_surface(rng.normal(size=(100, 3)), 3, 4)
    with pytest.raises(FittingError, match="collinear"):
        fit_surface(np.outer(np.arange(30.0), [1.0, 2.0, 3.0]), 4, 4)


@pytest.mark.parametrize("scale", [1e-300, 1e300])
def test_extreme_units(scale):
    # fitting is affine invariant: the same fit in any units, no overflow or underflow
    rng = np.random.default_rng(7)
    P = wavy_points(rng, 30)
    P = P / size_of(P)
    for fit in (
        lambda X: interpolate_curve(X, 3),
        lambda X: approximate_curve(X, 8, 3),
        lambda X: approximate_curve(X, tolerance=1e-3 * size_of(X)),
    ):
        a, b = fit(P), fit(P * scale)
        assert a.knots.shape == b.knots.shape and np.allclose(
            a.knots, b.knots, rtol=0, atol=1e-12
        )
        assert np.abs(b.control_points / scale - a.control_points).max() <= 1e-12
    uv = rng.uniform(0, 1, (200, 2))
    Q = np.column_stack([uv, np.sin(uv[:, 0])])
    a = fit_surface(Q, 5, 5, parameters=uv)
    b = fit_surface(Q * scale, 5, 5, parameters=uv)
    assert np.abs(b.control_points / scale - a.control_points).max() <= 1e-12
    with pytest.raises(FittingError, match="floating-point range"):
        interpolate_curve([[-1.7e308], [1.7e308], [-1.7e308], [1.7e308]], 3)


def test_tolerance_zero_interpolates():
    P = wavy_points(np.random.default_rng(8), 12)
    c = approximate_curve(P, tolerance=0.0)
    assert len(c.control_points) == 12
    assert np.abs(c.evaluate(parametrize(P)) - P).max() <= 1e-12 * size_of(P)


def test_bad_input_knot_helpers():
    with pytest.raises(SplineKitError, match="increase strictly"):
        averaged_knots([0.0, 0.5, 0.4, 1.0], 2)
    with pytest.raises(FittingError, match="too few parameters"):
        averaged_knots([0.0, 0.5, 1.0], 3)
    with pytest.raises(FittingError, match="exceeds the number of data points"):
        approximation_knots(np.linspace(0, 1, 5), 2, 6)
    with pytest.raises(SplineKitError, match="method must be"):
        approximation_knots(np.linspace(0, 1, 9), 2, 5, method="even")


def test_bad_input_schoenberg_whitney():
    # all data in the first half of the domain: basis functions of the second half are unconstrained
    P = np.random.default_rng(3).normal(size=(6, 2))
    t = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 1.0])
    U = [0, 0, 0, 0, 0.7, 0.8, 1, 1, 1, 1]
    with pytest.raises(FittingError, match="Schoenberg-Whitney"):
        interpolate_curve(P, 3, parameters=t, knots=U)
    with pytest.raises(SplineKitError, match="outside the parameter domain"):
        interpolate_curve(P, 3, parameters=t + 1.0, knots=U)
