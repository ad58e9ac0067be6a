"""Edge-continuity benchmark: splinekit.analysis against OpenCascade's LocalAnalysis, in one run.

Run from the repository root::

    python benchmarks/bench_continuity.py           # 32 samples per edge
    python benchmarks/bench_continuity.py --quick   # 8 samples per edge

Cases:

* the Utah teapot (``models/teapot.py``: 32 Bézier patches, 8 with collapsed sides);
* the mug (``models/mug.py``): its 536 bicubic patches (the Catmull-Clark cage refined once and
  converted by ``to_bsplines(0)``), and the Catmull-Clark limit surface itself (134 quads).

splinekit: ``shell_continuity(part, samples)`` from scratch: it finds the shared edges (end points,
then one side lying on the other), the corresponding parameters on both sides, and G0 gap, G1
angle and G2 curvature jump at every sample. Peer: OpenCascade's
``LocalAnalysis_SurfaceContinuity(s1, u1, v1, s2, u2, v2, GeomAbs_G2)`` called per point from
Python on the same parameter pairs (which it is given: the edge finding is splinekit's work
only), reading ``C0Value``, ``G1Angle`` and ``G2CurvatureGap``. OCC cannot evaluate a
Catmull-Clark limit surface, so that case has no peer.

Agreement: the largest difference of the G0 gap and of the G1 angle (OCC folds it into
[0, pi/2]) over the points where OCC is done (it is not at the teapot's poles).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_eval import Table, measure, versions

import splinekit as sk
from splinekit.analysis import shell_continuity


def occ_pairs(handles, report):
    """``[(h1, u1, v1, h2, u2, v2), ...]`` for every sample of every edge of ``report``."""
    out = []
    for e in report.edges:
        ha, hb = handles[e.patches[0]], handles[e.patches[1]]
        for (ua, va), (ub, vb) in e.uv.tolist():
            out.append((ha, ua, va, hb, ub, vb))
    return out


def occ_loop(pairs):
    from OCP.GeomAbs import GeomAbs_Shape
    from OCP.LocalAnalysis import LocalAnalysis_SurfaceContinuity

    g2 = GeomAbs_Shape.GeomAbs_G2
    out = np.full((len(pairs), 3), np.nan)
    for i, (ha, ua, va, hb, ub, vb) in enumerate(pairs):
        la = LocalAnalysis_SurfaceContinuity(ha, ua, va, hb, ub, vb, g2)
        if la.IsDone():
            out[i] = la.C0Value(), la.G1Angle(), la.G2CurvatureGap()
    return out


def agreement(report, occ) -> tuple[float, str]:
    gap = np.concatenate([e.gap for e in report.edges])
    angle = np.concatenate([np.minimum(e.angle, np.pi - e.angle) for e in report.edges])
    done = np.isfinite(occ[:, 0])
    diff = max(float(np.abs(occ[done, 0] - gap[done]).max()), float(np.abs(occ[done, 1] - angle[done]).max()))
    return diff, f"gap and angle; OCC done at {int(done.sum()):,} of {len(done):,} points"


def cpu_seconds(fn) -> float:
    """CPU time of one call: on a machine shared with other processes it says more than wall time."""
    start = time.process_time()
    fn()
    return time.process_time() - start


def run_case(tab, case, part, patches, samples):
    t_ours, reps, report = measure(lambda: shell_continuity(part, samples=samples), max_repeats=3)
    cpu_ours = cpu_seconds(lambda: shell_continuity(part, samples=samples))
    n = sum(e.gap.size for e in report.edges)
    s = report.summary
    tab.add(case, "**splinekit** `shell_continuity`", n, t_ours, ref=t_ours, repeats=reps,
            note=f"CPU {cpu_ours:.3g} s; {s['edges']} edges: G2 {s['G2']}, G1 {s['G1']}, G0 {s['G0']}, none {s['none']}; "
                 "edge finding included")
    if patches is None:
        return report
    try:
        handles = [sk.occ.to_occ(p) for p in patches]
        pairs = occ_pairs(handles, report)
        t_occ, reps, occ = measure(lambda: occ_loop(pairs), max_repeats=3)
        cpu_occ = cpu_seconds(lambda: occ_loop(pairs))
        diff, note = agreement(report, occ)
        tab.add(case, "OCC `LocalAnalysis_SurfaceContinuity` per point", n, t_occ, ref=t_ours, repeats=reps, diff=diff,
                note=f"CPU {cpu_occ:.3g} s (CPU ratio {cpu_occ / cpu_ours:.2f}); {note}; given the parameter pairs")
    except Exception as exc:  # noqa: BLE001 - a peer that cannot run is reported, not fatal
        tab.fail(case, "OCC LocalAnalysis", exc)
    return report


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="8 samples per edge instead of 32")
    args = ap.parse_args(argv)
    samples = 8 if args.quick else 32
    load_start = os.getloadavg()[0]
    from models import build_model
    from models import mug

    tab = Table()
    teapot = build_model("teapot").bodies[0]
    run_case(tab, f"teapot, 32 Bézier patches, {samples} samples/edge", teapot, teapot, samples)
    mug_patches = build_model("mug").bodies[0]
    run_case(tab, f"mug, {len(mug_patches)} bicubic patches, {samples} samples/edge", mug_patches, mug_patches, samples)
    cage = mug.surface()
    run_case(tab, f"mug, Catmull-Clark limit surface ({cage.mesh.n_faces} quads), {samples} samples/edge", cage, None,
             samples)

    print(f"# splinekit edge-continuity benchmark{' (--quick)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print("points = samples over all edges; ratio = OCC time / splinekit time (> 1: splinekit is faster).")
    print()
    print(tab.render())


if __name__ == "__main__":
    main()
