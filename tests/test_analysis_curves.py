"""Curve analysis (splinekit.analysis.curves) against closed forms: a cubic with its inflection at
t = 1/2, circles without any, a spline through sine samples with inflections at multiples of pi,
combs of circles, G0/G1/G2 where lines and arcs meet."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.analysis import curvature_comb, curve_continuity, inflections
from splinekit.errors import SplineKitError


@settings(max_examples=25, deadline=None)
@given(st.floats(0.2, 3.0), st.floats(0.2, 3.0))
def test_cubic_inflection_closed_form(h0, h1):
    # x = 3 t, so the curvature's sign is y'': 6 [(-h1 - 2 h0)(1 - t) + (2 h1 + h0) t], zero at
    b = sk.BezierCurve([[0, 0], [1, h0], [2, -h1], [3, 0]])
    expected = (12 * h0 + 6 * h1) / (18 * (h0 + h1))
    assert np.allclose(inflections(b), [expected], atol=1e-12)
    # the same curve in 3-D, tilted out of every coordinate plane, and as a rational curve
    R = np.linalg.qr(np.array([[1.0, 2.0, 0.5], [0.3, -1.0, 2.0], [1.5, 0.2, -0.7]]))[0]
    P3 = np.column_stack([b.control_points, np.zeros(4)]) @ R.T + [1.0, -2.0, 3.0]
    assert np.allclose(inflections(sk.BezierCurve(P3)), [expected], atol=1e-10)
    rational = sk.NurbsCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], b.control_points, [1.0, 1.0, 1.0, 1.0])
    assert np.allclose(inflections(rational), [expected], atol=1e-12)


def test_rational_cubic_inflection_against_dense_signed_curvature():
    c = sk.NurbsCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], [[0, 0], [1, 2], [2, -2], [3, 0]], [1.0, 3.0, 0.5, 1.0])
    roots = inflections(c)
    u = np.linspace(0, 1, 200001)
    k = sk.diffgeom.curves.signed_curvature(c, u)
    changes = u[:-1][np.sign(k[:-1]) != np.sign(k[1:])]
    assert roots.size == changes.size == 1 and abs(roots[0] - changes[0]) < 1e-5


def test_circles_and_convex_curves_have_none():
    assert inflections(sk.circle([0, 0], None, 2.0)).size == 0
    assert inflections(sk.circle([0, 0, 0], [1, 1, 1], 0.5)).size == 0
    assert inflections(sk.arc([0, 0], None, 1.0, 0.0, 3.0)).size == 0
    assert inflections(sk.line([0, 0], [1, 1])).size == 0  # straight: no isolated sign change


def test_sine_like_spline_inflects_near_multiples_of_pi():
    x = np.linspace(0, 4 * np.pi, 81)
    c = sk.interpolate_curve(np.column_stack([x, np.sin(x)]))
    r = c.evaluate(inflections(c))[:, 0] / np.pi
    inner = r[(r > 0.5) & (r < 3.5)]
    assert np.allclose(inner, [1.0, 2.0, 3.0], atol=1e-4)


def test_s_curve_of_two_arcs_inflects_at_the_knot():
    # two quarter circles joined tangentially with opposite turns: curvature +1 then -1
    a = sk.arc([0, 1], None, 1.0, -np.pi / 2, 0.0)           # counter-clockwise from (0, 0) to (1, 1)
    b = sk.arc([2, 1], None, 1.0, np.pi, np.pi / 2).reverse()  # ends at (1, 1) ... joined below
    pts = np.concatenate([a.control_points, b.reverse().control_points[1:]])
    w = np.concatenate([a.weights, b.reverse().weights[1:]])
    s = sk.NurbsCurve(2, [0, 0, 0, 0.5, 0.5, 1, 1, 1], pts, w)
    assert np.allclose(s.evaluate(np.array([0.5])), [[1.0, 1.0]])
    assert np.allclose(inflections(s), [0.5])


def test_comb_of_a_circle_points_outward_with_the_default_length():
    r = 2.0
    comb = curvature_comb(sk.circle([1.0, -1.0], None, r), samples=17)
    assert np.allclose(comb.curvature, 1.0 / r)
    outward = comb.points - [1.0, -1.0]
    assert np.allclose(np.einsum("ij,ij->i", comb.comb, outward / r), 0.2 * np.hypot(2 * r, 2 * r))
    assert np.allclose(comb.tips, comb.points + comb.comb)
    assert curvature_comb(sk.circle([0, 0], None, r), samples=5, scale=3.0).comb[0] @ [1, 0] == pytest.approx(1.5)


def test_comb_flips_side_at_the_inflection():
    b = sk.BezierCurve([[0, 0], [1, 1], [2, -1], [3, 0]])
    comb = curvature_comb(b, samples=11)
    side = comb.comb[:, 1]
    assert (side[:5] > 0).all() and (side[6:] < 0).all() and abs(side[5]) < 1e-12


def test_curve_continuity_levels():
    line = sk.line([0, 0], [1, 0])
    arc = sk.arc([1, 1], None, 1.0, -np.pi / 2, 0.0)  # leaves (1, 0) along +x, radius 1
    g1 = curve_continuity(line, arc)
    assert g1.level == "G1" and g1.ends == ("end", "start")
    assert g1.gap == 0 and g1.angle < 1e-15 and g1.curvature_jump == pytest.approx(1.0, rel=1e-12)
    # either curve reversed: the same joint
    assert curve_continuity(arc.reverse(), line.reverse()).level == "G1"
    assert curve_continuity(line, arc.reverse()).ends == ("end", "end")
    # one circle split: G2; two radii: G1 with the known jump
    left, right = sk.circle([0, 0], None, 1.5).split(0.3)
    assert curve_continuity(left, right).level == "G2"
    other = sk.arc([1, 2], None, 2.0, -np.pi / 2, 0.0)
    assert curve_continuity(line, other).curvature_jump == pytest.approx(0.5, rel=1e-12)
    kink = curve_continuity(line, sk.line([1, 0], [2, 1]))
    assert kink.level == "G0" and kink.angle == pytest.approx(np.pi / 4, abs=1e-15)
    assert curve_continuity(line, sk.line([1, 1e-3], [2, 0])).level == "none"


def test_bad_curves():
    with pytest.raises(SplineKitError, match="curve"):
        curvature_comb(3.0)
    with pytest.raises(SplineKitError, match="samples"):
        curvature_comb(sk.line([0, 0], [1, 0]), samples=1)
    with pytest.raises(SplineKitError, match="dimension"):
        curve_continuity(sk.line([0, 0], [1, 0]), sk.line([1, 0, 0], [2, 0, 0]))
    with pytest.raises(SplineKitError, match="dim"):
        inflections(sk.line([0, 0, 0, 0], [1, 1, 1, 1]))
    with pytest.raises(SplineKitError, match="scale"):
        curvature_comb(sk.line([0, 0], [1, 0]), scale=-1)
