"""Trimmed faces: a surface, its trimming loops in the (u, v) plane and its orientation."""

from __future__ import annotations

from functools import partial

import numpy as np

from ..construct.curves import line
from ..errors import ParameterError
from ..surfaces import BezierSurface, SplineSurface
from .._validate import as_positive
from ..tolerances import INTEGRAL_RTOL
from . import mass
from .check import Checkable, check_face
from .classify import contains_uv
from .edge import DEFAULT_TOLERANCE, Edge
from .topology import TopologyQueries, shell_topology

__all__ = ["TrimmedFace", "as_surface"]


def as_surface(surface, what: str = "surface") -> SplineSurface:
    """``surface`` (a Bézier, B-spline or NURBS surface in 3-D) as a SplineSurface."""
    if isinstance(surface, BezierSurface):
        surface = surface.to_bspline()
    if not isinstance(surface, SplineSurface):
        raise ParameterError(f"{what} must be a Bézier, B-spline or NURBS surface, got {type(surface).__name__}")
    if surface.dim != 3:
        raise ParameterError(f"{what} must have 3-D control points, got {surface.dim}-D")
    return surface


def _as_loop(loop, index: int, tolerance: float) -> tuple[Edge, ...]:
    if isinstance(loop, (Edge,)) or hasattr(loop, "evaluate"):
        raise ParameterError(f"loop {index} must be a list of edges or 2-D curves, got a single {type(loop).__name__}")
    try:
        items = list(loop)
    except TypeError:
        raise ParameterError(f"loop {index} must be a list of edges or 2-D curves, got {type(loop).__name__}") from None
    if not items:
        raise ParameterError(f"loop {index} is empty")
    edges = []
    for j, item in enumerate(items):
        if isinstance(item, Edge):
            edges.append(item)
        else:
            try:
                edges.append(Edge(item, tolerance=tolerance))
            except ParameterError as exc:
                raise ParameterError(f"loop {index}, edge {j}: {exc}") from None
    return tuple(edges)


