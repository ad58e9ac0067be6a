"""A block with every edge rounded and a round pocket with a filleted floor: an exact B-rep solid.

Units: millimetres. A ``length`` x ``width`` x ``height`` box with all twelve
edges filleted to radius ``round`` (OpenCascade closes each corner with a
spherical patch), then a cylindrical pocket of diameter ``pocket`` and depth
``depth`` cut into the middle of the top face, whose floor edge is filleted
to radius ``floor_fillet``.

Made with :func:`splinekit.brep.fillet` and :func:`splinekit.brep.cut` on
splinekit's native box and cylinder; the result is one
:class:`~splinekit.brep.Solid` of trimmed faces: planes, cylinders, spheres
and tori as rational B-splines (the fillets on B-spline faces are OCC's
approximations). Meshes are its tessellation (``tolerance``).
"""

from __future__ import annotations

import math

from splinekit.errors import ParameterError

from ._base import Model, Parameter, resolve_params

NAME = "block"

PARAMETERS = (
    Parameter("length", 40.0, "mm", 20.0, 200.0, "size along x"),
    Parameter("width", 30.0, "mm", 20.0, 200.0, "size along y"),
    Parameter("height", 20.0, "mm", 14.0, 100.0, "size along z"),
    Parameter("round", 3.0, "mm", 0.5, 5.0, "fillet radius of the twelve outer edges"),
    Parameter("pocket", 12.0, "mm", 6.0, 20.0, "pocket diameter"),
    Parameter("depth", 8.0, "mm", 3.0, 12.0, "pocket depth"),
    Parameter("floor_fillet", 2.0, "mm", 0.5, 2.5, "fillet radius where the pocket's wall meets its floor"),
    Parameter("tolerance", 0.01, "mm", 0.005, 0.5, "chordal tolerance of the tessellation (STL and other meshes)"),
)

_SPANDREL = 1.0 - math.pi / 4.0  # area of a square r x r minus its inscribed quarter disk, over r^2
_SPANDREL_CENTROID = (10.0 - 3.0 * math.pi) / (12.0 - 3.0 * math.pi)  # its centroid from the corner, over r


def _check_fit(v: dict) -> None:
    """ParameterError naming the parameter when the pocket and the fillets do not fit."""
    radius, r = 0.5 * v["pocket"], v["round"]
    room = 0.5 * min(v["length"], v["width"]) - r
    if radius >= room:
        raise ParameterError(
            f"parameter 'pocket' = {v['pocket']:g}: the pocket must stay on the flat of the top face "
            f"(diameter below {2 * room:g} mm: the smaller side minus twice 'round')"
        )
    if v["depth"] > v["height"] - 2.0 * r:
        raise ParameterError(
            f"parameter 'depth' = {v['depth']:g}: expected at most height - 2 x round = "
            f"{v['height'] - 2 * r:g} mm, so the pocket's floor stays above the rounded bottom"
        )
    if v["floor_fillet"] >= min(radius, v["depth"]):
        raise ParameterError(
            f"parameter 'floor_fillet' = {v['floor_fillet']:g}: expected less than the pocket's radius "
            f"and depth ({min(radius, v['depth']):g} mm)"
        )


def exact_volume(v: dict) -> float:
    """Volume in mm^3: the rounded box (a smaller box grown by a ball of radius ``round``), minus
    the pocket, plus the floor fillet's spandrel turned about the pocket's axis (Pappus)."""
    r, R, d, p = v["round"], 0.5 * v["pocket"], v["depth"], v["floor_fillet"]
    a, b, c = (v[k] - 2 * r for k in ("length", "width", "height"))
    box = a * b * c + 2 * r * (a * b + b * c + c * a) + math.pi * r * r * (a + b + c) + 4 / 3 * math.pi * r**3
    fillet = 2 * math.pi * (R - _SPANDREL_CENTROID * p) * _SPANDREL * p * p
    return box - math.pi * R * R * d + fillet


def exact_area(v: dict) -> float:
    """Area in mm^2: the rounded box, plus the pocket's wall (its floor replaces the top's disk),
    with the floor fillet (a quarter circle turned about the axis, Pappus) instead of the floor's
    outer ring and the wall's lowest ``floor_fillet``."""
    r, R, d, p = v["round"], 0.5 * v["pocket"], v["depth"], v["floor_fillet"]
    a, b, c = (v[k] - 2 * r for k in ("length", "width", "height"))
    box = 2 * (a * b + b * c + c * a) + 2 * math.pi * r * (a + b + c) + 4 * math.pi * r * r
    fillet = 2 * math.pi * (R - p + 2 * p / math.pi) * (math.pi * p / 2)
    return box + 2 * math.pi * R * d - math.pi * (R * R - (R - p) ** 2) - 2 * math.pi * R * p + fillet


def solid(v: dict):
    """The block as one exact :class:`~splinekit.brep.Solid` for checked parameters ``v``."""
    from splinekit import brep

    L, W, H = v["length"], v["width"], v["height"]
    R, d = 0.5 * v["pocket"], v["depth"]
    body = brep.fillet(brep.box(L, W, H), "all", v["round"])
    margin = 1.0  # the cutter sticks out of the top face, so no faces coincide
    body = brep.cut(body, brep.cylinder(R, d + margin, origin=(0.5 * L, 0.5 * W, H - d)))
    # the floor's circular edge, at its point on the +y side (the wall's seam is on the +x side)
    body = brep.fillet(body, [(0.5 * L, 0.5 * W + R, H - d)], v["floor_fillet"])
    return brep.Solid(body.shells, name=NAME)


def build(**params) -> Model:
    """The block as one exact solid (``solids``).

    Checks (closed forms of :func:`exact_volume` and :func:`exact_area`, 1e-6
    relative): ``"volume"`` (mm^3), ``"area"`` (mm^2); ``"faces"``: 29 (6 flats,
    12 edge fillets, 8 corner patches, the pocket's wall, floor and floor
    fillet); ``"euler_characteristic"``: 2 (no through hole).
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
            "faces": (29, 0),
            "euler_characteristic": (2, 0),
        },
    )
