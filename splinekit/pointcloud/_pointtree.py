"""The compiled k-nearest-neighbour search of a point cloud, and PCA normals in the same pass.

:func:`compiled_knn` and :func:`compiled_normals` answer what the numpy path answers (scipy's
cKDTree query, then the closed-form eigen-analysis of :mod:`splinekit.pointcloud._cloud`) with
the kernels of :mod:`splinekit.pointcloud._knn_kernels` (module notes there: a Morton-ordered
point hierarchy, queries in Morton order, the normal computed while the neighbourhood is in
cache). Both return ``None`` when the numpy path should serve (compiled code off or not worth
loading, see :func:`splinekit._kernels.load`). Results come back in the caller's point order.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels

KERNELS = "splinekit.pointcloud._knn_kernels"


def _kernels_for(n: int, k: int):
    # the numpy path spends about 4 microseconds a point at k = 16 (query + covariance +
    # eigenvectors), four of the loader's work units; it grows about linearly with k
    return _kernels.load(KERNELS, work=n * k / 4)


class _SortedCloud:
    """Points ``(n, 3)`` sorted along a Morton curve (``order``: sorted -> original index) and
    the box heap over leaves of ``LEAF`` sorted points (module notes of the kernels)."""

    def __init__(self, kernels, P: np.ndarray):
        lo, hi = P.min(axis=0), P.max(axis=0)
        with np.errstate(over="ignore", divide="ignore"):
            ext = hi - lo
            inv = np.where((ext > 0) & np.isfinite(ext), float((1 << 21) - 1) / np.where(ext > 0, ext, 1.0), 0.0)
        codes = kernels.morton_codes(P, lo, inv)
        self.order = np.argsort(codes, kind="stable")
        self.S = np.ascontiguousarray(P[self.order])
        n_leaves = max(1, -(-len(P) // kernels.LEAF))
        self.L = 1 << int(np.ceil(np.log2(n_leaves))) if n_leaves > 1 else 1
        self.lo, self.hi = kernels.node_boxes(self.S, self.L)

    def unsort_rows(self, A: np.ndarray) -> np.ndarray:
        out = np.empty_like(A)
        out[self.order] = A
        return out

    def unsort_indices(self, idx: np.ndarray) -> np.ndarray:
        return self.unsort_rows(self.order[idx])


def compiled_knn(P: np.ndarray, k: int):
    """``(distances (n, k), indices (n, k))`` of the ``k`` nearest points of every point of
    ``P`` (itself first, ascending), or None for the numpy path. A row whose distances
    overflow the float range has ``inf`` distances (indices then meaningless)."""
    kernels = _kernels_for(len(P), k)
    if kernels is None:
        return None
    cloud = _SortedCloud(kernels, P)
    d2 = np.empty((len(P), k))
    idx = np.empty((len(P), k), dtype=np.int64)
    kernels.knn(cloud.S, cloud.lo, cloud.hi, cloud.L, k, d2, idx)
    lost = idx < 0
    idx[lost] = 0
    d = np.sqrt(d2)
    d[lost] = np.inf
    return cloud.unsort_rows(d), cloud.unsort_indices(idx)


def compiled_normals(P: np.ndarray, k: int, want_indices: bool):
    """PCA over the ``k`` nearest neighbours of every point, or None for the numpy path.

    Returns ``(eigenvalues (n, 3) ascending, unit normals (n, 3), k-th neighbour distance (n,),
    neighbour indices (n, k) or None)``; the distance is ``inf`` where distances overflow the
    float range (the other values of that row are then meaningless)."""
    kernels = _kernels_for(len(P), k)
    if kernels is None:
        return None
    cloud = _SortedCloud(kernels, P)
    n = len(P)
    values, normals, kth = np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
    idx = np.empty((n if want_indices else 0, k), dtype=np.int64)
    kernels.knn_normals(cloud.S, cloud.lo, cloud.hi, cloud.L, k, values, normals, kth, idx, want_indices)
    idx_out = None
    if want_indices:
        idx[idx < 0] = 0
        idx_out = cloud.unsort_indices(idx)
    return cloud.unsort_rows(values), cloud.unsort_rows(normals), np.sqrt(cloud.unsort_rows(kth)), idx_out
