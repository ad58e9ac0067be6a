"""The results table of a batch: one row per variant, read back to resume, written atomically as
``results.parquet`` (pyarrow) and ``results.csv``.

Columns, in this order: the constant columns the caller puts first (a sweep's ``model``), ``key`` (:func:`~splinekit.batch.grid.variant_key`), the parameters,
``status`` (``ok``, ``failed``: the task raised, its message in ``error``; ``skipped``: not run
again, its figures taken from the results already in the folder), ``error``, then what the task
returned (measures, output paths), then ``recipe`` (what was asked of each variant: a row is
reused only for the same recipe).
"""

from __future__ import annotations

import os

from .. import _signals
from .._atomic import atomic_write
from ..errors import FileFormatError, MissingDependencyError
from .cluster import INSTALL_HINT

__all__ = ["DONE", "RESULTS_CSV", "RESULTS_PARQUET", "STATUSES", "pandas_module", "previous_rows", "table", "write"]

RESULTS_PARQUET = "results.parquet"
RESULTS_CSV = "results.csv"
STATUSES = ("ok", "failed", "skipped")
DONE = ("ok", "skipped")
"""Statuses of a row whose figures are complete, so that a resumed run need not build it again."""


def pandas_module():
    """``pandas`` (with pyarrow for parquet), or MissingDependencyError naming the extra."""
    try:
        import pandas
        import pyarrow  # noqa: F401  (parquet engine; imported here so its absence is reported up front)
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"sweep results are pandas tables written with pyarrow: {INSTALL_HINT} ({exc})") from None
    return pandas


def previous_rows(out: str) -> dict:
    """``{key: row dict}`` of the finished rows (status ``ok`` or ``skipped``) in the results
    already in folder ``out`` (empty when there are none). FileFormatError if the file is unreadable."""
    path = os.path.join(out, RESULTS_PARQUET)
    if not os.path.isfile(path):
        return {}
    pandas = pandas_module()
    try:
        old = pandas.read_parquet(path, engine="pyarrow")
    except Exception as exc:  # pyarrow raises its own ArrowInvalid / OSError family on a damaged file
        raise FileFormatError(f"cannot read the earlier results {path!r} to resume: {exc}; "
                              "remove it or run with force=True (--force)") from None
    if "key" not in old.columns or "status" not in old.columns:
        raise FileFormatError(f"{path!r} is not a sweep results file (no key/status columns); remove it or use another folder")
    old = old[old["status"].isin(DONE)]
    return {row["key"]: row for row in old.to_dict("records")}


def table(rows: list, param_names: list, leading: dict | None = None):
    """The results DataFrame of ``rows`` (dicts with ``key``, the parameters, ``status``,
    ``error``, ``recipe`` and the task's columns), columns in the documented order, after the
    columns ``leading`` (name -> the value of every row)."""
    pandas = pandas_module()
    leading = dict(leading or {})
    frame = pandas.DataFrame.from_records([{**leading, **row} for row in rows])
    first = [*leading, "key", *param_names, "status", "error"]
    rest = [c for c in frame.columns if c not in first and c != "recipe"]
    return frame.reindex(columns=[*first, *rest, "recipe"])


def write(frame, out: str) -> tuple[str, str]:
    """Write ``frame`` as ``results.parquet`` and ``results.csv`` in folder ``out``, each
    atomically (a failed write leaves the earlier file untouched); returns both paths."""
    parquet = atomic_write(os.path.join(out, RESULTS_PARQUET),
                           lambda tmp: frame.to_parquet(tmp, engine="pyarrow", index=False), "sweep results")
    csv = atomic_write(os.path.join(out, RESULTS_CSV), lambda tmp: frame.to_csv(tmp, index=False), "sweep results")
    return parquet, csv
