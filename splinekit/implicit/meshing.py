"""Meshing an implicit: its zero set as a closed triangle mesh.

:func:`mesh_implicit` (also :meth:`Implicit.to_mesh`) samples ``F`` on a regular grid of
spacing at most ``edge_length`` (per axis ``n = ceil(extent / edge_length) + 1`` points,
spacing ``extent / (n - 1)``), vectorized in chunks of x-slabs, and hands the samples to
:func:`~splinekit.implicit.marching.grid_mesh` (marching tetrahedra on the Kuhn split of every
cell: the zero set of the piecewise-linear interpolant, a closed 2-manifold, outward-facing).
That is splinekit's one iso-surface mesher. It replaced manifold3d's ``Manifold.level_set``
(marching tetrahedra on a body-centred grid, called back once per grid point): at the same
edge length this one is several times faster and gives about 1.7 times as many triangles and
about twice the deviation, still ``O(edge_length^2)`` (``benchmarks/bench_meshing.py``).

The mesh's deviation from the surface is measured afterwards: the largest
estimated distance to ``F = 0`` over its vertices, edge midpoints and
triangle centroids, the distance being ``|F|`` for an exact signed distance
and ``|F| / |grad F|`` (its first-order estimate) otherwise. That estimate is
too low where ``F`` underestimates the distance (outside an intersection,
inside a union), but a mesh cuts a convex crease (of an intersection) from
inside and a concave one (of a union) from outside, where ``F`` is exact.
For a closed surface of area ``A`` meshed with deviation ``d``, the mesh's
volume differs from the solid's by at most about ``d A`` (every surface
element moves by at most ``d``).
"""

from __future__ import annotations

import numpy as np

from .. import limits
from ..diffgeom.protocol import ImplicitSurface
from ..errors import BackendError, ParameterError
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from ._checks import check_bounds, positive
from .marching import grid_mesh

__all__ = [
    "BYTES_PER_GRID_POINT",
    "CHUNK",
    "MAX_GRID_POINTS",
    "PADDING",
    "ImplicitMesh",
    "deviation",
    "mesh_implicit",
]

MAX_GRID_POINTS = 100_000_000
"""Largest sampling grid accepted (800 MB of values); beyond it ask for a longer edge. The memory
budget (:mod:`splinekit.limits`) usually refuses a smaller grid first."""

BYTES_PER_GRID_POINT = 48
"""Peak memory per grid point charged to the memory budget (:mod:`splinekit.limits`): the
values, the inside mask and cell counts of the mesher, and the evaluation chunks."""

PADDING = 2.0
"""Cells of margin added around an implicit's own bounds, so that the surface
never reaches the grid's outer layer."""

CHUNK = 1 << 20
"""Grid points evaluated per vectorized call."""


class ImplicitMesh(PolyMesh):
    """A :class:`~splinekit.mesh.polymesh.PolyMesh` produced by meshing an implicit.

    Extra attributes
    ----------------
    deviation : float
        Measured largest distance (model units) of the mesh from ``F = 0``:
        over vertices, edge midpoints and triangle centroids (module notes).
    edge_length : float
        The requested grid spacing.
    """

    def __reduce__(self):
        t = self.topology
        return (
            _rebuild,
            (np.array(self.vertices), np.array(t.face_indices), np.array(t.face_offsets), self.deviation, self.edge_length),
        )

    def __repr__(self):
        return super().__repr__().replace("PolyMesh(", "ImplicitMesh(", 1)[:-1] + f", deviation={self.deviation:.3g})"

    @classmethod
    def of_topology(cls, vertices, topology, deviation, edge_length) -> "ImplicitMesh":
        """A mesh of ``vertices (V, 3)`` and a checked ``Topology`` (adopted, not copied), with
        its measured ``deviation`` and the grid's ``edge_length`` (for meshers outside this module)."""
        mesh = cls._adopt(vertices, topology)
        object.__setattr__(mesh, "deviation", float(deviation))
        object.__setattr__(mesh, "edge_length", float(edge_length))
        return mesh


def _rebuild(vertices, face_indices, face_offsets, deviation, edge_length):
    topology = Topology(len(vertices), face_indices, face_offsets, check=True)
    return ImplicitMesh.of_topology(vertices, topology, deviation, edge_length)


def _grid_axes(lo, hi, step):
    """Per-axis point counts ``n`` and spacings (at most ``step``) of the sampling grid over ``lo..hi``.

    A grid above ``MAX_GRID_POINTS`` raises ParameterError; the count is
    checked in floating point first, so a tiny edge length over a large box
    can neither overflow the int64 cast nor wrap the product of the counts."""
    with np.errstate(over="ignore"):  # an infinite extent or count is refused just below
        extent = hi - lo
        counts = np.maximum(np.ceil(extent / step) + 1.0, 2.0)  # float: may exceed int64
    total = float(np.prod(counts))
    if not total <= MAX_GRID_POINTS:
        raise ParameterError(
            f"a grid step of {step!r} over a box of size {extent.tolist()} needs {total:.3g} grid points "
            f"(more than {MAX_GRID_POINTS:.3g}); use a longer edge length"
        )
    limits.check(BYTES_PER_GRID_POINT * total, f"a meshing grid of {total:.3g} points (step {step!r})")
    n = counts.astype(np.int64)
    return n, extent / (n - 1)


