"""Vectorized test-mesh generators for the subdivision benchmark.

Every generator returns ``(V, F)``: ``V`` an ``(n, 3)`` float64 array and ``F``
an ``(f, k)`` int64 array of faces, counter-clockwise seen from outside
(consistently oriented, closed, manifold).  Nothing loops per face or per
vertex; the only Python loop is over icosphere levels.

- :func:`icosahedron`: 12 vertices, 20 triangles, on the unit sphere.
- :func:`icosphere`: the icosahedron split ``level`` times (each triangle into
  four at the edge midpoints), new points projected onto the unit sphere;
  ``20 * 4**level`` triangles.
- :func:`cube`: 8 vertices, 6 quads, the cube ``[-1, 1]^3``.
- :func:`torus`: ``nu * nv`` quads on a torus with radii ``R`` and ``r``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["icosahedron", "icosphere", "cube", "torus", "unique_edges"]


def icosahedron() -> tuple[np.ndarray, np.ndarray]:
    """The regular icosahedron inscribed in the unit sphere (12 vertices, 20 triangles)."""
    t = (1.0 + 5.0**0.5) / 2.0
    V = np.array(
        [
            [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
            [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
            [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
        ],
        dtype=np.float64,
    )
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    F = np.array(
        [
            [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
            [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
            [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
            [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
        ],
        dtype=np.int64,
    )
    return V, F


def unique_edges(F: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Undirected edges ``(E, 2)`` (sorted pairs) and, per half-edge ``(f, k)``, its edge id.

    Half-edge ``(i, j)`` runs from ``F[i, j]`` to ``F[i, (j + 1) % k]``.
    """
    a = F
    b = np.roll(F, -1, axis=1)
    lo = np.minimum(a, b).ravel()
    hi = np.maximum(a, b).ravel()
    key = lo * np.int64(n_vertices) + hi
    ukey, inv = np.unique(key, return_inverse=True)
    edges = np.column_stack([ukey // n_vertices, ukey % n_vertices])
    return edges, inv.reshape(F.shape)


def icosphere(level: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Icosahedron split ``level`` times at edge midpoints, projected to the unit sphere.

    ``10 * 4**level + 2`` vertices, ``20 * 4**level`` triangles.
    """
    V, F = icosahedron()
    for _ in range(int(level)):
        n = len(V)
        edges, he = unique_edges(F, n)
        mid = V[edges[:, 0]] + V[edges[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        V = np.vstack([V, mid])
        e = he + n  # new vertex on half-edge (i, j): from corner j to corner j + 1
        v0, v1, v2 = F[:, 0], F[:, 1], F[:, 2]
        e01, e12, e20 = e[:, 0], e[:, 1], e[:, 2]
        F = np.stack(
            [
                np.column_stack([v0, e01, e20]),
                np.column_stack([v1, e12, e01]),
                np.column_stack([v2, e20, e12]),
                np.column_stack([e01, e12, e20]),
            ],
            axis=1,
        ).reshape(-1, 3)
    return V, F


def cube() -> tuple[np.ndarray, np.ndarray]:
    """The cube ``[-1, 1]^3``: 8 vertices, 6 quads with outward normals."""
    i = np.arange(8)
    V = np.column_stack([(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1]).astype(np.float64) * 2.0 - 1.0
    F = np.array(
        [
            [0, 2, 3, 1],  # z = -1
            [4, 5, 7, 6],  # z = +1
            [0, 1, 5, 4],  # y = -1
            [2, 6, 7, 3],  # y = +1
            [0, 4, 6, 2],  # x = -1
            [1, 3, 7, 5],  # x = +1
        ],
        dtype=np.int64,
    )
    return V, F


def torus(nu: int = 100, nv: int = 100, R: float = 1.0, r: float = 0.35) -> tuple[np.ndarray, np.ndarray]:
    """A torus of ``nu * nv`` quads (``nu`` around the axis, ``nv`` around the tube).

    Vertex ``(i, j)`` is ``i * nv + j``; every vertex has valence 4.
    """
    if nu < 3 or nv < 3:
        raise ValueError("a torus needs nu, nv >= 3")
    u = np.arange(nu) * (2.0 * np.pi / nu)
    v = np.arange(nv) * (2.0 * np.pi / nv)
    cu, su = np.cos(u)[:, None], np.sin(u)[:, None]
    cv, sv = np.cos(v)[None, :], np.sin(v)[None, :]
    ring = R + r * cv
    V = np.stack(
        [np.broadcast_to(ring * cu, (nu, nv)), np.broadcast_to(ring * su, (nu, nv)), np.broadcast_to(r * sv, (nu, nv))],
        axis=-1,
    ).reshape(-1, 3)
    i = np.arange(nu)[:, None]
    j = np.arange(nv)[None, :]
    i1 = (i + 1) % nu
    j1 = (j + 1) % nv
    a = i * nv + j
    b = i1 * nv + j
    c = i1 * nv + j1
    d = i * nv + j1
    # (u, v) -> position has outward normal d/du x d/dv, so (a, b, c, d) is counter-clockwise from outside
    F = np.stack([a, b, c, d], axis=-1).reshape(-1, 4).astype(np.int64)
    return np.ascontiguousarray(V), F


def mixed_torus(nu: int = 100, nv: int = 100, R: float = 1.0, r: float = 0.35):
    """A closed torus of triangles, quads and pentagons interleaved face by face.

    Returns ``(V, indices, offsets)``: ``V`` ``(n, 3)``, the flat corner indices and the
    ``(F + 1,)`` face offsets (CSR). It is :func:`torus` (``nv`` a multiple of 4) with a midpoint
    vertex on every edge ``(i, j) - (i + 1, j)`` with ``j % 4 == 0``: in each block of four quads
    along ``j`` the first and last become pentagons, the second is split into two triangles and
    the third stays a quad, so consecutive faces have sizes 5, 3, 3, 4, 5, 5, 3, 3, 4, 5, ...
    ``5 * nu * nv / 4`` faces.
    """
    if nv % 4:
        raise ValueError("mixed_torus needs nv divisible by 4")
    V, Q = torus(nu, nv, R, r)
    Q = Q.reshape(nu, nv // 4, 4, 4)  # (i, block, j % 4, corner a b c d)
    n = nu * nv
    mid_index = n + np.arange(nu * (nv // 4)).reshape(nu, nv // 4)
    edge = Q[:, :, 0, :2]  # the edges (a, b) of the quads with j % 4 == 0
    M = 0.5 * (V[edge[..., 0]] + V[edge[..., 1]]).reshape(-1, 3)
    m_low = mid_index  # on the bottom edge a-b of the quad j % 4 == 0
    m_high = np.roll(mid_index, -1, axis=1)  # on the top edge c-d of the quad j % 4 == 3 (next block)
    q0, q1, q2, q3 = (Q[:, :, k] for k in range(4))
    parts = [
        q0[..., 0], m_low, q0[..., 1], q0[..., 2], q0[..., 3],  # pentagon
        q1[..., 0], q1[..., 1], q1[..., 2],  # triangle
        q1[..., 0], q1[..., 2], q1[..., 3],  # triangle
        q2[..., 0], q2[..., 1], q2[..., 2], q2[..., 3],  # quad
        q3[..., 0], q3[..., 1], q3[..., 2], m_high, q3[..., 3],  # pentagon
    ]
    indices = np.stack(parts, axis=-1).reshape(-1).astype(np.int64)
    sizes = np.tile(np.array([5, 3, 3, 4, 5], dtype=np.int64), nu * (nv // 4))
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return np.vstack([V, M]), indices, offsets
