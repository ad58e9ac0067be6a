"""Packaging contracts: import isolation, lazy backends, the demo command."""

import os
import subprocess
import sys

import numpy as np
import pytest

import splinekit as sk
from splinekit import _kernels
from splinekit.errors import MissingDependencyError, SplineKitError

HEAVY = ("OCP", "build123d", "cadquery", "manifold3d", "matplotlib", "numba")


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_import_loads_no_heavy_backend():
    loaded = _run(
        "import sys, splinekit; "
        f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    )
    assert loaded == ""


def test_import_works_without_ocp_and_occ_calls_name_the_package():
    code = (
        "import sys; sys.modules['OCP'] = None; sys.modules['build123d'] = None; sys.modules['cadquery'] = None\n"
        "import splinekit as sk\n"
        "c = sk.BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])\n"
        "try:\n"
        "    sk.occ.to_occ(c)\n"
        "except sk.errors.MissingDependencyError as e:\n"
        "    print('missing:', e)\n"
    )
    out = _run(code)
    assert out.startswith("missing:") and "cadquery" in out


def test_missing_dependency_error_is_a_splinekit_error():
    assert issubclass(MissingDependencyError, SplineKitError)
    assert issubclass(MissingDependencyError, ImportError)


def test_demo_writes_png_and_reports(tmp_path):
    target = tmp_path / "demo.png"
    result = subprocess.run(
        [sys.executable, "-m", "splinekit.cli", "demo", "-o", str(target)],
        capture_output=True,
        text=True,
        check=True,
    )
    assert target.stat().st_size > 10_000
    with open(target, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    text = result.stdout
    assert "max deviation" in text and "area" in text
    # every invariance check printed by the demo is at rounding level
    devs = [float(line.rsplit(" ", 1)[1]) for line in text.splitlines() if "max deviation" in line]
    assert devs and max(devs) < 1e-12


def _random_nurbs_surface(rng, pu=3, pv=2, nu=9, nv=7, dim=3):
    def knots(p, n):
        inner = np.sort(rng.uniform(0, 1, n - p - 1))
        inner[1] = inner[2]  # a double knot
        return np.concatenate([[0] * (p + 1), inner, [1] * (p + 1)])

    return sk.NurbsSurface(pu, pv, knots(pu, nu), knots(pv, nv), rng.normal(size=(nu, nv, dim)), rng.uniform(0.2, 5, (nu, nv)))


@pytest.mark.parametrize("rational", [False, True])
@pytest.mark.parametrize("dim", [2, 3, 5])
def test_compiled_and_numpy_paths_agree(rational, dim, monkeypatch):
    """The numba kernels repeat the numpy path's arithmetic: scattered surface points
    agree exactly; grids and grid normals (BLAS order and reciprocal in the kernels), and
    curve points and derivatives (Horner on the per-span Taylor table) to rounding. The kernels serve at
    every size here (thresholds 0; by default only a large job, or enough work, loads them)."""
    pytest.importorskip("numba")
    monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    rng = np.random.default_rng(7 + dim)
    S = _random_nurbs_surface(rng, dim=dim)
    if not rational:
        S = sk.BSplineSurface(S.degree_u, S.degree_v, S.knots_u, S.knots_v, S.control_points)
    C = S.isocurve(u=0.37)
    n = 20_005
    u = rng.uniform(0, 1, n)
    v = rng.uniform(0, 1, n)
    us, vs = np.linspace(0, 1, 150), np.linspace(0, 1, 140)
    def run():
        return (
            C.evaluate(u),
            S.evaluate(u, v),
            S.evaluate_grid(us, vs),
            S.derivatives_grid(us, vs, 1),
            C.derivatives(u, 3),
            S.normal_grid(us, vs) if dim == 3 else None,
        )

    fast = run()
    assert _kernels.get("splinekit.basis._numba_kernels") is not None
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    slow = run()
    np.testing.assert_array_equal(fast[1], slow[1])
    cscale = np.abs(C.control_points).max()
    np.testing.assert_allclose(fast[0], slow[0], rtol=0, atol=1e-14 * cscale)
    for k in range(4):  # each derivative to rounding of its own size
        np.testing.assert_allclose(fast[4][k], slow[4][k], rtol=0, atol=1e-13 * np.abs(slow[4][k]).max())
    if dim == 3:
        np.testing.assert_allclose(fast[5], slow[5], rtol=0, atol=1e-12)
    scale = np.abs(S.control_points).max()
    np.testing.assert_allclose(fast[2], slow[2], rtol=0, atol=1e-14 * scale)
    np.testing.assert_allclose(fast[3], slow[3], rtol=1e-12, atol=1e-12 * scale)
    # and the grid equals pointwise evaluation
    U, V = np.meshgrid(us, vs, indexing="ij")
    np.testing.assert_allclose(slow[2], S.evaluate(U, V), rtol=0, atol=1e-14 * scale)


def test_numba_is_not_imported_for_small_batches():
    out = _run(
        "import sys, numpy as np, splinekit as sk\n"
        "c = sk.BSplineCurve.uniform(3, np.random.rand(10, 3))\n"
        "c.evaluate(np.linspace(0, 1, 1000))\n"
        "print('numba' in sys.modules)"
    )
    assert out == "False"


def test_numba_is_not_imported_by_the_first_demo_grid():
    """The README's demo grid (1000 x 1000 points): the numpy path serves a first call in a
    fresh process, as loading the compiled kernels would cost many times the call itself."""
    out = _run(
        "import sys, numpy as np\n"
        "from splinekit.cli import demo_surface\n"
        "g = np.linspace(0, 1, 1000)\n"
        "demo_surface().evaluate_grid(g, g)\n"
        "print('numba' in sys.modules)"
    )
    assert out == "False"


def test_first_calls_of_every_benchmarked_family_run_the_numpy_path():
    """The cold-start rule (issue 17) without a clock: the first calls that
    benchmarks/bench_cold_start.py times, at its sizes, in a fresh process with the default rule,
    import no numba, so each costs what the numpy path's first call costs. One process serves
    them all: the work they add up to stays below LOAD_WORK, so each is below it alone."""
    out = _run(
        "import os, sys, numpy as np\n"
        "os.environ.pop('SPLINEKIT_NUMBA', None)\n"
        "import splinekit as sk\n"
        "from splinekit import _kernels\n"
        "from splinekit.basis.knots import clamped_uniform\n"
        "rng = np.random.default_rng(1)\n"
        "g = np.linspace(0.0, 1.0, 20)\n"
        "P = np.stack([*np.meshgrid(g, g, indexing='ij'), rng.uniform(-0.3, 0.3, (20, 20))], axis=-1)\n"
        "U = clamped_uniform(3, 20)\n"
        "s = sk.NurbsSurface(3, 3, U, U, P, rng.uniform(0.5, 2.0, (20, 20)))\n"
        "c = sk.NurbsCurve(3, clamped_uniform(3, 50), rng.uniform(-1, 1, (50, 3)), rng.uniform(0.5, 2.0, 50))\n"
        "x, u, v = np.linspace(0, 1, 100_000), rng.uniform(0, 1, 100_000), rng.uniform(0, 1, 100_000)\n"
        "c.derivatives(x, 2); s.evaluate(u, v)\n"
        "g = np.linspace(0.0, 1.0, 1000); s.evaluate_grid(g, g)\n"
        "g = np.linspace(0.0, 1.0, 300); s.normal_grid(g, g); sk.curvature(s, g, g, grid=True)\n"
        "print(0 < _kernels._served < _kernels.LOAD_WORK, 'numba' in sys.modules)"
    )
    assert out == "True False"


def test_kernels_load_once_the_numpy_path_has_served_load_work():
    """Jobs of at least MIN_WORK add up: the kernels load with the job that brings the work
    served to LOAD_WORK, and from then on serve every job of at least MIN_WORK."""
    pytest.importorskip("numba")
    out = _run(
        "import os, sys, numpy as np\n"
        "os.environ.pop('SPLINEKIT_NUMBA', None)\n"
        "import splinekit as sk\n"
        "from splinekit import _kernels\n"
        "_kernels.LOAD_WORK = 100_000\n"
        "c = sk.BSplineCurve.uniform(3, np.random.rand(10, 3))\n"
        "seen = []\n"
        "for n in (30_000, 5_000, 30_000, 30_000, 30_000, 20_000):\n"
        "    c.evaluate(np.linspace(0, 1, n))\n"
        "    seen.append(_kernels.get('splinekit.basis._taylor_kernels') is not None)\n"
        "print(seen)"
    )
    assert out == "[False, False, False, False, True, True]"


def test_env_switch_one_loads_kernels_at_the_first_large_job():
    """SPLINEKIT_NUMBA=1 (the steady state of a long session): the first job of at least
    MIN_WORK loads the kernels, without waiting for LOAD_WORK; smaller jobs still do not."""
    pytest.importorskip("numba")
    code = (
        "import os, sys, numpy as np\n"
        "os.environ['SPLINEKIT_NUMBA'] = '1'\n"
        "import splinekit as sk\n"
        "from splinekit import _kernels\n"
        "c = sk.BSplineCurve.uniform(3, np.random.rand(10, 3))\n"
        "c.evaluate(np.linspace(0, 1, _kernels.MIN_WORK - 1))\n"
        "small = 'numba' in sys.modules\n"
        "c.evaluate(np.linspace(0, 1, _kernels.MIN_WORK))\n"
        "print(small, _kernels.get('splinekit.basis._taylor_kernels') is not None)"
    )
    assert _run(code) == "False True"


def test_first_small_tessellation_does_not_import_numba():
    """A first tessellation of a small model (a few thousand triangles) runs on the numpy path:
    its kernels would take far longer to load than the tessellation takes."""
    out = _run(
        "import sys, numpy as np, splinekit as sk\n"
        "g = np.linspace(-1, 1, 6)\n"
        "P = np.stack([*np.meshgrid(g, g, indexing='ij'), np.zeros((6, 6))], axis=-1)\n"
        "P[..., 2] = 0.3 * np.sin(2 * P[..., 0]) * np.cos(2 * P[..., 1])\n"
        "mesh = sk.tessellate(sk.BSplineSurface.uniform(3, 3, P), 1e-3, relative=True)\n"
        "print(len(mesh.faces) > 1000, 'numba' in sys.modules)"
    )
    assert out == "True False"


def test_env_switch_is_read_at_call_time(monkeypatch):
    module = "splinekit.basis._numba_kernels"
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    assert _kernels.load(module, work=10**9) is None
    assert _kernels.get(module) is None
    monkeypatch.delenv("SPLINEKIT_NUMBA")
    assert _kernels.load(module, work=10) is None
    assert os.environ.get("SPLINEKIT_NUMBA") is None


def test_atomic_write_failure_keeps_existing_file(tmp_path):
    from splinekit._atomic import atomic_write

    target = tmp_path / "picture.png"
    target.write_bytes(b"old contents")

    def failing(tmp):
        with open(tmp, "wb") as fh:
            fh.write(b"half a file")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(target, failing)
    assert target.read_bytes() == b"old contents"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["picture.png"]


def test_render_refuses_non_3d_surface(tmp_path):
    from splinekit.plot import render_surface

    flat = sk.BSplineSurface.uniform(1, 1, np.zeros((2, 2, 2)))
    with pytest.raises(SplineKitError, match="3-D"):
        render_surface(flat, tmp_path / "x.png")
    assert not list(tmp_path.iterdir())
