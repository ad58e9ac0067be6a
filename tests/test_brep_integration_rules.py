"""The integration rules behind mass properties (splinekit/brep/kronrod.py, tensor_rule.py,
green_rule.py): the Gauss-Kronrod pairs against numpy's Gauss-Legendre rule and their degree of
exactness, the Bernstein evaluation against splinekit.basis, planar faces (whose inner Green
integral is a fixed Gauss rule) against the shoelace formula, a twisted bilinear face against
scipy's dblquad, and the error estimates against the true errors of closed forms at every
tolerance."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy import integrate as si

import splinekit as sk
from splinekit.basis.bernstein import all_bernstein
from splinekit.brep import Shell, TrimmedFace
from splinekit.brep import green_rule, primitives
from splinekit.brep.kronrod import K15, K21, K31
from splinekit.brep.mass import area_and_volume, area_with_error, mass_properties
from splinekit.brep.tensor_rule import bernstein_ders

PI = np.pi
TEAPOT_AREA = 21153.3212370  # scipy's dblquad on every patch at 1e-12 (benchmarks/bench_mass.py)


@pytest.mark.parametrize("pair, n", [(K15, 7), (K21, 10), (K31, 15)])
def test_gauss_kronrod_pairs_embed_gauss_legendre_and_are_exact_to_degree_3n_plus_1(pair, n):
    g, w = np.polynomial.legendre.leggauss(n)
    gauss = pair.wg != 0
    assert pair.n == 2 * n + 1 and np.count_nonzero(gauss) == n
    assert np.allclose(pair.x[gauss], g, rtol=0, atol=1e-15) and np.allclose(pair.wg[gauss], w, rtol=0, atol=1e-15)
    assert np.allclose(pair.t, 0.5 * (pair.x + 1), rtol=0, atol=0)
    exact_to = 3 * n + 1 if n % 2 == 0 else 3 * n + 2  # odd n: the next odd degree is free by symmetry
    # Legendre polynomials (well scaled at high degree): P_0 integrates to 2, the others to 0
    legendre = np.polynomial.legendre.legvander(pair.x, exact_to + 2)  # (N, degree + 1)
    moments = pair.wk @ legendre
    assert abs(moments[0] - 2.0) < 1e-15 and np.abs(moments[1:exact_to + 1]).max() < 1e-15
    assert abs(moments[exact_to + 1 if exact_to % 2 else exact_to + 2]) > 1e-4  # not beyond


@pytest.mark.parametrize("p", [1, 2, 3, 5, 7])
def test_bernstein_values_and_derivatives_match_the_basis_module(p):
    t = np.linspace(-0.05, 1.05, 37).reshape(1, 37)
    assert np.abs(bernstein_ders(p, t) - all_bernstein(p, t, 1)).max() <= 1e-13 * max(1, p)


def _planar_face(corner, e1, e2, polygon, holes):
    """``corner + u e1 + v e2`` on ``[-1.5, 1.5]^2`` trimmed by a counter-clockwise polygon
    ``(n, 2)`` and clockwise circles ``(cu, cv, r)``."""
    corner, e1, e2 = (np.asarray(x, dtype=float) for x in (corner, e1, e2))
    k = [-1.5, -1.5, 1.5, 1.5]
    cp = np.array([[corner - 1.5 * e1 - 1.5 * e2, corner - 1.5 * e1 + 1.5 * e2],
                   [corner + 1.5 * e1 - 1.5 * e2, corner + 1.5 * e1 + 1.5 * e2]])
    surface = sk.BSplineSurface(1, 1, k, k, cp)
    outer = [sk.line(polygon[i], polygon[(i + 1) % len(polygon)]) for i in range(len(polygon))]
    loops = [outer] + [[sk.circle(np.array([cu, cv]), None, r).reverse()] for cu, cv, r in holes]
    return TrimmedFace(surface, loops)


def _segment_distance(p, a, b):
    d = b - a
    s = np.clip(np.dot(p - a, d) / np.dot(d, d), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + s * d)))


@settings(max_examples=25, deadline=None)
@given(radii=st.lists(st.floats(0.5, 1.0), min_size=3, max_size=9), phase=st.floats(0.0, 2 * PI),
       n_holes=st.integers(0, 3), hole_sizes=st.lists(st.floats(0.05, 0.4), min_size=3, max_size=3),
       e1=st.tuples(st.floats(0.5, 3.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
       e2=st.tuples(st.floats(-1.0, 1.0), st.floats(0.5, 3.0), st.floats(-1.0, 1.0)))
def test_planar_polygons_with_circular_holes_against_the_shoelace_formula(radii, phase, n_holes, hole_sizes, e1, e2):
    n = len(radii)
    angles = 2 * PI * np.arange(n) / n
    polygon = np.column_stack([np.cos(angles), np.sin(angles)]) * np.array(radii)[:, None]  # star-shaped, ccw
    safe = min(_segment_distance(np.zeros(2), polygon[i], polygon[(i + 1) % n]) for i in range(n))
    holes = []
    for i in range(n_holes):  # on a circle of radius safe / 2, small enough not to meet each other
        theta = phase + 2 * PI * i / n_holes
        r = hole_sizes[i] * safe * (np.sin(PI / n_holes) if n_holes > 1 else 1.0)
        holes.append((0.5 * safe * np.cos(theta), 0.5 * safe * np.sin(theta), r))
    e1, e2, corner = np.array(e1), np.array(e2), np.array([3.0, -2.0, 7.0])
    jac = np.linalg.norm(np.cross(e1, e2))
    assume(jac >= 0.1 * np.linalg.norm(e1) * np.linalg.norm(e2))  # a plane, not a sliver
    x, y = polygon[:, 0], polygon[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area_uv = 0.5 * cross.sum()
    first_uv = np.array([((x + np.roll(x, -1)) * cross).sum(), ((y + np.roll(y, -1)) * cross).sum()]) / 6.0
    for cu, cv, r in holes:
        area_uv -= PI * r * r
        first_uv -= PI * r * r * np.array([cu, cv])
    face = _planar_face(corner, e1, e2, polygon, holes)
    for tol in (1e-6, 1e-10):
        mp = mass_properties(face, tol)
        exact = jac * area_uv
        assert abs(mp.area - exact) <= max(mp.area_error, 1e-13 * exact), (mp.area, exact)
        assert mp.area_error <= tol * exact
        c_uv = first_uv / area_uv
        centroid = corner + c_uv[0] * e1 + c_uv[1] * e2
        assert np.abs(mp.centroid - centroid).max() <= max(10 * tol, 1e-12) * 3.0


def test_a_twisted_bilinear_face_is_not_taken_for_a_plane():
    # z = u v over [-1, 1]^2, trimmed by the unit disc: |S_u x S_v| = sqrt(1 + u^2 + v^2)
    cp = np.array([[[-1, -1, 1], [-1, 1, -1]], [[1, -1, -1], [1, 1, 1]]], dtype=float)
    surface = sk.BSplineSurface(1, 1, [-1, -1, 1, 1], [-1, -1, 1, 1], cp)
    assert green_rule._affine_map(surface) is None
    face = TrimmedFace(surface, [[sk.circle(np.zeros(2), None, 1.0)]])
    exact = 2 * PI / 3 * (2 ** 1.5 - 1)  # the integral of sqrt(1 + r^2) r dr dtheta
    a, err = area_with_error(face, 1e-10)
    assert abs(a - exact) <= err <= 1e-10 * exact
    ref, _ = si.dblquad(lambda r, th: np.sqrt(1 + r * r) * r, 0, 2 * PI, 0, 1, epsabs=0, epsrel=1e-12)
    assert abs(ref - exact) <= 1e-11 * exact  # the closed form itself, independently


def _cases():
    from models import teapot

    pot = [TrimmedFace(sk.BezierSurface(net)) for net in teapot.control_nets(20.0)]
    return {
        "sphere": (primitives.sphere(10.0), 4 / 3 * PI * 1000, 4 * PI * 100, 0.0),
        "torus": (primitives.torus(10.0, 3.0), 2 * PI**2 * 90, 4 * PI**2 * 30, 0.0),
        "box with hole": (primitives.box_with_hole(20.0, 4.0), 8000 - PI * 320, 2400 - 32 * PI + 160 * PI, 0.0),
        "cone": (primitives.cone(3.0, 1.0, 5.0), PI * 5 * 13 / 3, PI * 10 + PI * 4 * np.hypot(2, 5), 0.0),
        "cylinder": (primitives.cylinder(2.0, 3.0), PI * 12, 2 * PI * 4 + 2 * PI * 6, 0.0),
        "teapot": (Shell(pot), None, TEAPOT_AREA, 1e-7),  # the reference's last digit
    }


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-8, 1e-10, 1e-12])
def test_the_error_estimates_bound_the_true_errors(tol):
    for name, (body, volume, area, slack) in _cases().items():
        a, ea, v, ev = area_and_volume(Shell(list(body.faces)), tol)
        assert abs(a - area) <= ea + slack, (name, tol, a - area, ea)
        assert ea <= tol * area or tol == 1e-12, (name, tol, ea)
        if volume is not None:
            assert abs(v - volume) <= ev, (name, tol, v - volume, ev)
