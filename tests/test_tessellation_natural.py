"""B-rep faces bounded by their natural domain that share no edge (a whole sphere, a whole torus)
meshed by the patch path (splinekit.tessellation.natural).

Judged against what the tessellator does not compute: the closed-form volume and area of the
sphere and torus (a mesh within ``tol`` of a surface of area ``A`` encloses the exact volume
within about ``A * tol``), exact distances to the analytic surfaces, the surfaces' own
evaluators at the triangles' barycentric (u, v), and the topology (Euler characteristic).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.brep import Shell, Solid, TrimmedFace, primitives
from splinekit.tessellation.natural import natural_faces
from splinekit.tessellation.trimmed import _Prepared

BARY = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])


def remeasured(mesh, faces):
    """Largest distance between each face's surface (its own evaluator) at the barycentric
    (u, v) of every triangle's centre and edge midpoints (from ``corner_uv``) and the flat point."""
    X = mesh.vertices[np.asarray(mesh.faces)]
    worst = 0.0
    for f in np.unique(mesh.face_patch):
        sel = np.flatnonzero(mesh.face_patch == f)
        uv = np.einsum("bj,fjd->fbd", BARY, mesh.corner_uv[sel]).reshape(-1, 2)
        flat = np.einsum("bj,fjd->fbd", BARY, X[sel]).reshape(-1, 3)
        worst = max(worst, float(np.linalg.norm(faces[f].surface.evaluate(uv[:, 0], uv[:, 1]) - flat, axis=1).max()))
    return worst


def _is_natural(obj):
    faces = obj.faces
    sk.tessellate(obj, 1e-1, relative=True)  # builds and caches the face set's preparation
    prep = faces[0]._cache["tessellate"]
    assert isinstance(prep, _Prepared)
    return natural_faces(prep.faces, prep.uses, prep.table)


def test_whole_sphere_and_torus_are_natural_faces_and_others_are_not():
    assert _is_natural(primitives.sphere(1.0)).tolist() == [True]
    assert _is_natural(primitives.torus(2.0, 0.5)).tolist() == [True]
    # a cylinder's side shares its circles with the caps; a box's faces share every edge
    assert not _is_natural(primitives.cylinder(1.0, 2.0)).any()
    assert not _is_natural(primitives.box(1.0, 2.0, 3.0)).any()


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4])
@pytest.mark.parametrize("kind", ["sphere", "torus"])
def test_natural_solids_closed_within_tolerance_and_closed_form_measures(kind, rel):
    if kind == "sphere":
        r = 1.5
        solid = primitives.sphere(r, center=(0.3, -0.2, 0.1))
        volume, area, genus = 4 / 3 * math.pi * r**3, 4 * math.pi * r**2, 0
    else:
        R, r = 2.0, 0.6
        solid = primitives.torus(R, r, center=(0.3, -0.2, 0.1))
        volume, area, genus = 2 * math.pi**2 * R * r**2, 4 * math.pi**2 * R * r, 1
    mesh = sk.tessellate(solid, rel, relative=True)
    tol = mesh.tolerance
    assert mesh.is_closed
    assert mesh.euler_characteristic == 2 - 2 * genus
    assert np.all(mesh.face_patch == 0) and np.all(mesh.vertex_patch == 0)
    dev = remeasured(mesh, solid.faces)
    assert dev <= tol * (1 + 1e-9)
    assert mesh.max_deviation == pytest.approx(dev, rel=1e-9, abs=1e-15)
    # within tol of the surface: the enclosed volume is the exact one within area * tol
    # (inscribed in the convex sphere: below it)
    assert abs(volume - mesh.volume) <= area * tol
    assert kind != "sphere" or mesh.volume < volume
    # vertices on the analytic surface; normals unit, outward (the exact normal at each vertex)
    X = mesh.vertices - np.array([0.3, -0.2, 0.1])
    if kind == "sphere":
        assert np.allclose(np.linalg.norm(X, axis=1), r, rtol=0, atol=1e-12)
        outward = X / r
    else:
        rho = np.hypot(X[:, 0], X[:, 1])
        assert np.allclose(np.hypot(rho - R, X[:, 2]), r, rtol=0, atol=1e-12)
        ring = np.column_stack([X[:, 0] / rho * R, X[:, 1] / rho * R, np.zeros(len(X))])
        outward = (X - ring) / r
    assert np.allclose(mesh.normals, outward, atol=1e-9)
    # every triangle faces outward (its normal agrees with the exact one at its centroid)
    F = np.asarray(mesh.faces)
    tri = mesh.vertices[F]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.einsum("ij,ij->i", fn, outward[F].sum(axis=1)) > 0)


