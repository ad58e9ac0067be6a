"""Point classification: ``face.contains_uv`` against the trims and ``solid.contains`` in 3-D.

Independent references: a pure-Python even-odd ray test on random polygons (no shared code),
closed-form inside tests of the primitives (sphere, torus, cylinder, cone, a box with a through
hole whose hole is outside), distances to closed-form surfaces for ON, and OpenCascade's
``BRepClass3d_SolidClassifier`` on the same shapes built with build123d (in
tests/occ/test_brep_classify_occ.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from splinekit import _kernels
from splinekit.brep import TrimmedFace, box, box_with_hole, cone, cylinder, sphere, torus
from splinekit.brep.classify import INSIDE, ON, OUTSIDE
from splinekit.construct import circle, line
from splinekit.errors import SplineKitError
from splinekit.pointcloud.meshdistance import KERNELS
from splinekit.surfaces import BSplineSurface

PLANE = BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                       np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float))


def _polygon_face(vertices, holes=()):
    loops = []
    for poly in (vertices, *holes):
        m = len(poly)
        loops.append([line(poly[i], poly[(i + 1) % m]) for i in range(m)])
    return TrimmedFace(PLANE, loops)


def _brute_force_inside(poly, x, y):
    """Even-odd rule, one point, plain Python: the textbook crossing test."""
    inside = False
    m = len(poly)
    for i in range(m):
        (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % m]
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def _distance_to_polygon(poly, q):
    P = np.asarray(poly)
    A, B = P, np.roll(P, -1, axis=0)
    AB = B - A
    t = np.clip(((q[:, None, :] - A[None]) * AB[None]).sum(-1) / (AB * AB).sum(-1)[None], 0, 1)
    return np.linalg.norm(q[:, None, :] - (A[None] + t[..., None] * AB[None]), axis=-1).min(axis=1)


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 12), st.integers(0, 2**31 - 1))
def test_contains_uv_matches_brute_force_on_random_polygons(n, seed):
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * np.pi, n))
    assume(np.min(np.diff(np.concatenate([angles, [angles[0] + 2 * np.pi]]))) >= 1e-3)  # no sliver edges
    radii = rng.uniform(0.05, 0.45, n)
    poly = [(0.5 + r * math.cos(a), 0.5 + r * math.sin(a)) for r, a in zip(radii, angles)]  # star-shaped, CCW
    q = rng.uniform(0.0, 1.0, (400, 2))
    q = q[_distance_to_polygon(poly, q) > 1e-6]
    face = _polygon_face(poly)
    got = face.contains_uv(q)
    want = np.array([_brute_force_inside(poly, x, y) for x, y in q])
    assert np.array_equal(got == INSIDE, want)
    assert not np.any(got == ON)
    # the polygon's own vertices and edge mid points are ON
    P = np.array(poly)
    onq = np.concatenate([P, 0.5 * (P + np.roll(P, -1, axis=0))])
    assert np.all(face.contains_uv(onq) == ON)


def test_contains_uv_with_a_circular_hole_and_tolerance():
    face = TrimmedFace(PLANE, [[line((0.1, 0.1), (0.9, 0.1)), line((0.9, 0.1), (0.9, 0.9)),
                                line((0.9, 0.9), (0.1, 0.9)), line((0.1, 0.9), (0.1, 0.1))],
                               [circle((0.5, 0.5), None, 0.2).reverse()]], tolerance=1e-6)
    rng = np.random.default_rng(1)
    q = rng.uniform(0, 1, (20000, 2))
    r = np.hypot(q[:, 0] - 0.5, q[:, 1] - 0.5)
    clear = (np.abs(r - 0.2) > 1e-5) & (np.abs(q - 0.1).min(axis=1) > 1e-5) & (np.abs(q - 0.9).min(axis=1) > 1e-5)
    box_in = np.all((q > 0.1) & (q < 0.9), axis=1)
    want = np.where(box_in & (r > 0.2), INSIDE, OUTSIDE)
    got = face.contains_uv(q)
    assert np.array_equal(got[clear], want[clear])
    # ON within the tolerance (the plane's uv is its length), not beyond 2x
    ang = rng.uniform(0, 2 * np.pi, 200)
    for dr, expect in ((0.0, ON), (0.5e-6, ON), (-0.5e-6, ON), (3e-6, INSIDE), (-3e-6, OUTSIDE)):
        p = 0.5 + (0.2 + dr) * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        assert np.all(face.contains_uv(p) == expect), dr
    assert face.contains_uv([0.5, 0.5]) == OUTSIDE and face.contains_uv((0.2, 0.2)) == INSIDE
    with pytest.raises(SplineKitError):
        face.contains_uv(np.zeros((3, 3)))
    with pytest.raises(SplineKitError):
        face.contains_uv([[np.nan, 0.5]])


def test_contains_uv_on_periodic_faces():
    f = sphere(2).faces[0]
    q = np.random.default_rng(2).uniform(-0.2, 1.2, (2000, 2))
    inside = np.all((q > 1e-6) & (q < 1 - 1e-6), axis=1)
    outside = np.any((q < -1e-6) | (q > 1 + 1e-6), axis=1)
    got = f.contains_uv(q)
    assert np.all(got[inside] == INSIDE) and np.all(got[outside] == OUTSIDE)


CASES = {
    "sphere": (sphere(3.0, center=(1, 2, 3)), lambda p: np.linalg.norm(p - [1, 2, 3], axis=1) - 3.0),
    "torus": (torus(5.0, 1.5), lambda p: np.hypot(np.hypot(p[:, 0], p[:, 1]) - 5.0, p[:, 2]) - 1.5),
    "cylinder": (cylinder(2.0, 5.0), lambda p: np.maximum.reduce([np.hypot(p[:, 0], p[:, 1]) - 2.0, -p[:, 2], p[:, 2] - 5.0])),
    "cone": (cone(3.0, 1.0, 4.0), lambda p: np.maximum.reduce([
        (np.hypot(p[:, 0], p[:, 1]) - (3.0 - 0.5 * p[:, 2])) * 4.0 / math.hypot(4.0, 2.0), -p[:, 2], p[:, 2] - 4.0])),
    "box_with_hole": (box_with_hole(20.0, 4.0), lambda p: np.maximum(np.abs(p).max(axis=1) - 10.0,
                                                                      4.0 - np.hypot(p[:, 0], p[:, 1]))),
}


@pytest.fixture(params=["mesh", "winding"])
def path(request, monkeypatch):
    """Both classification paths: the tessellation's signed distance (compiled search, switched
    on at once) and the coarse meshes' winding numbers (compiled code off)."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1" if request.param == "mesh" else "0")
    if request.param == "mesh" and _kernels.load(KERNELS) is None:  # loaded: serves every size
        pytest.skip("numba is not installed")
    return request.param


