"""The planar shortcuts of the trimmed-face tessellator: affine faces measured from their
corners' offsets (no surface evaluation) and straight edges on them sampled at their ends only,
judged by evaluating the faces' own surfaces (the independent yardstick of
test_tessellation_brep) and by closed-form areas and volumes."""

from __future__ import annotations

import numpy as np
import pytest

import splinekit as sk
from splinekit.brep import Edge, TrimmedFace, primitives
from splinekit.construct.curves import line

from test_tessellation_brep import measured_deviation


def _quad_face(corners3, tolerance=1e-7, lift=0.0):
    """The bilinear face through ``corners3`` ``(2, 2, 3)`` over [0, 1]^2, its four sides
    straight in (u, v) and (lifted by ``lift`` at their middles, like a sloppy file's edges) in space."""
    S = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.asarray(corners3, dtype=float))
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    edges = []
    for k in range(4):
        p, q = uv[k], uv[(k + 1) % 4]
        P, Q = S.evaluate(p[:1], p[1:])[0], S.evaluate(q[:1], q[1:])[0]
        if lift:
            M = 0.5 * (P + Q) + [0.0, 0.0, lift]
            curve = sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([P, 2 * M - 0.5 * (P + Q), Q]))
        else:
            curve = line(P, Q)
        edges.append(Edge(line(p, q), curve, tolerance=max(tolerance, 2 * lift)))
    return TrimmedFace(S, [edges], tolerance=max(tolerance, 2 * lift))


@pytest.mark.parametrize("lift", [0.0, 0.004])
def test_affine_face_deviation_is_the_measured_one(lift):
    # a parallelogram: the reported deviation (from the corners' offsets) is what evaluating
    # the surface at every triangle's centre and edge midpoints gives
    face = _quad_face([[[0, 0, 0], [1, 6, 0]], [[10, 0, 0], [11, 6, 0]]], lift=lift)
    mesh = sk.tessellate(face, 1e-3)
    dev = measured_deviation(mesh, [face])
    assert mesh.max_deviation == pytest.approx(dev, rel=1e-9, abs=1e-13)
    assert dev <= 1e-3 + lift + 1e-12
    assert mesh.area == pytest.approx(60.0, rel=1e-3 + lift)


@pytest.mark.parametrize("tol", [1e-1, 1e-2, 1e-3])
def test_twisted_quad_with_straight_sides_is_still_measured(tol):
    # a hyperbolic paraboloid z = c u v: straight sides, not a plane, so neither shortcut applies
    c = 2.0
    face = _quad_face([[[0, 0, 0], [0, 4, 0]], [[4, 0, 0], [4, 4, c]]])
    mesh = sk.tessellate(face, tol)
    assert measured_deviation(mesh, [face]) <= tol * (1 + 1e-9)
    assert mesh.max_deviation <= tol * (1 + 1e-9)
    # interior vertices lie on the surface z = c x y / 16 (exactly: they are evaluated)
    V = mesh.vertices
    assert np.abs(V[:, 2] - c * V[:, 0] * V[:, 1] / 16).max() <= 1e-12
    if tol <= 1e-2:
        assert mesh.n_faces > 2  # refined, not two flat triangles


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-5])
def test_box_with_hole_planar_path_closed_and_exact(rel):
    # the straight edges carry no inner samples at any tolerance; the hole's circle is sampled
    # to the tolerance; the volume is within area x tolerance of the closed form
    side, r = 20.0, 4.0
    mesh = sk.tessellate(primitives.box_with_hole(side, r), rel, relative=True)
    volume = side**3 - np.pi * r**2 * side
    area = 6 * side**2 - 2 * np.pi * r**2 + 2 * np.pi * r * side
    assert mesh.is_closed and mesh.volume > 0
    assert abs(mesh.volume - volume) <= area * mesh.tolerance
    V = mesh.vertices
    on_box_edge = (np.isclose(np.abs(V), side / 2).sum(axis=1) >= 2)
    assert on_box_edge.sum() == 8  # the corners only
