"""Crafted files that crashed, hung, exhausted memory or were misread by the readers.

Each test here failed on the readers before they were hardened: a STEP file nested 80,000 levels
deep (a segmentation fault inside OpenCascade, reproduced in a subprocess), 3MF XML that regular
expressions parse in quadratic time, a zip bomb, 3MF and glTF instancing bombs, a 3MF transform
that overflows, glTF JSON of the wrong types, a PLY comment holding ``end_header``, an OBJ file
with CR-only line endings. The STEP scan's nesting depth is checked against an independent,
character-by-character reference on generated text.
"""

from __future__ import annotations

import contextlib
import glob
import json
import os
import re
import struct
import subprocess
import sys
import tracemalloc
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import exporters
from exporters import _stepscan
from exporters.step import read_step_shape
from splinekit import limits
from splinekit.errors import FileFormatError, ResourceLimitError
from splinekit.mesh import primitives

from _readerfiles import (
    CORE_NS, RELS, STEP_HEAD, STEP_TAIL, TETRA_T, TETRA_V, glb, mesh_object, model_xml, nested_step, tetra_gltf,
    write_3mf, write_bytes,
)

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STEP_DATA = os.path.join(REPO, "..", "shared", "data", "step")
STEP_FILES = sorted(f for f in glob.glob(os.path.join(STEP_DATA, "*")) if f.lower().endswith((".stp", ".step")))


@contextlib.contextmanager
def _allocation_peak():
    """Yields a list that holds, after the block, the peak of memory allocated inside it (MiB).

    tracemalloc follows Python's and numpy's allocations (numpy reports its buffers to it), so the
    figure is this block's own peak; the process's ru_maxrss is a high-water mark that a large
    test session has usually passed long before, which would hide an allocation here."""
    started = not tracemalloc.is_tracing()
    if started:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    box = [0.0]
    try:
        yield box
    finally:
        box[0] = (tracemalloc.get_traced_memory()[1] - base) / 2**20
        if started:
            tracemalloc.stop()


# -- STEP: nesting that crashes OpenCascade ----------------------------------------------------
def _run(code: str, *args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, timeout=300,
                          cwd=REPO)


def test_deeply_nested_step_is_refused_instead_of_crashing(tmp_path):
    """80,000 nested lists (160 KB) killed the process inside OCC's parser; now a FileFormatError."""
    pytest.importorskip("OCP")
    path = tmp_path / "deep.step"
    path.write_text(nested_step(80_000))
    code = (
        "import sys, exporters\n"
        "from splinekit.errors import FileFormatError\n"
        "try:\n    exporters.import_step(sys.argv[1])\n"
        "except FileFormatError as exc:\n    print('refused:', exc)\n"
    )
    done = _run(code, path)
    assert done.returncode == 0, f"import_step crashed (status {done.returncode}): {done.stderr[-500:]}"
    assert "refused:" in done.stdout and "80001 levels" in done.stdout and str(_stepscan.MAX_NESTING) in done.stdout
    # `splinekit info` hands STEP files to OCC by another path: one line, no crash
    info = subprocess.run([sys.executable, "-m", "splinekit.cli", "info", str(path)], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert info.returncode not in (0, -11, 139), info.stderr
    assert "nest" in info.stderr and "Traceback" not in info.stderr


def test_nesting_limit_is_far_below_what_occ_survives(tmp_path):
    """The limit is refused in-process; OCC itself (in a subprocess) still reads 10x the limit."""
    pytest.importorskip("OCP")
    limit = _stepscan.MAX_NESTING
    ok, deep = tmp_path / "ok.step", tmp_path / "deep.step"
    ok.write_text(nested_step(limit - 1))  # the entity's own parameter list adds a level
    deep.write_text(nested_step(limit))
    assert _stepscan.scan_step(ok).depth == limit
    with pytest.raises(FileFormatError, match=rf"nest {limit + 1} levels deep .*line 8"):
        _stepscan.scan_step(deep)
    far = tmp_path / "far.step"
    far.write_text(nested_step(10 * limit))
    code = "import sys\nfrom OCP.STEPControl import STEPControl_Reader\nSTEPControl_Reader().ReadFile(sys.argv[1])\nprint('alive')"
    done = _run(code, far)
    assert done.returncode == 0 and "alive" in done.stdout


def _reference_scan(text: str) -> tuple[int, bool]:
    """``(deepest nesting, balanced)`` of the parentheses outside strings and comments, one
    character at a time (an independent reference for the vectorized scan). Balanced: no ')'
    closes nothing, and nothing is open at a ';' or at the end."""
    depth = best = 0
    balanced = True
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "'":
            i += 1
            while i < n:
                if text[i] == "'":
                    if i + 1 < n and text[i + 1] == "'":
                        i += 2
                        continue
                    break
                i += 1
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            i = n if end < 0 else end + 1
        elif c == "(":
            depth += 1
            best = max(best, depth)
        elif c == ")":
            balanced &= depth > 0
            depth = max(depth - 1, 0)
        elif c == ";":
            balanced &= depth == 0
        i += 1
    return best, balanced and depth == 0


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(["(", ")", "'", "''", "/*", "*/", "*", "/", ";", "a", " ", "\n", "((", "))", "();"]),
                max_size=80))
