"""Run one task per variant on a Dask cluster and gather the results table.

The task is any picklable callable ``task(params) -> dict`` of scalar figures (measures, output
paths). It runs on a worker; only its dict travels back. A task that raises is recorded as a
``failed`` row with its message, and the batch goes on; so does a variant whose worker died.
"""

from __future__ import annotations

import functools
import os
import time
import uuid

from .._atomic import checked_path
from .._progress import progress
from ..errors import ParameterError
from . import results
from .cluster import CONNECT_TIMEOUT, cluster_client, distributed_module

__all__ = ["run", "summary_text"]


def _guarded(task, params: dict) -> dict:
    """``task(params)`` with ``status`` ``ok``; an exception becomes ``status`` ``failed`` and its
    message (runs on the worker)."""
    try:
        figures = dict(task(dict(params)))
    except Exception as exc:  # the batch goes on: any failure of one variant is that variant's row
        return {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
    figures.setdefault("status", "ok")
    figures.setdefault("error", None)
    return figures


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


def run(task, rows: list, *, keys: list, out, recipe: str = "", leading=None, client=None, scheduler=None,
        n_workers=None, force: bool = False, timeout: float = CONNECT_TIMEOUT, label: str = "sweep"):
    """Run ``task`` on every row of ``rows`` and return the results as a pandas DataFrame.

    Parameters
    ----------
    task : callable
        ``task(params: dict) -> dict`` of scalar columns; picklable (a module-level function or
        an instance of a module-level class), as it is sent to the workers.
    rows : list of dict
        The parameters of each variant (:func:`splinekit.batch.variants`).
    keys : list of str
        One key per row (:func:`splinekit.batch.variant_key`): a row whose key and ``recipe``
        are found finished in ``out``'s earlier results is not run again but copied from there
        with status ``skipped``, unless ``force``.
    out : path
        Folder of ``results.parquet`` and ``results.csv`` (created if missing).
    leading : dict, optional
        Columns of the same value in every row, put first (the model's name).
    client, scheduler, n_workers, timeout
        The cluster, see :func:`splinekit.batch.cluster_client`.

    The DataFrame's ``attrs["summary"]`` holds the counts per status, the variants and the
    wall time in seconds (``seconds``).
    """
    if not callable(task):
        raise ParameterError(f"task must be callable, got {type(task).__name__}")
    if len(keys) != len(rows):
        raise ParameterError(f"{len(keys)} keys for {len(rows)} rows: one key per row is needed")
    out = checked_path(out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise ParameterError(f"output folder {out!r} exists and is not a folder")
    results.pandas_module()  # a missing extra is reported before any work
    start = time.perf_counter()
    earlier = {} if force else results.previous_rows(out)
    names = list(dict.fromkeys(name for row in rows for name in row))
    table_rows: list = [None] * len(rows)
    todo = []
    for i, (key, params) in enumerate(zip(keys, rows)):
        old = earlier.get(key)
        if old is not None and old.get("recipe") == recipe:
            table_rows[i] = {**old, "status": "skipped", "error": None}
        else:
            todo.append(i)
    if todo:
        _compute(task, rows, keys, todo, table_rows, recipe, label,
                 dict(client=client, scheduler=scheduler, n_workers=n_workers, timeout=timeout))
    frame = results.table(table_rows, names, leading or {})
    counts = frame["status"].value_counts()
    frame.attrs["summary"] = {"variants": len(rows), **{s: int(counts.get(s, 0)) for s in results.STATUSES},
                              "seconds": time.perf_counter() - start}
    os.makedirs(out, exist_ok=True)
    results.write(frame, out)
    return frame


def _compute(task, rows, keys, todo, table_rows, recipe, label, cluster) -> None:
    """Submit the rows ``todo`` and fill their entries of ``table_rows`` as they finish."""
    distributed = distributed_module()
    token = uuid.uuid4().hex[:8]  # task keys unique on a scheduler shared with other batches
    with cluster_client(**cluster) as client:
        futures = client.map(functools.partial(_guarded, task), [rows[i] for i in todo],
                             key=[f"{label}-{keys[i]}-{token}" for i in todo], pure=False)
        where = {f.key: i for f, i in zip(futures, todo)}
        try:
            with progress(len(todo), label) as bar:
                # in batches: one gather per group of finished tasks instead of a round trip each
                for batch in distributed.as_completed(futures).batches():
                    finished = [f for f in batch if f.status == "finished"]
                    figures = dict(zip((f.key for f in finished), client.gather(finished)))
                    for future in batch:
                        i = where[future.key]
                        if future.key not in figures:  # the worker died (KilledWorker), or the result was lost
                            figures[future.key] = {"status": "failed", "error": _error_text(future.exception())}
                        table_rows[i] = {"key": keys[i], **rows[i], **figures[future.key], "recipe": recipe}
                        future.release()  # the scheduler forgets it: memory stays flat over long batches
                        bar.advance()
        except BaseException:
            client.cancel(futures)
            raise


def summary_text(summary: dict) -> str:
    """``"12 variants: 10 ok, 1 failed, 1 skipped in 3.2 s"`` from ``attrs["summary"]``."""
    parts = ", ".join(f"{summary.get(s, 0)} {s}" for s in results.STATUSES)
    return f"{summary['variants']} variants: {parts} in {summary['seconds']:.1f} s"
