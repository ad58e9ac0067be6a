"""Continuity across shared edges (splinekit.analysis) against known answers: a cubic split at a
simple knot meets itself G2, a quarter cylinder on a plane is G1 with a curvature jump of 1/r, two
planes at a known angle, Catmull-Clark patches G2 away from and G1 at extraordinary vertices, B-rep
primitives with known edge angles, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from _geometry import random_knots, random_points
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.analysis import NoSharedEdgeError, edge_continuity, shell_continuity
from splinekit.errors import SplineKitError


def _plane(p0, p1, width=2.0):
    """The strip swept by the segment p0-p1 along +y (the u direction runs p0 -> p1)."""
    return sk.extrude(sk.line(p0, p1), [0.0, width, 0.0])


def _quarter_cylinder(r, width=2.0):
    """Quarter cylinder of radius r tangent to the plane z = 0 along the y axis, rising toward +x."""
    return sk.extrude(sk.arc([0.0, 0.0, r], [0.0, -1.0, 0.0], r, -np.pi / 2, 0.0, x_axis=[1.0, 0.0, 0.0]), [0.0, width, 0.0])


def _cubic_surface(seed):
    rng = np.random.default_rng(seed)
    ku = np.array([0, 0, 0, 0, 0.3, 0.55, 1, 1, 1, 1], dtype=float)
    kv = random_knots(rng, 3, n_spans=2)
    P = random_points(rng, (6, len(kv) - 4)) * 0.2
    P[..., 0] += np.arange(6)[:, None]
    P[..., 1] += np.arange(len(kv) - 4)[None, :]
    return sk.BSplineSurface(3, 3, ku, kv, P)


# -- known answers ---------------------------------------------------------------------------------
@settings(max_examples=15, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([0.3, 0.55]), st.booleans())
def test_split_at_simple_knot_is_g2(seed, knot, reverse):
    left, right = _cubic_surface(seed).split(knot, direction="u")
    if reverse:  # the neighbour's parametrization runs the other way along the edge
        right = right.reverse("v")
    e = edge_continuity(left, right, samples=33)
    assert e.level == "G2"
    assert e.sides == ("u1", "u0")
    scale = max(1.0, float(np.abs(e.normal_curvature).max()))
    assert e.max_gap < 1e-12 and e.max_angle < 1e-10 and e.max_curvature_jump < 1e-9 * scale
    assert e.flipped == reverse  # reversing v flips the normal: b is turned back to a's side


def test_split_at_a_new_double_knot_point_is_still_g2_and_a_kink_is_not():
    s = _cubic_surface(3)
    left, right = s.split(0.45, direction="u")  # not a knot: the geometry is the same C2 surface
    assert edge_continuity(left, right).level == "G2"
    # move the first interior row of the right piece up: the tangent plane turns
    P = np.array(right.control_points)
    P[1, :, 2] += 0.5
    bent = sk.BSplineSurface(3, 3, right.knots_u, right.knots_v, P)
    assert edge_continuity(left, bent).level == "G0"


@pytest.mark.parametrize("r", [0.25, 0.7, 3.0])
def test_quarter_cylinder_on_a_plane_is_g1_with_jump_one_over_r(r):
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    cyl = _quarter_cylinder(r)
    e = edge_continuity(plane, cyl, samples=40)
    assert e.level == "G1"
    assert e.max_gap < 1e-14 and e.max_angle < 1e-14
    assert np.allclose(e.curvature_jump, 1.0 / r, rtol=1e-12, atol=0)
    # the plane has none; the cylinder bends toward the plane's upward normal
    assert np.allclose(e.normal_curvature[:, 0], 0.0, atol=1e-12)
    assert np.allclose(np.abs(e.normal_curvature[:, 1]), 1.0 / r, rtol=1e-12)
    assert np.allclose(e.curvature_vector_jump, 1.0 / r, rtol=1e-12)
    assert set(e.sample_levels) == {"G1"}


@pytest.mark.parametrize("slope", [0.1, 0.5, 2.0, -1.0])
def test_kinked_planes_report_the_angle(slope):
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    other = _plane([0.0, 0.0, 0.0], [1.0, 0.0, slope])
    e = edge_continuity(other, plane)  # any order
    assert e.level == "G0"
    assert np.allclose(e.angle, abs(np.arctan(slope)), atol=1e-13)


def test_gap_makes_level_none_and_is_measured():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    lifted = _plane([0.0, 0.0, 1e-4], [1.0, 0.0, 1e-4])
    e = edge_continuity(plane, lifted)
    assert e.level == "none"
    assert np.allclose(e.gap, 1e-4, rtol=1e-9)
    assert edge_continuity(plane, lifted, gap_tol=2e-4).level == "G2"


def test_transposed_reversed_and_partial_neighbours():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    other = _plane([0.0, 0.0, 0.0], [1.0, 0.0, 0.5])
    e = edge_continuity(plane, other.reverse("v").transpose())
    assert e.sides == ("u1", "v0") and e.level == "G0"
    assert np.allclose(e.angle, np.arctan(0.5), atol=1e-13)
    # a neighbour along the middle half of the edge (a T-junction): sampled on the shorter side,
    # reported with a's parameters
    half = sk.extrude(sk.line([0.0, 0.5, 0.0], [1.0, 0.5, 0.5]), [0.0, 1.0, 0.0])
    e = edge_continuity(plane, half)
    assert np.allclose(sorted(e.params[[0, -1]]), [0.25, 0.75], atol=1e-12)
    assert np.allclose(e.uv[:, 0, 0], 1.0) and np.allclose(e.uv[:, 1, 0], 0.0)
    assert np.allclose(sorted(e.points[[0, -1], 1]), [0.5, 1.5]) and np.allclose(e.points[:, [0, 2]], 0.0)


def test_given_edge_and_tolerances():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    cyl = _quarter_cylinder(0.5)
    e = edge_continuity(plane, cyl, edge=("u1", "u0"), samples=5)
    assert e.params.shape == (5,) and e.level == "G1"
    assert edge_continuity(plane, cyl, curvature_tol=10.0).level == "G2"
    assert edge_continuity(plane, cyl, angle_tol=1e-12, gap_tol=1e-12).level == "G1"
    assert edge_continuity(plane, _plane([0.0, 0.0, 0.0], [1.0, 0.0, 0.01]), angle_tol=0.02).level == "G2"


def _cube_patches():
    cube = sk.PolyMesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float),
                       np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]))
    fine = sk.subdivide(cube, "catmull-clark", levels=2)  # 96 quads; the 8 cube corners stay valence 3
    return fine, sk.SubdivisionSurface(fine, "catmull-clark")


def test_catmull_clark_is_g2_away_from_and_g1_at_extraordinary_vertices():
    mesh, surface = _cube_patches()
    F = np.asarray(mesh.faces)
    valence = np.bincount(F.ravel())
    extraordinary = set(np.flatnonzero(valence == 3).tolist())
    edges = {}
    for f, quad in enumerate(F):
        for k in range(4):
            edges.setdefault(tuple(sorted((int(quad[k]), int(quad[(k + 1) % 4])))), []).append(f)
    at_ev = [(k, fs) for k, fs in edges.items() if set(k) & extraordinary]
    away = [(k, fs) for k, fs in edges.items() if not (set(F[fs[0]]) | set(F[fs[1]])) & extraordinary]
    for _, (f, g) in away[:3]:
        e = edge_continuity(sk.SubdivisionPatch(surface, f), sk.SubdivisionPatch(surface, g), samples=9)
        assert e.level == "G2" and not e.singular.any()
    for _, (f, g) in at_ev[:3]:
        e = edge_continuity(sk.SubdivisionPatch(surface, f), sk.SubdivisionPatch(surface, g), samples=9)
        assert e.level == "G1"
        assert e.extraordinary.sum() == 1 and e.extraordinary[[0, -1]].any()  # the vertex end
        assert (e.sample_levels[~e.extraordinary] == "G2").all()
        assert e.angle[e.extraordinary][0] < 1e-12  # the exact limit normal, shared by both patches


def test_shell_continuity_of_brep_primitives():
    box = shell_continuity(sk.brep.box(1.0, 2.0, 3.0), samples=8)
    assert box.summary["edges"] == 12 and box.summary["G0"] == 12 and box.free_edges == 0
    assert np.allclose(box.max_angle, np.pi / 2, atol=1e-12)
    cyl = shell_continuity(sk.brep.cylinder(1.0, 2.0), samples=16)
    levels = sorted(cyl.levels.tolist())
    assert levels == ["G0", "G0", "G2"]  # the two rims at right angles, the seam smooth
    seam = cyl.edges[int(np.flatnonzero(cyl.levels == "G2")[0])]
    assert seam.patches[0] == seam.patches[1]
    assert np.allclose(np.abs(seam.normal_curvature), 1.0, rtol=1e-9)  # across the seam: the circle


def test_sphere_seam_through_the_poles_is_flagged_not_nan():
    face = sk.brep.sphere(2.0).faces[0]
    e = edge_continuity(face, face)  # the seam meridian, pole to pole
    assert e.singular[0] and e.singular[-1] and not e.singular[1:-1].any()
    for a in (e.gap, e.angle, e.normal_curvature, e.curvature_jump):
        assert np.isfinite(a).all()
    assert np.allclose(e.normal_curvature, -0.5, rtol=1e-6)  # outward normal: the sphere bends away
    assert e.level == "G2"


def test_shell_continuity_of_a_patch_list_and_a_subdivision_surface():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    r = shell_continuity([plane, _quarter_cylinder(0.5), _plane([2.0, 0.0, 0.0], [3.0, 0.0, 0.0])], samples=8)
    assert r.summary["edges"] == 1 and r.levels.tolist() == ["G1"] and r.faces.tolist() == [[0, 1]]
    assert r.free_edges == 3 + 3 + 4
    _, surface = _cube_patches()
    s = shell_continuity(surface, samples=5)
    assert s.summary["edges"] == 192 and s.free_edges == 0  # a closed quad mesh: 2 F edges
    # the 8 valence-3 vertices have 3 edges each; every other edge is G2
    assert s.summary["G1"] == 24 and s.summary["G2"] == 168
    assert "shared edges" in s.table()


# -- bad input -------------------------------------------------------------------------------------
def test_faces_that_share_no_edge():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(NoSharedEdgeError, match="share no edge"):
        edge_continuity(plane, _plane([5.0, 0.0, 0.0], [6.0, 0.0, 0.0]))
    assert issubclass(NoSharedEdgeError, SplineKitError)


def test_bad_arguments_name_the_problem():
    plane = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    cyl = _quarter_cylinder(0.5)
    for kwargs, match in [({"samples": 1}, "samples"), ({"gap_tol": -1.0}, "gap_tol"), ({"angle_tol": np.nan}, "angle_tol"),
                          ({"curvature_tol": "x"}, "curvature_tol"), ({"edge": ("u7", "u0")}, "u7"),
                          ({"edge": (9, 0)}, "outside"), ({"edge": "u1"}, "pair")]:
        with pytest.raises(SplineKitError, match=match):
            edge_continuity(plane, cyl, **kwargs)
    with pytest.raises(SplineKitError, match="parametric surface"):
        edge_continuity(plane, sk.line([0, 0, 0], [1, 0, 0]))
    flat = sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], [[[0, 0], [0, 1]], [[1, 0], [1, 1]]])
    with pytest.raises(SplineKitError, match="3-D"):
        edge_continuity(flat, plane)
    with pytest.raises(SplineKitError, match="empty"):
        shell_continuity([])
    with pytest.raises(SplineKitError, match="Shell"):
        shell_continuity(3)


def test_non_finite_surface_values_are_refused():
    def f(u, v):
        out = np.column_stack([u, v, np.zeros_like(u)])
        out[u > 0.5, 2] = np.nan
        return out

    bad = sk.ParametricSurface(f, domain=((0.0, 1.0), (0.0, 1.0)))
    good = _plane([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], width=1.0).transpose()
    with pytest.raises(SplineKitError, match="not finite|non-finite"):
        edge_continuity(bad, good)


def test_batched_subdivision_edges_agree_with_the_generic_matcher():
    _, surface = _cube_patches()
    batch = {tuple(sorted(e.patches)): e for e in shell_continuity(surface, samples=7).edges}
    generic = shell_continuity(sk.analysis.shell.subdivision_patches(surface)[:6], samples=7)
    assert generic.summary["edges"] >= 3
    for e in generic.edges:
        b = batch[tuple(sorted(e.patches))]
        assert e.level == b.level
        assert np.allclose(np.sort(np.abs(e.normal_curvature).ravel()), np.sort(np.abs(b.normal_curvature).ravel()), atol=1e-9)
        assert abs(e.max_curvature_jump - b.max_curvature_jump) < 1e-9 and abs(e.max_angle - b.max_angle) < 1e-12


@pytest.mark.parametrize("name", ["teapot", "vase", "mug", "bracket", "wing", "block"])
def test_every_model_is_analysed(name):
    from models import MODELS, build_model

    assert set(MODELS) == {"teapot", "vase", "mug", "bracket", "wing", "block"}  # a new model joins this list
    model = build_model(name)
    parts = list(model.bodies) + list(model.solids)
    assert parts
    for part in parts:
        r = shell_continuity(part, samples=5)
        assert r.summary["edges"] > 0 and r.summary["none"] == 0  # sewn parts: every shared edge closes G0
        for e in r.edges:
            for a in (e.gap, e.angle, e.normal_curvature, e.curvature_jump, e.curvature_vector_jump):
                assert np.isfinite(a).all()
        if model.closed:
            assert r.free_edges == 0
