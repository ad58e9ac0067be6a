#!/usr/bin/env python
"""Mesh export benchmark: splinekit's writers against trimesh, numpy-stl and a raw write, in one run.

Run from the repository root::

    python benchmarks/bench_export.py           # 1,000,000 triangles (a few minutes)
    python benchmarks/bench_export.py --quick   # 100,000 triangles (well under a minute)

Cases (each the median of several repeats after a warm-up, files in a temporary folder that is
removed at the end):

1. binary STL of a closed triangle mesh (a torus, 1M triangles): splinekit ``export_stl`` from a
   fresh mesh (a new PolyMesh of the same vertices and checked connectivity each call, so its face
   normals are computed as trimesh's are) against trimesh (a fresh ``Trimesh`` each time), then
   both with their normals cached on a mesh kept between calls (splinekit's cached face normals
   of the immutable mesh; trimesh's cache, which also keeps the triangles after the warm-up);
   numpy-stl (gather into its record array, ``save`` computing normals) and the raw write of the
   very same bytes (already prepared; only ``open``/``write``). Target: splinekit within 2x of the
   raw write. Every peer's file is read back and its triangles and normals compared with
   splinekit's (max abs difference column).
2. binary PLY and GLB writes of the same mesh; ASCII STL, OBJ and 3MF writes of a 200,000-triangle
   torus (text costs about a microsecond per float in every Python writer): splinekit against
   trimesh's exporters, every call on both sides from a fresh mesh. GLB is compared without
   normals on both sides (trimesh writes none by default); OBJ with vertex normals on both sides
   (trimesh: ``include_normals=True``, 8 decimals; splinekit: exact coordinates, normals to 15
   decimals).
3. reading binary STL, binary PLY and OBJ files of the smaller mesh: splinekit against trimesh.

``--quick`` uses 100,000 and 10,000 triangles.

Profile (cProfile and time per step, 2-core machine under load 4-6, 2026-11-26), which led to the
current code; ratios are trimesh time / splinekit time in ``--quick`` before -> after:

- STL, normals cached (0.39 -> 0.44-0.68 at 100k; 0.89 -> 2.2 at 1M): splinekit computed the
  normals on every call. Now the writer takes the mesh's cached face normals (polygon meshes: their
  fan triangles' normals, cached through ``PolyMesh.derived``), builds the records a 16k-triangle
  chunk at a time in one reused buffer (a fresh 5 MB array cost ~3 of 7.6 ms in page faults) and
  reserves the file's size before writing (``posix_fallocate``: ext4 otherwise allocates the new
  file's blocks inside the rename over the old one, 7 ms per 5 MB). What is left at 100k without
  numba (16 ms against trimesh's 9): the atomic write, 8 ms, as much as trimesh's whole export --
  the rename frees the replaced file's 5 MB of page cache (2.9 ms, the same as unlinking it) and
  the new file needs fresh pages; trimesh truncates and rewrites in place, with no temporary file
  -- plus the gather of the float32 corners, 7 ms in numpy (0.57 ms per chunk in ``np.take``).
  With the numba kernel (1M triangles) the gather is fused and splinekit wins.
- STL, fresh (1.89 -> 1.0-1.2 at 100k, 1.8 at 1M): the normals now come from
  ``PolyMesh.face_normals`` (shared with every other user of the mesh), which took 35 ms for 100k
  triangles: numpy's ``max(axis=1)`` of an (n, 3) array (8 ms; 0.4 ms by columns), ``min/max(axis=0)``
  (1.3 ms against 60 us by columns), whole-mesh temporaries (now 65k-row chunks: 1M triangles 400
  -> 265 ms) and fan corners built for triangle meshes.
- OBJ write (0.76 -> 1.7-2.1): 70% of the time was Python's shortest float text (~1 us per number)
  for ``v`` and ``vn``, the rest ``%d`` on the face indices. The face lines (uniform faces) and the
  unit normals (15 decimals) are now built in numpy as fixed-width NUL-padded fields squeezed in one
  pass (``exporters/_text.py``); coordinates stay exact. trimesh's row wrote no ``vn`` (it writes
  normals only when cached): it now writes them, as the row's name says.
- PLY read (0.71 -> 1.2-1.6): the parse took 5%; the rest was the closed-manifold check of
  ``Topology``: ``np.unique`` with its inverse plus a second argsort for the edges' half-edges.
  One stable sort (numpy's timsort: 9 ms against quicksort's 67 ms for 600k keys of a mesh listed
  in order, no slower shuffled) now gives edges, inverse and half-edge pairs; edge ends gathered,
  not divided; uniform faces checked for repeated vertices by corner pairs. 200k-triangle check
  223 -> 60 ms.
- OBJ read (0.78 -> 1.7-2.1): three ``re.findall`` scans took 131 of 377 ms, byte-string to
  number conversion 82, byte-string arrays 36. Plain files (what exporters write) are now parsed
  with numpy byte operations and ``np.fromstring`` (``exporters/_objscan.py``); anything else goes
  to the general reader, and the tests read every file both ways.
- STL read (not losing, 1.04-1.19 -> 2.0): the vertex-merging hash collided on the symmetric torus
  (2,600 hashes for 5,000 points: mirrored points differ in sign bits that cancelled), so every
  read fell back to the exact row sort; each column now goes through a splitmix64 mix.
- GLB (0.93 -> 2.0-3.9): trimesh writes no normals; the row now compares the same content, and
  ``min/max(axis=0)`` became column loops (1.3 ms -> 60 us per 50k vertices).

The script prints markdown tables and the load average (other processes skew timings).
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import shutil
import statistics
import tempfile
import time

import numpy as np

import exporters
from _ratios import report, skipped
from splinekit.mesh import PolyMesh
from splinekit.mesh.geometry import triangulate
from splinekit.mesh.primitives import torus

STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


# --------------------------------------------------------------------------------------
# timing


FIRST_CALL = [0.0]  # time of the warm-up call of the latest measure()


def measure(fn, max_repeats: int = 5):
    """Median wall time of ``fn()`` after one warm-up call; ``(seconds, repeats)``.

    The warm-up (numba kernel load or compile, per-mesh caches such as vertex normals, page
    faults) is not counted; its time is kept in ``FIRST_CALL[0]``. Slow cases get fewer repeats.
    """
    gc.collect()
    t0 = time.perf_counter()
    fn()
    FIRST_CALL[0] = time.perf_counter() - t0
    times = []
    while True:
        gc.collect()
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        wanted = max_repeats + 4 if times[0] < 0.05 else max_repeats if times[0] < 0.5 else 3 if times[0] < 1.5 else 1
        if len(times) >= wanted:
            return statistics.median(times), len(times)


def first_call() -> str:
    return f"first call {fmt_t(FIRST_CALL[0])}"


def fmt_t(t):
    if t is None:
        return "-"
    return f"{t:.2f} s" if t >= 1.0 else f"{t * 1e3:.3g} ms"


class Table:
    def __init__(self, ref_label: str):
        self.rows = []
        self.ref_label = ref_label

    def add(self, case, impl, seconds, nbytes, *, repeats=None, ref=None, sk=None, diff=None, note=""):
        self.rows.append({"case": case, "impl": impl, "t": seconds, "nbytes": nbytes, "repeats": repeats,
                          "ref": ref, "sk": sk, "diff": diff, "note": note})

    def fail(self, case, impl, exc):
        msg = f"{type(exc).__name__}: {exc}".replace("|", "/").splitlines()[0][:110]
        self.rows.append({"case": case, "impl": impl, "t": None, "nbytes": None, "repeats": None, "ref": None,
                          "sk": None, "diff": None, "note": f"not run: {msg}"})

    def report_ratios(self, target: float = 1.0):
        """The lines check_ratios.py reads: peer time / splinekit time for every peer row (the raw
        writes are floors, not peers), and one line per peer that did not run."""
        for r in self.rows:
            if "splinekit" in r["impl"] or r["impl"].startswith("raw"):
                continue
            label = f"{r['case']} / {r['impl']}".replace("`", "")
            if r["t"] is None or r["sk"] is None:
                skipped(label, r["note"])
            else:
                report(label, r["t"] / r["sk"], target)

    def render(self):
        lines = [f"| case | implementation | time | file size | MB/s | ratio vs {self.ref_label} "
                 "| ratio vs splinekit | max abs diff vs splinekit | notes |", "|" + "---|" * 9]
        for r in self.rows:
            mbs = "-" if not r["t"] or not r["nbytes"] else f"{r['nbytes'] / r['t'] / 1e6:,.0f}"
            ref = "-" if r["ref"] is None or r["t"] is None else f"{r['t'] / r['ref']:.2f}"
            sk = "-" if r["sk"] is None or r["t"] is None else f"{r['t'] / r['sk']:.2f}"
            diff = "-" if r["diff"] is None else f"{r['diff']:.1e}"
            size = "-" if not r["nbytes"] else f"{r['nbytes'] / 1e6:.1f} MB"
            note = r["note"]
            if r["repeats"] is not None:
                runs = {1: "1 run after a warm-up"}.get(r["repeats"], f"median of {r['repeats']} after a warm-up")
                note = runs + ("; " + note if note else "")
            lines.append(f"| {r['case']} | {r['impl']} | {fmt_t(r['t'])} | {size} | {mbs} | {ref} | {sk} | {diff} | {note} |")
        return "\n".join(lines)


# --------------------------------------------------------------------------------------
# data


def fresh_mesh(mesh: PolyMesh) -> PolyMesh:
    """A new PolyMesh of the same vertices and (already checked) connectivity: nothing derived from
    its geometry (normals) is cached yet, as in a new ``trimesh.Trimesh(..., process=False)``."""
    return PolyMesh.from_topology(mesh.vertices, mesh.topology)


def make_mesh(n_triangles: int) -> PolyMesh:
    """A closed triangulated torus with about ``n_triangles`` triangles."""
    nu = round((n_triangles / 2 / 0.5) ** 0.5)
    nv = max(3, round(n_triangles / 2 / nu))
    quads = torus(nu, nv, R=30.0, r=10.0)
    tris, _ = triangulate(quads)
    return PolyMesh(quads.vertices, tris)


def read_stl_records(path) -> np.ndarray:
    with open(path, "rb") as fh:
        data = fh.read()
    n = int.from_bytes(data[80:84], "little")
    assert len(data) == 84 + 50 * n, f"{path}: {len(data)} bytes for {n} triangles"
    return np.frombuffer(data, dtype=STL_RECORD, count=n, offset=84)


def stl_diff(path, reference: np.ndarray) -> float:
    """Largest difference of triangle corners and normals between two binary STL files."""
    got = read_stl_records(path)
    if got.shape != reference.shape:
        return float("inf")
    dv = np.abs(got["vertices"].astype(np.float64) - reference["vertices"]).max()
    dn = np.abs(got["normal"].astype(np.float64) - reference["normal"]).max()
    return float(max(dv, dn))


# --------------------------------------------------------------------------------------
# cases


def bench_binary_stl(tab: Table, mesh: PolyMesh, folder: str, repeats: int):
    import_errors = {}
    try:
        import trimesh
    except ImportError as exc:
        trimesh, import_errors["trimesh"] = None, exc
    try:
        import stl as numpy_stl
        from stl import mesh as numpy_stl_mesh
    except ImportError as exc:
        numpy_stl, import_errors["numpy-stl"] = None, exc

    V, F = mesh.vertices, mesh.faces
    T = len(F)
    case = f"1. binary STL, {T:,} triangles"
    sk_path = os.path.join(folder, "splinekit.stl")
    t_sk, n_sk = measure(lambda: exporters.export_stl(sk_path, fresh_mesh(mesh)), repeats)
    sk_first = first_call()
    with open(sk_path, "rb") as fh:
        data = fh.read()
    reference = read_stl_records(sk_path).copy()
    warm = fresh_mesh(mesh)
    _ = warm.face_normals  # cached on the immutable mesh, as trimesh caches its own below
    cached_path = os.path.join(folder, "splinekit_cached.stl")
    t_cached, n_cached = measure(lambda: exporters.export_stl(cached_path, warm), repeats)
    with open(cached_path, "rb") as fh:
        assert fh.read() == data, "a mesh with cached normals must write the same bytes"

    raw_path = os.path.join(folder, "raw.stl")

    def raw_write():
        with open(raw_path, "wb") as fh:
            fh.write(data)

    t_raw, n_raw = measure(raw_write, repeats)
    tab.add(case, "raw write of the same bytes", t_raw, len(data), repeats=n_raw, ref=t_raw, sk=t_sk,
            note="bytes prepared in advance; open + write only")

    atomic_path = os.path.join(folder, "raw_atomic.stl")

    def raw_atomic():
        tmp = atomic_path + ".tmp"
        with open(tmp, "wb") as fh:
            fh.write(data)
        os.replace(tmp, atomic_path)

    t, n = measure(raw_atomic, repeats)
    tab.add(case, "raw write to a temporary file + rename", t, len(data), repeats=n, ref=t_raw, sk=t_sk,
            note="the floor for an atomic writer")
    tab.add(case, "**splinekit** `export_stl` (fresh mesh)", t_sk, len(data), repeats=n_sk, ref=t_raw, sk=t_sk, diff=0.0,
            note=f"a new PolyMesh each time: gather, normals, atomic write; {sk_first} (includes loading or compiling the numba kernel, when used)")
    tab.add(case, "**splinekit** `export_stl` (normals cached)", t_cached, len(data), repeats=n_cached, ref=t_raw,
            sk=t_cached, diff=0.0, note="the mesh's face normals computed before timing; gather, atomic write")

    if trimesh is None:
        tab.fail(case, "trimesh", import_errors["trimesh"])
    else:
        tm_path = os.path.join(folder, "trimesh.stl")
        fresh = lambda: trimesh.Trimesh(vertices=V, faces=F, process=False, validate=False)
        t, n = measure(lambda: fresh().export(tm_path, file_type="stl"), repeats)
        tab.add(case, "trimesh `Trimesh.export` (fresh mesh)", t, os.path.getsize(tm_path), repeats=n, ref=t_raw,
                sk=t_sk, diff=stl_diff(tm_path, reference), note="computes face normals, as splinekit does")
        cached = fresh()
        _ = cached.face_normals
        t, n = measure(lambda: cached.export(tm_path, file_type="stl"), repeats)
        tab.add(case, "trimesh `Trimesh.export` (normals cached)", t, os.path.getsize(tm_path), repeats=n,
                ref=t_raw, sk=t_cached, diff=stl_diff(tm_path, reference),
                note="normals (and triangles, after the warm-up) cached; against splinekit with normals cached")

    if numpy_stl is None:
        tab.fail(case, "numpy-stl", import_errors["numpy-stl"])
    else:
        ns_path = os.path.join(folder, "numpy_stl.stl")
        V32 = V.astype(np.float32)

        def numpy_stl_write():
            m = numpy_stl_mesh.Mesh(np.zeros(T, dtype=numpy_stl_mesh.Mesh.dtype), calculate_normals=False)
            m.vectors[:] = V32[F]
            m.save(ns_path, mode=numpy_stl.Mode.BINARY)  # update_normals=True: computes the normals

        t, n = measure(numpy_stl_write, repeats)
        # numpy-stl stores unnormalized normals (|n| = twice the area): compare the corners only
        got = read_stl_records(ns_path)
        dv = float(np.abs(got["vertices"].astype(np.float64) - reference["vertices"]).max())
        tab.add(case, "numpy-stl `Mesh.save`", t, os.path.getsize(ns_path), repeats=n, ref=t_raw, sk=t_sk,
                diff=dv, note="from vertices + faces: gather, normals, save; its normals are not unit "
                "(diff: corners only)")
    return t_sk / t_raw


def bench_other_writers(tab: Table, mesh: PolyMesh, small: PolyMesh, folder: str, repeats: int):
    try:
        import trimesh
    except ImportError as exc:
        trimesh = None
        missing = exc
    # (case, file, label, mesh, writer, trimesh file type, trimesh options, note); every call on
    # both sides starts from a new mesh, so nothing derived (normals) is cached on either side
    cases = [
        ("2. binary PLY", "a.ply", "export_ply", mesh, exporters.export_ply, "ply", {}, "float64 coordinates"),
        ("2. GLB", "a.glb", "export_glb", mesh, exporters.export_glb, None, {},
         "float32 positions + angle-weighted vertex normals (computed each time), uint32 indices"),
        ("2. GLB", "b.glb", "export_glb(normals=False)", mesh, lambda p, m: exporters.export_glb(p, m, normals=False),
         "glb", {}, "float32 positions, uint32 indices (what trimesh writes)"),
        ("2. ASCII STL", "a.stl", "export_stl(binary=False)", small,
         lambda p, m: exporters.export_stl(p, m, binary=False), "stl_ascii", {}, "exact float64 text"),
        ("2. OBJ (v, vn, f)", "a.obj", "export_obj", small, exporters.export_obj, "obj", {"include_normals": True},
         "exact float64 positions; vertex normals (computed each time) to 15 decimals"),
        ("2. 3MF", "a.3mf", "export_3mf", small, exporters.export_3mf, "3mf", {}, "deflate-compressed XML"),
    ]
    for case, name, label, m, writer, tm_type, tm_options, note in cases:
        V, F = m.vertices, m.faces
        case = f"{case}, {len(F):,} triangles"
        write = lambda p, m=m, writer=writer: writer(p, fresh_mesh(m))
        path = os.path.join(folder, "sk_" + name)
        t_sk, n = measure(lambda write=write, path=path: write(path), repeats)
        tab.add(case, f"**splinekit** `{label}`", t_sk, os.path.getsize(path), repeats=n, sk=t_sk,
                note=f"{note}; {first_call()}")
        if tm_type is None:
            continue
        if trimesh is None:
            tab.fail(case, "trimesh", missing)
            continue
        tm_path = os.path.join(folder, "tm_" + name)
        fresh = lambda V=V, F=F: trimesh.Trimesh(vertices=V, faces=F, process=False, validate=False)
        try:
            t, n = measure(lambda fresh=fresh, p=tm_path, kind=tm_type, o=tm_options: fresh().export(p, file_type=kind, **o),
                           repeats)
        except Exception as exc:  # noqa: BLE001 - a peer failing is reported, not fatal
            tab.fail(case, "trimesh", exc)
            continue
        extra = {"obj": "vertex normals computed each time; 8 decimals (not exact)", "ply": "binary, float64 coordinates",
                 "glb": "float32 positions, no normals"}.get(tm_type, "")
        tab.add(case, "trimesh `Trimesh.export` (fresh mesh)", t, os.path.getsize(tm_path), repeats=n, sk=t_sk,
                note=extra)


def bench_readers(tab: Table, mesh: PolyMesh, folder: str, repeats: int):
    try:
        import trimesh
    except ImportError as exc:
        trimesh, missing = None, exc
    for suffix, process, note in ((".stl", True, "merges duplicate vertices"), (".ply", False, ""), (".obj", False, "")):
        path = os.path.join(folder, "read" + suffix)
        exporters.export_mesh(path, mesh)
        case = f"3. read {suffix[1:].upper()}{' (binary)' if suffix != '.obj' else ''}, {mesh.n_faces:,} triangles"
        t_sk, n = measure(lambda path=path: exporters.import_mesh(path), repeats)
        tab.add(case, f"**splinekit** `import_{suffix[1:]}`", t_sk, os.path.getsize(path), repeats=n, sk=t_sk, note=note)
        if trimesh is None:
            tab.fail(case, "trimesh", missing)  # said, not skipped silently
        else:
            t, n = measure(lambda path=path, process=process: trimesh.load(path, force="mesh", process=process), repeats)
            tab.add(case, f"trimesh `load` (process={process})", t, os.path.getsize(path), repeats=n, sk=t_sk,
                    note="merges duplicate vertices" if process else "")


def versions() -> str:
    parts = [f"Python {platform.python_version()}", f"numpy {np.__version__}"]
    for mod, label in (("trimesh", "trimesh"), ("stl", "numpy-stl"), ("numba", "numba")):
        try:
            m = __import__(mod)
            parts.append(f"{label} {getattr(m, '__version__', '?')}")
        except ImportError:
            parts.append(f"{label} absent")
    return ", ".join(parts)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="100,000 / 10,000 triangles and fewer repeats")
    args = ap.parse_args(argv)
    # binary formats at full size; text formats (ASCII STL, OBJ, 3MF XML) and readers on a smaller mesh:
    # formatting floats as text costs about a microsecond each in every Python library
    n_binary, n_text = (100_000, 10_000) if args.quick else (1_000_000, 200_000)
    repeats = 3 if args.quick else 5
    start = time.perf_counter()
    load_start = os.getloadavg()[0]
    mesh = make_mesh(n_binary)
    small = make_mesh(n_text)
    folder = tempfile.mkdtemp(prefix="splinekit-bench-export-")
    try:
        tab = Table("raw write")
        ratio = bench_binary_stl(tab, mesh, folder, repeats)
        bench_other_writers(tab, mesh, small, folder, repeats)
        bench_readers(tab, small, folder, repeats)
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    print(f"# splinekit mesh export benchmark{' (--quick: reduced size, targets are indicative only)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; load average at start {load_start:.2f}, "
          f"at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print(f"Meshes: closed triangulated tori, {mesh.n_faces:,} triangles ({mesh.n_vertices:,} vertices) and "
          f"{small.n_faces:,} triangles for the text formats and readers. Files go to the page cache of a temporary "
          "folder (no fsync), so 'raw write' is a memory copy into the kernel.")
    print("Ratios are time / reference time (< 1: faster than the reference).")
    print()
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads
    print()
    print("## Target")
    print()
    print("| case | target | measured ratio | met |")
    print("|---|---|---|---|")
    print(f"| 1. binary STL | splinekit within 2x of the raw write | {ratio:.2f} | {'met' if ratio <= 2.0 else '**not met**'} |")
    print()
    print(f"total benchmark time: {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
