"""Cross-check splinekit against OpenCascade (OCP 7.9) on random geometry.

The OCC objects are built here, directly from the arrays, with the small
helpers below (1-based OCC arrays, knots as distinct values plus
multiplicities), so a bug in ``splinekit.occ.to_occ`` cannot hide a bug in the
math; ``to_occ`` / ``from_occ`` get their own round-trip tests.

Random geometry (``tests/_geometry.py``): degrees 1-7, clamped knot vectors on
a random domain with interior knots of multiplicity 1..degree, control points
in a random box of size 0.1..100, weights uniform in [0.2, 5]; every test runs
polynomial and rational. Each case draws from
``numpy.random.default_rng([SALT, seed, rational])`` and failure messages
print the full case, so any failure is reproducible from its test id.
Evaluation of large batches (at least ``splinekit._kernels.MIN_WORK``
points) may run compiled kernels instead of numpy; the ``large_batch`` tests
check that path against OCC as well.

Tolerances
----------
* Round trips splinekit -> OCC -> splinekit are lossless: 1e-12 relative to
  the net size ``max(1, max|P|)`` (only rational control points are divided
  by their weights and back, which costs an ulp).
* Points and derivatives: ``|ours - occ| <= 1e-9 * scale_k`` with, for the
  derivative of order ``k`` (``(k, l)`` on surfaces),
  ``scale_k = max(1, net, max over the sampled parameters of |occ value|)``.
  A point is compared relative to the net size. A k-th derivative scales
  like ``net * (p / h)**k`` (``h`` a knot spacing) and rounding errors scale
  with the terms summed, not with the possibly small result at one
  parameter; the largest value of that derivative over the samples is the
  natural "net size" for it, and the floor ``max(1, net)`` covers
  derivatives that are identically zero (order above the degree).
* Knot algebra (insertion, refinement, elevation, removal, Bézier
  decomposition): knots exactly equal in count and to 1e-12 relative to the
  domain in value, control points to 1e-9 * net, weights to 1e-9 * max weight.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.Geom import Geom_BezierCurve, Geom_BezierSurface, Geom_BSplineCurve, Geom_BSplineSurface
from OCP.GeomConvert import GeomConvert_BSplineCurveToBezierCurve, GeomConvert_BSplineSurfaceToBezierSurface
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TColgp import TColgp_Array1OfPnt, TColgp_Array2OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal, TColStd_Array2OfReal

import splinekit as sk
from splinekit import _kernels
from _geometry import (
    interior_params,
    middle_of_widest_span,
    random_curve_data,
    random_points,
    random_surface_data,
    random_weights,
)
from splinekit.errors import KnotRemovalError

RTOL = 1e-9  # evaluation and knot algebra, relative (see the module docstring)
ROUND_TRIP_TOL = 1e-12  # to_occ / from_occ, relative to the net size
KNOT_TOL = 1e-12  # knot values, relative to the domain length

RATIONAL = pytest.mark.parametrize("rational", [False, True], ids=["poly", "rational"])
DIRECTION = pytest.mark.parametrize("direction", ["u", "v"])

# Test-specific salts, so that different tests draw different geometry.
SALT_CURVE_ROUND_TRIP = 101
SALT_CURVE_EVAL = 102
SALT_CURVE_INSERT = 103
SALT_CURVE_ELEVATE = 104
SALT_CURVE_REMOVE = 105
SALT_CURVE_BEZIER = 106
SALT_SURF_ROUND_TRIP = 201
SALT_SURF_EVAL = 202
SALT_SURF_INSERT = 203
SALT_SURF_ELEVATE = 204
SALT_SURF_REMOVE = 205
SALT_SURF_BEZIER = 206
SALT_BEZIER_CURVE = 301
SALT_BEZIER_SURFACE = 302


def make_rng(salt: int, seed: int, rational: bool, *extra: int) -> np.random.Generator:
    return np.random.default_rng([salt, seed, int(rational), *extra])


# ----------------------------------------------------------------------------------------
# OCC construction and read-back (independent of splinekit.occ)
# ----------------------------------------------------------------------------------------
def _real1(values) -> TColStd_Array1OfReal:
    arr = TColStd_Array1OfReal(1, len(values))
    for i, x in enumerate(values):
        arr.SetValue(i + 1, float(x))
    return arr


def _int1(values) -> TColStd_Array1OfInteger:
    arr = TColStd_Array1OfInteger(1, len(values))
    for i, x in enumerate(values):
        arr.SetValue(i + 1, int(x))
    return arr


def _pnt1(P) -> TColgp_Array1OfPnt:
    arr = TColgp_Array1OfPnt(1, len(P))
    for i, x in enumerate(P):
        arr.SetValue(i + 1, gp_Pnt(float(x[0]), float(x[1]), float(x[2])))
    return arr


def _pnt2(P) -> TColgp_Array2OfPnt:
    nu, nv = P.shape[:2]
    arr = TColgp_Array2OfPnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            x = P[i, j]
            arr.SetValue(i + 1, j + 1, gp_Pnt(float(x[0]), float(x[1]), float(x[2])))
    return arr


def _real2(W) -> TColStd_Array2OfReal:
    nu, nv = W.shape
    arr = TColStd_Array2OfReal(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            arr.SetValue(i + 1, j + 1, float(W[i, j]))
    return arr


def knots_and_mults(U):
    """Distinct knot values and their multiplicities, in order (exact comparison)."""
    values, mults = [], []
    for x in U:
        x = float(x)
        if values and x == values[-1]:
            mults[-1] += 1
        else:
            values.append(x)
            mults.append(1)
    return values, mults


def occ_bspline_curve(p, U, P, W=None) -> Geom_BSplineCurve:
    k, m = knots_and_mults(U)
    if W is None:
        return Geom_BSplineCurve(_pnt1(P), _real1(k), _int1(m), int(p), False)
    return Geom_BSplineCurve(_pnt1(P), _real1(W), _real1(k), _int1(m), int(p), False)


def occ_bspline_surface(pu, pv, ku, kv, P, W=None) -> Geom_BSplineSurface:
    uk, um = knots_and_mults(ku)
    vk, vm = knots_and_mults(kv)
    args = (_real1(uk), _real1(vk), _int1(um), _int1(vm), int(pu), int(pv), False, False)
    if W is None:
        return Geom_BSplineSurface(_pnt2(P), *args)
    return Geom_BSplineSurface(_pnt2(P), _real2(W), *args)


def occ_bezier_curve(P, W=None) -> Geom_BezierCurve:
    return Geom_BezierCurve(_pnt1(P)) if W is None else Geom_BezierCurve(_pnt1(P), _real1(W))


def occ_bezier_surface(P, W=None) -> Geom_BezierSurface:
    return Geom_BezierSurface(_pnt2(P)) if W is None else Geom_BezierSurface(_pnt2(P), _real2(W))


def _xyz(v) -> np.ndarray:
    return np.array([v.X(), v.Y(), v.Z()])


def _flat_knots(knot, mult, count) -> np.ndarray:
    return np.repeat([knot(i) for i in range(1, count + 1)], [mult(i) for i in range(1, count + 1)])


def read_occ_curve(h) -> dict:
    """Degree, full knot vector, poles and weights (1 if non-rational) of an OCC curve."""
    n = h.NbPoles()
    out = {
        "degree": h.Degree(),
        "points": np.array([_xyz(h.Pole(i)) for i in range(1, n + 1)]),
        "weights": np.array([h.Weight(i) for i in range(1, n + 1)]),
        "rational": bool(h.IsRational()),
    }
    if isinstance(h, Geom_BSplineCurve):
        out["knots"] = _flat_knots(h.Knot, h.Multiplicity, h.NbKnots())
    return out


def read_occ_surface(h) -> dict:
    nu, nv = h.NbUPoles(), h.NbVPoles()
    out = {
        "degrees": (h.UDegree(), h.VDegree()),
        "points": np.array([[_xyz(h.Pole(i, j)) for j in range(1, nv + 1)] for i in range(1, nu + 1)]),
        "weights": np.array([[h.Weight(i, j) for j in range(1, nv + 1)] for i in range(1, nu + 1)]),
        "rational": bool(h.IsURational() or h.IsVRational()),
    }
    if isinstance(h, Geom_BSplineSurface):
        out["knots_u"] = _flat_knots(h.UKnot, h.UMultiplicity, h.NbUKnots())
        out["knots_v"] = _flat_knots(h.VKnot, h.VMultiplicity, h.NbVKnots())
    return out


def occ_knot_index(knot, count, value) -> int:
    """1-based index of the distinct knot equal to ``value``."""
    hits = [i for i in range(1, count + 1) if knot(i) == value]
    assert len(hits) == 1, f"knot {value!r} not found exactly once in the OCC knot sequence"
    return hits[0]


# ----------------------------------------------------------------------------------------
# splinekit construction and comparison helpers
# ----------------------------------------------------------------------------------------
def sk_curve(p, U, P, W=None):
    return sk.BSplineCurve(p, U, P) if W is None else sk.NurbsCurve(p, U, P, W)


def sk_surface(pu, pv, ku, kv, P, W=None):
    return sk.BSplineSurface(pu, pv, ku, kv, P) if W is None else sk.NurbsSurface(pu, pv, ku, kv, P, W)


def net_size(P) -> float:
    return max(1.0, float(np.abs(P).max()))


def describe(**arrays) -> str:
    """Full-precision dump of a case, for reproducing a failure by hand."""
    with np.printoptions(precision=17, threshold=100_000, linewidth=200):
        return "\n".join(f"  {k} = {v!r}" for k, v in arrays.items())


def assert_close(actual, expected, atol, what, case=""):
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != OCC {expected.shape}\n{case}"
    if actual.size == 0:
        return
    err = np.abs(actual - expected)
    worst = np.unravel_index(int(np.argmax(err)), err.shape)
    assert err[worst] <= atol, (
        f"{what}: |splinekit - OCC| = {err[worst]:.3e} > {atol:.3e} at index {worst}: "
        f"splinekit {actual[worst]!r}, OCC {expected[worst]!r}\n{case}"
    )

def assert_round_trip_points(back, P, W, net, case):
    """Control points (and weights, or their absence) survived a trip through OCC."""
    assert_close(back.control_points, P, ROUND_TRIP_TOL * net, "round-trip control points", case)
    if W is not None:
        assert_close(back.weights, W, ROUND_TRIP_TOL * W.max(), "round-trip weights", case)
    else:
        assert back.weights is None, case



def assert_curve_matches(ours, occ: dict, net: float, case: str, what: str):
    """Same degree, knot vector, control points and weights as read back from OCC."""
    assert ours.degree == occ["degree"], f"{what}: degree {ours.degree} != OCC {occ['degree']}\n{case}"
    assert ours.is_rational == occ["rational"], f"{what}: rational flag differs from OCC\n{case}"
    knots = ours.knots
    assert knots.shape == occ["knots"].shape, f"{what}: knots {knots!r} vs OCC {occ['knots']!r}\n{case}"
    assert_close(knots, occ["knots"], KNOT_TOL * (knots[-1] - knots[0]), f"{what}: knots", case)
    assert_close(ours.control_points, occ["points"], RTOL * net, f"{what}: control points", case)
    if ours.is_rational:
        assert_close(ours.weights, occ["weights"], RTOL * occ["weights"].max(), f"{what}: weights", case)


def assert_surface_matches(ours, occ: dict, net: float, case: str, what: str):
    degrees = (ours.degree_u, ours.degree_v)
    assert degrees == occ["degrees"], f"{what}: degrees {degrees} != OCC {occ['degrees']}\n{case}"
    assert ours.is_rational == occ["rational"], f"{what}: rational flag differs from OCC\n{case}"
    for name, knots in (("knots_u", ours.knots_u), ("knots_v", ours.knots_v)):
        ref = occ[name]
        assert knots.shape == ref.shape, f"{what}: {name} {knots!r} vs OCC {ref!r}\n{case}"
        assert_close(knots, ref, KNOT_TOL * (knots[-1] - knots[0]), f"{what}: {name}", case)
    assert_close(ours.control_points, occ["points"], RTOL * net, f"{what}: control points", case)
    if ours.is_rational:
        assert_close(ours.weights, occ["weights"], RTOL * occ["weights"].max(), f"{what}: weights", case)


def assert_derivative_close(ours, ref, net, what, case):
    """Compare one derivative order over all samples, relative to its scale (module docstring)."""
    scale = max(1.0, net, float(np.abs(ref).max()))
    assert_close(ours, ref, RTOL * scale, f"{what} (scale {scale:.3g})", case)


def occ_curve_ders(h, us):
    """OCC's D3 output ``(4, m, 3)`` and DN for orders 1..3 ``(3, m, 3)``."""
    d3, dn = [], []
    for u in us:
        P, V1, V2, V3 = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec()
        h.D3(float(u), P, V1, V2, V3)
        d3.append([_xyz(P), _xyz(V1), _xyz(V2), _xyz(V3)])
        dn.append([_xyz(h.DN(float(u), k)) for k in (1, 2, 3)])
    return np.array(d3).transpose(1, 0, 2), np.array(dn).transpose(1, 0, 2)


