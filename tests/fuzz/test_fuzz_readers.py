"""Fuzzing every file reader: mutated valid files give a valid, finite result or a SplineKitError.

Each reader (STL binary and ASCII, OBJ, PLY binary and ASCII, 3MF, glTF binary, STEP) gets valid
files written by the exporters or by hand, mutated by hypothesis:

- bytes: flips (biased towards the headers), truncation, deletion, insertion of format tokens
  (``end_header``, ``(``, ``'``, ``nan``, ``1e999``, line endings, ...), duplication of a slice
  (repeated elements, deeper nesting), replacement of a number by an extreme one;
- structure: the XML of a 3MF model part (elements duplicated, attributes changed) repackaged in
  a fresh zip; the JSON of a GLB (any value replaced by a JSON value of any type, keys deleted,
  array entries repeated) with consistent chunk lengths; PLY header lines.

The oracle: a mesh reader returns a PolyMesh with finite vertices and face indices in range, or
raises SplineKitError; a case may take at most :data:`CASE_SECONDS`. STEP files go to OpenCascade,
whose crashes no Python code can catch, so they are read in a worker subprocess (restarted after a
crash, which counts as a failure).

The default run tries :data:`QUICK` cases per reader; ``pytest -m slow tests/fuzz`` runs
:data:`LONG` per reader and prints the outcomes (ok / SplineKitError / other), the slowest case
and the peak memory.
"""

from __future__ import annotations

import collections
import io
import json
import os
import re
import resource
import select
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import exporters
from splinekit.errors import SplineKitError
from splinekit.mesh import PolyMesh, primitives

from _readerfiles import RELS, TETRA_T, TETRA_V, glb, mesh_object, model_xml, tetra_gltf

QUICK = 200
LONG = 20_000
CASE_SECONDS = 10.0
HANG_WALL_SECONDS = 600.0
"""Wall-clock limit of one STEP case, for a worker blocked without using CPU time."""

RUNS = [pytest.param(QUICK, id="quick"), pytest.param(LONG, id="long", marks=pytest.mark.slow)]

OUTCOMES: dict = collections.defaultdict(collections.Counter)
SLOWEST: dict = collections.defaultdict(float)


# -- valid files to start from -------------------------------------------------------------------
def _mesh() -> PolyMesh:
    """A closed mesh with triangles and quads and non-round coordinates."""
    box = primitives.box()
    return box.with_vertices(box.vertices * [1.5, 0.25, 3.0] + [0.1, -2.0, 1e-3])


def _file_bytes(write, suffix: str, tmp_dir) -> bytes:
    path = os.path.join(tmp_dir, "base" + suffix)
    write(path)
    with open(path, "rb") as fh:
        return fh.read()


def _affine_text(seed: int) -> str:
    M = np.random.default_rng(seed).standard_normal((4, 3))
    return " ".join(repr(float(v)) for v in M.ravel())


def _base_3mf_model() -> bytes:
    """A model part with a mesh object, an object of two transformed components and two items."""
    resources = (mesh_object(1, TETRA_V, TETRA_T)
                 + f'<object id="2"><components><component objectid="1" transform="{_affine_text(1)}"/>'
                 + '<component objectid="1"/></components></object>')
    build = f'<item objectid="2" transform="{_affine_text(2)}"/><item objectid="1"/>'
    return model_xml(resources, build).encode()


def _base_gltf() -> tuple:
    nodes = [{"scale": [2, 2, 2], "children": [1, 2]}, {"mesh": 0, "translation": [10, 0, 0]},
             {"mesh": 0, "rotation": [0, 0, 0.6, 0.8]}, {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 5, 5, 1]}]
    return tetra_gltf(nodes, [0, 3], n_points=6)


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    """Valid files (bytes) per reader name."""
    tmp = str(tmp_path_factory.mktemp("fuzz-bases"))
    mesh = _mesh()
    out = {
        "stl-binary": _file_bytes(lambda p: exporters.export_stl(p, mesh), ".stl", tmp),
        "stl-ascii": _file_bytes(lambda p: exporters.export_stl(p, mesh, binary=False), ".stl", tmp),
        "obj": _file_bytes(lambda p: exporters.export_obj(p, mesh), ".obj", tmp),
        "ply-binary": _file_bytes(lambda p: exporters.export_ply(p, mesh), ".ply", tmp),
        "ply-ascii": _file_bytes(lambda p: exporters.export_ply(p, mesh, binary=False), ".ply", tmp),
        "3mf": _base_3mf_model(),
        "glb": _base_gltf(),
    }
    try:
        import OCP  # noqa: F401
    except ImportError:
        pass
    else:
        from splinekit import BSplineSurface

        grid = np.stack(np.meshgrid(np.linspace(0, 2, 3), np.linspace(0, 1, 3), indexing="ij"), axis=-1)
        net = np.concatenate([grid, np.sin(grid[..., :1] * grid[..., 1:])], axis=-1)
        surface = BSplineSurface(2, 2, [0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1], net)
        out["step"] = _file_bytes(lambda p: exporters.export_step(p, [surface], names=["patch (1)"]), ".step", tmp)
    return out


