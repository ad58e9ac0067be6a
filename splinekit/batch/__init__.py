"""Batch builds on Dask: one task per variant, from a laptop to a cluster.

The engine here knows nothing of models or file formats: :func:`run` takes any picklable
``task(params) -> dict`` and a list of parameter rows, runs them on a Dask cluster (the caller's
client or scheduler, or a local cluster of single-threaded worker processes started for the
batch), records a failing variant as a ``failed`` row and goes on, skips rows already finished in
the output folder, and writes ``results.parquet`` / ``results.csv`` atomically. The model sweep
(``splinekit.sweep("vase", {...})``, ``splinekit sweep vase --grid ...``) is built on it in
``models.sweep``, which knows how to build, measure and export a model.

dask, distributed, pandas and pyarrow are the optional extra ``sweep``
(``pip install -e ".[sweep]"``); they are imported when a batch runs, not with this package.
"""

from .cluster import CONNECT_TIMEOUT, cluster_client
from .grid import DEFAULT_MAX_VARIANTS, parse_grid, variant_key, variants
from .plot import plot_measure
from .results import RESULTS_CSV, RESULTS_PARQUET, STATUSES
from .run import run, summary_text

__all__ = [
    "CONNECT_TIMEOUT",
    "DEFAULT_MAX_VARIANTS",
    "RESULTS_CSV",
    "RESULTS_PARQUET",
    "STATUSES",
    "cluster_client",
    "parse_grid",
    "plot_measure",
    "run",
    "summary_text",
    "variant_key",
    "variants",
]