def occ_surface_ders(h, us, vs):
    """``(ref, d2, d3)``: DN for every (k, l) with k, l <= 2 as a ``(3, 3, m, 3)`` array
    ([0, 0] from Value), and the D2 / D3 outputs keyed by their (k, l)."""
    m = len(us)
    ref = np.zeros((3, 3, m, 3))
    d2 = {key: np.zeros((m, 3)) for key in ((0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1))}
    d3 = {key: np.zeros((m, 3)) for key in ((3, 0), (0, 3), (2, 1), (1, 2))}
    for i, (u, v) in enumerate(zip(us, vs)):
        u, v = float(u), float(v)
        ref[0, 0, i] = _xyz(h.Value(u, v))
        for k in range(3):
            for l in range(3):
                if k + l:
                    ref[k, l, i] = _xyz(h.DN(u, v, k, l))
        P, Su, Sv, Suu, Svv, Suv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
        h.D2(u, v, P, Su, Sv, Suu, Svv, Suv)
        for key, val in zip(((0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1)), (P, Su, Sv, Suu, Svv, Suv)):
            d2[key][i] = _xyz(val)
        vecs = [gp_Vec() for _ in range(9)]
        h.D3(u, v, gp_Pnt(), *vecs)
        # D3 fills D1U, D1V, D2U, D2V, D2UV, D3U, D3V, D3UUV, D3UVV
        for key, val in zip(((3, 0), (0, 3), (2, 1), (1, 2)), vecs[5:]):
            d3[key][i] = _xyz(val)
    return ref, d2, d3


