"""An L bracket with bosses, four through holes and fillets: an exact B-rep solid made with exact booleans.

Units: millimetres. Two plates of thickness ``thickness`` and width ``width``
(along y): a base plate ``length`` long on the xy-plane and an upright plate
``height`` tall on the yz-plane, sharing the corner block. The inside of the
bend is rounded with radius ``bend``, the base plate's two free vertical
corners with radius ``corner``. Two cylindrical bosses (height
``boss_height``, wall ``boss_wall`` around the hole) stand on the base plate;
a hole of diameter ``hole`` runs through each boss and the plate, and two
more through the upright.

Built from splinekit's native box and cylinder solids
(:mod:`splinekit.brep.primitives`) with the exact booleans
:func:`splinekit.brep.fuse` / :func:`splinekit.brep.cut` and the fillets of
:func:`splinekit.brep.fillet` (OpenCascade does the booleans and the blends):
the result is one :class:`~splinekit.brep.Solid` of trimmed faces, written
exactly to STEP; meshes are its tessellation (``tolerance``).
"""

from __future__ import annotations

import math

import numpy as np

from splinekit import brep
from splinekit.errors import ParameterError

from ._base import Model, Parameter, resolve_params

NAME = "bracket"

PARAMETERS = (
    Parameter("length", 60.0, "mm", 30.0, 300.0, "length of the base plate along x"),
    Parameter("height", 50.0, "mm", 30.0, 300.0, "height of the upright plate along z"),
    Parameter("width", 40.0, "mm", 25.0, 200.0, "width of both plates along y"),
    Parameter("thickness", 6.0, "mm", 2.0, 12.0, "plate thickness"),
    Parameter("hole", 6.0, "mm", 2.0, 12.0, "hole diameter"),
    Parameter("boss_wall", 2.0, "mm", 1.0, 4.0, "wall of the bosses around their holes"),
    Parameter("boss_height", 3.0, "mm", 1.0, 10.0, "height of the bosses above the base plate"),
    Parameter("bend", 4.0, "mm", 1.0, 6.0, "fillet radius inside the bend"),
    Parameter("corner", 5.0, "mm", 1.0, 10.0, "fillet radius of the base plate's free corners"),
    Parameter("tolerance", 0.01, "mm", 0.005, 0.5, "chordal tolerance of the tessellation (STL and other meshes)"),
)

# the drills stick out this far past the faces they pierce, so no faces coincide
_DRILL_MARGIN = 1.0


def _check_fit(v: dict) -> None:
    """ParameterError naming the parameter when bosses, holes and fillets do not fit on the plates."""
    t, w, l, h = v["thickness"], v["width"], v["length"], v["height"]
    r_boss = 0.5 * v["hole"] + v["boss_wall"]
    if r_boss >= 0.25 * w:
        raise ParameterError(
            f"parameter 'hole' = {v['hole']:g}: the bosses (diameter hole + 2 x boss_wall = {2 * r_boss:g} mm) "
            f"must be narrower than a quarter of the width x 2 = {0.5 * w:g} mm"
        )
    free = 0.5 * (l - t) - r_boss  # from a boss to either end of the base plate's free length
    for name in ("bend", "corner"):
        if v[name] >= free:
            raise ParameterError(
                f"parameter '{name}' = {v[name]:g}: expected less than {free:g} mm, the room between a boss "
                "and the end of the base plate"
            )
    if v["corner"] >= 0.5 * w:
        raise ParameterError(f"parameter 'corner' = {v['corner']:g}: expected less than half the width ({0.5 * w:g} mm)")
    room = 0.5 * (h - t) - 0.5 * v["hole"]  # from an upright hole down to the bend
    if v["bend"] >= room:
        raise ParameterError(
            f"parameter 'hole' = {v['hole']:g}: the upright holes reach the bend fillet "
            f"(expected hole/2 + bend < {0.5 * (h - t):g} mm)"
        )


def hole_centres(v: dict) -> tuple[np.ndarray, np.ndarray]:
    """Centres of the base-plate holes (axis z) and the upright holes (axis x), ``(2, 3)`` each, mid-plate."""
    t, w = v["thickness"], v["width"]
    ys = np.array([0.25 * w, 0.75 * w])
    base = np.stack([np.full(2, t + 0.5 * (v["length"] - t)), ys, np.full(2, 0.5 * t)], axis=1)
    upright = np.stack([np.full(2, 0.5 * t), ys, np.full(2, t + 0.5 * (v["height"] - t))], axis=1)
    return base, upright


