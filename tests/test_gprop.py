"""splinekit.interop.gprop: measurements of OCC shapes against closed forms (a cube made of six
bilinear patches, a NURBS sphere, a box with a through hole) and the point comparison between
splinekit's and OCC's evaluation of the same patches."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

import splinekit as sk  # noqa: E402
from splinekit import brep  # noqa: E402
from splinekit.interop import gprop  # noqa: E402
from splinekit.interop.occ import to_occ, to_shape  # noqa: E402


def cube_patches(a: float, origin=(0.0, 0.0, 0.0)) -> list:
    """The six faces of the cube ``origin + [0, a]^3`` as bilinear patches, ``Su x Sv`` outward."""
    o = np.asarray(origin, float)
    c = o + a * np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    P = lambda i, j, k: c[4 * i + 2 * j + k]  # noqa: E731
    quads = [  # (p00, p10, p01, p11) with (p10 - p00) x (p01 - p00) outward
        (P(0, 0, 0), P(0, 1, 0), P(1, 0, 0), P(1, 1, 0)),  # z = 0, normal -z
        (P(0, 0, 1), P(1, 0, 1), P(0, 1, 1), P(1, 1, 1)),  # z = a, normal +z
        (P(0, 0, 0), P(1, 0, 0), P(0, 0, 1), P(1, 0, 1)),  # y = 0, normal -y
        (P(0, 1, 0), P(0, 1, 1), P(1, 1, 0), P(1, 1, 1)),  # y = a, normal +y
        (P(0, 0, 0), P(0, 0, 1), P(0, 1, 0), P(0, 1, 1)),  # x = 0, normal -x
        (P(1, 0, 0), P(1, 1, 0), P(1, 0, 1), P(1, 1, 1)),  # x = a, normal +x
    ]
    knots = [0.0, 0.0, 1.0, 1.0]
    return [sk.BSplineSurface(1, 1, knots, knots, np.array([[p00, p01], [p10, p11]])) for p00, p10, p01, p11 in quads]


def sphere_patch(r: float):
    profile = sk.arc([0, 0, 0], [0, -1, 0], r, -math.pi / 2, math.pi / 2, x_axis=[1, 0, 0])
    return sk.revolve(profile, [0, 0, 0], [0, 0, 1])


def test_cube_measures_are_the_closed_forms():
    a, origin = 3.0, (1.0, -2.0, 0.5)
    shape = to_shape(cube_patches(a, origin))
    assert gprop.topology_counts(shape) == {"SOLID": 1, "SHELL": 1, "FACE": 6, "EDGE": 12, "VERTEX": 8}
    assert gprop.occ_euler_characteristic(shape) == 2
    assert gprop.occ_area(shape) == pytest.approx(6 * a**2, rel=1e-12)
    assert gprop.occ_volume(shape) == pytest.approx(a**3, rel=1e-12)
    lo, hi = gprop.occ_bbox(shape)  # tight up to the shape's tolerance, 1e-7
    np.testing.assert_allclose(lo, origin, rtol=0, atol=2e-7)
    np.testing.assert_allclose(hi, np.add(origin, a), rtol=0, atol=2e-7)
    assert gprop.face_kinds(shape) == {"BSplineSurface, degree 1 x 1": 6}
    assert gprop.trimmed_face_count(shape) == 0
    assert gprop.is_valid(shape)


def test_sphere_measures_and_an_open_shape_has_no_volume():
    r = 2.5
    shape = to_shape([sphere_patch(r)])
    # one face closed on itself: a seam edge and two degenerate pole edges between two vertices
    assert gprop.topology_counts(shape) == {"SOLID": 1, "SHELL": 1, "FACE": 1, "EDGE": 3, "VERTEX": 2}
    # the degenerate pole edges are points: V - (E - 2) + F = 2 - 1 + 1, the sphere's closed form
    assert gprop.occ_euler_characteristic(shape) == 2
    assert gprop.occ_volume(shape) == pytest.approx(4 / 3 * math.pi * r**3, rel=1e-9)
    lo, hi = gprop.occ_bbox(shape)  # the exact geometry, not the control net (which reaches r sqrt 2)
    np.testing.assert_allclose(lo, -r, rtol=0, atol=2e-7)
    np.testing.assert_allclose(hi, r, rtol=0, atol=2e-7)
    assert gprop.face_kinds(shape) == {"BSplineSurface, degree 2 x 2, rational": 1}
    open_shape = to_shape(cube_patches(1.0)[:5])  # a box without its lid
    counts = gprop.topology_counts(open_shape)
    assert counts["SOLID"] == 0 and counts["FACE"] == 5
    assert gprop.occ_volume(open_shape) == 0.0
    assert gprop.occ_area(open_shape) == pytest.approx(5.0, rel=1e-12)


def test_faces_with_holes_are_counted_as_trimmed():
    s, r = 20.0, 4.0
    shape = to_occ(brep.box_with_hole(s, r))
    assert gprop.trimmed_face_count(shape) == 2  # the top and the bottom face, each with a hole
    assert gprop.occ_volume(shape) == pytest.approx(s**3 - math.pi * r**2 * s, rel=1e-9)
    assert gprop.topology_counts(shape)["FACE"] == 7


def test_point_deviation_is_rounding_only_for_the_same_surface():
    patches = cube_patches(2.0) + [sphere_patch(1.5)]
    worst, n = gprop.point_deviation(patches, samples=5)
    assert n == 25 * len(patches)
    assert worst <= 1e-13


def test_point_deviation_measures_a_displaced_surface(monkeypatch):
    """OCC evaluating a copy moved by d along x: the deviation found is d (closed form)."""
    d = 1e-3
    moved = np.eye(4)
    moved[0, 3] = d
    monkeypatch.setattr(gprop, "to_shape", lambda patch: to_shape(patch.transform(moved)))
    worst, _ = gprop.point_deviation([sphere_patch(1.0)], samples=4)
    assert worst == pytest.approx(d, rel=1e-9)
