"""The compiled curve kernels on the per-span Taylor table (splinekit.basis.taylor) against the
numpy path (Cox-de Boor, A2.2/A2.3) and against scipy's BSpline, on random knots (repeated
knots included), degrees, dimensions and weights."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.interpolate import BSpline

import splinekit as sk
from splinekit import _kernels
from splinekit.basis.taylor import MAX_DEGREE, span_taylor

pytest.importorskip("numba")


@pytest.fixture
def compiled_everywhere(monkeypatch):
    """Compiled kernels at every size (thresholds 0); yields a switch to the numpy path."""
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)

    def numpy_path(on: bool):
        if on:
            monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
        else:
            monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)

    return numpy_path


def random_curve(seed: int, degree: int, n: int, dim: int, rational: bool, clamped: bool):
    rng = np.random.default_rng(seed)
    inner = np.sort(rng.uniform(0.0, 1.0, n - degree - 1))
    if inner.size >= 3 and degree >= 2:
        inner[2] = inner[1]  # a repeated interior knot (an empty span inside the domain)
    if clamped:
        U = np.concatenate([[0.0] * (degree + 1), inner, [1.0] * (degree + 1)])
    else:
        U = np.sort(np.concatenate([inner, rng.uniform(-1.0, 0.0, degree + 1), rng.uniform(1.0, 2.0, degree + 1)]))
    P = rng.normal(size=(n, dim)) * 10.0
    if rational:
        return sk.NurbsCurve(degree, U, P, rng.uniform(0.2, 5.0, n))
    return sk.BSplineCurve(degree, U, P)


def sample(curve, seed: int, m: int = 600):
    """Scattered and sorted parameters, every knot of the domain and both ends."""
    a, b = curve.domain
    rng = np.random.default_rng(seed)
    U = np.asarray(curve.knots)
    knots = U[(U >= a) & (U <= b)]
    return np.concatenate([rng.uniform(a, b, m), np.linspace(a, b, m), knots, [a, b]])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    seed=st.integers(0, 2**31 - 1),
    degree=st.integers(1, MAX_DEGREE + 1),
    extra=st.integers(0, 12),
    dim=st.integers(1, 4),
    rational=st.booleans(),
    clamped=st.booleans(),
)
def test_taylor_kernels_match_the_numpy_path(compiled_everywhere, seed, degree, extra, dim, rational, clamped):
    """Points and derivatives up to order degree + 1 (the last one zero for a polynomial curve)
    agree with A2.2/A2.3 to rounding of each derivative's size; degrees above MAX_DEGREE take
    the A2.2 kernels and agree too."""
    compiled_everywhere(False)  # the fixture is shared by all examples: start each on the kernels
    curve = random_curve(seed, degree, degree + 1 + extra, dim, rational, clamped)
    u = sample(curve, seed)
    order = degree + 1
    fast_pts, fast_ders = curve.evaluate(u), curve.derivatives(u, order)
    compiled_everywhere(True)
    slow_pts, slow_ders = curve.evaluate(u), curve.derivatives(u, order)
    scale = np.abs(curve.control_points).max()
    np.testing.assert_allclose(fast_pts, slow_pts, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(fast_ders[0], slow_pts, rtol=0, atol=1e-13 * scale)
    for k in range(1, order + 1):
        size = max(np.abs(slow_ders[k]).max(), scale)
        np.testing.assert_allclose(fast_ders[k], slow_ders[k], rtol=0, atol=1e-11 * size, err_msg=f"order {k}")


@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_taylor_kernels_match_scipy(compiled_everywhere, degree):
    """Against an independent evaluator: scipy's BSpline on the same knots and control points
    (non-rational), and on (wP, w) then divided (rational), with its derivative splines."""
    for rational in (False, True):
        curve = random_curve(11 + degree, degree, 17, 3, rational, clamped=True)
        u = sample(curve, 5)
        spl = BSpline(np.asarray(curve.knots), np.asarray(curve.homogeneous_points), degree)
        h, h1 = spl(u), spl.derivative(1)(u)
        ref = h[:, :3] / h[:, 3:]
        ref1 = (h1[:, :3] - h1[:, 3:] * ref) / h[:, 3:]
        ders = curve.derivatives(u, 1)
        scale = np.abs(curve.control_points).max()
        np.testing.assert_allclose(curve.evaluate(u), ref, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(ders[0], ref, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(ders[1], ref1, rtol=0, atol=1e-11 * np.abs(ref1).max())


def test_span_taylor_table_reproduces_the_control_polygon_ends():
    """A clamped curve starts at its first control point and the table's first span says so;
    the breakpoints are the distinct knots of the domain."""
    curve = random_curve(3, 3, 9, 2, rational=False, clamped=True)
    breaks, table = span_taylor(3, np.asarray(curve.knots), np.asarray(curve.control_points))
    np.testing.assert_array_equal(breaks, np.unique(curve.knots))
    assert table.shape == (4, breaks.size - 1, 4, 2)
    np.testing.assert_allclose(table[0, 0, 0], curve.control_points[0], rtol=0, atol=1e-14)
    assert not table[1:, :, 3].any()  # derivative r has degree 3 - r
