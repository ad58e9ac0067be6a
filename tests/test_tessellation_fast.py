"""The fast B-rep tessellation path (planes and right circular cylinders bounded by lines and
circles): the same guarantees as the general path, judged independently.

Independent yardsticks: closed-form volumes, the faces' own evaluators at the triangles'
barycentric (u, v) (the chordal deviation) and at the corners' (u, v) (the vertices), the faces'
own normals, exact circle geometry (every vertex of a hole on its circle), the general path's
triangle counts, and the curves' own evaluators for the circle maps.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_tessellation_brep import SOLIDS, measured_deviation

import splinekit as sk
from splinekit import _kernels
from splinekit.brep import primitives
from splinekit.tessellation import fast_mesh
from splinekit.tessellation.arcs import CircleMap
from splinekit.tessellation import trimmed
from splinekit.tessellation.trimmed import _Prepared, _tessellate_trimmed

FAST = ["box", "box_with_hole", "plate_with_holes", "cylinder"]
MAKE = {
    "box": (lambda: primitives.box(20.0, 30.0, 10.0), 6000.0, 2 * (600 + 200 + 300)),
    **{name: SOLIDS[name][:3] for name in ("box_with_hole", "plate_with_holes", "cylinder")},
}


@pytest.fixture(params=["numpy", "numba"])
def path(request, monkeypatch):
    """Runs a test on the numpy path and on the compiled kernels (loaded at every size)."""
    if request.param == "numba":
        pytest.importorskip("numba")
        monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
        monkeypatch.setattr(_kernels, "MIN_WORK", 0)
        monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
        assert _kernels.load(fast_mesh.KERNELS) is not None
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    return request.param


def _plan(solid):
    return solid.faces[0]._cache["tessellate"].memo.get("fast")


def _check(solid, mesh, volume, area):
    """Every guarantee of a solid's Tessellation, against independent evaluations."""
    tol = mesh.tolerance
    faces = solid.faces
    assert mesh.is_closed
    assert mesh.volume > 0 and abs(mesh.volume - volume) <= area * tol
    dev = measured_deviation(mesh, faces)
    assert dev <= tol * (1 + 1e-9)
    assert abs(mesh.max_deviation - dev) <= 1e-9 * tol + 1e-12  # the same yardstick, a true value
    F = np.asarray(mesh.faces)
    size = float(np.ptp(mesh.vertices, axis=0).max())
    for f in np.unique(mesh.face_patch):
        sel = mesh.face_patch == f
        uv = mesh.corner_uv[sel].reshape(-1, 2)
        # corner (u, v) on the triangle's own face map to the vertices
        got = faces[f].surface.evaluate(uv[:, 0], uv[:, 1])
        assert np.abs(got - mesh.vertices[F[sel]].reshape(-1, 3)).max() <= 1e-12 * size
        # triangles face like their face's outward normal
        X = mesh.vertices[F[sel]]
        fn = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        c = mesh.corner_uv[sel].mean(axis=1)
        assert (np.einsum("ij,ij->i", fn, faces[f].normals(c[:, 0], c[:, 1])) > 0).all()
    # vertex normals: their face's exact normal at their (u, v); at a pole (Su x Sv = 0) its limit,
    # the normal a millionth of the domain towards the domain's centre
    for f in np.unique(mesh.vertex_patch):
        sel = mesh.vertex_patch == f
        uv = mesh.uv[sel]
        exact = faces[f].normals(uv[:, 0], uv[:, 1])
        pole = np.linalg.norm(exact, axis=1) == 0
        assert np.abs(mesh.normals[sel][~pole] - exact[~pole]).max(initial=0) <= 1e-12
        if pole.any():
            (u0, u1), (v0, v1) = faces[f].surface.domain
            near = uv[pole] + 1e-6 * (np.array([0.5 * (u0 + u1), 0.5 * (v0 + v1)]) - uv[pole])
            assert np.abs(mesh.normals[sel][pole] - faces[f].normals(near[:, 0], near[:, 1])).max() <= 1e-5
        got = faces[f].surface.evaluate(mesh.uv[sel, 0], mesh.uv[sel, 1])
        assert np.abs(got - mesh.vertices[sel]).max() <= 1e-12 * size


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
@pytest.mark.parametrize("name", FAST)
def test_fast_path_keeps_every_guarantee(name, rel, path):
    make, volume, area = MAKE[name]
    solid = make()
    mesh = sk.tessellate(solid, rel, relative=True)
    assert _plan(solid) is not None  # these parts take the fast path
    _check(solid, mesh, volume, area)
    # a second call (plan cached) gives the same mesh as the first (plan built)
    again = sk.tessellate(solid, rel, relative=True)
    assert np.array_equal(again.faces, mesh.faces) and np.array_equal(again.vertices, mesh.vertices)


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-4])
@pytest.mark.parametrize("name", ["box_with_hole", "plate_with_holes", "cylinder"])
def test_numpy_and_compiled_paths_agree(name, rel, monkeypatch):
    pytest.importorskip("numba")
    make = MAKE[name][0]
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    a = sk.tessellate(make(), rel, relative=True)
    monkeypatch.delenv("SPLINEKIT_NUMBA")
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    assert _kernels.load(fast_mesh.KERNELS) is not None
    b = sk.tessellate(make(), rel, relative=True)
    # the same counts (set by the circle counts), vertices, deviation and volume; the ear
    # clipping may order triangles differently only where rounding moves one of its choices
    assert (a.n_faces, a.n_vertices) == (b.n_faces, b.n_vertices)
    assert np.abs(a.vertices - b.vertices).max() <= 1e-12 * np.abs(a.vertices).max()
    assert np.abs(a.normals - b.normals).max() <= 1e-12
    assert math.isclose(a.max_deviation, b.max_deviation, rel_tol=1e-9, abs_tol=1e-15)
    assert math.isclose(a.volume, b.volume, rel_tol=1e-12)
    assert np.array_equal(np.sort(a.face_patch), np.sort(b.face_patch))


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-5])
@pytest.mark.parametrize("name", ["box_with_hole", "plate_with_holes", "cylinder"])
def test_no_more_triangles_than_the_general_path(name, rel):
    solid = MAKE[name][0]()
    fast = sk.tessellate(solid, rel, relative=True)
    prep = _Prepared.of(solid.faces, solid.faces[0]._cache["diagonal"][1])
    general = _tessellate_trimmed(prep, fast.tolerance, 0.5)
    assert general.max_deviation <= fast.tolerance * (1 + 1e-9)
    assert fast.n_faces <= general.n_faces


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-5])
def test_hole_vertices_lie_on_the_exact_circle(rel):
    # box 20 with a hole of radius 4 on the z axis: every vertex is a box corner or on the circle,
    # and the circle is cut at uniform angle into as few segments as the tolerance allows
    solid = primitives.box_with_hole(20.0, 4.0)
    mesh = sk.tessellate(solid, rel, relative=True)
    V = mesh.vertices
    corner = (np.abs(np.abs(V) - 10.0) < 1e-12).all(axis=1)
    on_hole = np.abs(np.hypot(V[:, 0], V[:, 1]) - 4.0) < 1e-12
    assert (corner | on_hole).all() and corner.sum() == 8
    # both circles have the same count, no larger than the sagitta and the angle criterion need
    # (with the margin the cylinder's rational parametrization asks for: at most 10% more)
    per_circle = on_hole.sum() // 2
    step = min(0.5, 2 * math.acos(1 - mesh.tolerance / 4.0))
    assert math.ceil(2 * math.pi / step) <= per_circle <= math.ceil(1.1 * 2 * math.pi / step) + 1


