"""Validity checks of trimmed faces, shells and solids: every bad-input kind of issue 12 (trims not
closed, leaving the domain, crossing, facing the wrong way; open shells passed as solids) gives
its named problem, and the raising helper raises a SplineKitError naming the face."""

from __future__ import annotations

import numpy as np
import pytest

from splinekit.brep import Edge, Shell, Solid, TrimmedFace, box, box_with_hole, cone, cylinder, plate_with_holes, sphere, torus
from splinekit.brep.check import Problem
from splinekit.construct import circle, line
from splinekit.curves import NurbsCurve
from splinekit.errors import BRepError, SplineKitError, TrimError
from splinekit.surfaces import BSplineSurface

PLANE = BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                       np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float))


def square(pts):
    return [line(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]


OUTER = square([(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9)])


@pytest.mark.parametrize("solid", [box(1, 2, 3), cylinder(2, 5), cone(2, 0, 3), cone(1, 2, 3), sphere(3), torus(5, 1),
                                   box_with_hole(20, 4), plate_with_holes(30, 20, 5, [(5, 5, 2), (20, 10, 4)])],
                         ids=lambda s: s.name)
def test_primitives_are_valid(solid):
    assert solid.check() == [] and solid.is_valid
    assert solid.validated() is solid
    for f in solid.faces:
        assert f.is_valid


BAD_FACES = {
    "open-loop": [OUTER[:3] + [line((0.1, 0.9), (0.1, 0.2))]],
    "trim-outside-domain": [square([(0.1, 0.1), (1.2, 0.1), (0.9, 0.9), (0.1, 0.9)])],
    "wrong-loop-orientation": [square([(0.1, 0.1), (0.1, 0.9), (0.9, 0.9), (0.9, 0.1)])],
    "self-intersecting-loop": [square([(0.1, 0.1), (0.9, 0.9), (0.9, 0.1), (0.1, 0.9)])],
    "crossing-loops": [OUTER, square([(0.3, 0.3), (0.3, 0.95), (0.6, 0.95), (0.6, 0.3)][::-1])[::-1]],
    "inner-loop-outside": [square([(0.1, 0.1), (0.5, 0.1), (0.5, 0.5), (0.1, 0.5)]), [circle((0.75, 0.75), None, 0.1).reverse()]],
}


@pytest.mark.parametrize("kind", list(BAD_FACES))
def test_each_bad_trim_is_named_and_raises(kind):
    face = TrimmedFace(PLANE, BAD_FACES[kind], name="lid")
    problems = face.check()
    assert kind in {p.kind for p in problems}, problems
    assert not face.is_valid
    with pytest.raises(TrimError, match="'lid'") as info:
        face.raise_if_invalid()
    assert isinstance(info.value, SplineKitError)
    # inside a solid the message names the face's index and name
    b = box(1, 1, 1)
    shell = Shell([face] + list(b.faces))
    with pytest.raises(TrimError, match=r"face 0 'lid'"):
        shell.raise_if_invalid()


def test_measured_values():
    gap = TrimmedFace(PLANE, BAD_FACES["open-loop"]).check()
    p = next(p for p in gap if p.kind == "open-loop")
    assert p.value == pytest.approx(0.1) and p.where == {"loop": 0, "edge": 3}
    out = next(p for p in TrimmedFace(PLANE, BAD_FACES["trim-outside-domain"]).check() if p.kind == "trim-outside-domain")
    assert out.value == pytest.approx(0.2)  # the plane is 1 x 1: (u, v) is length
    wrong = TrimmedFace(PLANE, BAD_FACES["wrong-loop-orientation"]).check()
    assert wrong[0].value == pytest.approx(-0.64)  # the square's area, negative: clockwise
    # an inner loop turned counter-clockwise: named as loop 1
    ccw_hole = TrimmedFace(PLANE, [OUTER, [circle((0.5, 0.5), None, 0.2)]]).check()
    assert [(p.kind, p.loop) for p in ccw_hole] == [("wrong-loop-orientation", 1)]
    assert ccw_hole[0].value == pytest.approx(np.pi * 0.04, rel=1e-3)


def test_open_loop_measured_in_3d_through_the_surface():
    """A gap of 1e-3 in (u, v) on a surface 1000 units wide is a 1-unit gap in 3-D."""
    big = BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                         1000.0 * np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float))
    loop = OUTER[:3] + [line((0.1, 0.9), (0.1, 0.101))]
    p = TrimmedFace(big, [loop]).check()
    assert p[0].kind == "open-loop" and p[0].value == pytest.approx(1.0)
    # within tolerance: not a problem
    loop = OUTER[:3] + [line((0.1, 0.9), (0.1, 0.1 + 1e-12))]
    assert TrimmedFace(big, [loop], tolerance=1e-7).check() == []


