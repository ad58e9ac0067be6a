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

``work`` is the size of the job in point-equivalents: one unit is about what the numpy path
spends on one point of a cubic curve (a microsecond or so), so a caller whose unit is cheaper
or dearer scales its count (a grid point of a surface costs about a sixteenth of that, a point
with its full curvature about three).

One cache policy: kernel modules decorate with ``numba.njit(cache=True)``, so compiled code is
kept on disk beside the source and later processes only load it. Loading is still not free:
importing numba and initialising its compiler takes about 0.3-1 s in a fresh process, far more
than the numpy path needs for a typical call (a 1000 x 1000 grid: 10-50 ms). Hence two
thresholds, in the same unit:

- :data:`MIN_WORK`: a job smaller than this always runs on the numpy path (the compiled code
  does not win on it);
- :data:`LOAD_WORK`: compiled kernels are loaded only once the numpy path has served this much
  work in jobs of at least :data:`MIN_WORK` (a single job this large loads them at once). So the
  first call after ``import splinekit`` costs what the numpy path costs, unless it is large
  enough to pay for the load itself, and a long session still moves to the compiled code.
  Once any kernel module is loaded (numba's compiler is up), further modules load at the first
  job of at least :data:`MIN_WORK`.

One switch, the environment variable ``SPLINEKIT_NUMBA`` (read on every call): ``0`` turns
compiled code off everywhere (the test suite checks that both paths agree); ``1`` loads the
kernels at the first job of at least :data:`MIN_WORK`, without waiting for :data:`LOAD_WORK`
(for long sessions and benchmarks of the steady state); unset, the rule above. numba is
imported on the first load, never by ``import splinekit``.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

from ._signals import reraise_interrupt

MIN_WORK = 20_000
"""Smallest job (point-equivalents, see the module docstring) sent to compiled kernels."""

LOAD_WORK = 2_000_000
"""Work the numpy path serves (in jobs of at least :data:`MIN_WORK`) before the first kernel
module is loaded: about two seconds of numpy time, about twice the cost of the load. A first
call loads only when it is this large itself, so it stays within about 1.5 times the numpy
path's time; later, the job that brings the total to this pays the load whole, which adds at
most about half to what the session has spent on such jobs so far."""

_modules: dict[str, ModuleType | None] = {}
_served = 0  # work the numpy path has served while no kernel module was loaded


def enabled() -> bool:
    """False when ``SPLINEKIT_NUMBA=0`` is set (read on every call, so tests may flip it)."""
    return os.environ.get("SPLINEKIT_NUMBA", "") != "0"


def _eager() -> bool:
    """True when ``SPLINEKIT_NUMBA=1`` is set: no waiting for :data:`LOAD_WORK`."""
    return os.environ.get("SPLINEKIT_NUMBA", "") == "1"


def loaded() -> bool:
    """True once a kernel module has been loaded in this process (numba's compiler is up)."""
    return any(module is not None for module in _modules.values())


def get(module: str) -> ModuleType | None:
    """The compiled-kernel module ``module`` if it is already loaded (and compiled code is on), else None.

    Never loads: for kernels that win at every size once loaded (the fixed per-call work of a
    small tessellation) but whose job alone does not pay for loading them; the caller of the
    whole job asks :func:`load` with its size first.
    """
    return _modules.get(module) if enabled() else None


def load(module: str, work: float | None = None, *, min_work: float | None = None) -> ModuleType | None:
    """The compiled-kernel module ``module`` (a dotted name), or None when the numpy path should serve.

    None when compiled code is switched off, when numba is missing or broken, when ``work`` is
    given and below ``min_work`` (default :data:`MIN_WORK`; a family whose kernels win on
    smaller jobs passes its own), or while no kernel module is loaded yet and the work the
    numpy path has served (this job included) is below :data:`LOAD_WORK` (unless
    ``SPLINEKIT_NUMBA=1``). Without ``work`` the module is loaded unconditionally. A module is
    imported once and remembered.
    """
    global _served
    if not enabled():
        return None
    if work is not None:
        if work < (MIN_WORK if min_work is None else min_work):
            return None
        if module not in _modules and not loaded() and not _eager():
            _served += work
            if _served < LOAD_WORK:
                return None
    if module not in _modules:
        try:
            _modules[module] = importlib.import_module(module)
        except ImportError as exc:  # numba absent or broken: the numpy path serves
            reraise_interrupt(exc)  # ...but Ctrl-C while numba initialises stays an interrupt
            _modules[module] = None
    return _modules[module]
