#!/usr/bin/env python
"""Point classification of B-rep solids: ``Solid.contains`` against OpenCascade's
``BRepClass3d_SolidClassifier`` called per point from Python, and trimesh's ``contains`` on the
same tessellation, in one run.

Run from the repository root::

    python benchmarks/bench_contains.py            # 100,000 points per part, 3 repeats
    python benchmarks/bench_contains.py --quick    # 20,000 points, 1 repeat

Parts (build123d, converted with ``splinekit.occ.from_occ``; OCC classifies the build123d shape
itself): a 20 mm box minus a radius-4 through hole, and a 10 mm box with every edge filleted at
radius 2 (26 faces: planes, cylinders, sphere corners). Points: uniform in the part's bounding box.

Figures: splinekit's first call (tessellation of the solid and, in a fresh process, loading the
compiled nearest-triangle search) and its warm time (median of the repeats); OCC timed on an
evenly strided subset and extrapolated (trimesh too), both with a new classifier per point and with one
classifier re-used through ``Perform``; trimesh (ray tests) on splinekit's classification mesh.
Agreement: the share of the subset where OCC gives the same code (OCC's tolerance is the faces'
tolerance, as splinekit's), and where trimesh gives the same side (trimesh has no ON). The
ratios are the peer's time over splinekit's warm time; the target is 10 against OCC per point.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir)))

from _ratios import report, skipped  # noqa: E402
from splinekit.brep.classify import INSIDE, ON, OUTSIDE  # noqa: E402
from splinekit.occ import from_occ  # noqa: E402
from splinekit.tessellation.inside import solid_mesh_distance  # noqa: E402


TRIMESH_POINTS = 500
"""trimesh is timed on this many of the points (evenly strided) and extrapolated: its ray tests
without embree took 15 s and 2 GB for 2,000 points on the filleted box's mesh."""


def parts():
    import build123d as bd

    b = bd.Box(10, 10, 10)
    return {
        "box with hole": (bd.Box(20, 20, 20) - bd.Cylinder(4, 20)).solids()[0],
        "filleted box": b.fillet(2, b.edges()).solids()[0],
    }


def occ_classify(shape, points, tol, reuse):
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN, TopAbs_ON, TopAbs_OUT

    code = {TopAbs_IN: INSIDE, TopAbs_OUT: OUTSIDE, TopAbs_ON: ON}
    out = np.empty(len(points), dtype=np.int8)
    if reuse:
        c = BRepClass3d_SolidClassifier(shape)
        for i, p in enumerate(points):
            c.Perform(gp_Pnt(*map(float, p)), tol)
            out[i] = code[c.State()]
    else:
        for i, p in enumerate(points):
            out[i] = code[BRepClass3d_SolidClassifier(shape, gp_Pnt(*map(float, p)), tol).State()]
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20,000 points, one repeat")
    parser.add_argument("--points", type=int, default=None)
    parser.add_argument("--repeats", type=int, default=None)
    args = parser.parse_args(argv)
    n = args.points or (20_000 if args.quick else 100_000)
    repeats = args.repeats or (1 if args.quick else 3)
    n_occ = min(n, 2_000 if args.quick else 5_000)
    print(f"load average before: {os.getloadavg()[0]:.2f} (2 cores shared; other processes skew the times)")
    try:
        import trimesh
    except ImportError as exc:
        trimesh = None
        skipped("trimesh", exc)
    rows = []
    for name, shape in parts().items():
        solid = from_occ(shape.wrapped)
        tol = max(f.tolerance for f in solid.faces)
        bb = shape.bounding_box()
        lo, hi = np.array([bb.min.X, bb.min.Y, bb.min.Z]), np.array([bb.max.X, bb.max.Y, bb.max.Z])
        P = np.random.default_rng(0).uniform(lo, hi, (n, 3))
        t0 = time.perf_counter()
        ours = solid.contains(P)
        first = time.perf_counter() - t0
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            ours = solid.contains(P)
            times.append(time.perf_counter() - t0)
        warm = statistics.median(times)
        md, dev_bound = solid_mesh_distance(solid)
        rows.append((name, f"splinekit (first call {first:.2f} s)", warm, 1.0, "--", "--"))
        sub = np.linspace(0, n - 1, n_occ).astype(np.intp)
        for reuse, label in ((False, "OCC new classifier per point"), (True, "OCC one classifier, Perform")):
            t0 = time.perf_counter()
            occ = occ_classify(shape.wrapped, P[sub], tol, reuse)
            t = (time.perf_counter() - t0) * n / n_occ
            agree = float(np.mean(occ == ours[sub]))
            rows.append((name, label + f" (x{n / n_occ:.0f} of {n_occ})", t, t / warm, f"{agree:.4%}", "--"))
        if trimesh is not None:
            # a subset: without embree trimesh's ray tests take ~8 ms and ~1 MB a point here
            tsub = np.linspace(0, n - 1, min(n, TRIMESH_POINTS)).astype(np.intp)
            tm = trimesh.Trimesh(md.V, md.tris, process=False)
            t0 = time.perf_counter()
            inside = tm.contains(P[tsub])
            t = (time.perf_counter() - t0) * n / len(tsub)
            agree = float(np.mean(inside == (ours[tsub] == INSIDE)))
            rows.append((name, f"trimesh contains, {len(md.tris)} tri. (x{n / len(tsub):.0f} of {len(tsub)})", t,
                         t / warm, "--", f"{agree:.4%}"))
        print(f"{name}: {len(solid.faces)} faces, {len(md.tris)} mesh triangles, band +-{dev_bound + tol:.2g}, "
              f"{int((ours == INSIDE).sum())} inside, {int((ours == ON).sum())} on, {int((ours == OUTSIDE).sum())} outside")
    print()
    header = ("part", "classifier", f"time s ({n} pts)", "peer / splinekit", "same as OCC", "same side as trimesh")
    widths = [14, 52, 18, 16, 12, 20]
    print("  ".join(h.ljust(w) for h, w in zip(header, widths)))
    print("  ".join("-" * w for w in widths))
    for name, label, t, ratio, a_occ, a_tm in rows:
        cells = (name, label, f"{t:.3f}", f"{ratio:.1f}", a_occ, a_tm)
        print("  ".join(c.ljust(w) for c, w in zip(cells, widths)))
    print(f"\nload average after: {os.getloadavg()[0]:.2f}")
    for name, label, _, ratio, _, _ in rows:
        if label.startswith("OCC new"):
            report(f"contains {name}: OCC classifier per point / splinekit", ratio, 10.0)
        elif label.startswith("OCC one"):
            report(f"contains {name}: OCC re-used classifier / splinekit", ratio, 10.0)
        elif label.startswith("trimesh"):
            report(f"contains {name}: trimesh / splinekit", ratio, 1.0)


if __name__ == "__main__":
    main()
