"""B-spline and NURBS curves and surfaces against two independent libraries: geomdl (NURBS-Python)
and splipy. Neither shares code with splinekit; each is given the same degree, full knot vector,
control points and weights, and must agree on

* curves (geomdl): points and derivatives up to order 3, knot insertion, Bézier degree elevation,
  decomposition into Bézier segments, and B-spline degree elevation segment by segment;
* surfaces (geomdl): points, partial derivatives up to order 2 and knot insertion in u and v;
* surfaces (splipy): grids of points and partial derivatives, knot insertion and degree elevation.

Geometry is random (tests/_geometry: clamped knots with interior multiplicities up to the degree,
weights in [0.2, 5], nets of scale 0.1 to 100), a few hundred cases per property; ``-m slow`` runs
four times as many. Tolerance: 1e-11 relative to the largest value compared (the libraries evaluate
in another order, so they agree to rounding, a few ulps amplified by the weights' spread), 1e-12
for control points of knot algebra (a few convex combinations).
"""

from __future__ import annotations

import numpy as np
import pytest
import splipy
from _geometry import random_curve_data, random_surface_data
from geomdl import BSpline, NURBS, helpers, operations

from splinekit import BezierCurve, BSplineCurve, BSplineSurface, NurbsCurve, NurbsSurface

CASES = 200  # random geometries per property in the default run
SLOW_CASES = 800
RTOL = 1e-11
KNOT_ALGEBRA_RTOL = 1e-12


def _case_counts():
    return [pytest.param(CASES, id=f"{CASES}-cases"), pytest.param(SLOW_CASES, id=f"{SLOW_CASES}-cases", marks=pytest.mark.slow)]


def _assert_close(ours, theirs, rtol, what):
    ours, theirs = np.asarray(ours, float), np.asarray(theirs, float)
    assert ours.shape == theirs.shape, (what, ours.shape, theirs.shape)
    scale = max(1.0, float(np.abs(theirs).max()))
    err = float(np.abs(ours - theirs).max())
    assert err <= rtol * scale, f"{what}: |splinekit - reference| = {err:.3e} > {rtol:.0e} * {scale:.3e}"


# -- building the references' objects from plain arrays ---------------------------------------------


def geomdl_curve(p, U, P, W):
    c = (BSpline.Curve if W is None else NURBS.Curve)(normalize_kv=False)
    c.degree = int(p)
    c.ctrlpts = np.asarray(P).tolist()
    if W is not None:
        c.weights = np.asarray(W).tolist()
    c.knotvector = np.asarray(U).tolist()
    return c


def geomdl_surface(pu, pv, ku, kv, P, W):
    """geomdl's flat control point list runs over v fastest: index ``i * nv + j``, as P.reshape."""
    s = (BSpline.Surface if W is None else NURBS.Surface)(normalize_kv=False)
    s.degree_u, s.degree_v = int(pu), int(pv)
    s.ctrlpts_size_u, s.ctrlpts_size_v = P.shape[:2]
    s.ctrlpts = P.reshape(-1, P.shape[-1]).tolist()
    if W is not None:
        s.weights = W.ravel().tolist()
    s.knotvector_u, s.knotvector_v = np.asarray(ku).tolist(), np.asarray(kv).tolist()
    return s


def splipy_surface(pu, pv, ku, kv, P, W):
    """splipy takes order = degree + 1, the net as (nu, nv, dim) listed with u fastest, and a
    rational net in homogeneous form (w x, w y, w z, w)."""
    net = P if W is None else np.concatenate([P * W[..., None], W[..., None]], axis=-1)
    flat = net.transpose(1, 0, 2).reshape(-1, net.shape[-1])
    return splipy.Surface(splipy.BSplineBasis(pu + 1, ku), splipy.BSplineBasis(pv + 1, kv), flat, rational=W is not None)


def ours_curve(p, U, P, W):
    return BSplineCurve(p, U, P) if W is None else NurbsCurve(p, U, P, W)


