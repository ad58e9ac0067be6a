"""Bad input: every error is a specific SplineKitError subclass whose message
names the problem, and random malformed input never escapes as anything else.

The fuzz tests run with warnings turned into errors and numpy's floating-point
error handling set to raise, so a RuntimeWarning (overflow, invalid value,
division by zero) inside splinekit is reported as a failure too.
"""

from __future__ import annotations

import contextlib
import math
import re
import warnings
from datetime import timedelta

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from splinekit import (
    BezierCurve,
    BezierSurface,
    BSplineCurve,
    BSplineSurface,
    NurbsCurve,
    NurbsSurface,
    SplineKitError,
    bernstein,
)
from splinekit.errors import (
    ControlPointError,
    DegreeError,
    DomainError,
    KnotRemovalError,
    KnotVectorError,
    ParameterError,
    WeightError,
)

P5 = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, -1.0], [3.0, 1.0], [4.0, 0.0]])
U5 = [0, 0, 0, 1, 2, 3, 3, 3]  # degree 2, 5 control points, domain [0, 3]


def curve():
    return BSplineCurve(2, U5, P5)


def nurbs():
    return NurbsCurve(2, U5, P5, [1.0, 2.0, 0.5, 1.0, 1.0])


def surface():
    P = np.random.default_rng(0).normal(size=(3, 4, 3))
    return BSplineSurface(1, 2, [0, 0, 0.5, 1, 1], [0, 0, 0, 1, 2, 2, 2], P)


def test_errors_are_value_errors():
    for cls in (ControlPointError, DegreeError, DomainError, KnotRemovalError, KnotVectorError, ParameterError,
                WeightError):
        assert issubclass(cls, SplineKitError)
    assert issubclass(SplineKitError, ValueError)


def raises(cls, *words):
    """``pytest.raises(cls)`` that also checks the message contains every word
    (case-insensitive, literal)."""

    @contextlib.contextmanager
    def ctx():
        with pytest.raises(cls) as info:
            yield info
        assert type(info.value) is cls or issubclass(type(info.value), cls)
        message = str(info.value).lower()
        for word in words:
            assert str(word).lower() in message, f"{word!r} not in message {str(info.value)!r}"

    return ctx()


# ---------------------------------------------------------------------------------------
# Knot vectors
# ---------------------------------------------------------------------------------------
def test_knots_not_non_decreasing():
    with raises(KnotVectorError, "non-decreasing", "knots[4]", "1.0"):
        BSplineCurve(2, [0, 0, 0, 2, 1, 3, 3, 3], P5)
    with raises(KnotVectorError, "non-decreasing", "knots_v"):
        BSplineSurface(1, 1, [0, 0, 1, 1], [0, 1, 0, 1], np.zeros((2, 2, 3)))


@pytest.mark.parametrize("knots", [[0, 0, 0, 1, 2, 2, 2], [0, 0, 0, 1, 2, 3, 3, 3, 3], [0, 1], []])
def test_wrong_knot_count(knots):
    # 5 control points of degree 2 need 5 + 2 + 1 = 8 knots
    with raises(KnotVectorError, f"has {len(knots)} values", "= 8"):
        BSplineCurve(2, knots, P5)
    with raises(KnotVectorError, "= 8"):
        NurbsCurve(2, knots, P5, np.ones(5))


def test_wrong_knot_count_surface_names_direction():
    with raises(KnotVectorError, "knots_u", "5 values", "= 4"):
        BSplineSurface(1, 1, [0, 0, 0.5, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 3)))
    with raises(KnotVectorError, "knots_v", "5 values", "= 4"):
        NurbsSurface(1, 1, [0, 0, 1, 1], [0, 0, 0, 1, 1], np.zeros((2, 2, 3)), np.ones((2, 2)))


def test_interior_multiplicity_above_degree():
    P6 = np.vstack([P5, [[5.0, 1.0]]])
    with raises(KnotVectorError, "interior knot 1.0", "multiplicity 3"):
        BSplineCurve(2, [0, 0, 0, 1, 1, 1, 2, 2, 2], P6)


def test_end_multiplicity_above_degree_plus_one():
    with raises(KnotVectorError, "0.0", "appears 4 times"):
        BSplineCurve(2, [0, 0, 0, 0, 1, 3, 3, 3], P5)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_knots(bad):
    knots = [0, 0, 0, 1, 2, 3, 3, 3]
    knots[3] = bad
    with raises(KnotVectorError, "knots[3]", "not finite"):
        BSplineCurve(2, knots, P5)


