"""The memory floor of a workload: its peak memory against the size of the arrays it returns.

One helper for every benchmark::

    from _memory import measure_memory
    mem = measure_memory(lambda: splinekit_call(...))
    print(mem.line())  # "peak 41.2 MB (numpy/Python) / 44.0 MB (RSS) = 2.1x its output arrays (19.6 MB)"

Two peaks, taken in one extra (untimed) call:

- ``traced``: the peak of the allocations Python and numpy report to :mod:`tracemalloc` while the
  call runs (exact for numpy arrays and Python objects; blind to C++ libraries such as
  manifold3d or OpenCascade, which allocate with their own allocators);
- ``rss``: the peak resident set size above its value at the start (sees every allocator, and
  counts memory freed to the allocator but not returned to the system): Linux's high-water mark
  ``VmHWM``, reset to the current RSS through ``/proc/self/clear_refs`` before the call; where
  that reset is refused, sampled every millisecond by a thread (which misses short spikes).
  None off Linux.

The output size is the sum of ``nbytes`` of every array in the result (ndarrays, a PolyMesh's
vertices and flat faces, scipy sparse matrices' three arrays, inside tuples, lists and dicts).
A ratio near 1 is the floor: the workload holds little beyond what it returns.

For a peer whose allocations in one process would skew the next (or that must run without
splinekit's kernels loaded), the same ``VmHWM`` figure is taken in a fresh child process::

    from _memory import in_child, mb, measure_here
    # in the benchmark's ``--child CASE`` branch:  print(json.dumps(measure_here(lambda: fn(P))))
    peak = in_child(__file__, "splinekit:100000", {"SPLINEKIT_NUMBA": "1"})
    print(mb(peak))  # "41 MB", or "n/a" when the child failed or /proc is missing

:func:`measure_here` runs the workload once to warm up, resets the high-water mark and reports how
far the second run raised it above the resident size before it.
"""

from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import threading
import tracemalloc
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Memory", "in_child", "mb", "measure_here", "measure_memory", "output_bytes"]


def output_bytes(obj) -> int:
    """Bytes of the arrays held by ``obj`` (see the module notes); shared arrays counted once."""
    seen, total, stack = set(), 0, [obj]
    while stack:
        x = stack.pop()
        if isinstance(x, np.ndarray):
            base = x if x.base is None else x.base
            if id(base) not in seen:
                seen.add(id(base))
                total += x.nbytes
        elif isinstance(x, (tuple, list)):
            stack.extend(x)
        elif isinstance(x, dict):
            stack.extend(x.values())
        elif hasattr(x, "face_indices") and hasattr(x, "vertices"):  # a PolyMesh
            stack.extend([x.vertices, x.face_indices, x.face_offsets])
        elif all(hasattr(x, a) for a in ("data", "indices", "indptr")):  # scipy.sparse CSR/CSC
            stack.extend([x.data, x.indices, x.indptr])
    return total


def _status(key: str) -> int | None:
    """A ``/proc/self/status`` size in bytes (``VmRSS``, ``VmHWM``), or None."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _reset_high_water_mark() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


@dataclass
class Memory:
    traced: int  # bytes, tracemalloc peak above the start
    rss: int | None  # bytes, RSS peak above the start (None: not available)
    output: int  # bytes of the result's arrays
    result: object = field(default=None, repr=False)  # what fn returned

    def ratio(self) -> float:
        return self.traced / self.output if self.output else float("inf")

    def line(self) -> str:
        rss = "-" if self.rss is None else f"{self.rss / 1e6:.1f} MB"
        out = f"{self.output / 1e6:.1f} MB"
        return (f"peak {self.traced / 1e6:.1f} MB (numpy/Python) / {rss} (RSS) = "
                f"{self.ratio():.1f}x its output arrays ({out})")


def measure_memory(fn) -> Memory:
    """Run ``fn()`` once more and measure its peaks (see the module notes); not a timing run."""
    gc.collect()
    exact = _reset_high_water_mark()
    start = _status("VmRSS")
    peak = [start or 0]
    done = threading.Event()

    def sample():
        while not done.wait(0.001):
            now = _status("VmRSS")
            if now is not None and now > peak[0]:
                peak[0] = now

    thread = None if exact else threading.Thread(target=sample, daemon=True)
    tracing = tracemalloc.is_tracing()
    if not tracing:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    if thread is not None:
        thread.start()
    try:
        result = fn()
    finally:
        done.set()
        if thread is not None:
            thread.join()
        traced = tracemalloc.get_traced_memory()[1] - base
        if not tracing:
            tracemalloc.stop()
    end = _status("VmHWM" if exact else "VmRSS")
    if end is not None and end > peak[0]:
        peak[0] = end
    rss = None if start is None else peak[0] - start
    return Memory(traced, rss, output_bytes(result), result)


def measure_here(run) -> int | None:
    """Peak RSS growth (bytes) of ``run()`` in this process, after a warm-up call; None without /proc."""
    run()
    if not _reset_high_water_mark():
        return None
    base = _status("VmRSS")
    run()
    peak = _status("VmHWM")
    return None if base is None or peak is None else peak - base


def in_child(script: str, case: str, env: dict | None = None, timeout: float = 900) -> int | None:
    """Run ``python script --child case`` (which prints :func:`measure_here`'s figure as JSON on its
    last line) and return the figure, or None when the child fails or /proc is missing."""
    try:
        res = subprocess.run([sys.executable, script, "--child", case], capture_output=True, text=True,
                             timeout=timeout, env={**os.environ, **(env or {})}, check=True)
        return json.loads(res.stdout.strip().splitlines()[-1])
    except Exception:  # noqa: BLE001 (a peer missing in the child, no /proc: no figure)
        return None


def mb(nbytes) -> str:
    """``nbytes`` in megabytes for a table cell: one decimal below 10 MB, "n/a" for None."""
    if nbytes is None:
        return "n/a"
    return f"{nbytes / 1e6:.1f} MB" if abs(nbytes) < 10e6 else f"{nbytes / 1e6:.0f} MB"
