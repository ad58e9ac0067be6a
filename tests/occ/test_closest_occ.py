"""Closest points (splinekit.closest) against OpenCascade's point projection
(GeomAPI_ProjectPointOnCurve / GeomAPI_ProjectPointOnSurf): never farther than OCC.
"""

from __future__ import annotations

import numpy as np
from _geometry import random_curve_data, random_surface_data
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve, GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from test_closest import make_curve, make_surface, points_around, smooth_surface

from splinekit.closest import project
from splinekit.interop.occ import to_occ


def occ_surface_distances(handle, Q):
    """OCC's lowest distance per point (inf where OCC finds no orthogonal foot)."""
    out = np.full(len(Q), np.inf)
    uv = np.full((len(Q), 2), np.nan)
    for i, q in enumerate(Q):
        pr = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, q)), handle)
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
            uv[i] = pr.LowerDistanceParameters()
    return out, uv


def occ_curve_distances(handle, Q):
    out = np.full(len(Q), np.inf)
    for i, q in enumerate(Q):
        pr = GeomAPI_ProjectPointOnCurve(gp_Pnt(*map(float, q)), handle)
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
    return out


def test_surfaces_against_occ_smooth():
    """CAD-like patches: never farther than OCC's projection, at every point."""
    rng = np.random.default_rng(4)
    better = compared = 0
    for trial in range(6):
        s = smooth_surface(rng, rational=trial % 2 == 1, degrees=[(3, 3), (2, 3), (5, 4)][trial % 3])
        Q = points_around(rng, s.control_points, 60, inflate=0.4)
        res = project(s, Q)
        occ, _ = occ_surface_distances(to_occ(s), Q)
        size = max(1.0, float(np.abs(s.control_points).max()))
        have = np.isfinite(occ)
        assert have.sum() > 20
        assert np.all(res.distances[have] <= occ[have] + 1e-9 * size), (trial, (res.distances - occ)[have].max())
        better += int((res.distances[have] < occ[have] - 1e-9 * size).sum())
        compared += int(have.sum())
        # the reported points lie on the surface at the reported parameters, at the reported distance
        np.testing.assert_allclose(s.evaluate(res.parameters[:, 0], res.parameters[:, 1]), res.points, atol=1e-12 * size)
        np.testing.assert_allclose(np.linalg.norm(res.points - Q, axis=1), res.distances, atol=1e-12 * size)
    # OCC finds orthogonal feet only; boundary minima are where splinekit is nearer
    assert better < compared


def test_surfaces_against_occ_random():
    """Wild random nets (tests/_geometry, degrees up to 7, weights in [0.2, 5]):
    never farther than OCC either.

    These nets fold over themselves, so the distance has many local minima close
    together; OCC reports orthogonal feet only and misses boundary minima, so
    splinekit is often nearer. The count of points where splinekit is nearer is
    checked loosely (it is the reason boundary handling exists).
    """
    rng = np.random.default_rng(11)
    better = compared = 0
    for trial in range(14):
        data = random_surface_data(rng, rational=trial % 2 == 0, max_degree=7, max_spans=4)
        s = make_surface(*data)
        Q = points_around(rng, data[4], 30)
        res = project(s, Q)
        occ, _ = occ_surface_distances(to_occ(s), Q)
        size = max(1.0, float(np.abs(data[4]).max()))
        have = np.isfinite(occ)
        diff = (res.distances - occ)[have]
        assert np.all(diff <= 1e-9 * size), (trial, diff.max() / size)
        better += int((diff < -1e-6 * size).sum())
        compared += int(have.sum())
        assert np.isfinite(res.distances).all() and np.isfinite(res.parameters).all()
    assert compared > 200
    assert 0 < better < compared


def test_curves_against_occ():
    rng = np.random.default_rng(5)
    for trial in range(20):
        p, U, P, W = random_curve_data(rng, rational=trial % 2 == 0, max_degree=6)
        c = make_curve(p, U, P, W)
        Q = np.concatenate([points_around(rng, P, 25, inflate=0.5), c.evaluate(rng.uniform(*c.domain, 5)) + rng.normal(0, 1e-3, (5, 3))])
        res = project(c, Q)
        occ = occ_curve_distances(to_occ(c), Q)
        ends = np.linalg.norm(Q[:, None] - c.evaluate(np.array(c.domain))[None], axis=-1).min(1)
        size = max(1.0, float(np.abs(P).max()))
        assert np.all(res.distances <= np.minimum(occ, ends) + 1e-9 * size), (trial, p, W is not None)
        np.testing.assert_allclose(c.evaluate(res.parameters), res.points, atol=1e-12 * size)
