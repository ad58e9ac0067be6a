"""Cold start: the first call after ``import splinekit`` against a warm call, numpy vs compiled.

Run from the repository root::

    python benchmarks/bench_cold_start.py            # every kernel family, 3 fresh processes each
    python benchmarks/bench_cold_start.py --quick    # 1 fresh process each
    python benchmarks/bench_cold_start.py --forced   # compiled kernels at every size (threshold 0)

(with the worktree first on the path, e.g. ``PYTHONPATH=$PWD python benchmarks/...``).

Each case runs in a fresh Python process per path: ``import splinekit``, build the geometry (not
timed), time the first call (**cold**: it pays for importing numba and loading the compiled
kernels from numba's on-disk cache, when the library chooses them), then the median of five more
calls (**warm**). The numpy path is the same process with ``SPLINEKIT_NUMBA=0``; the compiled
path is the library's default with ``SPLINEKIT_NUMBA`` unset (:mod:`splinekit._kernels` decides,
so it may well be the numpy path), or with ``--forced`` (``SPLINEKIT_NUMBA=1``, thresholds 0)
the compiled kernels at every size, as before the cold-start rule. The numba cache is filled by
a first untimed run, so "cold" means a new process, not a new install.

Families (one case each, at the sizes of the README's benchmark table):
curve points, curve derivatives, scattered surface points, tensor grids (the ``splinekit demo``
grid and a 20 x 20 NURBS grid), grid normals, grid curvature (``curvature(..., grid=True)``) and
tessellation of a bicubic NURBS patch.

The ratios printed are compiled / numpy: the target is a cold ratio of at most 1.5 (a first call
never much slower than the numpy path's) and a warm ratio at most 1 (compiled code only where it
wins).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

from _ratios import report

CHILD = r"""
import json, sys, time
import numpy as np
import splinekit as sk
from splinekit import _kernels
from splinekit.basis.knots import clamped_uniform

case, forced = sys.argv[1], sys.argv[2] == "1"
if forced:
    _kernels.MIN_WORK = _kernels.LOAD_WORK = 0

rng = np.random.default_rng(20240601)


def nurbs_surface(n=20):
    g = np.linspace(0.0, 1.0, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, rng.uniform(-0.3, 0.3, X.shape)], axis=-1)
    return sk.NurbsSurface(3, 3, clamped_uniform(3, n), clamped_uniform(3, n), P, rng.uniform(0.5, 2.0, (n, n)))


def curve(rational):
    P, w, U = rng.uniform(-1.0, 1.0, (50, 3)), rng.uniform(0.5, 2.0, 50), clamped_uniform(3, 50)
    return sk.NurbsCurve(3, U, P, w) if rational else sk.BSplineCurve(3, U, P)


if case == "curve points":
    c, x = curve(False), np.linspace(0.0, 1.0, 1_000_000)
    call = lambda: c.evaluate(x)
elif case == "curve derivatives":
    c, x = curve(True), np.linspace(0.0, 1.0, 100_000)
    call = lambda: c.derivatives(x, 2)
elif case == "surface points":
    s, u, v = nurbs_surface(), rng.uniform(0, 1, 100_000), rng.uniform(0, 1, 100_000)
    call = lambda: s.evaluate(u, v)
elif case == "grid (demo)":
    from splinekit.cli import demo_surface
    s = demo_surface()
    (a, b), (c_, d) = s.domain
    us, vs = np.linspace(a, b, 1000), np.linspace(c_, d, 1000)
    call = lambda: s.evaluate_grid(us, vs)
elif case == "grid 20x20":
    s, g = nurbs_surface(), np.linspace(0.0, 1.0, 1000)
    call = lambda: s.evaluate_grid(g, g)
elif case == "normals":
    s, g = nurbs_surface(), np.linspace(0.0, 1.0, 300)
    call = lambda: s.normal_grid(g, g)
elif case == "curvature grid":
    s, g = nurbs_surface(), np.linspace(0.0, 1.0, 300)
    call = lambda: sk.curvature(s, g, g, grid=True)
elif case == "tessellation":
    s = nurbs_surface(12)
    call = lambda: sk.tessellate(s, 1e-4, relative=True)
else:
    raise SystemExit(f"unknown case {case!r}")

t0 = time.perf_counter()
call()
cold = time.perf_counter() - t0
warm = []
for _ in range(5):
    t0 = time.perf_counter()
    call()
    warm.append(time.perf_counter() - t0)
print(json.dumps({"cold": cold, "warm": sorted(warm)[2], "numba": "numba" in sys.modules}))
"""

CASES = ("curve points", "curve derivatives", "surface points", "grid (demo)", "grid 20x20", "normals",
         "curvature grid", "tessellation")


def run(case: str, numba: bool, forced: bool) -> dict:
    """One fresh process: the cold and warm seconds of ``case``: the numpy path
    (``SPLINEKIT_NUMBA=0``), the library's default (the variable unset) or, ``forced``, the
    compiled kernels at every size (``SPLINEKIT_NUMBA=1`` and thresholds 0)."""
    env = {k: v for k, v in os.environ.items() if k != "SPLINEKIT_NUMBA"}
    if not numba:
        env["SPLINEKIT_NUMBA"] = "0"
    elif forced:
        env["SPLINEKIT_NUMBA"] = "1"
    done = subprocess.run([sys.executable, "-c", CHILD, case, "1" if forced else "0"], env=env,
                          capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"{case}: child failed\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="one fresh process per case and path (default three)")
    ap.add_argument("--forced", action="store_true", help="compiled kernels at every size (threshold 0)")
    ap.add_argument("--case", action="append", choices=CASES, help="only this case (repeatable)")
    args = ap.parse_args(argv)
    processes = 1 if args.quick else 3
    cases = args.case or CASES
    for case in cases:  # fill numba's on-disk cache, untimed
        run(case, True, True)
    mode = "forced compiled" if args.forced else "library default"
    print(f"first call (cold, fresh process) and warm call (median of 5); compiled = {mode}; "
          f"median of {processes} process(es); ms")
    print()
    print("| case | numpy cold | numpy warm | compiled cold | compiled warm | numba loaded | cold ratio | warm ratio |")
    print("|---|---|---|---|---|---|---|---|")
    ratios = []
    for case in cases:
        rows = {flag: [run(case, flag, args.forced) for _ in range(processes)] for flag in (False, True)}
        med = {flag: {k: statistics.median(r[k] for r in rs) for k in ("cold", "warm")} for flag, rs in rows.items()}
        loaded = "yes" if all(r["numba"] for r in rows[True]) else ("no" if not any(r["numba"] for r in rows[True]) else "some")
        n, c = med[False], med[True]
        print(f"| {case} | {1e3 * n['cold']:.1f} | {1e3 * n['warm']:.1f} | {1e3 * c['cold']:.1f} | "
              f"{1e3 * c['warm']:.1f} | {loaded} | {c['cold'] / n['cold']:.2f} | {c['warm'] / n['warm']:.2f} |")
        ratios.append((case, n, c))
    print()
    for case, n, c in ratios:  # the lines check_ratios.py reads: numpy path / compiled path, more is better
        report(f"cold start {case}: numpy first call / compiled first call", n["cold"] / c["cold"], 1 / 1.5)
        report(f"cold start {case}: numpy warm / compiled warm", n["warm"] / c["warm"], 1.0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