def test_empty_domain():
    with raises(KnotVectorError, "empty domain"):
        BSplineCurve(2, [0] * 8, P5)


@pytest.mark.parametrize("knots", [[[0, 0, 0, 1, 2, 3, 3, 3]], None, "01234567", [0, 0, 0, 1, 2, "x", 3, 3]])
def test_knots_of_wrong_shape_or_type(knots):
    with pytest.raises(KnotVectorError):
        BSplineCurve(2, knots, P5)


# ---------------------------------------------------------------------------------------
# Weights
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [0.0, -2.0, -0.0])
def test_non_positive_weights(bad):
    w = [1.0, 1.0, bad, 1.0, 1.0]
    with raises(WeightError, "weights[2]", "> 0"):
        NurbsCurve(2, U5, P5, w)
    with raises(WeightError, "> 0"):
        BezierCurve(P5, w)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_weights(bad):
    w = [1.0, 1.0, 1.0, bad, 1.0]
    with raises(WeightError, "weights[3]", "finite"):
        NurbsCurve(2, U5, P5, w)
    W = np.ones((2, 2))
    W[1, 0] = bad
    with raises(WeightError, "weights[1, 0]", "finite"):
        NurbsSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 3)), W)


@pytest.mark.parametrize("w", [np.ones(4), np.ones(6), np.ones((5, 1)), 1.0])
def test_weights_of_wrong_shape(w):
    with raises(WeightError, "shape", "(5,)"):
        NurbsCurve(2, U5, P5, w)


def test_surface_weights_of_wrong_shape():
    with raises(WeightError, "shape", "(2, 2)", "(2, 3)"):
        NurbsSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 3)), np.ones((2, 3)))


# ---------------------------------------------------------------------------------------
# Control points
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_control_points(bad):
    P = P5.copy()
    P[2, 1] = bad
    with raises(ControlPointError, "control_points[2]", "not finite"):
        BSplineCurve(2, U5, P)
    with raises(ControlPointError, "not finite"):
        NurbsCurve(2, U5, P, np.ones(5))
    with raises(ControlPointError, "not finite"):
        BezierCurve(P)
    S = np.zeros((2, 3, 3))
    S[1, 2, 0] = bad
    with raises(ControlPointError, "control_points[1, 2]", "not finite"):
        BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 0.5, 1, 1], S)
    with raises(ControlPointError, "not finite"):
        BezierSurface(S)


@pytest.mark.parametrize(
    "P, words",
    [
        (np.arange(5.0), ["shape", "(5,)"]),
        (np.zeros((5, 2, 1)), ["shape", "(5, 2, 1)"]),
        (np.zeros((5, 0)), ["at least one coordinate"]),
        (np.zeros((2, 2)), ["at least 3 points"]),
        (5.0, ["shape"]),
        ([[0, 0], [1], [2, 2], [3, 3], [4, 4]], ["real numbers"]),
        ([["a", "b"]] * 5, ["real numbers"]),
        (np.ones((5, 2), dtype=complex), ["real numbers"]),
        (None, ["shape"]),
    ],
)
def test_control_points_of_wrong_shape_or_type(P, words):
    with raises(ControlPointError, *words):
        BSplineCurve(2, U5, P)


def test_too_few_control_points_for_degree():
    with raises(ControlPointError, "at least 4 points", "got 3"):
        BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1], np.zeros((3, 2)))
    with raises(ControlPointError, "at least 2 points"):
        BezierCurve([[0.0, 1.0]])


def test_surface_control_points_of_wrong_shape():
    with raises(ControlPointError, "(nu, nv, dim)", "(2, 2)"):
        BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2)))
    with raises(ControlPointError, "at least 3 points along axis 1"):
        BSplineSurface(1, 2, [0, 0, 1, 1], [0, 0, 0, 1, 1], np.zeros((2, 2, 3)))
    with raises(ControlPointError, "shape"):
        BezierSurface(np.zeros((3, 3)))


# ---------------------------------------------------------------------------------------
# Degrees
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("degree", [0, -1, -100])
def test_degree_below_one(degree):
    with raises(DegreeError, ">= 1", f"got {degree}"):
        BSplineCurve(degree, U5, P5)
    with raises(DegreeError, "degree_v", ">= 1"):
        BSplineSurface(1, degree, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 3)))
    with raises(DegreeError, ">= 1"):
        BSplineCurve.closed(degree, P5)


