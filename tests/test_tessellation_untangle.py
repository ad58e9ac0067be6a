"""Trims that cross in (u, v) within their edges' own tolerance (CAD exports with sliver faces):
moved apart in (u, v) and meshed, judged against the exact area of the face and the mesh's own
boundary; the same trims with tight tolerances are still refused."""

from __future__ import annotations

import numpy as np
import pytest

import splinekit as sk
from splinekit.brep import Edge, TrimmedFace
from splinekit.construct.curves import line
from splinekit.errors import SplineKitError
from splinekit.tessellation.untangle import crossing_pairs, untangle

A, B, C = 10.0, 6.0, 2.0  # the surface: (u, v) in [0, 1]^2 -> (A u, B v, 2 C u (1 - u))
H = 1e-3  # the sliver's height in v at u = 1/2 (6e-3 in space)


def _surface():
    """A parabolic cylinder (curved in u, so its trims are sampled finely)."""
    cp = np.array([[[0, 0, 0], [0, B, 0]], [[A / 2, 0, C], [A / 2, B, C]], [[A, 0, 0], [A, B, 0]]], dtype=float)
    return sk.BSplineSurface(2, 1, [0, 0, 0, 1, 1, 1], [0, 0, 1, 1], cp)


def _image(p, q):
    """The 3-D curve of the (u, v) segment p -> q on the surface: a quadratic, exactly."""
    S = _surface()
    t = np.array([0.0, 0.5, 1.0])
    X = S.evaluate(p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))
    return sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([X[0], 2 * X[1] - 0.5 * (X[0] + X[2]), X[2]]))


def _sliver_face(tolerance):
    """A rectangle [0, 1/2] x [0, 1] with a sliver along v = 0 out to u = 1: the bottom edge runs
    to (1, 0), the next edge comes back to (1/2, H). That edge's pcurve dips below v = 0 (it
    crosses the bottom edge in (u, v)) while its 3-D curve is the straight chord, 1.5e-3 .. 6e-3
    away from the pcurve's image: within a tolerance of 1e-2, far outside one of 1e-7."""
    corners = [(0.0, 0.0), (1.0, 0.0), (0.5, H), (0.5, 1.0), (0.0, 1.0)]
    edges = []
    for k, (p, q) in enumerate(zip(corners, corners[1:] + corners[:1])):
        curve3 = _image(p, q)
        if k == 1:  # the crossing pcurve: a quadratic whose middle control point lies below v = 0
            pc = sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([p, (0.75, -H), q]))
        else:
            pc = line(np.array(p), np.array(q))
        edges.append(Edge(pc, curve3, tolerance=tolerance))
    return TrimmedFace(_surface(), [edges], tolerance=tolerance)


def test_crossing_trims_within_their_tolerance_mesh():
    face = _sliver_face(1e-2)
    mesh = sk.tessellate(face, 1e-3)
    # exact area of the rectangle [0, 1/2] x [0, 1]: B times the parabola's arc length over
    # x in [0, A/2] (z = 2 C u (1 - u), slope dz/dx = 2 C (1 - 2u) / A); the sliver adds
    # at most its triangle (A/2 by B H); the mesh is within its tolerance of the surface
    k = 2 * C / A
    s = lambda x: 0.5 * (x * np.hypot(1, x) + np.arcsinh(x))  # integral of sqrt(1 + x^2)
    exact = B * (A / 2) * (s(k) - s(0)) / k
    assert exact - 1e-3 * 2 * A <= mesh.area <= exact + 0.5 * (A / 2) * (B * H) + 1e-3 * 2 * A
    assert mesh.max_deviation <= 1e-3 + 1e-2  # the tolerance plus the edges' own
    # every triangle faces the surface's normal there (no fold where the trims were moved)
    F = np.asarray(mesh.faces)
    X = mesh.vertices[F]
    n = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    uv = mesh.corner_uv.mean(axis=1)
    assert (np.einsum("ij,ij->i", n, face.normals(uv[:, 0], uv[:, 1])) > 0).all()
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, count = np.unique(e, axis=0, return_counts=True)
    assert set(count.tolist()) <= {1, 2}
    boundary = np.unique(e, axis=0)[count == 1]
    assert (np.bincount(boundary.ravel()) [np.unique(boundary)] == 2).all()  # a simple loop
    assert len(boundary) == len(np.unique(boundary))  # closed: as many edges as vertices


def test_crossing_trims_with_tight_tolerances_are_refused():
    with pytest.raises(SplineKitError, match="face 0.*cross"):
        sk.tessellate(_sliver_face(1e-7), 1e-3)


def test_untangle_moves_the_looser_edge_to_the_material_side():
    # a sliver polygon: edge 0 along y = 0 to (4, 0), edge 1 back above it but dipping below
    # y = 0 at x = 2, edge 2 closing the triangle; edge 1 has the larger tolerance, so it moves
    P = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 0.0],
                  [3.0, 0.05], [2.0, -0.05], [1.0, 0.05], [0.0, 0.1], [-1.0, 1.0]])
    owner = np.array([0, 0, 0, 0, 1, 1, 1, 1, 2, 2])
    corner = np.array([True, False, False, False, True, False, False, False, True, False])
    n = len(P)
    segs = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    assert crossing_pairs(P, segs)[0].size
    Q, moved = untangle(P, segs, owner, corner, np.array([1e-3, 1e-2, 1e-3]))
    assert crossing_pairs(Q, segs)[0].size == 0
    assert set(np.flatnonzero(moved).tolist()) <= {5, 6, 7}  # only edge 1's inner points
    assert (Q[moved, 1] > 0).all() and (Q[~moved] == P[~moved]).all()
    # an edge doubling back on itself is spread along its chord
    R = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [3.0, 0.0], [3.0, 1.0]])
    segs = np.column_stack([np.arange(5), (np.arange(5) + 1) % 5])
    Q, moved = untangle(R, segs, np.array([0, 0, 0, 1, 2]), np.array([True, False, False, True, True]), np.ones(3))
    assert crossing_pairs(Q, segs)[0].size == 0
    assert np.allclose(Q[:4, 0], [0.0, 1.0, 2.0, 3.0])
