"""A tapered, twisted wing lofted through NACA 4-digit sections, closed by flat tip caps.

Units: millimetres and degrees. The wing spans ``span`` along +y from the
root (y = 0); the chord shrinks linearly from ``root_chord`` to
``taper * root_chord`` and the sections turn about the straight quarter-chord
line by a twist growing linearly from 0 at the root to ``twist`` at the tip
(negative = washout, leading edge down). Each section is a NACA 4-digit
airfoil (``camber`` percent at ``camber_position`` of the chord,
``thickness`` percent, closed trailing edge) whose upper and lower halves are
cubic B-splines interpolated through cosine-spaced points, with the leading
edge tangent imposed so the two halves meet smoothly. The halves are lofted
(:func:`splinekit.construct.loft`) into an upper and a lower skin, and each
end section is closed by the planar ruled face between its halves: four
exact faces bounding one solid.
"""

from __future__ import annotations

import numpy as np

from splinekit import interpolate_curve, loft, ruled

from ._base import INTEGRAL_TOLERANCE, Model, Parameter, resolve_params, surface_integrals

NAME = "wing"

PARAMETERS = (
    Parameter("span", 300.0, "mm", 50.0, 2000.0, "length of the wing along y"),
    Parameter("root_chord", 120.0, "mm", 20.0, 500.0, "chord at the root"),
    Parameter("taper", 0.5, "", 0.2, 1.0, "tip chord / root chord"),
    Parameter("twist", -3.0, "deg", -10.0, 10.0, "twist of the tip section (negative: leading edge down)"),
    Parameter("thickness", 12.0, "%", 6.0, 24.0, "maximum thickness, percent of the chord"),
    Parameter("camber", 2.0, "%", 0.0, 6.0, "maximum camber, percent of the chord"),
    Parameter("camber_position", 0.4, "", 0.2, 0.7, "chordwise position of the maximum camber (fraction)"),
    Parameter("sections", 5, "", 2, 9, "number of airfoil sections lofted root to tip", kind=int),
)

_POINTS = 25  # data points per half section, leading and trailing edge included

# NACA 4-digit half-thickness coefficients, last one for a closed trailing edge
_THICKNESS = (0.2969, -0.1260, -0.3516, 0.2843, -0.1036)


def half_thickness(x: np.ndarray, t: float) -> np.ndarray:
    """NACA half thickness ``y_t(x)`` for thickness ratio ``t`` at chord fractions ``x`` in [0, 1]."""
    a0, a1, a2, a3, a4 = _THICKNESS
    return 5.0 * t * (a0 * np.sqrt(x) + x * (a1 + x * (a2 + x * (a3 + x * a4))))


def camber_line(x: np.ndarray, m: float, p: float) -> tuple[np.ndarray, np.ndarray]:
    """NACA mean line ``y_c(x)`` and its slope for camber ratio ``m`` at position ``p``."""
    front = x < p
    k = np.where(front, m / p**2, m / (1.0 - p) ** 2)
    yc = np.where(front, k * (2 * p * x - x**2), k * ((1 - 2 * p) + 2 * p * x - x**2))
    return yc, 2.0 * k * (p - x)


def airfoil_halves(t: float, m: float, p: float, n: int = _POINTS):
    """Upper and lower surface points ``(n, 2)`` (chord fraction, height), each from trailing to leading edge.

    Also returns the unit tangent ``(2,)`` with which the upper half arrives at
    the leading edge (the lower half arrives with its opposite).
    """
    beta = np.linspace(np.pi, 0.0, n)
    x = 0.5 * (1.0 - np.cos(beta))  # cosine spacing: dense at both edges, from x = 1 to x = 0
    yt = half_thickness(x, t)
    yc, slope = camber_line(x, m, p)
    theta = np.arctan(slope)
    s, c = np.sin(theta), np.cos(theta)
    upper = np.stack([x - yt * s, yc + yt * c], axis=1)
    lower = np.stack([x + yt * s, yc - yt * c], axis=1)
    theta0 = theta[-1]
    return upper, lower, np.array([np.sin(theta0), -np.cos(theta0)])


