"""Reference tests of the B-spline and Bernstein bases.

Every value is compared against an independent, deliberately slow and naive
implementation written here: the scalar recursive Cox-de Boor formula with the
0/0 = 0 convention, its derivative formula, the closed-form Bernstein
polynomial through ``math.comb``, and exact rational de Casteljau evaluation
with ``fractions.Fraction``.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

import splinekit
from splinekit import BezierCurve, bernstein
from splinekit.basis import all_bernstein, basis_ders, basis_funs, design_matrix, find_span

ATOL = 1e-14


# ---------------------------------------------------------------------------------------
# The naive reference
# ---------------------------------------------------------------------------------------
def _ratio(num: float, den: float) -> float:
    """``num / den`` with the Cox-de Boor convention 0/0 = 0 (and x/0 = 0)."""
    return 0.0 if den == 0.0 else num / den


def naive_N(i: int, p: int, U, u: float, b: float) -> float:
    """``N_{i,p}(u)`` by the scalar Cox-de Boor recursion.

    Degree-0 functions are the indicators of ``[U[i], U[i+1])``, except at the
    right end ``b`` of the domain, where the left limit is used (indicator of
    ``(U[i], U[i+1]]``) so that the basis still sums to one there.
    """
    if p == 0:
        if u == b:
            return 1.0 if U[i] < u <= U[i + 1] else 0.0
        return 1.0 if U[i] <= u < U[i + 1] else 0.0
    left = _ratio(u - U[i], U[i + p] - U[i]) * naive_N(i, p - 1, U, u, b) if U[i + p] != U[i] else 0.0
    right = (
        _ratio(U[i + p + 1] - u, U[i + p + 1] - U[i + 1]) * naive_N(i + 1, p - 1, U, u, b)
        if U[i + p + 1] != U[i + 1]
        else 0.0
    )
    return left + right


def naive_dN(k: int, i: int, p: int, U, u: float, b: float) -> float:
    """k-th derivative of ``N_{i,p}`` by the derivative formula (NURBS Book eq. 2.9),
    applied recursively: ``N^(k)_{i,p} = p (N^(k-1)_{i,p-1} / (U[i+p] - U[i])
    - N^(k-1)_{i+1,p-1} / (U[i+p+1] - U[i+1]))`` with 0/0 = 0."""
    if k == 0:
        return naive_N(i, p, U, u, b)
    if k > p:
        return 0.0
    a = _ratio(naive_dN(k - 1, i, p - 1, U, u, b), U[i + p] - U[i]) if U[i + p] != U[i] else 0.0
    c = (
        _ratio(naive_dN(k - 1, i + 1, p - 1, U, u, b), U[i + p + 1] - U[i + 1])
        if U[i + p + 1] != U[i + 1]
        else 0.0
    )
    return p * (a - c)


def naive_basis_vector(p, U, u, order=0):
    """All ``n`` basis functions (or their ``order``-th derivatives) at ``u``."""
    n = len(U) - p - 1
    b = U[n]
    return np.array([naive_dN(order, i, p, U, u, b) for i in range(n)])


# ---------------------------------------------------------------------------------------
# Random knot vectors (clamped and unclamped, with repeated knots)
# ---------------------------------------------------------------------------------------
def random_knot_vector(rng: np.random.Generator):
    """A valid knot vector: ``(p, U)`` with ``n >= p + 1`` control points.

    Distinct values are strictly increasing with gaps in [0.05, 2] (random,
    non-uniform); interior multiplicities are 1..p, and the end values get up
    to p + 1 (clamped) or the vector is left unclamped.
    """
    while True:
        p = int(rng.integers(1, 7))
        n = int(rng.integers(p + 1, p + 9))
        m = n + p + 1
        mults = []
        total = 0
        while total < m:
            cap = p + 1 if not mults else p
            k = int(min(rng.integers(1, cap + 1), m - total))
            mults.append(k)
            total += k
        gaps = rng.uniform(0.05, 2.0, size=len(mults))
        values = np.cumsum(gaps) - gaps[0] + rng.uniform(-3, 3)
        U = np.repeat(values, mults)
        if rng.random() < 0.5:
            # force clamping: p + 1 equal values at both ends
            U[: p + 1] = U[p]
            U[-(p + 1):] = U[n]
        vals, counts = np.unique(U, return_counts=True)
        a, b = U[p], U[n]
        inner_ok = not np.any((vals > a) & (vals < b) & (counts > p))
        if a < b and inner_ok and counts.max() <= p + 1:
            return p, U


def parameters_for(p, U, rng, count=25):
    """Random parameters in the domain plus every knot of the domain and both ends."""
    n = len(U) - p - 1
    a, b = U[p], U[n]
    knots = U[(U >= a) & (U <= b)]
    return np.unique(np.concatenate([rng.uniform(a, b, count), knots, [a, b]]))


KNOT_VECTORS = [random_knot_vector(np.random.default_rng(seed)) for seed in range(60)]


# ---------------------------------------------------------------------------------------
# B-spline basis values
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("p, U", KNOT_VECTORS)
def test_basis_funs_match_naive_cox_de_boor(p, U):
    rng = np.random.default_rng(1)
    us = parameters_for(p, U, rng)
    span = find_span(p, U, us)
    vals = basis_funs(p, U, span, us)
    assert vals.shape == (us.size, p + 1)
    for row, (u, s) in enumerate(zip(us, span)):
        ref = naive_basis_vector(p, U, float(u))
        full = np.zeros_like(ref)
        full[s - p : s + 1] = vals[row]
        np.testing.assert_allclose(full, ref, rtol=0, atol=ATOL, err_msg=f"p={p} U={U.tolist()} u={u!r}")


@pytest.mark.parametrize("p, U", KNOT_VECTORS)
def test_find_span_contains_parameter(p, U):
    rng = np.random.default_rng(2)
    us = parameters_for(p, U, rng)
    n = len(U) - p - 1
    span = find_span(p, U, us)
    assert span.shape == us.shape
    assert np.all((span >= p) & (span <= n - 1))
    inside = us < U[n]
    assert np.all(U[span[inside]] <= us[inside])
    assert np.all(us[inside] < U[span[inside] + 1])
    # the right end belongs to the last non-empty span
    end = ~inside
    assert np.all(U[span[end]] < U[span[end] + 1])
    assert np.all(U[span[end] + 1] == U[n])


@pytest.mark.parametrize("p, U", KNOT_VECTORS)
def test_basis_derivatives_match_naive_formula(p, U):
    rng = np.random.default_rng(3)
    us = parameters_for(p, U, rng, count=12)
    order = p + 1  # includes one order above the degree (identically zero)
    span = find_span(p, U, us)
    ders = basis_ders(p, U, span, us, order)
    assert ders.shape == (order + 1, us.size, p + 1)
    h = np.diff(np.unique(U)).min()
    for k in range(order + 1):
        # derivative values scale like (p / h)^k; compare relative to that scale
        scale = max(1.0, (p / h) ** k)
        for row, (u, s) in enumerate(zip(us, span)):
            ref = naive_basis_vector(p, U, float(u), order=k)
            full = np.zeros_like(ref)
            full[s - p : s + 1] = ders[k, row]
            np.testing.assert_allclose(
                full, ref, rtol=0, atol=ATOL * scale, err_msg=f"k={k} p={p} U={U.tolist()} u={u!r}"
            )
    np.testing.assert_array_equal(ders[p + 1], 0.0)


@pytest.mark.parametrize("p, U", KNOT_VECTORS)
def test_partition_of_unity_and_nonnegativity(p, U):
    n = len(U) - p - 1
    us = np.concatenate([np.linspace(U[p], U[n], 2001), U[p : n + 1]])
    span = find_span(p, U, us)
    vals = basis_funs(p, U, span, us)
    np.testing.assert_allclose(vals.sum(axis=1), 1.0, rtol=0, atol=ATOL)
    assert (vals >= 0.0).all()
    # derivatives of a partition of unity sum to zero
    ders = basis_ders(p, U, span, us, p)
    h = np.diff(np.unique(U)).min()
    for k in range(1, p + 1):
        np.testing.assert_allclose(ders[k].sum(axis=1), 0.0, rtol=0, atol=1e-12 * max(1.0, (p / h) ** k))


@pytest.mark.parametrize("p, U", KNOT_VECTORS[:30])
@pytest.mark.parametrize("order", [0, 1, 2])
def test_design_matrix_matches_basis(p, U, order):
    rng = np.random.default_rng(4)
    us = parameters_for(p, U, rng)
    n = len(U) - p - 1
    A = design_matrix(p, U, us, order=order)
    assert A.shape == (us.size, n)
    dense = A.toarray()
    span = find_span(p, U, us)
    ders = basis_ders(p, U, span, us, order)[order]
    expected = np.zeros((us.size, n))
    for row, s in enumerate(span):
        expected[row, s - p : s + 1] = ders[row]
    np.testing.assert_array_equal(dense, expected)
    # and against the naive reference
    h = np.diff(np.unique(U)).min()
    ref = np.array([naive_basis_vector(p, U, float(u), order) for u in us])
    np.testing.assert_allclose(dense, ref, rtol=0, atol=ATOL * max(1.0, (p / h) ** order))
    # the exported top-level name is the same function
    assert splinekit.design_matrix is design_matrix


def test_design_matrix_evaluates_a_spline():
    p, U = KNOT_VECTORS[7]
    n = len(U) - p - 1
    rng = np.random.default_rng(5)
    P = rng.normal(size=(n, 3))
    curve = splinekit.BSplineCurve(p, U, P)
    us = np.linspace(U[p], U[n], 101)
    np.testing.assert_allclose(design_matrix(p, U, us) @ P, curve.evaluate(us), rtol=0, atol=1e-13)


# ---------------------------------------------------------------------------------------
# The NURBS Book, Ex2.3 / A2.2 and Ex2.4 / A2.3
# ---------------------------------------------------------------------------------------
NB_U = np.array([0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5], dtype=float)


def test_nurbs_book_example_2_3_basis_values():
    # On [2, 3) (span 4) the closed-form pieces are
    #   N_{2,2} = (3 - u)^2 / 2
    #   N_{3,2} = (u - 1)(3 - u) / 2 + (4 - u)(u - 2) / 2
    #   N_{4,2} = (u - 2)^2 / 2
    # so at u = 5/2: 1/8, 3/8 + 3/8 = 6/8, 1/8.
    u = np.array([2.5])
    span = find_span(2, NB_U, u)
    assert span.tolist() == [4]
    vals = basis_funs(2, NB_U, span, u)
    assert vals[0].tolist() == [1 / 8, 6 / 8, 1 / 8]
    full = design_matrix(2, NB_U, u).toarray()[0]
    assert full.tolist() == [0, 0, 1 / 8, 6 / 8, 1 / 8, 0, 0, 0]
    # the naive reference agrees exactly too
    assert naive_basis_vector(2, NB_U, 2.5).tolist() == [0, 0, 1 / 8, 6 / 8, 1 / 8, 0, 0, 0]


def test_nurbs_book_example_2_4_derivatives():
    # Differentiating the pieces above:
    #   N'_{2,2} = -(3 - u)        -> -1/2,   N''_{2,2} =  1
    #   N'_{3,2} = 5 - 2u          ->  0,     N''_{3,2} = -2
    #   N'_{4,2} = u - 2           ->  1/2,   N''_{4,2} =  1
    # and the third derivatives of quadratics vanish.
    u = np.array([2.5])
    span = find_span(2, NB_U, u)
    ders = basis_ders(2, NB_U, span, u, 3)[:, 0, :]
    assert ders.tolist() == [
        [1 / 8, 6 / 8, 1 / 8],
        [-1 / 2, 0.0, 1 / 2],
        [1.0, -2.0, 1.0],
        [0.0, 0.0, 0.0],
    ]


def test_nurbs_book_example_piecewise_closed_forms():
    """The quadratic pieces of N_{3,2} on [1, 2), [2, 3), [3, 4) (NURBS Book Ex2.2)."""
    pieces = [
        (1.0, 2.0, lambda u: (u - 1) ** 2 / 2),
        (2.0, 3.0, lambda u: (u - 1) * (3 - u) / 2 + (4 - u) * (u - 2) / 2),
        (3.0, 4.0, lambda u: (4 - u) ** 2 / 2),
    ]
    for lo, hi, f in pieces:
        us = np.linspace(lo, hi, 17)[:-1]
        got = design_matrix(2, NB_U, us).toarray()[:, 3]
        np.testing.assert_allclose(got, [f(u) for u in us], rtol=0, atol=ATOL)


# ---------------------------------------------------------------------------------------
# Bernstein polynomials
# ---------------------------------------------------------------------------------------
def closed_form_bernstein(n, i, t):
    return math.comb(n, i) * t**i * (1 - t) ** (n - i)


@pytest.mark.parametrize("n", [0, 1, 2, 3, 5, 8, 13, 20, 30])
def test_bernstein_matches_comb_closed_form(n):
    ts = np.concatenate([np.linspace(0, 1, 101), np.random.default_rng(n).uniform(0, 1, 50)])
    for i in range(n + 1):
        got = bernstein(n, i, ts)
        assert got.shape == ts.shape
        # exact reference through Fractions, then rounded
        ref = np.array([float(closed_form_bernstein(n, i, Fraction(float(t)))) for t in ts])
        np.testing.assert_allclose(got, ref, rtol=0, atol=ATOL, err_msg=f"B_{i}^{n}")
        # and the float closed form
        flt = np.array([closed_form_bernstein(n, i, float(t)) for t in ts])
        np.testing.assert_allclose(got, flt, rtol=0, atol=ATOL)


def test_bernstein_out_of_range_index_is_zero_and_shapes():
    t = np.linspace(0, 1, 7).reshape(7, 1)
    assert np.array_equal(bernstein(4, -1, t), np.zeros((7, 1)))
    assert np.array_equal(bernstein(4, 5, t), np.zeros((7, 1)))
    assert bernstein(3, 1, 0.5).shape == ()
    assert float(bernstein(3, 1, 0.5)) == 3 / 8
    assert all_bernstein(4, t).shape == (5, 7, 1)


@pytest.mark.parametrize("n", [1, 2, 4, 7, 12])
def test_bernstein_derivatives_match_closed_form(n):
    # d/dt B_i^n = n (B_{i-1}^{n-1} - B_i^{n-1})
    ts = np.linspace(0, 1, 41)
    ders = all_bernstein(n, ts, order=2)
    assert ders.shape == (3, n + 1, ts.size)

    def B(m, i, t):
        return closed_form_bernstein(m, i, t) if 0 <= i <= m else 0.0

    for i in range(n + 1):
        d1 = np.array([n * (B(n - 1, i - 1, t) - B(n - 1, i, t)) for t in ts])
        np.testing.assert_allclose(ders[1, i], d1, rtol=0, atol=1e-13 * n)
        if n >= 2:
            d2 = np.array(
                [n * (n - 1) * (B(n - 2, i - 2, t) - 2 * B(n - 2, i - 1, t) + B(n - 2, i, t)) for t in ts]
            )
            np.testing.assert_allclose(ders[2, i], d2, rtol=0, atol=1e-13 * n * n)


def test_bernstein_partition_of_unity_high_degree():
    ts = np.linspace(0, 1, 1001)
    vals = all_bernstein(40, ts)
    np.testing.assert_allclose(vals.sum(axis=0), 1.0, rtol=0, atol=ATOL)
    assert (vals >= 0).all()


# ---------------------------------------------------------------------------------------
# Degree-25 Bézier curve against exact rational arithmetic
# ---------------------------------------------------------------------------------------
def exact_de_casteljau(points, t: Fraction):
    """de Casteljau in Fractions: ``points`` a list of tuples of Fractions."""
    b = [list(pt) for pt in points]
    while len(b) > 1:
        b = [[(1 - t) * x + t * y for x, y in zip(b[j], b[j + 1])] for j in range(len(b) - 1)]
    return b[0]


# Measured (numpy 2.4, x86-64): max error 5.3e-16 (non-rational) and 2.4e-16
# (rational), relative to the largest control-point coordinate of each axis.
BEZIER_RTOL = 1e-13


def _degree25_setup(seed, n_random=195):
    rng = np.random.default_rng(seed)
    P = rng.uniform(-1, 1, size=(26, 3)) * np.array([1.0, 10.0, 1e3])
    ts = np.concatenate([[0.0, 1.0, 0.5, 1e-3, 1 - 1e-3], rng.uniform(0, 1, n_random)])
    return P, ts


# exact Fractions take about 30 ms per parameter: 45 random parameters by default, 195 under -m slow
N_RANDOM = [45, pytest.param(195, marks=pytest.mark.slow)]


@pytest.mark.parametrize("n_random", N_RANDOM)
def test_degree_25_bezier_against_exact_fractions(n_random):
    P, ts = _degree25_setup(25, n_random)
    curve = BezierCurve(P)
    assert curve.degree == 25
    got = curve.evaluate(ts)
    Pf = [tuple(Fraction(float(x)) for x in row) for row in P]
    exact = np.array([[float(x) for x in exact_de_casteljau(Pf, Fraction(float(t)))] for t in ts])
    # relative to the scale of each coordinate (the curve is a convex combination)
    scale = np.abs(P).max(axis=0)
    rel = np.abs(got - exact) / scale
    assert rel.max() <= BEZIER_RTOL, f"max relative error {rel.max():.3g}"
    # the exact end points are reproduced exactly
    np.testing.assert_array_equal(got[0], P[0])
    np.testing.assert_array_equal(got[1], P[-1])


@pytest.mark.parametrize("n_random", N_RANDOM)
def test_degree_25_rational_bezier_against_exact_fractions(n_random):
    P, ts = _degree25_setup(26, n_random)
    w = np.random.default_rng(27).uniform(0.25, 4.0, size=26)
    curve = BezierCurve(P, weights=w)
    got = curve.evaluate(ts)
    H = [tuple(Fraction(float(x)) * Fraction(float(wi)) for x in row) + (Fraction(float(wi)),) for row, wi in zip(P, w)]
    exact = []
    for t in ts:
        h = exact_de_casteljau(H, Fraction(float(t)))
        exact.append([float(x / h[-1]) for x in h[:-1]])
    exact = np.array(exact)
    scale = np.abs(P).max(axis=0)
    rel = np.abs(got - exact) / scale
    assert rel.max() <= BEZIER_RTOL, f"max relative error {rel.max():.3g}"


def test_degree_25_bezier_derivative_against_exact_hodograph():
    """C'(t) = 25 * sum (P[i+1] - P[i]) B_i^24(t), evaluated exactly."""
    P, ts = _degree25_setup(28)
    curve = BezierCurve(P)
    got = curve.derivatives(ts[:60], 1)[1]
    Pf = [tuple(Fraction(float(x)) for x in row) for row in P]
    D = [tuple(25 * (b - a) for a, b in zip(Pf[i], Pf[i + 1])) for i in range(25)]
    exact = np.array([[float(x) for x in exact_de_casteljau(D, Fraction(float(t)))] for t in ts[:60]])
    scale = np.abs(np.array(D, dtype=float)).max(axis=0)
    rel = np.abs(got - exact) / scale
    assert rel.max() <= 1e-12, f"max relative error {rel.max():.3g}"
