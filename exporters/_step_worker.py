"""The child process of :mod:`exporters._step_isolated`: STEP transfers, shapes out as BREP files.

Run as ``python -m exporters._step_worker``. It imports OCP once, prints ``"ready"`` as a JSON
line, then serves one request per line of its standard input, a JSON object ``{"path", "mode",
"metres", "out", "budget"}``: it limits its address space to what it maps then plus ``budget``
bytes, transfers the file, writes ``out/0.bin``, ``out/1.bin``, ... (OCC's binary BREP, which
keeps every double exactly; the text BREP format rounds coordinates by up to 1e-13, enough to
change how OCC's STEP reader treats a written face on a knife edge) and answers with one JSON
line, ``{"names": [...]}`` or ``{"error": class name, "message": ...}`` for a SplineKitError.
A crash or a hang gives no answer: the parent kills it and starts another.
"""

from __future__ import annotations

import json
import os
import resource
import sys

from splinekit.errors import SplineKitError

from .step import _ocp_step, _read_named_shapes, read_step_shape


def _limit_address_space(extra: float) -> None:
    """Soft address-space limit: what the process maps now plus ``extra`` bytes (none for inf).
    Only the soft limit changes, so a later request may raise it again up to the hard limit."""
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = hard
    if extra != float("inf"):
        with open("/proc/self/status") as fh:
            now = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmSize"))
        limit = now + int(extra) if hard == resource.RLIM_INFINITY else min(now + int(extra), hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def serve(request: dict) -> dict:
    """One transfer: the answer for ``request`` (see the module docstring)."""
    from OCP.BinTools import BinTools  # optional heavy backend, loaded by _ocp_step already

    try:
        _limit_address_space(float(request["budget"]))
    except (OSError, ValueError, StopIteration):  # no /proc (not Linux): the time limit still holds
        pass
    try:
        if request["mode"] == "shape":
            named = [(None, read_step_shape(request["path"], isolated=False))]
        else:
            named = _read_named_shapes(request["path"], float(request["metres"]))
        for i, (_, shape) in enumerate(named):
            if not BinTools.Write_s(shape, os.path.join(request["out"], f"{i}.bin")):
                raise OSError("OpenCascade could not write a binary BREP file")
        return {"names": [name for name, _ in named]}
    except SplineKitError as exc:
        return {"error": type(exc).__name__, "message": str(exc)}
    except MemoryError:
        return {"error": "ResourceLimitError", "message": "MemoryError"}


def main() -> None:
    _ocp_step()  # load OCC's STEP libraries once, before any address-space limit
    print(json.dumps("ready"), flush=True)
    for line in sys.stdin:
        print(json.dumps(serve(json.loads(line))), flush=True)


if __name__ == "__main__":
    main()
