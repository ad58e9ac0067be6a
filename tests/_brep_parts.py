"""Exact test bodies for the B-rep tests, built with splinekit's own constructors (revolve,
circle, line): spheres, tori, tubes, a box with a through hole, plates with holes.

Each face is oriented by comparing ``Su x Sv`` at the middle of its domain with the outward
direction the builder knows, so no test relies on a constructor's parametrization direction.
"""

from __future__ import annotations

import numpy as np

import splinekit as sk
from splinekit.brep import Shell, Solid, TrimmedFace

Z = np.array([0.0, 0.0, 1.0])


def oriented(surface, loops=(), outward=None, inside=None, name=None) -> TrimmedFace:
    """A face of ``surface`` whose ``reversed`` flag makes its normal point along ``outward``
    (a vector) or away from the point ``inside``, judged at a point of the face: the middle of
    the domain, or the start of the outer loop's first pcurve nudged inside."""
    face = TrimmedFace(surface, loops)
    (a, b), (c, d) = surface.domain
    uv = np.array([0.5 * (a + b), 0.5 * (c + d)])
    if loops:
        pc = face.outer_loop[0].pcurve
        t0, t1 = pc.domain
        der = pc.derivatives(np.array([0.5 * (t0 + t1)]), 1)
        tangent = der[1][0] / np.linalg.norm(der[1][0])
        uv = der[0][0] + 1e-3 * np.array([-tangent[1], tangent[0]])  # material on the left
    n = face.normals(uv[:1], uv[1:])[0]
    point = surface.evaluate(uv[:1], uv[1:])[0]
    direction = outward if outward is not None else point - np.asarray(inside, float)
    return TrimmedFace(surface, loops, reversed=bool(n @ direction < 0), name=name)


def plane(corner, e1, e2):
    """The bilinear patch ``corner + u e1 + v e2`` on ``[0, 1]^2``."""
    corner, e1, e2 = (np.asarray(x, dtype=float) for x in (corner, e1, e2))
    cp = np.array([[corner, corner + e2], [corner + e1, corner + e1 + e2]])
    return sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], cp)


def square_loop():
    """The boundary of ``[0, 1]^2`` counter-clockwise, as four 2-D lines."""
    c = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return [sk.line(c[i], c[(i + 1) % 4]) for i in range(4)]


def circle_loop(center_uv, radius_uv, clockwise=False):
    """A 2-D circle in the (u, v) plane as a one-curve loop (counter-clockwise unless ``clockwise``)."""
    c = sk.circle(np.asarray(center_uv, dtype=float), None, radius_uv)
    return [c.reverse() if clockwise else c]


def sphere(radius=1.0, center=(0.0, 0.0, 0.0)) -> Solid:
    """One untrimmed rational face (poles at both ends of the profile)."""
    center = np.asarray(center, dtype=float)
    profile = sk.arc(center, [0, 1, 0], radius, -np.pi / 2, np.pi / 2, x_axis=[1, 0, 0])
    s = sk.revolve(profile, center, Z)
    return Solid(Shell([oriented(s, inside=center)]))


def torus(major=3.0, minor=1.0, center=(0.0, 0.0, 0.0)) -> Solid:
    center = np.asarray(center, dtype=float)
    tube = sk.circle(center + [major, 0, 0], [0, 1, 0], minor)
    s = sk.revolve(tube, center, Z)
    (a, b), (c, d) = s.domain
    p = s.evaluate(np.array([0.5 * (a + b)]), np.array([0.5 * (c + d)]))[0] - center
    ring = center + major * np.array([p[0], p[1], 0.0]) / np.hypot(p[0], p[1])  # the tube's axis there
    return Solid(Shell([oriented(s, inside=ring)]))


def _cylinder_side(radius, height, base, inward=False):
    base = np.asarray(base, dtype=float)
    s = sk.revolve(sk.line(base + [radius, 0, 0], base + [radius, 0, height]), base, Z)
    (a, b), (c, d) = s.domain
    p = s.evaluate(np.array([0.5 * (a + b)]), np.array([0.5 * (c + d)]))[0]
    radial = p - base
    radial[2] = 0.0
    return oriented(s, outward=-radial if inward else radial)


def tube(outer=3.0, inner=1.0, height=4.0, base=(0.0, 0.0, 0.0)) -> Solid:
    """A cylinder of radius ``outer`` with a coaxial through hole of radius ``inner``: two
    cylindrical faces and two planar annuli trimmed by circles (outer loop and a hole)."""
    base = np.asarray(base, dtype=float)
    faces = [_cylinder_side(outer, height, base), _cylinder_side(inner, height, base, inward=True)]
    for z, up in ((0.0, False), (height, True)):
        corner = base + [-outer, -outer, z]
        s = plane(corner, [2 * outer, 0, 0], [0, 2 * outer, 0])
        loops = [circle_loop((0.5, 0.5), 0.5), circle_loop((0.5, 0.5), inner / (2 * outer), clockwise=True)]
        faces.append(oriented(s, loops, outward=Z if up else -Z))
    return Solid(Shell(faces))


def box_with_hole(size=20.0, radius=4.0) -> Solid:
    """The cube ``[0, size]^3`` minus the cylinder of ``radius`` along z through its centre."""
    a = size
    mid = np.array([a / 2, a / 2, a / 2])
    faces = []
    for axis in range(3):
        e1, e2 = np.eye(3)[(axis + 1) % 3] * a, np.eye(3)[(axis + 2) % 3] * a
        for at in (0.0, a):
            corner = np.eye(3)[axis] * at
            s = plane(corner, e1, e2)
            loops = ()
            if axis == 2:
                loops = [square_loop(), circle_loop((0.5, 0.5), radius / a, clockwise=True)]
            faces.append(oriented(s, loops, inside=mid))
    faces.append(_cylinder_side(radius, a, [a / 2, a / 2, 0.0], inward=True))
    return Solid(Shell(faces))


def plate_with_holes(width=10.0, height=6.0, holes=((0.2, 0.3, 0.1), (0.7, 0.5, 0.15), (0.45, 0.75, 0.05))):
    """A planar ``width x height`` face with circular holes ``(u, v, radius in u units)``.

    The surface maps ``[0, 1]^2`` onto the rectangle, so a circle in (u, v) is an ellipse with
    semi-axes ``r width`` and ``r height`` in space."""
    s = plane([0, 0, 0], [width, 0, 0], [0, height, 0])
    loops = [square_loop()] + [circle_loop((u, v), r, clockwise=True) for u, v, r in holes]
    return TrimmedFace(s, loops)
