"""Corner arithmetic shared by the compiled subdivision kernels (numba, ``cache=True``), and the
numbering the kernels agree on with :mod:`splinekit.subdiv._compiled`.

Corners of uniform meshes (``k = 4`` quads, ``k = 3`` triangles) are located by arithmetic; other
meshes pass ``cf`` (face of each corner). Helpers take scalars only: numba reference-counts every
array argument of an inlined function on each call, which cost more than the rows themselves.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_CHUNK = 1024
"""Rows (corners, edges) per task of the parallel kernels."""
SMOOTH, DART, CREASE, CORNER = 0, 1, 2, 3
CATMULL_CLARK, LOOP = 0, 1


# -- corners ------------------------------------------------------------------------------------
# Helpers take scalars only (see the module docstring). Face ``f`` spans corners ``fs .. fe - 1``.
@njit(cache=True, inline="always")
def _nxt(c, k, fs, fe):
    if k == 4:
        return c - 3 if (c & 3) == 3 else c + 1
    if k == 3:
        return c - 2 if c % 3 == 2 else c + 1
    return fs if c + 1 == fe else c + 1


@njit(cache=True, inline="always")
def _prv(c, k, fs, fe):
    if k == 4:
        return c + 3 if (c & 3) == 0 else c - 1
    if k == 3:
        return c + 2 if c % 3 == 0 else c - 1
    return fe - 1 if c == fs else c - 1


@njit(cache=True, inline="always")
def _fof(c, k):
    """Face of corner ``c`` of a uniform mesh (``k`` 3 or 4)."""
    return c >> 2 if k == 4 else c // 3


@njit(cache=True)
def vertex_corners(fi, n_vertices, edges):
    """Corners of each vertex (ascending) as CSR ``(offsets (V+1,), corners (H,) int32)`` and the
    valence (edges per vertex)."""
    H = fi.size
    vc_off = np.zeros(n_vertices + 1, np.int64)
    for h in range(H):
        vc_off[fi[h] + 1] += 1
    for v in range(n_vertices):
        vc_off[v + 1] += vc_off[v]
    pos = vc_off[:-1].copy()
    vc = np.empty(H, np.int32)
    for h in range(H):
        v = fi[h]
        vc[pos[v]] = h
        pos[v] += 1
    valence = np.zeros(n_vertices, np.int64)
    for e in range(edges.shape[0]):
        valence[edges[e, 0]] += 1
        valence[edges[e, 1]] += 1
    return vc_off, vc, valence
