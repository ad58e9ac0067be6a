"""Exact signed distance of a closed mesh on a grid by scanning the characteristic regions of its
features: the numpy side of :mod:`splinekit.pointcloud._gridsdf_scan` (whose module notes give
the argument), called by :meth:`~splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels, limits
from ..mesh.topology import Topology

SCAN_KERNELS = "splinekit.pointcloud._gridsdf_scan"

SEARCH_KERNELS = "splinekit.pointcloud._meshdistance_kernels"

SAMPLE_BYTES = 16
"""Bytes per grid sample besides the output: its least squared distance and triangle."""

REGION_BYTES = 80
"""Bytes per region (two per triangle, one per edge and vertex): cut radius, kind, owner, box."""


def adjacency(T, n_vertices):
    """What the regions need of a closed mesh's connectivity (triangles ``T`` in the hierarchy's
    order): edges ``(a, b)``, their two half-edges ``(E, 2)`` (``3 t + k`` is edge ``k`` of
    triangle ``t``), vertex -> neighbour CSR ``(ptr, nbr)`` and a triangle at each vertex."""
    m = len(T)
    topo = Topology(n_vertices, T.ravel(), np.arange(m + 1, dtype=np.int64) * 3, check=False)
    edges = topo.edges
    eh = np.ascontiguousarray(topo.edge_halfedges)
    ptr, eid = topo.vertex_edges
    owner_v = np.repeat(np.arange(n_vertices), np.diff(ptr))
    ends = edges[eid]
    nbr = np.where(ends[:, 0] == owner_v, ends[:, 1], ends[:, 0])
    vown = np.zeros(n_vertices, dtype=np.int64)
    for c in range(3):
        vown[T[:, c]] = np.arange(m)
    return (np.ascontiguousarray(edges[:, 0]), np.ascontiguousarray(edges[:, 1]), eh,
            np.ascontiguousarray(ptr, dtype=np.int64), np.ascontiguousarray(nbr, dtype=np.int64), vown)


def coarse_upper(dist, origin, spacing, shape, every):
    """Exact distances ``(G, origin, spacing)`` on the coarse grid of every ``every``-th sample
    (and one node past the last), by the hierarchy's nearest-triangle search."""
    gshape = (np.asarray(shape) - 1 + every - 1) // every + 1
    gh = spacing * every
    axes = [np.arange(k) for k in gshape]
    idx = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    d, _, _, _ = dist.bvh.nearest(_kernels.load(SEARCH_KERNELS), origin + idx * gh)
    return d.reshape(tuple(gshape)), origin, gh


def scan_grid(dist, kern, origin, spacing, shape, limit, count=None):
    """Signed distances (flat, unit box) at the samples ``origin + (i, j, k) * spacing`` of a
    grid of ``shape`` (unit box), ``inf`` beyond ``sqrt(limit)``; None when some triangle is too
    thin for a plane (the block kernel serves). ``kern``: the compiled module. ``count``:
    ``(parts, 2)`` int64 to receive the columns and distances measured per parallel part."""
    plane, _ = dist._bvh_planes
    if not plane.any(axis=1).all():
        return None
    b = dist.bvh
    V = dist.unit_vertices
    T = np.ascontiguousarray(dist.tris[b.order])
    fn, en, vn = dist._bvh_normals  # NotManifoldError for an open mesh
    prism = dist._bvh_prisms
    total = int(np.prod(shape))
    n_regions = 2 * len(T) + 3 * len(T) // 2 + len(V)
    limits.check(SAMPLE_BYTES * total + REGION_BYTES * n_regions,
                 f"the region scan's work arrays for {total:,} samples and {n_regions:,} regions")
    ea, eb, eh, ptr, nbr, vown = adjacency(T, len(V))
    n = 2 * len(T) + len(ea) + len(V)
    shape = np.asarray(shape, dtype=np.int64)
    G, go, gh = coarse_upper(dist, origin, spacing, shape, kern.CUT_NODES)
    R = np.empty(n)
    kind = np.empty(n, dtype=np.int64)
    owner = np.empty(n, dtype=np.int64)
    box = np.empty((n, 6), dtype=np.int64)
    reach = float(np.sqrt(limit))
    kern.cut_all(V, T, b.tri, plane, prism, ea, eb, eh, ptr, nbr, vown, origin, spacing, shape, G, go, gh, reach, R, kind,
                 owner, box)
    best = np.full(total, np.inf)
    who = np.full(total, -1, dtype=np.int64)
    parts = kern.parts()
    if count is None:
        count = np.zeros((parts, 2), dtype=np.int64)
    kern.scan(V, T, b.tri, plane, prism, ea, eb, eh, ptr, nbr, vown, R, kind, box, origin, spacing, shape, limit, best,
              who, parts, count)
    out = np.empty(total)
    kern.finish(origin, spacing, shape, best, who, b.tri, fn, en, vn, out)
    return out
