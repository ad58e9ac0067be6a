"""Fuzz: every public constructor and every budgeted operation, on generated bad and
extreme arguments, either raises a SplineKitError or returns a finite result.

The default run tries a few hundred cases per target; the long run (``-m slow``)
runs each target for ``LONG_CASES`` cases in a fresh interpreter and reports the
cases, the outcomes and the interpreter's peak memory. Run one target by hand with
``python tests/fuzz/test_fuzz_constructors.py <target> <cases>``.

Every case runs under a 256 MiB memory budget (32 MiB for grids) (:mod:`splinekit.limits`) and
level-set evolutions under a small work budget, so that a case that is refused
is refused quickly and one that is accepted stays cheap.
"""

from __future__ import annotations

import collections
import json
import math
import os
import resource
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splinekit
from splinekit import limits
from splinekit.errors import SplineKitError

DEFAULT_CASES = 150
# targets whose cases take a fifth of a second each: fewer in the default run (the long run has them all)
DEFAULT_CASES_OF = {"samplers": 40, "construct": 60}
LONG_CASES = 20_000
BUDGET = "256M"
BUDGETS = {"grids": "32M"}
"""Smaller budgets for targets whose accepted cases would otherwise take seconds each."""
FLOAT_MAX = float(np.finfo(np.float64).max)

# -- strategies: numbers, counts and arrays that are wrong in every way the report found -------------------
nasty_float = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 5e-324, 1e300, -1e300, FLOAT_MAX, -FLOAT_MAX, math.nan, math.inf]),
    st.floats(-10.0, 10.0),
)
count = st.one_of(
    st.integers(-3, 12),
    st.sampled_from([10**6, 10**9, 2**63, 10**30, -(2**63)]),
    st.sampled_from([math.inf, math.nan, 2.5, 3.0, True, "3", None, np.int64(4), np.float64(4.0)]),
)
junk = st.sampled_from([None, "x", "", b"\0", [], [[]], {}, object(), [1, "a"], [[0, 1], [2]], np.zeros((0, 3)), [np.nan]])


def float_arrays(shape_choices):
    @st.composite
    def build(draw):
        shape = draw(st.sampled_from(shape_choices))
        size = int(np.prod(shape))
        mode = draw(st.sampled_from(["plain", "nasty", "huge"]))
        if mode == "plain":
            values = draw(st.lists(st.floats(-10, 10), min_size=size, max_size=size))
        elif mode == "huge":
            values = draw(st.lists(st.sampled_from([FLOAT_MAX, -FLOAT_MAX, 1e308, -1e308, 1e300, 1e200]) | st.floats(-10, 10),
                                   min_size=size, max_size=size))
        else:
            values = draw(st.lists(nasty_float, min_size=size, max_size=size))
        return np.array(values, dtype=np.float64).reshape(shape)

    return build()


def arg(shape_choices):
    """An argument that is usually a float array of one of ``shape_choices``, sometimes junk."""
    return st.one_of(float_arrays(shape_choices), float_arrays(shape_choices), junk, nasty_float)


def knot_vectors(max_len=12):
    return st.one_of(
        st.lists(st.floats(0, 1), min_size=2, max_size=max_len).map(sorted),
        st.lists(nasty_float, min_size=0, max_size=max_len),
        st.integers(1, 4).map(lambda p: [0.0] * (p + 1) + [1.0] * (p + 1)),
        junk,
    )


CURVE_POINTS = [(2, 2), (3, 3), (4, 3), (5, 2), (6, 3), (4, 1), (3,), (0, 3), (2, 2, 2)]
NET_SHAPES = [(2, 2, 3), (3, 3, 3), (4, 4, 3), (2, 3, 2), (4, 2, 3), (3, 3), (0, 2, 3)]