@pytest.mark.parametrize("degree", [2.5, 2.0, "2", None, True, np.float64(2.0), [2]])
def test_degree_not_an_integer(degree):
    with raises(DegreeError, "integer"):
        BSplineCurve(degree, U5, P5)
    with raises(DegreeError, "degree_u", "integer"):
        NurbsSurface(degree, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.zeros((2, 2, 3)), np.ones((2, 2)))


def test_numpy_integer_degree_is_accepted():
    assert BSplineCurve(np.int64(2), U5, P5).degree == 2


def test_huge_degree():
    # either the degree is refused outright or there are too few control points
    with pytest.raises((DegreeError, ControlPointError)):
        BSplineCurve(10**30, U5, P5)


# ---------------------------------------------------------------------------------------
# Parameters outside the domain
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("u", [-0.5, 3.5, 1e300, math.nan, math.inf, -math.inf])
def test_evaluate_outside_domain(u):
    value = "nan" if math.isnan(u) else repr(float(u))
    with raises(DomainError, value, "domain"):
        curve().evaluate(u)
    with raises(DomainError, value, "domain"):
        curve().evaluate([0.5, u, 1.0])
    with raises(DomainError, value):
        nurbs().evaluate(np.array([[1.0], [u]]))


@pytest.mark.parametrize("u", [-0.5, 3.5, math.nan])
def test_derivatives_outside_domain(u):
    value = "nan" if math.isnan(u) else repr(float(u))
    with raises(DomainError, value, "domain"):
        curve().derivatives(u, 2)
    with raises(DomainError, value, "domain"):
        nurbs().tangent(u)


def test_derivative_order_invalid():
    with raises(ParameterError, "order", ">= 0"):
        curve().derivatives(1.0, -1)
    with raises(ParameterError, "order", "integer"):
        curve().derivatives(1.0, 1.5)


@pytest.mark.parametrize("u", [0.0, 3.0])
def test_split_at_domain_end(u):
    with raises(DomainError, repr(u), "strictly inside"):
        curve().split(u)


@pytest.mark.parametrize("u", [-1.0, 7.0, math.nan])
def test_split_outside_domain(u):
    with raises(DomainError, "nan" if math.isnan(u) else repr(u), "domain"):
        curve().split(u)
    with raises(DomainError):
        BezierCurve(P5).split(u)


@pytest.mark.parametrize("u", [-1.0, 3.5, math.inf])
def test_insert_knot_outside_domain(u):
    with raises(DomainError, repr(u), "domain"):
        curve().insert_knot(u)
    with raises(DomainError, repr(u), "domain"):
        nurbs().refine([1.5, u])


def test_insert_knot_above_multiplicity():
    with raises(KnotVectorError, "multiplicity 3", "at most 2"):
        curve().insert_knot(1.0, 2)
    with raises(KnotVectorError, "multiplicity 3", "at most 2"):
        surface().insert_knot(1.0, 2, direction="v")


def test_insert_knot_times_invalid():
    with raises(ParameterError, "times", ">= 0"):
        curve().insert_knot(1.5, -1)
    with raises(ParameterError, "times", "integer"):
        curve().insert_knot(1.5, 1.0)


def test_surface_parameters_outside_domain():
    s = surface()
    with raises(DomainError, "v = 3.0", "domain"):
        s.evaluate(0.5, 3.0)
    with raises(DomainError, "u = -1.0", "domain"):
        s.derivatives(-1.0, 0.5)
    with raises(DomainError, "strictly inside"):
        s.split(2.0, direction="v")
    with raises(DomainError, "2.5", "domain"):
        s.insert_knot(2.5, direction="v")
    with raises(DomainError):
        s.evaluate_grid([0.5, 1.5], [0.5])
    with raises(ParameterError, "same shape"):
        s.evaluate([0.1, 0.2], [0.1, 0.2, 0.3])


def test_surface_direction_invalid():
    with raises(ParameterError, "direction", "'w'"):
        surface().split(0.5, direction="w")
    with raises(ParameterError, "direction"):
        surface().elevate_degree(1, direction=2)


# ---------------------------------------------------------------------------------------
# Knot removal
# ---------------------------------------------------------------------------------------
def test_knot_removal_beyond_tolerance():
    with raises(KnotRemovalError, "removing knot 1.0", "tolerance"):
        curve().remove_knot(1.0)
    with raises(KnotRemovalError, "tolerance"):
        nurbs().remove_knot(2.0)
    with raises(KnotRemovalError, "tolerance"):
        surface().remove_knot(1.0, direction="v")
    # an explicit, too small tolerance
    moved = curve().insert_knot(1.5)
    P = moved.control_points.copy()
    P[3] += 1e-6
    nudged = BSplineCurve(2, moved.knots, P)
    with raises(KnotRemovalError, "tolerance"):
        nudged.remove_knot(1.5, tol=1e-9)
    assert nudged.remove_knot(1.5, tol=1e-5).knots.tolist() == U5