def surface_params(rng, ku, kv, pu, pv, count):
    """Random (u, v) pairs, the four corners, and points on every knot line."""
    (a, b), (c, d) = (ku[pu], ku[-pu - 1]), (kv[pv], kv[-pv - 1])
    us = [a, a, b, b] + list(rng.uniform(a, b, count))
    vs = [c, d, c, d] + list(rng.uniform(c, d, count))
    for x in np.unique(ku):
        us.append(x)
        vs.append(rng.uniform(c, d))
    for y in np.unique(kv):
        us.append(rng.uniform(a, b))
        vs.append(y)
    for x, y in zip(np.unique(ku), rng.permutation(np.unique(kv))):  # knot x knot crossings
        us.append(x)
        vs.append(y)
    return np.array(us), np.array(vs)


def curve_case(seed, salt, p, U, P, W, **more):
    return f"reproduce with default_rng([{salt}, {seed}, {int(W is not None)}]):\n" + describe(
        degree=p, knots=U, control_points=P, weights=W, **more
    )


def surface_case(seed, salt, pu, pv, ku, kv, P, W, **more):
    return f"reproduce with default_rng([{salt}, {seed}, {int(W is not None)}]):\n" + describe(
        degree_u=pu, degree_v=pv, knots_u=ku, knots_v=kv, control_points=P, weights=W, **more
    )


# Degrees cycle through 1..7 with the seed so that every degree is covered.
def curve_degree(seed: int) -> int:
    return 1 + seed % 7


def surface_degrees(seed: int) -> tuple[int, int]:
    return 1 + seed % 7, 1 + (3 * seed + 2) % 7