# -- the finite-result check ----------------------------------------------------------------------------
def _arrays_of(value, depth=0):
    """The float arrays inside a result (geometry objects by their defining arrays)."""
    if depth > 4 or value is None or isinstance(value, (str, bytes, bool)):
        return
    if isinstance(value, (float, int, np.floating, np.integer)):
        yield np.asarray(value, dtype=np.float64)
        return
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            yield value
        return
    if isinstance(value, dict):
        for item in value.values():
            yield from _arrays_of(item, depth + 1)
        return
    if isinstance(value, (list, tuple)):
        for item in value[:50]:
            yield from _arrays_of(item, depth + 1)
        return
    for name in ("control_points", "weights", "vertices", "phi", "values", "points", "knots", "knots_u", "knots_v"):
        try:
            found = getattr(value, name, None)
        except SplineKitError:
            continue
        if isinstance(found, np.ndarray):
            yield from _arrays_of(found, depth + 1)


def check_finite(result, what):
    for a in _arrays_of(result):
        assert np.isfinite(a).all(), f"{what} returned non-finite values"


# -- targets: each draws arguments and makes one call -----------------------------------------------------
def _curves(draw):
    import splinekit as sk

    kind = draw(st.sampled_from(["bezier", "rbezier", "bspline", "nurbs"]))
    P = draw(arg(CURVE_POINTS))
    if kind == "bezier":
        c = sk.BezierCurve(P)
    elif kind == "rbezier":
        c = sk.BezierCurve(P, draw(arg([(2,), (3,), (4,), (6,), (5,)])))
    elif kind == "bspline":
        c = sk.BSplineCurve(draw(count), draw(knot_vectors()), P)
    else:
        c = sk.NurbsCurve(draw(count), draw(knot_vectors()), P, draw(arg([(2,), (3,), (4,), (6,), (5,)])))
    u = draw(st.lists(st.floats(0, 1), min_size=1, max_size=8))
    return c, c.evaluate(u)


def _surfaces(draw):
    import splinekit as sk

    kind = draw(st.sampled_from(["bezier", "rbezier", "bspline", "nurbs"]))
    P = draw(arg(NET_SHAPES))
    W = draw(arg([(2, 2), (3, 3), (4, 4), (2, 3), (4, 2)]))
    if kind == "bezier":
        s = sk.BezierSurface(P)
    elif kind == "rbezier":
        s = sk.BezierSurface(P, W)
    elif kind == "bspline":
        s = sk.BSplineSurface(draw(count), draw(count), draw(knot_vectors()), draw(knot_vectors()), P)
    else:
        s = sk.NurbsSurface(draw(count), draw(count), draw(knot_vectors()), draw(knot_vectors()), P, W)
    u = draw(st.lists(st.floats(0, 1), min_size=1, max_size=6))
    return s, s.evaluate(u, u[::-1]), s.evaluate_grid(u, u)


def _conics(draw):
    import splinekit as sk

    which = draw(st.sampled_from(["circle", "arc", "ellipse", "line", "polyline", "arc3"]))
    c3 = lambda: draw(arg([(3,), (2,), (4,)]))  # noqa: E731
    if which == "circle":
        return sk.circle(c3(), c3(), draw(nasty_float))
    if which == "arc":
        return sk.arc(c3(), c3(), draw(nasty_float), draw(nasty_float), draw(nasty_float))
    if which == "ellipse":
        return sk.ellipse(c3(), c3(), draw(nasty_float), draw(nasty_float))
    from splinekit.construct import curves as cc

    if which == "line":
        return cc.line(c3(), c3())
    if which == "polyline":
        return cc.polyline(draw(arg(CURVE_POINTS)))
    return cc.arc_through_points(c3(), c3(), c3())


def _construct(draw):
    import splinekit as sk

    c0 = sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], draw(float_arrays([(3, 3)])))
    c1 = sk.BSplineCurve(2, [0, 0, 0, 1, 1, 1], draw(float_arrays([(3, 3)])))
    which = draw(st.sampled_from(["revolve", "extrude", "ruled", "loft", "sweep", "coons"]))
    if which == "revolve":
        return sk.revolve(c0, draw(arg([(3,)])), draw(arg([(3,)])), draw(nasty_float))
    if which == "extrude":
        return sk.extrude(c0, draw(arg([(3,), (2,)])))
    if which == "ruled":
        return sk.ruled(c0, c1)
    if which == "loft":
        return sk.loft([c0, c1, c0.transform(np.eye(3) * 2.0)], degree=draw(count))
    if which == "sweep":
        return sk.sweep(c0, c1)
    return sk.coons(c0, c1, sk.BSplineCurve(1, [0, 0, 1, 1], [c0.evaluate(0.0), c1.evaluate(0.0)]),
                    sk.BSplineCurve(1, [0, 0, 1, 1], [c0.evaluate(1.0), c1.evaluate(1.0)]))