# -- mutations -----------------------------------------------------------------------------------
TOKENS = [
    b"0", b"-1", b"1e308", b"1e999", b"-1e999", b"nan", b"inf", b"4294967295", b"99999999999999999999", b"1.5",
    b"\x00", b"\r", b"\n", b"\r\n", b" ", b"\t", b"(", b")", b"'", b"''", b"/*", b"*/", b"<", b">", b"/>", b"&",
    b"&amp;", b"&#0;", b'"', b"#", b";", b",", b"=", b"$", b"*", b"{", b"}", b"[", b"]", b":", b"\\", b"\xff\xfe",
    b"\xc3", b"end_header", b"comment end_header", b"element", b"property", b"list", b"uchar", b"double", b"solid",
    b"endsolid", b"facet", b"vertex", b"endloop", b"v", b"f", b"vn", b"vt", b"<object", b"<item objectid=\"1\"/>",
    b"#1", b"#999999", b"ENDSEC;", b"DATA;", b"((((((((", b"))))))))",
]
EXTREMES = [b"0", b"-0", b"1e308", b"-1e308", b"1e999", b"nan", b"-inf", b"5e-324", b"4294967296", b"-2147483649",
            b"99999999999999999999999", b"1e-999", b"0x10", b"1_0", b"+7", b"3.", b".5", b"1e", b""]
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def mutate_bytes(draw, buf: bytes, text: bool) -> bytes:
    """One to four random byte-level edits of ``buf``."""
    for op in draw(st.lists(st.sampled_from(["flip", "truncate", "insert", "delete", "duplicate", "number"]),
                            min_size=1, max_size=4)):
        n = len(buf)
        if op == "flip" and n:
            head = draw(st.booleans())  # half the flips hit the first 128 bytes: headers, counts
            pos = draw(st.integers(0, min(n, 128) - 1 if head else n - 1))
            buf = buf[:pos] + bytes([buf[pos] ^ draw(st.integers(1, 255))]) + buf[pos + 1:]
        elif op == "truncate":
            buf = buf[:draw(st.integers(0, n))]
        elif op == "insert":
            pos = draw(st.integers(0, n))
            token = draw(st.sampled_from(TOKENS) | st.binary(min_size=1, max_size=8))
            buf = buf[:pos] + token * draw(st.integers(1, 4)) + buf[pos:]
        elif op == "delete" and n:
            start = draw(st.integers(0, n - 1))
            buf = buf[:start] + buf[start + draw(st.integers(1, 64)):]
        elif op == "duplicate" and n:
            start = draw(st.integers(0, n - 1))
            piece = buf[start:start + draw(st.integers(1, 256))]
            buf = buf[:start] + piece * draw(st.integers(2, 9)) + buf[start:]
        elif op == "number" and text:
            numbers = list(_NUMBER.finditer(buf))
            if numbers:
                m = numbers[draw(st.integers(0, len(numbers) - 1))]
                buf = buf[:m.start()] + draw(st.sampled_from(EXTREMES)) + buf[m.end():]
    return buf


_ELEMENT = re.compile(rb"<(?:vertex|triangle|item|component|object)\b[^>]*?/>")
_ATTRIBUTE = re.compile(rb'\b(\w+)="[^"]*"')


