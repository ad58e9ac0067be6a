"""Point-cloud normals benchmark: splinekit against Open3D (and trimesh), in one run.

Run from the repository root::

    python benchmarks/bench_pointcloud.py           # 1M points; Open3D's orientation on 100k (minutes)
    python benchmarks/bench_pointcloud.py --quick   # 200k points, orientation on 50k (about a minute)
    python benchmarks/bench_pointcloud.py --row     # only the issue-17 row (300k points, a minute)

Part 0, the issue-17 row: PCA normals, k = 16, unoriented, on 300k torus points (100k with
``--quick``), every implementation timed interleaved with the others (best of several rounds,
the machine is shared) and its peak memory measured in a fresh child process (growth of
VmHWM) against the size of the output, the ``(n, 3)`` float64 normals:

- splinekit ``estimate_normals(P, 16, orient=False)`` on its compiled path (``SPLINEKIT_NUMBA=1``:
  the steady state; the first call, which loads or compiles the kernels, is printed apart);
- splinekit's numpy path (``SPLINEKIT_NUMBA=0``: cKDTree query with ``workers=-1``, the
  closed-form eigen-solve);
- the plain scipy version the issue names: ``cKDTree(P).query(P, 16, workers=-1)`` and
  ``numpy.linalg.eigh`` on the batched covariances;
- pykdtree (OpenMP kNN) with the same batched ``eigh``, when installed (the option of taking
  it as a core dependency);
- Open3D ``estimate_normals(KDTreeSearchParamKNN(16))``.

Each implementation's wall time and CPU time (all its threads) are printed: on this shared
2-core machine the wall time swings with the other users' load (Open3D's OpenMP threads wait
for each other at barriers and suffer most), the CPU time much less.

Profile, first round (300k points, k = 16, this 2-core machine under a load average of 7): the
numpy path spent about 65 % of its time in the cKDTree query (6.4 s of 9.9 s), 16 % gathering
the ``(n, 16, 3)`` neighbourhoods and forming covariances, 2 % building the tree and 3 % in the
closed-form eigen-solve (``numpy.linalg.eigh``: four times that). pykdtree's query was no
faster than cKDTree's with ``workers=-1`` here (two cores: its OpenMP gain does not show), so
it was not taken. A compiled bounding-volume hierarchy over the points in Morton order
(``splinekit/pointcloud/_knn_kernels.py``), queried in Morton order with the covariance and
eigen-solve in the same pass, then made the row: 0.38 s against Open3D's 0.68 s on an idle
machine (1.8x, short of the 2x target), about 90 % of it the search: some 75 tree nodes, 11
leaves, 90 distances and 34 ordered insertions a query.

Profile, second round (this session; CPU time of one thread, load average about 4-5, 300k
points; 100k in brackets): the hierarchy path 671 ms (207 ms); the grid path that replaced it
(``splinekit/pointcloud/_cellgrid_kernels.py``) 270 ms (80 ms), 2.5 times less. Its stages:
validation 0.5 ms, bounding box 0.9 ms, the cell side from two to four crowding trials 3.7 ms
(1.0 ms), the counting sort by cell 9.4 ms (2.2 ms), the search 184 ms (46 ms), covariance and
eigen-solve 68 ms (24 ms), the checks after 1.2 ms. Within the search (about 0.6 microseconds
a query): gathering the 27 cells' ~117 candidates once per cell (7.5 points a cell) ~30 ms;
selecting the k nearest ~105 ms (squared distances and threshold passes, which vectorize,
~16 ms; compacting the ~1.5 k candidates under the threshold and dropping the farthest down
to k the rest: an ordered insertion of them cost 1.4 times as much, a binary heap over all
candidates, the first try, 1.35 times as much for the whole kernel); the settling check, the
wide 5 x 5 x 5 block (9 queries of 300k on the torus) and the loop the rest. The fixed cost
of a call (everything but search and normals) is about 15 ms at 300k, 4 ms at 100k. The row
hash matters: a linear one made the rows a surface passes through collide, and at 100k points
half the candidates came from other rows (now 6-9 %). What limits it now: the selection of
the k nearest among ~7 k candidates (smaller cells give fewer candidates but send more
queries to the wide block: 1.13 times slower at a side of 1.1 k-th distances), then the
closed-form eigen-solve (an arccos and two cosines a point, ~110 ns) and the covariance. Two
threads split the points evenly (tasks of 1024 grid-sorted points); on this loaded machine the
second thread rarely got a core of its own (two threads: the same CPU time, no shorter wall).

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
through OpenMP; splinekit's compiled search and normals use all cores (numba
threads), its numpy path's k-d tree queries too (``workers=-1``). The load
average is printed: other processes on the machine skew the timings.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_eval import Table, measure, versions

from _kernel_switch import with_numba
from _memory import in_child, mb, measure_here

from splinekit.pointcloud import estimate_normals, orient_normals

K = 16

ROW_POINTS = {True: 100_000, False: 300_000}  # --quick, full
ROW_TARGETS = {"open3d": 2.0, "scipy": 3.0}  # issue 17: splinekit at least this many times faster


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


def batched_eigh_normals(P, idx):
    X = P[idx]
    X -= X.mean(axis=1)[:, None]
    return np.linalg.eigh(np.einsum("nki,nkj->nij", X, X) / K)[1][:, :, 0]


def plain_scipy(P):
    from scipy.spatial import cKDTree

    _, idx = cKDTree(P).query(P, K, workers=-1)
    return batched_eigh_normals(P, idx)


def pca_impls(o3d):
    """``[(key, label, fn(P))]`` of the row's implementations that can run here, and skip notes."""
    impls = [
        ("splinekit", "**splinekit** estimate_normals(orient=False)",
         lambda P: with_numba("1", lambda: estimate_normals(P, K, orient=False))),
        ("numpy", "splinekit numpy path (SPLINEKIT_NUMBA=0)",
         lambda P: with_numba("0", lambda: estimate_normals(P, K, orient=False))),
        ("scipy", "plain scipy: cKDTree query (workers=-1) + numpy.linalg.eigh", plain_scipy),
    ]
    skipped = []
    try:
        from pykdtree.kdtree import KDTree

        impls.append(("pykdtree", "pykdtree query (OpenMP) + numpy.linalg.eigh",
                      lambda P: batched_eigh_normals(P, KDTree(P).query(P, k=K)[1].astype(np.int64))))
    except ImportError as exc:
        skipped.append(f"pykdtree: not run ({exc})")
    if isinstance(o3d, Exception):
        skipped.append(f"Open3D: not run ({type(o3d).__name__}: {o3d})")
    else:
        impls.append(("open3d", "Open3D estimate_normals(KNN 16)", lambda P: o3d_normals(o3d, P)))
    return impls, skipped