def _fit(draw):
    import splinekit as sk

    which = draw(st.sampled_from(["interpolate", "approximate", "interpolate_surface"]))
    if which == "interpolate":
        return sk.interpolate_curve(draw(arg([(4, 3), (6, 2), (3, 3), (8, 3)])), degree=draw(count))
    if which == "approximate":
        return sk.approximate_curve(draw(arg([(8, 3), (12, 2), (6, 3)])), draw(count), degree=draw(count))
    return sk.interpolate_surface(draw(arg([(4, 4, 3), (5, 4, 3), (3, 3, 3)])), degree_u=draw(count), degree_v=draw(count))


def _polymesh(draw):
    import splinekit as sk

    V = draw(arg([(4, 3), (8, 3), (3, 2), (6, 3)]))
    F = draw(st.one_of(
        st.lists(st.lists(st.integers(-2, 9), min_size=3, max_size=4), min_size=1, max_size=6),
        st.lists(st.lists(nasty_float, min_size=3, max_size=3), min_size=1, max_size=3),
        junk,
        st.just(np.broadcast_to(np.array([[0, 1, 2]]), (10**9, 3))),
    ))
    return sk.PolyMesh(V, F)


def _subdivision(draw):
    import splinekit as sk
    from splinekit.mesh import primitives as pr

    mesh = draw(st.sampled_from([pr.box(), pr.icosphere(0), pr.grid(2, 2)]))
    scheme = draw(st.sampled_from(["catmull-clark", "loop", "doo-sabin", "bogus", None]))
    key = draw(st.one_of(st.integers(-2, 12), nasty_float, st.sampled_from([None, "1", True, b"0"]), st.integers(10**18, 10**20)))
    creases = draw(st.sampled_from([None, "dict", "pairs", "junk"]))
    creases = {None: None, "dict": {(0, key): draw(nasty_float)}, "pairs": ([[0, key]], [1.0]), "junk": draw(junk)}[creases]
    corners = draw(st.sampled_from([None, "dict", "junk"]))
    corners = {None: None, "dict": {key: draw(nasty_float)}, "junk": draw(junk)}[corners]
    which = draw(st.sampled_from(["subdivide", "surface", "refine", "to_bsplines", "limit"]))
    levels = draw(count)
    if which == "subdivide":
        return sk.subdivide(mesh, scheme, levels, creases=creases, corners=corners)
    S = sk.SubdivisionSurface(mesh, scheme, creases=creases, corners=corners)
    if which == "refine":
        return S.refine(levels)
    if which == "to_bsplines":
        return S.to_bsplines(levels)[0][:4]
    if which == "limit":
        return S.limit_points()
    return S


def _primitives(draw):
    from splinekit.mesh import primitives as pr

    which = draw(st.sampled_from(["icosphere", "box", "torus", "grid"]))
    if which == "icosphere":
        return pr.icosphere(draw(count), draw(nasty_float), draw(arg([(3,)])))
    if which == "box":
        return pr.box(draw(arg([(3,), ()])), draw(arg([(3,)])))
    if which == "torus":
        return pr.torus(draw(count), draw(count), draw(nasty_float), draw(nasty_float))
    return pr.grid(draw(count), draw(count), draw(arg([(2,), ()])))


