"""Dispatch between the numpy path and the optional compiled kernels.

numba is present whenever the project is installed (cadquery depends on it),
but it is imported only on the first evaluation of at least
:data:`MIN_POINTS` points (or refinement producing at least
:data:`MIN_FACES` faces), never by ``import splinekit``. Set the environment
variable ``SPLINEKIT_NUMBA=0`` to always use the numpy path (the test suite
checks that both paths agree).
"""

from __future__ import annotations

import importlib
import os

MIN_POINTS = 20_000
MIN_FACES = 20_000
_state: dict = {}


def _load(name: str):
    """The compiled-kernel module ``name`` (imported once), or None when numba is missing or broken."""
    if name not in _state:
        try:
            module = importlib.import_module(name)
        except ImportError:  # numba absent or broken: the numpy path serves
            module = None
        _state[name] = module
    return _state[name]


def _enabled() -> bool:
    return os.environ.get("SPLINEKIT_NUMBA", "1") != "0"


def kernels(n_points: int):
    """The kernel module when compiled kernels should serve ``n_points``, else None."""
    if n_points < MIN_POINTS or not _enabled():
        return None
    return _load("splinekit.basis._numba_kernels")


def subdiv_kernels(n_faces: int):
    """The subdivision kernel module (:mod:`splinekit.subdiv._kernels`) when a refinement
    producing ``n_faces`` faces should use it, else None."""
    if n_faces < MIN_FACES or not _enabled():
        return None
    return _load("splinekit.subdiv._kernels")


def compiled(module: str, n_points: int):
    """The compiled-kernel module ``module`` (dotted name) when ``n_points``
    points should use compiled kernels, else None."""
    if n_points < MIN_POINTS or not _enabled():
        return None
    return _load(module)