def test_reversed_natural_face_faces_inward():
    solid = primitives.sphere(2.0)
    face = solid.faces[0]
    inner = TrimmedFace(face.surface, face.loops, reversed=True)
    out, inn = sk.tessellate(face, 1e-3), sk.tessellate(inner, 1e-3)
    assert inn.is_closed and inn.volume < 0
    assert inn.volume == pytest.approx(-out.volume, rel=1e-12)
    assert np.allclose(inn.normals, -out.normals)
    assert np.allclose(np.einsum("ij,ij->i", inn.normals, inn.vertices), -2.0, atol=1e-9)
    assert remeasured(inn, [inner]) <= inn.tolerance * (1 + 1e-9)


def test_hollow_ball_shell_with_a_reversed_inner_sphere():
    outer = primitives.sphere(2.0).faces[0]
    inner = primitives.sphere(1.0).faces[0]
    inner = TrimmedFace(inner.surface, inner.loops, reversed=True)
    solid = Solid([Shell([outer]), Shell([inner])])
    mesh = sk.tessellate(solid, 1e-4, relative=True)
    assert mesh.is_closed
    exact = 4 / 3 * math.pi * (2.0**3 - 1.0**3)
    assert abs(mesh.volume - exact) <= 4 * math.pi * (4.0 + 1.0) * mesh.tolerance


def test_mixed_face_set_keeps_face_numbers_and_stays_closed():
    ball = primitives.sphere(1.0, center=(10.0, 0.0, 0.0))
    block = primitives.box_with_hole(4.0, 1.0)
    objs = [block, ball]
    faces = [f for o in objs for f in o.faces]
    mesh = sk.tessellate(objs, 1e-3, relative=True)
    assert mesh.is_closed
    assert sorted(np.unique(mesh.face_patch)) == list(range(len(faces)))
    assert remeasured(mesh, faces) <= mesh.tolerance * (1 + 1e-9)
    # the sphere's triangles are those of the sphere alone at the same absolute tolerance
    alone = sk.tessellate(ball, mesh.tolerance)
    sphere_rows = mesh.face_patch == len(faces) - 1
    assert int(sphere_rows.sum()) == alone.n_faces
    assert np.allclose(np.sort(mesh.vertices[np.unique(np.asarray(mesh.faces)[sphere_rows])], axis=0),
                       np.sort(alone.vertices, axis=0))  # fmt: skip
    exact = 4**3 - math.pi * 1.0**2 * 4 + 4 / 3 * math.pi
    assert abs(mesh.volume - exact) <= mesh.area * mesh.tolerance


def test_untrimmed_lone_face_is_open_and_within_tolerance():
    rng = np.random.default_rng(3)
    g = np.linspace(0.0, 1.0, 6)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, 0.2 * rng.standard_normal(X.shape)], axis=-1)
    knots = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]
    face = TrimmedFace(sk.BSplineSurface(3, 3, knots, knots, P))
    mesh = sk.tessellate(face, 1e-3, relative=True)
    assert not mesh.is_closed
    assert remeasured(mesh, [face]) <= mesh.tolerance * (1 + 1e-9)
    # the boundary is the domain's: the corners of (u, v) are vertices
    for corner in ([0, 0], [0, 1], [1, 0], [1, 1]):
        assert np.min(np.linalg.norm(mesh.uv - corner, axis=1)) <= 1e-12


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    R=st.floats(1.0, 5.0),
    ratio=st.floats(0.05, 0.9),
    rel=st.sampled_from([3e-2, 1e-2, 3e-3, 1e-3]),
    reversed_=st.booleans(),
)
def test_torus_any_proportions(R, ratio, rel, reversed_):
    r = R * ratio
    face = primitives.torus(R, r).faces[0]
    if reversed_:
        face = TrimmedFace(face.surface, face.loops, reversed=True)
    mesh = sk.tessellate(face, rel, relative=True)
    assert mesh.is_closed and mesh.euler_characteristic == 0
    assert remeasured(mesh, [face]) <= mesh.tolerance * (1 + 1e-9)
    exact = 2 * math.pi**2 * R * r**2
    area = 4 * math.pi**2 * R * r
    signed = -exact if reversed_ else exact
    assert abs(mesh.volume - signed) <= area * mesh.tolerance
    assert abs(mesh.volume) < exact
