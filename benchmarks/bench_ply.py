#!/usr/bin/env python
"""Binary PLY with faces of mixed sizes: splinekit's reader and writer against plyfile, in one run.

Run from the repository root::

    python benchmarks/bench_ply.py           # 500,000 faces
    python benchmarks/bench_ply.py --quick   # 100,000 faces

The mesh is a closed torus of triangles, quads and pentagons interleaved face by face
(``_meshes.mixed_torus``: sizes 5, 3, 3, 4, 5, 5, 3, ...), the worst case for a reader that
takes runs of equal records. Timed, interleaved round by round (best of the rounds):

- read: splinekit ``import_ply`` (header, records, and the closed-manifold checks of the
  PolyMesh it returns) against ``plyfile.PlyData.read`` (records only, faces as an object
  array of per-face arrays) and, for the record parsing alone, splinekit's ``_read_element``;
- write: splinekit ``export_ply`` (atomic write) against ``plyfile.PlyData.write`` of a
  structured array prepared before timing (building its per-face object array is not counted).

trimesh's binary PLY reader assumes one face size and refuses these files ("PLY is unexpected
length"); it is reported as skipped. Both files are read back by the other library and compared.
Target: splinekit at least as fast as plyfile (ratio plyfile / splinekit >= 1) for reading and
writing.

Profile finding: the former reader took one step per run of equal records, so a file whose
consecutive faces differ in size cost one step per face (2 s per 100k faces). Records now are
chained for the whole element at once (a next-record table over every byte, followed by
baby-step giant-step); what remains is about half record parsing and half the manifold checks
of the PolyMesh (an edge sort), which plyfile does not do.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import tempfile
import time
from importlib.metadata import version

import numpy as np

import exporters
from _memory import measure_memory
from _meshes import mixed_torus
from _ratios import report, skipped
from exporters import ply as ply_module
from splinekit.mesh.polymesh import PolyMesh
from splinekit.mesh.topology import Topology


def best(fn, rounds):
    times, out = [], None
    for _ in range(rounds):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def parse_only(path):
    """splinekit's record parsing alone: the face element's lists, no mesh built."""
    data = open(path, "rb").read()
    fmt, elements, start = ply_module._parse_header(data, path)
    stream = ply_module._Stream(data, start, fmt, path)
    pos, out = start, None
    for el in elements:
        wanted = {"vertex_indices"} if el.name == "face" else {"x", "y", "z"}
        values, pos = ply_module._read_element(stream, pos, el, wanted)
        out = values if el.name == "face" else out
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="100,000 faces and fewer rounds")
    args = ap.parse_args(argv)
    nu, nv = (200, 400) if args.quick else (400, 1000)
    rounds = 3 if args.quick else 5
    load_start = os.getloadavg()[0]
    V, idx, off = mixed_torus(nu, nv)
    mesh = PolyMesh.from_topology(V, Topology(len(V), idx, off, check=True))
    try:
        import plyfile
    except ImportError as exc:
        plyfile = None
        skipped("plyfile", f"not installed ({exc}); pip install plyfile")
    folder = tempfile.mkdtemp(prefix="splinekit-bench-ply-")
    try:
        sk_path, pf_path = os.path.join(folder, "sk.ply"), os.path.join(folder, "pf.ply")
        exporters.export_ply(sk_path, mesh)
        if plyfile is not None:
            vert = np.empty(len(V), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
            vert["x"], vert["y"], vert["z"] = V.T
            face = np.empty(mesh.n_faces, dtype=[("vertex_indices", object)])
            face["vertex_indices"] = [f.astype(np.int32) for f in np.split(idx, off[1:-1])]
            doc = plyfile.PlyData([plyfile.PlyElement.describe(vert, "vertex"),
                                   plyfile.PlyElement.describe(face, "face", len_types={"vertex_indices": "u1"})])
        calls = {
            "sk_read": lambda: exporters.import_ply(sk_path),
            "sk_parse": lambda: parse_only(sk_path),
            "sk_write": lambda: exporters.export_ply(sk_path, mesh),
        }
        if plyfile is not None:
            calls["pf_read"] = lambda: plyfile.PlyData.read(sk_path)
            calls["pf_write"] = lambda: doc.write(pf_path)
        times = {k: [] for k in calls}
        for _ in range(rounds):  # interleaved: the machine's load drifts alike for all
            for k, fn in calls.items():
                t, _ = best(fn, 1)
                times[k].append(t)
        t = {k: min(v) for k, v in times.items()}
        checks = []
        if plyfile is not None:
            got = plyfile.PlyData.read(sk_path)["face"]["vertex_indices"]
            checks.append(("plyfile reads splinekit's file", bool(np.array_equal(np.concatenate(got), idx))))
            back = exporters.import_ply(pf_path)
            checks.append(("splinekit reads plyfile's file", back == mesh))
        try:
            import trimesh
            trimesh.load(sk_path, process=False)
            checks.append(("trimesh reads splinekit's file", True))
        except ImportError as exc:
            skipped("trimesh", f"not installed ({exc})")
        except Exception as exc:  # noqa: BLE001 - a peer failing is reported
            skipped("trimesh", f"its binary PLY reader refuses mixed face sizes: {exc}")
        mem = measure_memory(lambda: exporters.import_ply(sk_path))
        size = os.path.getsize(sk_path)
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    print(f"# Binary PLY, mixed face sizes{' (--quick)' if args.quick else ''}\n")
    print(f"Python {platform.python_version()}, numpy {np.__version__}, plyfile "
          f"{version('plyfile') if plyfile else 'absent'}; {os.cpu_count()} CPUs; load average "
          f"{load_start:.2f} at start, {os.getloadavg()[0]:.2f} at end; best of {rounds} interleaved rounds\n")
    print(f"{mesh.n_faces:,} faces (triangles, quads, pentagons interleaved), {mesh.n_vertices:,} vertices, "
          f"file {size / 1e6:.1f} MB\n")
    print("| operation | **splinekit** | plyfile | ratio plyfile / splinekit |")
    print("|---|---|---|---|")
    pf_r, pf_w = t.get("pf_read"), t.get("pf_write")
    fmt = lambda s: "-" if s is None else f"{s * 1e3:.0f} ms"
    rat = lambda p, s: "-" if p is None else f"{p / s:.2f}"
    print(f"| read (splinekit: checked PolyMesh) | {fmt(t['sk_read'])} | {fmt(pf_r)} | {rat(pf_r, t['sk_read'])} |")
    print(f"| read, records only | {fmt(t['sk_parse'])} | {fmt(pf_r)} | {rat(pf_r, t['sk_parse'])} |")
    print(f"| write | {fmt(t['sk_write'])} | {fmt(pf_w)} | {rat(pf_w, t['sk_write'])} |")
    print()
    for label, ok in checks:
        print(f"- {label}: {'same mesh' if ok else '**DIFFERENT**'}")
    print(f"- memory of import_ply: {mem.line()}")
    print()
    if pf_r is not None:
        report("PLY mixed faces: read, plyfile / splinekit", pf_r / t["sk_read"], 1.0)
        report("PLY mixed faces: write, plyfile / splinekit", pf_w / t["sk_write"], 1.0)


if __name__ == "__main__":
    main()