class TrimmedFace(TopologyQueries, Checkable):
    """A bounded piece of a surface: one outer trimming loop and any number of inner ones (holes).

    Parameters
    ----------
    surface : BezierSurface, BSplineSurface or NurbsSurface (3-D)
        The underlying surface; ``face.surface`` returns it unchanged.
    loops : list of loops, outer first
        Each loop is a closed chain of :class:`Edge` (or plain 2-D curves, turned into edges
        with no 3-D curve), end to end in the ``(u, v)`` plane. The outer loop runs
        counter-clockwise, inner loops clockwise (material on the left). An empty list bounds
        the face by the surface's natural domain.
    reversed : bool
        The face's outward normal is ``-(Su x Sv)`` instead of ``Su x Sv`` (OpenCascade's
        ``TopAbs_REVERSED``). Loops keep their orientation in ``(u, v)``.
    tolerance : float
        Geometric tolerance (model units) for closure and edge checks.
    name : str, optional
        A label (STEP face names, debugging).
    """

    __slots__ = ("_surface", "_loops", "_reversed", "_tolerance", "_name", "_cache")

    def __init__(self, surface, loops=(), reversed: bool = False, *, tolerance: float = DEFAULT_TOLERANCE,
                 name: str | None = None):
        if not isinstance(reversed, (bool, np.bool_)):
            raise ParameterError(f"reversed must be True or False, got {reversed!r}")
        tolerance = as_positive(tolerance, "tolerance")
        if loops is None:
            loops = ()
        try:
            loop_list = list(loops)
        except TypeError:
            raise ParameterError(f"loops must be a list of loops (outer first), got {type(loops).__name__}") from None
        object.__setattr__(self, "_surface", as_surface(surface))
        object.__setattr__(self, "_loops", tuple(_as_loop(lp, i, tolerance) for i, lp in enumerate(loop_list)))
        object.__setattr__(self, "_reversed", bool(reversed))
        object.__setattr__(self, "_tolerance", tolerance)
        object.__setattr__(self, "_name", None if name is None else str(name))
        object.__setattr__(self, "_cache", {})

    def __setattr__(self, name, value):
        raise AttributeError("TrimmedFace is immutable; operations return new faces")

    def __reduce__(self):
        # pickling rebuilds through the constructor (the cache is not kept)
        return (partial(TrimmedFace, tolerance=self._tolerance, name=self._name),
                (self._surface, self._loops, self._reversed))

    surface = property(lambda self: self._surface, doc="The underlying (untrimmed) surface.")
    loops = property(lambda self: self._loops, doc="Tuple of loops (tuples of Edge), outer first; empty: natural domain.")
    reversed = property(lambda self: self._reversed, doc="Whether the outward normal is -(Su x Sv).")
    tolerance = property(lambda self: self._tolerance, doc="Geometric tolerance (model units).")
    name = property(lambda self: self._name, doc="Optional label.")

    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The surface's parameter domain ``((u0, u1), (v0, v1))``."""
        return self._surface.domain

    @property
    def is_trimmed(self) -> bool:
        """Whether the face has trimming loops (False: bounded by its natural domain)."""
        return bool(self._loops)

    @property
    def outer_loop(self) -> tuple[Edge, ...]:
        """The outer loop's edges (the natural domain's four sides for an untrimmed face)."""
        return self.boundary_loops()[0]

    @property
    def inner_loops(self) -> tuple[tuple[Edge, ...], ...]:
        """The holes' loops."""
        return self._loops[1:]

    def boundary_loops(self) -> tuple[tuple[Edge, ...], ...]:
        """The loops that bound the face: ``loops``, or for an untrimmed face the natural domain's
        boundary as one counter-clockwise loop of four straight pcurves (3-D curves: the surface's
        iso-curves; a side that collapses to a point is marked degenerate)."""
        if self._loops:
            return self._loops
        if "natural" not in self._cache:
            self._cache["natural"] = (tuple(self._natural_edges()),)
        return self._cache["natural"]

    def _natural_edges(self):
        (u0, u1), (v0, v1) = self.domain
        corners = np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1]])
        s = self._surface
        for k in range(4):
            a, b = corners[k], corners[(k + 1) % 4]
            pc = line(a, b)
            t = np.linspace(0.0, 1.0, 9)
            uv = pc.evaluate(t)
            pts = s.evaluate(uv[:, 0], uv[:, 1])
            size = float(np.max(np.linalg.norm(pts - pts[0], axis=1)))
            yield Edge(pc, degenerate=size <= self._tolerance, tolerance=self._tolerance)

    @property
    def edges(self) -> tuple[Edge, ...]:
        """Every edge use of the face, loop after loop."""
        return tuple(e for lp in self.boundary_loops() for e in lp)

    def contains_uv(self, uv, tolerance: float | None = None) -> np.ndarray:
        """Classify ``(n, 2)`` parameter points against the trims: ``int8`` codes ``1`` inside,
        ``0`` on a trim (within ``tolerance``, 3-D units), ``-1`` outside
        (:func:`splinekit.brep.classify.contains_uv`)."""
        return contains_uv(self, uv, tolerance)

    def _problems(self):
        return check_face(self)

    def _topologies(self):
        # the face alone as a one-face shell: its seams pair up, its other edges are free
        if "topology" not in self._cache:
            self._cache["topology"] = shell_topology([self])
        return (self._cache["topology"],)

    def flipped(self) -> "TrimmedFace":
        """The same face with the opposite orientation."""
        return TrimmedFace(self._surface, self._loops, not self._reversed, tolerance=self._tolerance, name=self._name)

    def normals(self, u, v) -> np.ndarray:
        """Unit outward normals ``(n, 3)`` at parameters ``u``, ``v`` (``(n,)`` each): ``Su x Sv``
        normalized, negated for a reversed face."""
        d = self._surface.derivatives(u, v, 1)
        n = np.cross(d[1, 0], d[0, 1])
        length = np.linalg.norm(n, axis=-1, keepdims=True)
        n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
        return -n if self._reversed else n

    # -- mass properties (splinekit.brep.mass) ------------------------------------------------
    def area(self, tol: float = INTEGRAL_RTOL) -> float:
        """Area of the trimmed face to relative tolerance ``tol`` (adaptive quadrature)."""
        return mass.area(self, tol)

    def centroid(self, tol: float = INTEGRAL_RTOL) -> np.ndarray:
        """``(3,)`` centroid of the face's area."""
        return mass.centroid(self, tol)

    def inertia(self, tol: float = INTEGRAL_RTOL) -> np.ndarray:
        """``(3, 3)`` inertia tensor of the face (unit areal density) about its centroid."""
        return mass.inertia(self, tol)

    def mass_properties(self, tol: float = INTEGRAL_RTOL):
        """Area, centroid, inertia, principal moments and axes with error estimates
        (:class:`splinekit.brep.mass.MassProperties`)."""
        return mass.mass_properties(self, tol)

    def __repr__(self):
        holes = len(self._loops) - 1 if self._loops else 0
        kind = type(self._surface).__name__
        trim = f"{len(self._loops)} loop(s), {holes} hole(s)" if self._loops else "natural domain"
        return f"TrimmedFace({kind}, {trim}{', reversed' if self._reversed else ''}{f', name={self._name!r}' if self._name else ''})"
