"""A block with every edge rounded and a rounded rectangular pocket with a filleted floor: an exact B-rep solid.

Units: millimetres. A ``length`` x ``width`` x ``height`` box with all twelve
edges filleted to radius ``round`` (OpenCascade closes each corner with a
spherical patch); a ``pocket_length`` x ``pocket_width`` pocket ``depth``
deep cut into the middle of the top face, its four vertical corners
rounded to radius ``corner`` and the edge all round its floor filleted to
radius ``floor_fillet`` (cylinders along the sides, tori at the corners).

Made with :func:`splinekit.brep.fillet` and :func:`splinekit.brep.cut` on
splinekit's native boxes; the result is one :class:`~splinekit.brep.Solid`
of trimmed faces: planes, cylinders, spheres and tori as rational
B-splines (fillets of B-spline faces are OCC's approximations, within
about 1e-7 relative in volume and area). Meshes are its tessellation
(``tolerance``).
"""

from __future__ import annotations

import math

from splinekit import brep
from splinekit.errors import ParameterError

from ._base import Model, Parameter, resolve_params

NAME = "block"

PARAMETERS = (
    Parameter("length", 40.0, "mm", 30.0, 200.0, "size along x"),
    Parameter("width", 30.0, "mm", 20.0, 200.0, "size along y"),
    Parameter("height", 20.0, "mm", 14.0, 100.0, "size along z"),
    Parameter("round", 3.0, "mm", 0.5, 5.0, "fillet radius of the twelve outer edges"),
    Parameter("pocket_length", 20.0, "mm", 10.0, 30.0, "pocket size along x"),
    Parameter("pocket_width", 12.0, "mm", 9.0, 22.0, "pocket size along y"),
    Parameter("depth", 8.0, "mm", 3.0, 12.0, "pocket depth"),
    Parameter("corner", 4.0, "mm", 2.5, 5.5, "radius of the pocket's vertical corners"),
    Parameter("floor_fillet", 2.0, "mm", 0.5, 2.4, "fillet radius where the pocket's walls meet its floor"),
    Parameter("tolerance", 0.01, "mm", 0.005, 0.5, "chordal tolerance of the tessellation (STL and other meshes)"),
)

_SPANDREL = 1.0 - math.pi / 4.0  # area of a square r x r minus its inscribed quarter disk, over r^2
_SPANDREL_CENTROID = (10.0 - 3.0 * math.pi) / (12.0 - 3.0 * math.pi)  # its centroid from the corner, over r


def _check_fit(v: dict) -> None:
    """ParameterError naming the parameter when the pocket and the fillets do not fit."""
    r = v["round"]
    for size, side in (("pocket_length", "length"), ("pocket_width", "width")):
        if v[size] >= v[side] - 2 * r:
            raise ParameterError(
                f"parameter '{size}' = {v[size]:g}: the pocket must stay on the flat of the top face "
                f"(less than {side} - 2 x round = {v[side] - 2 * r:g} mm)"
            )
    if v["depth"] > v["height"] - 2 * r:
        raise ParameterError(
            f"parameter 'depth' = {v['depth']:g}: expected at most height - 2 x round = "
            f"{v['height'] - 2 * r:g} mm, so the pocket's floor stays above the rounded bottom"
        )
    half = 0.5 * min(v["pocket_length"], v["pocket_width"])
    if v["corner"] >= half:
        raise ParameterError(
            f"parameter 'corner' = {v['corner']:g}: expected less than half the pocket's smaller side ({half:g} mm)"
        )
    if v["floor_fillet"] >= min(v["corner"], v["depth"]):
        raise ParameterError(
            f"parameter 'floor_fillet' = {v['floor_fillet']:g}: expected less than the pocket's corner radius "
            f"and depth ({min(v['corner'], v['depth']):g} mm)"
        )


