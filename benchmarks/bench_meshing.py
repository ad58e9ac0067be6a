#!/usr/bin/env python
"""Iso-surface meshing and mesh distance: time and accuracy of splinekit's one mesher and one mesh distance.

Run from the repository root::

    python benchmarks/bench_meshing.py           # finer grids, 400k query points
    python benchmarks/bench_meshing.py --quick   # coarser grids, 100k query points (well under a minute)

1. ``Implicit.to_mesh(h)`` on shapes with closed forms, checked as well as timed: a sphere
   (area ``4 pi R^2``, volume ``4/3 pi R^3``), a torus (area ``4 pi^2 R r``, volume
   ``2 pi^2 R r^2``) and a CSG tree (no closed form: only closedness and the measured deviation).
   Each row gives the time, the triangles, whether the mesh is closed, its Euler characteristic
   (2 for a sphere, 0 for a torus), the relative area and volume errors and the mesh's measured
   ``deviation`` next to the true largest distance of its vertices from the surface.
2. ``from_mesh(torus mesh, resolution)``: the exact signed-distance grid of a closed mesh; its
   samples are compared with a brute-force distance to every triangle on a strided subset.
3. ``closest_points_on_mesh``: exact unsigned distance from random points to a torus mesh,
   compared with brute force on a strided subset.

Times are medians of repeats after one warm-up call (compiled kernels loaded), so they measure
the warm path; the load average is printed since other processes skew the figures.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import time

import numpy as np

import splinekit.implicit as si
from splinekit.mesh import primitives
from splinekit.pointcloud import closest_points_on_mesh
from splinekit.pointcloud.meshdistance import closest_points_on_triangles


def measure(fn, repeats=3):
    """Median wall time of ``fn()`` after one warm-up call: ``(seconds, result)``."""
    fn()
    times, result = [], None
    for _ in range(repeats):
        gc.collect()
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def brute_distance(V, T, P):
    """Distance from each point ``(m, 3)`` to every triangle, the minimum: ``(m,)`` (reference)."""
    A, B, C = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    out = np.empty(len(P))
    for i, p in enumerate(P):  # a reference, not a hot path
        q = closest_points_on_triangles(np.broadcast_to(p, A.shape), A, B, C)
        out[i] = np.linalg.norm(q - p, axis=1).min()
    return out


def mesh_rows(quick):
    R, r = 1.0, 0.35
    shapes = [
        ("sphere R=1", si.sphere((0.1, -0.2, 0.05), R), 4 * np.pi * R**2, 4 / 3 * np.pi * R**3,
         lambda p: np.abs(np.linalg.norm(p - (0.1, -0.2, 0.05), axis=1) - R), 2),
        ("torus 1, 0.35", si.torus((0, 0, 0), R, r), 4 * np.pi**2 * R * r, 2 * np.pi**2 * R * r**2,
         lambda p: np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - R, p[:, 2]) - r), 0),
        ("CSG tree", (si.box((0, 0, 0), (1.6, 1.2, 1.0)) - si.cylinder((0, 0, 0), 0.25, 3.0, axis=(1, 0, 0)))
         | si.smooth_union(si.sphere((0.9, 0.6, 0.5), 0.5), si.torus((0.9, 0.6, 0.5), 0.6, 0.15), 0.2),
         None, None, None, None),
    ]
    edges = (0.05, 0.025) if quick else (0.025, 0.0125)
    rows = []
    for name, shape, area, volume, dist, euler in shapes:
        for h in edges:
            t, m = measure(lambda s=shape, h=h: s.to_mesh(h))
            V = np.asarray(m.vertices)
            row = [name, h, t, m.n_faces, m.is_closed, m.euler_characteristic]
            if area is None:
                row += ["", "", f"{m.deviation:.2e}", ""]
            else:
                assert m.euler_characteristic == euler, (name, h, m.euler_characteristic)
                row += [f"{m.area / area - 1:+.2e}", f"{m.volume / volume - 1:+.2e}",
                        f"{m.deviation:.2e}", f"{dist(V).max():.2e}"]  # fmt: skip
            rows.append(row)
    print("| shape | h | to_mesh | triangles | closed | Euler | area rel. err | volume rel. err | deviation "
          "| true vertex dist |")
    print("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|")
    for name, h, t, nf, closed, chi, ea, ev, dev, true in rows:
        print(f"| {name} | {h} | {t * 1e3:.1f} ms | {nf} | {closed} | {chi} | {ea} | {ev} | {dev} | {true} |")


def distance_rows(quick):
    mesh = primitives.torus(96, 48, 1.0, 0.35)
    V = np.asarray(mesh.vertices)
    T = np.asarray(mesh.faces)
    T = np.concatenate([T[:, [0, 1, 2]], T[:, [0, 2, 3]]])  # the quads fan-split
    res = 64 if quick else 128
    t, sdf = measure(lambda: si.from_mesh(mesh, res))
    pts = sdf.points().reshape(-1, 3)
    pick = np.linspace(0, len(pts) - 1, 300).astype(np.int64)
    err = np.abs(np.abs(sdf.values.ravel()[pick]) - brute_distance(V, T, pts[pick])).max()
    print(f"\nfrom_mesh(torus, {res}): {t * 1e3:.1f} ms for {len(pts)} samples "
          f"({len(pts) / t / 1e6:.2f} M/s), max |d| error on 300 samples {err:.1e}")  # fmt: skip
    n = 100_000 if quick else 400_000
    P = np.random.default_rng(3).uniform(-1.6, 1.6, (n, 3))
    t, (d, _, _) = measure(lambda: closest_points_on_mesh(mesh, P))
    pick = np.linspace(0, n - 1, 300).astype(np.int64)
    err = np.abs(d[pick] - brute_distance(V, T, P[pick])).max()
    print(f"closest_points_on_mesh(torus, {n} points): {t * 1e3:.1f} ms ({n / t / 1e6:.2f} M/s), "
          f"max error on 300 points {err:.1e}")  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="coarser grids and fewer points")
    args = ap.parse_args(argv)
    print(f"# bench_meshing ({'quick' if args.quick else 'full'}): python {platform.python_version()}, "
          f"numpy {np.__version__}, load average {os.getloadavg()[0]:.2f}\n")  # fmt: skip
    mesh_rows(args.quick)
    distance_rows(args.quick)


if __name__ == "__main__":
    main()
