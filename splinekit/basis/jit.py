"""Dispatch between the numpy path and the optional compiled kernels.

numba is present whenever the project is installed (cadquery depends on it),
but it is imported only on the first evaluation of at least
:data:`MIN_POINTS` points, never by ``import splinekit``. Set the environment
variable ``SPLINEKIT_NUMBA=0`` to always use the numpy path (the test suite
checks that both paths agree).
"""

from __future__ import annotations

import os

MIN_POINTS = 20_000
_state: dict = {}


def kernels(n_points: int):
    """The kernel module when compiled kernels should serve ``n_points``, else None."""
    if n_points < MIN_POINTS or os.environ.get("SPLINEKIT_NUMBA", "1") == "0":
        return None
    if "module" not in _state:
        try:
            from . import _numba_kernels as module
        except ImportError:  # numba absent or broken: the numpy path serves
            module = None
        _state["module"] = module
    return _state["module"]