def test_scan_matches_a_character_by_character_reference(tmp_path_factory, pieces):
    text = "".join(pieces)
    path = tmp_path_factory.mktemp("scan") / "t.step"
    path.write_bytes(text.encode())
    depth, balanced = _reference_scan(text)
    if balanced:
        assert _stepscan.scan_step(path).depth == depth
    else:
        with pytest.raises(FileFormatError, match="unbalanced parentheses"):
            _stepscan.scan_step(path)


def test_parentheses_in_strings_and_comments_do_not_count(tmp_path):
    deep = "(" * 5000
    cases = {
        "string": f"#1=PRODUCT('{deep}','it''s {deep}',(1.));\n",
        "comment": f"/* {deep} 'quote in a comment */\n#1=PRODUCT('a',(1.));\n",
        "comment in string": f"#1=PRODUCT('/* {deep}',(1.));\n",
    }
    for name, body in cases.items():
        path = tmp_path / f"{name}.step"
        path.write_text(STEP_HEAD + body + STEP_TAIL)
        assert _stepscan.scan_step(path).depth == 2, name
    # a quote in a comment must not hide nesting after the comment; a statement left open is refused
    path = tmp_path / "open.step"
    path.write_text(STEP_HEAD + "#1=A((1.);\n" + STEP_TAIL)
    with pytest.raises(FileFormatError, match=r"a '\(' is not closed in the statement ending at line 8"):
        _stepscan.scan_step(path)
    path = tmp_path / "hidden.step"
    path.write_text(STEP_HEAD + "/* ' */\n#1=A(" + "(" * 300 + ")" * 300 + ");\n" + STEP_TAIL)
    with pytest.raises(FileFormatError, match="nest 301 levels"):
        _stepscan.scan_step(path)


def test_step_size_and_entities_are_checked_against_the_budget(tmp_path):
    path = tmp_path / "many.step"
    path.write_text(STEP_HEAD + "".join(f"#{i}=CARTESIAN_POINT('',(0.,0.,0.));\n" for i in range(1, 2001)) + STEP_TAIL)
    scan = _stepscan.scan_step(path)
    # the points and 9 header/section statements; the ';' inside the string '2;1' does not count
    assert scan.entities == 2000 + 9
    with limits.budget(scan.size * _stepscan.BYTES_PER_FILE_BYTE - 1):
        with pytest.raises(ResourceLimitError, match="many.step"):
            _stepscan.scan_step(path)
    with limits.budget(scan.size * _stepscan.BYTES_PER_FILE_BYTE + 1):  # enough for the size, not the entities
        with pytest.raises(ResourceLimitError, match="2009 entities"):
            _stepscan.scan_step(path)


@pytest.mark.skipif(not STEP_FILES, reason="the shared STEP files (../shared/data/step) are not present")
def test_real_step_files_pass_the_scan_and_still_read(capsys):
    """Files from thirteen CAD systems nest at most 4 levels; the scan passes them and OCC reads them
    through `splinekit info`'s reader (the scan is on its path)."""
    pytest.importorskip("OCP")

    total_bytes, total_s = 0, 0.0
    for path in STEP_FILES:
        start = time.perf_counter()
        scan = _stepscan.scan_step(path)
        total_s += time.perf_counter() - start
        total_bytes += scan.size
        assert 3 <= scan.depth <= 4 < _stepscan.MAX_NESTING, path
        assert not read_step_shape(path).IsNull()
    with capsys.disabled():
        print(f"\nSTEP scan: {len(STEP_FILES)} files, {total_bytes / 2**20:.1f} MiB in {total_s * 1e3:.0f} ms "
              f"({total_s * 1e3 / (total_bytes / 2**20):.1f} ms/MiB)")
    assert total_s < 5.0


