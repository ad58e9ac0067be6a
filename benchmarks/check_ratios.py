#!/usr/bin/env python
"""Regression check of the speed ratios: run the short version of every benchmark and fail when a
ratio falls below its target.

Run from the repository root (CI does not: timings on shared machines are too noisy)::

    python benchmarks/check_ratios.py                   # every benchmark, --quick (about 10-20 minutes)
    python benchmarks/check_ratios.py --only ply --only booleans
    python benchmarks/check_ratios.py --full            # the full sizes (much longer)

Each benchmark runs in a fresh process with the repository first on ``PYTHONPATH`` and prints
``ratio: <name> = <value> (target >= <target>)`` lines (``benchmarks/_ratios.py``; a ratio is a
peer's time over splinekit's, or another figure where more is better) and ``skipped peer: ...``
lines for peers it could not run. This script prints one table of every ratio, then the skipped
peers, then the benchmarks that failed or printed no ratio, with the load average (other
processes skew the ratios: rerun a failing benchmark on a quiet machine before believing it).
Exit status 1 when a ratio is below its target or a benchmark failed, else 0.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import time

from _ratios import PATTERN

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

# every benchmark, the arguments of its short version, and how long it may take (seconds)
BENCHMARKS = {
    "booleans": (["--quick"], 600),
    "cold_start": (["--quick"], 2400),
    "contains": (["--quick"], 900),
    "continuity": (["--quick"], 900),
    "curvature": (["--quick"], 600),
    "deviation": (["--quick"], 900),
    "eval": (["--quick"], 900),
    "export": (["--quick"], 900),
    "implicit": (["--quick"], 900),
    "mass": (["--quick"], 900),
    "meshing": (["--quick"], 1500),
    "neural": (["--quick"], 1200),
    "ply": (["--quick"], 600),
    "pointcloud": (["--quick"], 900),
    "project": (["--quick"], 600),
    "sdf_grid": (["--quick"], 900),
    "step": (["--quick"], 900),
    "subdiv": (["--quick"], 1200),
    "subdiv_compose": (["--quick"], 600),
    "sweep": (["--quick"], 900),
    "tessellate": (["--quick"], 1200),
    "tessellate_pairs": (["--quick"], 600),
}
RATIO = re.compile(PATTERN)
SKIPPED = re.compile(r"^skipped peer: (?P<what>.*)$")


def run(name: str, args: list, timeout: float) -> dict:
    """One benchmark in a fresh process: its ratio lines, skipped peers and status."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [REPO, os.environ.get("PYTHONPATH")])))
    t0 = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, os.path.join(HERE, f"bench_{name}.py"), *args], cwd=REPO, env=env,
                              capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"ratios": [], "skipped": [], "error": f"timed out after {timeout:.0f} s", "seconds": timeout}
    ratios, skipped = [], []
    for line in done.stdout.splitlines():
        m = RATIO.match(line.strip())
        if m:
            ratios.append((m["name"], float(m["ratio"]), float(m["target"])))
        s = SKIPPED.match(line.strip())
        if s:
            skipped.append(s["what"])
    error = None
    if done.returncode:
        tail = (done.stderr.strip().splitlines() or ["(no error output)"])[-1]
        error = f"exit status {done.returncode}: {tail[:160]}"
    return {"ratios": ratios, "skipped": skipped, "error": error, "seconds": time.perf_counter() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", action="append", choices=sorted(BENCHMARKS), help="only this benchmark (repeatable)")
    ap.add_argument("--full", action="store_true", help="the full sizes instead of --quick")
    opts = ap.parse_args(argv)
    names = opts.only or list(BENCHMARKS)
    load_start = os.getloadavg()[0]
    results = {}
    for name in names:
        args, timeout = BENCHMARKS[name]
        if opts.full:
            args, timeout = [a for a in args if a != "--quick"], timeout * 10
        print(f"running bench_{name}.py {' '.join(args)} ...", file=sys.stderr, flush=True)
        results[name] = res = run(name, args, timeout)
        for label, ratio, target in res["ratios"]:  # as they come: a long run shows its progress
            print(f"  {label}: {ratio:.3g} (target >= {target:.3g})", file=sys.stderr, flush=True)
        if res["error"]:
            print(f"  failed: {res['error']}", file=sys.stderr, flush=True)

    print(f"# Speed ratios ({'full' if opts.full else 'quick'} benchmarks)\n")
    print(f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}; "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; load average {load_start:.2f} at start, "
          f"{os.getloadavg()[0]:.2f} at end\n")
    print("| benchmark | ratio | measured | target | met |")
    print("|---|---|---:|---:|---|")
    below = 0
    for name, res in results.items():
        for label, ratio, target in res["ratios"]:
            ok = ratio >= target
            below += not ok
            print(f"| {name} | {label} | {ratio:.3g} | >= {target:.3g} | {'yes' if ok else '**NO**'} |")
    skipped = [(n, s) for n, r in results.items() for s in r["skipped"]]
    if skipped:
        print("\nPeers not run:\n")
        for name, what in skipped:
            print(f"- {name}: {what}")
    failed = [(n, r["error"]) for n, r in results.items() if r["error"]]
    silent = [n for n, r in results.items() if not r["error"] and not r["ratios"]]
    if failed:
        print("\nBenchmarks that failed:\n")
        for name, error in failed:
            print(f"- {name}: {error}")
    if silent:
        print(f"\nBenchmarks without a ratio (no peer to time against): {', '.join(silent)}")
    print(f"\n{sum(len(r['ratios']) for r in results.values())} ratios, {below} below target, "
          f"{len(failed)} benchmarks failed; {sum(r['seconds'] for r in results.values()):.0f} s")
    return 1 if below or failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