_SPANDREL = 1.0 - math.pi / 4.0  # area of a square r x r minus its inscribed quarter disk, over r^2


def exact_volume(v: dict) -> float:
    """The bracket's volume in mm^3 by hand.

    The L section (plates plus the bend fillet's spandrel ``bend^2 (1 - pi/4)``) times the width,
    minus the two rounded corners' spandrels times the thickness, plus the bosses, minus the holes
    (the base holes also run through the bosses).
    """
    t, w, l, h = (v[k] for k in ("thickness", "width", "length", "height"))
    r = 0.5 * v["hole"]
    rb, hb, c, b = 0.5 * v["hole"] + v["boss_wall"], v["boss_height"], v["corner"], v["bend"]
    section = l * t + (h - t) * t + _SPANDREL * b * b
    return (section * w - 2 * _SPANDREL * c * c * t + 2 * math.pi * rb * rb * hb
            - 2 * math.pi * r * r * (t + hb) - 2 * math.pi * r * r * t)


def exact_area(v: dict) -> float:
    """The bracket's surface area in mm^2 by hand.

    The extruded L section: twice its area plus its perimeter (each fillet replaces two straight
    lengths ``rho`` by a quarter circle ``pi rho / 2``) times the width; each rounded corner takes
    a spandrel off the top and the bottom face and swaps ``2 c`` for ``pi c / 2`` on the side;
    the bosses add their side walls; each hole takes two disks and adds its wall.
    """
    t, w, l, h = (v[k] for k in ("thickness", "width", "length", "height"))
    r = 0.5 * v["hole"]
    rb, hb, c, b = 0.5 * v["hole"] + v["boss_wall"], v["boss_height"], v["corner"], v["bend"]
    section = l * t + (h - t) * t + _SPANDREL * b * b
    perimeter = 2 * l + 2 * h - (2 - math.pi / 2) * b
    area = 2 * section + perimeter * w
    area -= 2 * (2 * _SPANDREL * c * c + (2 - math.pi / 2) * c * t)
    area += 2 * 2 * math.pi * rb * hb
    area += 2 * (2 * math.pi * r * (t + hb) - 2 * math.pi * r * r)
    area += 2 * (2 * math.pi * r * t - 2 * math.pi * r * r)
    return area


def solid(v: dict):
    """The bracket as one exact :class:`~splinekit.brep.Solid` for checked parameters ``v``."""
    t, w, l, h = v["thickness"], v["width"], v["length"], v["height"]
    r, hb = 0.5 * v["hole"], v["boss_height"]
    r_boss = r + v["boss_wall"]
    m = _DRILL_MARGIN
    base_holes, upright_holes = hole_centres(v)
    body = brep.fuse(brep.box(l, w, t), brep.box(t, w, h - t, origin=(0.0, 0.0, t)))
    # the inside of the bend: the edge along y where the base's top meets the upright's face
    body = brep.fillet(body, [(t, 0.5 * w, t)], v["bend"])
    body = brep.fillet(body, [(l, 0.0, 0.5 * t), (l, w, 0.5 * t)], v["corner"])
    bosses = [brep.cylinder(r_boss, hb, origin=(x, y, t)) for x, y, _ in base_holes]
    body = brep.fuse(body, bosses)
    drills = [brep.cylinder(r, t + hb + 2 * m, origin=(x, y, -m)) for x, y, _ in base_holes]
    drills += [brep.cylinder(r, t + 2 * m, origin=(-m, y, z), axis=(1.0, 0.0, 0.0)) for _, y, z in upright_holes]
    body = brep.cut(body, drills)
    return brep.Solid(body.shells, name=NAME)


def build(**params) -> Model:
    """The bracket as one exact solid (``solids``), no patch bodies and no mesh.

    Checks (closed forms of :func:`exact_volume` and :func:`exact_area`, 1e-6
    relative): ``"volume"`` (mm^3), ``"area"`` (mm^2); ``"faces"``: 19 (the L's
    8 planar faces, 3 fillets, 2 boss walls and 2 boss tops, 4 hole walls);
    ``"euler_characteristic"``: -6 (a closed surface of genus 4, one handle per hole).
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
            "faces": (19, 0),
            "euler_characteristic": (-6, 0),
        },
    )
