"""STEP files whose syntax is clean but whose entities make OCC's transfer crash: read in the
worker process (exporters._step_isolated), each gives a SplineKitError naming the file.

The crashers are mutations of a file build123d writes (a box minus a cylinder), one per class
found by replacing one reference at a time in such a file (150 tries per kind): a reference to an
entity of the wrong type, an entity referring to itself, and two entities referring to each
other. Each test first shows that the file crashes an in-process read (the test would fail if the
file were harmless), then that the default, isolated read refuses it. Both run in subprocesses
so that a crash cannot take pytest down.
"""

from __future__ import annotations

import json
import math
import re
import signal
import subprocess
import sys

import pytest

_READ = r"""
import json, sys
import exporters
from splinekit.errors import SplineKitError
out = []
for path in sys.argv[2:]:
    try:
        items = exporters.import_step(path, strict=False, isolated=sys.argv[1] == "isolated")
        out.append(["ok", len(items)])
    except SplineKitError as exc:
        out.append([type(exc).__name__, str(exc)])
print(json.dumps(out))
"""


def _read(paths, mode: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _READ, mode, *paths], capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def base_step(tmp_path_factory) -> str:
    bd = pytest.importorskip("build123d")
    path = str(tmp_path_factory.mktemp("step") / "base.step")
    bd.export_step(bd.Box(1, 2, 3) - bd.Cylinder(0.3, 5), path)
    return path


def _first(text: str, kind: str) -> tuple[str, list[str]]:
    """The id and the referenced ids of the first ``kind`` entity (e.g. a LINE)."""
    match = re.search(rf"^#(\d+)\s*=\s*{kind}\((.*)\);", text, re.M)
    return match.group(1), re.findall(r"#(\d+)", match.group(2))


def _set_reference(text: str, entity: str, index: int, target: str) -> str:
    """``text`` with the ``index``-th reference of entity ``#entity`` replaced by ``#target``."""
    match = re.search(rf"^#{entity}\s*=.*$", text, re.M)
    line = match.group(0)
    head, body = line.split("=", 1)
    refs = list(re.finditer(r"#\d+", body))
    ref = refs[index]
    body = body[: ref.start()] + f"#{target}" + body[ref.end():]
    return text[: match.start()] + head + "=" + body + text[match.end():]


def _crashers(base: str, folder) -> dict[str, str]:
    text = open(base).read()
    line, (point, vector) = _first(text, "LINE")  # LINE('', point, vector)
    direction = _first(text[text.index(f"#{vector} ="):], "VECTOR")[1][0]  # VECTOR('', direction, length)
    variants = {
        # a VECTOR whose direction is a CARTESIAN_POINT
        "wrong type": _set_reference(text, vector, 0, point),
        # a VECTOR whose direction is the VECTOR itself
        "self reference": _set_reference(text, vector, 0, vector),
        # a LINE whose VECTOR's direction is the LINE: a cycle of two
        "cycle of two": _set_reference(text, vector, 0, line),
    }
    assert direction != point  # the mutations did change a reference
    paths = {}
    for name, content in variants.items():
        assert content != text
        path = str(folder / (name.replace(" ", "_") + ".step"))
        with open(path, "w") as fh:
            fh.write(content)
        paths[name] = path
    return paths


NAMES = ["wrong type", "self reference", "cycle of two"]


@pytest.fixture(scope="module")
def crashers(base_step, tmp_path_factory) -> dict[str, str]:
    return _crashers(base_step, tmp_path_factory.mktemp("crashers"))


@pytest.mark.parametrize("name", NAMES)
def test_crasher_ends_an_in_process_read(crashers, name):
    done = _read([crashers[name]], "in-process")
    assert done.returncode in (-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS), (done.returncode, done.stdout)


def test_crashers_give_a_splinekit_error_naming_the_file(crashers, base_step):
    paths = [crashers[n] for n in NAMES] + [base_step]
    done = _read(paths, "isolated")
    assert done.returncode == 0, done.stderr[-2000:]
    outcomes = json.loads(done.stdout.strip().splitlines()[-1])
    for name, path, (kind, message) in zip(NAMES, paths, outcomes[:-1]):
        assert kind == "FileFormatError", (name, kind, message)
        assert repr(path) in message and "crashed" in message, (name, message)
    # the worker was replaced after each crash: the valid file after them still reads
    assert outcomes[-1] == ["ok", 1], outcomes[-1]


def test_isolated_read_equals_the_in_process_read(base_step):
    import exporters
    from splinekit.brep import Solid

    isolated = exporters.import_step(base_step)
    direct = exporters.import_step(base_step, isolated=False)
    assert [i.name for i in isolated] == [i.name for i in direct]
    assert all(isinstance(i.geometry, Solid) for i in isolated + direct)
    # the BREP round trip keeps every face and its exact geometry
    a, b = isolated[0].geometry, direct[0].geometry
    assert len(a.faces) == len(b.faces)
    exact = 1 * 2 * 3 - math.pi * 0.3**2 * 3  # the box minus the hole the cylinder drills through it
    assert abs(a.volume() - exact) <= 1e-6 * exact and abs(b.volume() - exact) <= 1e-6 * exact


def test_the_worker_is_held_to_the_memory_budget(tmp_path):
    bd = pytest.importorskip("build123d")
    from exporters import _step_isolated
    from splinekit import limits
    from splinekit.errors import SplineKitError

    plate = bd.Box(40, 40, 1)
    holes = [bd.Pos(x, y, 0) * bd.Cylinder(0.3, 3) for x in range(-19, 20, 2) for y in range(-19, 20, 2)]
    plate -= bd.Compound(children=holes)
    base_step = str(tmp_path / "plate.step")  # 400 holes, 1.6 MB: OCC needs tens of MB to read it
    bd.export_step(plate, base_step)
    # 1 MiB of address space beyond a fresh worker's (a worker that read larger files before has
    # room in its heap): OCC's first large allocation fails and the worker dies; this process gets
    # the error and a new worker reads the file under no limit
    _step_isolated._stop()
    with limits.budget("1M"), pytest.raises(SplineKitError, match="memory budget of 1 MiB"):
        _step_isolated.transfer(base_step, "named")
    with limits.budget("off"):
        assert len(_step_isolated.transfer(base_step, "named")) == 1


def test_a_transfer_over_its_time_limit_is_refused(base_step, monkeypatch):
    from exporters import _step_isolated
    from splinekit.errors import FileFormatError

    _step_isolated.start()  # the limit is on the transfer, not on the worker's start
    monkeypatch.setattr(_step_isolated, "BASE_SECONDS", 0.0)
    monkeypatch.setattr(_step_isolated, "SECONDS_PER_MB", 0.0)
    with pytest.raises(FileFormatError, match="did not finish translating the STEP file .*base.step"):
        _step_isolated.transfer(base_step, "named")
    monkeypatch.undo()
    assert len(_step_isolated.transfer(base_step, "named")) == 1  # a new worker took over
