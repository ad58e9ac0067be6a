#!/usr/bin/env python
"""Mesh -> signed-distance grid: splinekit's from_mesh against trimesh and Open3D, in one run.

Run from the repository root::

    python benchmarks/bench_sdf_grid.py           # 81,920 triangles at 128^3 (a few minutes)
    python benchmarks/bench_sdf_grid.py --quick   # 5,120 triangles at 48^3 (seconds)

Case: a lumpy sphere, closed and non-convex: an icosphere of level 6 (81,920
triangles; level 4, 5,120 triangles, with ``--quick``) with its radius
modulated by ``1 + 0.3 sin(3 theta) sin^2(phi) + 0.15 cos(5 phi)``, sampled on
the grid ``from_mesh`` builds (128 samples along the longest side, 10 %
padding, one extra layer: about 130^3 = 2.2 million samples).

Timed:

- **splinekit**: ``from_mesh(mesh, 128)``: the whole grid, exact distance and
  sign at every sample. The first call (which also compiles the numba kernel,
  or loads it from numba's cache) is reported apart from a second call.
- **splinekit, narrow band**: ``from_mesh(mesh, 128, band=3 voxel diagonals)``.
- **trimesh**: ``trimesh.proximity.signed_distance`` on a random subset of
  the grid points, extrapolated linearly to the whole grid (it is far too slow
  for all of them).
- **Open3D**: ``RaycastingScene.compute_signed_distance`` on all grid points
  (Embree BVH; sign by ray parity), when ``open3d`` imports.

The agreement of the peers' distances with splinekit's on the points they
computed is printed too (max |difference|, and the number of samples whose
sign differs; trimesh's sign convention is positive inside, so it is negated).
On the full case Open3D's ray-parity sign is wrong at 3 of the 1,854,840
samples (the generalized winding number, computed by brute force, agrees with
splinekit there), hence its max |difference| of about 0.5.

The grid is then meshed both ways: marching tetrahedra straight from the
samples (``SampledSDF.to_mesh()``, including the deviation measurement) and
the base class's meshing of the interpolant resampled for edge length ``h``,
the grid spacing (``SampledSDF.to_mesh(h)``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _ratios import report, skipped

from splinekit.implicit import from_mesh
from splinekit.mesh import PolyMesh, primitives
from splinekit.mesh.geometry import triangulate


def _timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def lumpy_sphere(level):
    m = primitives.icosphere(level)
    V = np.asarray(m.vertices)
    th = np.arctan2(V[:, 1], V[:, 0])
    ph = np.arccos(np.clip(V[:, 2], -1.0, 1.0))
    r = 1.0 + 0.3 * np.sin(3 * th) * np.sin(ph) ** 2 + 0.15 * np.cos(5 * ph)
    return PolyMesh(V * r[:, None], m.faces)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--quick", action="store_true", help="small case")
    args = ap.parse_args()
    level, res, subset = (4, 48, 1000) if args.quick else (6, 128, 3000)
    mesh = lumpy_sphere(level)
    V = np.asarray(mesh.vertices)
    T, _ = triangulate(mesh)
    print(f"mesh: {len(T)} triangles; grid resolution {res}")

    sdf, t_first = _timed(from_mesh, mesh, res)
    sdf, t_sk = _timed(from_mesh, mesh, res)
    n = int(np.prod(sdf.shape))
    print(f"splinekit from_mesh           : {t_sk:8.3f} s  ({n} samples, {n / t_sk / 1e6:.2f} M/s; first call {t_first:.3f} s)")
    band = 3.0 * float(np.linalg.norm(sdf.spacing))
    nb, t_nb = _timed(from_mesh, mesh, res, band=band)
    print(f"splinekit from_mesh, band     : {t_nb:8.3f} s  ({nb.n_stored} samples stored of {n}, {nb.nbytes() / 1e6:.1f} MB)")
    pts = sdf.points().reshape(-1, 3)
    ref = sdf.values.ravel()

    rng = np.random.default_rng(0)
    pick = rng.choice(n, subset, replace=False)
    try:
        import trimesh
    except ImportError:
        skipped("trimesh", "not installed")
    else:
        tm = trimesh.Trimesh(V, T, process=False)
        d_tm, t_tm = _timed(trimesh.proximity.signed_distance, tm, pts[pick])
        t_ext = t_tm * n / subset
        diff = np.abs(-d_tm - ref[pick])
        print(
            f"trimesh signed_distance       : {t_ext:8.3f} s  extrapolated from {subset} points in {t_tm:.3f} s; "
            f"ratio trimesh / splinekit = {t_ext / t_sk:.1f}; max |diff| {diff.max():.2e}, "
            f"sign mismatches {int(np.sum(np.sign(-d_tm) != np.sign(ref[pick])))} of {subset}"
        )
        report("mesh SDF grid: trimesh / splinekit", t_ext / t_sk, 3.0)
    try:
        import open3d as o3d
    except (ImportError, OSError) as exc:  # not installed, or a missing system library
        skipped("open3d", f"not available ({type(exc).__name__}: {exc})")
    else:
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)), o3d.core.Tensor(T.astype(np.uint32)))
        q = o3d.core.Tensor(pts.astype(np.float32))
        d_o3, t_o3 = _timed(lambda: scene.compute_signed_distance(q).numpy())
        diff = np.abs(d_o3 - ref)
        print(
            f"open3d compute_signed_distance: {t_o3:8.3f} s  ratio open3d / splinekit = {t_o3 / t_sk:.2f}; "
            f"max |diff| {diff.max():.2e} (float32), sign mismatches {int(np.sum(np.sign(d_o3) != np.sign(ref)))} of {n}"
        )
        report("mesh SDF grid: open3d / splinekit", t_o3 / t_sk, 3.0)

    # meshing the grid: marching tetrahedra straight from the samples vs the
    # base class's meshing of the interpolant resampled for edge length h
    m_grid, t_grid = _timed(sdf.to_mesh)
    h = float(sdf.spacing.min())
    m_ls, t_ls = _timed(sdf.to_mesh, h)
    print(
        f"to_mesh from the samples      : {t_grid:8.3f} s  ({m_grid.n_faces} triangles); "
        f"resampled for edge {h:.4g}: {t_ls:.3f} s ({m_ls.n_faces} triangles); ratio {t_ls / t_grid:.1f}"
    )


if __name__ == "__main__":
    main()