def mutate_3mf(draw, model: bytes) -> bytes:
    """A 3MF package: the model XML edited (elements repeated, attributes changed or dropped, byte
    edits), zipped afresh; sometimes the zip bytes edited too."""
    kind = draw(st.sampled_from(["xml", "element", "attribute", "zip"]))
    if kind == "element":
        found = list(_ELEMENT.finditer(model))
        m = found[draw(st.integers(0, len(found) - 1))]
        model = model[:m.end()] + m.group() * draw(st.integers(1, 200)) + model[m.end():]
    elif kind == "attribute":
        found = list(_ATTRIBUTE.finditer(model))
        m = found[draw(st.integers(0, len(found) - 1))]
        value = draw(st.sampled_from(EXTREMES + [b"1 2 3", b"-1", b"2", b"1e300 0 0 0 1e300 0 0 0 1e300 0 0 0", b"&lt;"]))
        new = b"" if draw(st.integers(0, 3)) == 0 else m.group(1) + b'="' + value + b'"'  # dropped, or a new value
        model = model[:m.start()] + new + model[m.end():]
    elif kind in ("xml", "zip"):
        model = mutate_bytes(draw, model, text=True) if kind == "xml" else model
    out = io.BytesIO()
    method = draw(st.sampled_from([zipfile.ZIP_DEFLATED, zipfile.ZIP_STORED]))
    with zipfile.ZipFile(out, "w", compression=method) as z:
        z.writestr("_rels/.rels", RELS)
        z.writestr("3D/3dmodel.model", model)
    data = out.getvalue()
    return mutate_bytes(draw, data, text=False) if kind == "zip" else data


_JSON_KEYS = ["nodes", "children", "mesh", "meshes", "primitives", "attributes", "POSITION", "indices", "mode",
              "accessors", "bufferView", "bufferViews", "buffer", "buffers", "byteOffset", "byteLength",
              "byteStride", "count", "componentType", "type", "matrix", "translation", "rotation", "scale",
              "scene", "scenes", "sparse", "uri", "extensionsRequired", "normalized"]
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.sampled_from([0, 1, 2, 3, -1, 4, 5121, 5123, 5125, 5126])
    | st.floats() | st.text(max_size=6) | st.sampled_from(["VEC3", "SCALAR", "MAT4", "KHR_draco_mesh_compression"]),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.sampled_from(_JSON_KEYS), inner, max_size=3),
    max_leaves=10,
)


def _paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, prefix + (i,))


def mutate_glb(draw, base: tuple) -> bytes:
    """A GLB: the JSON edited (a value replaced by any JSON value, a key deleted, an array entry
    repeated) with consistent chunk lengths, or the BIN chunk or the whole file edited."""
    doc, binary = json.loads(json.dumps(base[0])), base[1]
    kind = draw(st.sampled_from(["replace", "delete", "repeat", "bin", "bytes"]))
    paths = list(_paths(doc))[1:]
    path = paths[draw(st.integers(0, len(paths) - 1))]
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    if kind == "replace":
        parent[path[-1]] = draw(JSON_VALUES)
    elif kind == "delete":
        del parent[path[-1]]
    elif kind == "repeat" and isinstance(parent, list):
        parent.extend([parent[path[-1]]] * draw(st.integers(1, 50)))
    elif kind == "bin":
        binary = mutate_bytes(draw, binary, text=False)
    data = glb(doc, binary)
    return mutate_bytes(draw, data, text=False) if kind == "bytes" else data


def mutate_ply(draw, base: bytes) -> bytes:
    """A header line's word replaced (types, counts, names), or byte edits."""
    end = base.index(b"end_header\n") + len(b"end_header\n")
    if draw(st.booleans()):
        return mutate_bytes(draw, base, text=b"format ascii" in base)
    lines = base[:end].split(b"\n")
    i = draw(st.integers(1, len(lines) - 3))
    words = lines[i].split(b" ")
    j = draw(st.integers(0, len(words) - 1))
    words[j] = draw(st.sampled_from([b"float", b"double", b"uchar", b"int", b"list", b"vertex", b"face",
                                     b"vertex_indices", b"x", b"-1", b"0", b"4294967296", b"99999999999", b"ascii",
                                     b"binary_big_endian", b"comment", b"end_header", b"property", b"element"]))
    lines[i] = b" ".join(words)
    if draw(st.booleans()):
        lines.insert(i, lines[i])  # a repeated header line
    return b"\n".join(lines) + base[end:]