def ours_surface(pu, pv, ku, kv, P, W):
    return BSplineSurface(pu, pv, ku, kv, P) if W is None else NurbsSurface(pu, pv, ku, kv, P, W)


def parameters(rng, U, count):
    """Random parameters, the domain's ends and every distinct knot (where spans switch)."""
    a, b = U[0], U[-1]
    return np.unique(np.concatenate([rng.uniform(a, b, count), np.unique(U)]))


def insertion_site(rng, U, p):
    """A parameter inside the domain and a multiplicity that keeps it at most ``p``: half the time
    an existing interior knot (raising its multiplicity), else a fresh value."""
    values, counts = np.unique(U[p + 1 : -p - 1], return_counts=True)
    room = counts < p
    if room.any() and rng.random() < 0.5:
        k = int(rng.choice(np.flatnonzero(room)))
        return float(values[k]), int(rng.integers(1, p - counts[k] + 1))
    while True:
        u = float(rng.uniform(U[0], U[-1]))
        if np.abs(np.unique(U) - u).min() > 1e-3 * (U[-1] - U[0]):
            return u, int(rng.integers(1, p + 1))


# -- curves against geomdl -------------------------------------------------------------------------


@pytest.mark.parametrize("cases", _case_counts())
def test_curve_points_and_derivatives_match_geomdl(cases):
    rng = np.random.default_rng(20261125)
    for case in range(cases):
        data = random_curve_data(rng, rational=case % 2 == 1, max_degree=6)
        ref, ours = geomdl_curve(*data), ours_curve(*data)
        u = parameters(rng, data[1], 6)
        order = 3
        theirs = np.array([ref.derivatives(float(x), order) for x in u]).transpose(1, 0, 2)
        got = ours.derivatives(u, order)
        for k in range(order + 1):
            _assert_close(got[k], theirs[k], RTOL, f"case {case}: derivative {k}")
        _assert_close(ours.evaluate(u), np.array(ref.evaluate_list(u.tolist())), RTOL, f"case {case}: points")


@pytest.mark.parametrize("cases", _case_counts())
def test_curve_knot_insertion_matches_geomdl(cases):
    rng = np.random.default_rng(11)
    for case in range(cases):
        p, U, P, W = random_curve_data(rng, rational=case % 2 == 1, max_degree=6)
        u, r = insertion_site(rng, U, p)
        ref = operations.insert_knot(geomdl_curve(p, U, P, W), [u], [r])
        got = ours_curve(p, U, P, W).insert_knot(u, times=r)
        np.testing.assert_array_equal(got.knots, ref.knotvector, err_msg=f"case {case}")
        _assert_close(got.control_points, ref.ctrlpts, KNOT_ALGEBRA_RTOL, f"case {case}: control points")
        if W is not None:
            _assert_close(got.weights, ref.weights, KNOT_ALGEBRA_RTOL, f"case {case}: weights")


def _homogeneous(P, W):
    return np.asarray(P) if W is None else np.column_stack([np.asarray(P) * np.asarray(W)[:, None], W])


@pytest.mark.parametrize("cases", _case_counts())
def test_bezier_degree_elevation_matches_geomdl(cases):
    """geomdl elevates the homogeneous Bézier net (helpers.degree_elevation, the closed form)."""
    rng = np.random.default_rng(12)
    for case in range(cases):
        p, by = int(rng.integers(1, 8)), int(rng.integers(1, 4))
        P = rng.uniform(-10, 10, (p + 1, 3))
        W = rng.uniform(0.2, 5.0, p + 1) if case % 2 else None
        got = BezierCurve(P, W).elevate(by=by)
        theirs = np.array(helpers.degree_elevation(p, _homogeneous(P, W).tolist(), num=by))
        _assert_close(_homogeneous(got.control_points, got.weights), theirs, KNOT_ALGEBRA_RTOL, f"case {case}")


def _segments(curve):
    """geomdl's Bézier decomposition: homogeneous nets, one per knot span."""
    return [_homogeneous(s.ctrlpts, s.weights if hasattr(s, "weights") and s.rational else None)
            for s in operations.decompose_curve(curve)]


