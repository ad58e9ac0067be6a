"""Peak memory of one workload, measured in a fresh child process (shared by the benchmarks).

The child resets the peak resident set size (``VmHWM``, through ``/proc/self/clear_refs``)
after its set-up and warm-up call, runs the workload once more and reports how far the peak
rose above the resident size before it: this sees every allocation, numpy's and those inside
compiled kernels or C++ peers alike (tracemalloc sees numpy's only).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys


def status(key: str) -> int:
    """A ``/proc/self/status`` entry in bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    raise KeyError(key)


def measure_here(run) -> int | None:
    """Peak RSS growth (bytes) of ``run()`` in this process, after a warm-up call; None without /proc."""
    run()
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # reset VmHWM to the current RSS
        base = status("VmRSS")
    except OSError:
        return None
    run()
    return status("VmHWM") - base


def in_child(script: str, case: str, env: dict | None = None, timeout: float = 900) -> int | None:
    """Run ``python script --child case`` (which prints ``measure_here``'s figure as JSON on its last
    line) and return the figure, or None when the child fails or /proc is missing."""
    try:
        res = subprocess.run([sys.executable, script, "--child", case], capture_output=True, text=True,
                             timeout=timeout, env={**os.environ, **(env or {})}, check=True)
        return json.loads(res.stdout.strip().splitlines()[-1])
    except Exception:  # noqa: BLE001 (a peer missing in the child, no /proc: no figure)
        return None


def mb(nbytes) -> str:
    if nbytes is None:
        return "n/a"
    return f"{nbytes / 1e6:.1f} MB" if abs(nbytes) < 10e6 else f"{nbytes / 1e6:.0f} MB"
