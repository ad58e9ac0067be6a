"""The memory budget: one limit for every allocation whose size is known in advance.

Operations whose output size can be estimated before they allocate
(tessellation, subdivision, grids, samplers, file readers after the header,
instancing) call :func:`check` with that estimate first; above the budget it
raises :class:`~splinekit.errors.ResourceLimitError` and nothing is allocated.

The budget, in bytes, is chosen in this order:

1. the innermost active ``with splinekit.limits.budget(nbytes):`` block;
2. the environment variable ``SPLINEKIT_MEMORY_BUDGET`` (bytes, or with a
   suffix: ``512M``, ``8G``; ``0`` or ``off`` disables the check);
3. :data:`DEFAULT_FRACTION` of the machine's physical memory.

>>> import splinekit
>>> with splinekit.limits.budget("1G"):
...     pass
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import os

from .errors import ParameterError, ResourceLimitError

__all__ = ["DEFAULT_FRACTION", "ENV_VAR", "budget", "check", "current_budget", "parse_size"]

ENV_VAR = "SPLINEKIT_MEMORY_BUDGET"
DEFAULT_FRACTION = 0.5
"""Fraction of physical memory one operation may claim when nothing else is set."""

_FALLBACK_BYTES = 4 * 2**30  # when the machine's memory cannot be read
_SUFFIXES = {"": 1, "B": 1, "K": 2**10, "KB": 2**10, "KIB": 2**10, "M": 2**20, "MB": 2**20, "MIB": 2**20,
             "G": 2**30, "GB": 2**30, "GIB": 2**30, "T": 2**40, "TB": 2**40, "TIB": 2**40}

_override: contextvars.ContextVar[float | None] = contextvars.ContextVar("splinekit_memory_budget", default=None)


def parse_size(value) -> float:
    """Bytes as a float from an int/float or a string such as ``"512M"``, ``"8G"``, ``"0"``/``"off"``
    (``math.inf``: no limit). Raises ParameterError for anything else."""
    if isinstance(value, bool):
        raise ParameterError(f"memory budget must be a size in bytes, got {value!r}")
    if isinstance(value, (int, float)):
        number = float(value)
        if math.isnan(number) or number < 0:
            raise ParameterError(f"memory budget must be a size >= 0 in bytes, got {value!r}")
        return math.inf if number == 0 else number
    if isinstance(value, str):
        text = value.strip().upper().replace("_", "")
        if text in ("OFF", "NONE", "INF", "0"):
            return math.inf
        digits = text.rstrip("KMGTIB")
        suffix = text[len(digits):]
        try:
            number = float(digits)
        except ValueError:
            number = math.nan
        if suffix in _SUFFIXES and math.isfinite(number) and number >= 0:
            return math.inf if number == 0 else number * _SUFFIXES[suffix]
    raise ParameterError(f"memory budget {value!r} is not a size: give bytes or a number with K, M, G or T (0 or 'off' for none)")


def _physical_memory() -> float:
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return float(_FALLBACK_BYTES)


def current_budget() -> float:
    """The budget in bytes that :func:`check` applies now (``math.inf`` when disabled)."""
    override = _override.get()
    if override is not None:
        return override
    env = os.environ.get(ENV_VAR)
    if env is not None and env.strip():
        try:
            return parse_size(env)
        except ParameterError as exc:
            raise ParameterError(f"{ENV_VAR}={env!r}: {exc}") from None
    return DEFAULT_FRACTION * _physical_memory()


@contextlib.contextmanager
def budget(nbytes):
    """Within the block, :func:`check` uses ``nbytes`` (a size as :func:`parse_size` reads it)."""
    token = _override.set(parse_size(nbytes))
    try:
        yield
    finally:
        _override.reset(token)


def _human(nbytes: float) -> str:
    if not math.isfinite(nbytes):
        return "unbounded"
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{nbytes:.0f} B"


def check(nbytes, what: str) -> None:
    """Raise ResourceLimitError when an allocation of ``nbytes`` bytes (an estimate, may be a
    float, ``inf`` or huge) for ``what`` (e.g. ``"tessellation of 32 patches at tolerance 1e-6"``)
    exceeds the budget. Call it before allocating."""
    estimate = float(nbytes)
    limit = current_budget()
    if math.isnan(estimate) or estimate > limit:
        raise ResourceLimitError(
            f"{what} needs about {_human(estimate)}, over the memory budget of {_human(limit)}; "
            f"raise it with {ENV_VAR}=<bytes, e.g. 16G> or `with splinekit.limits.budget(...)`"
        )