# ========================================================================================
# B-spline / NURBS curves
# ========================================================================================
@RATIONAL
@pytest.mark.parametrize("seed", range(21))
def test_curve_round_trip(seed, rational):
    rng = make_rng(SALT_CURVE_ROUND_TRIP, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_ROUND_TRIP, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    net = net_size(P)
    own = read_occ_curve(occ_bspline_curve(p, U, P, W))

    handle = sk.occ.to_occ(curve)
    assert isinstance(handle, Geom_BSplineCurve)
    theirs = read_occ_curve(handle)
    # to_occ builds what the direct construction builds (rational control points pass
    # through splinekit's homogeneous form (w P, w), so they may differ by an ulp)
    assert theirs["degree"] == own["degree"] == p and theirs["rational"] == own["rational"] == rational, case
    assert np.array_equal(theirs["knots"], own["knots"]), case
    assert np.array_equal(theirs["weights"], own["weights"]), case
    assert_close(theirs["points"], own["points"], ROUND_TRIP_TOL * net, "to_occ poles", case)
    assert np.array_equal(own["knots"], U), case
    assert_close(own["points"], P, 0.0, "OCC poles", case)

    for back in (sk.occ.from_occ(handle), sk.occ.from_occ(occ_bspline_curve(p, U, P, W))):
        assert type(back) is type(curve), case
        assert back.degree == p, case
        assert back.knots.shape == U.shape, case
        assert_close(back.knots, U, ROUND_TRIP_TOL * (U[-1] - U[0]), "round-trip knots", case)
        assert_round_trip_points(back, P, W, net, case)
        assert back.almost_equal(curve, ROUND_TRIP_TOL * net), case


@RATIONAL
@pytest.mark.parametrize("seed", range(35))
def test_curve_points_and_derivatives(seed, rational):
    rng = make_rng(SALT_CURVE_EVAL, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_EVAL, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    h = occ_bspline_curve(p, U, P, W)
    net = net_size(P)
    # Random parameters, the domain ends, and every knot. At an interior knot where a
    # derivative jumps, both OCC (documented for DN) and splinekit take the piece to the
    # right; at the end of the domain both take the last piece.
    us = np.concatenate([interior_params(rng, U, p, 12), np.unique(U)])
    ours = curve.derivatives(us, 3)
    d3, dn = occ_curve_ders(h, us)
    values = np.array([_xyz(h.Value(float(u))) for u in us])
    assert_derivative_close(curve.evaluate(us), values, net, "evaluate vs Value", case + describe(params=us))
    for k in range(4):
        assert_derivative_close(ours[k], d3[k], net, f"derivative {k} vs D3", case + describe(params=us))
        if k:
            assert_derivative_close(ours[k], dn[k - 1], net, f"derivative {k} vs DN", case + describe(params=us))


@RATIONAL
@pytest.mark.parametrize("seed", range(28))
def test_curve_insert_knot(seed, rational):
    rng = make_rng(SALT_CURVE_INSERT, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_INSERT, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    net = net_size(P)
    a, b = U[p], U[-p - 1]

    inserts = [(float(rng.uniform(a, b)), 1), (float(rng.uniform(a, b)), int(rng.integers(1, p + 1)))]
    inner, mult = np.unique(U[p + 1 : -p - 1], return_counts=True)
    raisable = inner[mult < p]
    if raisable.size:  # an existing interior knot, raised by up to its headroom
        k = float(rng.choice(raisable))
        have = int(np.count_nonzero(U == k))
        inserts.append((k, int(rng.integers(1, p - have + 1))))
    for u, times in inserts:
        h = occ_bspline_curve(p, U, P, W)
        h.InsertKnot(u, times, 0.0, True)  # Add=True: multiplicity grows by `times`
        what = f"insert_knot({u!r}, times={times})"
        assert_curve_matches(curve.insert_knot(u, times), read_occ_curve(h), net, case, what)

    # several knots at once (refinement) against OCC's InsertKnots
    values = np.sort(rng.uniform(a, b, int(rng.integers(1, 4))))
    mults = [int(rng.integers(1, p + 1)) for _ in values]
    extra = np.repeat(values, mults)
    h = occ_bspline_curve(p, U, P, W)
    h.InsertKnots(_real1(values), _int1(mults), 0.0, True)
    assert_curve_matches(curve.refine(extra), read_occ_curve(h), net, case, f"refine({extra!r})")


@RATIONAL
@pytest.mark.parametrize("seed", range(28))
def test_curve_elevate_degree(seed, rational):
    rng = make_rng(SALT_CURVE_ELEVATE, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_ELEVATE, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    by = 1 + seed % 3
    h = occ_bspline_curve(p, U, P, W)
    # OCC keeps the knot values and raises every multiplicity (ends included) by `by`,
    # which is what splinekit does too: same continuity at every knot.
    h.IncreaseDegree(p + by)
    assert_curve_matches(curve.elevate_degree(by), read_occ_curve(h), net_size(P), case, f"elevate_degree({by})")


@RATIONAL
@pytest.mark.parametrize("seed", range(28))
def test_curve_remove_knot(seed, rational):
    rng = make_rng(SALT_CURVE_REMOVE, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_REMOVE, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    net = net_size(P)
    # Absolute tolerance in model units for both kernels, scaled with the net. The
    # removals below undo an insertion, so both must succeed to rounding.
    tol = RTOL * net

    # 1) a new knot inserted `times` times, then `remove` of them removed again
    u = middle_of_widest_span(rng, U)
    times = int(rng.integers(1, p + 1))
    remove = int(rng.integers(1, times + 1))
    h = occ_bspline_curve(p, U, P, W)
    h.InsertKnot(u, times, 0.0, True)
    idx = occ_knot_index(h.Knot, h.NbKnots(), u)
    # OCC's RemoveKnot(Index, M, Tol) sets the multiplicity TO M (M = 0 removes the knot)
    assert h.RemoveKnot(idx, times - remove, tol), f"OCC refused to remove {u!r}\n{case}"
    ours = curve.insert_knot(u, times).remove_knot(u, remove, tol=tol)
    what = f"insert_knot({u!r}, {times}).remove_knot({u!r}, {remove})"
    assert_curve_matches(ours, read_occ_curve(h), net, case, what)
    if remove == times:  # back to the original curve
        assert ours.knots.shape == U.shape, case
        assert_close(ours.control_points, P, RTOL * net, what + " vs original", case)

    # 2) an existing interior knot raised, then lowered back to its multiplicity
    inner, mult = np.unique(U[p + 1 : -p - 1], return_counts=True)
    raisable = inner[mult < p]
    if raisable.size:
        k = float(rng.choice(raisable))
        have = int(np.count_nonzero(U == k))
        extra = int(rng.integers(1, p - have + 1))
        h = occ_bspline_curve(p, U, P, W)
        h.InsertKnot(k, extra, 0.0, True)
        idx = occ_knot_index(h.Knot, h.NbKnots(), k)
        assert h.RemoveKnot(idx, have, tol), f"OCC refused to lower knot {k!r} back to multiplicity {have}\n{case}"
        ours = curve.insert_knot(k, extra).remove_knot(k, extra, tol=tol)
        what = f"insert_knot({k!r}, {extra}).remove_knot({k!r}, {extra})"
        assert_curve_matches(ours, read_occ_curve(h), net, case, what)

    # 3) an original interior knot of random geometry is not removable: both refuse
    if inner.size:
        k = float(rng.choice(inner))
        have = int(np.count_nonzero(U == k))
        h = occ_bspline_curve(p, U, P, W)
        idx = occ_knot_index(h.Knot, h.NbKnots(), k)
        occ_removed = h.RemoveKnot(idx, have - 1, tol)
        with pytest.raises(KnotRemovalError):
            curve.remove_knot(k, 1, tol=tol)
        assert not occ_removed, f"OCC removed knot {k!r} that splinekit refused\n{case}"


@RATIONAL
@pytest.mark.parametrize("seed", range(21))
def test_curve_bezier_decomposition(seed, rational):
    rng = make_rng(SALT_CURVE_BEZIER, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_CURVE_BEZIER, p, U, P, W)
    net = net_size(P)
    ours = sk_curve(p, U, P, W).to_bezier()
    conv = GeomConvert_BSplineCurveToBezierCurve(occ_bspline_curve(p, U, P, W))
    assert conv.NbArcs() == len(ours) == np.unique(U).size - 1, case
    for i, seg in enumerate(ours):
        arc = read_occ_curve(conv.Arc(i + 1))
        assert seg.degree == arc["degree"] == p, case
        assert seg.is_rational == arc["rational"], case
        assert_close(seg.control_points, arc["points"], RTOL * net, f"arc {i} poles", case)
        if rational:
            assert_close(seg.weights, arc["weights"], RTOL * arc["weights"].max(), f"arc {i} weights", case)


# ========================================================================================
# B-spline / NURBS surfaces
# ========================================================================================
@RATIONAL
@pytest.mark.parametrize("seed", range(14))
def test_surface_round_trip(seed, rational):
    rng = make_rng(SALT_SURF_ROUND_TRIP, seed, rational)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_ROUND_TRIP, pu, pv, ku, kv, P, W)
    surf = sk_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    own = read_occ_surface(occ_bspline_surface(pu, pv, ku, kv, P, W))

    handle = sk.occ.to_occ(surf)
    assert isinstance(handle, Geom_BSplineSurface)
    theirs = read_occ_surface(handle)
    assert theirs["degrees"] == own["degrees"] == (pu, pv), case
    assert theirs["rational"] == own["rational"] == rational, case
    for key in ("knots_u", "knots_v", "weights"):
        assert np.array_equal(theirs[key], own[key]), f"to_occ {key} differ from the direct construction\n{case}"
    assert_close(theirs["points"], own["points"], ROUND_TRIP_TOL * net, "to_occ poles", case)

    for back in (sk.occ.from_occ(handle), sk.occ.from_occ(occ_bspline_surface(pu, pv, ku, kv, P, W))):
        assert type(back) is type(surf), case
        assert (back.degree_u, back.degree_v) == (pu, pv), case
        assert back.knots_u.shape == ku.shape and back.knots_v.shape == kv.shape, case
        assert_close(back.knots_u, ku, ROUND_TRIP_TOL * (ku[-1] - ku[0]), "round-trip knots_u", case)
        assert_close(back.knots_v, kv, ROUND_TRIP_TOL * (kv[-1] - kv[0]), "round-trip knots_v", case)
        assert_round_trip_points(back, P, W, net, case)


@RATIONAL
@pytest.mark.parametrize("seed", range(21))
def test_surface_points_and_derivatives(seed, rational):
    rng = make_rng(SALT_SURF_EVAL, seed, rational)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_EVAL, pu, pv, ku, kv, P, W)
    surf = sk_surface(pu, pv, ku, kv, P, W)
    h = occ_bspline_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    us, vs = surface_params(rng, ku, kv, pu, pv, 10)
    case += describe(u=us, v=vs)
    ours = surf.derivatives(us, vs, 3)
    ref, d2, d3 = occ_surface_ders(h, us, vs)

    assert_derivative_close(surf.evaluate(us, vs), ref[0, 0], net, "evaluate vs Value", case)
    for k in range(3):
        for l in range(3):
            what = f"d^{k + l}S/du^{k}dv^{l} vs " + ("Value" if k + l == 0 else f"DN(u, v, {k}, {l})")
            assert_derivative_close(ours[k, l], ref[k, l], net, what, case)
    for (k, l), val in (*d2.items(), *d3.items()):
        what = f"d^{k + l}S/du^{k}dv^{l} vs D{'2' if k + l <= 2 else '3'}"
        assert_derivative_close(ours[k, l], val, net, what, case)

    # evaluate_grid against point-wise OCC values
    gu = interior_params(rng, ku, pu, 3)
    gv = interior_params(rng, kv, pv, 4)
    grid = np.array([[_xyz(h.Value(float(x), float(y))) for y in gv] for x in gu])
    assert_derivative_close(surf.evaluate_grid(gu, gv), grid, net, "evaluate_grid vs Value", case)


@DIRECTION
@RATIONAL
@pytest.mark.parametrize("seed", range(14))
def test_surface_insert_knot(seed, rational, direction):
    rng = make_rng(SALT_SURF_INSERT, seed, rational, ord(direction))
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_INSERT, pu, pv, ku, kv, P, W) + f"\n  (extra rng key {ord(direction)})"
    surf = sk_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    p, U = (pu, ku) if direction == "u" else (pv, kv)
    a, b = U[p], U[-p - 1]

    def occ_insert(u, times):
        h = occ_bspline_surface(pu, pv, ku, kv, P, W)
        if direction == "u":
            h.InsertUKnot(u, times, 0.0, True)  # Add=True: multiplicity grows by `times`
        else:
            h.InsertVKnot(u, times, 0.0, True)
        return read_occ_surface(h)

    inserts = [(float(rng.uniform(a, b)), 1), (float(rng.uniform(a, b)), int(rng.integers(1, p + 1)))]
    inner, mult = np.unique(U[p + 1 : -p - 1], return_counts=True)
    raisable = inner[mult < p]
    if raisable.size:
        k = float(rng.choice(raisable))
        have = int(np.count_nonzero(U == k))
        inserts.append((k, int(rng.integers(1, p - have + 1))))
    for u, times in inserts:
        what = f"insert_knot({u!r}, times={times}, direction={direction!r})"
        assert_surface_matches(surf.insert_knot(u, times, direction=direction), occ_insert(u, times), net, case, what)

    # refinement against InsertUKnots / InsertVKnots
    values = np.sort(rng.uniform(a, b, int(rng.integers(1, 4))))
    mults = [int(rng.integers(1, p + 1)) for _ in values]
    h = occ_bspline_surface(pu, pv, ku, kv, P, W)
    (h.InsertUKnots if direction == "u" else h.InsertVKnots)(_real1(values), _int1(mults), 0.0, True)
    extra = np.repeat(values, mults)
    what = f"refine({extra!r}, direction={direction!r})"
    assert_surface_matches(surf.refine(extra, direction), read_occ_surface(h), net, case, what)


@RATIONAL
@pytest.mark.parametrize("seed", range(14))
def test_surface_elevate_degree(seed, rational):
    rng = make_rng(SALT_SURF_ELEVATE, seed, rational)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_ELEVATE, pu, pv, ku, kv, P, W)
    surf = sk_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    bu, bv = int(rng.integers(0, 3)), int(rng.integers(0, 3))
    for du, dv in ((bu, 0), (0, max(bv, 1)), (max(bu, 1), bv)):
        h = occ_bspline_surface(pu, pv, ku, kv, P, W)
        h.IncreaseDegree(pu + du, pv + dv)  # as for curves: knots kept, multiplicities + by
        ours = surf.elevate_degree(du, direction="u").elevate_degree(dv, direction="v")
        what = f"elevate_degree u by {du}, v by {dv}"
        assert_surface_matches(ours, read_occ_surface(h), net, case, what)


@DIRECTION
@RATIONAL
@pytest.mark.parametrize("seed", range(14))
def test_surface_remove_knot(seed, rational, direction):
    rng = make_rng(SALT_SURF_REMOVE, seed, rational, ord(direction))
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_REMOVE, pu, pv, ku, kv, P, W) + f"\n  (extra rng key {ord(direction)})"
    surf = sk_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    tol = RTOL * net
    p, U = (pu, ku) if direction == "u" else (pv, kv)

    def occ_handle():
        h = occ_bspline_surface(pu, pv, ku, kv, P, W)
        if direction == "u":
            return h, h.InsertUKnot, h.RemoveUKnot, h.UKnot, h.NbUKnots
        return h, h.InsertVKnot, h.RemoveVKnot, h.VKnot, h.NbVKnots

    # a new knot inserted and (partly) removed again; RemoveUKnot(Index, M, Tol) sets
    # the multiplicity TO M
    u = middle_of_widest_span(rng, U)
    times = int(rng.integers(1, p + 1))
    remove = int(rng.integers(1, times + 1))
    h, insert, remove_occ, knot, nb = occ_handle()
    insert(u, times, 0.0, True)
    assert remove_occ(occ_knot_index(knot, nb(), u), times - remove, tol), f"OCC refused to remove {u!r}\n{case}"
    ours = surf.insert_knot(u, times, direction=direction).remove_knot(u, remove, tol=tol, direction=direction)
    what = f"insert_knot({u!r}, {times}).remove_knot({u!r}, {remove}), direction {direction!r}"
    assert_surface_matches(ours, read_occ_surface(h), net, case, what)
    if remove == times:
        assert_close(ours.control_points, P, RTOL * net, what + " vs original", case)

    # an existing interior knot raised, then lowered back
    inner, mult = np.unique(U[p + 1 : -p - 1], return_counts=True)
    raisable = inner[mult < p]
    if raisable.size:
        k = float(rng.choice(raisable))
        have = int(np.count_nonzero(U == k))
        extra = int(rng.integers(1, p - have + 1))
        h, insert, remove_occ, knot, nb = occ_handle()
        insert(k, extra, 0.0, True)
        assert remove_occ(occ_knot_index(knot, nb(), k), have, tol), f"OCC refused to lower {k!r}\n{case}"
        ours = surf.insert_knot(k, extra, direction=direction).remove_knot(k, extra, tol=tol, direction=direction)
        what = f"insert_knot({k!r}, {extra}).remove_knot({k!r}, {extra}), direction {direction!r}"
        assert_surface_matches(ours, read_occ_surface(h), net, case, what)

    # an original knot of random geometry: both refuse
    if inner.size:
        k = float(rng.choice(inner))
        have = int(np.count_nonzero(U == k))
        h, _, remove_occ, knot, nb = occ_handle()
        occ_removed = remove_occ(occ_knot_index(knot, nb(), k), have - 1, tol)
        with pytest.raises(KnotRemovalError):
            surf.remove_knot(k, 1, tol=tol, direction=direction)
        assert not occ_removed, f"OCC removed knot {k!r} that splinekit refused\n{case}"


