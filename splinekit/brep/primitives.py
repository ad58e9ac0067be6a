"""Exact primitive solids as B-reps: box, cylinder, cone, sphere, torus and plates with through holes.

Every solid is built from exact NURBS surfaces (bilinear planes, surfaces of revolution of a line,
an arc or a circle, The NURBS Book A8.1) bounded by :class:`~splinekit.brep.Edge` uses that carry
their pcurve, their 3-D curve (same parameter, same direction) and a key shared by the two uses of
one edge. Faces point outward (``reversed=True`` where the surface's ``Su x Sv`` points inward, as
on the wall of a hole). The layout follows OpenCascade's primitives, so the topology counts match
``BRepPrimAPI``: a cylinder has 3 faces, 3 edges (two circles and a seam) and 2 vertices; a sphere
1 face, a seam, two degenerate pole edges and 2 vertices; a torus 1 face, 2 seams and 1 vertex.

Planar faces are parametrized by length: ``(u, v)`` are distances (model units) along two
orthonormal in-plane axes, so a circular hole is a circle in ``(u, v)`` too. Periodic faces run
over ``[0, 1] x [0, 1]``: ``u`` around the axis (counter-clockwise about it, starting at
``x_axis``), ``v`` along the profile.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..construct import arc, circle, line, revolve
from ..construct._checks import as_positive, as_unit, as_vector, perpendicular
from ..curves import NurbsCurve
from ..errors import ParameterError
from ..surfaces import BSplineSurface
from .edge import Edge
from .face import TrimmedFace
from .shell import Shell, Solid

__all__ = ["box", "cylinder", "cone", "sphere", "torus", "plate_with_holes", "box_with_hole"]

_serial = itertools.count()


def _keys():
    """A fresh namespace for the edge keys of one solid: ``key(*parts)`` -> a tuple unique to it."""
    token = next(_serial)
    return lambda *parts: ("primitive", token) + parts


def _frame(axis, x_axis):
    """Orthonormal ``(X, Y, Z)`` with ``Z`` along ``axis`` and ``X`` along ``x_axis`` projected."""
    Z = as_unit(axis, "axis")
    if x_axis is None:
        X = perpendicular(Z)
    else:
        X = as_vector(x_axis, "x_axis", (3,))
        X = X - np.dot(X, Z) * Z
        n = float(np.linalg.norm(X))
        if not n > 1e-12 * max(1.0, float(np.linalg.norm(x_axis))):
            raise ParameterError(f"x_axis = {np.asarray(x_axis).tolist()} is parallel to the axis")
        X = X / n
    return X, np.cross(Z, X), Z


# -- planar faces --------------------------------------------------------------------------------
class _Circle:
    """A circular edge of a planar face: centre, radius, seam direction, sense about the face's
    outward normal (``ccw``) and its key."""

    def __init__(self, center, radius, x_axis, ccw, key):
        self.center, self.radius, self.x_axis, self.ccw, self.key = center, radius, x_axis, ccw, key


def _planar_face(normal, loops, name):
    """A planar face, outward ``normal``; ``loops`` (outer first) are lists of edge specs:
    ``(p, q, key)`` straight edges from 3-D point ``p`` to ``q``, or one :class:`_Circle`.

    The surface is the bilinear patch covering the loops' extent, parametrized by length along
    ``ex, ey`` with ``ex x ey = normal``; every pcurve's 3-D curve is its exact affine image.
    """
    n = as_unit(normal, "normal")
    first = loops[0][0]
    if isinstance(first, _Circle):
        o, ex = first.center, first.x_axis
    else:
        o, ex = np.asarray(first[0], float), np.asarray(first[1], float) - np.asarray(first[0], float)
    ex = ex - np.dot(ex, n) * n
    ex = ex / np.linalg.norm(ex)
    ey = np.cross(n, ex)

    def to_uv(p):
        d = np.asarray(p, float) - o
        return np.array([d @ ex, d @ ey])

    # the patch spans the loops' bounding box in (u, v)
    ext = []
    for lp in loops:
        for e in lp:
            if isinstance(e, _Circle):
                c = to_uv(e.center)
                ext += [c - e.radius, c + e.radius]
            else:
                ext += [to_uv(e[0]), to_uv(e[1])]
    ext = np.array(ext)
    (u0, v0), (u1, v1) = ext.min(axis=0), ext.max(axis=0)
    corners = np.array([[o + a * ex + b * ey for b in (v0, v1)] for a in (u0, u1)])
    surface = BSplineSurface(1, 1, [u0, u0, u1, u1], [v0, v0, v1, v1], corners)

    edges = []
    for lp in loops:
        out = []
        for e in lp:
            if isinstance(e, _Circle):
                x2 = to_uv(e.center + e.x_axis) - to_uv(e.center)
                pc = circle(to_uv(e.center), None, e.radius, x_axis=x2)
                if not e.ccw:
                    pc = pc.reverse()
                P = o + pc.control_points[:, :1] * ex + pc.control_points[:, 1:] * ey
                out.append(Edge(pc, NurbsCurve(pc.degree, pc.knots, P, pc.weights), key=e.key))
            else:
                p, q, key = e
                out.append(Edge(line(to_uv(p), to_uv(q)), line(p, q), key=key))
        edges.append(out)
    return TrimmedFace(surface, edges, name=name)


def _polygon_loop(points, key, ids):
    """Straight edge specs around ``points`` (3-D, in loop order); keys from vertex ``ids``."""
    m = len(points)
    return [(points[i], points[(i + 1) % m], key("line", *sorted((ids[i], ids[(i + 1) % m])))) for i in range(m)]


def box(dx, dy, dz, origin=(0.0, 0.0, 0.0), *, name: str | None = "box") -> Solid:
    """Axis-aligned box ``[ox, ox + dx] x [oy, oy + dy] x [oz, oz + dz]`` (``origin`` = the min
    corner, as OpenCascade's ``BRepPrimAPI_MakeBox``): 6 planar faces, 12 edges, 8 vertices."""
    return plate_with_holes(dx, dy, dz, (), origin=origin, name=name)


def plate_with_holes(dx, dy, dz, holes=(), origin=(0.0, 0.0, 0.0), *, name: str | None = "plate") -> Solid:
    """A box with vertical (``z``) cylindrical through holes.

    Parameters
    ----------
    dx, dy, dz : float > 0
        Sizes; ``origin`` is the min corner.
    holes : sequence of ``(x, y, radius)``
        Hole axes at ``(x, y)`` measured from ``origin``; each hole must lie strictly inside the
        plate's ``x, y`` extent and not touch another hole (checked).

    The top and bottom faces carry one clockwise inner loop per hole; each hole's wall is a
    cylindrical face (reversed: its outward normal points at the hole's axis) with a seam on the
    ``+x`` side.
    """
    sx, sy, sz = (as_positive(v, n) for v, n in ((dx, "dx"), (dy, "dy"), (dz, "dz")))
    o = as_vector(origin, "origin", (3,))
    hs = []
    for i, h in enumerate(holes):
        try:
            x, y, r = (float(t) for t in h)
        except (TypeError, ValueError):
            raise ParameterError(f"hole {i} must be (x, y, radius), got {h!r}") from None
        if not (r > 0 and r < x < sx - r and r < y < sy - r):
            raise ParameterError(f"hole {i} = ({x!r}, {y!r}, radius {r!r}) does not lie strictly inside the {sx!r} x {sy!r} plate")
        for j, (x2, y2, r2) in enumerate(hs):
            if np.hypot(x - x2, y - y2) <= r + r2:
                raise ParameterError(f"holes {j} and {i} touch or overlap")
        hs.append((x, y, r))
    key = _keys()
    # vertices i + 2 j + 4 k at o + (i dx, j dy, k dz)
    V = np.array([o + [i * sx, j * sy, k * sz] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    quads = {  # vertex ids counter-clockwise seen from outside, outward normal
        "bottom": ([0, 2, 3, 1], (0, 0, -1)),
        "top": ([4, 5, 7, 6], (0, 0, 1)),
        "front": ([0, 1, 5, 4], (0, -1, 0)),
        "back": ([2, 6, 7, 3], (0, 1, 0)),
        "left": ([0, 4, 6, 2], (-1, 0, 0)),
        "right": ([1, 3, 7, 5], (1, 0, 0)),
    }
    X = np.array([1.0, 0.0, 0.0])
    faces = []
    for face_name, (ids, normal) in quads.items():
        loops = [_polygon_loop(V[ids], key, ids)]
        if face_name in ("top", "bottom"):
            z = sz if face_name == "top" else 0.0
            # seen from outside the top face the hole's loop runs clockwise; from below, the same
            # circle runs the other way round about +z, i.e. clockwise about -z
            loops += [[_Circle(o + [x, y, z], r, X, False, key("hole", i, face_name))] for i, (x, y, r) in enumerate(hs)]
        faces.append(_planar_face(normal, loops, face_name))
    for i, (x, y, r) in enumerate(hs):
        wall = _revolved_line_face(o + [x + r, y, 0.0], o + [x + r, y, sz], o + [x, y, 0.0], [0.0, 0.0, 1.0],
                                   key, (("hole", i, "bottom"), ("hole", i, "top"), ("seam", i)),
                                   reversed=True, name=f"hole {i}")
        faces.append(wall)
    return Solid(Shell(faces, name=name), name=name)


def box_with_hole(size, hole_radius, center=(0.0, 0.0, 0.0), *, name: str | None = "box_with_hole") -> Solid:
    """A cube of edge ``size`` centred at ``center`` with a through hole of ``hole_radius`` along
    ``z`` on its axis (build123d's ``Box(s, s, s) - Cylinder(r, s)``): volume ``s^3 - pi r^2 s``."""
    s = as_positive(size, "size")
    r = as_positive(hole_radius, "hole_radius")
    c = as_vector(center, "center", (3,))
    if not r < s / 2:
        raise ParameterError(f"hole_radius = {r!r} must be smaller than half the size ({s / 2!r})")
    return plate_with_holes(s, s, s, [(s / 2, s / 2, r)], origin=c - s / 2, name=name)


# -- surfaces of revolution --------------------------------------------------------------------
def _revolved_line_face(p0, p1, axis_origin, axis, key, keys, *, reversed=False, name=None):
    """The surface swept by the segment ``p0 -> p1`` turning about the axis (u around, v along the
    segment), bounded by its two circles (``keys[0]`` at ``p0``, ``keys[1]`` at ``p1``; a circle
    of radius 0 is a degenerate edge) and the seam (``keys[2]``) in the plane of the segment."""
    surface = revolve(line(p0, p1), axis_origin, axis)
    return _periodic_face(surface, key, keys, reversed=reversed, name=name)


def _periodic_face(surface, key, keys, *, closed_v=False, reversed=False, name=None):
    """The face of a surface of revolution on ``[0, 1]^2`` with one counter-clockwise loop:
    ``v = 0`` edge, seam ``u = 1``, ``v = 1`` edge backwards, seam ``u = 0`` backwards.

    ``keys = (key_v0, key_v1, key_seam)``; a ``v`` side whose 3-D image is a point becomes a
    degenerate edge (no curve, no key). ``closed_v``: the ``v = 0`` and ``v = 1`` sides are the same
    circle (a torus), keyed ``key_v0``.
    """
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    kv0, kv1, kseam = keys
    if closed_v:
        kv1 = kv0
    sides = [("v", 0.0, kv0), ("u", 1.0, kseam), ("v", 1.0, kv1), ("u", 0.0, kseam)]
    edges = []
    for k, (d, value, kk) in enumerate(sides):
        a, b = corners[k], corners[(k + 1) % 4]
        pc = line(a, b)
        iso = surface.isocurve(v=value) if d == "v" else surface.isocurve(u=value)
        if k >= 2:  # these sides run against the isocurve's parameter
            iso = iso.reverse()
        pts = iso.control_points
        if np.ptp(pts, axis=0).max() <= 1e-12 * max(1.0, float(np.abs(pts).max())):
            edges.append(Edge(pc, degenerate=True))
        else:
            edges.append(Edge(pc, iso, key=key(*kk) if isinstance(kk, tuple) else key(kk)))
    return TrimmedFace(surface, [edges], reversed, name=name)


def cone(radius1, radius2, height, origin=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), *, x_axis=None,
         name: str | None = "cone") -> Solid:
    """A (truncated) circular cone: radius ``radius1`` at ``origin``, ``radius2`` at
    ``origin + height * axis`` (one of them may be 0: an apex, a degenerate edge), as
    ``BRepPrimAPI_MakeCone``. The seam lies on the ``x_axis`` side (default a fixed perpendicular
    of the axis). ``radius1 == radius2`` gives a cylinder."""
    r1 = float(radius1)
    r2 = float(radius2)
    if not (np.isfinite(r1) and np.isfinite(r2) and r1 >= 0 and r2 >= 0 and (r1 > 0 or r2 > 0)):
        raise ParameterError(f"cone radii must be >= 0, finite and not both 0, got {radius1!r}, {radius2!r}")
    h = as_positive(height, "height")
    o = as_vector(origin, "origin", (3,))
    X, Y, Z = _frame(axis, x_axis)
    key = _keys()
    top = o + h * Z
    side = _revolved_line_face(o + r1 * X, top + r2 * X, o, Z, key, ("bottom", "top", "seam"), name="side")
    faces = [side]
    if r1 > 0:
        faces.append(_planar_face(-Z, [[_Circle(o, r1, X, True, key("bottom"))]], "bottom"))
    if r2 > 0:
        faces.append(_planar_face(Z, [[_Circle(top, r2, X, True, key("top"))]], "top"))
    return Solid(Shell(faces, name=name), name=name)


def cylinder(radius, height, origin=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), *, x_axis=None,
             name: str | None = "cylinder") -> Solid:
    """A closed circular cylinder: base centre ``origin``, along ``axis`` (``BRepPrimAPI_MakeCylinder``):
    a lateral face with a seam and two planar caps trimmed by circles; 3 faces, 3 edges, 2 vertices."""
    r = as_positive(radius, "radius")
    return cone(r, r, height, origin, axis, x_axis=x_axis, name=name)


def sphere(radius, center=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), *, x_axis=None, name: str | None = "sphere") -> Solid:
    """A sphere: one face (a semicircle from the south to the north pole revolved about ``axis``),
    a seam meridian on the ``x_axis`` side and two degenerate edges at the poles."""
    r = as_positive(radius, "radius")
    c = as_vector(center, "center", (3,))
    X, Y, Z = _frame(axis, x_axis)
    # the arc's plane normal X x Z makes it run from -Z through +X to +Z, so Su x Sv points outward
    profile = arc(c, np.cross(X, Z), r, -np.pi / 2, np.pi / 2, x_axis=X)
    surface = revolve(profile, c, Z)
    face = _periodic_face(surface, _keys(), ("south", "north", "seam"), name="sphere")
    return Solid(Shell([face], name=name), name=name)


def torus(major_radius, minor_radius, center=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), *, x_axis=None,
          name: str | None = "torus") -> Solid:
    """A ring torus (``major_radius > minor_radius``): one face with two seams (the outer equator
    ``v = 0`` and the meridian ``u = 0``) meeting at one vertex."""
    R = as_positive(major_radius, "major_radius")
    r = as_positive(minor_radius, "minor_radius")
    if not r < R:
        raise ParameterError(f"minor_radius = {r!r} must be smaller than major_radius = {R!r} (a ring torus)")
    c = as_vector(center, "center", (3,))
    X, Y, Z = _frame(axis, x_axis)
    # minor circle in the (X, Z) plane starting outward, turning towards +Z: Su x Sv points outward
    profile = circle(c + R * X, np.cross(X, Z), r, x_axis=X)
    surface = revolve(profile, c, Z)
    face = _periodic_face(surface, _keys(), ("equator", None, "meridian"), closed_v=True, name="torus")
    return Solid(Shell([face], name=name), name=name)
