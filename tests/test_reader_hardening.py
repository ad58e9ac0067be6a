"""Crafted files that crashed, hung, exhausted memory or were misread by the readers.

Each test here failed on the readers before they were hardened: a STEP file nested 80,000 levels
deep (a segmentation fault inside OpenCascade, reproduced in a subprocess), 3MF XML that regular
expressions parse in quadratic time, a zip bomb, 3MF and glTF instancing bombs, a 3MF transform
that overflows, glTF JSON of the wrong types, a PLY comment holding ``end_header``, an OBJ file
with CR-only line endings. The STEP scan's nesting depth is checked against an independent,
character-by-character reference on generated text.
"""

from __future__ import annotations

import glob
import io
import json
import os
import re
import resource
import struct
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import exporters
from exporters import _stepscan
from splinekit import limits
from splinekit.errors import FileFormatError, ResourceLimitError, SplineKitError
from splinekit.mesh import primitives

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STEP_DATA = os.path.join(REPO, "..", "shared", "data", "step")
STEP_FILES = sorted(f for f in glob.glob(os.path.join(STEP_DATA, "*")) if f.lower().endswith((".stp", ".step")))

STEP_HEAD = (
    "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
    "FILE_NAME('x','2020-01-01T00:00:00',(''),(''),'','','');\n"
    "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n"
)
STEP_TAIL = "ENDSEC;\nEND-ISO-10303-21;\n"


def nested_step(depth: int) -> str:
    """A syntactically valid STEP file whose one point nests its coordinates ``depth`` lists deep."""
    return STEP_HEAD + "#1=CARTESIAN_POINT(''," + "(" * depth + "0." + ")" * depth + ");\n" + STEP_TAIL


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


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


def _reference_depth(text: str) -> int:
    """Deepest parenthesis nesting outside strings and comments, one character at a time
    (an independent reference for the vectorized scan; a surplus ')' counts from zero again)."""
    depth = best = 0
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
            depth = max(depth - 1, 0)
        i += 1
    return best


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(["(", ")", "'", "''", "/*", "*/", "*", "/", ";", "a", " ", "\n", "((", "))"]),
                max_size=80))
def test_scan_depth_matches_a_character_by_character_reference(tmp_path_factory, pieces):
    text = "".join(pieces)
    path = tmp_path_factory.mktemp("scan") / "t.step"
    path.write_bytes(text.encode())
    assert _stepscan.scan_step(path).depth == _reference_depth(text)


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
    # a quote in a comment must not hide nesting after the comment
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
    from splinekit.cli import read_step_shape

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
    entity = "#1=PRODUCT('name (1)','it''s',(1.,(2.,3.)),$);\n"
    times = {}
    for mib in (4, 32):
        path = tmp_path / f"big{mib}.step"
        path.write_text(STEP_HEAD + entity * (mib * 2**20 // len(entity)) + STEP_TAIL)
        start = time.perf_counter()
        scan = _stepscan.scan_step(path)
        times[mib] = (time.perf_counter() - start) / mib
        assert scan.depth == 3
    assert times[32] < 3 * times[4] + 0.01