def issue_row(quick: bool, o3d) -> None:
    """Part 0 (module notes): the issue-17 row, interleaved, with peak memory from child processes."""
    n = ROW_POINTS[quick]
    rounds = 3 if quick else 5
    P, true = torus_cloud(n)
    impls, skipped = pca_impls(o3d)
    first, best, cpu, out = {}, {}, {}, {}
    for key, _, fn in impls:  # warm-up: loads kernels, thread pools, imports
        t = time.perf_counter()
        out[key] = fn(P)
        first[key] = time.perf_counter() - t
        best[key] = cpu[key] = np.inf
    for _ in range(rounds):
        for key, _, fn in impls:
            c, t = time.process_time(), time.perf_counter()
            fn(P)
            best[key] = min(best[key], time.perf_counter() - t)
            cpu[key] = min(cpu[key], time.process_time() - c)
    out_bytes = n * 3 * 8
    script = os.path.abspath(__file__)
    print(f"## issue-17 row: PCA normals, k = {K}, unoriented, {n} torus points "
          f"(best of {rounds} interleaved rounds; load average {os.getloadavg()[0]:.2f})\n")
    print("| implementation | best s | peer / splinekit | CPU s (all threads) | CPU peer / splinekit "
          f"| max angle to the true normal | peak memory (output {mb(out_bytes)}) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    ours = best["splinekit"]
    for key, label, _ in impls:
        peak = in_child(script, f"{key}:{n}", {"SPLINEKIT_NUMBA": "1" if key == "splinekit" else "0"})
        ratio = best[key] / ours
        print(f"| {label} | {best[key]:.3f} | {ratio:.2f} | {cpu[key]:.3f} | {cpu[key] / cpu['splinekit']:.2f} "
              f"| {max_line_angle(out[key], true):.2f} deg | {mb(peak)} |")
    for note in skipped:
        print(f"| {note} | | | | | | |")
    print(f"\nsplinekit's first call (kernels loaded from numba's cache, or compiled): {first['splinekit']:.3f} s")
    for key, target in ROW_TARGETS.items():
        if key in best:
            ratio = best[key] / ours
            print(f"target: {key} / splinekit >= {target}: {ratio:.2f} -> {'met' if ratio >= target else 'NOT met'}")
        else:
            print(f"target: {key} / splinekit >= {target}: peer not run")
    print()


def child(spec: str) -> None:
    """``--child key:n``: the peak RSS growth of one implementation (as JSON on the last line)."""
    key, n = spec.split(":")
    P, _ = torus_cloud(int(n))
    impls, _ = pca_impls(open3d_module())
    fn = dict((k, f) for k, _, f in impls)[key]
    print(json.dumps(measure_here(lambda: fn(P))))


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
    ap.add_argument("--row", action="store_true", help="only the issue-17 row (part 0)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child(args.child)
        return
    cfg = sizes(args.quick)
    start = time.perf_counter()
    o3d = open3d_module()
    print(f"# point-cloud normals ({'quick' if args.quick else 'full'} sizes)\n")
    print(versions() + (f", open3d {o3d.__version__}" if not isinstance(o3d, Exception) else ", open3d missing"))
    print(f"{os.cpu_count()} CPUs\n")
    issue_row(args.quick, o3d)
    if args.row:
        return
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

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs\n")
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads
    print(f"\ntotal {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