@RATIONAL
@pytest.mark.parametrize("seed", range(10))
def test_surface_bezier_decomposition(seed, rational):
    rng = make_rng(SALT_SURF_BEZIER, seed, rational)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_SURF_BEZIER, pu, pv, ku, kv, P, W)
    net = net_size(P)
    ours = sk_surface(pu, pv, ku, kv, P, W).to_bezier()
    conv = GeomConvert_BSplineSurfaceToBezierSurface(occ_bspline_surface(pu, pv, ku, kv, P, W))
    shape = (np.unique(ku).size - 1, np.unique(kv).size - 1)
    assert (conv.NbUPatches(), conv.NbVPatches()) == (len(ours), len(ours[0])) == shape, case
    for i in range(shape[0]):
        for j in range(shape[1]):
            patch = read_occ_surface(conv.Patch(i + 1, j + 1))
            seg = ours[i][j]
            assert (seg.degree_u, seg.degree_v) == patch["degrees"] == (pu, pv), case
            assert seg.is_rational == patch["rational"], case
            assert_close(seg.control_points, patch["points"], RTOL * net, f"patch ({i}, {j}) poles", case)
            if rational:
                assert_close(seg.weights, patch["weights"], RTOL * patch["weights"].max(), f"patch ({i}, {j}) weights", case)