def _rounded_box(v: dict) -> tuple[float, float]:
    """``(volume, area)`` of the box with every edge rounded: a smaller box grown by a ball."""
    r = v["round"]
    a, b, c = (v[k] - 2 * r for k in ("length", "width", "height"))
    volume = a * b * c + 2 * r * (a * b + b * c + c * a) + math.pi * r * r * (a + b + c) + 4 / 3 * math.pi * r**3
    area = 2 * (a * b + b * c + c * a) + 2 * math.pi * r * (a + b + c) + 4 * math.pi * r * r
    return volume, area


def exact_volume(v: dict) -> float:
    """Volume in mm^3: the rounded box, minus the pocket (a rectangle with rounded corners times
    the depth), plus the floor fillet's spandrel along the straight sides and, at the four
    corners, turned a full turn about the corner axes in all (Pappus)."""
    a, b, d, rho, p = v["pocket_length"], v["pocket_width"], v["depth"], v["corner"], v["floor_fillet"]
    straight = 2 * (a + b) - 8 * rho
    pocket = d * (a * b - (4 - math.pi) * rho**2)
    fillet = _SPANDREL * p * p * (straight + 2 * math.pi * (rho - _SPANDREL_CENTROID * p))
    return _rounded_box(v)[0] - pocket + fillet


def exact_area(v: dict) -> float:
    """Area in mm^2: the rounded box plus the pocket's walls (its floor replaces the opening);
    the floor fillet swaps ``2 p`` of floor and wall for a quarter circle ``pi p / 2`` along the
    straight sides, and at the corners a ring of floor and a band of wall for a quarter torus
    (a quarter circle turned a full turn in all, Pappus)."""
    a, b, d, rho, p = v["pocket_length"], v["pocket_width"], v["depth"], v["corner"], v["floor_fillet"]
    straight = 2 * (a + b) - 8 * rho
    walls = (straight + 2 * math.pi * rho) * d
    sides = straight * (math.pi * p / 2 - 2 * p)
    torus = 2 * math.pi * (rho - p + 2 * p / math.pi) * (math.pi * p / 2)
    corners = torus - math.pi * (rho**2 - (rho - p) ** 2) - 2 * math.pi * rho * p
    return _rounded_box(v)[1] + walls + sides + corners


def solid(v: dict):
    """The block as one exact :class:`~splinekit.brep.Solid` for checked parameters ``v``."""
    L, W, H = v["length"], v["width"], v["height"]
    a, b, d = v["pocket_length"], v["pocket_width"], v["depth"]
    x0, y0 = 0.5 * (L - a), 0.5 * (W - b)
    body = brep.fillet(brep.box(L, W, H), "all", v["round"])
    margin = 1.0  # the cutter sticks out of the top face, so no faces coincide
    body = brep.cut(body, brep.box(a, b, d + margin, origin=(x0, y0, H - d)))
    # the pocket's four vertical edges, at mid depth
    body = brep.fillet(body, [(x, y, H - 0.5 * d) for x in (x0, x0 + a) for y in (y0, y0 + b)], v["corner"])
    # one floor edge: OCC rounds the whole tangent chain round the floor
    body = brep.fillet(body, [(0.5 * L, y0, H - d)], v["floor_fillet"])
    return brep.Solid(body.shells, name=NAME)


def build(**params) -> Model:
    """The block as one exact solid (``solids``).

    Checks (closed forms of :func:`exact_volume` and :func:`exact_area`, 1e-6
    relative): ``"volume"`` (mm^3), ``"area"`` (mm^2); ``"faces"``: 43 (the
    rounded box's 6 flats, 12 edge fillets and 8 corner patches; the pocket's
    4 walls, 4 corners, floor and 8 floor fillets); ``"euler_characteristic"``:
    2 (no through hole).
    """
    v = resolve_params(NAME, PARAMETERS, params)
    _check_fit(v)
    volume, area = exact_volume(v), exact_area(v)
    return Model(
        name=NAME,
        params=v,
        solids=[solid(v)],
        closed=True,
        checks={
            "volume": (volume, 1e-6 * volume),
            "area": (area, 1e-6 * area),
            "faces": (43, 0),
            "euler_characteristic": (2, 0),
        },
    )
