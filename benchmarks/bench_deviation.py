"""Deviation benchmark: ``splinekit.analysis.deviation`` of a million points against its peers, in one run.

Run from the repository root::

    python benchmarks/bench_deviation.py           # 1,000,000 points per case (a few minutes)
    python benchmarks/bench_deviation.py --quick   # 20,000 points (well under a minute)

Cases (the points lie near the reference: surface points moved along random directions by up
to 2 % of its size, like a scan):

1. a bicubic NURBS surface (13 x 13 control points, 10 x 10 spans, weights in [0.5, 2]);
2. the Utah teapot from ``models`` (32 bicubic patches): a whole part;
3. a triangle mesh: the teapot tessellated (about 40,000 triangles).

Peers: OpenCascade from Python (OCP) called per point, ``GeomAPI_ProjectPointOnSurf`` built
anew per point (the usual idiom) and one projector initialised once per patch and re-used with
``Perform`` (for the teapot: every patch per point, the lowest distance kept); trimesh's
``proximity.closest_point`` for the mesh. The peers are timed on an evenly strided subset of
the points and extrapolated linearly (the table says so). "max abs diff" compares unsigned
distances where both found the same minimum (within 1e-6 of the size; OCC reports orthogonal
feet only and misses boundary minima).
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
from bench_project import compare

import splinekit as sk
from models import build_model
from splinekit.analysis import deviation, sample_sources
from splinekit.basis.knots import clamped_uniform


def sizes(quick: bool) -> dict:
    if quick:
        return {"points": 20_000, "occ_subset": 200, "teapot_subset": 40, "trimesh_subset": 5_000}
    return {"points": 1_000_000, "occ_subset": 2_000, "teapot_subset": 200, "trimesh_subset": 50_000}


def nurbs_surface(rng):
    g = np.linspace(0.0, 1.0, 13)
    X, Y = np.meshgrid(g, g, indexing="ij")
    cp = np.stack([X, Y, rng.uniform(-0.3, 0.3, X.shape)], axis=-1)
    K = clamped_uniform(3, 13)
    return sk.NurbsSurface(3, 3, K, K, cp, rng.uniform(0.5, 2.0, (13, 13)))


def scan_of(rng, patches, n):
    """``n`` points near the patches: random patch points moved by up to 2 % of the size."""
    pick = rng.integers(len(patches), size=n)
    uv = rng.uniform(0.0, 1.0, size=(n, 2))
    P = np.empty((n, 3))
    for k in range(len(patches)):  # one batch per patch
        rows = np.flatnonzero(pick == k)
        (a, b), (c, d) = patches[k].domain
        P[rows] = patches[k].evaluate(a + (b - a) * uv[rows, 0], c + (d - c) * uv[rows, 1])
    size = float(np.ptp(P, axis=0).max())
    return P + rng.uniform(-1.0, 1.0, size=P.shape) * 0.02 * size / np.sqrt(3.0), size


def occ_new_each(handles, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        for h in handles:
            pr = GeomAPI_ProjectPointOnSurf(gp_Pnt(x, y, z), h)
            if pr.NbPoints():
                out[i] = min(out[i], pr.LowerDistance())
    return out


def occ_reused(handles, domains, Q):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    projectors = []
    for h, ((a, b), (c, d)) in zip(handles, domains):
        pr = GeomAPI_ProjectPointOnSurf()
        pr.Init(h, a, b, c, d)
        projectors.append(pr)
    out = np.full(len(Q), np.inf)
    for i, (x, y, z) in enumerate(Q):
        p = gp_Pnt(x, y, z)
        for pr in projectors:
            pr.Perform(p)
            if pr.NbPoints():
                out[i] = min(out[i], pr.LowerDistance())
    return out


def trimesh_closest(mesh, Q):
    import trimesh

    tm = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=False)
    _, dist, _ = trimesh.proximity.closest_point(tm, Q)
    return dist


def bench_case(tab, cfg, label, reference, P, size, peers, subset_key):
    N = len(P)
    sources = sample_sources(reference)  # sampled once, as the CLI does; the timing is the measurement
    deviation(sources, P[:1000])  # warm-up: loads the compiled mesh search (numba cache)
    t_sk, k, res = measure(lambda: deviation(sources, P), 3, warm=True)
    tab.add(label, "**splinekit** `analysis.deviation` (batch, signed)", N, t_sk, ref=t_sk, repeats=k,
            note=f"{first_call_note()}; reference sampled beforehand ({sources.part.n_vertices:,} samples)")
    sub = subset_index(N, cfg[subset_key])
    mine = np.abs(res.distances)
    for name, fn in peers:
        try:
            t, k, out = measure(lambda fn=fn: fn(P[sub]), 1)
            diff, note = compare(mine[sub], out, size)
            m = len(sub)
            tab.add(label, name, N, t * N / m, ref=t_sk, diff=diff, repeats=k,
                    note=("all points" if m == N else f"extrapolated from {m:,} points") + "; " + note)
        except Exception as exc:  # noqa: BLE001 - a peer that cannot run is listed, not fatal
            tab.fail(label, name, exc)
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="20,000 points per case")
    args = ap.parse_args(argv)
    cfg = sizes(args.quick)
    start = time.perf_counter()
    load_start = os.getloadavg()[0]
    rng = np.random.default_rng(20241125)
    tab = Table()
    n = cfg["points"]

    surf = nurbs_surface(rng)
    P, size = scan_of(rng, [surf], n)
    h = [sk.occ.to_occ(surf)]
    bench_case(tab, cfg, f"1. {n:,} points near a bicubic NURBS surface (10x10 spans)", surf, P, size, [
        ("OCC `GeomAPI_ProjectPointOnSurf(pnt, surface)` per point", lambda Q: occ_new_each(h, Q)),
        ("OCC one `GeomAPI_ProjectPointOnSurf`, `Init` once, `Perform(pnt)` per point",
         lambda Q: occ_reused(h, [surf.domain], Q)),
    ], "occ_subset")

    patches = [p for body in build_model("teapot").bodies for p in body]
    P, size = scan_of(rng, patches, n)
    hs = [sk.occ.to_occ(p) for p in patches]
    bench_case(tab, cfg, f"2. {n:,} points near the teapot (32 bicubic patches)", patches, P, size, [
        ("OCC `GeomAPI_ProjectPointOnSurf` per point and patch", lambda Q: occ_new_each(hs, Q)),
        ("OCC 32 projectors, `Init` once, `Perform(pnt)` per point and patch",
         lambda Q: occ_reused(hs, [p.domain for p in patches], Q)),
    ], "teapot_subset")

    mesh = sk.tessellate(patches, 2e-4, relative=True)
    bench_case(tab, cfg, f"3. {n:,} points near the teapot as a mesh ({mesh.n_faces:,} triangles)", mesh, P, size, [
        ("trimesh `proximity.closest_point` (unsigned)", lambda Q: trimesh_closest(mesh, Q)),
    ], "trimesh_subset")

    print(f"# splinekit deviation benchmark{' (--quick: reduced sizes)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print("Times are for the full point count; ratio = peer time / splinekit time (> 1: splinekit is faster).")
    print("splinekit's time covers the mesh search, the exact Newton refinement, seams, trims and signs "
          "(the reference's sampling is done once beforehand, as for several analyses of one part).")
    print()
    print(tab.render())
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