# ========================================================================================
# Bézier curves and surfaces
# ========================================================================================
@RATIONAL
@pytest.mark.parametrize("seed", range(21))
def test_bezier_curve(seed, rational):
    rng = make_rng(SALT_BEZIER_CURVE, seed, rational)
    p = curve_degree(seed)
    P = random_points(rng, (p + 1,))
    W = random_weights(rng, p + 1) if rational else None
    case = f"reproduce with default_rng([{SALT_BEZIER_CURVE}, {seed}, {int(rational)}]):\n" + describe(
        control_points=P, weights=W
    )
    net = net_size(P)
    bez = sk.BezierCurve(P, W)
    h = occ_bezier_curve(P, W)

    # round trip through to_occ / from_occ
    handle = sk.occ.to_occ(bez)
    assert isinstance(handle, Geom_BezierCurve)
    own, theirs = read_occ_curve(h), read_occ_curve(handle)
    assert np.array_equal(own["weights"], theirs["weights"]), case
    assert_close(theirs["points"], own["points"], ROUND_TRIP_TOL * net, "to_occ poles", case)
    assert own["rational"] == theirs["rational"] == rational, case
    for back in (sk.occ.from_occ(handle), sk.occ.from_occ(h)):
        assert isinstance(back, sk.BezierCurve) and back.degree == p, case
        assert_round_trip_points(back, P, W, net, case)

    # points and derivatives on [0, 1]
    ts = np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, 12)])
    ours = bez.derivatives(ts, 3)
    d3, dn = occ_curve_ders(h, ts)
    for k in range(4):
        assert_derivative_close(ours[k], d3[k], net, f"derivative {k} vs D3", case + describe(params=ts))
        if k:
            assert_derivative_close(ours[k], dn[k - 1], net, f"derivative {k} vs DN", case + describe(params=ts))

    # degree elevation against Geom_BezierCurve::Increase
    by = 1 + seed % 3
    h.Increase(p + by)
    up = read_occ_curve(h)
    ours = bez.elevate(by)
    assert ours.degree == up["degree"] == p + by, case
    assert_close(ours.control_points, up["points"], RTOL * net, f"elevate({by}) poles", case)
    if rational:
        assert_close(ours.weights, up["weights"], RTOL * up["weights"].max(), f"elevate({by}) weights", case)