def mutation(reader: str):
    """A strategy of mutated files (bytes) for ``reader`` from ``bases[reader]``."""

    @st.composite
    def mutated(draw, base):
        if reader == "3mf":
            return mutate_3mf(draw, base)
        if reader == "glb":
            return mutate_glb(draw, base)
        if reader.startswith("ply"):
            return mutate_ply(draw, base)
        return mutate_bytes(draw, base, text=reader not in ("stl-binary",))

    return mutated


# -- running a case -----------------------------------------------------------------------------
SUFFIX = {"stl-binary": ".stl", "stl-ascii": ".stl", "obj": ".obj", "ply-binary": ".ply", "ply-ascii": ".ply",
          "3mf": ".3mf", "glb": ".glb", "step": ".step"}


def check_mesh(mesh) -> None:
    assert isinstance(mesh, PolyMesh), type(mesh)
    V = mesh.vertices
    assert V.ndim == 2 and V.shape[1] == 3 and np.isfinite(V).all(), "non-finite vertices"
    idx = mesh.face_indices
    assert idx.size == 0 or (idx.min() >= 0 and idx.max() < len(V)), "face index out of range"


_STEP_WORKER = r"""
import json, sys
import numpy as np
import exporters
from splinekit.errors import SplineKitError

def finite(g):
    for name in ("control_points", "weights", "knots", "knots_u", "knots_v", "vertices"):
        a = getattr(g, name, None)
        if a is not None and not np.isfinite(np.asarray(a, dtype=float)).all():
            return False
    return True

import OCP.STEPCAFControl  # noqa: F401 - loaded before the first case is timed
import exporters._step_isolated
exporters._step_isolated.start()  # the reader's own worker process, also before the first case
print(json.dumps("ready"), flush=True)
for line in sys.stdin:
    try:
        items = exporters.import_step(line.rstrip("\n"))
        out = "ok" if all(finite(item.geometry) for item in items) else "other: non-finite geometry"
    except SplineKitError:
        out = "SplineKitError"
    except BaseException as exc:
        out = "other: %s: %s" % (type(exc).__name__, str(exc)[:300])
    sys.stdout.write(json.dumps(out) + "\n")
    sys.stdout.flush()
"""