def test_step_scan_is_linear_on_a_large_file(tmp_path):
    """32 MiB of entities with strings: time per MiB within a factor of 3 of a 4 MiB file's."""
    entity = "#%d=PRODUCT('name (1) #7','it''s',(1.,(2.,3.)),#1);\n"
    times = {}
    for mib in (4, 32):
        path = tmp_path / f"big{mib}.step"
        count = mib * 2**20 // len(entity % 10**5)
        path.write_text(STEP_HEAD + "".join(entity % i for i in range(1, count + 1)) + STEP_TAIL)
        start = time.perf_counter()
        scan = _stepscan.scan_step(path)
        times[mib] = (time.perf_counter() - start) / mib
        assert scan.depth == 3 and scan.entities == count + 9
    assert times[32] < 3 * times[4] + 0.01


# -- 3MF ---------------------------------------------------------------------------------------
def _transform_text(M) -> str:
    """3MF's transform attribute of a 4 x 4 row-vector affine matrix."""
    return " ".join(repr(float(v)) for v in np.asarray(M)[:, :3].ravel())


def _affine(rng) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3] = rng.standard_normal((3, 3))
    M[3, :3] = rng.standard_normal(3) * 10
    return M


def test_3mf_xml_is_parsed_in_linear_time(tmp_path):
    """200 KB of unclosed <object tags took 19-22 s with the regular expressions; now milliseconds."""
    head = f'<?xml version="1.0"?><model xmlns="{CORE_NS}"><resources>'.encode()
    for body in (b"<object " * 25_600, b"".join(b'<object id="%d">' % i for i in range(14_000))):
        path = write_3mf(tmp_path / "slow.3mf", head + body)
        start = time.perf_counter()
        with pytest.raises(FileFormatError, match=r"slow\.3mf.*(not well-formed|no element found)"):
            exporters.import_3mf(path)
        assert time.perf_counter() - start < 2.0


def test_3mf_zip_bomb_is_refused_before_it_is_inflated(tmp_path):
    """A model part that inflates to 256 MiB (from a few hundred KB) is refused from its declared
    size; the reader's memory stays far below it."""
    head = model_xml(mesh_object(1, TETRA_V, TETRA_T)).encode()
    chunks = [head[:-len(b"</model>")]] + [b" " * 2**20] * 256 + [b"</model>"]
    path = write_3mf(tmp_path / "bomb.3mf", chunks)
    assert os.path.getsize(path) < 2**20
    with _allocation_peak() as peak, limits.budget("128M"), pytest.raises(ResourceLimitError, match=r"bomb\.3mf"):
        exporters.import_3mf(path)
    assert peak[0] < 64


def test_3mf_member_larger_than_its_header_says_is_refused(tmp_path):
    """A zip whose headers understate the model part's size: reading stops at the declared size."""
    model = model_xml(mesh_object(1, TETRA_V, TETRA_T)).encode() + b" " * 100_000
    path = write_3mf(tmp_path / "liar.3mf", model)
    raw = bytearray(path.read_bytes())
    true = struct.pack("<I", len(model))
    for at in [m.start() for m in re.finditer(re.escape(true), bytes(raw))]:  # local and central headers
        raw[at:at + 4] = struct.pack("<I", 1000)
    path.write_bytes(bytes(raw))
    with pytest.raises(FileFormatError, match=r"liar\.3mf"):
        exporters.import_3mf(path)


def test_3mf_build_instancing_is_estimated_before_expanding(tmp_path):
    """3,000 build items of one 1,000-vertex object (a 40 KB file) expand to 3M vertices: refused
    under a 64 MiB budget before any copy is made."""
    rng = np.random.default_rng(0)
    V = rng.standard_normal((1000, 3))
    T = np.stack([np.zeros(998, int), np.arange(1, 999), np.arange(2, 1000)], axis=1)
    path = write_3mf(tmp_path / "items.3mf", model_xml(mesh_object(1, V, T), '<item objectid="1"/>' * 3000))
    with _allocation_peak() as peak, limits.budget("64M"), pytest.raises(ResourceLimitError, match=r"3000000 vertices.*items\.3mf|items\.3mf.*3000000 vertices"):
        exporters.import_3mf(path)
    assert peak[0] < 48


