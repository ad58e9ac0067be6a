"""The benchmarks stay indexed: every ``benchmarks/bench_*.py`` is run by ``check_ratios.py``,
listed in ``benchmarks/README.md`` and has a ``--quick`` version, and the ratio lines the
benchmarks print are the lines ``check_ratios.py`` reads."""

from __future__ import annotations

import contextlib
import io
import re
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"
NAMES = sorted(p.stem[len("bench_"):] for p in BENCH.glob("bench_*.py"))


@pytest.fixture(scope="module")
def helpers():
    sys.path.insert(0, str(BENCH))
    try:
        import _ratios
        import check_ratios

        yield _ratios, check_ratios
    finally:
        sys.path.remove(str(BENCH))


def test_every_benchmark_is_checked_listed_and_has_a_short_version(helpers):
    _, check_ratios = helpers
    readme = (BENCH / "README.md").read_text()
    assert NAMES and sorted(check_ratios.BENCHMARKS) == NAMES
    for name in NAMES:
        assert f"`bench_{name}.py`" in readme, name
        assert "--quick" in (BENCH / f"bench_{name}.py").read_text(), name


@pytest.mark.parametrize("ratio,target", [(2.5, 1.0), (0.125, 1 / 1.2), (float("nan"), 3.0), (1e-5, 0.5)])
def test_ratio_lines_are_read_back(helpers, ratio, target):
    _ratios, _ = helpers
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        _ratios.report("a / b, with: punctuation (x)", ratio, target)
    m = re.match(_ratios.PATTERN, out.getvalue().strip())
    assert m is not None and m["name"] == "a / b, with: punctuation (x)"
    got = float(m["ratio"])
    assert (got != got and ratio != ratio) or got == pytest.approx(ratio, rel=1e-2)
    assert float(m["target"]) == pytest.approx(target, rel=1e-5)