def test_pcurve_off_its_3d_curve():
    b = box_with_hole(20, 4)
    top = b.faces[1]
    hole = top.inner_loops[0][0]
    c = hole.curve
    moved = NurbsCurve(c.degree, c.knots, c.control_points + [0.0, 0.0, 1e-3], c.weights)
    bad = TrimmedFace(top.surface, [top.loops[0], [Edge(hole.pcurve, moved, key=hole.key)]], name="top")
    problems = bad.check()
    assert [p.kind for p in problems] == ["pcurve-deviation"] and problems[0].value == pytest.approx(1e-3)


def test_open_shell_as_solid_and_inward_solid():
    b = box(1, 1, 1)
    open_solid = Solid(Shell(b.faces[:5]))
    assert [p.kind for p in open_solid.check()] == ["open-shell"]
    assert open_solid.check()[0].value == 4
    with pytest.raises(BRepError, match="open") as info:
        open_solid.raise_if_invalid()
    assert not isinstance(info.value, TrimError)
    # a shell alone may be open
    assert Shell(b.faces[:5]).is_valid
    inward = Solid(Shell([f.flipped() for f in b.faces]))
    assert [p.kind for p in inward.check()] == ["inward-shell"]
    assert inward.check()[0].value == pytest.approx(-1.0, rel=1e-9)
    # a void shell must point into the void
    outer = box(4, 4, 4, origin=(-2, -2, -2)).outer_shell
    void = Shell([f.flipped() for f in sphere(1).faces])
    assert Solid([outer, void]).is_valid
    bad = Solid([outer, sphere(1).outer_shell])
    assert [p.kind for p in bad.check()] == ["inward-shell"]


def test_inconsistent_orientation_names_both_faces():
    b = box(1, 1, 1)
    s = Solid(Shell([b.faces[0].flipped()] + list(b.faces[1:])))
    kinds = {p.kind for p in s.check()}
    assert kinds == {"inconsistent-orientation"}
    with pytest.raises(BRepError, match="'bottom'"):
        s.raise_if_invalid()
    # an edge shared by three faces
    s3 = Shell(list(b.faces) + [b.faces[0].flipped()])
    assert "non-manifold-edge" in {p.kind for p in s3.check()}


def test_problem_is_a_frozen_record():
    p = Problem("open-loop", "m", 1.0, face=2, loop=0)
    with pytest.raises(AttributeError):
        p.kind = "x"
    assert p.where == {"face": 2, "loop": 0}


def test_pcurve_deviation_tells_a_parameter_mismatch_from_a_wrong_curve():
    """The same segment traversed with another parametrization is 'only the parameters differ';
    a displaced segment is not."""
    from splinekit.curves import BSplineCurve

    plane_face = box(1, 1, 1).faces[1]  # the top face: (u, v) = (x, y) at z = 1
    loop = list(plane_face.loops[0])
    e = loop[0]
    a, b = e.curve.evaluate(0.0), e.curve.evaluate(1.0)
    # a quadratic with its middle control point off centre: same segment, other speed
    skewed = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, a + 0.8 * (b - a), b]))
    face = TrimmedFace(plane_face.surface, [[Edge(e.pcurve, skewed, key=e.key)] + loop[1:]], name="top")
    (p,) = face.check()
    assert p.kind == "pcurve-deviation" and "only the parameters differ" in p.message
    moved = BSplineCurve(1, [0, 0, 1, 1], np.array([a, b]) + [0.0, 0.0, 0.01])
    (p,) = TrimmedFace(plane_face.surface, [[Edge(e.pcurve, moved, key=e.key)] + loop[1:]]).check()
    assert p.kind == "pcurve-deviation" and "only the parameters" not in p.message
    assert p.value == pytest.approx(0.01)


