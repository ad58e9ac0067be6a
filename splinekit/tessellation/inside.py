"""Which side of a solid's boundary points lie on, from a closed tessellation of the solid.

Used by :func:`splinekit.brep.classify.contains` (``Solid.contains``), which settles the points this
module cannot decide (``near``) exactly on the B-rep faces and edges.

The mesh: :func:`splinekit.tessellation.tessellate` of the solid at :data:`MESH_RTOL` of its
size, closed and oriented outward, cached on the solid with its
:class:`~splinekit.pointcloud.meshdistance.MeshDistance`. Its signed distance (nearest triangle,
sign from the angle-weighted pseudo-normal of the nearest feature) is exact for the mesh, in
``O(log T)`` per point.

Why the mesh's sign is the solid's away from the mesh: every point of a mesh triangle is joined to
the exact surface point of the same ``(u, v)`` by a segment of length at most the tessellation's
deviation ``dev``. Sliding every triangle point along its segment deforms the mesh into the exact
boundary, and no point of the deformation is farther than ``dev`` from the mesh, so the winding
number (inside or outside) of every point farther than ``dev`` from the mesh is the same for the
mesh and for the solid. The same segments bound the exact distance: ``|d_exact - |d_mesh|| <= dev``.
So a point with ``|d_mesh| > dev_bound + tol`` is not ON and lies on the mesh's side; ``dev_bound``
is :data:`DEVIATION_SAFETY` times the larger of the measured deviation (measured at the triangles'
centres and edge mid points, where the chord error of a curved patch peaks) and the requested one.

Profile that motivated it (box with a through hole, 100,000 random points in its box, before):
the generalized winding numbers of every face's coarse mesh against every point took 5.7 s of
7.5 s, the distance band around the coarse meshes 1.1 s; a filleted box (26 faces) took about
40 s. One nearest-triangle query per point replaces both.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels, limits
from ..brep.trims import INSIDE, OUTSIDE
from ..errors import SplineKitError
from ..pointcloud.meshdistance import KERNELS, MeshDistance
from .core import tessellate

__all__ = ["DEVIATION_SAFETY", "MESH_RTOL", "SLOW_PATH_WORK", "mesh_sides", "solid_mesh_distance"]

MESH_RTOL = 1e-4
"""Chordal tolerance of the classification mesh, relative to the solid's bounding-box diagonal.
Finer meshes cost more triangles (a filleted box: 1,700 at 1e-3, 16,600 at 1e-4, tessellated in
0.06 s and 0.18 s) and shrink the band of points settled on the exact faces tenfold."""

DEVIATION_SAFETY = 2.0
"""The band's half-width is this times the tessellation's measured deviation (plus the ON
tolerance): the measurement samples triangle centres and edge mid points, not every point."""


SLOW_PATH_WORK = 300
"""Cost per point of the path without this module (winding numbers on the faces' coarse meshes,
about 0.3-0.4 ms a point on a box with a hole and on a filleted box), in :mod:`splinekit._kernels`
work units: the size of the job the compiled nearest-triangle search saves, given to the loader.
The numpy nearest-triangle search is no alternative here: for a point deep inside it certifies
against every triangle within its distance (memory and time ~ points x triangles)."""

ORDER_CELLS = 16
"""Query points are sorted by the cells of a ``16^3`` grid over their box: the compiled search
starts from the previous point's triangle, and neighbours in the query order then lie close
(100,000 random points against a filleted box's 16,600 triangles: 0.42 s sorted, 0.86 s not)."""


GRID_SAMPLES = 1 << 18
"""Samples of the grid of the mesh's signed distances kept beside it (cubic cells over the solid's
box, about this many): a point whose nearest sample's distance exceeds the point's distance to
that sample plus the band takes the sample's sign (the signed distance is 1-Lipschitz), so only
the points in the cells along the boundary need a nearest-triangle search."""


def solid_mesh_distance(solid):
    """``(MeshDistance, dev_bound)`` of the solid's closed tessellation, or None when the
    tessellation is not closed, encloses a negative volume (faces turned inward, against the
    contract of :class:`~splinekit.brep.Solid`) or fails; then the caller classifies without it,
    as before this module (winding numbers of coarse face meshes; near the boundary those also
    trust the faces' normals, so a solid turned inside out is classified wrongly there). Cached on the
    solid (``solid._cache["inside_mesh"]``)."""
    cache = solid._cache
    if "inside_mesh" not in cache:
        try:
            mesh = tessellate(solid, MESH_RTOL, relative=True)
            md = MeshDistance(mesh.vertices, np.asarray(mesh.faces))
            md.pseudo_normals  # NotManifoldError when an edge has not two triangles
            a, b, c = (md.unit_vertices[md.tris[:, k]] for k in range(3))
            if not np.einsum("ij,ij->", a, np.cross(b, c)) > 0:  # six times the signed volume
                raise SplineKitError("the solid's tessellation is not oriented outward")
            # the requested tolerance as a floor: a curved trim on a plane has no surface error
            # to measure, but its chords stand off the trim by up to the tolerance
            dev = max(float(mesh.max_deviation), float(mesh.tolerance))
            cache["inside_mesh"] = (md, DEVIATION_SAFETY * dev)
        except SplineKitError:
            cache["inside_mesh"] = None
    return cache["inside_mesh"]


def mesh_sides(solid, points, tolerance: float):
    """Sides of ``points`` ``(n, 3)`` from the solid's mesh, or None without a closed mesh.

    Returns ``(codes (n,) int8, near (n,) bool, bound (n,) float)``: ``codes`` is ``1`` inside and
    ``-1`` outside the mesh (the solid's answer wherever ``near`` is False); ``near`` marks the
    points within ``dev_bound + tolerance`` of the mesh, whose answer (and whether they are ON)
    must come from the exact boundary; ``bound`` is an upper bound of each point's exact distance
    to the boundary (model units).
    """
    n = len(points)
    kernels = _kernels.get(KERNELS) or _kernels.load(KERNELS, work=n * SLOW_PATH_WORK)
    if kernels is None:  # compiled code off, not worth loading for this job, or numba missing
        return None
    found = solid_mesh_distance(solid)
    if found is None:
        return None
    md, dev_bound = found
    band = dev_bound + tolerance
    limits.check(n * 8 * 24, "signed distances to the classification mesh")
    d = np.empty(n)
    # the grid's nearest sample settles the points well away from the boundary
    grid = _distance_grid(solid, md)
    if grid is not None:
        origin, h, values = grid
        idx = np.clip(np.rint((points - origin) / h).astype(np.intp), 0, np.array(values.shape) - 1)
        r = np.linalg.norm(points - (origin + idx * h), axis=1)
        d = values[idx[:, 0], idx[:, 1], idx[:, 2]]
        ask = np.flatnonzero(np.abs(d) <= r + band)
        d[ask] = _signed(md, points[ask], kernels)
    else:
        d = _signed(md, points, kernels)
    a = np.abs(d)
    codes = np.where(d < 0, np.int8(INSIDE), np.int8(OUTSIDE))
    return codes, a <= band, a + band


def _signed(md, points, kernels):
    """Signed distances ``(n,)`` of ``points`` to the mesh, the points searched in grid-cell order."""
    d = np.empty(len(points))
    if len(points) == 0:
        return d
    order = _spatial_order(points)
    d[order] = md.signed(points[order], kernels=kernels)[0]
    return d


def _distance_grid(solid, md):
    """``(origin (3,), spacing h, values (i, j, k))``: the mesh's signed distances at the samples
    ``origin + (i, j, k) h`` of a grid over the solid's box (:data:`GRID_SAMPLES`), cached beside
    the mesh; None when the compiled grid kernel does not serve."""
    cache = solid._cache
    if "inside_grid" not in cache:
        lo, hi = md.V.min(axis=0), md.V.max(axis=0)
        ext = np.maximum(hi - lo, 1e-9 * float((hi - lo).max()))
        h = float(np.cbrt(np.prod(ext) / GRID_SAMPLES))
        shape = np.ceil(ext / h).astype(np.intp) + 1
        limits.check(int(np.prod(shape)) * 8 * 2, "the classification mesh's distance grid")
        values = md.grid_signed(lo, np.full(3, h), shape)
        cache["inside_grid"] = None if values is None else (lo, h, values)
    return cache["inside_grid"]


def _spatial_order(points):
    """Permutation ``(n,)`` sorting ``points`` by the cells of an :data:`ORDER_CELLS` grid over
    their box (row by row)."""
    lo = points.min(axis=0)
    ext = np.maximum(points.max(axis=0) - lo, 1e-300)
    q = np.clip(((points - lo) / ext * ORDER_CELLS).astype(np.int64), 0, ORDER_CELLS - 1)
    return np.lexsort((q[:, 2], q[:, 1], q[:, 0]))
