"""The Dask cluster a batch runs on: the caller's client or scheduler unchanged, or a local
cluster of one single-threaded worker process per core, started and closed around the batch.

dask and distributed are an optional extra (``pip install -e ".[sweep]"``) imported only here,
when a batch runs, so ``import splinekit`` never loads them.
"""

from __future__ import annotations

import contextlib
import logging
import os

from .. import _signals
from ..errors import BackendError, MissingDependencyError, ParameterError

__all__ = ["CONNECT_TIMEOUT", "cluster_client", "distributed_module"]

CONNECT_TIMEOUT = 5.0
"""Seconds to wait for a scheduler given by address before reporting it unreachable."""

LOCAL_SETTINGS = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
}
"""Dask settings of the local cluster a batch starts: no statistical profiler, and rarer
housekeeping ticks. Each wake-up of a worker's event loop takes the GIL from the thread that
builds the model; on a busy machine every hand-over waits for the OS to schedule the other
thread. Measured on the 2-core machine under load: 1.6 s per vase variant in a worker with
these settings, 3.3 s with dask's defaults (0.6 s in the client process alone). A cluster the
caller gives is used with its own settings."""

SLOW_MALLOC_ENV = "MALLOC_TRIM_THRESHOLD_"
"""Left out of the environment the nanny gives the local cluster's worker processes. Dask sets
it to 64 KiB so that workers hand freed memory back to the OS; glibc then also stops adapting
its mmap threshold, and every large numpy temporary becomes an mmap, a munmap and fresh page
faults. Measured on the idle 2-core machine: 60 vase variants took 9.5 s in a worker with it,
5.5 s without it, and 5.5 s in a plain process (9.7 s in a plain process with it set)."""

INSTALL_HINT = 'pip install "splinekit[sweep]" (from a checkout: pip install -e ".[sweep]")'


def distributed_module():
    """The ``distributed`` package, or MissingDependencyError naming the extra to install."""
    try:
        import distributed
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"parameter sweeps run on Dask: {INSTALL_HINT} ({exc})") from None
    return distributed


def _is_client(obj) -> bool:
    return hasattr(obj, "submit") and hasattr(obj, "scheduler_info")


@contextlib.contextmanager
def cluster_client(client=None, scheduler=None, *, n_workers=None, timeout: float = CONNECT_TIMEOUT):
    """Context manager giving a ``distributed.Client``.

    Parameters
    ----------
    client : distributed.Client or str, optional
        Used as it is and left open (a string is a scheduler address, as ``scheduler``).
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``) or a scheduler file (``.json``, as
        written by ``dask scheduler --scheduler-file``); the client made for it is closed at the
        end, the cluster is left running. BackendError naming the address when no scheduler
        answers within ``timeout`` seconds.
    n_workers : int, optional
        Workers of the local cluster started when neither ``client`` nor ``scheduler`` is given
        (default: one per core). Each is a process with one thread: OpenCascade and numba are
        not safe to run from several threads of one process.
    """
    if client is not None and not isinstance(client, str) and not _is_client(client):
        raise ParameterError(f"client must be a distributed.Client or a scheduler address, got {type(client).__name__}")
    if client is not None and scheduler is not None:
        raise ParameterError("give either client= or scheduler=, not both")
    if isinstance(client, str):
        client, scheduler = None, client
    if client is not None:
        yield client
        return
    distributed = distributed_module()
    if scheduler is not None:
        yield from _connected(distributed, str(scheduler), timeout)
        return
    if n_workers is None:
        n_workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise ParameterError(f"n_workers must be a positive integer, got {n_workers!r}")
    import dask  # installed with distributed

    environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
               if k != SLOW_MALLOC_ENV}
    # the dashboard on a free port: the fixed default (8787) collides with other clusters on the machine
    with dask.config.set({**LOCAL_SETTINGS, "distributed.nanny.pre-spawn-environ": environ}), \
            distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                                     silence_logs=logging.ERROR) as cluster, \
            distributed.Client(cluster) as local:
        yield local


def _connected(distributed, address: str, timeout: float):
    """Generator body of :func:`cluster_client` for a scheduler address or scheduler file."""
    is_file = address.endswith(".json")
    if is_file and not os.path.isfile(address):
        raise BackendError(f"cannot reach the Dask scheduler: scheduler file {address!r} does not exist")
    try:
        remote = (distributed.Client(scheduler_file=address, timeout=timeout) if is_file
                  else distributed.Client(address, timeout=timeout))
    except (OSError, TimeoutError, ValueError, TypeError) as exc:  # refused, timed out, malformed
        raise BackendError(f"cannot reach the Dask scheduler at {address!r} within {timeout:g} s: {exc}") from None
    try:
        yield remote
    finally:
        remote.close()