def test_angle_tolerance_none_needs_fewer_triangles_at_a_coarse_tolerance():
    solid = primitives.cylinder(1.0, 3.0)
    coarse = sk.tessellate(solid, 0.3, angle_tolerance=None)
    default = sk.tessellate(solid, 0.3)
    assert coarse.n_faces < default.n_faces
    _check(solid, coarse, 3 * math.pi, 8 * math.pi)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(
    holes=st.lists(st.tuples(st.floats(0.15, 0.85), st.floats(0.15, 0.85), st.floats(0.02, 0.12)), min_size=1, max_size=4),
    rel=st.sampled_from([1e-1, 1e-2, 1e-3, 1e-4]),
)
def test_random_plates_with_holes(holes, rel, path):
    # holes that keep clear of each other and of the sides
    dx, dy, dz = 40.0, 30.0, 5.0
    spec = []
    for x, y, r in holes:
        x, y, r = x * dx, y * dy, r * dy
        if x - r < 1 or x + r > dx - 1 or y - r < 1 or y + r > dy - 1:
            continue
        if all(math.hypot(x - a, y - b) > r + c + 1 for a, b, c in spec):
            spec.append((x, y, r))
    solid = primitives.plate_with_holes(dx, dy, dz, spec)
    volume = dx * dy * dz - sum(math.pi * r * r * dz for _, _, r in spec)
    area = 2 * (dx * dy + dx * dz + dy * dz) + sum(2 * math.pi * r * dz for _, _, r in spec)
    mesh = sk.tessellate(solid, rel, relative=True)
    assert _plan(solid) is not None
    _check(solid, mesh, volume, area)


