"""Explicit tolerances. There is no mutable global state: functions that need a
tolerance take it as an argument whose default comes from :data:`DEFAULT`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

__all__ = ["Tolerances", "DEFAULT", "geometric_tolerance"]


@dataclass(frozen=True)
class Tolerances:
    """Tolerances used when a caller does not give one.

    Attributes
    ----------
    param : float
        Relative slack (times the domain length) within which a parameter just
        outside the domain is accepted and clamped onto it, so that values such
        as ``np.linspace(a, b)`` computed in floating point never fail.
    knot : float
        Relative distance (times the domain length) under which two knot values
        count as the same knot when a knot is looked up by value.
    point : float
        Geometric tolerance for knot removal and closedness checks, relative to
        the control net's size (see :func:`geometric_tolerance`).
    """

    param: float = 1e-10
    knot: float = 1e-12
    point: float = 1e-9


DEFAULT = Tolerances()


def geometric_tolerance(tol, points) -> float:
    """``tol`` checked (finite, >= 0), or by default ``DEFAULT.point`` times the
    size of the control net (its largest absolute coordinate, at least 1), so
    that the default means the same for a part in metres and one in microns."""
    if tol is None:
        return DEFAULT.point * max(1.0, float(np.abs(points).max()))
    try:
        tol = float(tol)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"tol must be a number, got {tol!r}") from None
    if not (math.isfinite(tol) and tol >= 0):
        raise ParameterError(f"tol must be finite and >= 0, got {tol!r}")
    return tol
