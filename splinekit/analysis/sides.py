"""Edge uses as the continuity analysis sees them: a surface, a trimming curve in its ``(u, v)``
plane with the face's material on its left, and the face's orientation.

A B-rep :class:`~splinekit.brep.TrimmedFace` gives its own edge uses; a bare surface (a spline or
Bézier patch, a :class:`~splinekit.SubdivisionPatch`, anything with ``domain``, ``evaluate`` and
``derivatives``) gives the four sides of its natural domain, counter-clockwise, as straight
pcurves. :class:`Trace` is the surface along a pcurve as a curve in space, with the chain-rule
derivatives the closest-point search needs.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, replace

import numpy as np

from ..brep import Edge, TrimmedFace
from ..diffgeom.protocol import SubdivisionPatch, as_surface
from ..errors import ParameterError
from .stacked import points_many

__all__ = ["SIDE_NAMES", "Side", "Trace", "as_patch", "extraordinary_corners", "sides_of", "sides_of_all", "subdivision_info"]

SIDE_NAMES = ("v0", "u1", "v1", "u0")
"""The natural domain's sides in counter-clockwise order: ``v = v0``, ``u = u1``, ``v = v1``, ``u = u0``."""

_PROBE = 9
"""Samples per side that decide whether it collapses to a point."""


@dataclass(frozen=True, eq=False)
class Side:
    """One face's use of an edge.

    ``patch``: index of the face in the caller's list; ``surface``: its parametric surface;
    ``pcurve``: 2-D curve in the surface's ``(u, v)`` plane, material on its left (None for a
    natural side: ``segment`` gives it);
    ``flip``: the face is reversed (its normal is ``-Su x Sv``); ``name``: ``"u0"``... for a
    natural side, else ``"edge <i>"``; ``key``: the B-rep edge key or None; ``tolerance``: model
    units (0 for bare surfaces); ``degenerate``: the side collapses to a point in space;
    ``segment``: ``(start, end)`` uv of a straight natural side, parametrized over ``[0, 1]``
    (evaluated in closed form).
    """

    patch: int
    surface: object
    pcurve: object
    flip: bool
    name: str
    key: object
    tolerance: float
    degenerate: bool
    segment: tuple | None = None

    @property
    def domain(self) -> tuple:
        """The pcurve's parameter range (``(0, 1)`` for a natural side)."""
        return (0.0, 1.0) if self.segment is not None else tuple(self.pcurve.domain)

    def uv(self, t) -> np.ndarray:
        """``(n, 2)`` parameters on the surface at pcurve parameters ``t`` ``(n,)``, clamped into
        the surface's domain (a trim may leave it by rounding)."""
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        if self.segment is not None:  # a natural side: the straight pcurve in closed form
            a, b = self.segment
            uv = a + t[:, None] * (b - a)
        else:
            uv = np.asarray(self.pcurve.evaluate(t), dtype=np.float64).reshape(-1, 2)
        (u0, u1), (v0, v1) = self.surface.domain
        return np.column_stack([np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1)])

    def points(self, t) -> np.ndarray:
        """``(n, 3)`` points of the surface along the side at pcurve parameters ``t``."""
        uv = self.uv(t)
        return np.asarray(self.surface.evaluate(uv[:, 0], uv[:, 1]), dtype=np.float64).reshape(-1, 3)

    def direction(self, t) -> np.ndarray:
        """``(n, 2)``: the pcurve's derivative at ``t``."""
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        if self.segment is not None:
            a, b = self.segment
            return np.broadcast_to(b - a, (t.size, 2)).copy()
        return np.asarray(self.pcurve.derivatives(t, 1), dtype=np.float64).reshape(2, -1, 2)[1]

    def fractions(self, f) -> np.ndarray:
        """Pcurve parameters at fractions ``f`` of its domain."""
        a, b = self.domain
        return a + (b - a) * np.asarray(f, dtype=np.float64)


class Trace:
    """The surface along a side's pcurve, ``C(t) = S(p(t))``, as a curve in space.

    ``evaluate(t)`` ``(n, 3)``; ``derivatives(t, order)`` ``(order + 1, n, 3)`` for order <= 2 by
    the chain rule: ``C' = Su u' + Sv v'``, ``C'' = Suu u'^2 + 2 Suv u' v' + Svv v'^2 + Su u'' + Sv v''``.
    """

    def __init__(self, side: Side):
        self.side = side
        self.domain = tuple(float(x) for x in side.domain)

    def evaluate(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        return self.side.points(t.ravel()).reshape(t.shape + (3,))

    def derivatives(self, t, order: int = 1) -> np.ndarray:
        if order > 2:
            raise ParameterError(f"an edge trace gives derivatives up to order 2, got {order}")
        t = np.asarray(t, dtype=np.float64)
        flat = t.ravel()
        if self.side.segment is not None:  # straight: p' = end - start, p'' = 0
            p = np.zeros((order + 1, flat.size, 2))
            if order >= 1:
                p[1] = self.side.direction(flat)
        else:
            p = np.asarray(self.side.pcurve.derivatives(flat, order), dtype=np.float64).reshape(order + 1, -1, 2)
        uv = self.side.uv(flat)
        d = np.asarray(self.side.surface.derivatives(uv[:, 0], uv[:, 1], order), dtype=np.float64)
        out = np.empty((order + 1, flat.size, 3))
        out[0] = d[0, 0]
        if order >= 1:
            du, dv = p[1, :, :1], p[1, :, 1:]
            out[1] = d[1, 0] * du + d[0, 1] * dv
        if order >= 2:
            ddu, ddv = p[2, :, :1], p[2, :, 1:]
            out[2] = d[2, 0] * du**2 + 2.0 * d[1, 1] * du * dv + d[0, 2] * dv**2 + d[1, 0] * ddu + d[0, 1] * ddv
        return out.reshape((order + 1,) + t.shape + (3,))


def as_patch(obj, what: str):
    """``(surface, flip, tolerance)`` of a TrimmedFace or a bare 3-D parametric surface; a
    ParameterError naming ``what`` for anything else."""
    if isinstance(obj, TrimmedFace):
        return obj.surface, obj.reversed, obj.tolerance
    surface = as_surface(obj, what)
    try:
        (u0, _), (v0, _) = surface.domain
        u0, v0 = float(u0), float(v0)
    except (TypeError, ValueError):
        raise ParameterError(f"{what} must be a parametric surface with domain ((u0, u1), (v0, v1)); "
                             f"{type(obj).__name__} has domain {getattr(obj, 'domain', None)!r}") from None
    net = getattr(surface, "control_points", None)  # splines: no evaluation needed
    dim = np.shape(net)[-1] if net is not None else np.shape(surface.evaluate(np.array([u0]), np.array([v0])))[-1]
    if dim != 3:
        raise ParameterError(f"{what} must be a surface in 3-D space, this one has dim={dim}")
    return surface, False, 0.0


def _natural_sides(index: int, surface) -> list[Side]:
    """The four sides of the natural domain, counter-clockwise (``degenerate`` not yet known)."""
    (u0, u1), (v0, v1) = surface.domain
    corners = np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1]], dtype=np.float64)
    return [Side(index, surface, None, False, SIDE_NAMES[k], None, 0.0, False, (corners[k], corners[(k + 1) % 4]))
            for k in range(4)]


