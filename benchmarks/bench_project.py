"""Closest-point (projection) benchmark: splinekit against its peers, in one run.

Run from the repository root::

    python benchmarks/bench_project.py           # full sizes (about a minute)
    python benchmarks/bench_project.py --quick   # smaller sizes (a few seconds)

Cases:

1. 10,000 random points, uniform in the bounding box of a bicubic NURBS surface
   (13 x 13 control points: 10 x 10 knot spans, a wavy height field, weights in
   [0.5, 2]) inflated by 10 % on every side, projected onto the surface.
2. 10,000 random points in the inflated bounding box of a cubic NURBS curve
   (50 control points, 47 spans), projected onto the curve.

Peers: OpenCascade from Python (OCP), called per point: ``GeomAPI_ProjectPointOnSurf``
/ ``GeomAPI_ProjectPointOnCurve`` built anew for each point (the usual idiom), and one
projector initialised once and re-used with ``Perform(point)`` (OCC keeps its sample
grid). OCC is timed on an evenly strided subset of the points and extrapolated
linearly; the table says so. geomdl 5.4 and splipy 1.10 have no point projection
(splipy's ``SplineObject.project`` projects onto coordinate planes), so they are
listed as not run.

Accuracy columns: OCC reports orthogonal feet only, so a point whose nearest surface
point lies on the boundary has no OCC answer or a farther one. "max |d diff|" is the
largest ``|d_splinekit - d_OCC|`` over the points where OCC's lowest distance is
within 1e-9 (relative) of splinekit's or better, i.e. where both found the same
minimum; the notes count the points where splinekit is nearer (by more than 1e-9 x
size), where OCC is nearer, and where OCC found nothing.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_eval import Table, first_call_note, measure, subset_index, versions

import splinekit as sk
from splinekit.basis.knots import clamped_uniform
from splinekit.closest import project


def sizes(quick: bool) -> dict:
    if quick:
        return {"points": 2_000, "occ_subset": 40, "max_repeats": 1}
    return {"points": 10_000, "occ_subset": 1_000, "max_repeats": 3}


def make_geometry(seed=20240602):
    rng = np.random.default_rng(seed)
    g = np.linspace(0.0, 1.0, 13)
    X, Y = np.meshgrid(g, g, indexing="ij")
    SP = np.stack([X, Y, rng.uniform(-0.3, 0.3, X.shape)], axis=-1)
    K = clamped_uniform(3, 13)
    surf = sk.NurbsSurface(3, 3, K, K, SP, rng.uniform(0.5, 2.0, (13, 13)))
    CP = np.cumsum(rng.uniform(-1.0, 1.0, (50, 3)), axis=0)
    curve = sk.NurbsCurve(3, clamped_uniform(3, 50), CP, rng.uniform(0.5, 2.0, 50))
    return rng, surf, curve


def box_points(rng, pts, n, inflate=0.1):
    flat = np.asarray(pts).reshape(-1, 3)
    lo, hi = flat.min(0), flat.max(0)
    pad = inflate * (hi - lo)
    return rng.uniform(lo - pad, hi + pad, (n, 3))


def occ_surface_new_each(h, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        pr = GeomAPI_ProjectPointOnSurf(gp_Pnt(x, y, z), h)
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
    return out


def occ_surface_reused(h, domain, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    (a, b), (c, d) = domain
    pr = GeomAPI_ProjectPointOnSurf()
    pr.Init(h, a, b, c, d)
    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        pr.Perform(gp_Pnt(x, y, z))
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
    return out


def occ_curve_new_each(h, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
    from OCP.gp import gp_Pnt

    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        pr = GeomAPI_ProjectPointOnCurve(gp_Pnt(x, y, z), h)
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
    return out


def occ_curve_reused(h, domain, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
    from OCP.gp import gp_Pnt

    a, b = domain
    pr = GeomAPI_ProjectPointOnCurve()
    pr.Init(h, a, b)
    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        pr.Perform(gp_Pnt(x, y, z))
        if pr.NbPoints():
            out[i] = pr.LowerDistance()
    return out


def compare(d_sk, d_occ, size):
    """``(max |diff| where both found the same minimum, notes)``.

    Same minimum: the distances agree within 1e-6 x size (OCC's default
    precision is coarser than splinekit's). splinekit nearer: by more than that
    (OCC missed the minimum, usually a boundary one). OCC nearer: by more than
    1e-9 x size (splinekit missed it)."""
    found = np.isfinite(d_occ)
    same = found & (np.abs(d_sk - d_occ) <= 1e-6 * size)
    sk_nearer = found & (d_sk < d_occ - 1e-6 * size)
    occ_nearer = found & (d_occ < d_sk - 1e-9 * size)
    diff = float(np.max(np.abs(d_sk[same] - d_occ[same]))) if same.any() else None
    worst = float((d_sk - d_occ)[occ_nearer].max()) if occ_nearer.any() else 0.0
    note = (f"same minimum at {int(same.sum())}, splinekit nearer at {int(sk_nearer.sum())}, "
            f"OCC nearer at {int(occ_nearer.sum())} (by up to {worst:.2g}), no OCC foot at {int((~found).sum())}")
    return diff, note


def bench_case(tab, cfg, label, geom, Q, peers):
    R = cfg["max_repeats"]
    N = len(Q)
    # warm-up on a few points: loads the compiled grid kernels (numba cache) so that
    # the measurement below times the projection itself
    t0 = time.perf_counter()
    project(geom, Q[:10])
    warm = time.perf_counter() - t0
    t_sk, k, res = measure(lambda: project(geom, Q), R)
    tab.add(label, "**splinekit** `project` (batch)", N, t_sk, ref=t_sk, repeats=k,
            note=f"{first_call_note()}; a first call on 10 points took {Table._fmt_t(warm)}")
    size = max(1.0, float(np.abs(geom.control_points).max()))
    sub = subset_index(N, cfg["occ_subset"])
    for name, fn in peers:
        try:
            t, k, out = measure(lambda fn=fn: fn(Q[sub]), R)
            diff, note = compare(res.distances[sub], out, size)
            m = len(sub)
            tab.add(label, name, N, t * N / m, ref=t_sk, diff=diff, repeats=k,
                    note=("all points" if m == N else f"extrapolated from {m:,} points") + "; " + note)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, name, exc)
    for lib in ("geomdl", "splipy"):
        tab.fail(label, lib, RuntimeError("no point projection / closest-point operation in the library"))
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats (a few seconds)")
    args = ap.parse_args(argv)
    cfg = sizes(args.quick)
    start = time.perf_counter()
    load_start = os.getloadavg()[0]
    rng, surf, curve = make_geometry()
    tab = Table()
    n = cfg["points"]

    Qs = box_points(rng, surf.control_points, n)
    hs = sk.occ.to_occ(surf)
    bench_case(tab, cfg, f"1. {n:,} points onto a bicubic NURBS surface, 10x10 spans", surf, Qs, [
        ("OCC `GeomAPI_ProjectPointOnSurf(pnt, surface)` per point", lambda Q: occ_surface_new_each(hs, Q)),
        ("OCC one `GeomAPI_ProjectPointOnSurf`, `Init` once, `Perform(pnt)` per point",
         lambda Q: occ_surface_reused(hs, surf.domain, Q)),
    ])

    Qc = box_points(rng, curve.control_points, n)
    hc = sk.occ.to_occ(curve)
    bench_case(tab, cfg, f"2. {n:,} points onto a cubic NURBS curve, 47 spans", curve, Qc, [
        ("OCC `GeomAPI_ProjectPointOnCurve(pnt, curve)` per point", lambda Q: occ_curve_new_each(hc, Q)),
        ("OCC one `GeomAPI_ProjectPointOnCurve`, `Init` once, `Perform(pnt)` per point",
         lambda Q: occ_curve_reused(hc, curve.domain, Q)),
    ])

    print(f"# splinekit projection benchmark{' (--quick: reduced sizes)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print("Times are for the full point count; ratio = peer time / splinekit time (> 1: splinekit is faster).")
    print("Rows marked 'extrapolated from N points' were timed on an evenly strided subset and scaled linearly.")
    print("splinekit's time includes sampling the geometry and building its k-d tree (once per call).")
    print("'max abs diff' is max |d_splinekit - d_OCC| over the points where both found the same minimum; "
          "OCC reports orthogonal feet only, so it misses boundary minima (see the notes).")
    print()
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads
    if tab.failures:
        print()
        print("## Peers not run")
        print()
        for case, impl, msg in tab.failures:
            print(f"- {case} / {impl}: {msg}")
    print()
    print(f"total benchmark time: {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
