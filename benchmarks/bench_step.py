#!/usr/bin/env python
"""STEP export benchmark: splinekit's ``export_step`` against build123d's, in one run.

Run from the repository root::

    python benchmarks/bench_step.py            # 100 faces, several repeats, 4 large foreign files
    python benchmarks/bench_step.py --quick    # 20 faces, 2 small foreign files

Case: 100 bicubic B-spline faces of 8 x 8 random poles (clamped uniform knots),
written as separate faces to one AP214 file.

* splinekit: ``exporters.export_step(path, surfaces)``: the timing includes the
  conversion of every surface to an OCC face, the XCAF document and the
  full-precision (16-digit) write;
* splinekit, shapes prebuilt: the same call given the OCC faces, so that only
  the document and the write are timed;
* build123d: ``build123d.export_step(Compound(faces), path)`` on the same faces,
  built once before timing (it writes OCC's default 12 significant digits).

The writers are called in turn, round after round, after one warm-up call each
(the first STEP write in a process loads OCC's translator, which takes
seconds); times are medians over the rounds and the ratio is the median of the
per-round ratios splinekit time / build123d time, so that both writers see the
same machine load. The target is a ratio of at most 1.5. The script also
reads both files back with ``import_step`` and reports the largest control
point difference from the exported surfaces, and prints the import times.

Import of STEP files written by other CAD systems (../shared/data/step, skipped
with a note when absent): per file, OCC's own read of the file to a shape
(``read_step_shape``, the floor: splinekit cannot read faster than OCC parses),
splinekit's ``import_step`` (both in this process, ``isolated=False``), its time
per face and how many faces it converted natively (the others go through
``BRepBuilderAPI_NurbsConvert``); the largest files are the CATIA ventilator,
the NX plate and the Inventor part.

Where the import's time goes (cProfile of ``import_step(path, isolated=False)``
sorted by cumulative and own time, then CPU seconds per phase without the
profiler; machine shared, load 3-5 on 2 cores, so figures move by 10-20%):

* OCC's own work that the converted model depends on: the NURBS conversion of
  the faces that do not convert natively (CATIA 1.05 s, NX 0.59 s, Inventor
  4.2 s, SolidWorks 1.2 s: OCC re-approximates every B-spline pcurve on a
  cylinder, cone or torus, 100-240 ms for some Inventor faces) and
  ``BRepCheck_Analyzer`` of the rebuilt objects (0.15-0.8 s; Alias 0.43 s, twice
  its read). The read plus these two alone come to 2.8x (CATIA), 3.9x (NX),
  5.4x (Inventor), 2.8x (SolidWorks) and 3.3x (Alias) OCC's read, so the 2x
  target cannot be met without replacing OCC's conversion, which would change
  the imported model;
* Python per edge use, which was cut: the SameParameter step (one
  ``splinekit.project`` per lagging use for its distance to the curve and one
  per piece count for the reparametrization, each building its own samples,
  plus one curve evaluation per use: 1.3-2.2 s) now measures all uses of a face
  with one ``CurveBatch`` each for pcurves and 3-D curves and runs the Newton
  searches of all its uses as one batch; curve knot refinement snapped its
  knots in a Python loop; the rebuild for the check evaluated every use's curve
  on its own; ``validate_knots`` sorted each knot vector again to count
  multiplicities. The imported model is unchanged (every pole, knot, tolerance,
  area and volume bitwise equal on the five files).

Before / after (CPU seconds of ``import_step``, the lower of two runs, the two
versions run in turn in fresh processes on the loaded machine; OCC's read is
the lowest of the four reads)::

    file                         OCC read  before  after  import/read before -> after
    alias_k1_allbspline            0.22     2.82   2.05    12.8 -> 9.3
    catiav5r18_ventilator          0.77     5.30   4.85     6.9 -> 6.3
    nx9_piattello                  0.31     3.10   2.90    10.0 -> 9.4
    sw2012_multibody_4solids       0.81     4.95   4.49     6.1 -> 5.5
    inventor2013_part_11752        1.04    13.01  10.53    12.5 -> 10.1
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir)))

import splinekit as sk
from _ratios import report, skipped
from exporters.step import export_step, import_step, read_step_shape
from splinekit.basis.knots import clamped_uniform
from splinekit.interop.occ_native_faces import native_faces

TARGET_RATIO = 1.5

STEP_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir, "shared", "data", "step")
FOREIGN = ("catiav5r18_ventilator.stp", "nx9_piattello.stp", "inventor2013_part_11752.stp", "sw2012_multibody_4solids.step")
FOREIGN_QUICK = ("ug19_io1_analytic.stp", "euclid_screw.step")


def interleaved_times(fns: dict, repeats: int) -> dict:
    """Per-call wall times of each function in ``fns``, called in turn ``repeats`` times.

    One untimed warm-up call each first. Interleaving the calls exposes every
    writer to the same machine load, so per-round ratios are steadier than
    ratios of separately measured medians.
    """
    for fn in fns.values():
        fn()
    times = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            gc.collect()
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return times


def make_faces(count: int, seed: int = 0) -> list:
    """``count`` bicubic 8 x 8 B-spline surfaces tiled on a grid, with random heights."""
    rng = np.random.default_rng(seed)
    U = clamped_uniform(3, 8)
    side = int(np.ceil(np.sqrt(count)))
    out = []
    g = np.linspace(0.0, 10.0, 8)
    for k in range(count):
        x0, y0 = 12.0 * (k % side), 12.0 * (k // side)
        P = np.empty((8, 8, 3))
        P[..., 0] = x0 + g[:, None]
        P[..., 1] = y0 + g[None, :]
        P[..., 2] = rng.uniform(-1.0, 1.0, (8, 8))
        out.append(sk.BSplineSurface(3, 3, U, U, P))
    return out


def max_pole_difference(surfaces, items) -> float:
    """Largest pole difference between ``surfaces`` and the faces read back (``import_step`` gives
    a Shell, TrimmedFace or surface per item); inf when the face counts differ."""
    got = []
    for it in items:
        faces = getattr(it.geometry, "faces", None)
        if faces is None:
            got.append(getattr(it.geometry, "surface", it.geometry))
        else:
            got.extend(f.surface for f in faces)
    if len(got) != len(surfaces):
        return float("inf")
    return max(float(np.abs(s.control_points - g.control_points).max()) for s, g in zip(surfaces, got))


def native_count(shape) -> tuple[int, int]:
    """``(faces converted natively, faces)`` of an OCC shape, as the B-rep reader decides."""
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopTools import TopTools_IndexedMapOfShape

    faces, edges = TopTools_IndexedMapOfShape(), TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
    return len(native_faces(shape, faces, edges)[0]), faces.Extent()


def _timed(fn) -> tuple[float, float]:
    """``(wall seconds, CPU seconds of this process)`` of one call of ``fn``."""
    gc.collect()
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def foreign_imports(names, repeats: int) -> None:
    """Print the import table of the foreign STEP files ``names``: wall and CPU times (the CPU
    time is the steadier figure on a shared machine: both run in this one process)."""
    if not os.path.isdir(STEP_DIR):
        skipped("foreign STEP files", f"{os.path.normpath(STEP_DIR)} is absent")
        return
    print()
    print(f"# STEP import of files from other CAD systems (in-process, median of {repeats}); "
          f"load average {os.getloadavg()[0]:.2f}")
    print()
    print("| file | faces | native | OCC read (floor) wall / CPU | splinekit import_step wall / CPU | CPU per face "
          "| import / read (CPU) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in names:
        path = os.path.join(STEP_DIR, name)
        import_step(path, isolated=False)  # warm-up
        runs = [(_timed(lambda: read_step_shape(path, isolated=False)), _timed(lambda: import_step(path, isolated=False)))
                for _ in range(repeats)]
        rw, rc = (statistics.median(read[j] for read, _ in runs) for j in (0, 1))
        iw, ic = (statistics.median(imp[j] for _, imp in runs) for j in (0, 1))
        native, total = native_count(read_step_shape(path, isolated=False))
        print(f"| {name} | {total} | {native} | {rw:.2f} s / {rc:.2f} s | {iw:.2f} s / {ic:.2f} s "
              f"| {ic / total * 1e3:.1f} ms | {ic / rc:.1f} |", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20 faces instead of 100")
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args(argv)
    count = 20 if args.quick else 100

    import build123d as bd

    surfaces = make_faces(count)
    occ_faces = [sk.occ.to_shape(s) for s in surfaces]
    b3d_compound = bd.Compound([bd.Face(f) for f in occ_faces])

    print(f"# STEP export: {count} bicubic B-spline faces, 8 x 8 poles each")
    print(f"python {platform.python_version()}, {platform.machine()}, load average {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        ours_path = os.path.join(tmp, "splinekit.step")
        shapes_path = os.path.join(tmp, "splinekit_shapes.step")
        theirs_path = os.path.join(tmp, "build123d.step")
        export_times = interleaved_times(
            {
                "ours": lambda: export_step(ours_path, surfaces),
                "shapes": lambda: export_step(shapes_path, occ_faces),
                "b3d": lambda: bd.export_step(b3d_compound, theirs_path),
            },
            args.repeats,
        )
        import_times = interleaved_times(
            {"ours": lambda: import_step(ours_path), "b3d": lambda: bd.import_step(theirs_path)},
            max(1, args.repeats // 2),
        )
        diff_ours = max_pole_difference(surfaces, import_step(ours_path))
        diff_b3d = max_pole_difference(surfaces, import_step(theirs_path))
        size_ours, size_b3d = os.path.getsize(ours_path), os.path.getsize(theirs_path)

    t_ours, t_shapes, t_b3d = (statistics.median(export_times[k]) for k in ("ours", "shapes", "b3d"))
    t_imp_ours, t_imp_b3d = (statistics.median(import_times[k]) for k in ("ours", "b3d"))
    ratio = statistics.median(o / b for o, b in zip(export_times["ours"], export_times["b3d"]))
    ratio_shapes = statistics.median(o / b for o, b in zip(export_times["shapes"], export_times["b3d"]))
    rows = [
        ("splinekit export_step (surfaces)", t_ours, size_ours, diff_ours),
        ("splinekit export_step (OCC faces prebuilt)", t_shapes, size_ours, diff_ours),
        ("build123d export_step (faces prebuilt)", t_b3d, size_b3d, diff_b3d),
    ]
    print()
    print("| writer | time | per face | file size | max pole error after import |")
    print("|---|---:|---:|---:|---:|")
    for name, t, size, diff in rows:
        print(f"| {name} | {t * 1e3:.1f} ms | {t / count * 1e6:.0f} us | {size / 1024:.0f} KiB | {diff:.1e} |")
    print()
    verdict = "met" if ratio <= TARGET_RATIO else "NOT met"
    print(
        f"ratio splinekit / build123d (median over {args.repeats} interleaved rounds): {ratio:.2f} "
        f"(target <= {TARGET_RATIO}: {verdict}); with prebuilt shapes: {ratio_shapes:.2f}"
    )
    print(f"import: splinekit import_step {t_imp_ours * 1e3:.1f} ms (to splinekit surfaces), "
          f"build123d import_step {t_imp_b3d * 1e3:.1f} ms (to an OCC shape)")
    report("STEP export: build123d / splinekit", 1.0 / ratio, 1.0 / TARGET_RATIO)  # the line check_ratios.py reads
    foreign_imports(FOREIGN_QUICK if args.quick else FOREIGN, 1 if args.quick else 2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
