"""OpenCascade's STEP transfer in a child process, so that a file it cannot survive becomes an error.

The syntax scan (:mod:`exporters._stepscan`) refuses what OCC's *parser* cannot survive. OCC's
*transfer* still crashes (segmentation fault, abort) or hangs on some syntactically clean files
whose entities make no sense: a reference to an entity of the wrong type, a reference cycle, an
impossible count (11 of 20,000 fuzzed files in the reliability report). No Python code can catch
a crash in the same process, so :func:`transfer` runs the transfer in a worker process
(:mod:`exporters._step_worker`) under a time limit and an address-space limit, and brings the
shapes back as OCC's binary BREP files (exact: a file read in the worker gives the same shapes,
to the last bit, as one read in this process). A crash, a hang or a memory exhaustion there raises
FileFormatError / ResourceLimitError naming the file, and the worker is replaced.

The worker is one long-lived interpreter per process, started on first use, because starting
one and importing OCP costs seconds (measured 3-8 s on a loaded 2-core machine) against a
transfer of well under a second for most files. It is started with :mod:`subprocess`
(``python -m exporters._step_worker``) rather than ``multiprocessing``: a spawned
multiprocessing child re-imports the caller's main script, which breaks a script without a
``__main__`` guard.
"""

from __future__ import annotations

import atexit
import json
import os
import select
import subprocess
import sys
import tempfile
import threading

from splinekit import limits
from splinekit.errors import FileFormatError, ResourceLimitError


__all__ = ["BASE_SECONDS", "SECONDS_PER_MB", "START_SECONDS", "start", "transfer"]

START_SECONDS = 300.0
"""Time the worker may take to start (interpreter, numpy, splinekit, OCP) on a loaded machine."""

BASE_SECONDS = 60.0
"""Time a transfer may take whatever the file's size."""

SECONDS_PER_MB = 60.0
"""Additional transfer time per MB of STEP text (the shared files take under 10 s per MB)."""

_ERRORS = {"FileFormatError": FileFormatError, "ResourceLimitError": ResourceLimitError}
_lock = threading.Lock()
_worker: list = []  # the running worker's Popen, if any


def _child_env() -> dict:
    """The caller's environment with the folders holding ``splinekit`` and ``exporters`` first
    on PYTHONPATH, so the child imports the same code as the caller."""
    roots = [os.path.dirname(os.path.dirname(os.path.abspath(f))) for f in (limits.__file__, __file__)]
    env = dict(os.environ)
    rest = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    env["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(roots + rest))
    return env


def _stop() -> None:
    while _worker:
        proc = _worker.pop()
        proc.kill()
        proc.wait()


atexit.register(_stop)


_HUNG = object()


def _answer(proc, seconds: float):
    """The worker's next JSON line; None when it died (end of its output), ``_HUNG`` when it
    said nothing within ``seconds``."""
    ready, _, _ = select.select([proc.stdout], [], [], seconds)
    if not ready:
        return _HUNG
    line = proc.stdout.readline()
    return json.loads(line) if line else None


def _spawn() -> None:
    """Start a worker without waiting for it: after a crash the next one starts at once, so the
    next read does not pay the whole start-up."""
    proc = subprocess.Popen([sys.executable, "-m", "exporters._step_worker"], env=_child_env(), text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    proc.splinekit_ready = False
    _worker.append(proc)


def _running():
    """The worker, started (or restarted after it died) and ready for a request."""
    if not (_worker and _worker[0].poll() is None):
        _stop()
        _spawn()
    proc = _worker[0]
    if not proc.splinekit_ready:
        if _answer(proc, START_SECONDS) != "ready":
            _stop()
            raise FileFormatError("the STEP reader's worker process did not start (is OCP installed?)")
        proc.splinekit_ready = True
    return proc


def start() -> None:
    """Start the worker now and wait until it is ready (it starts on first use otherwise)."""
    with _lock:
        _running()


def transfer(path: str, mode: str, metres: float = 0.001) -> list:
    """``(name, TopoDS_Shape)`` pairs of the STEP file ``path`` transferred by OCC in the worker.

    ``mode`` is ``"named"`` (the XCAF reading of :func:`exporters.import_step`: one pair per part,
    coordinates in units of ``metres``) or ``"shape"`` (all roots as one shape in millimetres,
    name ``None``: :func:`exporters.step.read_step_shape`). The transfer gets at most
    ``BASE_SECONDS + SECONDS_PER_MB * size`` seconds and the memory budget
    (:mod:`splinekit.limits`) as address space beyond what the worker maps when idle.
    """
    seconds = BASE_SECONDS + SECONDS_PER_MB * os.path.getsize(path) / 2**20
    budget = limits.current_budget()
    budget_text = f"{budget / 2**20:.0f} MiB" if budget != float("inf") else "(none set)"
    with _lock, tempfile.TemporaryDirectory(prefix="splinekit-step-") as out:
        proc = _running()
        request = {"path": os.path.abspath(path), "mode": mode, "metres": float(metres), "out": out,
                   "budget": "inf" if budget == float("inf") else int(budget)}
        proc.stdin.write(json.dumps(request) + "\n")
        proc.stdin.flush()
        result = _answer(proc, seconds)
        if result is None or result is _HUNG:
            _stop()
            _spawn()
            if result is _HUNG:
                raise FileFormatError(
                    f"OpenCascade did not finish translating the STEP file {path!r} within {seconds:.0f} s "
                    "(its entities may reference each other in a cycle); the file was refused"
                )
            raise FileFormatError(
                f"OpenCascade crashed translating the STEP file {path!r} (exit status {proc.returncode}): its "
                "entities are inconsistent (e.g. a reference to an entity of the wrong type) or it needs "
                f"more than the memory budget of {budget_text}"
            )
        if "error" in result:
            message = result["message"]
            if message == "MemoryError":
                message = (f"translating the STEP file {path!r} needs more than the memory budget of "
                           f"{budget_text}; raise it with {limits.ENV_VAR}=<bytes>")
            raise _ERRORS.get(result["error"], FileFormatError)(message)
        return [(name, _read_binary(os.path.join(out, f"{i}.bin"))) for i, name in enumerate(result["names"])]


def _read_binary(path: str):
    """The shape the worker wrote to ``path`` in OCC's binary BREP format."""
    from OCP.BinTools import BinTools
    from OCP.TopoDS import TopoDS_Shape

    shape = TopoDS_Shape()
    if not BinTools.Read_s(shape, path) or shape.IsNull():
        raise FileFormatError(f"the STEP reader's worker process wrote no readable shape to {path!r}")
    return shape
