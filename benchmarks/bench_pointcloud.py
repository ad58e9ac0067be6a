"""Point-cloud normals benchmark: splinekit against Open3D (and trimesh), in one run.

Run from the repository root::

    python benchmarks/bench_pointcloud.py           # 1M points; Open3D's orientation on 100k (minutes)
    python benchmarks/bench_pointcloud.py --quick   # 200k points, orientation on 50k (about a minute)

Cloud: points uniform by area on a torus (R = 1, r = 0.35) with exact outward
normals. Cases, all with k = 16 nearest neighbours:

1. PCA normals without orientation: ``splinekit.pointcloud.estimate_normals(P, k,
   orient=False)`` against Open3D ``PointCloud.estimate_normals(KDTreeSearchParamKNN(k))``.
   Accuracy: the largest angle between the estimated line and the true normal.
2. Consistent orientation alone, from unoriented normals:
   ``splinekit.pointcloud.orient_normals`` (minimum spanning tree on the kNN graph
   weighted by 1 - |n_i . n_j|, pointer-jumping sign propagation) against Open3D
   ``orient_normals_consistent_tangent_plane(k)`` (its Riemannian-graph MST).
   Accuracy: the fraction of normals pointing outward (1.0 = all; Open3D picks
   no global sign, so its fraction is max(f, 1 - f)).
3. Both together (what a user calls): normals and orientation.

trimesh has no point-cloud normal estimation (``trimesh.points`` offers a
single best-fit plane), so it is listed as not run. Open3D uses all cores
through OpenMP; splinekit's k-d tree queries use all cores (``workers=-1``),
the rest is single-threaded numpy. The load average is printed: other
processes on the machine skew the timings.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_eval import Table, measure, versions

from splinekit.pointcloud import estimate_normals, orient_normals

K = 16


def sizes(quick: bool) -> dict:
    # orientation sizes: (points, whether Open3D runs too); Open3D's orientation took 22 s
    # for 50k points here and grows faster than linearly, so it is not run on 1M
    if quick:
        return {"points": 200_000, "orient": [(50_000, True)], "max_repeats": 1}
    return {"points": 1_000_000, "orient": [(100_000, True), (1_000_000, False)], "max_repeats": 3}


def torus_cloud(n, R=1.0, r=0.35, seed=20261122):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2 * np.pi, 3 * n)
    v = rng.uniform(0, 2 * np.pi, 3 * n)
    keep = rng.uniform(0, 1 + r / R, 3 * n) < 1 + (r / R) * np.cos(v)  # uniform by area
    u, v = u[keep][:n], v[keep][:n]
    normal = np.column_stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)])
    return np.column_stack([R * np.cos(u), R * np.sin(u), np.zeros(n)]) + r * normal, normal


def max_line_angle(N, true):
    c = np.abs(np.einsum("nd,nd->n", N, true)) / np.linalg.norm(N, axis=1)
    return float(np.degrees(np.arccos(np.clip(c.min(), -1, 1))))


def outward_fraction(N, true, signless=False):
    f = float((np.einsum("nd,nd->n", N, true) > 0).mean())
    return max(f, 1 - f) if signless else f


def open3d_module():
    try:
        import open3d as o3d

        o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
        return o3d
    except Exception as exc:  # noqa: BLE001
        return exc


def o3d_normals(o3d, P):
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
    pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(K))
    return np.asarray(pc.normals)


def o3d_orient(o3d, P, N):
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
    pc.normals = o3d.utility.Vector3dVector(N)
    pc.orient_normals_consistent_tangent_plane(K)
    return np.asarray(pc.normals)


def o3d_both(o3d, P):
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
    pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(K))
    pc.orient_normals_consistent_tangent_plane(K)
    return np.asarray(pc.normals)


def row(tab, case, impl, n, fn, ref, accuracy, cfg):
    try:
        t, reps, out = measure(fn, cfg["max_repeats"])
    except Exception as exc:  # noqa: BLE001
        tab.fail(case, impl, exc)
        return None, None
    tab.add(case, impl, n, t, ref=ref, repeats=reps, note=accuracy(out))
    return t, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes, one repeat")
    args = ap.parse_args(argv)
    cfg = sizes(args.quick)
    start = time.perf_counter()
    o3d = open3d_module()
    tab = Table()

    n = cfg["points"]
    P, true = torus_cloud(n)
    case = f"PCA normals, k = {K}, unoriented"
    ours, N0 = row(tab, case, "**splinekit** estimate_normals(orient=False)", n,
                   lambda: estimate_normals(P, K, orient=False), None,
                   lambda N: f"max angle {max_line_angle(N, true):.2f} deg", cfg)
    tab.rows[-1]["ratio"] = 1.0 if ours else None
    if isinstance(o3d, Exception):
        tab.fail(case, "Open3D estimate_normals", o3d)
    else:
        row(tab, case, "Open3D estimate_normals", n, lambda: o3d_normals(o3d, P), ours,
            lambda N: f"max angle {max_line_angle(N, true):.2f} deg", cfg)
    tab.fail(case, "trimesh", RuntimeError("no point-cloud normal estimation in trimesh"))

    for m, with_o3d in cfg["orient"]:
        Pm, truem = (P, true) if m == n else torus_cloud(m, seed=7)
        Nm = N0 if m == n and N0 is not None else estimate_normals(Pm, K, orient=False)
        run_o3d = with_o3d and not isinstance(o3d, Exception)
        case = f"orientation only (MST), k = {K}"
        ours, _ = row(tab, case, "**splinekit** orient_normals", m, lambda: orient_normals(Pm, Nm, K), None,
                      lambda N: f"outward fraction {outward_fraction(N, truem):.6f}", cfg)
        tab.rows[-1]["ratio"] = 1.0 if ours else None
        if run_o3d:
            row(tab, case, "Open3D orient_normals_consistent_tangent_plane", m, lambda: o3d_orient(o3d, Pm, Nm),
                ours, lambda N: f"consistent fraction {outward_fraction(N, truem, signless=True):.6f} "
                "(no global sign)", cfg)
        case = f"normals + orientation, k = {K}"
        ours, _ = row(tab, case, "**splinekit** estimate_normals", m, lambda: estimate_normals(Pm, K), None,
                      lambda N: f"outward fraction {outward_fraction(N, truem):.6f}", cfg)
        tab.rows[-1]["ratio"] = 1.0 if ours else None
        if run_o3d:
            row(tab, case, "Open3D estimate_normals + orient_normals_consistent_tangent_plane", m,
                lambda: o3d_both(o3d, Pm), ours,
                lambda N: f"consistent fraction {outward_fraction(N, truem, signless=True):.6f} (no global sign)",
                cfg)

    print(f"# point-cloud normals ({'quick' if args.quick else 'full'} sizes)\n")
    print(versions() + (f", open3d {o3d.__version__}" if not isinstance(o3d, Exception) else ", open3d missing"))
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs\n")
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads
    print(f"\ntotal {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
