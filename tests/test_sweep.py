"""Parameter sweeps on a real Dask cluster: a 2-worker LocalCluster started once for the module,
and a scheduler and a worker started as separate processes.

What is independent of the code under test: the serial ``build_model`` + ``measure`` in this
process (the sweep's figures must equal them bit for bit), the vase's volume by Green's theorem
on its profiles (``Model.checks``, another method than the surface quadrature the sweep uses),
its rim at z = height, and the STL files read back by trimesh.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import distributed
import numpy as np
import pandas as pd
import psutil
import pytest
import trimesh

import splinekit as sk
from models import build_model
from models.measures import MEASURES, measure
from splinekit.batch import cluster_client, run, variant_key

ROOT = Path(__file__).resolve().parent.parent
GRID = {"height": [120.0, 250.0], "radius": [15.0, 40.0], "wall": [4.0]}
"""Four variants; radius 15 with wall 4 is refused by the model (wall over 40 % of the neck
radius): two failed rows beside two built."""


@pytest.fixture(scope="module")
def client():
    """The local cluster a sweep starts without a client (2 worker processes), started once here
    and then passed to the sweeps as a client of the caller's."""
    with cluster_client(n_workers=2) as c:
        assert isinstance(c.cluster, distributed.LocalCluster) and len(c.scheduler_info()["workers"]) == 2
        yield c


@pytest.fixture(scope="module")
def swept(client, tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    frame = sk.sweep("vase", GRID, formats=["stl"], out=out, client=client)
    return out, frame


def _same(a, b) -> bool:
    """Equal bit for bit (NaN equal to NaN); a float column may hold an int measure (NaN in failed rows)."""
    if isinstance(a, float) and math.isnan(a):
        return isinstance(b, float) and math.isnan(b)
    return a == b


def test_measures_equal_a_serial_build_bit_for_bit(swept):
    out, frame = swept
    done = frame[frame["status"] == "ok"]
    assert len(done) == 2
    for _, row in done.iterrows():
        params = {k: row[k] for k in ("height", "radius", "neck", "wall", "base")}
        model = build_model("vase", **params)  # serial, in this process
        expected = measure(model, MEASURES)
        for column, value in expected.items():
            got = row[column]
            got = got.item() if isinstance(got, np.generic) else got
            assert _same(got, value), (column, got, value)
        # independent figures: Green's theorem volume, the rim plane, the file read by trimesh
        reference, tol = model.checks["volume"]
        assert abs(row["volume"] - reference) <= tol
        assert row["checks_ok"] and row["valid"]
        assert abs(row["bbox_max_z"] - params["height"]) <= 1e-9 * params["height"]
        stl = trimesh.load(row["file_stl"], process=False)
        assert len(stl.faces) == row["triangles"]
        assert Path(row["file_stl"]).parent == out / "files"


def test_a_failing_variant_is_recorded_and_the_others_go_on(swept):
    out, frame = swept
    failed = frame[frame["status"] == "failed"]
    assert list(failed["radius"]) == [15.0, 15.0] and list(failed["height"]) == [120.0, 250.0]
    assert failed["error"].str.contains("ParameterError: parameter 'wall'").all()
    assert failed["volume"].isna().all() and failed["file_stl"].isna().all()
    assert (frame.loc[frame["radius"] == 40.0, "status"] == "ok").all()
    assert frame.attrs["summary"] == {**frame.attrs["summary"], "variants": 4, "ok": 2, "failed": 2, "skipped": 0}


def test_results_files_hold_the_returned_table(swept):
    out, frame = swept
    parquet = pd.read_parquet(out / "results.parquet")
    csv = pd.read_csv(out / "results.csv")
    assert list(parquet.columns) == list(frame.columns)
    assert list(parquet["key"]) == list(frame["key"]) == list(csv["key"])
    np.testing.assert_array_equal(parquet["volume"].to_numpy(), frame["volume"].to_numpy())
    assert list(frame.columns[:8]) == ["model", "key", "height", "radius", "neck", "wall", "base", "status"]
    assert not [p for p in os.listdir(out) if p.startswith(".splinekit-")]  # no temporary file left


def test_resume_skips_finished_variants_and_force_rebuilds(swept, client):
    out, first = swept
    again = sk.sweep("vase", GRID, formats=["stl"], out=out, client=client)
    ok = first["status"] == "ok"
    assert (again.loc[ok, "status"] == "skipped").all()
    # copied, not rebuilt: even the build time is the first run's
    np.testing.assert_array_equal(again.loc[ok, "build_time"].to_numpy(), first.loc[ok, "build_time"].to_numpy())
    assert (again.loc[~ok, "status"] == "failed").all()  # failed variants are tried again
    # a new value: only its variants are built
    more = sk.sweep("vase", {**GRID, "height": [120.0, 250.0, 300.0]}, formats=["stl"], out=out,
                    client=client, plot=False)
    assert dict(more["status"].value_counts()) == {"skipped": 2, "ok": 1, "failed": 3}
    # other measures asked of the same variant: rebuilt (the recipe differs)
    forced = sk.sweep("vase", {"height": [120.0], "radius": [40.0], "wall": [4.0]}, measures=["volume"],
                      out=out, client=client, force=True)
    assert list(forced["status"]) == ["ok"]
    assert "area" not in forced.columns


def test_plot_of_a_measure_against_two_parameters(swept):
    out, frame = swept
    # two parameters vary: the volume is drawn against both by default
    assert frame.attrs["plot"] == str(out / "volume.png")
    path = sk.batch.plot_measure(frame, "area", "radius", "height", path=out / "area.png")
    for picture in (frame.attrs["plot"], path):
        data = Path(picture).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 5000


def test_generic_batch_runs_any_picklable_callable(client, tmp_path):
    rows = [{"x": float(x)} for x in range(5)]
    keys = [variant_key("sqrt", "1", r) for r in rows]
    frame = run(_sqrt_or_fail, rows, keys=keys, out=tmp_path, client=client)
    assert list(frame["status"]) == ["ok", "ok", "ok", "failed", "ok"]
    np.testing.assert_array_equal(frame["root"].to_numpy()[[0, 1, 2, 4]], np.sqrt([0.0, 1.0, 2.0, 4.0]))
    assert frame["error"][3] == "ValueError: three is refused"


def test_without_a_client_a_local_cluster_is_started_and_closed(tmp_path):
    rows = [{"x": 1.0}, {"x": 2.0}]
    before = _children()
    frame = run(dict, rows, keys=["a", "b"], out=tmp_path, n_workers=1)  # dict(params) echoes the row
    assert list(frame["status"]) == ["ok", "ok"] and list(frame["x"]) == [1.0, 2.0]
    assert _children() <= before  # the local cluster's worker processes are gone again


def test_local_workers_keep_glibc_adaptive_malloc(client):
    # dask's nanny sets MALLOC_TRIM_THRESHOLD_ for its workers, which freezes glibc's mmap threshold
    # and made each variant 1.8x slower in a worker than in a plain process (bench_sweep)
    envs = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    assert len(envs) == 2 and set(envs.values()) == {None}


def _children() -> set:
    return {p.pid for p in psutil.Process().children(recursive=True) if p.is_running() and p.status() != psutil.STATUS_ZOMBIE}


def _sqrt_or_fail(params):
    if params["x"] == 3.0:
        raise ValueError("three is refused")
    return {"root": math.sqrt(params["x"])}


@pytest.fixture(scope="module")
def separate_cluster(tmp_path_factory):
    """A scheduler and a worker started as their own processes, as on a real cluster."""
    folder = tmp_path_factory.mktemp("cluster")
    scheduler_file = folder / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                               "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                              cwd=folder, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists():
            assert time.monotonic() < deadline and procs[0].poll() is None, "the scheduler did not start"
            time.sleep(0.2)
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file",
                                       str(scheduler_file), "--nworkers", "1", "--nthreads", "1", "--no-dashboard"],
                                      cwd=folder, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        with distributed.Client(scheduler_file=str(scheduler_file), timeout=30) as c:
            c.wait_for_workers(1, timeout=60)
        yield json.loads(scheduler_file.read_text())["address"]
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()


