#!/usr/bin/env python
"""Implicit-surface benchmark: SDF evaluation of a CSG tree and meshing, in one run.

Run from the repository root::

    python benchmarks/bench_implicit.py           # 1M points (about a minute)
    python benchmarks/bench_implicit.py --quick   # 100k points (well under 30 s)

Shape: ``(box - three axis cylinders) | smooth_union(sphere, torus)``, about
2.5 units across.

1. Signed distance at N random points in its bounding box:

   - splinekit's CSG tree (analytic, vectorized);
   - the same formulas written inline in numpy (the floor for an object tree
     evaluated node by node in numpy);
   - trimesh ``proximity.signed_distance`` and Open3D
     ``RaycastingScene.compute_signed_distance`` on a triangle mesh of the same
     shape (``to_mesh`` at edge length 0.03). They answer a different question
     (the distance to a mesh, not to the exact shape), so the max-difference
     column is the meshing error plus their own; trimesh is timed on an evenly
     strided subset and extrapolated (the table says so).

2. ``to_mesh`` at two edge lengths: total time, the part spent sampling the
   tree vectorized on the meshing grid, triangles and the measured
   deviation; and, at the coarse edge, manifold3d's ``level_set`` calling the
   tree point by point from Python, the approach the vectorized sampling
   replaced (``bench_meshing.py`` compares the meshers' accuracy).

Times are medians of several repeats (one run for slow cases); ratios are
peer time / splinekit time.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import time

import numpy as np
from _ratios import report, skipped

import splinekit.implicit as si
from splinekit.implicit import meshing


def measure(fn, max_repeats=5):
    """Median wall time of ``fn()`` after one warm-up call: ``(seconds, result)``."""
    gc.collect()
    t0 = time.perf_counter()
    result = fn()
    first = time.perf_counter() - t0
    if first > 2.0:
        return first, result
    times = []
    wanted = max_repeats if first < 0.3 else min(3, max_repeats) if first < 1.0 else 1
    while len(times) < wanted:
        gc.collect()
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def fmt_t(t):
    if t is None:
        return "n/a"
    return f"{t * 1e3:.1f} ms" if t < 1.0 else f"{t:.2f} s"


# -- the shape ------------------------------------------------------------------------------------
BOX_C, BOX_S = np.array([0.0, 0.0, 0.0]), np.array([1.6, 1.2, 1.0])
CYL_R, CYL_H = 0.25, 3.0
SPH_C, SPH_R = np.array([0.9, 0.6, 0.5]), 0.5
TOR_C, TOR_R, TOR_r = np.array([0.9, 0.6, 0.5]), 0.6, 0.15
BLEND = 0.2


def make_tree():
    body = si.box(BOX_C, BOX_S)
    for axis in np.eye(3):
        body = body - si.cylinder(BOX_C, CYL_R, CYL_H, axis=axis)
    return body | si.smooth_union(si.sphere(SPH_C, SPH_R), si.torus(TOR_C, TOR_R, TOR_r), BLEND)


def inline_numpy(p):
    """The same signed distance, written out in plain numpy."""
    q = np.abs(p - BOX_C) - 0.5 * BOX_S
    body = np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)
    v = p - BOX_C
    for k in range(3):
        rho = np.sqrt(v[:, (k + 1) % 3] ** 2 + v[:, (k + 2) % 3] ** 2)
        d = np.stack([rho - CYL_R, np.abs(v[:, k]) - 0.5 * CYL_H], axis=1)
        cyl = np.linalg.norm(np.maximum(d, 0.0), axis=1) + np.minimum(d.max(axis=1), 0.0)
        body = np.maximum(body, -cyl)
    sph = np.linalg.norm(p - SPH_C, axis=1) - SPH_R
    w = p - TOR_C
    tor = np.hypot(np.hypot(w[:, 0], w[:, 1]) - TOR_R, w[:, 2]) - TOR_r
    h = np.clip(0.5 + 0.5 * (tor - sph) / BLEND, 0.0, 1.0)
    blend = h * sph + (1 - h) * tor - BLEND * h * (1 - h)
    return np.minimum(body, blend)


# -- cases ------------------------------------------------------------------------------------------
def bench_eval(rows, n, tree, mesh, trimesh_subset):
    lo, hi = tree.bounds
    p = np.random.default_rng(7).uniform(lo - 0.2, hi + 0.2, (n, 3))
    t_sk, ref = measure(lambda: tree(p))
    rows.append(("CSG SDF", "splinekit.implicit tree", n, t_sk, t_sk, 0.0, ""))
    t, out = measure(lambda: inline_numpy(p))
    rows.append(("CSG SDF", "inline numpy (same formulas)", n, t, t_sk, float(np.abs(out - ref).max()), ""))
    V, T = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    note_mesh = f"mesh of {len(T)} triangles"
    try:
        import trimesh

        tm = trimesh.Trimesh(V, T, process=False)
        idx = np.unique(np.linspace(0, n - 1, trimesh_subset).round().astype(np.intp))
        t, out = measure(lambda: trimesh.proximity.signed_distance(tm, p[idx]), max_repeats=1)
        rows.append(("CSG SDF", "trimesh proximity.signed_distance", n, t * n / len(idx), t_sk,
                     float(np.abs(-out - ref[idx]).max()), f"{note_mesh}; {len(idx)} points, extrapolated"))  # fmt: skip
    except ImportError:
        rows.append(("CSG SDF", "trimesh (not installed)", n, None, t_sk, None, ""))
    try:
        import open3d as o3d

        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)), o3d.core.Tensor(T.astype(np.uint32)))
        pf = o3d.core.Tensor(p.astype(np.float32))
        t, out = measure(lambda: scene.compute_signed_distance(pf).numpy())
        threads = os.environ.get("OMP_NUM_THREADS", "all cores")
        rows.append(("CSG SDF", "Open3D RaycastingScene.compute_signed_distance", n, t, t_sk,
                     float(np.abs(out - ref).max()), f"{note_mesh}; float32; threads: {threads}"))  # fmt: skip
    except (ImportError, OSError) as exc:  # not installed, or a missing system library (libusb)
        rows.append(("CSG SDF", f"Open3D (not available: {type(exc).__name__}: {str(exc)[:60]})", n, None, t_sk, None, ""))


def bench_mesh(rows, tree, edges, naive_edge):
    for h in edges:
        lo, hi = tree.bounds
        lo, hi = lo - meshing.PADDING * h, hi + meshing.PADDING * h
        counts, spacing = meshing._grid_axes(lo, hi, h)
        t_sample, _ = measure(lambda lo=lo, s=spacing, c=counts: meshing._sample(tree, lo, s, c), max_repeats=3)
        t_mesh, mesh = measure(lambda h=h: tree.to_mesh(h), max_repeats=3)
        grid = int(np.prod(counts))
        note = f"{mesh.n_faces} triangles, deviation {mesh.deviation:.2e}, sampling {fmt_t(t_sample)} of it"
        rows.append((f"to_mesh h={h}", "splinekit (vectorized grid + marching tetrahedra)", grid, t_mesh, t_mesh, None, note))
        if h == naive_edge:
            import manifold3d

            def naive(box=list(lo) + list(hi), h=h):
                def f(x, y, z):
                    return -float(tree(np.array([[x, y, z]]))[0])

                return manifold3d.Manifold.level_set(f, box, h)

            t, m = measure(naive, max_repeats=1)
            rows.append((f"to_mesh h={h}", "manifold3d level_set calling the tree per point", grid, t, t_mesh, None,
                         f"{len(m.to_mesh().tri_verts)} triangles"))  # fmt: skip


def render(rows):
    out = ["| case | implementation | n | time | ns/point | ratio (this / splinekit) | max diff | note |",
           "|---|---|---:|---:|---:|---:|---:|---|"]  # fmt: skip
    for case, impl, n, t, ref, diff, note in rows:
        ns = "n/a" if t is None else f"{t / n * 1e9:.0f}"
        ratio = "n/a" if t is None else f"{t / ref:.2f}"
        d = "" if diff is None else f"{diff:.2e}"
        out.append(f"| {case} | {impl} | {n:,} | {fmt_t(t)} | {ns} | {ratio} | {d} | {note} |")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes")
    args = ap.parse_args(argv)
    n = 100_000 if args.quick else 1_000_000
    edges = (0.08, 0.05) if args.quick else (0.05, 0.025)
    tree = make_tree()
    print(f"# bench_implicit ({'quick' if args.quick else 'full'}): python {platform.python_version()}, "
          f"numpy {np.__version__}, load average {os.getloadavg()[0]:.2f}\n")  # fmt: skip
    t0 = time.perf_counter()
    mesh = tree.to_mesh(0.03)
    print(f"reference mesh for the mesh-based peers: {mesh.n_faces} triangles in {time.perf_counter() - t0:.2f} s, "
          f"deviation {mesh.deviation:.2e}\n")  # fmt: skip
    rows = []
    bench_eval(rows, n, tree, mesh, trimesh_subset=1_000 if args.quick else 3_000)
    bench_mesh(rows, tree, edges, naive_edge=edges[0])
    print(render(rows))
    print()
    for case, impl, _, t, ref, _, note in rows:  # the lines check_ratios.py reads
        if "splinekit" in impl:
            continue
        if t is None:
            skipped(f"{case} / {impl}", note or "not run")
        else:
            report(f"{case} / {impl}", t / ref, 1.0)


if __name__ == "__main__":
    main()
