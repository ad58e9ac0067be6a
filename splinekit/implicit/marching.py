"""Meshing sampled values: :func:`grid_mesh`, marching tetrahedra on the Kuhn split of every cell.

The one iso-surface mesher of splinekit: :meth:`Implicit.to_mesh
<splinekit.implicit.base.Implicit.to_mesh>` samples the implicit on a grid and calls it,
:meth:`SampledSDF.to_mesh <splinekit.implicit.sampled.SampledSDF.to_mesh>` calls it on its
samples, and the level sets and point-cloud reconstructions mesh through those.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from .._validate import as_float_array, as_real
from ..errors import ParameterError
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from ._checks import origin3, spacing3

__all__ = ["grid_mesh"]

# Peak memory charged to the memory budget (:mod:`splinekit.limits`) in the three rounds of
# :func:`grid_mesh`, each before it allocates; measured with tracemalloc on spheres and on a
# checkerboard (every cell straddling), with a margin; each round is checked on its own.
BYTES_PER_SAMPLE = 32
"""Per (padded) grid sample: the shifted values, their padded copy, the inside mask, the
int8 inside-corner count per cell and the straddle masks (measured 12 without padding)."""
BYTES_PER_CELL = 1200
"""Per cell that straddles the level: its corner and tetrahedron sample indices, the
corner values and the case masks (about 1000 by the sizes of those arrays)."""
BYTES_PER_TRIANGLE = 600
"""Per output triangle: edge keys, their sort and inverse, the vertices and the
PolyMesh/Topology built from them (measured peak 430-460 per triangle on spheres
and a checkerboard, everything included)."""

# -- meshing straight from the samples ------------------------------------------------------------------------
# Kuhn triangulation of the unit cube: 6 tetrahedra sharing the diagonal 0 -> 7
# (corner c has offset (c >> 2 & 1, c >> 1 & 1, c & 1)); the same split in every
# cell, so neighbouring cells agree on their shared face diagonals.
_CORNER = np.array([[(c >> 2) & 1, (c >> 1) & 1, c & 1] for c in range(8)], dtype=np.int64)
_AXIS_BIT = (4, 2, 1)


def _kuhn_tets():
    tets = []
    for perm in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        c1 = _AXIS_BIT[perm[0]]
        c2 = c1 | _AXIS_BIT[perm[1]]
        tet = [0, c1, c2, 7]
        M = np.array([_CORNER[tet[i]] - _CORNER[0] for i in (1, 2, 3)], dtype=float)
        if np.linalg.det(M) < 0:  # make every tetrahedron positively oriented
            tet[1], tet[2] = tet[2], tet[1]
        tets.append(tet)
    return np.array(tets, dtype=np.int64)


_TETS = _kuhn_tets()
_TET_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]], dtype=np.int64)


def _case_table():
    """For each inside-mask (bit i: tet vertex i inside) of a positively
    oriented tetrahedron, up to 2 triangles as local edge indices, oriented
    with normals from inside to outside: ``(16, 2, 3)`` (-1 unused)."""
    ref = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    table = np.full((16, 2, 3), -1, dtype=np.int64)
    edge_of = {(int(a), int(b)): e for e, (a, b) in enumerate(_TET_EDGES)}
    for mask in range(1, 15):
        ins = [i for i in range(4) if mask >> i & 1]
        out = [i for i in range(4) if not mask >> i & 1]
        if len(ins) == 2:
            a, b = ins
            c, d = out
            ring = [(a, c), (a, d), (b, d), (b, c)]
            tris = [ring[:3], [ring[0], ring[2], ring[3]]]
        else:
            lone = ins if len(ins) == 1 else out
            rest = out if len(ins) == 1 else ins
            tris = [[(lone[0], r) for r in rest]]
        direction = ref[out].mean(axis=0) - ref[ins].mean(axis=0)
        for k, tri in enumerate(tris):
            es = [edge_of[tuple(sorted(p))] for p in tri]
            pts = [ref[list(_TET_EDGES[e])].mean(axis=0) for e in es]
            if np.dot(np.cross(pts[1] - pts[0], pts[2] - pts[0]), direction) < 0:
                es[1], es[2] = es[2], es[1]
            table[mask, k] = es
    return table


_CASES = _case_table()
_CASE_TRIANGLES = (_CASES[:, :, 0] >= 0).sum(axis=1)  # triangles per inside-mask: 0, 1 or 2


def grid_mesh(values, origin, spacing, level: float = 0.0):
    """The ``level`` set of sampled values as a closed triangle PolyMesh.

    Marching tetrahedra on the Kuhn split of every cell: the exact zero set of
    the piecewise-linear interpolant over that tetrahedral mesh, so it is a
    closed 2-manifold (the grid is padded with a positive layer where the
    solid touches its border, capping it there). Samples ``< level`` are
    inside. Triangles face outward (toward larger values). Vectorized: one
    pass over the cells that straddle the level.

    Parameters
    ----------
    values : (nx, ny, nz) finite array
    origin : (3,)
    spacing : float or (3,)
    level : float

    Returns
    -------
    PolyMesh
        Empty (no faces) when no sample is inside or none is outside.
    """
    vals = as_float_array(values, "values")
    if vals.ndim == 3:
        padded = float(np.prod(np.asarray(vals.shape, dtype=np.float64) + 2.0))
        limits.check(padded * BYTES_PER_SAMPLE, f"meshing a grid of shape {vals.shape}")
    if vals.ndim != 3 or min(vals.shape) < 2:
        raise ParameterError(f"values must be an (nx, ny, nz) array with every axis >= 2, got shape {vals.shape}")
    if not np.isfinite(vals).all():
        raise ParameterError("values must be finite")
    origin = origin3(origin)
    spacing = spacing3(spacing)
    level = as_real(level, "level")
    with np.errstate(over="ignore"):
        v = vals - level
    if not np.isfinite(v).all():
        raise ParameterError(f"values - level overflows for level = {level!r}")
    border = np.concatenate([v[[0, -1]].ravel(), v[:, [0, -1]].ravel(), v[:, :, [0, -1]].ravel()])
    if (border < 0).any():
        v = np.pad(v, 1, constant_values=max(float(np.abs(v).max()), 1.0))
        origin = origin - spacing
    nx, ny, nz = v.shape
    inside = v < 0
    cube_in = np.zeros((nx - 1, ny - 1, nz - 1), dtype=np.int8)  # 0..8 inside corners
    for c in range(8):
        o = _CORNER[c]
        cube_in += inside[o[0] : nx - 1 + o[0], o[1] : ny - 1 + o[1], o[2] : nz - 1 + o[2]]
    straddle = (cube_in > 0) & (cube_in < 8)
    del cube_in
    count = int(np.count_nonzero(straddle))
    if count == 0:
        return PolyMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    limits.check(count * BYTES_PER_CELL, f"meshing {count:,} cells that straddle the level")
    cells = np.argwhere(straddle)
    del straddle
    strides = np.array([ny * nz, nz, 1], dtype=np.int64)
    base = cells @ strides  # flat index of each cell's corner 0
    corner_flat = base[:, None] + _CORNER @ strides  # (C, 8)
    vflat = v.ravel()
    tv = corner_flat[:, _TETS]  # (C, 6, 4) flat sample indices per tet vertex
    mask = ((vflat[tv] < 0) * (1 << np.arange(4))).sum(axis=2)  # (C, 6)
    n_tris = int(_CASE_TRIANGLES[mask].sum())
    limits.check(n_tris * BYTES_PER_TRIANGLE, f"an iso-surface of {n_tris:,} triangles")
    tris = _CASES[mask]  # (C, 6, 2, 3) local edges
    use = tris[..., 0] >= 0
    ci, ti, _ = np.nonzero(use)
    local = tris[use]  # (F, 3)
    ends = tv[ci, ti][:, None, :]  # (F, 1, 4)
    e = _TET_EDGES[local]  # (F, 3, 2)
    va = np.take_along_axis(np.broadcast_to(ends, (len(local), 3, 4)), e[..., :1], axis=2)[..., 0]
    vb = np.take_along_axis(np.broadcast_to(ends, (len(local), 3, 4)), e[..., 1:], axis=2)[..., 0]
    a, b = np.minimum(va, vb), np.maximum(va, vb)
    key = a * (nx * ny * nz) + b
    ukey, inv = np.unique(key.ravel(), return_inverse=True)
    ea, eb = ukey // (nx * ny * nz), ukey % (nx * ny * nz)
    fa, fb = vflat[ea], vflat[eb]
    t = fa / (fa - fb)  # fa, fb of opposite signs (one < 0 <= other)

    def pos(flat):
        ijk = np.stack([flat // (ny * nz), (flat // nz) % ny, flat % nz], axis=1)
        return origin + ijk * spacing

    P = pos(ea) + t[:, None] * (pos(eb) - pos(ea))
    F = inv.reshape(-1, 3).astype(np.int64)
    topo = Topology(len(P), F.ravel(), np.arange(len(F) + 1, dtype=np.int64) * 3, check=False)
    return PolyMesh.from_topology(P, topo)