def test_sweep_on_a_separately_started_scheduler_and_worker(separate_cluster, swept, tmp_path):
    address = separate_cluster
    assert address.startswith("tcp://127.0.0.1:")
    frame = sk.sweep("vase", {"height": [120.0, 250.0], "radius": [40.0], "wall": [4.0]}, measures=["volume", "area"],
                     out=tmp_path, scheduler=address)
    assert list(frame["status"]) == ["ok", "ok"]
    _, local = swept
    for _, row in frame.iterrows():
        same = local[(local["height"] == row["height"]) & (local["radius"] == 40.0)]
        assert same["volume"].iloc[0] == row["volume"] and same["area"].iloc[0] == row["area"]
    # the scheduler is left running: a second sweep uses it again
    again = sk.sweep("vase", {"height": [300.0]}, measures=["volume"], out=tmp_path / "again", scheduler=address)
    assert list(again["status"]) == ["ok"]


def test_cli_sweep_on_a_running_scheduler(separate_cluster, tmp_path):
    out = tmp_path / "sweep"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "splinekit.cli", "sweep", "vase", "--grid", "height=100:300:3",
                           "--set", "wall=3", "-o", str(out), "--format", "stl", "--measure", "volume,area",
                           "--scheduler", separate_cluster], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "3 variants: 3 ok, 0 failed, 0 skipped" in done.stdout
    frame = pd.read_parquet(out / "results.parquet")
    assert list(frame["height"]) == [100.0, 200.0, 300.0] and set(frame["wall"]) == {3.0}
    assert (out / "volume.png").is_file() and len(list((out / "files").glob("*.stl"))) == 3
    model = build_model("vase", height=200.0, wall=3.0)
    assert frame["volume"][1] == measure(model, ["volume"])["volume"]
