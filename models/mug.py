"""A mug: a Catmull-Clark cage of quads with a handle (genus 1) and a creased rim.

Units: millimetres. The cage has eight columns around the z axis: outer
wall, rim, inner wall and floor, closed at the bottom and on the floor by four
quads each, and a handle of square section that leaves the outer wall at one
face and comes back at another (so the surface is a torus: Euler
characteristic 0). The two rim rings carry semi-sharp crease sharpness
``sharpness`` (0 is smooth; the rim stays sharp for that many subdivision
steps, then smooths out; 10 is OpenSubdiv's "infinitely sharp").

The cage is subdivided ``levels`` times uniformly (creases carried along),
then ``SubdivisionSurface.to_bsplines(0)`` turns every face of the refined
mesh into one bicubic patch: exact on regular faces, a Coons patch of exact
or limit-interpolating boundary cubics near extraordinary vertices. Refining
first (rather than only around extraordinary vertices) keeps every patch
edge shared whole by two patches, with no T-junctions, so the patch set both
sews into one OCC solid and tessellates into a closed mesh.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from splinekit import PolyMesh, SubdivisionSurface
from splinekit.subdiv import Refinement

from ._base import INTEGRAL_TOLERANCE, Model, Parameter, resolve_params, surface_integrals

NAME = "mug"

PARAMETERS = (
    Parameter("size", 90.0, "mm", 30.0, 300.0, "height of the cage (the limit surface is a little smaller)"),
    Parameter("handle", 0.32, "", 0.15, 0.6, "how far the handle reaches out, as a fraction of size"),
    Parameter("sharpness", 2.0, "", 0.0, 10.0, "Catmull-Clark crease sharpness of the two rim rings"),
    Parameter("levels", 1, "", 0, 2, "uniform subdivision steps before the conversion to patches", kind=int),
)

_N = 8  # columns around the axis
# the closed cross-section loop (fractions of size): up the outside, over the rim, down the inside
_OUTER = [(0.40, 0.0), (0.42, 0.08), (0.42, 0.22), (0.42, 0.36), (0.42, 0.64), (0.42, 0.78), (0.42, 0.92), (0.42, 1.0)]
_INNER = [(0.36, 1.0), (0.36, 0.92), (0.36, 0.6), (0.36, 0.25), (0.34, 0.1)]
_LOW, _HIGH = 2, 4  # the handle replaces the outer faces of column 0 starting at these rings
_RIM = (len(_OUTER) - 1, len(_OUTER))  # ring numbers of the rim's outer and inner edge
_SECTIONS = 7  # handle sections between the two wall faces (excluded)


def _rings(size: float) -> np.ndarray:
    """Cage vertices of the rings ``(rings, N, 3)``; column 0 is centred on the +x axis."""
    loop = np.array(_OUTER + _INNER) * size
    theta = (np.arange(_N) - 0.5) * 2.0 * np.pi / _N
    c, s = np.cos(theta), np.sin(theta)
    return np.stack(
        [loop[:, :1] * c, loop[:, :1] * s, np.broadcast_to(loop[:, 1:], (len(loop), _N))], axis=-1
    )


def _cap(center: int, ring: np.ndarray) -> list:
    """Four quads closing an 8-vertex ring around ``center`` (a 2 x 2 grid), oriented like the ring."""
    return [[center, ring[2 * m], ring[2 * m + 1], ring[(2 * m + 2) % _N]] for m in range(4)]


def _handle_sections(size: float, reach: float, ring_points: np.ndarray) -> np.ndarray:
    """Corner points ``(_SECTIONS, 4, 3)`` of the handle's inner square sections.

    The handle's centre line is the half ellipse ``x = x0 + a cos(phi)``,
    ``z = zm + b sin(phi)`` for ``phi`` in (-90, 90) degrees, leaving the lower
    attachment face and entering the upper one horizontally. Corners go
    (-y, -n), (+y, -n), (+y, +n), (-y, +n) with ``n`` the in-plane normal,
    matching the attachment faces' corner order.
    """
    low = ring_points[[_LOW, _LOW + 1]][:, [0, 1]]  # (2 rings, 2 columns, 3)
    high = ring_points[[_HIGH, _HIGH + 1]][:, [0, 1]]
    x0 = float(low[..., 0].mean())
    z_low, z_high = float(low[..., 2].mean()), float(high[..., 2].mean())
    zm, b = 0.5 * (z_low + z_high), 0.5 * (z_high - z_low)
    a = reach * size
    phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, _SECTIONS + 2)[1:-1]
    centre = np.stack([x0 + a * np.cos(phi), np.zeros_like(phi), zm + b * np.sin(phi)], axis=1)
    tangent = np.stack([-a * np.sin(phi), np.zeros_like(phi), b * np.cos(phi)], axis=1)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.stack([-tangent[:, 2], np.zeros_like(phi), tangent[:, 0]], axis=1)
    half_w, half_h = 0.07 * size, 0.05 * size
    y = np.array([0.0, 1.0, 0.0])
    signs = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], dtype=float)
    return (
        centre[:, None, :]
        + signs[None, :, 0, None] * half_w * y
        + signs[None, :, 1, None] * half_h * normal[:, None, :]
    )


def cage(size: float = 90.0, handle: float = 0.32) -> tuple[PolyMesh, np.ndarray]:
    """The control cage and its rim edges: ``(PolyMesh of quads, (2 N, 2) vertex pairs)``.

    Faces are counter-clockwise seen from outside.
    """
    rings = _rings(size)
    n_rings = len(rings)
    ids = np.arange(n_rings * _N).reshape(n_rings, _N)
    points = [rings.reshape(-1, 3)]
    faces = []
    for r in range(n_rings - 1):
        for j in range(_N):
            if j == 0 and r in (_LOW, _HIGH):
                continue  # the handle attaches here
            k = (j + 1) % _N
            faces.append([ids[r, j], ids[r, k], ids[r + 1, k], ids[r + 1, j]])
    bottom, floor = n_rings * _N, n_rings * _N + 1
    points.append(np.array([[0.0, 0.0, _OUTER[0][1] * size], [0.0, 0.0, _INNER[-1][1] * size]]))
    faces += [f[::-1] for f in _cap(bottom, ids[0])]  # seen from below
    faces += _cap(floor, ids[-1])  # seen from above (inside the cup)
    # the handle: the lower face's corners, the inner sections, the upper face's corners
    sections = _handle_sections(size, handle, rings)
    first = len(points[0]) + 2
    section_ids = first + np.arange(_SECTIONS * 4).reshape(_SECTIONS, 4)
    points.append(sections.reshape(-1, 3))
    lower = np.array([ids[_LOW, 0], ids[_LOW, 1], ids[_LOW + 1, 1], ids[_LOW + 1, 0]])
    upper = np.array([ids[_HIGH + 1, 0], ids[_HIGH + 1, 1], ids[_HIGH, 1], ids[_HIGH, 0]])
    chain = [lower, *section_ids, upper]
    for s0, s1 in pairwise(chain):
        for i in range(4):
            faces.append([s0[i], s0[(i + 1) % 4], s1[(i + 1) % 4], s1[i]])
    rim = np.concatenate(
        [np.stack([ids[r], np.roll(ids[r], -1)], axis=1) for r in _RIM]
    )
    return PolyMesh(np.vstack(points), np.array(faces)), rim


def _creases(rim: np.ndarray, sharpness: float):
    return (rim, np.full(len(rim), float(sharpness))) if sharpness > 0 else None


def surface(size: float = 90.0, handle: float = 0.32, sharpness: float = 2.0, levels: int = 0) -> SubdivisionSurface:
    """The limit surface of the cage with the rim creased by ``sharpness``, as the
    Catmull-Clark surface of the cage refined ``levels`` times (the same limit surface:
    the refined mesh carries the creases' remaining sharpness)."""
    mesh, rim = cage(size, handle)
    if levels == 0:
        return SubdivisionSurface(mesh, "catmull-clark", creases=_creases(rim, sharpness))
    refinement = Refinement(mesh, "catmull-clark", levels, creases=_creases(rim, sharpness))
    fine = PolyMesh.from_topology(refinement.apply(mesh.vertices), refinement.topologies[-1])
    remaining = refinement.edge_sharpness[-1]  # the creases' sharpness left after ``levels`` steps
    return SubdivisionSurface(fine, "catmull-clark", creases=remaining if remaining.any() else None)


def limit_mesh(size: float = 90.0, handle: float = 0.32, sharpness: float = 2.0, levels: int = 3) -> PolyMesh:
    """A closed quad mesh on the limit surface: the cage refined ``levels`` times
    (with its creases), every vertex moved to its limit position.

    ``134 * 4**levels`` quads, genus 1 like the cage; the vertices lie on the
    exact limit surface and the facets are chords of it.
    """
    limit = surface(size, handle, sharpness, levels)
    return limit.mesh.with_vertices(limit.limit_points())


def build(**params) -> Model:
    """The mug as bicubic patches (one closed body ``"mug"``).

    ``134 * 4**levels`` patches. Checks: ``"euler_characteristic"`` = 0
    (genus 1, of the cage and of the sewn solid's topology), ``"volume"``
    (mm^3) by divergence-theorem quadrature of the patches and ``"area"``
    (mm^2), both adaptive (tolerance 1e-9 relative), ``"faces"``: the number of patches.
    """
    v = resolve_params(NAME, PARAMETERS, params)
    limit = surface(v["size"], v["handle"], v["sharpness"], v["levels"])
    patches, _info = limit.to_bsplines(0)
    area, volume = surface_integrals(patches)
    return Model(
        name=NAME,
        params=v,
        bodies=[patches],
        body_names=["mug"],
        mesh=None,
        closed=True,
        checks={
            "euler_characteristic": (0, 0),  # genus 1: what the cage and any closed mesh of it must have
            "volume": (volume, INTEGRAL_TOLERANCE * abs(volume)),
            "area": (area, INTEGRAL_TOLERANCE * area),
            "faces": (len(patches), 0),
        },
    )