class StepWorker:
    """A subprocess that reads STEP files with import_step, one path per line; a crash or a hang is
    reported as an outcome and the worker restarted."""

    def __init__(self):
        self.proc = None
        self.case_seconds = 0.0  # CPU time of the last case read

    def _start(self):
        self.proc = subprocess.Popen([sys.executable, "-c", _STEP_WORKER], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        ready, _, _ = select.select([self.proc.stdout], [], [], 300)
        if not ready or json.loads(self.proc.stdout.readline() or "null") != "ready":
            raise RuntimeError("the STEP worker did not start")

    def start(self):
        if self.proc is None or self.proc.poll() is not None:
            self._start()
        return self

    def cpu_seconds(self) -> float:
        """CPU time (user + system, seconds) the worker has used: what a case costs, which a loaded
        machine does not inflate as it does the wall clock."""
        with open(f"/proc/{self.proc.pid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()  # after the command name, which may hold spaces
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def read(self, path: str) -> str:
        self.start()
        self.proc.stdin.write(path + "\n")
        self.proc.stdin.flush()
        # a hang is CASE_SECONDS * 6 of the worker's CPU time, or a worker blocked without using
        # any for HANG_WALL_SECONDS; the wall clock alone called a slow case on a loaded machine a hang
        start, wall = self.cpu_seconds(), time.monotonic()
        ready, self.case_seconds = False, 0.0
        while not ready:
            ready, _, _ = select.select([self.proc.stdout], [], [], 1.0)
            used = self.cpu_seconds() - start
            self.case_seconds = used
            if not ready and (used > CASE_SECONDS * 6 or time.monotonic() - wall > HANG_WALL_SECONDS):
                self.close()
                return f"other: hang (over {CASE_SECONDS * 6:.0f} s of CPU time, {time.monotonic() - wall:.0f} s wall)"
        line = self.proc.stdout.readline()
        self.case_seconds = self.cpu_seconds() - start  # the worker's, even when it died (not yet reaped)
        if line:
            return json.loads(line)
        status = self.proc.wait()  # end of output: the worker died
        self.close()
        return f"other: crash (status {status})"

    def peak_mb(self) -> float:
        try:
            with open(f"/proc/{self.proc.pid}/status") as fh:
                return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM")) / 1024
        except (OSError, StopIteration, AttributeError):
            return float("nan")

    def close(self):
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None


def run_case(reader: str, path: str, worker) -> str:
    """The outcome of reading ``path``: ``"ok"``, ``"SplineKitError"`` or ``"other: ..."``."""
    if reader == "step":
        return worker.read(path)
    try:
        mesh = exporters.import_mesh(path)
    except SplineKitError:
        return "SplineKitError"
    except Exception as exc:  # noqa: BLE001 - every other exception is the failure being looked for
        return f"other: {type(exc).__name__}: {str(exc)[:300]}"
    try:
        check_mesh(mesh)
    except AssertionError as exc:
        return f"other: invalid result: {exc}"
    return "ok"


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


@pytest.mark.parametrize("examples", RUNS)
@pytest.mark.parametrize("reader", list(SUFFIX))
def test_fuzz_reader(reader, examples, bases, tmp_path, request):
    if examples > QUICK and "slow" not in (request.config.getoption("markexpr") or ""):
        pytest.skip("the long run: select it with -m slow")
    if reader not in bases:
        pytest.skip("OCP is not installed: no STEP reader")
    path = str(tmp_path / ("case" + SUFFIX[reader]))
    worker = StepWorker().start() if reader == "step" else None
    counts = OUTCOMES[(reader, examples)]
    failures = []
    report = os.environ.get("SPLINEKIT_FUZZ_REPORT")

    @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck),
              phases=[Phase.generate] if examples > QUICK else settings.default.phases)
    @given(mutation(reader)(bases[reader]))
    def case(content):
        with open(path, "wb") as fh:
            fh.write(content)
        if worker is not None:
            worker.start()  # restarted after a crash: not part of the next case's time
        # cases are timed by CPU time (the worker's for STEP), which a loaded machine does not inflate
        start = time.process_time()
        outcome = run_case(reader, path, worker)
        elapsed = worker.case_seconds if worker is not None else time.process_time() - start
        SLOWEST[(reader, examples)] = max(SLOWEST[(reader, examples)], elapsed)
        counts[outcome.split(":")[0]] += 1
        if report and sum(counts.values()) % 250 == 0:
            _write_report(f"{report}.{reader}.progress", reader, examples, counts, failures, worker, replace=True)
        if outcome.startswith("other") or elapsed > CASE_SECONDS:
            failures.append((outcome, round(elapsed, 2), content[:300]))
            if report:  # the whole input, to reproduce it
                with open(f"{report}.{reader}.failure{len(failures)}{SUFFIX[reader]}", "wb") as fh:
                    fh.write(content)
            if examples <= QUICK:  # the quick run stops and shrinks; the long run counts on
                assert not outcome.startswith("other"), outcome
                assert elapsed <= CASE_SECONDS, f"one case took {elapsed:.1f} s"

    try:
        case()
        assert not failures, f"{len(failures)} failures, the first: {failures[0]}"
    finally:
        peak = max(_peak_mb(), worker.peak_mb() if worker else 0.0)
        if worker:
            worker.close()
        line = (f"fuzz {reader}: {sum(counts.values())} cases, ok {counts['ok']}, SplineKitError "
                f"{counts['SplineKitError']}, other {counts['other']}; slowest {SLOWEST[(reader, examples)]:.2f} s; "
                f"peak memory {peak:.0f} MiB")
        if examples > QUICK:
            with request.config.pluginmanager.get_plugin("capturemanager").global_and_fixture_disabled():
                print("\n" + line)
        if report:
            _write_report(report, reader, examples, counts, failures, None, replace=False, peak=peak)


def _write_report(path, reader, examples, counts, failures, worker, replace, peak=None):
    """One JSON line of figures (SPLINEKIT_FUZZ_REPORT names the file; the long run also keeps a
    progress file per reader, rewritten every 250 cases)."""
    if peak is None:
        peak = max(_peak_mb(), worker.peak_mb() if worker else 0.0)
    record = {"reader": reader, "examples": examples, "cases": sum(counts.values()), **counts,
              "slowest_s": round(SLOWEST[(reader, examples)], 3), "peak_mib": round(peak),
              "failures": [f[:2] for f in failures[:5]]}
    with open(path, "w" if replace else "a") as fh:
        fh.write(json.dumps(record) + "\n")