@pytest.mark.parametrize("cases", _case_counts())
def test_curve_bezier_decomposition_matches_geomdl(cases):
    rng = np.random.default_rng(13)
    for case in range(cases):
        data = random_curve_data(rng, rational=case % 2 == 1, max_degree=6)
        theirs = _segments(geomdl_curve(*data))
        got = ours_curve(*data).to_bezier()
        assert len(got) == len(theirs), case
        for i, (g, t) in enumerate(zip(got, theirs)):
            _assert_close(_homogeneous(g.control_points, g.weights), t, KNOT_ALGEBRA_RTOL, f"case {case} segment {i}")


@pytest.mark.parametrize("cases", _case_counts())
def test_curve_degree_elevation_matches_geomdl_segment_by_segment(cases):
    """A B-spline raised by one degree has, span by span, the Bézier segments of the original raised
    by one degree: geomdl decomposes both and elevates the original's segments itself (geomdl's own
    degree_operations does not keep the geometry of a B-spline with interior knots)."""
    rng = np.random.default_rng(14)
    for case in range(cases):
        p, U, P, W = random_curve_data(rng, rational=case % 2 == 1, max_degree=5)
        got = ours_curve(p, U, P, W).elevate_degree(1)
        assert got.degree == p + 1
        _, counts = np.unique(U, return_counts=True)
        _, new_counts = np.unique(got.knots, return_counts=True)
        np.testing.assert_array_equal(new_counts, counts + 1)  # every distinct knot gains one
        expected = [np.array(helpers.degree_elevation(p, seg.tolist(), num=1))
                    for seg in _segments(geomdl_curve(p, U, P, W))]
        theirs = _segments(geomdl_curve(got.degree, got.knots, got.control_points, got.weights))
        assert len(theirs) == len(expected), case
        for i, (g, t) in enumerate(zip(theirs, expected)):
            _assert_close(g, t, 1e-11, f"case {case} segment {i}")


# -- surfaces against geomdl -----------------------------------------------------------------------


@pytest.mark.parametrize("cases", _case_counts())
def test_surface_points_and_derivatives_match_geomdl(cases):
    rng = np.random.default_rng(21)
    for case in range(cases):
        data = random_surface_data(rng, rational=case % 2 == 1, max_degree=4, max_spans=3)
        ref, ours = geomdl_surface(*data), ours_surface(*data)
        (a, b), (c, d) = ours.domain
        u = np.concatenate([[a, b], rng.uniform(a, b, 4)])
        v = np.concatenate([[d, c], rng.uniform(c, d, 4)])
        got = ours.derivatives(u, v, 2)
        theirs = np.array([ref.derivatives(float(x), float(y), 2) for x, y in zip(u, v)])  # (n, 3, 3, dim)
        for k in range(3):
            for l in range(3 - k):  # geomdl fills the mixed orders above the total order with zeros
                _assert_close(got[k, l], theirs[:, k, l], RTOL, f"case {case}: d^{k + l} / du^{k} dv^{l}")