def test_3mf_component_bomb_is_refused(tmp_path):
    """Twelve levels of ten components each: 10**12 copies of a tetrahedron from a 2 KB file."""
    resources = mesh_object(1, TETRA_V, TETRA_T)
    for level in range(2, 14):
        resources += f'<object id="{level}"><components>' + f'<component objectid="{level - 1}"/>' * 10 + "</components></object>"
    path = write_3mf(tmp_path / "nest.3mf", model_xml(resources, '<item objectid="13"/>'))
    with pytest.raises(ResourceLimitError, match=r"4000000000000 vertices"):
        exporters.import_3mf(path)
    cyc = model_xml(mesh_object(1, TETRA_V, TETRA_T) + '<object id="2"><components><component objectid="3"/></components></object>'
                    '<object id="3"><components><component objectid="2"/></components></object>', '<item objectid="2"/>')
    with pytest.raises(FileFormatError, match="contains itself"):
        exporters.import_3mf(write_3mf(tmp_path / "cycle.3mf", cyc))


def test_3mf_components_are_placed_like_trimesh_places_them(tmp_path):
    """An object of two placed copies of a tetrahedron, itself placed by a build item: the same
    vertices as the transforms applied point by point, and as trimesh's 3MF loader finds."""
    rng = np.random.default_rng(1)
    A, B, item = _affine(rng), _affine(rng), _affine(rng)
    resources = (mesh_object(1, TETRA_V, TETRA_T)
                 + f'<object id="2"><components><component objectid="1" transform="{_transform_text(A)}"/>'
                   f'<component objectid="1" transform="{_transform_text(B)}"/></components></object>')
    path = write_3mf(tmp_path / "comp.3mf", model_xml(resources, f'<item objectid="2" transform="{_transform_text(item)}"/>'))
    mesh = exporters.import_3mf(path)
    expected = [[*(np.array([*p, 1.0]) @ C @ item)[:3]] for C in (A, B) for p in TETRA_V.tolist()]
    np.testing.assert_allclose(mesh.vertices, expected, rtol=1e-12, atol=1e-12)
    assert mesh.n_faces == 8
    import trimesh  # the test extra installs it: no skip
    import lxml  # noqa: F401  (trimesh's 3MF loader needs it)
    other = trimesh.load(str(path), force="mesh")
    np.testing.assert_allclose(np.sort(other.vertices, axis=0), np.sort(mesh.vertices, axis=0), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("resources, message", [
    (f'<mesh></mesh>{mesh_object(1, TETRA_V, TETRA_T)}', r"a <mesh> outside an <object>"),
    (f'<components/>{mesh_object(1, TETRA_V, TETRA_T)}', r"a <components> outside an <object>"),
    ('<object id="1"><mesh></mesh><components/></object>', r"object '1' has more than one <mesh> or <components>"),
    ('<object id="1"><components/><mesh></mesh></object>', r"object '1' has more than one <mesh> or <components>"),
    ('<object id="1"><mesh></mesh><mesh></mesh></object>', r"object '1' has more than one <mesh> or <components>"),
])
def test_3mf_misplaced_mesh_or_components_is_refused(tmp_path, resources, message):
    """An object holds one <mesh> or one <components>, and only an object holds either."""
    path = write_3mf(tmp_path / "odd.3mf", model_xml(resources, '<item objectid="1"/>'))
    with pytest.raises(FileFormatError, match=r"odd\.3mf.*" + message + r" at line 1"):
        exporters.import_3mf(path)

def test_3mf_transform_that_overflows_is_refused(tmp_path):
    big = "1e300 0 0 0 1e300 0 0 0 1e300 0 0 0"
    path = write_3mf(tmp_path / "inf.3mf", model_xml(mesh_object(1, TETRA_V * 1e10, TETRA_T), f'<item objectid="1" transform="{big}"/>'))
    with pytest.raises(FileFormatError, match=r"inf\.3mf.*beyond the float64 range"):
        exporters.import_3mf(path)


def test_3mf_dtd_and_entities_are_refused(tmp_path):
    laughs = ('<?xml version="1.0"?><!DOCTYPE model [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
              '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">]>'
              f'<model xmlns="{CORE_NS}"><metadata name="x">&c;</metadata><resources>{mesh_object(1, TETRA_V, TETRA_T)}'
              '</resources></model>')
    with pytest.raises(FileFormatError, match=r"laughs\.3mf.*DOCTYPE"):
        exporters.import_3mf(write_3mf(tmp_path / "laughs.3mf", laughs))
    external = f'<?xml version="1.0"?><model xmlns="{CORE_NS}"><metadata>&ext;</metadata></model>'
    with pytest.raises(FileFormatError, match="undefined entity"):
        exporters.import_3mf(write_3mf(tmp_path / "ext.3mf", external))


def test_3mf_broken_packages_raise_only_file_format_errors(tmp_path):
    """Damage that leaked zlib.error, RuntimeError, NotImplementedError, UnicodeDecodeError or
    AttributeError from the zip and regex reader."""
    good = tmp_path / "good.3mf"
    exporters.export_3mf(good, primitives.box())
    raw = good.read_bytes()
    cases = {}
    # a corrupt deflate stream: flip bytes in the middle of the model's compressed data
    at = raw.find(b"3D/3dmodel.model") + 40
    cases["zlib"] = raw[:at] + bytes(b ^ 0x5A for b in raw[at:at + 64]) + raw[at + 64:]
    # an encrypted member (flag bit 0 set in the local and central headers)
    enc = bytearray(raw)
    for m in re.finditer(rb"PK\x03\x04|PK\x01\x02", raw):
        flag_at = m.start() + (6 if raw[m.start() + 2] == 3 else 8)
        enc[flag_at] |= 1
    cases["encrypted"] = bytes(enc)
    # an unknown compression method (99)
    odd = bytearray(raw)
    for m in re.finditer(rb"PK\x03\x04|PK\x01\x02", raw):
        method_at = m.start() + (8 if raw[m.start() + 2] == 3 else 10)
        odd[method_at:method_at + 2] = struct.pack("<H", 99)
    cases["method"] = bytes(odd)
    for name, content in cases.items():
        path = tmp_path / f"{name}.3mf"
        path.write_bytes(content)
        with pytest.raises(FileFormatError, match=re.escape(path.name)):
            exporters.import_3mf(path)
    # a relationship target that is not UTF-8 / missing
    bad_rels = RELS.replace('Target="/3D/3dmodel.model" ', "").encode()
    with pytest.raises(FileFormatError, match="no Target"):
        exporters.import_3mf(write_3mf(tmp_path / "rels.3mf", model_xml(mesh_object(1, TETRA_V, TETRA_T)), rels=bad_rels))
    latin = RELS.replace("/3D/3dmodel.model", "/3D/\xe9.model").encode("latin-1")
    with pytest.raises(FileFormatError, match=r"latin\.3mf"):
        exporters.import_3mf(write_3mf(tmp_path / "latin.3mf", model_xml(mesh_object(1, TETRA_V, TETRA_T)), rels=latin))


# -- glTF binary -------------------------------------------------------------------------------
def test_gltf_json_of_the_wrong_types_raises_file_format_errors(tmp_path):
    """Each of these leaked AttributeError, TypeError, OverflowError or RecursionError, or read a
    Python negative index as a valid one."""
    doc, binary = tetra_gltf([{"mesh": 0}], [0])
    exporters.import_glb(write_bytes(tmp_path / "ok.glb", glb(doc, binary)))  # the base document reads

    def variant(change):
        d = json.loads(json.dumps(doc))
        change(d)
        return d

    cases = {
        "list": [doc],
        "nodes": variant(lambda d: d.update(nodes={"0": {"mesh": 0}})),
        "node": variant(lambda d: d.update(nodes=[5])),
        "scene": variant(lambda d: d["scenes"].__setitem__(0, "all")),
        "children": variant(lambda d: d["nodes"][0].update(children=[-1])),
        "negmesh": variant(lambda d: d["nodes"][0].update(mesh=-1)),
        "boolmesh": variant(lambda d: d["nodes"][0].update(mesh=True)),
        "prims": variant(lambda d: d["meshes"][0].update(primitives={"a": 1})),
        "attrs": variant(lambda d: d["meshes"][0]["primitives"][0].update(attributes=[0])),
        "count": variant(lambda d: d["accessors"][0].update(count=1e400)),
        "strcount": variant(lambda d: d["accessors"][0].update(count="4")),
        "stride": variant(lambda d: d["bufferViews"][0].update(byteStride=-12)),
        "matrix": variant(lambda d: d["nodes"][0].update(matrix=[[1, 0, 0, 0]] * 4)),
        "nanscale": variant(lambda d: d["nodes"][0].update(scale=[1, float("nan"), 1])),
        "floatidx": variant(lambda d: d["accessors"][1].update(componentType=5126)),
        "ext": variant(lambda d: d.update(extensionsRequired="KHR_draco_mesh_compression")),
    }
    for name, bad in cases.items():
        path = write_bytes(tmp_path / f"{name}.glb", glb(bad, binary))
        with pytest.raises(FileFormatError, match=re.escape(path.name)):
            exporters.import_glb(path)
    deep = write_bytes(tmp_path / "deep.glb", glb(b"[" * 100_000 + b"]" * 100_000))
    with pytest.raises(FileFormatError, match=r"deep\.glb.*nests too deeply"):
        exporters.import_glb(deep)


def test_gltf_node_graph_must_be_trees(tmp_path):
    """A node listed twice as a child doubles the mesh per level: 40 levels gave 2**40 copies
    from a 2 KB file. Such graphs (and cycles) are refused; glTF requires trees."""
    nodes = [{"children": [i + 1, i + 1]} for i in range(40)] + [{"mesh": 0}]
    doc, binary = tetra_gltf(nodes, [0])
    with pytest.raises(FileFormatError, match=r"dag\.glb.*nodes\[1\] is a child of nodes\[0\] and nodes\[0\]"):
        exporters.import_glb(write_bytes(tmp_path / "dag.glb", glb(doc, binary)))
    doc, binary = tetra_gltf([{"mesh": 0, "children": [1]}, {"children": [0]}], [0])
    with pytest.raises(FileFormatError, match=r"cycle\.glb.*reached twice"):
        exporters.import_glb(write_bytes(tmp_path / "cycle.glb", glb(doc, binary)))


def test_gltf_instancing_is_estimated_before_expanding(tmp_path):
    """3,000 nodes placing one 1,000-point mesh (a 100 KB file) expand to 3M vertices: refused
    under a 64 MiB budget before any copy; a tree of placed copies reads like trimesh reads it."""
    nodes = [{"mesh": 0, "translation": [0, 0, float(i)]} for i in range(3000)]
    doc, binary = tetra_gltf(nodes, list(range(3000)), n_points=1000)
    path = write_bytes(tmp_path / "many.glb", glb(doc, binary))
    with _allocation_peak() as peak, limits.budget("64M"), pytest.raises(ResourceLimitError, match=r"3000000 vertices"):
        exporters.import_glb(path)
    assert peak[0] < 48
    # a small tree: a parent that scales and two translated children
    nodes = [{"scale": [2, 2, 2], "children": [1, 2]}, {"mesh": 0, "translation": [10, 0, 0]},
             {"mesh": 0, "rotation": [0, 0, 0.6, 0.8]}]
    doc, binary = tetra_gltf(nodes, [0])
    path = write_bytes(tmp_path / "tree.glb", glb(doc, binary))
    mesh = exporters.import_glb(path)
    assert len(mesh.vertices) == 8 and mesh.n_faces == 4
    import trimesh  # the test extra installs it: no skip
    other = trimesh.load(str(path), force="mesh", process=False)
    np.testing.assert_allclose(np.sort(mesh.vertices, axis=0), np.sort(other.vertices, axis=0), atol=1e-6)


# -- PLY, OBJ, STL ------------------------------------------------------------------------------
@pytest.mark.parametrize("binary", [True, False])
def test_ply_header_ends_at_the_end_header_line_not_at_a_comment(tmp_path, binary):
    """A comment mentioning end_header cut the header there: the body was read from the wrong
    offset (silent garbage in binary files)."""
    mesh = primitives.box()
    path = tmp_path / "m.ply"
    exporters.export_ply(path, mesh, binary=binary)
    raw = path.read_bytes()
    crafted = raw.replace(b"end_header\n", b"comment the line after this one is end_header\nend_header\n", 1)
    crafted = crafted.replace(b"element vertex", b"comment end_header marks the end of the header\nelement vertex", 1)
    path.write_bytes(crafted)
    got = exporters.import_ply(path)
    np.testing.assert_array_equal(got.vertices, mesh.vertices)
    np.testing.assert_array_equal(got.face_indices, mesh.face_indices)


@pytest.mark.parametrize("ending", [b"\r", b"\r\n", b"\n", b"mixed"])
def test_obj_accepts_every_line_ending(tmp_path, ending):
    """CR-only files (classic Mac OS) read as one vertex and no faces, silently."""
    mesh = primitives.box()
    path = tmp_path / "m.obj"
    exporters.export_obj(path, mesh)
    lines = path.read_bytes().split(b"\n")
    if ending == b"mixed":
        text = b"".join(line + (b"\r", b"\r\n", b"\n")[i % 3] for i, line in enumerate(lines))
    else:
        text = ending.join(lines)
    text = text.replace(b"f 1//1", b"f \\" + (b"\r" if ending == b"\r" else b"\n") + b"1//1", 1)  # a continued line
    path.write_bytes(text)
    got = exporters.import_obj(path)
    np.testing.assert_array_equal(got.vertices, mesh.vertices)
    np.testing.assert_array_equal(got.face_indices, mesh.face_indices)
    # error messages count lines the same way with any ending
    path.write_bytes(ending.replace(b"mixed", b"\r").join([b"v 0 0 0", b"v 1 0 0", b"v 0 1", b"f 1 2 3"]))
    with pytest.raises(FileFormatError, match=r"vertex 2 \(line 3\)"):
        exporters.import_obj(path)


def test_step_with_an_undefined_reference_or_unbalanced_statement_is_refused(tmp_path):
    """A reference to an entity the file does not define, or a statement with a surplus ')': OCC
    reports the syntax error, then import_step crashed (segmentation fault) or hung. Found by the
    fuzz suite (an entity renumbered #-177; a deleted "'',2,(")."""
    pytest.importorskip("OCP")
    from splinekit import BSplineSurface

    net = np.stack(np.meshgrid(np.linspace(0, 2, 3), np.linspace(0, 1, 3), indexing="ij"), axis=-1)
    net = np.concatenate([net, net[..., :1] * net[..., 1:]], axis=-1)
    good = tmp_path / "good.step"
    exporters.export_step(good, [BSplineSurface(2, 2, [0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1], net)])
    text = good.read_text()
    vector = re.search(r"#(\d+) = VECTOR", text)
    bad = tmp_path / "bad.step"
    bad.write_text(text.replace(vector.group(0), "#177 = VECTOR"))  # renumbered: its users refer to nothing
    code = ("import sys\nfrom OCP.STEPControl import STEPControl_Reader\nr = STEPControl_Reader()\n"
            "r.ReadFile(sys.argv[1])\nr.TransferRoots()\nprint('alive')")
    occ = _run(code, bad)  # what the scan protects against (a crash today; alive if OCC gets fixed)
    done = _run("import sys, exporters\ntry:\n    exporters.import_step(sys.argv[1])\n"
                "except exporters.step.FileFormatError as exc:\n    print('refused:', exc)", bad)
    assert done.returncode == 0, f"import_step crashed (status {done.returncode}); bare OCC: {occ.returncode}"
    assert f"entity #{vector.group(1)} is referenced but not defined" in done.stdout
    unbalanced = tmp_path / "unbalanced.step"  # a statement that closes one list too many
    unbalanced.write_text(re.sub(r"B_SPLINE_CURVE_WITH_KNOTS\('',2,\(", "B_SPLINE_CURVE_WITH_KNOTS(", text, count=1))
    done = _run("import sys, exporters\ntry:\n    exporters.import_step(sys.argv[1])\n"
                "except exporters.step.FileFormatError as exc:\n    print('refused:', exc)", unbalanced)
    assert done.returncode == 0, f"import_step crashed (status {done.returncode})"
    assert "unbalanced parentheses: a ')' closes nothing" in done.stdout
    minus = tmp_path / "minus.step"  # '#-0': import_step hung (over a minute)
    minus.write_text(re.sub(r"(LINE\('',#\d+,)#\d+", r"\1#-0", text, count=1))
    assert "#-0" in minus.read_text()
    with pytest.raises(FileFormatError, match="a '#' not followed by an entity number at line"):
        _stepscan.scan_step(minus)
    twice = tmp_path / "twice.step"
    twice.write_text(text.replace(vector.group(0), "#12 = VECTOR"))
    with pytest.raises(FileFormatError, match="entity #12 is defined 2 times"):
        _stepscan.scan_step(twice)
    quoted = tmp_path / "quoted.step"  # '#999' inside a string is text, not a reference
    quoted.write_text(text.replace("PRODUCT('", "PRODUCT('part #999 ", 1))
    assert "'part #999 " in quoted.read_text()
    assert _stepscan.scan_step(quoted).entities == _stepscan.scan_step(good).entities


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".3mf", ".glb"])
def test_mesh_files_are_checked_against_the_budget_before_reading(tmp_path, suffix):
    path = tmp_path / ("m" + suffix)
    exporters.export_mesh(path, primitives.box())
    size = os.path.getsize(path)
    with limits.budget(size * exporters._meshio.READ_BYTES_FACTOR - 1), pytest.raises(ResourceLimitError, match=path.name):
        exporters.import_mesh(path)
    with limits.budget(size * exporters._meshio.READ_BYTES_FACTOR * 100):
        assert exporters.import_mesh(path).n_faces >= 6


