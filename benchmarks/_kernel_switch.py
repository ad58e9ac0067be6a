"""Run a call with the compiled kernels switched on or off (``SPLINEKIT_NUMBA``), for benchmarks
that time both paths of the library side by side in one process."""

from __future__ import annotations

import os

__all__ = ["with_numba"]


def with_numba(value: str, fn):
    """``fn()`` with ``SPLINEKIT_NUMBA`` set to ``value`` ("1" or "0"); the setting is restored after."""
    saved = os.environ.get("SPLINEKIT_NUMBA")
    os.environ["SPLINEKIT_NUMBA"] = value
    try:
        return fn()
    finally:
        if saved is None:
            del os.environ["SPLINEKIT_NUMBA"]
        else:
            os.environ["SPLINEKIT_NUMBA"] = saved