@pytest.mark.parametrize("cases", _case_counts())
def test_surface_knot_insertion_matches_geomdl(cases):
    rng = np.random.default_rng(22)
    for case in range(cases):
        pu, pv, ku, kv, P, W = random_surface_data(rng, rational=case % 2 == 1, max_degree=4, max_spans=3)
        direction = "uv"[case % 4 // 2]
        p, U = (pu, ku) if direction == "u" else (pv, kv)
        t, r = insertion_site(rng, U, p)
        where, times = ([t, None], [r, 0]) if direction == "u" else ([None, t], [0, r])
        ref = operations.insert_knot(geomdl_surface(pu, pv, ku, kv, P, W), where, times)
        got = ours_surface(pu, pv, ku, kv, P, W).insert_knot(t, times=r, direction=direction)
        np.testing.assert_array_equal(got.knots_u, ref.knotvector_u, err_msg=f"case {case}")
        np.testing.assert_array_equal(got.knots_v, ref.knotvector_v, err_msg=f"case {case}")
        shape = got.control_points.shape
        _assert_close(got.control_points, np.reshape(ref.ctrlpts, shape), KNOT_ALGEBRA_RTOL, f"case {case}")
        if W is not None:
            _assert_close(got.weights, np.reshape(ref.weights, shape[:2]), KNOT_ALGEBRA_RTOL, f"case {case}: weights")


# -- surfaces against splipy -----------------------------------------------------------------------


@pytest.mark.parametrize("cases", _case_counts())
def test_surface_grids_and_partial_derivatives_match_splipy(cases):
    rng = np.random.default_rng(31)
    for case in range(cases):
        data = random_surface_data(rng, rational=case % 2 == 1, max_degree=5, max_spans=4)
        ref, ours = splipy_surface(*data), ours_surface(*data)
        u, v = parameters(rng, data[2], 5), parameters(rng, data[3], 4)
        _assert_close(ours.evaluate_grid(u, v), ref(u, v), RTOL, f"case {case}: grid")
        U, V = np.meshgrid(u, v, indexing="ij")
        got = ours.derivatives(U.ravel(), V.ravel(), 2)
        for k, l in [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)]:
            theirs = ref.derivative(u, v, d=(k, l)).reshape(-1, 3)
            _assert_close(got[k, l], theirs, RTOL, f"case {case}: d^{k + l} / du^{k} dv^{l}")


def _splipy_net(surface):
    """splipy's net as (nu, nv, dim) Cartesian points and (nu, nv) weights (None if polynomial)."""
    net = surface.controlpoints
    if not surface.rational:
        return net, None
    return net[..., :-1] / net[..., -1:], net[..., -1]


@pytest.mark.parametrize("cases", _case_counts())
def test_surface_knot_insertion_and_degree_elevation_match_splipy(cases):
    rng = np.random.default_rng(32)
    for case in range(cases):
        pu, pv, ku, kv, P, W = random_surface_data(rng, rational=case % 2 == 1, max_degree=4, max_spans=3)
        ours = ours_surface(pu, pv, ku, kv, P, W)
        direction = "uv"[case % 4 // 2]
        axis = "uv".index(direction)
        p, U = (pu, ku) if direction == "u" else (pv, kv)
        t, r = insertion_site(rng, U, p)
        ref = splipy_surface(pu, pv, ku, kv, P, W)
        ref.insert_knot([t] * r, direction=axis)
        got = ours.insert_knot(t, times=r, direction=direction)
        np.testing.assert_allclose(got.knots_u if axis == 0 else got.knots_v, ref.knots(axis, with_multiplicities=True),
                                   rtol=0, atol=1e-15 * max(1.0, abs(U).max()), err_msg=f"case {case}")
        theirs_P, theirs_W = _splipy_net(ref)
        _assert_close(got.control_points, theirs_P, KNOT_ALGEBRA_RTOL, f"case {case}: inserted net")
        if W is not None:
            _assert_close(got.weights, theirs_W, KNOT_ALGEBRA_RTOL, f"case {case}: inserted weights")
        # degree elevation by one in the same direction
        ref = splipy_surface(pu, pv, ku, kv, P, W)
        ref.raise_order(*((1, 0) if axis == 0 else (0, 1)))
        got = ours.elevate_degree(1, direction=direction)
        assert (got.degree_u, got.degree_v) == (ref.order(0) - 1, ref.order(1) - 1)
        np.testing.assert_allclose(got.knots_u, ref.knots(0, with_multiplicities=True), rtol=0, atol=1e-12 * max(1.0, abs(ku).max()))
        np.testing.assert_allclose(got.knots_v, ref.knots(1, with_multiplicities=True), rtol=0, atol=1e-12 * max(1.0, abs(kv).max()))
        theirs_P, theirs_W = _splipy_net(ref)
        _assert_close(got.control_points, theirs_P, 1e-10, f"case {case}: elevated net")
        if W is not None:
            _assert_close(got.weights, theirs_W, 1e-10, f"case {case}: elevated weights")