def _used(solid, path):
    """The mesh path answered when it was asked to (its mesh is cached on the solid)."""
    return path == "winding" or solid._cache.get("inside_mesh") is not None


@pytest.mark.parametrize("name", list(CASES))
def test_solid_contains_against_closed_forms(name, path):
    solid, sdf = CASES[name]
    rng = np.random.default_rng(3)
    lo, hi = np.array([-12.0, -12.0, -12.0]), np.array([12.0, 12.0, 12.0])
    if name in ("cylinder", "cone"):
        lo, hi = np.array([-4.0, -4.0, -1.0]), np.array([4.0, 4.0, 6.0])
    p = rng.uniform(lo, hi, (1500, 3))
    d = sdf(p)
    p, d = p[np.abs(d) > 1e-6], d[np.abs(d) > 1e-6]
    got = solid.contains(p)
    assert np.array_equal(got, np.where(d < 0, INSIDE, OUTSIDE)) and _used(solid, path)
    # far from the boundary only: every point settled by the mesh (or its distance grid) alone
    far = np.abs(d) > 0.5
    assert np.array_equal(solid.contains(p[far]), np.where(d[far] < 0, INSIDE, OUTSIDE))


def test_solid_contains_near_and_on_the_surface(path):
    s = sphere(3.0)
    rng = np.random.default_rng(4)
    dirs = rng.normal(size=(300, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    for r, expect in ((3.0, ON), (3.0 - 1e-4, INSIDE), (3.0 + 1e-4, OUTSIDE), (2.99, INSIDE), (3.01, OUTSIDE)):
        assert np.all(s.contains(r * dirs) == expect), r
    b = box_with_hole(20.0, 4.0)
    ang = rng.uniform(0, 2 * np.pi, 200)
    z = rng.uniform(-9, 9, 200)
    wall = np.stack([np.cos(ang), np.sin(ang), np.zeros(200)], axis=1)
    for r, expect in ((4.0, ON), (4.0 + 1e-4, INSIDE), (4.0 - 1e-4, OUTSIDE)):
        assert np.all(b.contains(r * wall + np.c_[0 * z, 0 * z, z]) == expect), r
    # near edges and corners of the box
    pts = np.array([[10 + 1e-4, 10 + 1e-4, 0], [10 - 1e-4, 10 - 1e-4, 0], [10 - 1e-4, 10 - 1e-4, 10 - 1e-4],
                    [10, 10, 10], [10, 0, 0], [0, 0, 0], [0, 0, 10.5], [4 * math.cos(0.3), 4 * math.sin(0.3), 10]])
    assert b.contains(pts).tolist() == [OUTSIDE, INSIDE, INSIDE, ON, ON, OUTSIDE, OUTSIDE, ON]
    assert b.contains([100.0, 0.0, 0.0]) == OUTSIDE
    assert _used(s, path) and _used(b, path)
    with pytest.raises(SplineKitError):
        b.contains(np.zeros((2, 2)))
