"""CurveBatch: many curves evaluated in one batch agree with each curve's own evaluation
(same kernels, so to the last bit) and with closed forms (a NURBS circle, a line)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.basis.knots import snapped_to_knots
from splinekit.curves.batch import CurveBatch
from splinekit.errors import DomainError, ParameterError
from splinekit.tolerances import DEFAULT


def _random_curves(rng, count, dim):
    """B-spline, NURBS and Bézier curves of degrees 1-4 with random (sometimes repeated) knots."""
    out = []
    for _ in range(count):
        p = int(rng.integers(1, 5))
        n = p + 1 + int(rng.integers(0, 6))
        inner = np.sort(rng.uniform(0.0, 1.0, n - p - 1))
        if inner.size > 1 and p > 1 and rng.random() < 0.3:
            inner[1] = inner[0]  # a repeated knot
        a, b = sorted(rng.uniform(-5.0, 5.0, 2))
        knots = a + (b - a + 1.0) * np.concatenate([[0.0] * (p + 1), inner, [1.0] * (p + 1)])
        P = rng.normal(size=(n, dim))
        kind = rng.integers(0, 3)
        if kind == 0:
            out.append(sk.BSplineCurve(p, knots, P))
        elif kind == 1:
            out.append(sk.NurbsCurve(p, knots, P, rng.uniform(0.2, 3.0, n)))
        else:
            out.append(sk.BezierCurve(P[: p + 1]))
    return out


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), dim=st.sampled_from([2, 3]))
def test_batch_matches_each_curve(seed, dim):
    rng = np.random.default_rng(seed)
    curves = _random_curves(rng, int(rng.integers(1, 12)), dim)
    batch = CurveBatch(curves)
    index = rng.integers(0, len(curves), 200)
    a, b = batch.domains[index, 0], batch.domains[index, 1]
    t = a + (b - a) * rng.uniform(0.0, 1.0, index.size)
    t[::7] = a[::7]  # domain ends and knots are where span search can go wrong
    t[::11] = b[::11]
    got, ders = batch.evaluate(index, t), batch.derivatives(index, t, 2)
    for i, c in enumerate(curves):
        rows = index == i
        if rows.any():
            np.testing.assert_array_equal(got[rows], c.evaluate(t[rows]))
            np.testing.assert_array_equal(ders[:, rows], c.derivatives(t[rows], 2))


def test_closed_forms():
    circle = sk.circle([1.0, 2.0, 0.0], [0.0, 0.0, 1.0], 3.0)
    line = sk.BSplineCurve(1, [0, 0, 1, 1], [[0.0, 0.0, 0.0], [2.0, 4.0, 6.0]])
    batch = CurveBatch([line, circle])
    t = np.linspace(*circle.domain, 41)
    index = np.r_[np.zeros(5, int), np.ones(t.size, int)]
    params = np.r_[np.linspace(0, 1, 5), t]
    pts = batch.evaluate(index, params)
    np.testing.assert_allclose(pts[:5], np.linspace(0, 1, 5)[:, None] * [2.0, 4.0, 6.0], rtol=0, atol=1e-15)
    r = np.linalg.norm(pts[5:] - [1.0, 2.0, 0.0], axis=1)
    np.testing.assert_allclose(r, 3.0, rtol=1e-14)
    d = batch.derivatives(index, params, 1)[1]
    np.testing.assert_allclose(d[:5], np.tile([2.0, 4.0, 6.0], (5, 1)), rtol=1e-14)
    # a circle's tangent is perpendicular to its radius
    np.testing.assert_allclose(np.einsum("md,md->m", d[5:], pts[5:] - [1.0, 2.0, 0.0]), 0.0, atol=1e-12)


def test_bad_input():
    line = sk.BSplineCurve(1, [0, 0, 1, 1], [[0.0, 0.0], [1.0, 1.0]])
    batch = CurveBatch([line])
    with pytest.raises(DomainError, match="curve 0"):
        batch.evaluate([0], [1.5])
    with pytest.raises(ParameterError):
        batch.evaluate([1], [0.5])
    with pytest.raises(ParameterError):
        CurveBatch([line, sk.BSplineCurve(1, [0, 0, 1, 1], [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])])
    with pytest.raises(ParameterError):
        CurveBatch([])


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_refine_snaps_like_one_knot_at_a_time(seed):
    """``snapped_to_knots`` (which ``refine`` applies to all its knots at once) gives, for every
    value, the first knot within the tolerance, or the value itself: the definition, applied one
    value at a time here, including values a hair off a knot."""
    rng = np.random.default_rng(seed)
    curve = _random_curves(rng, 1, 2)[0]
    curve = curve.to_bspline() if isinstance(curve, sk.BezierCurve) else curve
    a, b = curve.domain
    knots = np.asarray(curve.knots)
    values = np.concatenate([rng.uniform(a, b, 20), knots + rng.normal(scale=1e-13, size=knots.size) * (b - a)])
    values = np.clip(values, a, b)
    tol = DEFAULT.knot * (b - a)
    expected = np.array([knots[np.abs(knots - x) <= tol][0] if (np.abs(knots - x) <= tol).any() else x for x in values])
    np.testing.assert_array_equal(snapped_to_knots(knots, values, tol), expected)
    refined = curve.refine(values[:5])
    np.testing.assert_allclose(refined.evaluate(np.linspace(a, b, 50)), curve.evaluate(np.linspace(a, b, 50)), atol=1e-12)