def _implicit(draw):
    import splinekit.implicit as imp

    which = draw(st.sampled_from(["sphere", "box", "torus", "cylinder", "capsule", "cone", "rounded_box", "plane"]))
    v3 = lambda: draw(arg([(3,), (2,)]))  # noqa: E731
    f = draw(nasty_float)
    obj = {
        "sphere": lambda: imp.sphere(v3(), f),
        "box": lambda: imp.box(v3(), draw(arg([(3,), ()]))),
        "torus": lambda: imp.torus(v3(), f, draw(nasty_float), v3()),
        "cylinder": lambda: imp.cylinder(v3(), f, draw(nasty_float), v3()),
        "capsule": lambda: imp.capsule(v3(), v3(), f),
        "cone": lambda: imp.cone(v3(), v3(), f, draw(nasty_float)),
        "rounded_box": lambda: imp.rounded_box(v3(), draw(arg([(3,), ()])), f),
        "plane": lambda: imp.plane(),
    }[which]()
    return obj(draw(float_arrays([(4, 3), (1, 3)])))


def _tessellate(draw):
    import splinekit as sk

    s = sk.BezierSurface(draw(float_arrays([(2, 2, 3), (3, 3, 3), (4, 4, 3)])))
    tol = draw(st.one_of(nasty_float, st.sampled_from([1e-4, 1e-8, 1e-12, 1e-300, 0.1, 1.0])))
    angle = draw(st.one_of(st.none(), nasty_float))
    return sk.tessellate(s, tol, angle_tolerance=angle, relative=draw(st.booleans()))


def _grids(draw):
    import splinekit as sk
    from splinekit.implicit import sample, sphere

    which = draw(st.sampled_from(["evaluate_grid", "normal_grid", "sample", "from_mesh", "to_mesh"]))
    n = draw(st.one_of(st.integers(0, 40), st.sampled_from([10**5, 10**8])))
    m = draw(st.one_of(st.integers(0, 40), st.sampled_from([10**5, 10**8])))
    if which in ("evaluate_grid", "normal_grid"):
        s = sk.BezierSurface(draw(float_arrays([(3, 3, 3), (2, 2, 3)]))).to_bspline()
        # broadcast views: huge parameter vectors that cost no memory to pass
        us, vs = np.broadcast_to(np.float64(0.5), (n,)), np.broadcast_to(np.float64(0.25), (m,))
        return getattr(s, which)(us, vs)
    bounds = draw(st.one_of(st.just(((-1, -1, -1), (1, 1, 1))), arg([(2, 3)])))
    if which == "sample":
        return sample(sphere((0, 0, 0), 0.7), bounds, draw(count)).values
    if which == "from_mesh":
        from splinekit.implicit import from_mesh
        from splinekit.mesh import primitives as pr

        return from_mesh(pr.icosphere(1), draw(count)).values
    return sphere((0, 0, 0), 0.7).to_mesh(draw(nasty_float))


def _samplers(draw):
    import splinekit as sk
    from splinekit import pointcloud as pc
    from splinekit.mesh import primitives as pr

    which = draw(st.sampled_from(["curve", "surface", "mesh", "poisson"]))
    n = draw(count)
    if which == "curve":
        return pc.sample_curve(sk.BezierCurve(draw(float_arrays([(3, 3), (2, 2)]))), n)
    if which == "surface":
        return pc.sample_surface(sk.BezierSurface(draw(float_arrays([(2, 2, 3), (3, 3, 3)]))), n, rng=0)
    if which == "mesh":
        return pc.sample_mesh(pr.icosphere(1), n, rng=0)
    return pc.poisson_disk(pr.icosphere(1), draw(nasty_float), rng=0, oversampling=draw(st.one_of(nasty_float, st.just(2.0))))


def _levelset(draw):
    from splinekit.levelset import LevelSet

    phi = draw(st.one_of(float_arrays([(4, 4, 4), (3, 5, 4), (2, 4, 4)]), junk))
    ls = LevelSet(phi, draw(arg([(3,)])), draw(nasty_float), time=draw(nasty_float))
    speed = draw(st.one_of(nasty_float, float_arrays([(4, 4, 4)])))
    return ls.advance(draw(nasty_float), speed, curvature=draw(st.one_of(st.just(0.0), nasty_float)),
                      scheme=draw(st.sampled_from(["godunov", "weno5", "x"])), cfl=draw(st.one_of(st.just(0.5), nasty_float)),
                      max_work=draw(st.sampled_from([1e5, 1e6, math.nan, -1.0])))


