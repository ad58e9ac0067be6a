"""Deprecated: compiled kernels are loaded through :mod:`splinekit._kernels`.

Kept only for the subdivision modules that have not moved to ``_kernels.load`` yet; it keeps
their behaviour (a refinement of at least :data:`MIN_FACES` faces loads the kernels) and shares
the loader's switch (``SPLINEKIT_NUMBA=0``) and its cache of loaded modules. Delete it once
nothing imports it.
"""

from __future__ import annotations

import importlib

from .. import _kernels

MIN_POINTS = MIN_FACES = _kernels.MIN_WORK


def _load(name: str):
    """The compiled-kernel module ``name`` (imported once, into the loader's cache), or None when
    numba is missing or broken; whatever the switch says now (the caller decided earlier)."""
    if name not in _kernels._modules:
        try:
            _kernels._modules[name] = importlib.import_module(name)
        except ImportError:  # numba absent or broken: the numpy path serves
            _kernels._modules[name] = None
    return _kernels._modules[name]


def _enabled() -> bool:
    return _kernels.enabled()


def subdiv_kernels(n_faces: int):
    """The subdivision kernel module when a refinement producing ``n_faces`` faces should use it, else None."""
    if n_faces < MIN_FACES or not _kernels.enabled():
        return None
    return _load("splinekit.subdiv._kernels")