@RATIONAL
@pytest.mark.parametrize("seed", range(14))
def test_bezier_surface(seed, rational):
    rng = make_rng(SALT_BEZIER_SURFACE, seed, rational)
    pu, pv = surface_degrees(seed)
    P = random_points(rng, (pu + 1, pv + 1))
    W = random_weights(rng, (pu + 1, pv + 1)) if rational else None
    case = f"reproduce with default_rng([{SALT_BEZIER_SURFACE}, {seed}, {int(rational)}]):\n" + describe(
        control_points=P, weights=W
    )
    net = net_size(P)
    bez = sk.BezierSurface(P, W)
    h = occ_bezier_surface(P, W)

    handle = sk.occ.to_occ(bez)
    assert isinstance(handle, Geom_BezierSurface)
    own, theirs = read_occ_surface(h), read_occ_surface(handle)
    assert np.array_equal(own["weights"], theirs["weights"]), case
    assert_close(theirs["points"], own["points"], ROUND_TRIP_TOL * net, "to_occ poles", case)
    assert own["rational"] == theirs["rational"] == rational, case
    for back in (sk.occ.from_occ(handle), sk.occ.from_occ(h)):
        assert isinstance(back, sk.BezierSurface) and (back.degree_u, back.degree_v) == (pu, pv), case
        assert_round_trip_points(back, P, W, net, case)

    us = np.concatenate([[0.0, 0.0, 1.0, 1.0], rng.uniform(0.0, 1.0, 10)])
    vs = np.concatenate([[0.0, 1.0, 0.0, 1.0], rng.uniform(0.0, 1.0, 10)])
    case += describe(u=us, v=vs)
    ours = bez.derivatives(us, vs, 3)
    ref, d2, d3 = occ_surface_ders(h, us, vs)
    for k in range(3):
        for l in range(3):
            what = f"d^{k + l}S/du^{k}dv^{l} vs " + ("Value" if k + l == 0 else f"DN(u, v, {k}, {l})")
            assert_derivative_close(ours[k, l], ref[k, l], net, what, case)
    for (k, l), val in (*d2.items(), *d3.items()):
        assert_derivative_close(ours[k, l], val, net, f"d^{k + l}S/du^{k}dv^{l} vs D2/D3", case)

    # degree elevation against Geom_BezierSurface::Increase
    bu, bv = 1 + seed % 2, 1 + (seed // 2) % 3
    h.Increase(pu + bu, pv + bv)
    up = read_occ_surface(h)
    ours = bez.elevate(bu, "u").elevate(bv, "v")
    assert (ours.degree_u, ours.degree_v) == up["degrees"] == (pu + bu, pv + bv), case
    assert_close(ours.control_points, up["points"], RTOL * net, f"elevate({bu}, {bv}) poles", case)
    if rational:
        assert_close(ours.weights, up["weights"], RTOL * up["weights"].max(), f"elevate({bu}, {bv}) weights", case)


# ========================================================================================
# Large batches: evaluation of at least _kernels.MIN_WORK points may take a compiled path
# (numba kernels) instead of numpy; check that path against OCC too, on a subset.
# ========================================================================================
SALT_BATCH_CURVE = 401
SALT_BATCH_SURFACE = 402


def _batch_size() -> int:
    return max(int(_kernels.MIN_WORK), 1000)


@pytest.fixture(autouse=False)
def eager_kernels(monkeypatch):
    """Compiled kernels serve every batch of at least MIN_WORK points (no waiting for LOAD_WORK)."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")


@RATIONAL
@pytest.mark.parametrize("seed", range(7))
def test_curve_large_batch_evaluation(seed, rational, eager_kernels):
    rng = make_rng(SALT_BATCH_CURVE, seed, rational)
    p, U, P, W = random_curve_data(rng, rational, degree=curve_degree(seed))
    case = curve_case(seed, SALT_BATCH_CURVE, p, U, P, W)
    curve = sk_curve(p, U, P, W)
    h = occ_bspline_curve(p, U, P, W)
    us = np.concatenate([np.unique(U), interior_params(rng, U, p, _batch_size())])
    pts = curve.evaluate(us)
    pick = np.concatenate([np.arange(np.unique(U).size + 2), rng.choice(us.size, 300, replace=False)])
    ref = np.array([_xyz(h.Value(float(us[i]))) for i in pick])
    assert_derivative_close(pts[pick], ref, net_size(P), "batch evaluate vs Value", case + describe(params=us[pick]))


@RATIONAL
@pytest.mark.parametrize("seed", range(7))
def test_surface_large_batch_evaluation(seed, rational, eager_kernels):
    rng = make_rng(SALT_BATCH_SURFACE, seed, rational)
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational, surface_degrees(seed))
    case = surface_case(seed, SALT_BATCH_SURFACE, pu, pv, ku, kv, P, W)
    surf = sk_surface(pu, pv, ku, kv, P, W)
    h = occ_bspline_surface(pu, pv, ku, kv, P, W)
    net = net_size(P)
    n = _batch_size()

    # scattered pairs
    us, vs = surface_params(rng, ku, kv, pu, pv, n)
    pts = surf.evaluate(us, vs)
    pick = np.concatenate([np.arange(4), np.arange(n + 4, us.size), rng.choice(us.size, 300, replace=False)])
    ref = np.array([_xyz(h.Value(float(us[i]), float(vs[i]))) for i in pick])
    assert_derivative_close(pts[pick], ref, net, "batch evaluate vs Value", case + describe(u=us[pick], v=vs[pick]))

    # a grid of at least n points, knot lines included
    side = int(np.ceil(np.sqrt(n))) + 1
    gu = np.sort(np.concatenate([np.unique(ku), interior_params(rng, ku, pu, side)]))
    gv = np.sort(np.concatenate([np.unique(kv), interior_params(rng, kv, pv, side)]))
    grid = surf.evaluate_grid(gu, gv)
    iu = np.concatenate([[0, gu.size - 1], rng.integers(0, gu.size, 150)])
    iv = np.concatenate([[0, gv.size - 1], rng.integers(0, gv.size, 150)])
    ref = np.array([_xyz(h.Value(float(gu[i]), float(gv[j]))) for i, j in zip(iu, iv)])
    assert_derivative_close(grid[iu, iv], ref, net, "batch evaluate_grid vs Value", case)
