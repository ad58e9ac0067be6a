"""The one loader of compiled (numba) kernels.

Each layer keeps its compiled kernels in a module beside the numpy path they must agree with
(``splinekit/basis/_numba_kernels.py``, ``splinekit/subdiv/_kernels.py``, ...) and asks this
module for it::

    from .. import _kernels

    K = _kernels.load("splinekit.basis._numba_kernels", work=n_points)
    if K is None:
        ...  # the numpy path
    else:
        K.curve_points(...)

One threshold (:data:`MIN_WORK`: below it the numpy path serves, since compiling or loading
kernels costs more than it saves), one cache policy (kernel modules decorate with
``numba.njit(cache=True)``, so compiled code is kept on disk beside the source and later
processes only load it), and one switch: the environment variable ``SPLINEKIT_NUMBA=0`` turns
compiled code off everywhere (the test suite checks that both paths agree). numba is imported
on the first load, never by ``import splinekit``.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

from ._signals import reraise_interrupt

MIN_WORK = 20_000
"""Smallest amount of work (points, faces, cells: the caller's unit) sent to compiled kernels."""

_modules: dict[str, ModuleType | None] = {}


def enabled() -> bool:
    """False when ``SPLINEKIT_NUMBA=0`` is set (read on every call, so tests may flip it)."""
    return os.environ.get("SPLINEKIT_NUMBA", "1") != "0"


def load(module: str, work: int | None = None) -> ModuleType | None:
    """The compiled-kernel module ``module`` (a dotted name), or None when the numpy path should serve.

    None when compiled code is switched off, when numba is missing or broken, or when ``work``
    is given and below :data:`MIN_WORK`. The module is imported once and remembered.
    """
    if not enabled() or (work is not None and work < MIN_WORK):
        return None
    if module not in _modules:
        try:
            _modules[module] = importlib.import_module(module)
        except ImportError as exc:  # numba absent or broken: the numpy path serves
            reraise_interrupt(exc)  # ...but Ctrl-C while numba initialises stays an interrupt
            _modules[module] = None
    return _modules[module]