@pytest.mark.parametrize("u", [1.5, 0.0, 3.0])
def test_removal_of_a_knot_that_is_not_there(u):
    with raises(KnotRemovalError, repr(u), "not an interior knot"):
        curve().remove_knot(u)


def test_removal_more_times_than_the_multiplicity():
    with raises(KnotRemovalError, "multiplicity 2", "3 times"):
        curve().insert_knot(1.0).remove_knot(1.0, 3)
    with raises(KnotRemovalError, "not an interior", "u knot"):
        surface().remove_knot(0.25, direction="u")


@pytest.mark.parametrize(
    "tol", [math.nan, -1.0, math.inf, "small", object(), pytest.param(10**400, id="int-10**400")]
)
def test_knot_removal_tolerance_invalid(tol):
    # a NaN tolerance must not let any removal through
    with raises(SplineKitError, "tol"):
        curve().insert_knot(1.5).remove_knot(1.5, tol=tol)
    with raises(SplineKitError, "tol"):
        curve().remove_knot(1.0, tol=tol)


# ---------------------------------------------------------------------------------------
# Other arguments
# ---------------------------------------------------------------------------------------
def test_elevate_by_invalid():
    with raises(ParameterError, "by", ">= 0"):
        curve().elevate_degree(-1)
    with raises(ParameterError, "by", "integer"):
        BezierCurve(P5).elevate(1.5)


def test_bernstein_invalid():
    with raises(ParameterError, "n", ">= 0"):
        bernstein(-1, 0, 0.5)
    with raises(ParameterError, "i", "integer"):
        bernstein(3, 1.5, 0.5)
    with pytest.raises(ParameterError):
        bernstein(3, 1, "0.5")


@pytest.mark.parametrize("t", [math.nan, math.inf, -math.inf, [0.5, math.nan]])
def test_bernstein_non_finite_parameter(t):
    """The rest of the library refuses non-finite parameters; bernstein should too
    rather than return NaN (or, for inf, raise numpy's 'invalid value' warning)."""
    with strict(), pytest.raises(SplineKitError):
        bernstein(3, 1, t)


def test_transform_invalid():
    with raises(ParameterError, "matrix", "(2, 2)", "(3, 3)"):
        curve().transform(np.eye(4))
    with raises(ParameterError, "last row"):
        curve().transform(np.ones((3, 3)))
    with raises(ParameterError, "non-finite"):
        curve().transform(np.full((2, 2), np.nan))


def test_reparametrize_invalid():
    with raises(DomainError, "start < end"):
        curve().reparametrize(1.0, 1.0)
    with raises(DomainError, "finite"):
        curve().reparametrize(0.0, math.inf)
    for bad in ("a", None, object(), [0.0, 1.0]):
        with pytest.raises(SplineKitError):
            curve().reparametrize(bad, 1.0)