def _section_frames(v: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per section: spanwise position ``y``, chord and twist (radians)."""
    f = np.linspace(0.0, 1.0, v["sections"])
    chord = v["root_chord"] * (1.0 + (v["taper"] - 1.0) * f)
    return v["span"] * f, chord, np.radians(v["twist"]) * f


def _placed(points: np.ndarray, y: float, chord: float, twist: float, quarter: float) -> np.ndarray:
    """Airfoil points ``(n, 2)`` in chord units -> 3-D ``(n, 3)``: scaled, turned about the quarter chord."""
    x = points[:, 0] * chord - 0.25 * chord
    z = points[:, 1] * chord
    c, s = np.cos(twist), np.sin(twist)
    # positive twist raises the leading edge (x < quarter chord): a rotation about +y by -twist
    return np.stack([quarter + c * x + s * z, np.full(len(x), y), -s * x + c * z], axis=1)


def _half_curve(points3: np.ndarray, le_tangent3: np.ndarray):
    """The cubic through one half section's 3-D points, arriving at the leading edge along ``le_tangent3``.

    Every half of every section uses the same data parameters (uniform in the
    cosine-spacing angle), hence the same knots: the lofts need no knot
    insertion, and the caps' edges are cut into the same Bézier pieces as the
    skins' edges, which lets a tessellator stitch them.
    """
    length = float(np.linalg.norm(np.diff(points3, axis=0), axis=1).sum())
    parameters = np.linspace(0.0, 1.0, len(points3))
    return interpolate_curve(points3, degree=3, parameters=parameters, end_tangent=length * le_tangent3)


def sections(v: dict) -> tuple[list, list]:
    """The upper and lower half curves of every section, root first (each from trailing to leading edge)."""
    upper, lower, tangent = airfoil_halves(0.01 * v["thickness"], 0.01 * v["camber"], v["camber_position"])
    quarter = 0.25 * v["root_chord"]
    ups, lows = [], []
    for y, chord, twist in zip(*_section_frames(v)):
        t3 = _placed(np.vstack([tangent, [0.0, 0.0]]), 0.0, 1.0, twist, 0.0)
        direction = t3[0] - t3[1]  # a direction: the placement's translation cancels
        direction /= np.linalg.norm(direction)
        ups.append(_half_curve(_placed(upper, y, chord, twist, quarter), direction))
        lows.append(_half_curve(_placed(lower, y, chord, twist, quarter), -direction))
    return ups, lows


def build(**params) -> Model:
    """The wing as four exact faces (one closed body ``"wing"``).

    Checks: ``"volume"`` (mm^3) by divergence-theorem quadrature of the faces
    and ``"area"`` (mm^2), both adaptive (tolerance 1e-9 relative), ``"faces"`` = 4.
    """
    v = resolve_params(NAME, PARAMETERS, params)
    ups, lows = sections(v)
    stations = np.linspace(0.0, 1.0, len(ups))  # one spanwise parametrization for both skins
    degree = min(3, len(ups) - 1)
    upper_skin = loft(ups, degree, parameters=stations)
    lower_skin = loft(lows, degree, parameters=stations)
    root_cap = ruled(ups[0], lows[0])
    tip_cap = ruled(ups[-1], lows[-1])
    # S_u x S_v outward: u runs toward the leading edge (-x), v spanwise (+y) on the skins and
    # from the upper to the lower half (-z) on the caps
    faces = [upper_skin.reverse("u"), lower_skin, root_cap, tip_cap.reverse("u")]
    area, volume = surface_integrals(faces)
    return Model(
        name=NAME,
        params=v,
        bodies=[faces],
        body_names=["wing"],
        mesh=None,
        closed=True,
        checks={
            "volume": (volume, INTEGRAL_TOLERANCE * abs(volume)),
            "area": (area, INTEGRAL_TOLERANCE * area),
            "faces": (4, 0),
        },
    )
