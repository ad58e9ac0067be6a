"""Surface curvature benchmark: splinekit against its peers, in one run.

Run from the repository root::

    python benchmarks/bench_curvature.py           # 300 x 300 grid
    python benchmarks/bench_curvature.py --quick   # 100 x 100 grid

Case: Gaussian, mean and principal curvatures, principal directions and normals
on a 300 x 300 parameter grid of a bicubic NURBS surface (13 x 13 control
points, a wavy height field, weights in [0.5, 2]).

Peers:

* OpenCascade from Python (OCP): one ``GeomLProp_SLProps`` re-targeted with
  ``SetParameters(u, v)`` per point, reading the Gaussian, mean, max and min
  curvatures (its directions and normal are not read, which favours OCC).
  Timed on an evenly strided subset and extrapolated linearly.
* geomdl 5.4 has no curvature operation; the closest it offers is its
  per-point ``derivatives(u, v, order=2)``, timed as a lower bound for a
  geomdl-based curvature (the curvature algebra itself not included).
* splinekit pointwise: ``curvature(surface, U, V)`` on the flattened pairs
  instead of the grid path.

Accuracy: the largest difference between OCC's and splinekit's curvatures on
the points OCC computed, relative to the largest principal curvature.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_eval import Table, geomdl_surface, measure, subset_index, versions

import splinekit as sk
from splinekit.basis.knots import clamped_uniform


def make_surface(seed=20240603):
    rng = np.random.default_rng(seed)
    g = np.linspace(0.0, 1.0, 13)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, rng.uniform(-0.3, 0.3, X.shape)], axis=-1)
    K = clamped_uniform(3, 13)
    return sk.NurbsSurface(3, 3, K, K, P, rng.uniform(0.5, 2.0, (13, 13)))


def occ_curvatures(h, us, vs):
    from OCP.GeomLProp import GeomLProp_SLProps

    props = GeomLProp_SLProps(h, 2, 1e-9)
    out = np.empty((len(us), 4))
    for i, (u, v) in enumerate(zip(us.tolist(), vs.tolist())):
        props.SetParameters(u, v)
        out[i] = props.GaussianCurvature(), props.MeanCurvature(), props.MaxCurvature(), props.MinCurvature()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a 100 x 100 grid and fewer peer points")
    args = ap.parse_args(argv)
    n = 100 if args.quick else 300
    occ_points = 2_000 if args.quick else 10_000
    geomdl_points = 200 if args.quick else 1_000
    load_start = os.getloadavg()[0]

    surf = make_surface()
    grid = np.linspace(0.0, 1.0, n)
    U, V = np.meshgrid(grid, grid, indexing="ij")
    tab = Table()
    case = f"curvature, {n}x{n} grid"
    t_grid, reps, ours = measure(lambda: sk.curvature(surf, grid, grid, grid=True))
    tab.add(case, "**splinekit** `curvature(s, us, vs, grid=True)`", n * n, t_grid, ref=t_grid, repeats=reps)
    t_pts, reps, pts = measure(lambda: sk.curvature(surf, U, V))
    diff = float(np.abs(pts.gaussian - ours.gaussian).max())
    tab.add(case, "splinekit pointwise `curvature(s, U, V)`", n * n, t_pts, ref=t_grid, repeats=reps, diff=diff)

    idx = subset_index(n * n, occ_points)
    us, vs = U.ravel()[idx], V.ravel()[idx]
    try:
        h = sk.occ.to_occ(surf)
        t_occ, reps, occ = measure(lambda: occ_curvatures(h, us, vs), max_repeats=1)
        t_occ *= (n * n) / len(idx)
        scale = float(np.abs(np.stack([ours.k1, ours.k2])).max())
        mine = np.column_stack([ours.gaussian.ravel()[idx], ours.mean.ravel()[idx], ours.k1.ravel()[idx], ours.k2.ravel()[idx]])
        rel = np.abs(mine - occ).max(axis=0) / np.array([scale**2, scale, scale, scale])
        tab.add(case, "OCC `GeomLProp_SLProps` per point", n * n, t_occ, ref=t_grid, repeats=reps, diff=float(rel.max()),
                note=f"extrapolated from {len(idx):,} points; diff relative to max |k| (K: to max k^2)")
    except Exception as exc:  # noqa: BLE001 - a peer that cannot run is reported, not fatal
        tab.fail(case, "OCC GeomLProp_SLProps", exc)

    idx = subset_index(n * n, geomdl_points)
    try:
        g = geomdl_surface(surf)
        pairs = list(zip(U.ravel()[idx].tolist(), V.ravel()[idx].tolist()))
        t_gd, reps, _ = measure(lambda: [g.derivatives(u, v, order=2) for u, v in pairs], max_repeats=1)
        tab.add(case, "geomdl `derivatives(u, v, 2)` per point (no curvature op)", n * n, t_gd * (n * n) / len(idx),
                ref=t_grid, repeats=reps, note=f"extrapolated from {len(idx):,} points; derivatives only")
    except Exception as exc:  # noqa: BLE001
        tab.fail(case, "geomdl", exc)

    print(f"# splinekit curvature benchmark{' (--quick)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print("Times are for the full grid; ratio = peer time / splinekit grid time (> 1: splinekit is faster).")
    print()
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads


if __name__ == "__main__":
    main()
