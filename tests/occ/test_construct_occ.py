"""Geometric construction (splinekit.construct) against OpenCascade: Geom_Circle / Geom_Ellipse /
GC_MakeArcOfCircle, Geom_SurfaceOfRevolution and GeomFill_BSplineCurves with the Coons style,
built directly from arrays here (not through splinekit.occ). Tolerances as in test_construct.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from OCP.GC import GC_MakeArcOfCircle
from OCP.Geom import (
    Geom_BSplineCurve,
    Geom_Circle,
    Geom_Ellipse,
    Geom_SurfaceOfRevolution,
)
from OCP.GeomFill import GeomFill_BSplineCurves, GeomFill_CoonsStyle
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal

from test_construct import _arc_angle, dense, random_curve, random_direction, rng_for, unit

from splinekit import BSplineCurve
from splinekit.construct import arc, arc_through_points, bicubic_coons, circle, ellipse, revolve


# -- OCC helpers (1-based arrays, distinct knots + multiplicities) --------------------------------
def occ_curve(curve):
    P = curve.control_points
    poles = TColgp_Array1OfPnt(1, len(P))
    for i, x in enumerate(P):
        poles.SetValue(i + 1, gp_Pnt(*map(float, x)))
    values, counts = np.unique(curve.knots, return_counts=True)
    kn = TColStd_Array1OfReal(1, values.size)
    mu = TColStd_Array1OfInteger(1, values.size)
    for i, (k, m) in enumerate(zip(values, counts)):
        kn.SetValue(i + 1, float(k))
        mu.SetValue(i + 1, int(m))
    if curve.weights is None:
        return Geom_BSplineCurve(poles, kn, mu, curve.degree, False)
    w = TColStd_Array1OfReal(1, len(P))
    for i, x in enumerate(curve.weights):
        w.SetValue(i + 1, float(x))
    return Geom_BSplineCurve(poles, w, kn, mu, curve.degree, False)


def xyz(p):
    return np.array([p.X(), p.Y(), p.Z()])


def ax2(center, normal, x_axis):
    return gp_Ax2(gp_Pnt(*map(float, center)), gp_Dir(*map(float, normal)), gp_Dir(*map(float, x_axis)))


@pytest.mark.parametrize("seed", range(10))
def test_circle_and_arc_match_occ(seed):
    rng = rng_for(2, seed)
    center = rng.uniform(-5, 5, 3)
    normal = random_direction(rng)
    x_axis = unit(np.cross(normal, rng.normal(size=3)))
    r = rng.uniform(0.1, 20)
    start = rng.uniform(-3, 3)
    end = start + rng.uniform(0.1, 2 * math.pi)
    occ = Geom_Circle(ax2(center, normal, x_axis), r)
    for curve, a0, a1 in ((circle(center, normal, r, x_axis=x_axis), 0.0, 2 * math.pi),
                          (arc(center, normal, r, start, end, x_axis=x_axis), start, end)):
        # ends at the OCC points of the given angles
        assert np.allclose(curve.evaluate(0.0), xyz(occ.Value(a0)), rtol=0, atol=1e-12 * (r + 5))
        assert np.allclose(curve.evaluate(1.0), xyz(occ.Value(a1)), rtol=0, atol=1e-12 * (r + 5))
        # every point is the OCC point at its own angle (in OCC's axes)
        P = curve.evaluate(dense(60))
        ax = occ.Position()
        Xo, Yo = xyz(ax.XDirection()), xyz(ax.YDirection())
        d = P - center
        theta = np.arctan2(d @ Yo, d @ Xo)
        ref = np.array([xyz(occ.Value(float(t))) for t in theta])
        assert np.abs(P - ref).max() <= 1e-12 * (r + 5)


@pytest.mark.parametrize("seed", range(10))
def test_ellipse_implicit_equation_and_occ(seed):
    rng = rng_for(3, seed)
    center = rng.uniform(-5, 5, 3)
    normal = random_direction(rng)
    major_axis = unit(np.cross(normal, rng.normal(size=3)))
    a = rng.uniform(1, 10)
    b = a * rng.uniform(0.05, 1.0)
    e = ellipse(center, normal, a, b, major_axis=major_axis)
    P = e.evaluate(dense(401))
    d = P - center
    Y = np.cross(normal, major_axis)
    assert np.abs((d @ major_axis / a) ** 2 + (d @ Y / b) ** 2 - 1).max() <= 1e-13
    assert np.abs(d @ normal).max() <= 1e-13 * (a + 5)
    occ = Geom_Ellipse(ax2(center, normal, major_axis), a, b)
    t = np.arctan2(d @ Y / b, d @ major_axis / a)
    ref = np.array([xyz(occ.Value(float(x))) for x in t[::10]])
    assert np.abs(P[::10] - ref).max() <= 1e-12 * (a + 5)
    assert np.allclose(P[0], xyz(occ.Value(0.0)), rtol=0, atol=1e-12 * (a + 5))


@pytest.mark.parametrize("seed", range(10))
def test_arc_through_points_matches_occ(seed):
    rng = rng_for(4, seed)
    p0, p1, p2 = rng.uniform(-10, 10, (3, 3))
    a = arc_through_points(p0, p1, p2)
    occ = GC_MakeArcOfCircle(gp_Pnt(*p0), gp_Pnt(*p1), gp_Pnt(*p2)).Value()
    circ = occ.BasisCurve().Circ()
    center, r = xyz(circ.Location()), circ.Radius()
    P = a.evaluate(dense())
    assert np.abs(np.linalg.norm(P - center, axis=1) - r).max() <= 1e-11 * (r + 10)
    assert np.array_equal(P[0], p0) and np.array_equal(P[-1], p2)
    # p1 lies on our arc (the arc between p0 and p2 that contains it)
    fine = a.evaluate(np.linspace(0, 1, 20001))
    assert np.linalg.norm(fine - p1, axis=1).min() <= 2e-3 * r
    # the same arc length as OCC's trimmed arc
    length_occ = r * abs(occ.LastParameter() - occ.FirstParameter())
    assert abs(a.arc_length() - length_occ) <= 1e-9 * length_occ


@pytest.mark.parametrize("seed", range(12))
def test_revolve_matches_occ_surface_of_revolution(seed):
    rng = rng_for(8, seed)
    profile = random_curve(rng, bool(seed % 2), max_degree=4)
    origin = rng.uniform(-5, 5, 3)
    axis = random_direction(rng)
    angle = rng.uniform(0.2, 2 * math.pi)
    S = revolve(profile, origin, axis, angle)
    occ = Geom_SurfaceOfRevolution(occ_curve(profile), gp_Ax1(gp_Pnt(*origin), gp_Dir(*axis)))
    a, b = profile.domain
    u = rng.uniform(0, 1, 60)
    v = rng.uniform(a, b, 60)
    theta = _arc_angle(S.knots_u, u, angle)
    ref = np.array([xyz(occ.Value(float(t), float(w))) for t, w in zip(theta, v)])
    scale = np.abs(profile.control_points).max() + np.abs(origin).max()
    assert np.abs(S.evaluate(u, v) - ref).max() <= 1e-12 * scale


@pytest.mark.parametrize("seed", range(8))
def test_bicubic_coons_matches_occ_coons_style(seed):
    # OCC's GeomFill_BSplineCurves blends the poles; it equals the exact bicubic Coons patch for
    # Bézier boundaries of degree >= 3 with opposite sides of one degree (with interior knots or
    # lower degrees OCC's pole blending is an approximation); the boundaries form a closed loop on [0, 1]
    rng = rng_for(12, seed)
    P00, P10, P01, P11 = rng.uniform(-3, 3, (4, 3))

    def pair(a0, b0, a1, b1):
        p = int(rng.integers(3, 6))
        n = p + 1
        knots = np.concatenate([[0.0] * (p + 1), [1.0] * (p + 1)])
        out = []
        for a, b in ((a0, b0), (a1, b1)):
            pts = np.linspace(a, b, n) + 0.5 * rng.normal(size=(n, 3))
            pts[0], pts[-1] = a, b
            out.append(BSplineCurve(p, knots, pts))
        return out

    c0, c1 = pair(P00, P10, P01, P11)
    d0, d1 = pair(P00, P01, P10, P11)
    S = bicubic_coons(c0, c1, d0, d1)
    occ = GeomFill_BSplineCurves(occ_curve(c0), occ_curve(d1), occ_curve(c1.reverse()), occ_curve(d0.reverse()),
                                 GeomFill_CoonsStyle).Surface()
    u, v = rng.uniform(0, 1, 80), rng.uniform(0, 1, 80)
    ref = np.array([xyz(occ.Value(float(x), float(y))) for x, y in zip(u, v)])
    assert np.abs(S.evaluate(u, v) - ref).max() <= 1e-11
