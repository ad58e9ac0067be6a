"""Inputs the reliability report found accepted or escaping as the wrong error, and
extreme but valid inputs that evaluated to inf or NaN."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splinekit
from splinekit._atomic import atomic_write
from splinekit._validate import as_indices, as_path
from splinekit.errors import ControlPointError, DomainError, MeshTopologyError, ParameterError, SplineKitError
from splinekit.mesh import primitives

FLOAT_MAX = np.finfo(np.float64).max


# -- crease and corner maps ---------------------------------------------------------------------------
@pytest.mark.parametrize("key", [0.5, 2.5, 1.0, np.float64(1.0), True, "0", None, math.nan, math.inf, 1e20])
def test_corner_keys_must_be_integer_vertex_indices(key):
    with pytest.raises(ParameterError, match="corner vertex"):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", corners={key: 1.0})
    with pytest.raises(ParameterError, match="corner vertex"):
        splinekit.subdivide(primitives.box(), "catmull-clark", 1, corners={key: 1.0})


@pytest.mark.parametrize("key", [-1, 8, 10**20, np.uint64(2**63)])
def test_corner_keys_out_of_range(key):
    with pytest.raises(MeshTopologyError, match="outside 0..7"):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", corners={key: 1.0})


@pytest.mark.parametrize("key", [(0, 0.5), (0, 1.0), (0, True), (0, "1"), (0, math.nan), (0, math.inf), (0,), (0, 1, 2), 3])
def test_crease_keys_must_be_pairs_of_integer_vertex_indices(key):
    with pytest.raises(ParameterError):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", creases={key: 1.0})


@pytest.mark.parametrize("key", [(0, 10**20), (0, -1), (0, 8)])
def test_crease_keys_out_of_range(key):
    with pytest.raises(MeshTopologyError):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", creases={key: 1.0})


def test_crease_pair_arrays_are_not_truncated():
    # (edges, sharpness) with fractional indices was cast to int (0.5 -> 0) and accepted
    with pytest.raises(ParameterError, match="crease vertex"):
        splinekit.subdivide(primitives.box(), "catmull-clark", 1, creases=([[0.5, 1.0]], [2.0]))
    # integral indices still work and give the same result as a dict
    a = splinekit.subdivide(primitives.box(), "catmull-clark", 1, creases=([[0, 1]], [2.0]))
    b = splinekit.subdivide(primitives.box(), "catmull-clark", 1, creases={(0, 1): 2.0})
    assert np.array_equal(a.vertices, b.vertices)


@pytest.mark.parametrize("sharpness", [math.nan, -1.0, "x"])
def test_corner_and_crease_sharpness(sharpness):
    with pytest.raises(ParameterError):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", corners={0: sharpness})
    with pytest.raises(ParameterError):
        splinekit.SubdivisionSurface(primitives.box(), "catmull-clark", creases={(0, 1): sharpness})


def test_as_indices():
    assert as_indices([1, np.int32(2), np.uint8(3)], "i", 4).tolist() == [1, 2, 3]
    assert as_indices(np.zeros(0), "i", 4).dtype == np.int64  # an empty list of keys
    for bad in ([0.5], [1.0], [True], ["1"], [None], [[0, 1], [2]]):
        with pytest.raises(ParameterError):
            as_indices(bad, "i", 4)


# -- paths ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["a\0b.stl", b"a\0b.stl", "", 3, None])
def test_bad_paths_are_refused_with_a_splinekit_error(tmp_path, path):
    calls = []
    with pytest.raises(ParameterError):
        atomic_write(path, calls.append)
    assert not calls and not os.listdir(tmp_path)


def test_nul_path_names_the_problem():
    with pytest.raises(ParameterError, match="NUL"):
        as_path("x\0y")
    assert as_path(b"abc") == b"abc"


# -- tolerances ---------------------------------------------------------------------------------------
CURVE = splinekit.BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], np.random.default_rng(0).random((5, 3)))
SURFACE = splinekit.BezierSurface(np.random.default_rng(0).random((4, 4, 3)))


@pytest.mark.parametrize("tol", [math.nan, math.inf, -1.0, "x", [1e-6]])
@pytest.mark.parametrize(
    "call",
    [
        lambda tol: CURVE.arc_length(tol=tol),
        lambda tol: splinekit.BezierCurve(np.eye(3)).arc_length(tol=tol),
        lambda tol: CURVE.almost_equal(CURVE, tol),
        lambda tol: SURFACE.almost_equal(SURFACE, tol),
        lambda tol: splinekit.tessellate(SURFACE, tol),
    ],
)
def test_bad_tolerances_are_refused(call, tol):
    with pytest.raises(ParameterError):
        call(tol)


# -- extreme but accepted coordinates ------------------------------------------------------------------
def _knots(p, n, interior):
    return np.concatenate([np.zeros(p + 1), np.sort(interior)[: n - p - 1], np.ones(p + 1)])


coordinate = st.one_of(
    st.floats(-FLOAT_MAX, FLOAT_MAX, allow_nan=False, allow_infinity=False),
    st.sampled_from([FLOAT_MAX, -FLOAT_MAX, 1e308, -1e308, 8e307]),
)


@st.composite
def extreme_curves(draw):
    p = draw(st.integers(1, 5))
    n = draw(st.integers(p + 1, p + 4))
    dim = draw(st.integers(1, 3))
    P = np.array(draw(st.lists(coordinate, min_size=n * dim, max_size=n * dim))).reshape(n, dim)
    # distinct interior knots: a repeated one would be refused for its multiplicity, not its size
    interior = np.array(draw(st.lists(st.floats(0.01, 0.99), min_size=n - p - 1, max_size=n - p - 1, unique=True)))
    kind = draw(st.sampled_from(["bspline", "nurbs", "bezier"]))
    if kind == "bezier":
        return splinekit.BezierCurve(P[: p + 1])
    if kind == "nurbs":
        w = np.array(draw(st.lists(st.floats(0.1, 10.0), min_size=n, max_size=n)))
        return splinekit.NurbsCurve(p, _knots(p, n, interior), P, w)
    return splinekit.BSplineCurve(p, _knots(p, n, interior), P)


def _accepted(make):
    """The object, or None when it is refused for the one reason these inputs allow: a weight
    times a control point beyond the float range (any other refusal fails the test)."""
    try:
        return make()
    except ControlPointError as exc:
        assert "overflows the float range" in str(exc), exc
        return None


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_curves_near_the_float_limit_evaluate_to_finite_points(data):
    c = _accepted(lambda: data.draw(extreme_curves()))
    if c is None:
        return
    u = np.array(data.draw(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=20)))
    P = c.evaluate(u)
    assert np.isfinite(P).all()
    # the convex-hull property: inside the control points' box, up to the rounding of a convex
    # combination (a few units in the last place: (1 - t) a + t a can be one ulp below a)
    box = c.control_points
    slack = 4 * np.spacing(np.abs(box).max(axis=0))
    assert (P >= box.min(axis=0) - slack).all() and (P <= box.max(axis=0) + slack).all()
    assert np.isfinite(c.evaluate(float(u[0]))).all()
    try:
        D = c.derivatives(u, 2)
    except DomainError as exc:  # a derivative beyond the float range: refused, never returned as inf
        assert "float range" in str(exc), exc
        return
    assert np.isfinite(D).all()
    # the same points up to rounding: near the float limit the value path clips to the box
    assert (np.abs(D[0] - P) <= slack).all()


@st.composite
def extreme_surfaces(draw):
    p, q = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    P = np.array(draw(st.lists(coordinate, min_size=(p + 1) * (q + 1) * 3, max_size=(p + 1) * (q + 1) * 3)))
    P = P.reshape(p + 1, q + 1, 3)
    if draw(st.booleans()):
        w = np.array(draw(st.lists(st.floats(0.1, 10.0), min_size=(p + 1) * (q + 1), max_size=(p + 1) * (q + 1))))
        return splinekit.BezierSurface(P, w.reshape(p + 1, q + 1))
    return splinekit.BezierSurface(P)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_surfaces_near_the_float_limit_evaluate_to_finite_points(data):
    s = _accepted(lambda: data.draw(extreme_surfaces()))
    if s is None:
        return
    u = np.array(data.draw(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=10)))
    v = u[::-1].copy()
    box = s.control_points.reshape(-1, 3)
    slack = 4 * np.spacing(np.abs(box).max(axis=0))  # the rounding of a convex combination
    for P in (s.evaluate(u, v), s.evaluate_grid(u, v).reshape(-1, 3)):
        assert np.isfinite(P).all()
        assert (P >= box.min(axis=0) - slack).all() and (P <= box.max(axis=0) + slack).all()
    N = s.normal(u, v)
    assert np.isfinite(N).all()
    try:
        D = s.derivatives(u, v, 1)
    except DomainError as exc:  # a derivative beyond the float range: refused, never returned as inf
        assert "float range" in str(exc), exc
        return
    assert np.isfinite(D).all()


def test_the_reported_overflow_cases():
    # control points at the float limit: rounding in the convex combination overflowed
    c = splinekit.BezierCurve([[FLOAT_MAX, -FLOAT_MAX], [FLOAT_MAX, FLOAT_MAX], [FLOAT_MAX, -FLOAT_MAX]])
    P = c.evaluate(np.linspace(0, 1, 101))
    assert np.isfinite(P).all() and np.allclose(P[:, 0] / FLOAT_MAX, 1.0)
    # the middle of a line from -max to +max: (a + b) / 2 overflowed in the differences
    line = splinekit.BSplineCurve(1, [0, 0, 1, 1], [[-FLOAT_MAX], [FLOAT_MAX]])
    assert line.evaluate(0.5)[0] == 0.0
    with pytest.raises(DomainError, match="float range"):
        line.derivatives([0.5], 1)  # C' = 2 * max: not representable
    s = splinekit.BezierSurface(np.full((2, 2, 3), FLOAT_MAX) * np.array([1, -1, 1]))
    assert np.isfinite(s.evaluate_grid(np.linspace(0, 1, 5), np.linspace(0, 1, 5))).all()


def test_knot_algebra_near_the_float_limit_stays_exact():
    """A line from -max to +max: its differences overflow, but elevation, insertion and splitting
    are convex combinations of the control points, so the closed forms come out finite and exact."""
    line = splinekit.BSplineCurve(1, [0, 0, 1, 1], [[-FLOAT_MAX], [FLOAT_MAX]])
    M = FLOAT_MAX
    assert line.elevate_degree(1).control_points[:, 0].tolist() == [-M, 0.0, M]
    inserted = line.insert_knot(0.3).control_points[:, 0]
    np.testing.assert_allclose(inserted, [-M, -0.4 * M, M], rtol=1e-15)
    left, right = line.split(0.5)
    assert left.control_points[:, 0].tolist() == [-M, 0.0] and right.control_points[:, 0].tolist() == [0.0, M]


# -- found by the constructor fuzz (tests/fuzz/test_fuzz_constructors.py) --------------------------------
def test_cone_beyond_the_float_range_of_its_distance_is_refused():
    import splinekit.implicit as imp

    with pytest.raises(ParameterError, match="float range"):
        imp.cone((0, 0, 0), (0, 0, 1), 1e300)  # squared slant length overflowed (OverflowError)
    assert np.isfinite(imp.cone((0, 0, 0), (0, 0, 1), 1e150)([[0, 0, 0.5]])).all()


def test_sweep_along_a_path_beyond_1e154():
    # the rotation-minimizing frames squared raw chord lengths (OverflowError)
    path = splinekit.BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [0, 0, 0], [0, 0, 2.0**600]])
    profile = splinekit.BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.zeros((3, 3)))
    # refused with a SplineKitError (the frames no longer overflow into an OverflowError)
    with pytest.raises(SplineKitError):
        splinekit.sweep(profile, path)