@pytest.mark.parametrize("clearance, touches", [(0.07, False), (0.01, False), (-0.01, True)])
def test_a_hole_near_a_large_arc_is_judged_on_the_arcs_not_their_chords(clearance, touches):
    """The NX plate of the shared STEP set has a slot 0.07 inside its outer circle of radius
    47.5; the check's polyline of that circle (24 chords per quarter arc) cuts inside it by up to
    0.1, so the slot seemed to cross the outline. The distance is the circle's: the slot's bottom
    edge, over x in [-7, -4], at y = -(sqrt(R^2 - 7^2) - clearance)."""
    R = 47.5
    plane = BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                           np.array([[[-50, -50, 0], [-50, 50, 0]], [[50, -50, 0], [50, 50, 0]]], float))
    # the surface maps (u, v) in [0, 1]^2 onto [-50, 50]^2: loops in (u, v)
    to_uv = lambda p: (np.asarray(p, float) + 50.0) / 100.0  # noqa: E731
    outer = circle(to_uv((0.0, 0.0)), None, R / 100.0)
    # the circle comes nearest to the slot's bottom at its corner x = -7 (where |x| is largest)
    y = -(np.sqrt(R ** 2 - 7.0 ** 2) - clearance)
    slot = [(-4.0, y), (-7.0, y), (-7.0, y + 4.0), (-4.0, y + 4.0)]  # clockwise: a hole
    face = TrimmedFace(plane, [[outer], [line(to_uv(slot[k]), to_uv(slot[(k + 1) % 4])) for k in range(4)]])
    kinds = {p.kind for p in face.check()}
    assert ("crossing-loops" in kinds) == touches, kinds


@pytest.mark.parametrize("spike, touches", [(2e-7, False), (1e-2, True)])
def test_a_spike_back_along_the_previous_edge_within_its_tolerance_is_no_self_touching(spike, touches):
    """The Inventor part of the shared STEP set has a pcurve that starts with a 2e-7 run back
    along the previous edge (a seam) before it turns away; its edges' tolerance is 5e-4. Within
    twice the edges' tolerance that is the shared corner, not the loop touching itself; a run
    of 1e-2 back along the edge is."""
    from splinekit.construct import polyline

    x0, x1, y0, y1 = 0.1, 0.9, 0.1, 0.9
    loop = [Edge(line((x0, y0), (x1, y0)), tolerance=5e-4),
            Edge(line((x1, y0), (x1, y1)), tolerance=5e-4),
            # back down along the right side by `spike`, then across and down the left side
            Edge(polyline([(x1, y1), (x1, y1 - spike), (x0, y1 - spike)]), tolerance=5e-4),
            Edge(line((x0, y1 - spike), (x0, y0)), tolerance=5e-4)]
    face = TrimmedFace(PLANE, [loop], tolerance=1e-7)
    kinds = {p.kind for p in face.check()}
    assert ("self-intersecting-loop" in kinds) == touches, kinds


def test_a_sliver_face_is_checked_without_millions_of_segments():
    """The SolidWorks part of the shared STEP set has a face 4e-4 wide in u and 1 long in v whose
    short sides are trims of 45 cubic pieces: the check's polyline split its long sides into
    pieces as short as the short sides' chords (2.6 million segments, 15 GB in query pairs). Parts
    are now at most four per segment on average, and the face is still valid."""
    from splinekit.brep.check import _loop_polylines
    from splinekit.brep.trims import sample_trims
    from splinekit.curves import BSplineCurve

    w = 4e-4
    plane = BSplineSurface(1, 1, [0, 0, w, w], [0, 0, 1, 1], np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float))
    inner = np.linspace(0.0, 1.0, 46)[1:-1]

    def wiggle(v, forward):  # a cubic trim of 45 pieces across the short side, at v
        x = np.linspace(0.0, w, 48) if forward else np.linspace(w, 0.0, 48)
        return BSplineCurve(3, np.concatenate([[0] * 4, inner, [1] * 4]), np.column_stack([x, np.full(48, v)]))

    loop = [wiggle(0.0, True), line((w, 0.0), (w, 1.0)), wiggle(1.0, False), line((0.0, 1.0), (0.0, 0.0))]
    face = TrimmedFace(plane, [loop])
    raw = sum(len(p) for p, _, _ in sample_trims(face, 24))
    assert sum(len(p) for p, _, _ in _loop_polylines(face)) <= 5 * raw
    assert face.check() == []
