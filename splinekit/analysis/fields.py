"""The formulas of the analysis maps on ``(n, 3)`` unit normals, shared by the per-vertex
values (:mod:`.maps`) and the per-pixel pictures (:mod:`.pictures`); see :mod:`.maps` for
what they mean."""

from __future__ import annotations

import numpy as np

__all__ = ["VERTICAL_DEGREES", "draft_degrees", "isophote_angle", "zebra_angle", "zebra_stripe"]

VERTICAL_DEGREES = 1e-6
"""A draft angle within this of 0 is a vertical wall (rounding of exact normals), not an under-cut."""


def zebra_angle(normals, eye, axis) -> np.ndarray:
    """Angle ``(n,)`` in radians of the view direction ``-eye`` reflected by ``normals``
    ``(n, 3)``, about the unit ``axis``, from the direction back to the viewer (module notes)."""
    d = -eye
    r = d[None, :] - 2.0 * (normals @ d)[:, None] * normals
    e1 = eye - (eye @ axis) * axis
    if np.linalg.norm(e1) < 1e-9:  # looking along the bands: any direction across them
        e1 = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 = e1 / np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    return np.arctan2(r @ e2, r @ e1)


def zebra_stripe(angle, stripes: int) -> np.ndarray:
    """``(n,)`` 0 (black) or 1 (white) of reflection angles ``angle`` with ``stripes`` pairs all
    around; a white stripe is centred on the reflection back to the viewer (angle 0)."""
    return (np.floor(angle * (stripes / np.pi) + 0.5).astype(np.int64) % 2 == 0).astype(np.int8)


def isophote_angle(normals, direction) -> np.ndarray:
    """Angle ``(n,)`` in degrees between ``normals`` ``(n, 3)`` and the unit ``direction``."""
    return np.degrees(np.arccos(np.clip(normals @ direction, -1.0, 1.0)))


def draft_degrees(normals, pull) -> np.ndarray:
    """Draft angle ``(n,)`` in degrees, ``asin(n . pull)``, of ``normals`` ``(n, 3)``."""
    return np.degrees(np.arcsin(np.clip(normals @ pull, -1.0, 1.0)))
