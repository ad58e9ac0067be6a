"""Exact primitive solids: every face lies on the closed-form shape, every pcurve maps onto its
3-D edge curve, faces point outward, and the two uses of each edge key run in opposite senses."""

import numpy as np
import pytest

from splinekit.brep import box, box_with_hole, cone, cylinder, plate_with_holes, sphere, torus
from splinekit.errors import SplineKitError

GRID = np.linspace(0.0, 1.0, 13)


def _face_samples(face):
    """Points, outward normals and (u, v) on a grid over the face's surface domain."""
    (u0, u1), (v0, v1) = face.domain
    U, V = np.meshgrid(u0 + (u1 - u0) * GRID, v0 + (v1 - v0) * GRID, indexing="ij")
    u, v = U.ravel(), V.ravel()
    d = face.surface.derivatives(u, v, 1)
    regular = np.linalg.norm(np.cross(d[1, 0], d[0, 1]), axis=1) > 1e-8  # poles have no normal
    return face.surface.evaluate(u, v), np.where(regular[:, None], face.normals(u, v), 0.0)


def _residual_and_outward(solid, implicit, grad):
    """max |implicit| over every face and min of normal . grad (outward check, non-degenerate)."""
    worst, sign = 0.0, np.inf
    for f in solid.faces:
        p, n = _face_samples(f)
        worst = max(worst, float(np.abs(implicit(p)).max()))
        g = grad(p)
        ok = np.linalg.norm(n, axis=1) > 0.5
        sign = min(sign, float(np.min(np.einsum("ij,ij->i", n[ok], g[ok]))))
    return worst, sign


def test_sphere_on_closed_form_and_outward():
    c = np.array([1.0, -2.0, 0.5])
    s = sphere(3.0, center=c)
    res, sign = _residual_and_outward(s, lambda p: np.linalg.norm(p - c, axis=1) - 3.0, lambda p: p - c)
    assert res < 1e-13 and sign > 0


def test_torus_on_closed_form_and_outward():
    R, r = 5.0, 1.5
    t = torus(R, r)

    def implicit(p):
        return np.hypot(np.hypot(p[:, 0], p[:, 1]) - R, p[:, 2]) - r

    def grad(p):  # direction from the tube's centre circle
        rho = np.hypot(p[:, 0], p[:, 1])
        q = p.copy()
        q[:, :2] *= (R / rho)[:, None]
        q[:, 2] = 0
        return p - q

    res, sign = _residual_and_outward(t, implicit, grad)
    assert res < 1e-13 and sign > 0


def test_cylinder_and_cone_faces():
    r, h = 2.0, 5.0
    cyl = cylinder(r, h)
    side, bottom, top = cyl.faces
    p, n = _face_samples(side)
    assert np.abs(np.hypot(p[:, 0], p[:, 1]) - r).max() < 1e-13
    assert np.all(np.einsum("ij,ij->i", n[:, :2], p[:, :2]) > 0)
    for f, z, nz in ((bottom, 0.0, -1.0), (top, h, 1.0)):
        p, n = _face_samples(f)
        assert np.abs(p[:, 2] - z).max() < 1e-13 and np.allclose(n, [0, 0, nz])
    # truncated cone: radius linear in height
    c = cone(3.0, 1.0, 4.0)
    p, n = _face_samples(c.faces[0])
    assert np.abs(np.hypot(p[:, 0], p[:, 1]) - (3.0 - 2.0 * p[:, 2] / 4.0)).max() < 1e-13
    assert np.all(np.einsum("ij,ij->i", n[:, :2], p[:, :2]) > 0)
    apex = cone(2.0, 0.0, 3.0)
    assert len(apex.faces) == 2 and sum(e.degenerate for e in apex.faces[0].edges) == 1


def test_box_faces_planar_and_outward():
    b = box(1.0, 2.0, 3.0, origin=(1, 1, 1))
    centre = np.array([1.5, 2.0, 2.5])
    for f in b.faces:
        p, n = _face_samples(f)
        # every face is one of the six planes, its normal the axis that is constant on it
        axis = int(np.argmax(np.abs(n[0])))
        assert np.ptp(p[:, axis]) < 1e-13
        assert np.all(np.sign(p[:, axis] - centre[axis]) == np.sign(n[:, axis]))


def test_box_with_hole_faces():
    s, r = 20.0, 4.0
    b = box_with_hole(s, r)
    walls = [f for f in b.faces if f.name.startswith("hole")]
    assert len(walls) == 1 and walls[0].reversed
    p, n = _face_samples(walls[0])
    assert np.abs(np.hypot(p[:, 0], p[:, 1]) - r).max() < 1e-13
    assert np.all(np.einsum("ij,ij->i", n[:, :2], p[:, :2]) < 0)  # into the hole: away from material
    for f in b.faces:
        if f.name in ("top", "bottom"):
            assert len(f.inner_loops) == 1
            e = f.inner_loops[0][0]
            q = e.curve.evaluate(np.linspace(0, 1, 50))
            assert np.abs(np.hypot(q[:, 0], q[:, 1]) - r).max() < 1e-13
            assert np.abs(np.abs(q[:, 2]) - s / 2).max() < 1e-13


SOLIDS = [
    box(1, 2, 3),
    cylinder(2, 5, origin=(1, 2, 3), axis=(1, 1, 0)),
    cone(2, 1, 3),
    cone(0, 1, 2, axis=(0, 1, 1)),
    sphere(3, axis=(1, 0, 1)),
    torus(5, 1),
    box_with_hole(20, 4),
    plate_with_holes(30, 20, 5, [(5, 5, 2), (20, 10, 4)]),
]


@pytest.mark.parametrize("solid", SOLIDS, ids=lambda s: s.name)
def test_pcurves_map_onto_edge_curves(solid):
    t = np.linspace(0.0, 1.0, 31)
    for f in solid.faces:
        for e in f.edges:
            a, b = e.domain
            uv = e.pcurve.evaluate(a + (b - a) * t)
            p = f.surface.evaluate(uv[:, 0], uv[:, 1])
            if e.degenerate:
                assert e.curve is None and np.ptp(p, axis=0).max() < 1e-12
            else:
                assert np.abs(p - e.curve.evaluate(a + (b - a) * t)).max() < 1e-12


@pytest.mark.parametrize("solid", SOLIDS, ids=lambda s: s.name)
def test_each_key_used_twice_in_opposite_senses(solid):
    """Keyed uses come in pairs whose 3-D traversal (flipped on reversed faces) is opposite."""
    uses = {}
    for f in solid.faces:
        for e in f.edges:
            if e.degenerate:
                continue
            a, b = e.domain
            q = e.curve.evaluate(np.array([a, a + 0.3 * (b - a), b]))
            uses.setdefault(e.key, []).append(q[::-1] if f.reversed else q)
    for key, pair in uses.items():
        assert len(pair) == 2, key
        p, q = pair
        # same point set, walked the other way: q's points lie on p reversed at the matching ends
        assert np.allclose(p[0], q[2], atol=1e-12) and np.allclose(p[2], q[0], atol=1e-12), key


def test_bad_sizes_raise():
    for call in (lambda: box(0, 1, 1), lambda: sphere(-1), lambda: torus(1, 2), lambda: cone(0, 0, 1),
                 lambda: box_with_hole(10, 5), lambda: plate_with_holes(10, 10, 1, [(1, 1, 2)]),
                 lambda: plate_with_holes(10, 10, 1, [(3, 5, 2), (6, 5, 2)])):
        with pytest.raises(SplineKitError):
            call()
