"""The memory and work budgets: every operation whose output size is known in advance
is refused (ResourceLimitError) before it allocates.

Each refusal runs in a fresh interpreter, so that its peak resident memory
(``ru_maxrss``, a high-water mark) measures that call alone: the refusal must
come while the process is still small, not after building most of the output.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import splinekit
from splinekit import limits
from splinekit.errors import ParameterError, ResourceLimitError, SplineKitError
from splinekit.mesh import primitives

PEAK_MB = 500
"""The largest peak resident memory a refused call may reach (an interpreter with
numpy, scipy and splinekit imported is about 60-150 MB; compiling the numba
kernels on a cold cache adds up to a few hundred)."""

_RUNNER = textwrap.dedent(
    """
    import json, resource, sys
    # a safety net: a regression that allocates after all fails with MemoryError instead of
    # taking the machine down (the address space includes mapped libraries, hence the margin)
    resource.setrlimit(resource.RLIMIT_AS, (8 * 2**30, resource.getrlimit(resource.RLIMIT_AS)[1]))
    import numpy as np
    import splinekit
    from splinekit.mesh import primitives

    def peak_mb():
        try:
            with open("/proc/self/status") as fh:
                for line in fh:
                    if line.startswith("VmHWM:"):
                        return int(line.split()[1]) / 1024
        except OSError:
            pass
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    results = []
    for code in json.loads(sys.argv[1]):
        outcome = {"error": None, "message": ""}
        try:
            exec(compile(code, "<case>", "exec"), {"np": np, "splinekit": splinekit, "primitives": primitives})
        except BaseException as exc:
            outcome = {"error": type(exc).__name__, "message": str(exc)}
        # the peak never decreases: the peak after each case bounds that case's own peak. Linux
        # keeps ru_maxrss across exec (a child of a big pytest process starts at its parent's
        # size), so read the peak of this process's own address space (VmHWM) where there is one
        outcome["peak_mb"] = peak_mb()
        results.append(outcome)
    print(json.dumps(results))
    """
)


def run_fresh(codes, budget: str | None = "1G", timeout: float = 300) -> list[dict]:
    """Run each snippet of ``codes`` in turn in one new interpreter under
    ``SPLINEKIT_MEMORY_BUDGET=budget`` (unset when None); per snippet
    ``{"error": exception class name or None, "message", "peak_mb"}`` (the
    process's peak resident memory so far)."""
    env = dict(os.environ)
    env.pop(limits.ENV_VAR, None)
    # the numpy path: compiling numba kernels on a cold cache (a clean CI checkout) costs up to
    # a gigabyte of its own, which says nothing about the refusal; the budget checks come
    # before either path allocates
    env["SPLINEKIT_NUMBA"] = "0"
    if budget is not None:
        env[limits.ENV_VAR] = budget
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # for models/
    env["PYTHONPATH"] = os.pathsep.join(p for p in [root, env.get("PYTHONPATH", "")] if p)
    done = subprocess.run([sys.executable, "-c", _RUNNER, json.dumps(list(codes))], capture_output=True, text=True,
                          env=env, timeout=timeout)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


# The findings of the reliability report, each a small input asking for a huge allocation.
BOMBS = {
    "tessellate teapot at 1e-300": "from models import teapot\nsplinekit.tessellate(teapot.build().bodies[0], 1e-300)",
    "tessellate a Catmull-Clark box through 11 levels": (
        "splinekit.tessellate(splinekit.SubdivisionSurface(primitives.box(), 'catmull-clark'), levels=11)"
    ),
    "tessellate a curve at 1e-300": (
        "c = splinekit.BSplineCurve(3, [0]*4 + list(np.linspace(0, 1, 2000)[1:-1]) + [1]*4, np.random.default_rng(0).random((2002, 3)))\n"
        "splinekit.tessellate(c, 1e-300, angle_tolerance=None)"
    ),
    "subdivide a box 11 levels": "splinekit.subdivide(primitives.box(), 'catmull-clark', 11)",
    "subdivide loop 10 levels": "splinekit.subdivide(primitives.icosphere(1), 'loop', 10)",
    "subdivide doo-sabin 11 levels": "splinekit.subdivide(primitives.box(), 'doo-sabin', 11)",
    "SubdivisionSurface.refine(11)": "splinekit.SubdivisionSurface(primitives.box(), 'catmull-clark').refine(11)",
    "icosphere(10)": "primitives.icosphere(10)",
    "torus(1e5, 1e5)": "primitives.torus(100_000, 100_000)",
    "grid(1e5, 1e5)": "primitives.grid(100_000, 100_000)",
    "PolyMesh from a broadcast face array": (
        "F = np.broadcast_to(np.array([[0, 1, 2]]), (200_000_000, 3))\nsplinekit.PolyMesh(np.eye(3), F)"
    ),
    "surface evaluate_grid 1e5 x 1e5": (
        "s = splinekit.BezierSurface(np.random.default_rng(0).random((4, 4, 3)))\n"
        "t = np.linspace(0, 1, 100_000)\ns.evaluate_grid(t, t)"
    ),
    "surface derivatives_grid 3e4 x 3e4": (
        "s = splinekit.BezierSurface(np.random.default_rng(0).random((4, 4, 3)))\n"
        "t = np.linspace(0, 1, 30_000)\ns._spline.derivatives_grid(t, t, 2)"
    ),
    "implicit sample at resolution 400": (
        "from splinekit.implicit import sample, sphere\nsample(sphere((0, 0, 0), 1.0), ((-1, -1, -1), (1, 1, 1)), 400)"
    ),
    "level set from an implicit at resolution 400": (
        "from splinekit.implicit import sphere\nfrom splinekit.levelset import LevelSet\n"
        "LevelSet.from_implicit(sphere((0, 0, 0), 1.0), ((-1, -1, -1), (1, 1, 1)), 400)"
    ),
    "SDF from a mesh at resolution 400": (
        "from splinekit.implicit import from_mesh\nfrom_mesh(primitives.icosphere(2), 400)"
    ),
    "implicit to_mesh with a tiny edge": (
        "from splinekit.implicit import sphere\nsphere((0, 0, 0), 1.0).to_mesh(0.006)"
    ),
    "sample_mesh 4e7 points": "from splinekit.pointcloud import sample_mesh\nsample_mesh(primitives.icosphere(2), 40_000_000)",
    "sample_surface 4e7 points": (
        "from splinekit.pointcloud import sample_surface\n"
        "sample_surface(splinekit.BezierSurface(np.random.default_rng(0).random((4, 4, 3))), 40_000_000)"
    ),
    "sample_curve 4e7 points": (
        "from splinekit.pointcloud import sample_curve\nsample_curve(splinekit.BezierCurve(np.eye(3)), 40_000_000)"
    ),
    "poisson_disk radius 0.003": "from splinekit.pointcloud import poisson_disk\npoisson_disk(primitives.icosphere(3), 0.003)",
    # a cloud crowded within the radius: 2e10 neighbour pairs, counted before the pair list exists
    "poisson_disk on a crowded cloud": (
        "from splinekit.pointcloud import poisson_disk\n"
        "poisson_disk(np.random.default_rng(0).random((200_000, 3)) * 1e-3, 0.1)"
    ),
    # grid_mesh refuses in each of its rounds: the grid (a broadcast view, 8e9 samples), the
    # straddling cells (a checkerboard: every cell straddles) and the triangles
    "grid_mesh of a broadcast 2000^3 grid": (
        "from splinekit.implicit.marching import grid_mesh\ngrid_mesh(np.broadcast_to(1.0, (2000, 2000, 2000)), (0, 0, 0), 1.0)"
    ),
    "grid_mesh of a 200^3 checkerboard": (
        "from splinekit.implicit.marching import grid_mesh\nr = np.arange(200)\n"
        "v = ((r[:, None, None] + r[None, :, None] + r) % 2).astype(np.float64) - 0.5\n"
        "grid_mesh(v, (0, 0, 0), 1.0)"
    ),
}


@pytest.fixture(scope="module")
def refusals():
    """Every bomb run once, in order, in one fresh interpreter under a 1 GiB budget."""
    return dict(zip(BOMBS, run_fresh(BOMBS.values())))


@pytest.mark.parametrize("name", list(BOMBS))
def test_refused_before_allocating(refusals, name):
    out = refusals[name]
    assert out["error"] == "ResourceLimitError", out
    assert out["peak_mb"] < PEAK_MB, out
    # the message names the estimate, the budget and how to raise it
    assert "needs about" in out["message"] and "1 GiB" in out["message"] and limits.ENV_VAR in out["message"], out


def test_teapot_at_1e_4_is_refused_under_a_small_budget():
    # 16.5M triangles. Refinement rounds grow towards that count, and a round that fits
    # the budget is built (under 1 GiB one of about 2M triangles may be): the budget
    # bounds every round, it does not predict the last one
    out = run_fresh(["from models import teapot\nsplinekit.tessellate(teapot.build().bodies[0], 1e-4)"], budget="256M")[0]
    assert out["error"] == "ResourceLimitError" and "256 MiB" in out["message"], out
    assert out["peak_mb"] < PEAK_MB, out


def test_grid_mesh_is_charged_in_each_round():
    # a 40^3 checkerboard: about 69,000 straddling cells (83 MB charged) but 768,000 triangles
    # (460 MB): under 200 MB the cell round passes and the triangle round refuses; each round's
    # message names what it counts, so the three rounds are told apart
    checker = ("from splinekit.implicit.marching import grid_mesh\nr = np.arange({n})\n"
               "v = ((r[:, None, None] + r[None, :, None] + r) % 2).astype(np.float64) - 0.5\n"
               "m = grid_mesh(v, (0, 0, 0), 1.0)")
    small, big, crowded = run_fresh([checker.format(n=12), checker.format(n=40), BOMBS["poisson_disk on a crowded cloud"]],
                                    budget="200M")
    assert small["error"] is None, small
    assert big["error"] == "ResourceLimitError" and "triangles" in big["message"], big
    assert crowded["error"] == "ResourceLimitError" and "neighbour pairs" in crowded["message"], crowded
    assert big["peak_mb"] < PEAK_MB and crowded["peak_mb"] < PEAK_MB
    assert "cells that straddle" in run_fresh([BOMBS["grid_mesh of a 200^3 checkerboard"]])[0]["message"]
    assert "grid of shape" in run_fresh([BOMBS["grid_mesh of a broadcast 2000^3 grid"]])[0]["message"]


def test_poisson_disk_on_a_cloud_under_a_budget_keeps_working():
    # a sparse cloud's neighbour pairs fit a small budget: the count does not refuse real work
    code = ("from splinekit.pointcloud import poisson_disk\n"
            "P = np.random.default_rng(0).random((20_000, 3))\nassert 0 < len(poisson_disk(P, 0.05, 1)) < 20_000")
    assert run_fresh([code], budget="64M")[0]["error"] is None


def test_refused_under_the_default_budget():
    # the estimates exceed half the memory of any machine this runs on (tens of GB or more)
    names = ["tessellate teapot at 1e-300", "subdivide a box 11 levels", "grid(1e5, 1e5)", "surface evaluate_grid 1e5 x 1e5"]
    for name, out in zip(names, run_fresh([BOMBS[n] for n in names], budget=None)):
        assert out["error"] == "ResourceLimitError", (name, out)
        assert out["peak_mb"] < PEAK_MB, (name, out)


def test_environment_variable_changes_the_outcome():
    code = "primitives.icosphere(5)"  # 20480 triangles, about 10 MB
    assert run_fresh([code], budget="1G")[0]["error"] is None
    out = run_fresh([code, "with splinekit.limits.budget('1G'):\n    primitives.icosphere(5)"], budget="1M")
    assert out[0]["error"] == "ResourceLimitError" and "1 MiB" in out[0]["message"]
    assert out[1]["error"] is None, out  # the context manager overrides the environment
    assert run_fresh([code], budget="off")[0]["error"] is None


def test_context_manager_changes_the_outcome():
    primitives.icosphere(4)
    with limits.budget("100K"):
        with pytest.raises(ResourceLimitError, match="icosphere"):
            primitives.icosphere(4)
        with limits.budget("1G"):  # the innermost block wins
            primitives.icosphere(4)
        with pytest.raises(ResourceLimitError):
            splinekit.subdivide(primitives.box(), "catmull-clark", 6)
    splinekit.subdivide(primitives.box(), "catmull-clark", 3)


def test_refusal_is_a_splinekit_error_and_a_memory_error():
    with limits.budget("1K"):
        with pytest.raises(SplineKitError):
            primitives.torus(100, 100)
        with pytest.raises(MemoryError):
            primitives.torus(100, 100)


def test_tessellation_under_a_small_budget_is_refused_in_the_round_that_would_exceed_it():
    s = splinekit.BezierSurface(np.random.default_rng(1).random((4, 4, 3)))
    coarse = splinekit.tessellate(s, 1e-2)
    with limits.budget(len(coarse.faces) * 1000):
        splinekit.tessellate(s, 1e-2)  # fits
        with pytest.raises(ResourceLimitError, match="tessellation at tolerance"):
            splinekit.tessellate(s, 1e-7)


def test_tessellation_tiny_tolerance_is_refused_without_a_warning(recwarn):
    # 1e-300 made the predicted counts infinite; their cast to int warned and gave garbage counts
    s = splinekit.BezierSurface(np.random.default_rng(1).random((4, 4, 3)))
    with limits.budget("200M"):
        with pytest.raises(ResourceLimitError):
            splinekit.tessellate(s, 1e-300)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_subdivision_surface_evaluation_depth_follows_the_budget():
    # a deep evaluation asks for fewer levels under a small budget rather than failing
    default = splinekit.SubdivisionSurface(primitives.box(), "catmull-clark")._level_budget()
    S = splinekit.SubdivisionSurface(primitives.box(), "catmull-clark")
    with limits.budget("5M"):
        assert S._level_budget() < default
        P = S.evaluate([0], [0.3], [0.6])[0]
    assert np.allclose(P, S.evaluate([0], [0.3], [0.6])[0], atol=1e-6)


# -- the level-set work budget ---------------------------------------------------------------------------
def _sphere_levelset(n=16):
    from splinekit.levelset import LevelSet

    x = np.linspace(-1, 1, n)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    return LevelSet(np.sqrt(X**2 + Y**2 + Z**2) - 0.5, (-1, -1, -1), x[1] - x[0])


def test_levelset_advance_is_refused_beyond_the_work_budget():
    import time

    ls = _sphere_levelset(64)
    start = time.perf_counter()
    # 0.5 time units at unit speed: 250,000 steps x 262,144 samples, hours of work
    with pytest.raises(ResourceLimitError, match=r"sample updates.*max_work") as info:
        ls.advance(8000.0, 1.0)
    assert time.perf_counter() - start < 5.0
    assert "steps" in str(info.value)
    # tiny grid, a million steps: the per-step cost counts too
    with pytest.raises(ResourceLimitError):
        _sphere_levelset(3).advance(1e6, 1.0, cfl=1.0)


def test_levelset_work_budget_can_be_raised_and_lowered():
    ls = _sphere_levelset(16)
    with pytest.raises(ResourceLimitError):
        ls.advance(0.1, 1.0, max_work=1000)
    out = ls.advance(0.1, 1.0, max_work=1e7)
    assert out.time == pytest.approx(0.1)
    with pytest.raises(ParameterError, match="max_work"):
        ls.advance(0.1, 1.0, max_work=float("nan"))


def test_levelset_advance_reports_progress(monkeypatch):
    import io

    from splinekit import _progress

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    real = _progress.progress
    monkeypatch.setattr("splinekit.levelset.progress", lambda total, label: real(total, label, stream=stream))
    monkeypatch.setattr(_progress, "_MIN_INTERVAL", 0.0)
    ls = _sphere_levelset(8)
    ls.advance(0.5, 1.0)
    assert "advancing level set" in stream.getvalue() and "/" in stream.getvalue()