def _with_degeneracy(sides: list) -> list:
    """``sides`` with ``degenerate`` set where a side's probes (:data:`_PROBE` points, evaluated per
    group of surfaces) lie within 1e-9 of the model size of its start."""
    if not sides:
        return sides
    pts = points_many([(s, np.linspace(0.0, 1.0, _PROBE)) for s in sides])
    out = []
    for s, p in zip(sides, pts):
        if not np.isfinite(p).all():
            raise ParameterError(f"surface {s.patch} evaluates to non-finite points on its boundary")
        extent = float(np.linalg.norm(p - p[0], axis=1).max())
        out.append(replace(s, degenerate=extent <= 1e-9 * max(1.0, float(np.abs(p).max()))))
    return out


def sides_of_all(items) -> list[Side]:
    """Every edge use of every face or surface of ``items`` (numbered by position), the natural
    sides of bare surfaces probed for collapse together."""
    faces, natural = [], []
    for i, obj in enumerate(items):
        if isinstance(obj, TrimmedFace):
            faces += sides_of(i, obj)
        else:
            surface, _, _ = as_patch(obj, f"patch {i}")
            natural += _natural_sides(i, surface)
    return faces + _with_degeneracy(natural)


def sides_of(index: int, obj) -> list[Side]:
    """Every edge use of the face or surface ``obj`` (number ``index`` in the caller's list)."""
    if isinstance(obj, TrimmedFace):
        out = []
        for i, e in enumerate(obj.edges):
            if not isinstance(e, Edge):  # pragma: no cover - a TrimmedFace holds Edges only
                continue
            out.append(Side(index, obj.surface, e.pcurve, obj.reversed, f"edge {i}", e.key,
                            max(e.tolerance, obj.tolerance), e.degenerate))
        return out
    surface, _, _ = as_patch(obj, f"patch {index}")
    return _with_degeneracy(_natural_sides(index, surface))


_QUAD_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
"""``(u, v)`` of a Catmull-Clark patch's corners, in the order of its face's vertices."""

_EXTRAORDINARY: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
"""Per SubdivisionSurface: ``(quads (F, 4), extraordinary (V,) bool, limit normals (V, 3) or None)``."""


def subdivision_info(surface):
    """``(quads (F, 4), extraordinary (V,) bool, limit normals (V, 3) or None)`` of a Catmull-Clark
    SubdivisionSurface: the quads its ``evaluate`` addresses, cached per surface."""
    if surface not in _EXTRAORDINARY:
        mesh = surface.mesh
        base = mesh if mesh.is_quad_mesh else surface.refine(1)  # evaluate's quads: the first refinement's
        quads = np.asarray(base.faces, dtype=np.int64).reshape(-1, 4)
        count = np.bincount(quads.ravel(), minlength=base.n_vertices)
        interior = ~np.asarray(base.boundary_vertices, dtype=bool)
        irregular = interior & (count != 4)
        normals = np.asarray(surface.limit_normals()) if base is mesh and mesh.vertices.shape[1] == 3 else None
        _EXTRAORDINARY[surface] = (quads, irregular, normals)
    return _EXTRAORDINARY[surface]


def extraordinary_corners(surface):
    """``(uv (k, 2), normals (k, 3) or None)``: the corners of a Catmull-Clark patch
    (:class:`~splinekit.SubdivisionPatch`) at extraordinary vertices, with their exact limit
    normals when the control mesh is all quads (up to sign); nothing for other surfaces.

    At an extraordinary vertex the patch's parametrization degenerates: its derivatives shrink to
    zero, and the evaluator's normal there is a refined approximation (off by about 1e-3 rad)."""
    if not isinstance(surface, SubdivisionPatch):
        return np.zeros((0, 2)), None
    quads, irregular, normals = subdivision_info(surface.surface)
    corners = quads[surface.face]
    mask = irregular[corners]
    return _QUAD_CORNERS[mask], None if normals is None else normals[corners[mask]]
