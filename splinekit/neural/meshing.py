"""Meshing a neural signed distance in a narrow band: the network is evaluated near its surface only.

A network costs tens of microseconds per point on a loaded CPU, so a full ``n^3`` grid (2.4
million points at 128 cells) is what dominates meshing. A signed distance tells where its zero
set cannot be: with ``|grad F| <= L``, no surface lies within ``|F(c)| / L`` of a point ``c``.
:func:`band_mesh` therefore samples ``F`` first at the centres of blocks of ``BLOCK^3`` cells;
a block whose centre has ``|F| > L * (half block diagonal + one cell)`` (``L = LIPSCHITZ``,
a margin over the trained ``|grad F| ~ 1``) holds no surface, and its samples take the sign of its
centre (and that distance). Only the other blocks are sampled in full. The samples go to the
project's mesher (:func:`~splinekit.implicit.marching.grid_mesh`), and the deviation is measured
as :func:`~splinekit.implicit.mesh_implicit` does; on a network whose ``|grad F|`` stays below
``L`` the result is the mesh of the full grid, sample for sample.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from ..errors import ParameterError
from ..implicit._checks import positive
from ..implicit.marching import grid_mesh
from ..implicit.meshing import BYTES_PER_GRID_POINT, MAX_GRID_POINTS, PADDING, ImplicitMesh, deviation

__all__ = ["BLOCK", "LIPSCHITZ", "band_mesh"]

BLOCK = 6
"""Cells per side of a block whose centre decides whether it is sampled in full."""
LIPSCHITZ = 2.0
"""Bound assumed on ``|grad F|`` of a trained signed distance (the eikonal term holds it near 1)."""


def band_mesh(implicit, edge_length):
    """The zero set of a neural SDF as a closed ImplicitMesh (module notes); grid as
    :func:`~splinekit.implicit.mesh_implicit` lays it over the implicit's bounds."""
    h = positive(edge_length, "edge_length")
    lo, hi = implicit.bounds
    lo, hi = lo - PADDING * h, hi + PADDING * h
    counts = np.maximum(np.ceil((hi - lo) / h) + 1.0, 2.0)
    total = float(np.prod(counts))
    if not total <= MAX_GRID_POINTS:
        raise ParameterError(f"edge length {h!r} needs {total:.3g} grid points (more than {MAX_GRID_POINTS:.3g})")
    limits.check(BYTES_PER_GRID_POINT * total, f"a meshing grid of {total:.3g} points (step {h!r})")
    n = counts.astype(np.int64)
    spacing = (hi - lo) / (n - 1)
    blocks = -(-(n - 1) // BLOCK)  # ceil: blocks per axis
    bi = np.stack(np.meshgrid(*[np.arange(b) for b in blocks], indexing="ij"), axis=-1).reshape(-1, 3)
    start = bi * BLOCK
    stop = np.minimum(start + BLOCK, n - 1)
    centre = lo + spacing * 0.5 * (start + stop)
    Fc = implicit._value(centre)
    reach = LIPSCHITZ * (0.5 * np.linalg.norm(spacing * (stop - start), axis=1) + np.linalg.norm(spacing))
    near = np.abs(Fc) <= reach
    # far blocks: their centre's value everywhere (the sign is all the mesher needs of them)
    fill = np.repeat(np.repeat(np.repeat(Fc.reshape(*blocks), BLOCK, 0), BLOCK, 1), BLOCK, 2)
    values = np.ascontiguousarray(np.pad(fill, [(0, 1)] * 3, mode="edge")[: n[0], : n[1], : n[2]])
    # near blocks: every sample, block faces included (shared with the neighbours)
    off = np.stack(np.meshgrid(*[np.arange(BLOCK + 1)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    corner = start[near]
    limits.check(len(corner) * len(off) * 48.0, f"a band of {len(corner):,} blocks to sample")
    idx = np.minimum((corner[:, None, :] + off[None]).reshape(-1, 3), n - 1)
    flat = np.unique(np.ravel_multi_index(idx.T, tuple(n)))
    ijk = np.stack(np.unravel_index(flat, tuple(n)), axis=1)
    values.reshape(-1)[flat] = implicit._value(lo + spacing * ijk)
    mesh = grid_mesh(values, lo, spacing)
    V = np.asarray(mesh.vertices)
    T = mesh.topology.face_indices.reshape(-1, 3)
    return ImplicitMesh.of_topology(V, mesh.topology, deviation(implicit, V, T), h)
