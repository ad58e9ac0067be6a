"""A vase: an interpolated profile revolved into an exact, shelled NURBS solid.

Units: millimetres. The outer profile is a cubic B-spline interpolated
(:func:`splinekit.fit.interpolate_curve`) through seven points whose radii
follow a base, a belly of radius ``radius``, a neck of ``neck * radius`` and a
flared lip; the inner profile is interpolated through points of the outer
profile moved inward along its normal by ``wall``. Revolving about the z axis
(:func:`splinekit.construct.revolve`) the five pieces of the closed
cross-section (outer base disk, outer wall, flat rim ring, inner wall, inner
floor disk at height ``base``) gives five exact rational faces that close up
into one solid with outward normals ``S_u x S_v``. The wall is ``wall`` thick
(to a few percent) along the sides; where it meets the floor the inner
corner is placed by a horizontal offset, so on squat, wide vases the
thickness there can drop to about 0.7 ``wall``.
"""

from __future__ import annotations

import numpy as np

from splinekit import interpolate_curve, line, revolve
from splinekit.errors import ParameterError

from ._base import INTEGRAL_TOLERANCE, Model, Parameter, gauss_nodes, resolve_params, surface_integrals

NAME = "vase"

PARAMETERS = (
    Parameter("height", 160.0, "mm", 40.0, 600.0, "overall height"),
    Parameter("radius", 45.0, "mm", 15.0, 200.0, "outer radius of the belly"),
    Parameter("neck", 0.55, "", 0.3, 0.95, "neck radius as a fraction of the belly radius"),
    Parameter("wall", 2.5, "mm", 0.5, 6.0, "wall thickness, measured along the profile normal"),
    Parameter("base", 6.0, "mm", 1.0, 20.0, "thickness of the bottom"),
)

# heights (fractions of ``height``) of the profile points; their radii are set in _outer_points
_HEIGHTS = np.array([0.0, 0.12, 0.3, 0.5, 0.7, 0.85, 1.0])
_Z_AXIS = np.array([0.0, 0.0, 1.0])


def _outer_points(height: float, radius: float, neck: float) -> np.ndarray:
    """The seven outer profile points ``(7, 3)`` in the xz-plane (x = radius), bottom to top."""
    fractions = np.array([0.62, 0.9, 1.0, 0.88, 0.5 * (0.88 + neck), neck, neck + 0.12])
    zeros = np.zeros_like(_HEIGHTS)
    return np.stack([radius * fractions, zeros, height * _HEIGHTS], axis=1)