# ---------------------------------------------------------------------------------------
# Extreme but finite values: a clean result or a SplineKitError, never inf/nan or a
# floating-point warning
# ---------------------------------------------------------------------------------------
@contextlib.contextmanager
def strict():
    """Warnings are errors and numpy floating-point errors raise.

    Underflow stays ignored, as in numpy's default: it is harmless gradual
    underflow (e.g. a tiny weight times a tiny coordinate) and numpy never warns
    about it; overflow, invalid operations and division by zero raise."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(over="raise", divide="raise", invalid="raise", under="ignore"):
            yield


def _rejected(build, match):
    """``build()`` raises a SplineKitError whose message matches ``match``, with no
    floating-point warning or error on the way (a rejection must not be an accident)."""
    with strict(), pytest.raises(SplineKitError, match=match):
        build()


def test_extreme_weights_times_points_do_not_overflow():
    """Weights 1e200 on points 1e200: the homogeneous coordinates w * P overflow, so the
    curve is refused; at 1e150 the products fit and the values are the closed form."""
    _rejected(lambda: NurbsCurve(1, [0, 0, 1, 1], [[1e200], [1.0]], [1e200, 1.0]), "overflow")
    with strict():
        c = NurbsCurve(1, [0, 0, 1, 1], [[1e150], [1.0]], [1e150, 1.0])
        t = np.linspace(0, 1, 5)
        out = c.evaluate(t)[:, 0]
    # degree 1: C(t) = ((1 - t) w0 P0 + t w1 P1) / ((1 - t) w0 + t w1)
    expected = ((1 - t) * 1e300 + t) / ((1 - t) * 1e150 + t)
    np.testing.assert_allclose(out, expected, rtol=1e-14)


def test_subnormal_domain_is_refused():
    """A domain [0, 5e-324] is non-empty, but basis functions divide by its knot gap."""
    _rejected(lambda: BSplineCurve(1, [0, 0, 5e-324, 5e-324], [[0.0], [1.0]]), r"knots\[1\].*overflow")


def test_huge_domain_is_refused():
    """A domain [-1e308, 1e308] is wider than floating point represents (its length overflows)."""
    _rejected(lambda: BSplineCurve(1, [-1e308, -1e308, 1e308, 1e308], [[0.0], [1.0]]), "wider than")
    with strict():  # half as wide fits: the line from 0 to 1 is linear in u
        c = BSplineCurve(1, [-1e307, -1e307, 1e307, 1e307], [[0.0], [1.0]])
        np.testing.assert_allclose(c.evaluate(np.array([-1e307, 0.0, 1e307]))[:, 0], [0.0, 0.5, 1.0], rtol=0, atol=1e-15)


# ---------------------------------------------------------------------------------------
# Fuzzing: random malformed input only ever raises SplineKitError
# ---------------------------------------------------------------------------------------
FUZZ = settings(
    max_examples=80,
    deadline=timedelta(seconds=5),  # a hang shows up as a DeadlineExceeded failure
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

NAN, INF = math.nan, math.inf
finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
any_float = st.one_of(finite, st.sampled_from([NAN, INF, -INF, 0.0, -0.0]))


class Opaque:
    """An object numpy cannot convert."""

    def __repr__(self):
        return "Opaque()"


scalar_junk = st.one_of(
    any_float,
    st.integers(-(10**20), 10**20),
    st.booleans(),
    st.none(),
    st.text(max_size=4),
    st.builds(Opaque),
    st.complex_numbers(max_magnitude=10, allow_nan=False, allow_infinity=False),
    st.just(10**400),
    st.binary(max_size=3),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
)

shapes = hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=6)
float_arrays = hnp.arrays(np.float64, shapes, elements=any_float)
int_arrays = hnp.arrays(np.int64, shapes, elements=st.integers(-(10**6), 10**6))
odd_arrays = st.one_of(
    hnp.arrays(np.bool_, shapes),
    hnp.arrays(np.complex128, shapes, elements=st.complex_numbers(max_magnitude=10)),
    hnp.arrays(hnp.unicode_string_dtypes(max_len=3), shapes),
    hnp.arrays(object, shapes, elements=scalar_junk),
)
nested = st.recursive(scalar_junk, lambda inner: st.lists(inner, max_size=5), max_leaves=24)
junk = st.one_of(scalar_junk, float_arrays, int_arrays, odd_arrays, nested)

degree_junk = st.one_of(
    st.integers(-5, 12),
    st.integers(-(10**30), 10**30),
    st.floats(allow_nan=True),
    st.sampled_from([np.int64(2), np.int32(-1), np.float64(2.0), np.uint8(3), True, False]),
    scalar_junk,
)


@st.composite
def knot_junk(draw, size_hint):
    """Random knot vectors: near-valid lengths, unsorted, repeated, non-finite, or any junk."""
    kind = draw(st.integers(0, 3))
    if kind == 0:
        size = draw(st.integers(max(0, size_hint - 2), size_hint + 2))
        values = draw(st.lists(any_float, min_size=size, max_size=size))
        return sorted(values, key=lambda x: (math.isnan(x), x)) if draw(st.booleans()) else values
    if kind == 1:
        size = draw(st.integers(max(0, size_hint - 2), size_hint + 2))
        ints = sorted(draw(st.lists(st.integers(0, 4), min_size=size, max_size=size)))
        return np.array(ints, dtype=draw(st.sampled_from([np.float64, np.int64, np.float32])))
    if kind == 2:
        return draw(hnp.arrays(np.float64, (size_hint,), elements=any_float))
    return draw(junk)


@st.composite
def curve_arguments(draw):
    """Arguments of BSplineCurve / NurbsCurve: a valid set, with any subset replaced by junk."""
    p = draw(st.integers(1, 4))
    n = draw(st.integers(p + 1, p + 5))
    d = draw(st.integers(1, 4))
    args = {
        "degree": p,
        "knots": np.concatenate([np.zeros(p + 1), np.arange(1, n - p), np.full(p + 1, n - p)]),
        "control_points": draw(hnp.arrays(np.float64, (n, d), elements=finite)),
        "weights": draw(hnp.arrays(np.float64, (n,), elements=st.floats(0.1, 10))),
    }
    corrupt = draw(st.sets(st.sampled_from(sorted(args)), max_size=4))
    for key in corrupt:
        if key == "degree":
            args[key] = draw(degree_junk)
        elif key == "knots":
            args[key] = draw(knot_junk(n + p + 1))
        elif key == "control_points":
            args[key] = draw(st.one_of(junk, hnp.arrays(np.float64, (n, d), elements=any_float)))
        else:
            args[key] = draw(st.one_of(junk, hnp.arrays(np.float64, (n,), elements=any_float)))
    return args, corrupt


def only_splinekit_errors(fn, *args, **kwargs):
    """Call ``fn`` strictly; a SplineKitError is fine (returns None), anything else
    (another exception, a warning, a floating-point error) propagates."""
    with strict():
        try:
            return fn(*args, **kwargs)
        except SplineKitError:
            return None


def _exercise_curve(c):
    a, b = c.domain
    u = np.linspace(a, b, 7)
    with strict():
        pts = c.evaluate(u)
        ders = c.derivatives(u, 2)
    assert np.isfinite(pts).all() and np.isfinite(ders).all()


@FUZZ
@given(data=curve_arguments(), rational=st.booleans())
def test_fuzz_curve_constructors(data, rational):
    args, corrupt = data
    if rational:
        c = only_splinekit_errors(NurbsCurve, args["degree"], args["knots"], args["control_points"], args["weights"])
    else:
        c = only_splinekit_errors(BSplineCurve, args["degree"], args["knots"], args["control_points"])
    if not corrupt:
        assert c is not None
    if c is not None:
        _exercise_curve(c)


@FUZZ
@given(points=st.one_of(junk, hnp.arrays(np.float64, hnp.array_shapes(min_dims=1, max_dims=3, max_side=6), elements=any_float)),
       weights=st.one_of(st.none(), junk), degree=degree_junk)
def test_fuzz_bezier_and_closed_constructors(points, weights, degree):
    c = only_splinekit_errors(BezierCurve, points, weights)
    if c is not None:
        _exercise_curve(c)
    c = only_splinekit_errors(BSplineCurve.closed, degree, points, weights)
    if c is not None:
        _exercise_curve(c)
    c = only_splinekit_errors(BSplineCurve.uniform, degree, points)
    if c is not None:
        _exercise_curve(c)
    s = only_splinekit_errors(BezierSurface, points, weights)
    if s is not None:
        with strict():
            assert np.isfinite(s.evaluate_grid(np.linspace(0, 1, 3), np.linspace(0, 1, 3))).all()


@st.composite
def surface_arguments(draw):
    pu, pv = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    nu, nv = draw(st.integers(pu + 1, pu + 3)), draw(st.integers(pv + 1, pv + 3))
    d = draw(st.integers(1, 4))
    args = {
        "degree_u": pu,
        "degree_v": pv,
        "knots_u": np.concatenate([np.zeros(pu + 1), np.arange(1, nu - pu), np.full(pu + 1, nu - pu)]),
        "knots_v": np.concatenate([np.zeros(pv + 1), np.arange(1, nv - pv), np.full(pv + 1, nv - pv)]),
        "control_points": draw(hnp.arrays(np.float64, (nu, nv, d), elements=finite)),
        "weights": draw(hnp.arrays(np.float64, (nu, nv), elements=st.floats(0.1, 10))),
    }
    corrupt = draw(st.sets(st.sampled_from(sorted(args)), max_size=3))
    for key in corrupt:
        if key.startswith("degree"):
            args[key] = draw(degree_junk)
        elif key == "knots_u":
            args[key] = draw(knot_junk(nu + pu + 1))
        elif key == "knots_v":
            args[key] = draw(knot_junk(nv + pv + 1))
        elif key == "control_points":
            args[key] = draw(st.one_of(junk, hnp.arrays(np.float64, (nu, nv, d), elements=any_float)))
        else:
            args[key] = draw(st.one_of(junk, hnp.arrays(np.float64, (nu, nv), elements=any_float)))
    return args, corrupt


@FUZZ
@given(data=surface_arguments(), rational=st.booleans())
def test_fuzz_surface_constructors(data, rational):
    args, corrupt = data
    keys = ["degree_u", "degree_v", "knots_u", "knots_v", "control_points"]
    if rational:
        s = only_splinekit_errors(NurbsSurface, *[args[k] for k in keys], args["weights"])
    else:
        s = only_splinekit_errors(BSplineSurface, *[args[k] for k in keys])
    if not corrupt:
        assert s is not None
    if s is not None:
        (a, b), (c, d) = s.domain
        with strict():
            assert np.isfinite(s.evaluate_grid(np.linspace(a, b, 4), np.linspace(c, d, 3))).all()
            assert np.isfinite(s.derivatives(np.linspace(a, b, 4), np.linspace(c, d, 4), 1)).all()


# -- methods of valid objects with malformed arguments ----------------------------------
@st.composite
def valid_curves(draw):
    p = draw(st.integers(1, 4))
    n = draw(st.integers(p + 1, p + 4))
    d = draw(st.integers(1, 3))
    inner = np.sort(draw(hnp.arrays(np.float64, (n - p - 1,), elements=st.floats(0.05, 0.95), unique=True)))
    U = np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])
    P = draw(hnp.arrays(np.float64, (n, d), elements=st.floats(-10, 10)))
    kind = draw(st.sampled_from(["bspline", "nurbs", "bezier"]))
    if kind == "bspline":
        return BSplineCurve(p, U, P)
    w = draw(hnp.arrays(np.float64, (n,), elements=st.floats(0.1, 10)))
    if kind == "nurbs":
        return NurbsCurve(p, U, P, w)
    return BezierCurve(P, w if draw(st.booleans()) else None)


def param_junk(domain=(0.0, 1.0), knots=()):
    a, b = domain
    good = st.one_of(st.floats(a, b), st.sampled_from(list(knots) or [a, b]))
    near = st.floats(a - 1, b + 1, allow_nan=False)
    return st.one_of(good, near, junk)


count_junk = st.one_of(st.integers(-5, 10), st.integers(-(10**12), 10**12), scalar_junk)
small_count_junk = st.one_of(st.integers(-5, 4), scalar_junk)
order_junk = st.one_of(st.integers(-5, 40), scalar_junk)
tol_junk = st.one_of(st.none(), st.floats(-1, 1), st.floats(1e-12, 1e3), scalar_junk)


@FUZZ
@given(c=valid_curves(), data=st.data())
def test_fuzz_curve_evaluate(c, data):
    u = data.draw(param_junk(c.domain))
    out = only_splinekit_errors(c.evaluate, u)
    if out is not None:
        assert np.isfinite(out).all()


@FUZZ
@given(c=valid_curves(), data=st.data())
def test_fuzz_curve_derivatives(c, data):
    u = data.draw(param_junk(c.domain))
    order = data.draw(order_junk)
    out = only_splinekit_errors(c.derivatives, u, order)
    if out is not None:
        assert np.isfinite(out).all()
    only_splinekit_errors(c.tangent, u)


@FUZZ
@given(c=valid_curves(), data=st.data())
def test_fuzz_curve_insert_knot(c, data):
    spline = c.to_bspline() if isinstance(c, BezierCurve) else c
    u = data.draw(param_junk(spline.domain, spline.knots))
    times = data.draw(count_junk)
    new = only_splinekit_errors(spline.insert_knot, u, times)
    if new is not None:
        _exercise_curve(new)
    new = only_splinekit_errors(spline.refine, data.draw(st.one_of(junk, st.lists(param_junk(spline.domain), max_size=4))))
    if new is not None:
        _exercise_curve(new)


@FUZZ
@given(c=valid_curves(), by=small_count_junk)
def test_fuzz_curve_elevate_degree(c, by):
    if isinstance(c, BezierCurve):
        new = only_splinekit_errors(c.elevate, by)
    else:
        new = only_splinekit_errors(c.elevate_degree, by)
    if new is not None:
        _exercise_curve(new)


@FUZZ
@given(c=valid_curves(), data=st.data())
def test_fuzz_curve_split(c, data):
    u = data.draw(param_junk(c.domain, getattr(c, "knots", ())))
    parts = only_splinekit_errors(c.split, u)
    if parts is not None:
        for part in parts:
            _exercise_curve(part)


@FUZZ
@given(c=valid_curves(), data=st.data())
def test_fuzz_curve_remove_knot(c, data):
    spline = c.to_bspline() if isinstance(c, BezierCurve) else c
    u = data.draw(param_junk(spline.domain, spline.knots))
    if data.draw(st.booleans()):
        inserted = only_splinekit_errors(spline.insert_knot, u)
        spline = inserted if inserted is not None else spline
    times = data.draw(count_junk)
    tol = data.draw(tol_junk)
    new = only_splinekit_errors(spline.remove_knot, u, times, tol)
    if new is not None:
        _exercise_curve(new)


@st.composite
def valid_surfaces(draw):
    pu, pv = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    nu, nv = draw(st.integers(pu + 1, pu + 3)), draw(st.integers(pv + 1, pv + 3))
    ku = np.concatenate([np.zeros(pu + 1), np.linspace(0, 1, nu - pu + 1)[1:-1], np.ones(pu + 1)])
    kv = np.concatenate([np.zeros(pv + 1), np.linspace(0, 1, nv - pv + 1)[1:-1], np.ones(pv + 1)])
    P = draw(hnp.arrays(np.float64, (nu, nv, 3), elements=st.floats(-10, 10)))
    if draw(st.booleans()):
        W = draw(hnp.arrays(np.float64, (nu, nv), elements=st.floats(0.1, 10)))
        return NurbsSurface(pu, pv, ku, kv, P, W)
    return BSplineSurface(pu, pv, ku, kv, P)


direction_junk = st.one_of(st.sampled_from(["u", "v", "U", "V", 0, 1]), scalar_junk)


@FUZZ
@given(s=valid_surfaces(), data=st.data())
def test_fuzz_surface_methods(s, data):
    u = data.draw(param_junk(s.domain[0], s.knots_u))
    v = data.draw(param_junk(s.domain[1], s.knots_v))
    direction = data.draw(direction_junk)
    for fn, args in [
        (s.evaluate, (u, v)),
        (s.derivatives, (u, v, data.draw(order_junk))),
        (s.normal, (u, v)),
        (s.evaluate_grid, (u, v)),
        (s.isocurve, (u, None)),
    ]:
        out = only_splinekit_errors(fn, *args)
        if isinstance(out, np.ndarray):
            assert np.isfinite(out).all()
    for fn, args in [
        (s.insert_knot, (u, data.draw(count_junk), direction)),
        (s.elevate_degree, (data.draw(small_count_junk), direction)),
        (s.split, (u, direction)),
        (s.remove_knot, (u, data.draw(count_junk), data.draw(tol_junk), direction)),
        (s.refine, (data.draw(junk), direction)),
    ]:
        out = only_splinekit_errors(fn, *args)
        if out is None:
            continue
        for part in out if isinstance(out, tuple) else (out,):
            (a, b), (c, d) = part.domain
            with strict():
                assert np.isfinite(part.evaluate_grid(np.linspace(a, b, 3), np.linspace(c, d, 3))).all()


@FUZZ
@given(n=st.one_of(st.integers(-3, 30), scalar_junk), i=st.one_of(st.integers(-3, 30), scalar_junk), t=junk)
def test_fuzz_bernstein(n, i, t):
    out = only_splinekit_errors(bernstein, n, i, t)
    if out is not None:
        assert isinstance(out, (np.ndarray, np.floating))
        assert np.isfinite(out).all()


@FUZZ
@given(degree=degree_junk, knots=st.one_of(knot_junk(8), junk), u=junk, order=order_junk)
def test_fuzz_design_matrix(degree, knots, u, order):
    from splinekit import design_matrix

    A = only_splinekit_errors(design_matrix, degree, knots, u, order)
    if A is not None:
        assert np.isfinite(A.toarray()).all()


def test_messages_are_plain_text():
    """Messages show plain numbers, not numpy reprs such as np.float64(0.0)."""
    for build in (
        lambda: NurbsCurve(2, U5, P5, [1, 0, 1, 1, 1]),
        lambda: curve().evaluate(np.float64(7.0)),
        lambda: BSplineCurve(2, [0, 0, 0, 2, 1, 3, 3, 3], P5),
    ):
        with pytest.raises(SplineKitError) as info:
            build()
        assert not re.search(r"np\.\w+\(", str(info.value)), str(info.value)


def test_bernstein_far_outside_unit_interval_is_refused():
    # found by the fuzzer: at t = -2**53 the triangle's denominator (1 - t) + t rounds to 0
    with raises(DomainError, "too far outside"):
        bernstein(1, 0, -(2.0**53))
    # within the limit the extrapolated polynomial is exact: B_0^128(3) = (1 - 3)^128
    assert bernstein(128, 0, 3.0) == 2.0**128
