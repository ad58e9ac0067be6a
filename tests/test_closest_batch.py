"""``splinekit.closest.curve_distances`` (many point sets, each to its own curve, in one batched
search) against ``project`` on each curve alone, and against closed forms (circles, a polyline's
segments)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from splinekit import BSplineCurve
from splinekit.basis.knots import clamped_uniform
from splinekit.closest import batch, curve_distances, project
from splinekit.construct import circle, polyline
from splinekit.errors import ParameterError


def _point_segment_distances(points, a, b):
    """Distances of ``points`` (n, 3) to the segment ``a``-``b`` (closed form)."""
    d = b - a
    t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * d), axis=1)


def test_circles_in_closed_form():
    rng = np.random.default_rng(1)
    radii = [0.5, 2.0, 7.0]
    curves = [circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), r) for r in radii]
    sets = [rng.normal(scale=2 * r, size=(40, 3)) for r in radii]
    got = curve_distances(curves, sets)
    for r, pts, d in zip(radii, sets, got):
        exact = np.hypot(np.hypot(pts[:, 0], pts[:, 1]) - r, pts[:, 2])
        np.testing.assert_allclose(d, exact, rtol=0, atol=1e-9 * max(1.0, r))


def test_polyline_creases_in_closed_form():
    # degree 1: every knot is a crease, so seeds search piece by piece
    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 1], [0, 3, 0]], float)
    rng = np.random.default_rng(2)
    pts = rng.uniform(-1, 3, size=(200, 3))
    [d] = curve_distances([polyline(corners)], [pts])
    exact = np.min([_point_segment_distances(pts, a, b) for a, b in zip(corners[:-1], corners[1:])], axis=0)
    np.testing.assert_allclose(d, exact, rtol=0, atol=1e-12)


def test_random_splines_agree_with_project_on_each(monkeypatch):
    rng = np.random.default_rng(3)
    curves, sets = [], []
    for i in range(12):
        p = 1 + i % 4
        n = p + 1 + rng.integers(0, 6)
        curves.append(BSplineCurve(p, clamped_uniform(p, n), rng.normal(size=(n, 3))))
        sets.append(rng.normal(scale=1.5, size=(int(rng.integers(1, 30)), 3)))
    fallback = []
    with monkeypatch.context() as m:
        m.setattr(batch, "project", lambda curve, pts: fallback.append(curve) or project(curve, pts))
        got = curve_distances(curves, sets)
    # the batched search answers for every smooth curve; only polylines whose seeds stop on a
    # crease with the distance falling across it go through project, which searches on
    assert fallback and all(curve.degree == 1 for curve in fallback)
    for curve, pts, d in zip(curves, sets, got):
        assert d.shape == (len(pts),)
        np.testing.assert_allclose(d, project(curve, pts).distances, rtol=0, atol=1e-9)


def test_huge_curve_goes_through_project_and_empty_sets_are_kept():
    big = circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1e70)
    small = circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0)
    pts = np.array([[2e70, 0.0, 0.0], [0.0, 0.0, 1e70]])
    got = curve_distances([big, small], [pts, np.zeros((0, 3))])
    np.testing.assert_allclose(got[0], [1e70, np.sqrt(2.0) * 1e70], rtol=1e-9)
    assert got[1].shape == (0,)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_a_wrong_point_set_changes_the_answer(scale):
    # the search must read each set against its own curve: swapped sets give other distances
    a, b = circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0 * scale), circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 3.0 * scale)
    pa = np.array([[1.0, 0.0, 0.0]]) * scale
    pb = np.array([[3.0, 0.0, 0.0]]) * scale
    right = curve_distances([a, b], [pa, pb])
    assert max(right[0][0], right[1][0]) <= 1e-9 * scale
    wrong = curve_distances([a, b], [pb, pa])
    assert wrong[0][0] == pytest.approx(2.0 * scale) and wrong[1][0] == pytest.approx(2.0 * scale)


@pytest.mark.parametrize("sets, words", [
    ([np.zeros((2, 3))], "one point set per curve"),
    ([np.zeros((2, 2)), np.zeros((1, 3))], "shape (n, 3)"),
    ([np.array([[0.0, np.nan, 0.0]]), np.zeros((1, 3))], "not finite"),
    ([np.full((1, 3), 1e200), np.zeros((1, 3))], "beyond"),
])
def test_bad_point_sets_raise_naming_the_problem(sets, words):
    curves = [circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0), circle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 2.0)]
    with pytest.raises(ParameterError, match=re.escape(words)):
        curve_distances(curves, sets)
