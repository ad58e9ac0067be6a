"""Simple test and example meshes, built with whole-array numpy operations.

Every primitive returns a :class:`~splinekit.mesh.polymesh.PolyMesh` whose
faces are counter-clockwise seen from outside (normals point outward, or
toward +z for the flat grid).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_int, as_positive
from ..errors import ParameterError
from .polymesh import PolyMesh, check_mesh_size
from .topology import Topology

__all__ = ["icosphere", "box", "torus", "grid"]

MAX_ICOSPHERE_SUBDIVISIONS = 16
"""20 * 4**16 = 86 billion triangles, past any memory; below this the memory budget
(:mod:`splinekit.limits`) decides."""


def _positive(value, name):
    return as_positive(value, name)


def _vector3(value, name, positive=False):
    arr = as_float_array(value, name)
    arr = np.broadcast_to(arr, (3,)) if arr.ndim == 0 else arr
    if arr.shape != (3,) or not np.isfinite(arr).all() or (positive and (arr <= 0).any()):
        what = "3 finite numbers > 0" if positive else "3 finite numbers"
        raise ParameterError(f"{name} must be a number or {what}, got {value!r}")
    return np.array(arr, dtype=np.float64)


def icosphere(subdivisions: int = 2, radius: float = 1.0, center=(0.0, 0.0, 0.0)) -> PolyMesh:
    """Triangulated sphere: an icosahedron split ``subdivisions`` times, vertices on the sphere.

    Each split cuts every triangle into four at its edge midpoints and pushes the
    midpoints out to the sphere. Level ``n`` has ``10 * 4**n + 2`` vertices,
    ``30 * 4**n`` edges and ``20 * 4**n`` triangles; the 12 icosahedron vertices
    keep valence 5, all others have valence 6.
    """
    n = as_int(subdivisions, "subdivisions", minimum=0)
    if n > MAX_ICOSPHERE_SUBDIVISIONS:
        raise ParameterError(f"subdivisions = {n} exceeds {MAX_ICOSPHERE_SUBDIVISIONS}")
    r = _positive(radius, "radius")
    c = _vector3(center, "center")
    check_mesh_size(20 * 4**n, 3, f"icosphere({n})")
    t = (1.0 + 5.0**0.5) / 2.0
    V = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
         [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )
    F = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
         [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
         [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
         [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(n):
        t = Topology(len(V), F.ravel(), np.arange(len(F) + 1) * 3, check=False)
        mid = V[t.edges[:, 0]] + V[t.edges[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        # half-edge k of a face runs from corner k to k + 1: m[:, 0] on (0, 1), m[:, 1] on (1, 2), m[:, 2] on (2, 0)
        m = len(V) + t.halfedge_edge.reshape(F.shape)
        V = np.vstack([V, mid])
        F = np.stack(
            [
                np.stack([F[:, 0], m[:, 0], m[:, 2]], axis=1),
                np.stack([F[:, 1], m[:, 1], m[:, 0]], axis=1),
                np.stack([F[:, 2], m[:, 2], m[:, 1]], axis=1),
                m,
            ],
            axis=1,
        ).reshape(-1, 3)
    return PolyMesh(c + r * V, F)


def box(size=1.0, center=(0.0, 0.0, 0.0)) -> PolyMesh:
    """Axis-aligned box as 8 vertices and 6 outward quads.

    ``size`` is the edge length or the three edge lengths ``(sx, sy, sz)``.
    Vertex ``4 x + 2 y + z`` is the corner on the ``x``, ``y``, ``z`` side (0 = low).
    """
    s = _vector3(size, "size", positive=True)
    c = _vector3(center, "center")
    bits = (np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1
    V = c + (bits - 0.5) * s
    F = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5],   # -x, +x
         [0, 4, 5, 1], [2, 3, 7, 6],   # -y, +y
         [0, 2, 6, 4], [1, 5, 7, 3]],  # -z, +z
        dtype=np.int64,
    )
    return PolyMesh(V, F)


def torus(nu: int = 32, nv: int = 16, R: float = 1.0, r: float = 0.25) -> PolyMesh:
    """Quad torus around the z axis: ``nu`` quads around the z axis, ``nv`` around the tube.

    Vertex ``i * nv + j`` is ``((R + r cos t) cos s, (R + r cos t) sin s, r sin t)``
    with ``s = 2 pi i / nu`` and ``t = 2 pi j / nv``; needs ``0 < r < R`` and
    ``nu, nv >= 3``. Euler characteristic 0.
    """
    nu = as_int(nu, "nu", minimum=3)
    nv = as_int(nv, "nv", minimum=3)
    R = _positive(R, "R")
    r = _positive(r, "r")
    if r >= R:
        raise ParameterError(f"the tube radius r = {r} must be smaller than R = {R}")
    check_mesh_size(nu * nv, 4, f"torus({nu}, {nv})")
    s = 2.0 * np.pi * np.arange(nu) / nu
    t = 2.0 * np.pi * np.arange(nv) / nv
    S, T = np.meshgrid(s, t, indexing="ij")
    rho = R + r * np.cos(T)
    V = np.stack([rho * np.cos(S), rho * np.sin(S), r * np.sin(T)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i1, j1 = (i + 1) % nu, (j + 1) % nv
    F = np.stack([i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1], axis=-1).reshape(-1, 4)
    return PolyMesh(V, F)


def grid(nx: int = 4, ny: int = 4, size=(1.0, 1.0)) -> PolyMesh:
    """Flat quad patch ``[0, sx] x [0, sy]`` in the plane z = 0, normals +z.

    ``nx * ny`` quads, ``(nx + 1) * (ny + 1)`` vertices; vertex ``i * (ny + 1) + j``
    is at ``(sx i / nx, sy j / ny, 0)``. An open disk: Euler characteristic 1.
    """
    nx = as_int(nx, "nx", minimum=1)
    ny = as_int(ny, "ny", minimum=1)
    sz = as_float_array(size, "size")
    sz = np.broadcast_to(sz, (2,)) if sz.ndim == 0 else sz
    if sz.shape != (2,) or not np.isfinite(sz).all() or (sz <= 0).any():
        raise ParameterError(f"size must be a number or 2 finite numbers > 0, got {size!r}")
    check_mesh_size(nx * ny, 4, f"grid({nx}, {ny})")
    x = np.linspace(0.0, sz[0], nx + 1)
    y = np.linspace(0.0, sz[1], ny + 1)
    X, Y = np.meshgrid(x, y, indexing="ij")
    V = np.stack([X, Y, np.zeros_like(X)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    k = i * (ny + 1) + j
    F = np.stack([k, k + ny + 1, k + ny + 2, k + 1], axis=-1).reshape(-1, 4)
    return PolyMesh(V, F)
