"""The Utah teapot: Martin Newell's 32 bicubic Bézier patches (public-domain data, 306 vertices).

Units: millimetres. ``scale`` millimetres per unit of Newell's data, whose
teapot is 3.15 units tall (z up) and 6.525 long from the handle to the tip of
the spout (+x). The patches are the original ones, unchanged: the body is open
at the top (the lid sits inside the rim, which it does not touch) and the
handle and spout pierce the body, so the result is a set of exact faces, not
a closed solid (``closed`` is False). The STEP export is 32 B-spline faces.
"""

from __future__ import annotations

import numpy as np

from splinekit import BezierSurface

from . import teapot_data
from ._base import INTEGRAL_TOLERANCE, Model, Parameter, resolve_params, surface_integrals

NAME = "teapot"

PARAMETERS = (
    Parameter("scale", 20.0, "mm", 0.1, 1000.0, "millimetres per unit of the Newell data (height 3.15 units)"),
)


def vertices() -> np.ndarray:
    """The 306 control points of the data set, ``(306, 3)`` float64 in Newell's units."""
    return np.array(teapot_data.VERTICES.split(), dtype=float).reshape(-1, 3)


def patch_indices() -> np.ndarray:
    """Zero-based vertex numbers of the 32 patches, ``(32, 4, 4)`` int (row-major control nets)."""
    return np.array(teapot_data.PATCHES.split(), dtype=np.intp).reshape(-1, 4, 4) - 1


def patch_groups() -> list[str]:
    """The group name of each of the 32 patches (``"rim"``, ``"handle"``, ...), in patch order."""
    return [name for name, count in teapot_data.GROUPS for _ in range(count)]


def control_nets(scale: float = 1.0) -> np.ndarray:
    """The control nets of the 32 patches, ``(32, 4, 4, 3)``, times ``scale``."""
    return vertices()[patch_indices()] * scale


def build(**params) -> Model:
    """The 32 exact Bézier patches, scaled; one open body named ``"teapot"``.

    Checks: ``"faces"`` = 32 and ``"area"`` (mm^2): the surface area by
    adaptive quadrature of the exact patches (21153.3212370 mm^2 at the default
    scale; eight patches have collapsed edges), tolerance 1e-9 relative;
    ``"euler_characteristic"`` = 2: four open pieces, the body and the lid disks
    (1 each: closed at their apexes, open at the rim) and the handle and the
    spout tubes (0 each: open at both ends).
    """
    values = resolve_params(NAME, PARAMETERS, params)
    patches = [BezierSurface(net) for net in control_nets(values["scale"])]
    area, _ = surface_integrals(patches)
    return Model(
        name=NAME,
        params=values,
        bodies=[patches],
        body_names=["teapot"],
        mesh=None,
        closed=False,
        checks={"faces": (32, 0), "area": (area, INTEGRAL_TOLERANCE * area), "euler_characteristic": (2, 0)},
    )
