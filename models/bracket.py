"""An L bracket with four holes: NURBS primitives combined by manifold3d booleans.

Units: millimetres. Two plates of thickness ``thickness`` and width ``width``
(along y): a base plate ``length`` long on the xy-plane and an upright plate
``height`` tall on the yz-plane, sharing the corner block. Each plate has two
through holes of diameter ``hole`` centred on it. The plates are boxes made
of six bilinear B-spline patches, the holes exact NURBS cylinders (three
revolved faces each, made longer than the plates so no faces coincide);
:func:`splinekit.interop.booleans.union` and ``difference`` tessellate them
with chordal tolerance ``tolerance`` and return one closed triangle mesh.
"""

from __future__ import annotations

import numpy as np

from splinekit import BSplineSurface, line, revolve
from splinekit.errors import ParameterError
from splinekit.interop.booleans import difference, union, union_all
from splinekit.mesh.primitives import box as box_mesh

from ._base import Model, Parameter, resolve_params

NAME = "bracket"

PARAMETERS = (
    Parameter("length", 60.0, "mm", 30.0, 300.0, "length of the base plate along x"),
    Parameter("height", 50.0, "mm", 30.0, 300.0, "height of the upright plate along z"),
    Parameter("width", 40.0, "mm", 20.0, 200.0, "width of both plates along y"),
    Parameter("thickness", 6.0, "mm", 2.0, 12.0, "plate thickness"),
    Parameter("hole", 6.0, "mm", 2.0, 12.0, "hole diameter"),
    Parameter("tolerance", 0.01, "mm", 0.005, 0.5, "chordal tolerance of the tessellation fed to the booleans"),
)

_LINEAR = np.array([0.0, 0.0, 1.0, 1.0])


def box_patches(lower, upper) -> list:
    """Six bilinear B-spline patches bounding the box ``[lower, upper]`` (3-vectors), normals outward."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    mesh = box_mesh(upper - lower, 0.5 * (lower + upper))
    patches = []
    for v0, v1, v2, v3 in mesh.vertices[mesh.faces]:
        # u along v0 -> v1, v along v0 -> v3: S_u x S_v is the outward normal of a CCW quad
        net = np.array([[v0, v3], [v1, v2]])
        patches.append(BSplineSurface(1, 1, _LINEAR, _LINEAR, net))
    return patches


def cylinder_patches(base, axis, radius: float, length: float) -> list:
    """An exact NURBS cylinder: bottom disk, side and top disk (revolved lines), normals outward.

    ``base`` is the centre of the bottom disk, ``axis`` the unit direction to the top.
    """
    base, axis = np.asarray(base, float), np.asarray(axis, float)
    axis = axis / np.linalg.norm(axis)
    radial = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    radial = radius * radial / np.linalg.norm(radial)
    top = base + length * axis
    # the cross-section loop runs counter-clockwise in (radius, height): out, up, in
    profile = [line(base, base + radial), line(base + radial, top + radial), line(top + radial, top)]
    return [revolve(c, base, axis) for c in profile]


def _check_fit(v: dict) -> None:
    """ParameterError when the holes do not fit on the plates."""
    room = min(0.4 * v["width"], 0.6 * (v["length"] - v["thickness"]), 0.6 * (v["height"] - v["thickness"]))
    if v["hole"] > room:
        raise ParameterError(
            f"parameter 'hole' = {v['hole']:g}: expected at most {room:g} mm for these plates "
            "(0.4 x width, 0.6 x the free length and height)"
        )


def hole_centres(v: dict) -> tuple[np.ndarray, np.ndarray]:
    """Centres of the base-plate holes (axis z) and the upright holes (axis x), ``(2, 3)`` each, mid-plate."""
    t, w = v["thickness"], v["width"]
    ys = np.array([0.25 * w, 0.75 * w])
    base = np.stack([np.full(2, t + 0.5 * (v["length"] - t)), ys, np.full(2, 0.5 * t)], axis=1)
    upright = np.stack([np.full(2, 0.5 * t), ys, np.full(2, t + 0.5 * (v["height"] - t))], axis=1)
    return base, upright


def exact_volume(v: dict) -> float:
    """The bracket's volume in mm^3: the two plates (sharing the corner block) minus four holes."""
    t, w, l, h, d = (v[k] for k in ("thickness", "width", "length", "height", "hole"))
    plates = l * w * t + (h - t) * w * t
    return plates - 4 * np.pi * (0.5 * d) ** 2 * t


def volume_tolerance(v: dict) -> float:
    """Bound on ``|mesh volume - exact_volume|`` in mm^3 from the chordal tolerance.

    The planar faces are exact; each hole's wall is a polygon inscribed in its
    circle (vertices on the exact cylinder, edges within ``tolerance`` of it),
    whose area falls short of the disk by less than perimeter x tolerance, over
    the plate thickness. Plus a rounding allowance.
    """
    t, d = v["thickness"], v["hole"]
    return 4 * np.pi * d * v["tolerance"] * t + 1e-9 * exact_volume(v)


def build(**params) -> Model:
    """The bracket as one closed triangle mesh (``mesh``), no exact bodies.

    Checks: ``"volume"`` (mm^3): the closed-form volume, within the
    tessellation bound of :func:`volume_tolerance`; ``"euler_characteristic"``:
    -6 (a closed surface of genus 4, one handle per hole).
    """
    v = resolve_params(NAME, PARAMETERS, params)
    _check_fit(v)
    t, w, l, h, d, tol = (v[k] for k in ("thickness", "width", "length", "height", "hole", "tolerance"))
    base_plate = box_patches([0.0, 0.0, 0.0], [l, w, t])
    upright = box_patches([0.0, 0.0, t], [t, w, h])
    margin = max(1.0, t)  # the drills stick out of both sides of their plate
    base_holes, upright_holes = hole_centres(v)
    drills = [
        cylinder_patches(c - [0.0, 0.0, 0.5 * t + margin], [0.0, 0.0, 1.0], 0.5 * d, t + 2 * margin)
        for c in base_holes
    ] + [
        cylinder_patches(c - [0.5 * t + margin, 0.0, 0.0], [1.0, 0.0, 0.0], 0.5 * d, t + 2 * margin)
        for c in upright_holes
    ]
    # the upright's box sits on the base plate's top face: union them as meshes
    plates = union(base_plate, upright, tolerance=tol)
    mesh = difference(plates, union_all(drills, tolerance=tol), tolerance=tol)
    return Model(
        name=NAME,
        params=v,
        bodies=[],
        body_names=[],
        mesh=mesh,
        closed=True,
        checks={"volume": (exact_volume(v), volume_tolerance(v)), "euler_characteristic": (-6, 0)},
    )
