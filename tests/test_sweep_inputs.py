"""Parameter sweeps: the variants of a grid, list or table, the ``--grid`` syntax, the dispatch of
``splinekit.sweep``, and every bad input of the issue refused with a SplineKitError (one CLI line)
before any results file is written. No cluster runs here but for the unreachable scheduler."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest
from hypothesis import given
from hypothesis import strategies as st

import splinekit as sk
from splinekit.cli import main
from splinekit.batch import DEFAULT_MAX_VARIANTS, parse_grid, variant_key, variants
from splinekit.construct import sweep as construct_sweep
from splinekit.errors import BackendError, ParameterError, SplineKitError

ROOT = Path(__file__).resolve().parent.parent


def test_a_grid_is_the_full_factorial_last_axis_fastest():
    rows = variants({"a": [1, 2], "b": [10.0, 20.0, 30.0]})
    assert rows == [{"a": a, "b": b} for a in (1, 2) for b in (10.0, 20.0, 30.0)]
    assert variants({"a": 5, "b": np.array([1.5, 2.5])}) == [{"a": 5, "b": 1.5}, {"a": 5, "b": 2.5}]


def test_rows_from_a_list_a_dataframe_and_an_arrow_table_agree():
    rows = [{"height": 100.0, "wall": 2.0}, {"height": 150.0, "wall": 3.0}]
    assert variants(rows) == rows
    assert variants(pd.DataFrame(rows)) == rows
    assert variants(pa.Table.from_pylist(rows)) == rows
    assert all(type(v) is float for r in variants(pd.DataFrame(rows)) for v in r.values())  # not numpy scalars


@given(st.integers(1, 5), st.integers(1, 5), st.integers(1, 4))
def test_grid_count_is_the_product_of_the_axes(na, nb, nc):
    rows = variants({"a": list(range(na)), "b": list(range(nb)), "c": list(range(nc))})
    assert len(rows) == na * nb * nc and len({tuple(r.values()) for r in rows}) == na * nb * nc


def test_parse_grid_range_and_list():
    name, values = parse_grid("height=100:300:9")
    assert name == "height" and values == list(np.linspace(100.0, 300.0, 9)) and values[1] == 125.0
    assert parse_grid(" wall = 2,3,4 ") == ("wall", [2.0, 3.0, 4.0])
    assert parse_grid("x=5:5:1") == ("x", [5.0])
    for bad in ("height", "=1,2", "height=", "h=1:2", "h=1:2:0", "h=1:2:2.5", "h=a,b", "h=1:2:3:4", "h=nan,1", "h=1:inf:3"):
        with pytest.raises(ParameterError, match="--grid"):
            parse_grid(bad)


def test_variant_key_is_exact_and_order_free():
    a = variant_key("vase", "v1", {"height": 100.0, "wall": 2.0})
    assert a == variant_key("vase", "v1", {"wall": 2.0, "height": 100.0})
    assert a != variant_key("vase", "v2", {"height": 100.0, "wall": 2.0})  # another model version
    assert a != variant_key("vase", "v1", {"height": 100.0 + 1e-13, "wall": 2.0})


def test_sweep_dispatches_a_curve_to_the_surface_sweep():
    profile = sk.polyline([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    path = sk.line([0.0, 0.0, 0.0], [0.0, 0.0, 5.0])
    ours, theirs = sk.sweep(profile, path), construct_sweep(profile, path)
    assert type(ours) is type(theirs)
    np.testing.assert_array_equal(ours.control_points, theirs.control_points)
    by_name = sk.sweep(profile=profile, path=path, degree=2)
    np.testing.assert_array_equal(by_name.control_points, construct_sweep(profile, path, degree=2).control_points)
    with pytest.raises(SplineKitError):
        sk.sweep(42, path)  # neither a curve nor a model: construct.sweep's own error


def _bad(tmp_path, *args, **kwargs):
    """Run a sweep expected to fail; check that no results file appeared and return the error."""
    out = tmp_path / "out"
    with pytest.raises(SplineKitError) as info:
        sk.sweep(*args, out=out, **kwargs)
    assert not (out / "results.parquet").exists() and not (out / "results.csv").exists()
    return str(info.value)


def test_bad_inputs_raise_before_any_results_file(tmp_path):
    assert "unknown model 'vasse'" in _bad(tmp_path, "vasse", {"height": [100]})
    assert "has no parameter 'hieght'" in _bad(tmp_path, "vase", {"hieght": [100]})
    message = _bad(tmp_path, "vase", {"height": [100, 9999]})
    assert "parameter 'height' = 9999" in message and "[40, 600]" in message
    assert "empty" in _bad(tmp_path, "vase", {"height": []})
    assert "no parameters" in _bad(tmp_path, "vase", {})
    assert "no rows" in _bad(tmp_path, "vase", [])
    assert "no rows" in _bad(tmp_path, "vase", pd.DataFrame({"height": []}))
    assert "unknown measure 'volumen'" in _bad(tmp_path, "vase", {"height": [100]}, measures=["volumen"])
    assert "unknown format 'stp2'" in _bad(tmp_path, "vase", {"height": [100]}, formats="stl,stp2")
    assert "more than the budget of 3" in _bad(tmp_path, "vase", {"height": [100, 200], "wall": [2, 3]}, max_variants=3)


def test_a_grid_over_the_default_budget_is_refused_without_expanding_it(tmp_path):
    axis = list(np.linspace(40.0, 600.0, 1000))
    start = time.perf_counter()
    message = _bad(tmp_path, "vase", {"height": axis, "radius": axis, "wall": [2.0, 3.0]})
    assert "2,000,000 variants" in message and f"{DEFAULT_MAX_VARIANTS:,}" in message
    assert time.perf_counter() - start < 2.0


def test_an_error_leaves_earlier_results_untouched(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.csv").write_text("earlier\n")
    with pytest.raises(ParameterError):
        sk.sweep("vase", {"height": [1.0]}, out=out)
    assert (out / "results.csv").read_text() == "earlier\n"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_an_error_naming_it_within_seconds(tmp_path):
    address = f"tcp://127.0.0.1:{_free_port()}"  # nobody listens there
    start = time.perf_counter()
    message = _bad(tmp_path, "vase", {"height": [100]}, scheduler=address, timeout=1.0)
    assert address in message and isinstance(BackendError(message), SplineKitError)
    assert time.perf_counter() - start < 15.0  # 1 s of connecting plus distributed's retry back-off
    assert "does not exist" in _bad(tmp_path, "vase", {"height": [100]}, scheduler=str(tmp_path / "none.json"))


def test_cli_bad_inputs_are_one_line_and_status_1(tmp_path, capsys):
    out = tmp_path / "out"
    cases = [
        (["vasse", "--grid", "height=1,2"], "unknown model 'vasse'"),
        (["vase", "--grid", "hieght=100,200"], "no parameter 'hieght'"),
        (["vase", "--grid", "height=100:9000:3"], "parameter 'height' = 4550"),
        (["vase"], "nothing to sweep"),
        (["vase", "--grid", "height=1:2"], "--grid"),
        (["vase", "--grid", "height=100,200", "--grid", "height=300"], "given twice"),
        (["vase", "--grid", "height=100:300:400", "--grid", "wall=2:3:300", "--max-variants", "1000"], "budget of 1,000"),
        (["vase", "--grid", "height=100", "--measure", "volumen"], "unknown measure"),
        (["vase", "--grid", "height=100", "--plot", "volume:a,b,c"], "--plot"),
        (["vase", "--grid", "height=100", "--scheduler", f"tcp://127.0.0.1:{_free_port()}", "--timeout", "1"],
         "cannot reach the Dask scheduler at 'tcp://127.0.0.1:"),
    ]
    for args, expected in cases:
        status = main(["sweep", *args, "-o", str(out)])  # in this process: ten interpreters would take long
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert status == 1 and len(lines) == 1, (args, err)
        assert lines[0].startswith("splinekit: error:") and expected in lines[0], (args, err)
        assert not out.exists() or not any(out.iterdir())


def test_import_splinekit_loads_no_dask_nor_pandas():
    code = ("import sys, splinekit, splinekit.batch; "
            "print(','.join(m for m in ('dask', 'distributed', 'pandas', 'pyarrow') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.stdout.strip() == ""
