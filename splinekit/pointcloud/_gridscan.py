"""Exact signed distance of a closed mesh on a grid by scanning the characteristic regions of its
features: the numpy side of :mod:`splinekit.pointcloud._gridsdf_scan` (whose module notes give
the argument), called by :meth:`~splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels, limits
from ..mesh.topology import ranges

SCAN_KERNELS = "splinekit.pointcloud._gridsdf_scan"

SEARCH_KERNELS = "splinekit.pointcloud._meshdistance_kernels"

SAMPLE_BYTES = 8
"""Bytes per grid sample besides the output: its least squared distance."""

WIDE_REGIONS = 32
"""Most regions spanning the whole grid (knife edges, spike tips: not cut, each may hold half the
grid) that a scan takes on; a mesh with more goes to the block kernel."""

REGION_BYTES = 80
"""Bytes per region (two per triangle, one per edge and vertex): cut radius, kind, box, and the
mesh's connectivity and coarse grid shared out."""


def adjacency(dist):
    """What the regions need of a closed mesh's connectivity (:class:`MeshDistance` ``dist``,
    triangles in its hierarchy's order), with the vertices renumbered in the order of the first
    triangle at each (so that the regions of edges and vertices come in the hierarchy's spatial
    order, as the faces do, and the scan's writes stay local): vertices, triangles, edges
    ``(a, b)``, their two half-edges ``(E, 2)`` (``3 t + k`` is edge ``k`` of triangle ``t``),
    vertex -> neighbour CSR ``(ptr, nbr)`` and a triangle at each vertex. From the compiled
    set-up when it has them (:mod:`._meshsetup`, the same arrays)."""
    if dist._grid_arrays is not None and dist._grid_arrays.adjacency is not None:
        return dist._grid_arrays.adjacency
    topo, order = dist.topology, dist.bvh.order
    m, nv = len(order), len(dist.unit_vertices)
    at = np.empty(m, dtype=np.int64)  # original triangle -> its place in the hierarchy
    at[order] = np.arange(m)
    T = dist.tris[order]
    first = np.full(nv, m, dtype=np.int64)
    np.minimum.at(first, T.ravel(), np.repeat(np.arange(m), 3))
    vorder = np.argsort(first, kind="stable")
    new = np.empty(nv, dtype=np.int64)
    new[vorder] = np.arange(nv)
    eh = topo.edge_halfedges
    eh = 3 * at[eh // 3] + eh % 3
    eorder = np.argsort(np.minimum(eh[:, 0], eh[:, 1]), kind="stable")
    edges = new[topo.edges[eorder]]
    ptr, eid = topo.vertex_edges
    count = np.diff(ptr)[vorder]
    pick = ranges(ptr[vorder], count)  # each vertex's edges, vertices in the new order
    ends = topo.edges[eid[pick]]
    centre = np.repeat(vorder, count)
    nbr = new[np.where(ends[:, 0] == centre, ends[:, 1], ends[:, 0])]
    vown = np.zeros(nv, dtype=np.int64)
    for c in range(3):
        vown[new[T[:, c]]] = np.arange(m)
    return (np.ascontiguousarray(dist.unit_vertices[vorder]), new[T], np.ascontiguousarray(edges[:, 0]),
            np.ascontiguousarray(edges[:, 1]), np.ascontiguousarray(eh[eorder]),
            np.concatenate([[0], np.cumsum(count)]), nbr, vown)


def coarse_upper(dist, origin, spacing, shape, every):
    """Exact distances ``(G, origin, spacing)`` on the coarse grid of every ``every``-th sample
    (and one node past the last), by the hierarchy's nearest-triangle search."""
    gshape = (np.asarray(shape) - 1 + every - 1) // every + 1
    gh = spacing * every
    axes = [np.arange(k) for k in gshape]
    idx = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    d, _, _, _ = dist.bvh.nearest(_kernels.load(SEARCH_KERNELS), origin + idx * gh)
    return d.reshape(tuple(gshape)), origin, gh


def scan_grid(dist, kern, origin, spacing, shape, limit):
    """Signed distances (flat, unit box) at the samples ``origin + (i, j, k) * spacing`` of a
    grid of ``shape`` (unit box), ``inf`` beyond ``sqrt(limit)``; None when some triangle is too
    thin for a plane or more than :data:`WIDE_REGIONS` regions span the grid (the block kernel
    serves). ``kern``: the compiled module."""
    reg = regions(dist, kern, origin, spacing, shape, limit)
    if reg is None or np.count_nonzero(reg[2] == 2) > WIDE_REGIONS:
        return None
    return scan(dist, kern, reg, origin, spacing, shape, limit)


def regions(dist, kern, origin, spacing, shape, limit):
    """The mesh's regions for the grid (arguments of :func:`scan_grid`): ``(mesh, R, kind,
    box)``, the mesh's arrays as the kernels take them, each region's cut radius, kind and box of
    sample indices (:func:`~splinekit.pointcloud._gridsdf_scan.cut_all`); None when some
    triangle is too thin for a plane."""
    plane, _ = dist._bvh_planes
    if not plane.any(axis=1).all():
        return None
    b = dist.bvh
    dist._bvh_normals  # noqa: B018 -- NotManifoldError for an open mesh, before any work
    total = int(np.prod(shape))
    n_regions = 2 * len(dist.tris) + 3 * len(dist.tris) // 2 + len(dist.unit_vertices)
    limits.check(SAMPLE_BYTES * total + REGION_BYTES * n_regions,
                 f"the region scan's work arrays for {total:,} samples and {n_regions:,} regions")
    V, T, ea, eb, eh, ptr, nbr, vown = adjacency(dist)
    mesh = (V, T, b.tri, plane, dist._bvh_prisms, ea, eb, eh, ptr, nbr, vown)
    n = 2 * len(T) + len(ea) + len(V)
    shape = np.asarray(shape, dtype=np.int64)
    G, go, gh = coarse_upper(dist, origin, spacing, shape, kern.CUT_NODES)
    R = np.empty(n)
    kind = np.empty(n, dtype=np.int64)
    box = np.empty((n, 6), dtype=np.int64)
    kern.cut_all(*mesh, origin, spacing, shape, G, go, gh, float(np.sqrt(limit)), R, kind, box)
    return mesh, R, kind, box


def scan(dist, kern, reg, origin, spacing, shape, limit, count=None):
    """Signed distances (flat, unit box) from the regions ``reg`` (:func:`regions`) of the same
    grid. ``count``: ``(parts, 2)`` int64 to receive the columns and distances measured per
    parallel part (:func:`~splinekit.pointcloud._gridsdf_scan.parts`)."""
    mesh, R, kind, box = reg
    fn, en, vn = dist._bvh_normals
    total = int(np.prod(shape))
    best = np.full(total, np.inf)
    out = np.full(total, np.inf)
    parts = kern.parts()
    if count is None:
        count = np.zeros((parts, 2), dtype=np.int64)
    kern.scan(*mesh, R, kind, box, origin, spacing, np.asarray(shape, dtype=np.int64), limit, fn, en, vn, best, out,
              parts, count)
    return out
