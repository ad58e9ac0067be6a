"""Meshing an implicit: its zero set as a closed triangle mesh.

:func:`mesh_implicit` (also :meth:`Implicit.to_mesh`) runs manifold3d's
``Manifold.level_set`` (marching tetrahedra on a body-centred cubic grid:
two cubic grids, one shifted by half a cell), which wants *positive inside*,
so it is handed ``-F``.

``level_set`` calls its function once per grid point from C++ (about a
microsecond per call for a one-line Python formula); evaluating a CSG tree
point by point through numpy costs a hundred times more. So ``F`` is evaluated
here first, vectorized, on both grids, reproducing manifold's grid: per axis
``n = int(extent / edge_length + 1)`` points, spacing ``extent / (n - 1)``,
the primary grid at ``lo + spacing * i`` for ``i < n`` and the shifted one at
``lo + spacing * (i - 1/2)`` for ``i <= n``. ``level_set`` then gets a lookup
that turns a position back into a grid index (three dictionary look-ups of
the coordinates, about as cheap as a one-line formula). A position that is not
a grid point (a future manifold3d changing its grid) falls back to a direct
evaluation, so the result is right either way, only slower.

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
from ..errors import BackendError, ParameterError
from ..mesh.polymesh import PolyMesh
from .base import check_bounds, positive

__all__ = ["CHUNK", "MAX_GRID_POINTS", "PADDING", "ImplicitMesh", "mesh_implicit"]

MAX_GRID_POINTS = 100_000_000
"""Largest grid (both BCC grids together) accepted (800 MB of values, a few
minutes of level_set callbacks); beyond it ask for a longer edge."""

PADDING = 2.0
"""Cells of margin added around an implicit's own bounds, so that the surface
never reaches the grid's outer layer (which level_set treats as outside)."""

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


def _rebuild(vertices, face_indices, face_offsets, deviation, edge_length):
    from ..mesh.topology import Topology

    return _wrap(vertices, Topology(len(vertices), face_indices, face_offsets, check=True), deviation, edge_length)


def _wrap(vertices, topology, deviation, edge_length) -> ImplicitMesh:
    mesh = ImplicitMesh._adopt(vertices, topology)
    object.__setattr__(mesh, "deviation", float(deviation))
    object.__setattr__(mesh, "edge_length", float(edge_length))
    return mesh


def _grid_axes(lo, hi, edge_length):
    """Per-axis point counts ``n`` and spacings of manifold3d's level-set grid.

    A grid above ``MAX_GRID_POINTS`` raises ParameterError; the count is
    checked in floating point first, so a tiny edge length over a large box
    can neither overflow the int64 cast nor wrap the product of the counts."""
    with np.errstate(over="ignore"):  # an infinite extent or count is refused just below
        extent = hi - lo
        counts = np.maximum(np.floor(extent / edge_length + 1.0), 2.0)  # float: may exceed int64
    total = float(np.prod(counts)) + float(np.prod(counts + 1.0))
    if not total <= MAX_GRID_POINTS:
        raise ParameterError(
            f"edge_length={edge_length!r} over a box of size {extent.tolist()} needs {total:.3g} grid points "
            f"(more than {MAX_GRID_POINTS:.3g}); use a longer edge length"
        )
    # values of both grids, the evaluation chunks and manifold3d's output mesh
    limits.check(32.0 * total, f"a level-set grid of {total:.3g} points (edge_length={edge_length!r})")
    n = counts.astype(np.int64)
    return n, extent / (n - 1)


def _sample(implicit, lo, spacing, counts, shift):
    """``-F`` on the grid ``lo + spacing * (i + shift)``, ``i < counts``, flattened
    C-order (x slowest), evaluated in chunks of x-slabs."""
    axes = [lo[k] + spacing[k] * (np.arange(counts[k]) + shift) for k in range(3)]
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
        raise BackendError(f"{type(implicit).__name__} is not finite at some grid points of the level-set grid")
    return -out


def _lookup(implicit, lo, spacing, n):
    """The callback for level_set: ``-F`` looked up by grid position, or evaluated
    directly off the grid; and a one-item list counting the direct evaluations."""
    even = _sample(implicit, lo, spacing, n, 0.0)
    odd = _sample(implicit, lo, spacing, n + 1, -0.5)
    # a memoryview indexes like a list (a Python float per access) without a copy
    values = memoryview(np.concatenate([even, odd]))
    ny, nz = int(n[1]), int(n[2])
    strides = ((ny * nz, nz, 1), ((ny + 1) * (nz + 1), nz + 1, 1))
    # per axis, coordinate -> its share of the flat index; the coordinates are computed
    # as manifold3d computes them, so they match bit for bit. Bit 40 + axis marks the
    # shifted grid, so a position mixing the two grids is recognised and not misread.
    maps = []
    for k in range(3):
        table = {}
        for i in range(int(n[k])):
            table[float(lo[k] + spacing[k] * (i + 0.0))] = i * strides[0][k]
        for i in range(int(n[k]) + 1):
            table[float(lo[k] + spacing[k] * (i - 0.5))] = i * strides[1][k] + (1 << (40 + k)) + (len(even) if k == 0 else 0)
        maps.append(table)
    X, Y, Z = maps
    shifted = 7 << 40
    misses = [0]

    def direct(x, y, z):
        misses[0] += 1
        return -float(implicit._value(np.array([[x, y, z]]))[0])

    def sdf(x, y, z):
        try:
            index = X[x] + Y[y] + Z[z]
        except KeyError:
            return direct(x, y, z)
        grid = index >> 40
        if grid == 0:
            return values[index]
        if grid == 7:
            return values[index - shifted]
        return direct(x, y, z)

    return sdf, misses


def deviation(implicit, vertices, triangles) -> float:
    """Largest estimated distance to ``F = 0`` over the vertices, edge midpoints
    and centroids of a triangle mesh ``(V, 3)``, ``(T, 3)`` (module notes)."""
    if len(triangles) == 0:
        return 0.0
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    pts = np.concatenate([vertices, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), (a + b + c) / 3.0])
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
        Grid spacing in model units (> 0), about the longest edge of the result.
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
        ``F`` is not finite on the grid, or manifold3d reports an error.
    MissingDependencyError
        manifold3d is not installed.
    """
    from ..interop.booleans import _require_manifold3d, from_manifold
    from .base import Implicit

    if not isinstance(implicit, Implicit):
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
    n, spacing = _grid_axes(np.asarray(lo, float), np.asarray(hi, float), h)
    m3 = _require_manifold3d()
    sdf, _ = _lookup(implicit, np.asarray(lo, float), spacing, n)
    box = [float(v) for v in lo] + [float(v) for v in hi]
    manifold = m3.Manifold.level_set(sdf, box, h)
    mesh = from_manifold(manifold)  # checks the status
    V = np.asarray(mesh.vertices)
    T = mesh.topology.face_indices.reshape(-1, 3) if mesh.topology.n_faces else np.zeros((0, 3), np.int64)
    return _wrap(V, mesh.topology, deviation(implicit, V, T), h)
