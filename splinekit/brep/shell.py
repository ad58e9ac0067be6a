"""Shells (faces sharing edges) and solids (closed shells, outer first)."""

from __future__ import annotations

from functools import partial

from ..errors import ParameterError
from ..tolerances import INTEGRAL_RTOL
from . import mass
from .check import Checkable, check_shell, check_solid
from .classify import contains
from .face import TrimmedFace
from .topology import TopologyQueries, shell_topology

__all__ = ["Shell", "Solid"]


class MassQueries:
    """Mass properties of a shell or solid (a mixin; :mod:`splinekit.brep.mass` does the work).
    A shell's volume is meaningful when it is closed; in a solid, void shells (pointing into
    their voids) count negative."""

    __slots__ = ()

    def area(self, tol: float = INTEGRAL_RTOL) -> float:
        """Total area of the faces to relative tolerance ``tol``."""
        return mass.area(self, tol)

    def volume(self, tol: float = INTEGRAL_RTOL) -> float:
        """Enclosed volume by the divergence theorem over the oriented faces."""
        return mass.volume(self, tol)

    def centroid(self, tol: float = INTEGRAL_RTOL):
        """``(3,)`` centroid of the enclosed solid (unit density)."""
        return mass.centroid(self, tol)

    def inertia(self, tol: float = INTEGRAL_RTOL):
        """``(3, 3)`` inertia tensor of the enclosed solid (unit density) about its centroid."""
        return mass.inertia(self, tol)

    def mass_properties(self, tol: float = INTEGRAL_RTOL):
        """Area, volume, centroid, inertia, principal moments and axes with error estimates
        (:class:`splinekit.brep.mass.MassProperties`)."""
        return mass.mass_properties(self, tol)


class Shell(TopologyQueries, Checkable, MassQueries):
    """Connected trimmed faces that share edges.

    Parameters
    ----------
    faces : list of TrimmedFace
        The faces, oriented consistently (outward normals on a closed shell).
    name : str, optional
        A label (STEP product names).

    Edges are paired by their ``key`` where both uses carry one; uses without a key are paired
    geometrically (end points and mid point within the edges' tolerance).
    """

    __slots__ = ("_faces", "_name", "_cache")

    def __init__(self, faces, *, name: str | None = None):
        if isinstance(faces, TrimmedFace):
            faces = [faces]
        try:
            faces = tuple(faces)
        except TypeError:
            raise ParameterError(f"faces must be a list of TrimmedFace, got {type(faces).__name__}") from None
        if not faces:
            raise ParameterError("a shell needs at least one face")
        for i, f in enumerate(faces):
            if not isinstance(f, TrimmedFace):
                raise ParameterError(f"face {i} is a {type(f).__name__}, not a TrimmedFace")
        object.__setattr__(self, "_faces", faces)
        object.__setattr__(self, "_name", None if name is None else str(name))
        object.__setattr__(self, "_cache", {})

    def __setattr__(self, name, value):
        raise AttributeError("Shell is immutable")

    def __reduce__(self):
        return (partial(Shell, name=self._name), (self._faces,))

    faces = property(lambda self: self._faces, doc="Tuple of TrimmedFace.")
    name = property(lambda self: self._name, doc="Optional label.")

    def __len__(self) -> int:
        return len(self._faces)

    def _problems(self):
        return check_shell(self)

    def _topologies(self):
        if "topology" not in self._cache:
            self._cache["topology"] = shell_topology(self._faces)
        return (self._cache["topology"],)

    @property
    def edges(self) -> tuple:
        """The shell's edges as :class:`~splinekit.brep.topology.EdgeGroup` (the uses that are one edge)."""
        return self.topology.edges

    def __repr__(self):
        return f"Shell({len(self._faces)} faces{f', name={self._name!r}' if self._name else ''})"


class Solid(TopologyQueries, Checkable, MassQueries):
    """A solid bounded by closed shells: the outer shell first, then the voids' shells.

    Parameters
    ----------
    shells : Shell or list of Shell
        Closed, consistently oriented shells (outward normals; a void's shell points into the void).
    name : str, optional
        A label (STEP product names).
    """

    __slots__ = ("_shells", "_name", "_cache")

    def __init__(self, shells, *, name: str | None = None):
        if isinstance(shells, Shell):
            shells = [shells]
        try:
            shells = tuple(shells)
        except TypeError:
            raise ParameterError(f"shells must be a Shell or a list of Shell, got {type(shells).__name__}") from None
        if not shells:
            raise ParameterError("a solid needs at least one shell")
        for i, s in enumerate(shells):
            if not isinstance(s, Shell):
                raise ParameterError(f"shell {i} is a {type(s).__name__}, not a Shell")
        object.__setattr__(self, "_shells", shells)
        object.__setattr__(self, "_name", None if name is None else str(name))
        object.__setattr__(self, "_cache", {})

    def __setattr__(self, name, value):
        raise AttributeError("Solid is immutable")

    def __reduce__(self):
        return (partial(Solid, name=self._name), (self._shells,))

    shells = property(lambda self: self._shells, doc="Tuple of Shell, outer first.")
    outer_shell = property(lambda self: self._shells[0], doc="The outer shell.")
    name = property(lambda self: self._name, doc="Optional label.")

    @property
    def faces(self) -> tuple[TrimmedFace, ...]:
        """Every face of every shell."""
        return tuple(f for s in self._shells for f in s.faces)

    def _topologies(self):
        return tuple(s.topology for s in self._shells)

    def _problems(self):
        return check_solid(self)

    def contains(self, points, tolerance: float | None = None):
        """Classify ``(n, 3)`` points: ``int8`` codes ``1`` inside, ``0`` on the boundary (within
        ``tolerance``), ``-1`` outside (:func:`splinekit.brep.classify.contains`)."""
        return contains(self, points, tolerance)

    @property
    def edges(self) -> tuple:
        """Every shell's edges (:class:`~splinekit.brep.topology.EdgeGroup`, face indices per shell)."""
        return tuple(g for s in self._shells for g in s.edges)

    def __repr__(self):
        return f"Solid({len(self._shells)} shell(s), {len(self.faces)} faces{f', name={self._name!r}' if self._name else ''})"
