"""The first call on a face set: the fast path's own loop checks (:mod:`splinekit.tessellation.plan_checks`)
stand in for the general path's mesh at the requested tolerance.

Judged against the order the tessellator used before, which is kept as its fallback: the general
path first (it raises on bad loops), then the plan. Forcing that order (the checks patched to
refuse) must give the very same mesh on good parts and the very same error on bad loops; the
first call must give the same triangles as every later (warm) call; and on good parts the
general path must not run at all. The first call's shortcuts are checked against the routes they
replace: the plan from fewer recognition samples against the plan from all of them, the domain
check's control-point boxes against sampling every pcurve, the circle maps' speed bound against
finite differences.
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
from splinekit.tessellation.arcs import CircleMap, CircleMaps, _norm, _unwrap
from splinekit.tessellation.fast_mesh import fast_tessellation
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


def _plans(obj, monkeypatch):
    """The fast plan of ``obj``'s face set with the samples the plan chooses, and with all
    :data:`fast_plan.SAMPLES` forced (the count used before the fewer were allowed)."""
    faces = _faces(obj)
    size = float(np.linalg.norm(np.ptp(np.concatenate([f.surface.control_points.reshape(-1, 3) for f in faces]), axis=0)))
    few = fast_plan.build_plan(_Prepared(faces, size))
    with monkeypatch.context() as m:
        m.setattr(fast_plan, "FEW_SAMPLES", fast_plan.SAMPLES)  # every sample kept
        full = fast_plan.build_plan(_Prepared(faces, size))
    return few, full


@pytest.mark.parametrize("name", sorted(PARTS))
def test_fewer_recognition_samples_give_the_plan_of_all_samples(name, monkeypatch):
    obj = PARTS[name]()
    few, full = _plans(obj, monkeypatch)
    assert few is not None and full is not None and few.checked and full.checked
    assert np.array_equal(few.kind, full.kind) and np.array_equal(few.use_flip, full.use_flip)
    assert np.array_equal(few.arc_of, full.arc_of) and np.array_equal(few.end_vid, full.end_vid)
    assert np.array_equal(few.corners, full.corners)
    # the circles are fitted through the samples at the same parameters (evaluated in batches of
    # other sizes: equal to rounding); the sweeps are unwrapped over other chains
    scale = np.abs(full.corners).max()
    for a in ("arc_c", "arc_r", "arc_e1", "arc_e2", "arc_sweep"):
        assert np.allclose(getattr(few, a), getattr(full, a), rtol=0, atol=1e-14 * max(scale, 2 * math.pi)), a
    assert np.array_equal(few.fixed_T, full.fixed_T) and np.array_equal(few.fixed_face, full.fixed_face)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")  # the numpy path: no kernel loads in this test
    for rel in (1e-1, 1e-3):  # the same triangles from both plans
        a, b = fast_tessellation(few, rel * scale, None), fast_tessellation(full, rel * scale, None)
        assert np.array_equal(np.asarray(a.faces), np.asarray(b.faces))
        assert np.allclose(a.vertices, b.vertices, rtol=0, atol=1e-13 * scale)


def test_edges_of_many_pieces_keep_all_samples():
    four = sk.circle([0.0, 0.0], None, 1.0).transform(np.array([[0.3, 0, 0.5], [0, 0.3, 0.5], [0, 0, 1]]))
    b = np.unique(four.knots)
    eight = four.refine(np.repeat(0.5 * (b[:-1] + b[1:]), 2))  # each quarter split in two (joints of multiplicity 2)
    for hole, count in ((four, 37), (eight, fast_plan.SAMPLES)):
        face = TrimmedFace(_plane(), [_square(0, 1), [hole.reverse()]])
        prep = _Prepared([face], math.sqrt(2.0))
        rep = np.array([g[0] for g in prep.groups])
        keep, (i, j) = fast_plan.sample_parameters(prep, rep)
        assert keep.size == count and keep[i] == fast_plan.SAMPLES // 3 and keep[j] == 2 * fast_plan.SAMPLES // 3
        # symmetric, so that a use running against its group reads its own fractions backwards
        assert np.array_equal(keep[::-1], fast_plan.SAMPLES - 1 - keep)
        assert fast_plan.build_plan(prep).checked


@settings(max_examples=40, deadline=None)
@given(cx=st.floats(-0.1, 1.1), cy=st.floats(-0.1, 1.1), r=st.floats(0.05, 0.6), square=st.booleans())
def test_the_domain_check_refuses_exactly_the_pcurves_whose_samples_leave(cx, cy, r, square):
    # the check reads the pcurves' control point boxes first and samples only when a box reaches
    # the slack: it must refuse the same loops as sampling every pcurve (17 samples, 1% slack)
    if square:
        c = np.array([[cx - r, cy - r], [cx + r, cy - r], [cx + r, cy + r], [cx - r, cy + r]])
        loop = [line(c[k], c[(k + 1) % 4]) for k in range(4)]
    else:
        loop = _circle(cx, cy, r, False)
    t = np.linspace(0.0, 1.0, 17)
    uv = np.concatenate([e.evaluate(e.domain[0] + (e.domain[1] - e.domain[0]) * t) for e in loop])
    leaves = bool(((uv < -0.01) | (uv > 1.01)).any())
    face = TrimmedFace(_plane(), [loop])
    if leaves:
        with pytest.raises(SplineKitError, match="leaves the surface's domain"):
            _Prepared([face], math.sqrt(2.0))
    else:
        _Prepared([face], math.sqrt(2.0))


@settings(max_examples=20, deadline=None)
@given(arcs=st.lists(st.tuples(st.floats(-math.pi, math.pi), st.floats(0.3, 2 * math.pi)), min_size=1, max_size=4))
def test_circle_maps_speed_bound_against_finite_differences(arcs):
    # kappa = max |u''(theta) / u'(theta)| of each map, all maps' pieces in one pass, against
    # second differences of the map's own parameter at dense angles
    maps = [CircleMap.of(sk.arc([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 2.0, a, a + sweep), 1.0) for a, sweep in arcs]
    table = CircleMaps(maps)
    for q, m in enumerate(maps):
        ends = m.start + 2.0 * m.half
        worst = 0.0
        for lo, hi in zip(m.start, ends):  # piece by piece (u'' jumps at the joints)
            h = (hi - lo) / 4000
            theta = np.linspace(lo + 2 * h, hi - 2 * h, 3997)
            u = m.param(np.concatenate([theta - h, theta, theta + h]).clip(0.0, ends[-1])).reshape(3, -1)
            d1, d2 = (u[2] - u[0]) / (2 * h), (u[2] - 2 * u[1] + u[0]) / h**2
            worst = max(worst, float(np.abs(d2 / d1).max()))
        assert abs(table.kappa[q] - worst) <= 3e-3 * max(worst, 1e-3)  # 257 angles per piece against 4000


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), rows=st.integers(1, 6), cols=st.integers(2, 40), jumps=st.booleans())
def test_plan_helpers_equal_numpys_unwrap_and_norm_bit_for_bit(seed, rows, cols, jumps):
    # the plan's own unwrap and norm (without numpy's argument handling) must not change a bit
    rng = np.random.default_rng(seed)
    p = np.cumsum(rng.uniform(-1.5, 1.5, (rows, cols)), axis=1)
    if jumps:  # branch cuts, and steps of exactly pi either way
        p = np.mod(p, 2 * np.pi) - np.pi
        p[:, -1] = p[:, -2] + np.pi * rng.choice([-1.0, 1.0])
    assert np.array_equal(_unwrap(p), np.unwrap(p, axis=-1))
    v = rng.normal(size=(rows, cols, 3)) * 10.0 ** rng.integers(-5, 5)
    assert np.array_equal(_norm(v), np.linalg.norm(v, axis=-1))