def _sample(implicit, lo, spacing, counts):
    """``F`` on the grid ``lo + spacing * i``, ``i < counts``: ``(nx, ny, nz)``, evaluated in
    chunks of x-slabs; a BackendError when ``F`` is not finite somewhere."""
    axes = [lo[k] + spacing[k] * np.arange(counts[k]) for k in range(3)]
    nyz = int(counts[1] * counts[2])
    Y, Z = np.meshgrid(axes[1], axes[2], indexing="ij")
    yz = np.column_stack([Y.ravel(), Z.ravel()])
    out = np.empty(int(np.prod(counts)))
    slabs = max(1, CHUNK // nyz)
    pts = np.empty((slabs * nyz, 3))
    for start in range(0, int(counts[0]), slabs):
        xs = axes[0][start : start + slabs]
        m = len(xs) * nyz
        pts[:m, 0] = np.repeat(xs, nyz)
        pts[:m, 1:] = np.tile(yz, (len(xs), 1))
        with np.errstate(all="ignore"):  # non-finite values are reported below
            out[start * nyz : start * nyz + m] = implicit._value(pts[:m])
    if not np.isfinite(out).all():
        raise BackendError(f"{type(implicit).__name__} is not finite at some points of the meshing grid")
    return out.reshape(tuple(int(c) for c in counts))


def _closed_off(values, lo, hi, spacing):
    """``grid_mesh`` of samples over the box ``lo..hi`` that the solid may leave, closed off
    along the box: a layer of large positive values just outside puts the closing crossings
    within a millionth of a cell of the box faces (so they do not fold), and every vertex
    outside the box is then moved onto it. ``(mesh, vertices)``."""
    cap = min(1e6 * max(float(np.abs(values).max()), 1.0), 1e300)
    mesh = grid_mesh(np.pad(values, 1, constant_values=cap), lo - spacing, spacing)
    return mesh, np.clip(np.asarray(mesh.vertices), lo, hi)


def deviation(implicit, vertices, triangles) -> float:
    """Largest estimated distance to ``F = 0`` over the vertices, edge midpoints
    and centroids of a triangle mesh ``(V, 3)``, ``(T, 3)`` (module notes)."""
    if len(triangles) == 0:
        return 0.0
    # each edge once (two triangles share it): the same points as per triangle, a third fewer
    ends = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edges = np.unique(ends[:, 0] * len(vertices) + ends[:, 1])
    a, b = vertices[edges // len(vertices)], vertices[edges % len(vertices)]
    centroids = vertices[triangles].mean(axis=1)
    pts = np.concatenate([vertices, 0.5 * (a + b), centroids])
    worst = 0.0
    for start in range(0, len(pts), CHUNK):
        q = pts[start : start + CHUNK]
        with np.errstate(all="ignore"):
            if implicit.is_exact_sdf:
                F, g = np.abs(implicit._value(q)), None
            else:
                F, g = implicit._value_gradient(q)
                F, g = np.abs(F), np.linalg.norm(g, axis=1)
        if g is not None:
            # where the gradient vanishes there is no first-order estimate; |F| is kept
            F = np.where(g > 1e-12, F / np.where(g > 1e-12, g, 1.0), F)
        worst = max(worst, float(F.max()))
    return worst


def mesh_implicit(implicit, edge_length, bounds=None) -> ImplicitMesh:
    """The zero set of ``implicit`` as a closed, outward-oriented triangle mesh.

    Parameters
    ----------
    implicit : Implicit
    edge_length : float
        Grid spacing in model units (> 0): the largest step of the sampling
        grid. Triangles lie in the grid's cells, so no edge is longer than a
        cell diagonal, ``sqrt(3) * edge_length``.
    bounds : (lo (3,), hi (3,)), optional
        The box to mesh; default the implicit's own bounds grown by
        ``PADDING`` cells. Required for unbounded implicits (a plane, a
        complement). Where the surface leaves an explicit box the mesh is
        closed off along the box; those closing faces are not on ``F = 0``
        and count in ``deviation``.

    Returns
    -------
    ImplicitMesh
        A triangle PolyMesh with ``deviation`` and ``edge_length``; empty (no
        vertices, no faces) when ``F`` has no zero crossing on the grid.

    Raises
    ------
    ParameterError
        A non-positive edge length, malformed bounds, no bounds for an
        unbounded implicit, or a grid above ``MAX_GRID_POINTS`` points.
    BackendError
        ``F`` is not finite on the grid.
    """
    # an Implicit (base.py, which imports this module): the diffgeom protocol it implements,
    # with the evaluation hooks of the base class
    if not (isinstance(implicit, ImplicitSurface) and hasattr(implicit, "_value") and hasattr(implicit, "bounds")):
        raise ParameterError(f"expected a splinekit.implicit.Implicit, got {type(implicit).__name__}")
    h = positive(edge_length, "edge_length")
    if bounds is None:
        if implicit.bounds is None:
            raise ParameterError(
                f"{type(implicit).__name__} is unbounded (bounds is None): pass bounds=(lo, hi) to to_mesh"
            )
        lo, hi = implicit.bounds
        lo, hi = lo - PADDING * h, hi + PADDING * h
    else:
        lo, hi = check_bounds(bounds)
        with np.errstate(over="ignore"):  # an overflowing extent is refused by _grid_axes
            extent = hi - lo
        if not (extent >= 2.0 * h).all():  # fewer than 3 grid points: all of them on the outer layer
            raise ParameterError(
                f"bounds must be at least 2 * edge_length = {2 * h!r} long on every axis, "
                f"got lo={lo.tolist()}, hi={hi.tolist()}"
            )
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n, spacing = _grid_axes(lo, hi, h)
    values = _sample(implicit, lo, spacing, n)
    if bounds is None:
        mesh = grid_mesh(values, lo, spacing)
        V = np.asarray(mesh.vertices)
    else:
        mesh, V = _closed_off(values, lo, hi, spacing)
    T = mesh.topology.face_indices.reshape(-1, 3)
    return ImplicitMesh.of_topology(V, mesh.topology, deviation(implicit, V, T), h)