def test_other_faces_take_the_general_path():
    # a cone (not a cylinder) and a sphere: no plan, the general path, still closed and within tolerance
    for name in ("cone", "sphere"):
        make, volume, area, _ = SOLIDS[name]
        solid = make()
        mesh = sk.tessellate(solid, 1e-3, relative=True)
        assert _plan(solid) is None
        assert mesh.is_closed and abs(mesh.volume - volume) <= area * mesh.tolerance


@settings(max_examples=30, deadline=None)
@given(
    start=st.floats(-math.pi, math.pi),
    sweep=st.floats(0.2, 2 * math.pi),
    radius=st.floats(0.01, 100.0),
    rho=st.floats(0.2, 5.0),
)
def test_circle_map_against_the_curves_own_evaluator(start, sweep, radius, rho):
    # a circle arc with its pieces reparametrized (weights (w0, w1, w2) -> (w0, rho w1, rho^2 w2),
    # scaled along so that the joints stay shared): the same circle at other parameters
    centre = np.array([1.0, 2.0, 3.0])
    arc = sk.arc(centre, [0.3, -0.2, 1.0], radius, start, start + sweep)
    pieces = arc.to_bezier()
    W = []
    for i, p in enumerate(pieces):
        c = rho ** (2 * i)
        W += [c * p.weights[0], c * rho * p.weights[1]]
    W.append(rho ** (2 * len(pieces)) * pieces[-1].weights[2])
    skewed = sk.NurbsCurve(2, arc.knots, arc.control_points, W)
    t = np.linspace(*skewed.domain, 101)
    X = skewed.evaluate(t)
    assert np.abs(np.linalg.norm(X - centre, axis=1) - radius).max() <= 1e-12 * radius  # still the circle
    m = CircleMap.of(skewed, radius)
    assert m is not None
    assert np.linalg.norm(m.circle.centre - centre) <= 1e-9 * radius and abs(m.circle.radius - radius) <= 1e-9 * radius
    theta = m.angle(t)
    # the map's angles give the curve's own points, grow along it, and param inverts them
    assert np.abs(m.circle.points(theta) - X).max() <= 1e-9 * radius
    assert (np.diff(theta) > 0).all() and abs(theta[-1] - theta[0] - sweep) <= 1e-9
    assert np.abs(m.param(theta) - t).max() <= 1e-9 * (t[-1] - t[0])