def test_readers_refuse_what_is_not_a_regular_file(tmp_path):
    """A FIFO blocked the readers forever (open waits for a writer); /dev/zero never ends."""
    fifo = tmp_path / "pipe.stl"
    os.mkfifo(fifo)
    for path in (fifo, "/dev/zero", tmp_path):
        with pytest.raises(FileFormatError, match="not a regular file|is a directory|Is a directory"):
            exporters.import_stl(path)
    with pytest.raises(FileFormatError, match="not a regular file"):
        _stepscan.scan_step(fifo)


def test_ascii_ply_list_length_that_is_not_finite_is_refused(tmp_path):
    """An ASCII list length of inf leaked OverflowError (found by the long fuzz run)."""
    head = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n")
    for length in ("inf", "nan", "-inf"):
        path = write_bytes(tmp_path / "f.ply", (head + f"{length} 0 1 2\n").encode())
        with pytest.raises(FileFormatError, match="invalid list length"):
            exporters.import_ply(path)


def test_obj_vertex_with_other_whitespace_is_refused_with_its_line(tmp_path):
    """A form feed between coordinates leaked StopIteration (found by the long fuzz run)."""
    path = write_bytes(tmp_path / "ff.obj", b"v 0 0 0\nv 1\x0c0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(FileFormatError, match=r"vertex 1 \(line 2\) has fewer than 3 coordinates"):
        exporters.import_obj(path)


def test_step_bytes_outside_the_step_alphabet_are_refused(tmp_path):
    """Two non-ASCII bytes between list items crashed import_step (segmentation fault; found by
    the long fuzz run); inside strings such bytes stay allowed (CAD systems write raw UTF-8 names)."""
    body = "#1=CARTESIAN_POINT('pi\u00e8ce \u00e9',(0.,0.,0.));\n"
    ok = write_bytes(tmp_path / "ok.step", (STEP_HEAD + body + STEP_TAIL).encode("utf-8"))
    assert _stepscan.scan_step(ok).depth == 2
    bad = write_bytes(tmp_path / "bad.step", (STEP_HEAD + body + STEP_TAIL).encode().replace(b"(0.,", b"(E\xd5E\xd5 0.,"))
    with pytest.raises(FileFormatError, match=r"byte 0xD5 at line 8 .* only printable ASCII"):
        _stepscan.scan_step(bad)


def test_step_syntax_errors_reported_by_occ_stop_the_import(tmp_path):
    """A keyword split by spaces ("CARTES IAN_POINT") or an integer beyond 32 bits crashed
    import_step (found by the long fuzz run): the scan refuses the integer, and OCC's own syntax
    errors stop the import before the transfer."""
    pytest.importorskip("OCP")
    from splinekit import BSplineSurface

    net = np.stack(np.meshgrid(np.linspace(0, 2, 3), np.linspace(0, 1, 3), indexing="ij"), axis=-1)
    net = np.concatenate([net, net[..., :1] * net[..., 1:]], axis=-1)
    good = tmp_path / "good.step"
    exporters.export_step(good, [BSplineSurface(2, 2, [0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1], net)])
    text = good.read_text()
    split = write_bytes(tmp_path / "split.step", re.sub(r"(#\d+ = )CARTESIAN_POINT(\('',\(2\.)", r"\1CARTES    IAN_POINT\2",
                                                         text, count=1).encode())
    assert b"CARTES    IAN_POINT" in split.read_bytes()
    code = ("import sys, exporters\ntry:\n    exporters.import_step(sys.argv[1])\n"
            "except exporters.step.FileFormatError as exc:\n    print('refused:', exc)")
    done = _run(code, split)
    assert done.returncode == 0, f"import_step crashed (status {done.returncode})"
    assert "syntax error" in done.stdout
    big = write_bytes(tmp_path / "big.step", text.replace("(3,3)", "(4294967296,3)", 1).encode())
    with pytest.raises(FileFormatError, match="integer 4294967296 at line .* beyond 32 bits"):
        _stepscan.scan_step(big)
