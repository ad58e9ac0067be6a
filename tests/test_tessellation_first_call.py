"""The first call on a face set: the fast path's own loop checks (:mod:`splinekit.tessellation.plan_checks`)
stand in for the general path's mesh at the requested tolerance.

Judged against the order the tessellator used before, which is kept as its fallback: the general
path first (it raises on bad loops), then the plan. Forcing that order (the checks patched to
refuse) must give the very same mesh on good parts and the very same error on bad loops; the
first call must give the same triangles as every later (warm) call; and on good parts the
general path must not run at all.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_tessellation_brep import SOLIDS

import splinekit as sk
from splinekit.brep import TrimmedFace, primitives
from splinekit.construct.curves import line
from splinekit.errors import SplineKitError
from splinekit.tessellation import fast_plan, trimmed
from splinekit.tessellation.arcs import CircleMap
from splinekit.tessellation.trimmed import _Prepared

import _brep_shapes as shapes


def _filleted_box():
    bd = pytest.importorskip("build123d")
    from splinekit.interop.occ_brep import brep_from_shape

    return brep_from_shape(bd.fillet(bd.Box(20, 20, 20).edges(), 3).wrapped)


PARTS = {
    "box": lambda: primitives.box(20.0, 30.0, 10.0),
    "cylinder": lambda: primitives.cylinder(1.0, 3.0),
    "box_with_hole": lambda: primitives.box_with_hole(20.0, 4.0),
    "plate_with_holes": SOLIDS["plate_with_holes"][0],
    "box_with_holes_keyless": SOLIDS["box_with_holes_keyless"][0],
    "cylinder_keyless": SOLIDS["cylinder_keyless"][0],
    "filleted_box": _filleted_box,
}


def _faces(obj):
    return [f for o in (obj if isinstance(obj, list) else [obj]) for f in o.faces]


def _same_mesh(a, b):
    assert np.array_equal(np.asarray(a.faces), np.asarray(b.faces))
    for name in ("vertices", "normals", "uv", "vertex_patch", "face_patch", "corner_uv"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.max_deviation == b.max_deviation


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-5])
@pytest.mark.parametrize("name", sorted(PARTS))
def test_first_call_skips_the_general_path_and_meshes_as_before(name, rel, monkeypatch):
    before = PARTS[name]()
    with monkeypatch.context() as m:  # the order used before: the general path validates first
        m.setattr(fast_plan, "loops_valid", lambda *a: False)
        old = sk.tessellate(before, rel, relative=True)
    obj = PARTS[name]()
    calls = []
    general = trimmed._tessellate_trimmed
    monkeypatch.setattr(trimmed, "_tessellate_trimmed", lambda *a: calls.append(a) or general(*a))
    first = sk.tessellate(obj, rel, relative=True)
    assert not calls  # no general-path mesh on the first call
    plan = _faces(obj)[0]._cache["tessellate"].memo["fast"]
    assert plan.checked
    _same_mesh(first, old)
    warm = sk.tessellate(obj, rel, relative=True)
    _same_mesh(first, warm)
    assert not calls
    assert first.is_closed and first.volume > 0 and first.max_deviation <= first.tolerance


def _plane():
    return shapes.plane([0, 0, 0], [1, 0, 0], [0, 1, 0])


def _circle(cx, cy, r, hole):
    """A circle about ``(cx, cy)`` in the unit plane's (u, v): counter-clockwise, clockwise for a hole."""
    return shapes._disk_loop(cx, cy, r, 1.0, 1.0, 0.0, 0.0, hole)


def _square(a, b, hole=False):
    c = np.array([[a, a], [b, a], [b, b], [a, b]])
    loop = [line(c[k], c[(k + 1) % 4]) for k in range(4)]
    return [e.reverse() for e in reversed(loop)] if hole else loop


def _half_circle_and_a_short_line():
    c = sk.circle([0.0, 0.0], None, 1.0).transform(np.array([[0.3, 0, 0.5], [0, 0.3, 0.5], [0, 0, 1]]))
    upper, _ = c.split(0.5)  # from (0.8, 0.5) over the top to (0.2, 0.5)
    return [upper, line([0.2, 0.5], [0.75, 0.5])]  # stops 0.05 short of the start


