"""The B-rep tessellator's scattered surface evaluator (tessellation.batch.SurfaceBatch) on both
paths (numpy and the compiled kernel) against the surfaces' own public evaluators, and the
tables of both batch evaluators (built in whole-array passes) against each object's own knots."""

from __future__ import annotations

import numpy as np
import pytest

import splinekit as sk
from splinekit import _kernels
from splinekit.brep import primitives
from splinekit.tessellation.batch import CurveBatch, SurfaceBatch


@pytest.fixture(params=["0", "1"], ids=["numpy", "numba"])
def kernel_path(request, monkeypatch):
    if request.param == "1":
        pytest.importorskip("numba")
        monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
        assert _kernels.load("splinekit.tessellation._batch_kernels") is not None
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    return request.param


def test_points_and_partials_match_the_surfaces_own_evaluators(kernel_path):
    # planes (degree 1), a cylinder (2 x 1), a sphere and a torus (rational 2 x 2), several cells each
    faces = (primitives.torus(2.0, 0.6).faces + primitives.sphere(1.5, center=(1, 2, 3)).faces
             + primitives.box_with_hole(20.0, 4.0).faces)  # fmt: skip
    surfaces = [f.surface for f in faces]
    batch = SurfaceBatch(surfaces)
    rng = np.random.default_rng(5)
    n = 3000
    k = rng.integers(0, len(surfaces), n)
    dom = np.array([[*s.domain[0], *s.domain[1]] for s in surfaces])[k]
    u = dom[:, 0] + (dom[:, 1] - dom[:, 0]) * rng.random(n)
    v = dom[:, 2] + (dom[:, 3] - dom[:, 2]) * rng.random(n)
    u[:50] = dom[:50, 1]  # the domain's far ends (the last cell's closed side)
    v[50:100] = dom[50:100, 3]
    S, Su, Sv = batch.partials(k, u, v)
    assert np.array_equal(batch.evaluate(k, u, v), S)
    for j, s in enumerate(surfaces):
        sel = np.flatnonzero(k == j)
        D = s.derivatives(u[sel], v[sel], 1)
        scale = np.abs(s.control_points).max()
        assert np.allclose(S[sel], D[0, 0], rtol=0, atol=1e-13 * scale)
        assert np.allclose(Su[sel], D[1, 0], rtol=0, atol=1e-11 * scale)
        assert np.allclose(Sv[sel], D[0, 1], rtol=0, atol=1e-11 * scale)


def test_cell_location_is_the_same_on_both_paths(monkeypatch):
    pytest.importorskip("numba")
    faces = primitives.torus(2.0, 0.6).faces + primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4)]).faces
    batch = SurfaceBatch([f.surface for f in faces])
    rng = np.random.default_rng(8)
    n = 2000
    k = rng.integers(0, len(faces), n)
    dom = np.array([[*f.surface.domain[0], *f.surface.domain[1]] for f in faces])[k]
    # inside, on the ends and a little outside the domains (pcurves of CAD files stray)
    u = dom[:, 0] + (dom[:, 1] - dom[:, 0]) * rng.uniform(-0.01, 1.01, n)
    v = dom[:, 2] + (dom[:, 3] - dom[:, 2]) * rng.uniform(-0.01, 1.01, n)
    u[:40], v[40:80] = dom[:40, 1], dom[40:80, 2]
    got = []
    for env in ("0", "1"):
        monkeypatch.setenv("SPLINEKIT_NUMBA", env)
        if env == "1":
            assert _kernels.load("splinekit.tessellation._batch_kernels") is not None
        got.append(batch._cells(k, u, v))
    for a, b in zip(*got):
        assert np.array_equal(a, b)


def _random_spline(rng, degree, pieces, dim, rational, lo=0.0):
    """A clamped spline curve of ``pieces`` spans (random interior knots, some repeated) on ``[lo, lo + 1..3]``."""
    inner = np.sort(rng.uniform(0.05, 0.95, pieces - 1)) if pieces > 1 else np.zeros(0)
    if degree > 1 and inner.size > 1 and rng.random() < 0.5:
        inner[1] = inner[0]  # a repeated knot: one piece fewer
    knots = lo + rng.uniform(1.0, 3.0) * np.concatenate([np.zeros(degree + 1), inner, np.ones(degree + 1)])
    n = len(knots) - degree - 1
    P = rng.normal(size=(n, dim))
    if rational:
        return sk.NurbsCurve(degree, knots, P, rng.uniform(0.5, 2.0, n))
    return sk.BSplineCurve(degree, knots, P)


def test_curve_batch_tables_equal_the_one_curve_at_a_time_route():
    # the breaks, pieces and Bézier segments built in whole-array passes against each curve's own
    # knots and Bézier decomposition (mixed degrees, shared and distinct knot vectors, rational)
    rng = np.random.default_rng(3)
    curves = []
    for _ in range(40):
        p = int(rng.integers(1, 4))
        curves.append(_random_spline(rng, p, int(rng.integers(1, 5)), 2, rng.random() < 0.4, lo=rng.uniform(-2, 2)))
        if rng.random() < 0.3:  # the same knot vector again (grouped)
            c = curves[-1]
            curves.append(sk.BSplineCurve(c.degree, c.knots, rng.normal(size=(len(c.control_points), 2))))
    batch = CurveBatch(curves)
    for k, c in enumerate(curves):
        breaks = np.unique(c.knots[c.degree : len(c.knots) - c.degree])
        p, rows = batch.segments(k)
        assert p == c.degree and batch.breaks.count[k] == len(breaks) - 1 == len(rows)
        j = batch.breaks.start[k] + np.arange(batch.breaks.count[k])
        assert np.array_equal(batch.breaks.a[j], breaks[:-1]) and np.array_equal(batch.breaks.b[j], breaks[1:])
        assert batch.breaks.lo[k] == breaks[0] and batch.breaks.hi[k] == breaks[-1]
        # each row is the Bézier piece of that span: its end points are the curve's
        segs = batch.segs[p][rows]
        ends = np.concatenate([segs[:, 0, :2] / segs[:, 0, 2:], segs[:, -1, :2] / segs[:, -1, 2:]])
        assert np.allclose(ends, c.evaluate(np.concatenate([breaks[:-1], breaks[1:]])), atol=1e-12)
    t = np.concatenate([np.linspace(*c.domain, 7) for c in curves])
    k = np.repeat(np.arange(len(curves)), 7)
    want = np.concatenate([c.evaluate(np.linspace(*c.domain, 7)) for c in curves])
    assert np.allclose(batch.evaluate(k, t), want, atol=1e-12)


def test_surface_batch_breaks_equal_each_surfaces_own_knots():
    faces = primitives.torus(2.0, 0.6).faces + primitives.box_with_hole(20.0, 4.0).faces + primitives.sphere(1.0).faces
    surfaces = [f.surface for f in faces]
    batch = SurfaceBatch(surfaces)
    for k, s in enumerate(surfaces):
        bu, bv = (np.unique(U[p : len(U) - p]) for p, U in ((s.degree_u, s.knots_u), (s.degree_v, s.knots_v)))
        assert np.array_equal(batch.bu[k], bu) and np.array_equal(batch.bv[k], bv)
        assert (batch.lu.lo[k], batch.lu.hi[k], batch.lv.lo[k], batch.lv.hi[k]) == (bu[0], bu[-1], bv[0], bv[-1])
        assert batch.nsu[k] == len(bu) - 1 and batch.nsv[k] == len(bv) - 1
