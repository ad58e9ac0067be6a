"""Explicit tolerances. There is no mutable global state: functions that need a
tolerance take it as an argument whose default comes from :data:`DEFAULT`."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Tolerances", "DEFAULT"]


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
        Absolute geometric tolerance (model units) for knot removal and
        closedness checks.
    """

    param: float = 1e-10
    knot: float = 1e-12
    point: float = 1e-9


DEFAULT = Tolerances()
