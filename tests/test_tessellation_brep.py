"""Tessellation of trimmed faces, shells and solids: watertight, oriented, within the tolerance.

Judged against things the tessellator does not compute: closed-form volumes and areas, the
surfaces' own evaluators at the triangles' barycentric (u, v) (the chordal deviation), exact
distances to the analytic sphere / torus / cylinder, and the topology (Euler characteristic) of
the solids.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.brep import Edge, Shell, Solid, TrimmedFace, primitives
from splinekit.construct.curves import line
from splinekit.errors import SplineKitError

import _brep_shapes as shapes

BARY = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])


def measured_deviation(mesh, faces):
    """Largest distance between each face's own surface at the barycentric (u, v) of every
    triangle's centre and edge midpoints and the flat triangle's point there."""
    F = np.asarray(mesh.faces)
    X = mesh.vertices[F]
    worst = 0.0
    for f in np.unique(mesh.face_patch):
        sel = np.flatnonzero(mesh.face_patch == f)
        uv = np.einsum("bj,fjd->fbd", BARY, mesh.corner_uv[sel]).reshape(-1, 2)
        flat = np.einsum("bj,fjd->fbd", BARY, X[sel]).reshape(-1, 3)
        exact = faces[f].surface.evaluate(uv[:, 0], uv[:, 1])
        worst = max(worst, float(np.linalg.norm(exact - flat, axis=1).max()))
    return worst


def flat_points(mesh):
    F = np.asarray(mesh.faces)
    return np.einsum("bj,fjd->fbd", BARY, mesh.vertices[F]).reshape(-1, 3)


R_SPHERE, R_MAJOR, R_MINOR = 1.5, 2.0, 0.6
SOLIDS = {
    # name: (factory, exact volume, exact area, genus)
    "sphere": (lambda: primitives.sphere(R_SPHERE), 4 / 3 * math.pi * R_SPHERE**3, 4 * math.pi * R_SPHERE**2, 0),
    "torus": (lambda: primitives.torus(R_MAJOR, R_MINOR), 2 * math.pi**2 * R_MAJOR * R_MINOR**2,
              4 * math.pi**2 * R_MAJOR * R_MINOR, 1),  # fmt: skip
    "cylinder": (lambda: primitives.cylinder(1.0, 3.0), 3 * math.pi, 8 * math.pi, 0),
    "cone": (lambda: primitives.cone(1.0, 0.0, 2.0), 2 * math.pi / 3, math.pi * (1 + math.sqrt(5)), 0),
    "box_with_hole": (lambda: primitives.box_with_hole(20.0, 4.0), 20**3 - math.pi * 16 * 20,
                      6 * 400 + 2 * math.pi * 4 * 20 - 2 * math.pi * 16, 1),  # fmt: skip
    "plate_with_holes": (lambda: primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4), (28, 20, 5), (33, 8, 2.5)]),
                         40 * 30 * 5 - math.pi * 5 * (16 + 25 + 6.25),
                         2 * (1200 + 200 + 150) + sum(2 * math.pi * r * 5 - 2 * math.pi * r * r for r in (4, 5, 2.5)), 3),  # fmt: skip
    # keyless edges on natural-domain faces: paired geometrically by the tessellator
    "sphere_natural": (lambda: shapes.sphere(1.0)[0], 4 / 3 * math.pi, 4 * math.pi, 0),
    "torus_natural": (lambda: shapes.torus(2.0, 0.6)[0], 2 * math.pi**2 * 2.0 * 0.36, 4 * math.pi**2 * 2.0 * 0.6, 1),
    "cylinder_keyless": (lambda: shapes.cylinder(1.0, 3.0)[0], 3 * math.pi, 8 * math.pi, 0),
    "box_with_holes_keyless": (lambda: shapes.plate_with_holes()[0], shapes.plate_with_holes()[1], shapes.plate_with_holes()[2], 3),
}


@pytest.mark.parametrize("rel", [1e-3, 1e-4])
@pytest.mark.parametrize("name", sorted(SOLIDS))
def test_solid_closed_oriented_within_tolerance(name, rel):
    make, volume, area, genus = SOLIDS[name]
    solid = make()
    mesh = sk.tessellate(solid, rel, relative=True)
    tol = mesh.tolerance
    assert mesh.is_closed
    assert mesh.euler_characteristic == 2 - 2 * genus
    dev = measured_deviation(mesh, solid.faces)
    assert dev <= tol * (1 + 1e-9)
    assert mesh.max_deviation <= tol * (1 + 1e-9)
    assert abs(mesh.max_deviation - dev) <= 1e-9 * tol + 1e-12  # the same yardstick
    # outward: positive volume within the bound the tolerance implies
    assert mesh.volume > 0
    assert abs(mesh.volume - volume) <= area * tol
    # every triangle faces like its face's exact outward normal at the triangle's centre
    F = np.asarray(mesh.faces)
    X = mesh.vertices[F]
    fn = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    uv = mesh.corner_uv.mean(axis=1)
    exact = np.empty_like(fn)
    for f in np.unique(mesh.face_patch):
        sel = mesh.face_patch == f
        exact[sel] = solid.faces[f].normals(uv[sel, 0], uv[sel, 1])
    assert (np.einsum("fj,fj->f", fn, exact) > 0).all()


def test_geometric_deviation_against_the_analytic_surfaces():
    tol = 1e-3
    for solid, dist in (
        (primitives.sphere(R_SPHERE), lambda p: np.abs(np.linalg.norm(p, axis=1) - R_SPHERE)),
        (primitives.torus(R_MAJOR, R_MINOR),
         lambda p: np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - R_MAJOR, p[:, 2]) - R_MINOR)),  # fmt: skip
    ):
        mesh = sk.tessellate(solid, tol)
        d = dist(flat_points(mesh))
        assert d.max() <= tol
        assert d.max() > 0.2 * tol  # not far finer than asked


def test_triangle_count_scales_like_the_inverse_tolerance():
    # on a doubly curved surface the triangle count grows like 1 / tol
    solid = primitives.sphere(1.0)
    n1 = sk.tessellate(solid, 1e-3).n_faces
    n2 = sk.tessellate(solid, 1e-4).n_faces
    assert 5 < n2 / n1 < 20


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
def test_planar_faces_need_no_interior_points(rel):
    # a box: six rectangles, two triangles each, at every tolerance
    mesh = sk.tessellate(primitives.box(2.0, 3.0, 5.0), rel, relative=True)
    assert (mesh.n_faces, len(mesh.vertices)) == (12, 8)
    assert mesh.max_deviation <= 1e-14 * 6.2  # planes: rounding only
    assert math.isclose(mesh.volume, 30.0, rel_tol=1e-12)
    # a box with a through hole: every vertex is a corner of the box or lies on the hole's
    # circle (the planar faces are triangulated from their trims alone), and the volume lies
    # within the bound the tolerance gives
    make, volume, area, _ = SOLIDS["box_with_hole"]
    mesh = sk.tessellate(make(), rel, relative=True)
    V = mesh.vertices
    corner = (np.abs(np.abs(V) - 10.0) < 1e-9).all(axis=1)
    on_hole = np.abs(np.hypot(V[:, 0], V[:, 1]) - 4.0) < 1e-9
    assert (corner | on_hole).all()
    assert corner.sum() == 8
    assert mesh.is_closed and abs(mesh.volume - volume) <= area * mesh.tolerance


def test_batch_evaluator_matches_each_surfaces_own_evaluator():
    # the tessellator's batch evaluator (every face at once, in blocks of CHUNK queries) against
    # each surface's own evaluate / derivatives
    from splinekit.tessellation.batch import CHUNK, SPARSE_FROM, SurfaceBatch

    rng = np.random.default_rng(3)
    surfaces = [f.surface for f in primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4)]).faces]
    surfaces += [primitives.sphere(1.5).faces[0].surface, primitives.torus(2.0, 0.6).faces[0].surface]
    g = np.linspace(0.0, 1.0, 7)
    net = np.stack([*np.meshgrid(g, g, indexing="ij"), 0.2 * rng.standard_normal((7, 7))], axis=-1)
    surfaces.append(sk.NurbsSurface(3, 2, [0, 0, 0, 0, 0.3, 0.6, 0.8, 1, 1, 1, 1], [0, 0, 0, 0.2, 0.4, 0.5, 0.7, 1, 1, 1],
                                    net, rng.uniform(0.5, 2.0, (7, 7))))  # fmt: skip
    batch = SurfaceBatch(surfaces)
    dom = np.array([s.domain for s in surfaces])
    assert 300 < SPARSE_FROM < 2 * CHUNK // 10
    for n in (300, 2 * CHUNK + 123):  # gathered nets for small blocks, sparse products for large ones
        k = rng.integers(0, len(surfaces), n)
        u = rng.uniform(dom[k, 0, 0], dom[k, 0, 1])
        v = rng.uniform(dom[k, 1, 0], dom[k, 1, 1])
        X = batch.evaluate(k, u, v)
        S, Su, Sv = batch.partials(k, u, v)
        for i, s in enumerate(surfaces):
            sel = k == i
            D = s.derivatives(u[sel], v[sel], 1)
            scale = np.abs(s.control_points).max()
            for got, want in ((X[sel], D[0, 0]), (S[sel], D[0, 0]), (Su[sel], D[1, 0]), (Sv[sel], D[0, 1])):
                np.testing.assert_allclose(got, want, rtol=0, atol=1e-11 * scale * max(1.0, np.abs(want).max() / scale))


def test_curve_batch_matches_each_curves_own_derivatives():
    # the pcurve batch (used to project edge samples onto every face's pcurve at once) against
    # each curve's own evaluate / derivatives: rational and polynomial, several spans and degrees
    from splinekit.tessellation.batch import CurveBatch

    rng = np.random.default_rng(5)
    curves = [sk.NurbsCurve(2, [0, 0, 0, 0.5, 0.5, 1, 1, 1], rng.standard_normal((5, 2)), rng.uniform(0.5, 2.0, 5)),
              sk.BSplineCurve(3, [0, 0, 0, 0, 0.2, 0.7, 1, 1, 1, 1], rng.standard_normal((6, 2))),
              line((0.0, 1.0), (2.0, -1.0))]  # fmt: skip
    batch = CurveBatch(curves)
    k = rng.integers(0, len(curves), 500)
    dom = np.array([c.domain for c in curves])
    t = rng.uniform(dom[k, 0], dom[k, 1])
    C, dC = batch.partials(k, t)
    np.testing.assert_array_equal(C, batch.evaluate(k, t))
    for i, c in enumerate(curves):
        D = c.derivatives(t[k == i], 1)
        np.testing.assert_allclose(C[k == i], D[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(dC[k == i], D[1], rtol=0, atol=1e-11 * max(1.0, np.abs(D[1]).max()))


def test_shared_edges_use_the_same_vertices():
    solid = primitives.box_with_hole(20.0, 4.0)
    mesh = sk.tessellate(solid, 1e-2)
    # every mesh edge is used by exactly two triangles, and no two vertices coincide
    F = np.asarray(mesh.faces)
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert (counts == 2).all()
    V = np.round(mesh.vertices / 1e-9)
    assert len(np.unique(V, axis=0)) == len(V)


def test_reversed_faces_turn_the_mesh_inside_out():
    solid = primitives.cylinder(1.0, 2.0)
    inward = Solid(Shell([f.flipped() for f in solid.faces]))
    a = sk.tessellate(solid, 1e-3)
    b = sk.tessellate(inward, 1e-3)
    assert b.is_closed and a.n_faces == b.n_faces
    assert b.volume == pytest.approx(-a.volume, rel=1e-12)


def test_single_trimmed_face_and_lists():
    solid = primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4), (28, 20, 5)])
    top = next(f for f in solid.faces if f.name == "top")
    mesh = sk.tessellate(top, 1e-2)
    assert not mesh.is_closed
    area = 1200 - math.pi * (16 + 25)
    assert abs(mesh.area - area) <= 1e-2 * 2 * math.pi * 9 * 1.01  # chords cut off at most tol per unit of trim length
    F = np.asarray(mesh.faces)
    assert np.allclose(mesh.vertices[F][:, :, 2], 5.0)
    # a list of faces and a list of solids
    both = sk.tessellate([solid, primitives.sphere(1.0, center=(100, 0, 0))], 1e-2)
    assert both.is_closed
    assert both.euler_characteristic == (2 - 2 * 2) + 2


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    x=st.floats(8.0, 32.0), y=st.floats(8.0, 22.0), r=st.floats(0.5, 6.0),
    rel=st.sampled_from([3e-3, 1e-3, 3e-4]),
)  # fmt: skip
def test_plate_with_a_random_hole(x, y, r, rel):
    solid = primitives.plate_with_holes(40.0, 30.0, 4.0, [(x, y, min(r, x - 0.5, y - 0.5, 39.5 - x, 29.5 - y))])
    mesh = sk.tessellate(solid, rel, relative=True)
    assert mesh.is_closed and mesh.euler_characteristic == 0
    assert measured_deviation(mesh, solid.faces) <= mesh.tolerance * (1 + 1e-9)


# -- bad input ------------------------------------------------------------------------------


def _plane():
    return shapes.plane([0, 0, 0], [1, 0, 0], [0, 1, 0])


def _square(a=0.1, b=0.9):
    c = np.array([[a, a], [b, a], [b, b], [a, b]])
    return [line(c[k], c[(k + 1) % 4]) for k in range(4)]


def test_open_loop_names_the_face():
    c = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.8]])
    loop = [line(c[k], c[k + 1]) for k in range(3)] + [line([0.1, 0.9], [0.1, 0.1])]
    face = TrimmedFace(_plane(), [loop], name="lid")
    with pytest.raises(SplineKitError, match=r"face 0 \('lid'\).*not closed"):
        sk.tessellate(face, 1e-3)


def test_loop_facing_the_wrong_way_names_the_face():
    ok = TrimmedFace(_plane(), [_square()])
    bad = TrimmedFace(_plane(), [[e.reverse() for e in reversed(_square())]], name="upside")
    sk.tessellate(ok, 1e-3)
    with pytest.raises(SplineKitError, match=r"face 1 \('upside'\).*wrong way"):
        sk.tessellate([ok, bad], 1e-3)


def test_hole_facing_the_wrong_way():
    face = TrimmedFace(_plane(), [_square(0.0, 1.0), _square(0.3, 0.6)])  # hole counter-clockwise
    with pytest.raises(SplineKitError, match="face 0.*loop 1.*wrong way"):
        sk.tessellate(face, 1e-3)


def test_loop_leaving_the_domain():
    face = TrimmedFace(_plane(), [_square(0.5, 1.5)])
    with pytest.raises(SplineKitError, match="face 0.*leaves the surface's domain"):
        sk.tessellate(face, 1e-3)


def test_crossing_loops():
    hole_a = [e.reverse() for e in reversed(_square(0.2, 0.6))]
    hole_b = [e.reverse() for e in reversed(_square(0.4, 0.8))]
    face = TrimmedFace(_plane(), [_square(0.0, 1.0), hole_a, hole_b], name="sieve")
    with pytest.raises(SplineKitError, match=r"face 0 \('sieve'\).*cross"):
        sk.tessellate(face, 1e-3)


def test_self_crossing_loop():
    c = np.array([[0.1, 0.1], [0.9, 0.9], [0.9, 0.1], [0.1, 0.9]])  # a bow tie
    loop = [line(c[k], c[(k + 1) % 4]) for k in range(4)]
    with pytest.raises(SplineKitError, match="face 0"):
        sk.tessellate(TrimmedFace(_plane(), [loop]), 1e-3)


def test_hole_outside_the_outer_loop():
    outer = _square(0.0, 0.4)
    hole = [e.reverse() for e in reversed(_square(0.6, 0.9))]
    with pytest.raises(SplineKitError, match="face 0.*loop 1 bounds no material"):
        sk.tessellate(TrimmedFace(_plane(), [outer, hole]), 1e-3)


def test_mixed_list_is_refused():
    with pytest.raises(SplineKitError, match="item 1"):
        sk.tessellate([primitives.sphere(1.0), _plane()], 1e-3)


def test_edges_with_explicit_keys_and_curves_pair_with_keyless_ones():
    # a cylinder whose caps carry keyed edges with 3-D curves and whose side is natural-domain
    solid = primitives.cylinder(1.0, 2.0)
    side = next(f for f in solid.faces if f.name == "side")
    natural = TrimmedFace(side.surface, reversed=side.reversed)
    caps = [f for f in solid.faces if f.name != "side"]
    caps = [TrimmedFace(f.surface, [[Edge(e.pcurve, e.curve) for e in f.outer_loop]], f.reversed) for f in caps]
    mesh = sk.tessellate(Solid(Shell([natural] + caps)), 1e-3)
    assert mesh.is_closed and mesh.euler_characteristic == 2
    assert abs(mesh.volume - 2 * math.pi) <= 6 * math.pi * 1e-3


def test_cached_preparation_reused_only_for_the_same_face_set():
    """The tolerance-independent preparation is cached on the first face: a repeated call gives
    the very same mesh, another tolerance a valid one, and the same faces in another order (a
    different face set for the cache) a mesh whose face indices follow the new order."""
    solid = primitives.box_with_hole(20.0, 4.0)
    faces = list(solid.faces)
    first = sk.tessellate(solid, 0.05)
    again = sk.tessellate(solid, 0.05)
    np.testing.assert_array_equal(first.vertices, again.vertices)
    np.testing.assert_array_equal(np.asarray(first.faces), np.asarray(again.faces))
    fine = sk.tessellate(solid, 0.01)
    assert fine.is_closed and fine.max_deviation <= 0.01 and measured_deviation(fine, faces) <= 0.01 * (1 + 1e-9)
    order = faces[::-1]
    shuffled = sk.tessellate(order, 0.05)
    assert shuffled.is_closed and measured_deviation(shuffled, order) <= 0.05 * (1 + 1e-9)
    _, volume, area, _ = SOLIDS["box_with_hole"]
    assert abs(shuffled.volume - volume) <= area * 0.05 and abs(first.volume - volume) <= area * 0.05


@pytest.mark.parametrize("lift", [0.0, 0.004, 0.009])
def test_edges_off_their_face_by_their_tolerance_do_not_blow_up_the_mesh(lift):
    """Some CAD exports give edges a tolerance of 1e-2 and 3-D curves that far off the face (the
    NX part in the shared STEP set). The mesh cannot come closer to the surface than its boundary,
    so such edges must not be refined round after round (they made 50,000 samples and 2.7 million
    triangles on one cylinder face at 1e-3): the triangle count stays that of exact edges, and
    every interior sample still meets the tolerance plus the boundary's own offset."""
    a, b = 10.0, 6.0
    corners = np.array([[0.0, 0.0], [a, 0.0], [a, b], [0.0, b]])
    plane = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                              np.array([[[0, 0, 0], [0, b, 0]], [[a, 0, 0], [a, b, 0]]], dtype=float))
    edges = []
    for k in range(4):
        p, q = corners[k], corners[(k + 1) % 4]
        # the 3-D curve is lifted off the plane z = 0 by `lift` in its middle (ends on the corners)
        mid = np.append(0.5 * (p + q), lift)
        curve = sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([np.append(p, 0.0), 2 * mid - 0.5 * np.append(p + q, 0.0), np.append(q, 0.0)]))
        edges.append(Edge(line(p / [a, b], q / [a, b]), curve, tolerance=0.01))
    face = TrimmedFace(plane, [edges], tolerance=0.01)
    mesh = sk.tessellate(face, 1e-3)
    assert len(mesh.faces) <= 400
    # the exact plane and its mesh: interior vertices lie on z = 0, boundary ones at most `lift` off
    assert np.abs(mesh.vertices[:, 2]).max() <= lift + 1e-12
    assert mesh.area == pytest.approx(a * b, rel=1e-3 + 2 * lift)
