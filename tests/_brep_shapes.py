"""Small exact B-rep solids built from splinekit surfaces, for the tessellation tests.

Faces are natural-domain or trimmed spline surfaces; edges carry no keys, so the tessellator
pairs them geometrically (the seams of revolved faces with themselves, circles of caps and holes
with the iso-curves of the cylinders). Each function returns ``(solid, volume, area, genus)`` with
the closed-form volume and area.
"""

from __future__ import annotations

import math

import numpy as np

import splinekit as sk
from splinekit.brep import Shell, Solid, TrimmedFace
from splinekit.construct.curves import line


def _outward(surface, point_outward):
    """``reversed`` flag so that the face's normal at the domain centre points along
    ``point_outward(x)`` (a callable giving an outward direction at a 3-D point)."""
    (u0, u1), (v0, v1) = surface.domain
    u, v = np.array([0.5 * (u0 + u1) + 0.1 * (u1 - u0)]), np.array([0.5 * (v0 + v1) + 0.1 * (v1 - v0)])
    d = surface.derivatives(u, v, 1)
    n = np.cross(d[1, 0, 0], d[0, 1, 0])
    return bool(n @ point_outward(d[0, 0, 0]) < 0)


def sphere(r=1.0):
    profile = sk.arc([0, 0, 0], [0, -1, 0], r, -math.pi / 2, math.pi / 2, x_axis=[1, 0, 0])
    s = sk.revolve(profile, [0, 0, 0], [0, 0, 1])
    face = TrimmedFace(s, reversed=_outward(s, lambda x: x))
    return Solid(Shell([face])), 4 / 3 * math.pi * r**3, 4 * math.pi * r**2, 0


def torus(R=2.0, r=0.6):
    profile = sk.circle([R, 0, 0], [0, -1, 0], r, x_axis=[1, 0, 0])
    s = sk.revolve(profile, [0, 0, 0], [0, 0, 1])

    def out(x):
        c = np.array([x[0], x[1], 0.0])
        return x - R * c / np.linalg.norm(c)

    face = TrimmedFace(s, reversed=_outward(s, out))
    return Solid(Shell([face])), 2 * math.pi**2 * R * r**2, 4 * math.pi**2 * R * r, 1


def plane(o, a, b):
    """Bilinear patch ``o + u a + v b`` on [0, 1]^2 (normal ``a x b``)."""
    o, a, b = (np.asarray(x, dtype=float) for x in (o, a, b))
    return sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.array([[o, o + b], [o + a, o + a + b]]))


def _disk_loop(cx, cy, r, size_x, size_y, x0, y0, hole):
    """A circle of radius ``r`` about ``(cx, cy)`` in the (u, v) plane of a plane patch that maps
    [0, 1]^2 onto [x0, x0 + size_x] x [y0, y0 + size_y] (an ellipse in (u, v) when the patch is
    not square), counter-clockwise, or clockwise for a hole."""
    c = sk.circle([0.0, 0.0], None, 1.0)
    M = np.array([[r / size_x, 0, (cx - x0) / size_x], [0, r / size_y, (cy - y0) / size_y], [0, 0, 1]])
    c = c.transform(M)
    return [c.reverse() if hole else c]


def cylinder(r=1.0, h=3.0):
    side = sk.extrude(sk.circle([0, 0, 0], [0, 0, 1], r, x_axis=[1, 0, 0]), [0, 0, h])
    lateral = TrimmedFace(side, reversed=_outward(side, lambda x: np.array([x[0], x[1], 0.0])))
    top = plane([-r, -r, h], [2 * r, 0, 0], [0, 2 * r, 0])
    bottom = plane([-r, -r, 0], [2 * r, 0, 0], [0, 2 * r, 0])
    faces = [lateral,
             TrimmedFace(top, [_disk_loop(0, 0, r, 2 * r, 2 * r, -r, -r, False)]),
             TrimmedFace(bottom, [_disk_loop(0, 0, r, 2 * r, 2 * r, -r, -r, False)], reversed=True)]  # fmt: skip
    return Solid(Shell(faces)), math.pi * r**2 * h, 2 * math.pi * r * (r + h), 0


def _square_loop():
    c = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    return [line(c[k], c[(k + 1) % 4]) for k in range(4)]


def box_with_holes(sx=20.0, sy=20.0, sz=20.0, holes=((0.0, 0.0, 4.0),)):
    """A box ``[-sx/2, sx/2] x [-sy/2, sy/2] x [0, sz]`` with vertical through holes ``(cx, cy, r)``."""
    x0, y0 = -sx / 2, -sy / 2
    X, Y, Z = np.array([sx, 0, 0]), np.array([0, sy, 0]), np.array([0, 0, sz])
    o = np.array([x0, y0, 0.0])
    faces = [
        None,  # bottom (normal -z: a reversed +z plane), with the holes
        TrimmedFace(plane(o, X, Z)),  # front (y = y0), normal -y
        TrimmedFace(plane(o + X, Y, Z)),  # right, +x
        TrimmedFace(plane(o + Y, Z, X)),  # back, +y
        TrimmedFace(plane(o, Z, Y)),  # left, -x
    ]
    top_loops = [_square_loop()] + [_disk_loop(cx, cy, r, sx, sy, x0, y0, True) for cx, cy, r in holes]
    faces[0] = TrimmedFace(plane(o, X, Y), [_square_loop()] + [_disk_loop(cx, cy, r, sx, sy, x0, y0, True) for cx, cy, r in holes],
                           reversed=True)  # fmt: skip
    faces.append(TrimmedFace(plane(o + Z, X, Y), top_loops))
    for cx, cy, r in holes:
        wall = sk.extrude(sk.circle([cx, cy, 0], [0, 0, 1], r, x_axis=[1, 0, 0]), Z)
        faces.append(TrimmedFace(wall, reversed=not _outward(wall, lambda x: np.array([x[0] - cx, x[1] - cy, 0.0]))))
    volume = sx * sy * sz - sum(math.pi * r * r * sz for _, _, r in holes)
    area = 2 * (sx * sy + sx * sz + sy * sz) + sum(2 * math.pi * r * sz - 2 * math.pi * r * r for _, _, r in holes)
    return Solid(Shell(faces)), volume, area, len(holes)


def plate_with_holes():
    return box_with_holes(40.0, 30.0, 5.0, ((-10.0, -5.0, 4.0), (8.0, 6.0, 5.0), (12.0, -8.0, 2.5)))
