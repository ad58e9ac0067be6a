"""The bounding-volume hierarchy over a mesh's triangles that the compiled searches of
:class:`splinekit.pointcloud.meshdistance.MeshDistance` walk (the nearest-triangle search of
:mod:`._meshdistance_kernels` and the grid kernel of :mod:`._gridsdf_kernels`)."""

from __future__ import annotations

import numpy as np

_LEAF = 4  # triangles per leaf; the kernels assume 4


def _build(V, T, L):
    """The hierarchy's arrays with whole-array numpy: ``(order, tri, tlo, thi, nlo, nhi)``
    (:class:`TriangleBVH`)."""
    m = len(T)
    tri = V[T]  # (m, 3, 3)
    cen = tri.mean(axis=1)
    lo, hi = cen.min(axis=0), cen.max(axis=0)
    q = np.clip(((cen - lo) / np.maximum(hi - lo, 1e-300) * 1023.0).astype(np.int64), 0, 1023)
    code = np.zeros(m, dtype=np.int64)
    for bit in range(10):  # interleave 10 bits per axis
        for ax in range(3):
            code |= ((q[:, ax] >> bit) & 1) << (3 * bit + (2 - ax))
    order = np.argsort(code, kind="stable")
    pad = L * _LEAF - m
    tri_s = tri[order]
    tlo = np.concatenate([tri_s.min(axis=1), np.full((pad, 3), np.inf)])
    thi = np.concatenate([tri_s.max(axis=1), np.full((pad, 3), -np.inf)])
    nlo = np.empty((2 * L, 3))
    nhi = np.empty((2 * L, 3))
    nlo[L:] = tlo.reshape(L, _LEAF, 3).min(axis=1)
    nhi[L:] = thi.reshape(L, _LEAF, 3).max(axis=1)
    s = L // 2
    while s >= 1:
        nlo[s : 2 * s] = np.minimum(nlo[2 * s : 4 * s : 2], nlo[2 * s + 1 : 4 * s : 2])
        nhi[s : 2 * s] = np.maximum(nhi[2 * s : 4 * s : 2], nhi[2 * s + 1 : 4 * s : 2])
        s //= 2
    nlo[0], nhi[0] = np.inf, -np.inf
    return order, tri_s, tlo, thi, nlo, nhi


class TriangleBVH:
    """A complete binary tree over Morton-ordered triangles (``_LEAF`` per leaf),
    stored as a heap: node 1 is the root, node ``i`` has children ``2i, 2i + 1``,
    the leaves are nodes ``L .. 2L - 1``. Built with whole-array numpy or compiled passes."""

    def __init__(self, V, T, kernels=None):
        """``V (nv, 3)``, ``T (m, 3)``; ``kernels``: the compiled set-up module
        (:data:`~._meshsetup.SETUP_KERNELS`), which builds the same arrays bit for bit."""
        m = len(T)
        n_leaves = max(1, -(-m // _LEAF))
        L = 1 << int(np.ceil(np.log2(n_leaves))) if n_leaves > 1 else 1
        if kernels is not None:
            code = np.empty(m, dtype=np.int64)
            kernels.morton_codes(V, T, code)
            order = kernels.radix_order(code)
            tri_s = np.empty((m, 3, 3))
            tlo, thi = np.empty((L * _LEAF, 3)), np.empty((L * _LEAF, 3))
            nlo, nhi = np.empty((2 * L, 3)), np.empty((2 * L, 3))
            kernels.hierarchy(V, T, order, L, tri_s, tlo, thi, nlo, nhi)
        else:
            order, tri_s, tlo, thi, nlo, nhi = _build(V, T, L)
        self.order = order
        self.tri = np.ascontiguousarray(tri_s)
        self.tlo, self.thi = np.ascontiguousarray(tlo), np.ascontiguousarray(thi)
        self.lo, self.hi, self.n_leaves, self.m = nlo, nhi, L, m

    def nearest(self, kernels, points, max_distance=np.inf):
        """Exact nearest triangle of each point within ``max_distance``.

        Returns ``(d (n,), triangle (n,), closest (n, 3), region (n,))``: the
        distance (``inf`` and triangle -1 beyond ``max_distance``), the original
        triangle index, the closest point and its feature (0 face interior,
        1-3 vertex 0-2, 4 edge 01, 5 edge 12, 6 edge 20). ``kernels`` is the compiled
        module (:data:`KERNELS`), whose leaves hold ``_LEAF`` = 4 triangles as here."""
        P = np.ascontiguousarray(points, dtype=np.float64)
        n = len(P)
        d2 = np.full(n, np.inf)
        tri = np.full(n, -1, dtype=np.int64)
        cp = np.zeros((n, 3))
        reg = np.zeros(n, dtype=np.int64)
        limit = float(max_distance) ** 2 if np.isfinite(max_distance) else np.inf
        kernels.nearest(
            P, limit, self.lo, self.hi, self.tlo, self.thi, self.tri, self.n_leaves, self.m, d2, tri, cp, reg
        )
        found = tri >= 0
        tri[found] = self.order[tri[found]]
        return np.sqrt(d2), tri, cp, reg