def _profile_normals(curve, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(n, 3)`` of the profile and their unit normals pointing away from the axis side.

    The profile runs upward, so the tangent turned clockwise in the xz-plane,
    ``(t_z, 0, -t_x)``, points outward (away from the material's inside).
    """
    d = curve.derivatives(u, 1)
    t = d[1] / np.linalg.norm(d[1], axis=1, keepdims=True)
    return d[0], np.stack([t[:, 2], np.zeros(len(u)), -t[:, 0]], axis=1)


def _radius_at(curve, z: float) -> tuple[float, float]:
    """The profile's radius where it crosses height ``z`` and the radial part of its normal there."""
    a, b = curve.domain
    u = np.linspace(a, b, 2001)
    points = curve.evaluate(u)
    k = int(np.searchsorted(points[:, 2], z))  # the outer profile rises monotonically
    k = min(max(k, 1), len(u) - 1)
    s = (z - points[k - 1, 2]) / (points[k, 2] - points[k - 1, 2])
    uz = u[k - 1] + s * (u[k] - u[k - 1])
    p, n = _profile_normals(curve, np.array([uz]))
    return float(p[0, 0]), float(n[0, 0])


def profiles(height, radius, neck, wall, base):
    """``(outer, inner)`` profile curves (cubic B-splines in the xz-plane, both running upward).

    The inner one starts on the floor (z = ``base``) and ends on the rim plane (z = ``height``).
    """
    outer = interpolate_curve(_outer_points(height, radius, neck), degree=3)
    a, b = outer.domain
    u = np.linspace(a, b, 25)[1:-1]
    points, normals = _profile_normals(outer, u)
    moved = points - wall * normals
    # keep offset points clear of the floor and the rim plane, then end exactly on both
    keep = (moved[:, 2] > base + 2.0 * wall) & (moved[:, 2] < height - 2.0 * wall)
    r_floor, nr_floor = _radius_at(outer, base)
    top, top_normal = _profile_normals(outer, np.array([b]))
    # on the rim plane: the offset of the end point, slid along the end tangent to z = height
    tangent = np.array([-top_normal[0, 2], 0.0, top_normal[0, 0]])
    q = top[0] - wall * top_normal[0]
    q = q + (height - q[2]) / tangent[2] * tangent
    start = np.array([r_floor - wall / max(nr_floor, 1e-3), 0.0, base])
    inner = interpolate_curve(np.vstack([start, moved[keep], q]), degree=3)
    return outer, inner


def _pappus_volume(outer, inner, order: int = 12) -> float:
    """Volume of the revolved cross-section by Green's theorem, ``pi * closed integral of r^2 dz``.

    Only the two walls contribute (the base, floor and rim are horizontal);
    the loop runs up the outer wall and down the inner one. Gauss-Legendre
    on every span of the curves: exact for these polynomial profiles.
    """
    total = 0.0
    for curve, sign in ((outer, 1.0), (inner, -1.0)):
        u, weights = gauss_nodes(curve.bezier_breakpoints(), order)
        d = curve.derivatives(u, 1)
        total += sign * float(weights @ (d[0][:, 0] ** 2 * d[1][:, 2]))
    return np.pi * total


def build(**params) -> Model:
    """Five revolved NURBS faces bounding the vase (one closed body ``"vase"``).

    Checks: ``"volume"`` (mm^3) by Green's theorem on the profiles (Pappus),
    ``"area"`` (mm^2) by adaptive quadrature of the faces (both to 1e-9
    relative), ``"faces"`` = 5. Raises ParameterError when ``wall`` is too thick for the
    narrowest radius or ``base`` too thick for the height.
    """
    v = resolve_params(NAME, PARAMETERS, params)
    height, radius, neck, wall, base = (v[k] for k in ("height", "radius", "neck", "wall", "base"))
    narrowest = radius * min(0.62, neck)
    if wall > 0.4 * narrowest:
        raise ParameterError(
            f"parameter 'wall' = {wall:g}: expected at most {0.4 * narrowest:g} mm "
            f"(40% of the narrowest radius {narrowest:g} mm)"
        )
    if base > 0.25 * height:
        raise ParameterError(
            f"parameter 'base' = {base:g}: expected at most {0.25 * height:g} mm (a quarter of the height)"
        )
    outer, inner = profiles(height, radius, neck, wall, base)
    p0, p1 = outer.evaluate(np.array(outer.domain))
    q0, q1 = inner.evaluate(np.array(inner.domain))
    pieces = [
        line(np.zeros(3), p0),  # outer base disk, from the axis outward
        outer,  # up the outside
        line(p1, q1),  # rim ring, inward
        inner.reverse(),  # down the inside
        line(q0, np.array([0.0, 0.0, base])),  # floor disk, inward to the axis
    ]
    faces = [revolve(c, np.zeros(3), _Z_AXIS) for c in pieces]
    volume = _pappus_volume(outer, inner)
    area, _ = surface_integrals(faces)
    return Model(
        name=NAME,
        params=v,
        bodies=[faces],
        body_names=["vase"],
        mesh=None,
        closed=True,
        checks={
            "volume": (volume, INTEGRAL_TOLERANCE * volume),
            "area": (area, INTEGRAL_TOLERANCE * area),
            "faces": (5, 0),
        },
    )
