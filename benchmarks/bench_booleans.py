#!/usr/bin/env python
"""Mesh-boolean benchmark: splinekit's union against manifold3d called directly, in one run.

Run from the repository root::

    python benchmarks/bench_booleans.py           # two 1,310,720-triangle spheres (about 1-2 minutes)
    python benchmarks/bench_booleans.py --quick   # two 20,480-triangle spheres (a few seconds)

Case: the union of two overlapping icospheres (level 8: 1,310,720 triangles
each; level 5, 20,480 triangles, with ``--quick``), the second rotated and shifted by half a
radius so that the meshes cross everywhere along a long intersection curve.
Both operands are ordinary ``PolyMesh`` objects built beforehand with the
checked constructor (as a user would).

Timed, from arrays to arrays:

- **manifold3d direct**: ``Manifold(Mesh64(...))`` for both operands from the
  same numpy arrays (copied, since manifold3d's bindings refuse read-only
  arrays), ``a + b``, ``to_mesh64()`` and reading its two arrays.
- **splinekit**: ``union(PolyMesh, PolyMesh) -> PolyMesh``, with the cache of
  already-checked topologies cleared before every call, so the closed-manifold
  checks run every time (the first-call cost a user sees).
- **splinekit, operands checked before**: the same with the cache kept (the
  checks are skipped for a topology seen before, e.g. when chaining booleans).

The calls are interleaved round by round and each is reported as its median,
so that drifts in the machine's load hit all three alike. The overhead is
``splinekit / direct - 1``. Because two multi-second timings on a shared
machine differ by more than the wrapper costs, the wrapper's own work is also
timed on its own (checks, array copies, the orientation test, the wrapping of
the result) and given as a share of manifold3d's time; that figure is the
stable one. CPU time (``time.process_time``, all threads of the process) is
printed beside wall time: it is far less sensitive to other processes.
Target: overhead <= 10 %.

Chain of 10 booleans on the same operands (union, difference, intersection in turn, each
result read back as arrays / a PolyMesh): manifold3d with both operands built once and kept in
its own ``Manifold`` objects, against splinekit on PolyMeshes, each side paying its one
conversion of the operands. Target: splinekit at most 1.2x manifold3d. Profile finding (737k
triangles per operand): about half of one splinekit boolean was rebuilding both manifold3d
operands from the meshes; a PolyMesh now keeps its converted ``Manifold``
(``PolyMesh.derived``), so only the first boolean of a mesh converts it.

The peak memory of one union is reported against the size of its output arrays
(``benchmarks/_memory.py``; manifold3d's own C++ allocations show in the RSS figure only).
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import time
from importlib.metadata import version

import manifold3d as m3
import numpy as np

from _memory import measure_memory
from _ratios import report
from splinekit.interop import booleans
from splinekit.mesh import PolyMesh
from splinekit.mesh.primitives import icosphere


def timed(fn):
    """``(wall seconds, result)``."""
    wall, _, result = timed_cpu(fn)
    return wall, result


def timed_cpu(fn):
    """``(wall seconds, CPU seconds of the whole process, all threads, result)``."""
    gc.collect()
    c0, t0 = time.process_time(), time.perf_counter()
    result = fn()
    return time.perf_counter() - t0, time.process_time() - c0, result


def fmt(t: float) -> str:
    return f"{t:.3f} s" if t >= 1 else f"{t * 1e3:.1f} ms"


def operands(level: int):
    a = icosphere(level)
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    b = PolyMesh(a.vertices @ rot.T + [0.5, 0.2, 0.1], np.array(a.faces))  # its own, checked topology
    return a, b


def direct(a: PolyMesh, b: PolyMesh):
    """manifold3d alone, arrays to arrays."""
    ma = m3.Manifold(m3.Mesh64(vert_properties=np.array(a.vertices), tri_verts=a.faces.astype(np.uint64)))
    mb = m3.Manifold(m3.Mesh64(vert_properties=np.array(b.vertices), tri_verts=b.faces.astype(np.uint64)))
    out = (ma + mb).to_mesh64()
    return np.asarray(out.vert_properties), np.asarray(out.tri_verts)


def forget(*meshes):
    """Forget earlier checks and conversions: measure them every time."""
    booleans._VERIFIED.clear()
    for m in meshes:
        m.__dict__.pop("_derived", None)


def splinekit_cold(a, b):
    forget(a, b)
    return booleans.union(a, b)


CHAIN = ("union", "difference", "intersection") * 3 + ("union",)


def chain_direct(a, b):
    """manifold3d: both operands converted once, then ten booleans read back as arrays."""
    ma = m3.Manifold(m3.Mesh64(vert_properties=np.array(a.vertices), tri_verts=a.faces.astype(np.uint64)))
    mb = m3.Manifold(m3.Mesh64(vert_properties=np.array(b.vertices), tri_verts=b.faces.astype(np.uint64)))
    ops = {"union": lambda: ma + mb, "difference": lambda: ma - mb, "intersection": lambda: ma ^ mb}
    out = []
    for op in CHAIN:
        mesh = ops[op]().to_mesh64()
        out.append((np.asarray(mesh.vert_properties), np.asarray(mesh.tri_verts)))
    return out


def chain_splinekit(a, b):
    """splinekit: ten booleans on the same PolyMeshes (the first converts them)."""
    forget(a, b)
    return [getattr(booleans, op)(a, b) for op in CHAIN]


def wrapper_work(a, b):
    """Seconds spent by splinekit beyond manifold3d's own work, timed piece by piece."""
    booleans._VERIFIED.clear()
    t_in, (Va, Ta) = timed(lambda: booleans._checked_triangles(a, "a"))
    t_in2, (Vb, Tb) = timed(lambda: booleans._checked_triangles(b, "b"))
    ma = m3.Manifold(m3.Mesh64(vert_properties=Va, tri_verts=Ta))
    mb = m3.Manifold(m3.Mesh64(vert_properties=Vb, tri_verts=Tb))
    t_sign, _ = timed(lambda: (ma.volume() < 0, mb.volume() < 0, ma.status(), mb.status()))
    out = ma + mb
    t_raw, _ = timed(lambda: out.to_mesh64())
    t_wrap, _ = timed(lambda: booleans.from_manifold(out))
    return {"checks_and_copies": t_in + t_in2, "orientation_test": t_sign, "result_wrapping": max(t_wrap - t_raw, 0.0)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="20,480-triangle spheres instead of 1,310,720")
    ap.add_argument("--rounds", type=int, default=None, help="interleaved rounds (default 3, 15 with --quick)")
    args = ap.parse_args(argv)
    level = 5 if args.quick else 8
    rounds = args.rounds or (15 if args.quick else 3)
    load_start = os.getloadavg()[0]

    t_build, (a, b) = timed(lambda: operands(level))
    n_tri = a.n_faces

    # warm-up (page faults, lazy imports) and a correctness check of the wrapper against direct
    Vd, Td = direct(a, b)
    ours = booleans.union(a, b)
    same = ours.n_faces == len(Td) and ours.n_vertices == len(Vd)
    ref_volume = PolyMesh.from_topology(Vd, ours.topology).volume if same else float("nan")

    calls = {"direct": lambda: direct(a, b), "cold": lambda: splinekit_cold(a, b), "warm": lambda: booleans.union(a, b),
             "chain_direct": lambda: chain_direct(a, b), "chain_sk": lambda: chain_splinekit(a, b)}
    times = {k: [] for k in calls}
    cpu = {k: [] for k in calls}
    for _ in range(rounds):
        for k, fn in calls.items():
            wall, c, _ = timed_cpu(fn)
            times[k].append(wall)
            cpu[k].append(c)
    med = {k: statistics.median(v) for k, v in times.items()}
    med_cpu = {k: statistics.median(v) for k, v in cpu.items()}
    # single-threaded numpy work: the minimum over repeats is its cost, the rest is interference
    parts = [wrapper_work(a, b) for _ in range(5)]
    work = {k: min(p[k] for p in parts) for k in parts[0]}
    own = sum(work.values())

    print(f"# splinekit mesh-boolean benchmark{' (--quick: reduced size, target indicative only)' if args.quick else ''}")
    print()
    print(f"manifold3d {version('manifold3d')}, numpy {np.__version__}, Python {platform.python_version()}; "
          f"{platform.machine()}, {os.cpu_count()} CPUs; load average at start {load_start:.2f}, "
          f"at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print(f"Union of two icospheres of {n_tri:,} triangles each (built in {fmt(t_build)}, not timed); "
          f"result {ours.n_faces:,} triangles, volume {ours.volume:.6f}; "
          f"same mesh as manifold3d direct: {'yes' if same else 'NO'}"
          + (f" (volume difference {abs(ours.volume - ref_volume):.1e})" if same else ""))
    print()
    print(f"| implementation | wall, median of {rounds} (interleaved) | range | ratio to direct | overhead "
          f"| CPU time (all threads), median | CPU overhead |")
    print("|---|---|---|---|---|---|---|")
    labels = {"direct": "manifold3d direct (arrays -> Manifold, union, to_mesh64 -> arrays)",
              "cold": "**splinekit** `union(PolyMesh, PolyMesh)`, checks and conversion run",
              "warm": "**splinekit**, operands used before (checked and converted once, cached)"}
    for k in ("direct", "cold", "warm"):
        ratio = med[k] / med["direct"]
        runs = f"{fmt(min(times[k]))} - {fmt(max(times[k]))}"
        over = "-" if k == "direct" else f"{100 * (ratio - 1):+.1f} %"
        cpu_over = "-" if k == "direct" else f"{100 * (med_cpu[k] / med_cpu['direct'] - 1):+.1f} %"
        print(f"| {labels[k]} | {fmt(med[k])} | {runs} | {ratio:.3f} | {over} | {fmt(med_cpu[k])} | {cpu_over} |")
    print()
    ratio_chain = med["chain_sk"] / med["chain_direct"]
    print(f"Chain of {len(CHAIN)} booleans on the same two operands ({', '.join(CHAIN[:3])}, ...), each side "
          f"converting the operands once: manifold3d {fmt(med['chain_direct'])}, **splinekit** "
          f"{fmt(med['chain_sk'])}: {ratio_chain:.3f}x manifold3d (median of {rounds}, interleaved)")
    print()
    forget(a, b)
    print(f"Memory of one union (checks and conversion run): {measure_memory(lambda: splinekit_cold(a, b)).line()}")
    print()
    print("Wrapper's own work, timed on its own (minimum of 5):")
    print()
    for k, v in work.items():
        print(f"- {k.replace('_', ' ')}: {fmt(v)}")
    share = own / med["direct"]
    print(f"- total {fmt(own)} = {100 * share:.1f} % of manifold3d's direct time ({fmt(med['direct'])})")
    print()
    end_to_end = med["cold"] / med["direct"] - 1
    end_to_end_cpu = med_cpu["cold"] / med_cpu["direct"] - 1
    print("## Target")
    print()
    print("| target | measured | met |")
    print("|---|---|---|")
    print(f"| wrapper adds <= 10 % to manifold3d's time (own work, stable figure) | {100 * share:.1f} % | "
          f"{'met' if share <= 0.10 else '**not met**'} |")
    print(f"| same, end to end in CPU time (all threads; less sensitive to other processes) | "
          f"{100 * end_to_end_cpu:+.1f} % | {'met' if end_to_end_cpu <= 0.10 else '**not met**'} |")
    print(f"| same, end to end in wall time (difference of medians, noisy) | {100 * end_to_end:+.1f} % | "
          f"{'met' if end_to_end <= 0.10 else '**not met**'} |")
    print(f"| chain of {len(CHAIN)} booleans at most 1.2x manifold3d kept in its own objects | {ratio_chain:.3f}x | "
          f"{'met' if ratio_chain <= 1.2 else '**not met**'} |")
    print()
    report("booleans: one union, manifold3d direct / splinekit (CPU time)", med_cpu["direct"] / med_cpu["cold"], 1 / 1.1)
    report(f"booleans: chain of {len(CHAIN)}, manifold3d kept objects / splinekit", 1 / ratio_chain, 1 / 1.2)


if __name__ == "__main__":
    main()