@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_strip_merge_triangulates_the_strip(data):
    # two cylinders' bottom and top chains with points at unrelated u (the merge, not the regular
    # strip): the triangles are counter-clockwise in (u, v) (bottom v = 0, top v = 1), use every
    # point, and tile each strip exactly (their areas add up to its width)
    class Plan:
        pass

    plan = Plan()
    chains, uv = [], []
    lo, hi = [], []
    for q in range(2):
        a, w = data.draw(st.floats(-5, 5)), data.draw(st.floats(0.5, 3))
        for _side in range(2):
            # distinct points a chain's samples apart at least (floats a few ulps apart would
            # collapse into one point once scaled: no edge is sampled that finely)
            inner = sorted(data.draw(st.lists(st.integers(1, 999), max_size=8, unique=True)))
            inner = [k / 1000 for k in inner]
            u = a + w * np.array([0.0, *inner, 1.0])
            chains.append((q, len(uv) if not uv else sum(len(c) for c in uv), u))
            uv.append(u)
        lo.append(a)
        hi.append(a + w)
    # one "use" per chain; its points are the chain's, in increasing u (the top chain is given
    # in loop order, decreasing u, as a cylinder's loop runs)
    pts, cnt, ustart = [], [], []
    for k, (q, _, u) in enumerate(chains):
        top = k % 2 == 1
        ustart.append(len(pts))
        cnt.append(len(u))
        pts += [(x, 1.0 if top else 0.0) for x in (u[::-1] if top else u)]
    puv = np.array(pts)
    plan.zb_use, plan.zb_slot = np.array([0, 2]), np.array([0, 1])
    plan.zt_use, plan.zt_slot = np.array([3, 1]), np.array([1, 0])  # slots in reverse order
    plan.slot_lo, plan.slot_hi = np.array(lo), np.array(hi)
    T, q = fast_mesh._zipper(plan, np.array(ustart), np.array(cnt), puv)
    a, b, c = puv[T[:, 0]], puv[T[:, 1]], puv[T[:, 2]]
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    assert (area > 0).all()
    assert len(T) == len(puv) - 4
    assert set(T.ravel().tolist()) == set(range(len(puv)))
    for s in range(2):
        assert math.isclose(area[q == s].sum(), hi[s] - lo[s], rel_tol=1e-12)


def test_compiled_strip_matches_the_numpy_merge():
    # the compiled strip (inside the second kernel pass) against the numpy merge, on chains with
    # points at unrelated u, shared u and u within rounding of each other
    pytest.importorskip("numba")
    K = _kernels.load(fast_mesh.KERNELS)
    rng = np.random.default_rng(5)

    class Plan:
        pass

    for trial in range(60):
        nb, nt = rng.integers(0, 9, 2)
        ub = np.sort(rng.uniform(0.01, 0.99, nb))
        ut = np.sort(rng.uniform(0.01, 0.99, nt)) if trial % 3 else ub + rng.uniform(-1e-12, 1e-12, nb)
        ub, ut = np.concatenate([[0.0], ub, [1.0]]), np.concatenate([[0.0], ut, [1.0]])
        lo, w = rng.uniform(-3, 3), rng.uniform(0.5, 2)
        ub, ut = lo + w * ub, lo + w * ut
        puv = np.concatenate([np.column_stack([ub, np.zeros_like(ub)]), np.column_stack([ut[::-1], np.ones_like(ut)])])
        plan = Plan()
        plan.zb_use, plan.zb_slot, plan.zt_use, plan.zt_slot = (np.array([k]) for k in (0, 0, 1, 0))
        plan.slot_lo, plan.slot_hi = np.array([lo]), np.array([lo + w])
        ustart, cnt = np.array([0, len(ub)]), np.array([len(ub), len(ut)])
        want, _ = fast_mesh._zipper(plan, ustart, cnt, puv)
        bp = np.arange(len(ub))
        tp = np.arange(len(puv) - 1, len(ub) - 1, -1)
        T = np.empty((len(bp) + len(tp) - 2, 3), dtype=np.int64)
        assert K.strip(bp, len(bp), tp, len(tp), puv, lo, w, T, 0) == len(T)
        assert np.array_equal(T, want)


@pytest.mark.parametrize("name", ["box_with_hole", "plate_with_holes", "cylinder"])
def test_fast_path_serves_every_tolerance(name, monkeypatch, path):
    # the circle counts meet the tolerance and the angle criterion at once (no call falls back to
    # the general path): a sweep of tolerances, with and without the angle criterion
    solid = MAKE[name][0]()
    sk.tessellate(solid, 1e-2, relative=True)  # the plan
    calls = []
    monkeypatch.setattr(trimmed, "_tessellate_trimmed", lambda *a: calls.append(a))
    for rel in np.geomspace(1e-6, 0.5, 40):
        for angle in (0.5, None, 0.1):
            mesh = sk.tessellate(solid, rel, relative=True, angle_tolerance=angle)
            assert mesh.max_deviation <= mesh.tolerance
    assert not calls