BAD = {
    # name: loops on the unit plane, and the error the general path gives
    "overlapping circle holes": ([_square(0, 1), _circle(0.4, 0.5, 0.2, True), _circle(0.6, 0.5, 0.2, True)], "cross"),
    "circle hole outside the outer loop": ([_square(0, 0.5), _circle(0.75, 0.75, 0.1, True)], "bounds no material"),
    "circle hole counter-clockwise": ([_square(0, 1), _circle(0.5, 0.5, 0.2, False)], "wrong way"),
    "circle outer loop clockwise": ([_circle(0.5, 0.5, 0.4, True)], "wrong way"),
    "circle hole inside another": ([_square(0, 1), _circle(0.5, 0.5, 0.3, True), _circle(0.5, 0.5, 0.1, True)], "nest wrongly"),
    "square hole crossing a circle outer loop": ([_circle(0.5, 0.5, 0.4, False), _square(0.6, 0.95, hole=True)], "cross"),
    "circle hole crossing the outer square": ([_square(0, 0.8), _circle(0.75, 0.4, 0.1, True)], "cross"),
    "open loop with an arc": ([_half_circle_and_a_short_line()], "not closed"),
    "circle leaving the domain": ([_circle(0.9, 0.5, 0.3, False)], "leaves the surface's domain"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_invalid_loops_are_refused_on_a_first_call(name, monkeypatch):
    loops, message = BAD[name]
    with pytest.raises(SplineKitError, match=message) as new:
        sk.tessellate(TrimmedFace(_plane(), loops, name="bad"), 1e-3)
    assert "face 0 ('bad')" in str(new.value)
    # the same error as the general path gave when it ran first
    monkeypatch.setattr(fast_plan, "loops_valid", lambda *a: False)
    with pytest.raises(SplineKitError) as old:
        sk.tessellate(TrimmedFace(_plane(), loops, name="bad"), 1e-3)
    assert type(old.value) is type(new.value) and str(old.value) == str(new.value)


@pytest.mark.parametrize("name", sorted(set(BAD) - {"circle leaving the domain"}))
def test_the_plan_checks_refuse_invalid_loops_themselves(name):
    # not only the general path behind them: a plan built for such loops is marked unchecked
    face = TrimmedFace(_plane(), BAD[name][0])
    plan = fast_plan.build_plan(_Prepared([face], math.sqrt(2.0)))
    assert plan is None or not plan.checked


def test_valid_curved_loops_pass_the_plan_checks():
    loops = [_circle(0.5, 0.5, 0.45, False), _square(0.3, 0.45, hole=True), _circle(0.65, 0.6, 0.1, True)]
    face = TrimmedFace(_plane(), loops)
    plan = fast_plan.build_plan(_Prepared([face], math.sqrt(2.0)))
    assert plan is not None and plan.checked
    mesh = sk.tessellate(face, 1e-3)
    area = math.pi * 0.45**2 - 0.15**2 - math.pi * 0.1**2
    assert abs(mesh.area - area) <= 2 * math.pi * 0.55 * 1e-3


@settings(max_examples=30, deadline=None)
@given(
    arcs=st.lists(st.tuples(st.floats(-math.pi, math.pi), st.floats(0.2, 2 * math.pi), st.floats(0.01, 100.0)),
                  min_size=1, max_size=6),  # fmt: skip
    straight=st.booleans(),
)
def test_batched_circle_maps_against_the_curves_own_evaluators(arcs, straight):
    # arcs of every piece count in one batch (and a straight quadratic, which is no circle): each
    # map's angles give its curve's own points, and the batch agrees with the one-at-a-time maps
    curves = [sk.arc([1.0, 2.0, 3.0], [0.3, -0.2, 1.0], r, a, a + sweep) for a, sweep, r in arcs]
    if straight:
        curves.append(sk.NurbsCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [1, 1, 0], [2, 2, 0]], [1, 0.5, 1]))
    maps = CircleMap.batch([(c.knots, c.control_points, c.weights) for c in curves], 1.0)
    for c, m in zip(curves, maps):
        one = CircleMap.of(c, 1.0)
        if straight and c is curves[-1]:
            assert m is None and one is None
            continue
        assert m is not None and one is not None
        t = np.linspace(*c.domain, 101)
        r = m.circle.radius
        assert np.abs(m.circle.points(m.angle(t)) - c.evaluate(t)).max() <= 1e-9 * r
        assert np.abs(m.angle(t) - one.angle(t)).max() <= 1e-12
        assert np.abs(m.param(m.angle(t)) - t).max() <= 1e-9 * (t[-1] - t[0])