def _budget_and_paths(draw):
    from splinekit._atomic import atomic_write

    which = draw(st.sampled_from(["budget", "path"]))
    if which == "budget":
        with limits.budget(draw(st.one_of(nasty_float, junk, st.sampled_from(["1G", "12Q", "-1M", "off", "nanG", "1e400"])))):
            return limits.current_budget() > 0
    # junk's plain strings (such as "x") would be written in the working folder: keep them out of it
    elsewhere = junk.map(lambda j: os.path.join("/nonexistent-dir", j) if isinstance(j, str) and j else j)
    path = draw(st.one_of(st.text(max_size=8).map(lambda t: os.path.join("/nonexistent-dir", t)), st.sampled_from(["a\0b", b"\0", ""]), elsewhere))
    return atomic_write(path, lambda tmp: None)


TARGETS = {
    "curves": _curves,
    "surfaces": _surfaces,
    "conics": _conics,
    "construct": _construct,
    "fit": _fit,
    "polymesh": _polymesh,
    "subdivision": _subdivision,
    "mesh primitives": _primitives,
    "implicit primitives": _implicit,
    "tessellate": _tessellate,
    "grids": _grids,
    "samplers": _samplers,
    "level set": _levelset,
    "budget and paths": _budget_and_paths,
}


def run_target(name: str, cases: int) -> dict:
    """Run ``cases`` hypothesis examples of target ``name``; returns the outcome counts."""
    make = TARGETS[name]
    outcomes = collections.Counter()

    @settings(max_examples=cases, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(data=st.data())
    def case(data):
        with limits.budget(BUDGETS.get(name, BUDGET)), np.errstate(all="ignore"):
            try:
                result = make(data.draw)
            except SplineKitError as exc:
                outcomes[type(exc).__name__] += 1
                return
            except OSError as exc:  # only the path target writes; a missing folder is the OS's answer
                if name != "budget and paths" or "\0" in str(exc):
                    raise
                outcomes["OSError (missing folder)"] += 1
                return
        check_finite(result, name)
        outcomes["finite result"] += 1

    case()
    return dict(outcomes)


@pytest.mark.parametrize("name", list(TARGETS))
def test_fuzz(name):
    outcomes = run_target(name, DEFAULT_CASES_OF.get(name, DEFAULT_CASES))
    assert sum(outcomes.values()) > 0


@pytest.mark.slow
@pytest.mark.parametrize("name", list(TARGETS))
def test_fuzz_long(name):
    """LONG_CASES cases in a fresh interpreter; prints cases, outcomes and peak memory."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in [root, env.get("PYTHONPATH", "")] if p)
    done = subprocess.run([sys.executable, os.path.abspath(__file__), name, str(LONG_CASES)], capture_output=True,
                          text=True, env=env, timeout=4 * 3600)
    assert done.returncode == 0, done.stderr[-4000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    print(json.dumps(report))
    assert report["cases"] >= 1000


if __name__ == "__main__":
    # python tests/fuzz/test_fuzz_constructors.py <target> <cases> [<seconds>]: the cases run in
    # rounds of 1000 (fresh random examples each), a JSON line after each round, so that a run
    # stopped by the optional time limit still reports what it tried
    import time

    target, n = sys.argv[1], int(sys.argv[2])
    limit = float(sys.argv[3]) if len(sys.argv) > 3 else math.inf
    start = time.perf_counter()
    total = collections.Counter()
    while sum(total.values()) < n and time.perf_counter() - start < limit:
        total.update(run_target(target, min(1000, n - sum(total.values()))))
        print(json.dumps({
            "target": target,
            "cases": sum(total.values()),
            "outcomes": dict(total),
            "peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
            "seconds": round(time.perf_counter() - start, 1),
        }), flush=True)
