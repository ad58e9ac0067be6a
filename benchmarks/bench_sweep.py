#!/usr/bin/env python
"""Parameter-sweep benchmark: vase variants built serially in one process against the same
variants as a Dask sweep on a 2-worker LocalCluster, the scheduler's overhead per task, and
the on-paper estimate for 100,000 variants on 50 workers from these measured figures.

Run from the repository root::

    python benchmarks/bench_sweep.py            # 200 variants (a few minutes on 2 idle cores)
    python benchmarks/bench_sweep.py --quick    # 40 variants

Figures:

* serial: a loop calling the sweep's own task (:class:`models.parameter_sweep.VariantTask`:
  build, measure) in this process, no Dask;
* sweep: ``splinekit.sweep("vase", grid, n_workers=2)`` end to end, starting and closing its
  LocalCluster; and the same sweep on a cluster already running (``client=``), which is what a
  long sweep amortises towards. The ratio is serial time over sweep time (target 1.7x);
* empty tasks: :func:`splinekit.batch.run` of ``dict`` (a task that only echoes its row) on the
  running cluster: the per-task cost of scheduling, result transfer, collection and the table;
* the results table of 100,000 rows written as parquet + csv (atomically);
* the files of one variant (STEP + STL), for the disk traffic of a sweep that writes them.

The machine's load average is printed: other processes on the two cores skew every timing.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir)))

import splinekit as sk  # noqa: E402
from models import vase  # noqa: E402
from models.parameter_sweep import VariantTask, model_version  # noqa: E402
from splinekit.batch import cluster_client, results, run, variant_key, variants  # noqa: E402

MEASURES = ["area", "volume", "centroid", "faces", "valid"]
"""Exact measures, no tessellation (the tessellation would dominate the work per variant)."""
TARGET = 1.7
PAPER_VARIANTS, PAPER_WORKERS = 100_000, 50


def grid(n: int) -> dict:
    """``n`` vase variants: heights times wall thicknesses (all valid)."""
    walls = 10 if n >= 100 else 4
    return {"height": list(np.linspace(100.0, 400.0, n // walls)), "wall": list(np.linspace(1.5, 5.0, walls))}


def serial(rows) -> float:
    task = VariantTask("vase", vase.build, model_version(vase), tuple(MEASURES))
    start = time.perf_counter()
    for row in rows:
        task(row)
    return time.perf_counter() - start


def empty_tasks(client, n: int, folder: str) -> float:
    rows = [{"i": float(i)} for i in range(n)]
    keys = [variant_key("empty", "0", r) for r in rows]
    start = time.perf_counter()
    run(dict, rows, keys=keys, out=folder, client=client, force=True)
    return (time.perf_counter() - start) / n


def table_write(n: int, folder: str) -> float:
    """Seconds to write a results table of ``n`` rows shaped like a vase sweep's."""
    rng = np.random.default_rng(0)
    columns = ["height", "radius", "neck", "wall", "base", "build_time", "area", "volume", "centroid_x", "centroid_y",
               "centroid_z", "faces", "triangles"] + [f"bbox_{e}_{a}" for e in ("min", "max") for a in "xyz"]
    frame_rows = [{"key": f"{i:016x}", **dict(zip(columns, rng.random(len(columns)))), "status": "ok", "error": None,
                   "valid": True, "checks_ok": True, "checks_failed": "", "file_step": f"/shared/vase-{i:016x}.step",
                   "recipe": "{}"} for i in range(n)]
    frame = results.table(frame_rows, columns[:5])
    start = time.perf_counter()
    os.makedirs(folder, exist_ok=True)
    results.write(frame, folder)
    return time.perf_counter() - start


def file_sizes(folder: str) -> int:
    frame = sk.sweep("vase", {"height": [200.0]}, measures=["faces"], formats="step,stl", out=folder, n_workers=1, plot=False)
    return sum(os.path.getsize(frame[c][0]) for c in ("file_step", "file_stl"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="40 variants instead of 200")
    args = parser.parse_args()
    n = 40 if args.quick else 200
    g = grid(n)
    rows = variants(g)
    print(f"# bench_sweep: {len(rows)} vase variants, measures {','.join(MEASURES)}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        t_serial = serial(rows)
        per_variant = t_serial / len(rows)
        print(f"serial loop (one process)          {t_serial:8.1f} s   {1e3 * per_variant:7.1f} ms/variant")
        start = time.perf_counter()
        frame = sk.sweep("vase", g, measures=MEASURES, out=os.path.join(tmp, "a"), n_workers=2, plot=False)
        t_cold = time.perf_counter() - start
        assert frame.attrs["summary"]["ok"] == len(rows), frame.attrs["summary"]
        print(f"sweep, 2-worker LocalCluster        {t_cold:8.1f} s   ratio {t_serial / t_cold:.2f}x "
              "(cluster start and close included)")
        with cluster_client(n_workers=2) as client:  # the local cluster a sweep starts, kept for the next runs
            client.run(lambda: __import__("models"))  # workers warm: splinekit and the models imported
            start = time.perf_counter()
            sk.sweep("vase", g, measures=MEASURES, out=os.path.join(tmp, "b"), client=client, plot=False)
            t_warm = time.perf_counter() - start
            ratio = t_serial / t_warm
            verdict = "met" if ratio >= TARGET else "NOT met"
            print(f"sweep, cluster already running      {t_warm:8.1f} s   ratio {ratio:.2f}x "
                  f"(target {TARGET}x: {verdict})")
            overhead = empty_tasks(client, 1000, os.path.join(tmp, "c"))
            print(f"empty tasks (1000, run(dict))       {1e3 * overhead:8.2f} ms/task "
                  f"({1 / overhead:.0f} tasks/s through scheduler, transfer, collection, table)")
        t_table = table_write(PAPER_VARIANTS, os.path.join(tmp, "d"))
        print(f"results table, {PAPER_VARIANTS:,} rows (parquet+csv)  {t_table:5.1f} s")
        nbytes = file_sizes(os.path.join(tmp, "e"))
        print(f"files of one variant (STEP + STL)   {nbytes / 1e6:8.2f} MB")
    paper(per_variant, overhead, t_table, nbytes)


def paper(per_variant: float, overhead: float, t_table: float, nbytes: int) -> None:
    """What 100,000 variants would take on 50 workers, from the measured figures."""
    n, w = PAPER_VARIANTS, PAPER_WORKERS
    compute = n * per_variant / w
    scheduler = n * overhead  # the client and scheduler handle every task one after the other
    disk = n * nbytes
    print(f"\n# on paper: {n:,} variants on {w} workers (per-variant work and overheads as measured here)")
    print(f"compute            {n:,} x {1e3 * per_variant:.0f} ms / {w} workers = {compute / 60:6.1f} min")
    print(f"scheduling+results {n:,} x {1e3 * overhead:.2f} ms (serial in client and scheduler) = {scheduler / 60:6.1f} min")
    print(f"results table      {t_table:.1f} s once at the end")
    print(f"files              {disk / 1e9:.0f} GB if every variant writes STEP + STL "
          f"({disk / 1e6 / max(compute, scheduler):.0f} MB/s sustained onto the shared folder)")
    bound = "compute" if compute >= scheduler else "the scheduler / result collection"
    print(f"estimate: about {max(compute, scheduler) / 60 + t_table / 60:.0f} min, bound by {bound}; the scheduler "
          f"becomes the bottleneck above {per_variant / overhead:.0f} workers (work per variant / overhead per task)")


if __name__ == "__main__":
    main()
