"""The house keeps its shape: no import circles, imports only downward between the layers of the
design notes, project modules imported at module level (in-function imports are for optional
heavy backends), and no module over about 500 lines. The checks read the source with ``ast``
(tools/import_graph.py); the first tests show on a small made-up package that each check can fail.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _load_tool():
    spec = importlib.util.spec_from_file_location("_import_graph", ROOT / "tools" / "import_graph.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the class is made
    spec.loader.exec_module(module)
    return module


tool = _load_tool()


@pytest.fixture(scope="module")
def graph():
    return tool.build()


def _write(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def test_checker_finds_a_circle_an_upward_import_and_an_inner_import(tmp_path):
    _write(tmp_path, {
        "splinekit/__init__.py": "",
        "splinekit/errors.py": "from .basis import knots\n",  # base -> basis: upward
        "splinekit/basis/__init__.py": "",
        "splinekit/basis/knots.py": "from . import spans\n",
        "splinekit/basis/spans.py": "def f():\n    from . import knots\n",  # circle, via a function
        "splinekit/curves/__init__.py": "",
        "splinekit/curves/line.py": "def g():\n    import numba\n    from ..basis import knots\n",
    })
    g = tool.build(tmp_path, ("splinekit",))
    assert tool.cycles(g) == [["splinekit.basis.knots", "splinekit.basis.spans"]]
    assert ("splinekit.errors", "splinekit.basis.knots") in tool.upward(g)
    inner = {(m, t) for m, t, _ in tool.inner_project_imports(g)}
    assert inner == {("splinekit.basis.spans", "splinekit.basis.knots"),
                     ("splinekit.curves.line", "splinekit.basis.knots")}  # numba is a backend: allowed
    assert tool.long_modules(g, limit=2) == [("splinekit.curves.line", 3)]


def test_every_module_has_a_layer(graph):
    assert [m for m in graph.modules if tool.layer_of(m) < 0] == []


def test_no_import_circles(graph):
    assert tool.cycles(graph) == []


def test_imports_run_down_the_layers(graph):
    assert tool.upward(graph) == []


def test_project_modules_are_imported_at_module_level(graph):
    assert tool.inner_project_imports(graph) == []


def test_no_module_over_about_500_lines(graph):
    assert tool.long_modules(graph) == []
