"""The compiled k-nearest-neighbour search of a point cloud, and PCA normals in the same pass.

:func:`compiled_knn` and :func:`compiled_normals` answer what the numpy path answers (scipy's
cKDTree query, then the closed-form eigen-analysis of :mod:`splinekit.pointcloud._cloud`) with
compiled kernels. Two searches, one answer:

- a uniform cell grid (:mod:`splinekit.pointcloud._cellgrid_kernels`): each query reads the
  27 cells around it straight through; the fast path for surfaces and volumes sampled at a
  roughly even density, which is what normals are estimated on;
- a Morton-ordered bounding-volume hierarchy (:mod:`splinekit.pointcloud._knn_kernels`): adapts
  to any distribution. It serves the queries the grid could not settle within two rings of
  cells (outliers, density jumps), and whole clouds a grid does not fit (tight clusters far
  apart: one cell size cannot suit both the clusters and the space between them).

The cell side is measured, not assumed: the share of non-empty cells at two or three trial
sizes gives the local dimension of the cloud (about 2 for a surface, 3 for a volume), from
which the side that puts about :data:`OCCUPANCY` ``* k`` points in a non-empty cell follows.

Both return ``None`` when the numpy path should serve (compiled code off or not worth loading,
see :func:`splinekit._kernels.load`). Results come back in the caller's point order.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _kernels

KERNELS = "splinekit.pointcloud._cellgrid_kernels"
"""The grid kernels; the hierarchy's are its attribute ``hierarchy``."""

OCCUPANCY = 0.4
"""Target points per non-empty cell, as a fraction of ``k``: for a surface this makes the cell
side about 1.2 times the typical k-th neighbour distance, so the 27 cells around a point hold
its neighbourhood with room to spare (measured fastest on torus clouds of 100k-1M points)."""

CROWDING = 2.0
"""The grid does not fit when a point's own cell holds more than this times ``k`` points on
average (a query would read far more candidates than the hierarchy visits)."""

MAX_CELLS = 2
"""Cells per point at most (the grid's start table is 8 bytes a cell)."""


def _kernels_for(n: int, k: int):
    # the numpy path spends about 4 microseconds a point at k = 16 (query + covariance +
    # eigenvectors), four of the loader's work units; it grows about linearly with k
    return _kernels.load(KERNELS, work=n * k / 4)


def _dims(ext: np.ndarray, h: float) -> np.ndarray:
    return (np.floor(ext / h) + 1).astype(np.int64)


def _side_for(ext: np.ndarray, cells: float) -> float:
    """The side of ``cells`` cubes filling the box of extents ``ext`` (zero extents ignored);
    in logarithms, since the box's volume may overflow."""
    spread = ext[ext > 0]
    return float(np.exp((np.log(spread).sum() - math.log(cells)) / len(spread)))


def _smallest_side(ext: np.ndarray, n: int) -> float:
    """Smallest cell side whose grid over extents ``ext`` has at most ``MAX_CELLS * n + 64`` cells."""
    cap = MAX_CELLS * n + 64
    h = _side_for(ext, cap)
    while np.prod(_dims(ext, h).astype(float)) > cap:
        h *= 1.05
    return h


def cell_side(kernels, P: np.ndarray, lo: np.ndarray, ext: np.ndarray, k: int) -> float | None:
    """Cell side for the grid search of ``P`` (length), or None when no grid fits (all points
    one point, or extents beyond the float range)."""
    n = len(P)
    if not (np.isfinite(ext).all() and (ext > 0).any()):
        return None
    target = max(1.0, OCCUPANCY * k)
    floor = _smallest_side(ext, n)
    # first guess: the side at which the points would fill the bounding box at the target
    h = max(_side_for(ext, n / target), floor)
    m = n / kernels.occupied_cells(P, lo, h, _dims(ext, h))
    dim = 2.0  # a surface, until two measurements tell
    for _ in range(2):
        step = (target / m) ** (1 / dim)
        if abs(math.log(step)) < 0.05:
            break
        h_new = max(h * step, floor)
        if h_new == h:
            break
        m_new = n / kernels.occupied_cells(P, lo, h_new, _dims(ext, h_new))
        if m_new != m:
            dim = min(max(math.log(m_new / m) / math.log(h_new / h), 1.0), 3.0)
        h, m = h_new, m_new
    return h


class _Grid:
    """The points sorted by cell of a uniform grid (module notes of the grid kernels)."""

    def __init__(self, kernels, P: np.ndarray, k: int):
        self.lo, hi = kernels.bounds(P)
        with np.errstate(over="ignore", invalid="ignore"):
            ext = hi - self.lo
        h = cell_side(kernels, P, self.lo, ext, k)
        self.fits = h is not None
        if not self.fits:
            return
        self.h = h
        self.dims = _dims(ext, h)
        # cell numbers and cell faces are rounded apart by a few ulps of the coordinates
        self.guard = 16 * np.finfo(float).eps * float(np.abs(self.lo).max() + ext.max() + h)
        self.S, self.order, self.start, crowding = kernels.build(P, self.lo, h, self.dims)
        self.fits = crowding <= CROWDING * k

    def args(self, k: int):
        return self.S, self.order, self.start, self.lo, self.h, self.guard, self.dims, k


class _SortedCloud:
    """Points ``(n, 3)`` sorted along a Morton curve (``order``: sorted -> original index) and
    the box heap over leaves of ``LEAF`` sorted points (module notes of the hierarchy kernels)."""

    def __init__(self, tree, P: np.ndarray):
        lo, hi = P.min(axis=0), P.max(axis=0)
        with np.errstate(over="ignore", divide="ignore"):
            ext = hi - lo
            inv = np.where((ext > 0) & np.isfinite(ext), float((1 << 21) - 1) / np.where(ext > 0, ext, 1.0), 0.0)
        codes = tree.morton_codes(P, lo, inv)
        self.order = np.argsort(codes, kind="stable")
        self.S = np.ascontiguousarray(P[self.order])
        n_leaves = max(1, -(-len(P) // tree.LEAF))
        self.L = 1 << int(np.ceil(np.log2(n_leaves))) if n_leaves > 1 else 1
        self.lo, self.hi = tree.node_boxes(self.S, self.L)

    def rows_of(self, points: np.ndarray) -> np.ndarray:
        """Sorted positions of the original point indices ``points``."""
        rank = np.empty_like(self.order)
        rank[self.order] = np.arange(len(self.order))
        return rank[points]

    def args(self, points: np.ndarray):
        return self.S, self.order, self.rows_of(points), self.L, self.lo, self.hi


def _search(kernels, P: np.ndarray, k: int, on_grid, on_tree) -> None:
    """Run ``on_grid(grid, unsettled)`` and then ``on_tree(tree, points)`` for the original
    indices the grid left unsettled (all of them when no grid fits)."""
    grid = _Grid(kernels, P, k)
    if grid.fits:
        unsettled = np.empty(len(P), dtype=np.uint8)
        on_grid(grid, unsettled)
        if not unsettled.any():
            return
        points = grid.order[unsettled.view(bool)]
    else:
        points = np.arange(len(P))
    on_tree(_SortedCloud(kernels.hierarchy, P), points)


def compiled_knn(P: np.ndarray, k: int):
    """``(distances (n, k), indices (n, k))`` of the ``k`` nearest points of every point of
    ``P`` (itself first, ascending), or None for the numpy path. A row whose distances
    overflow the float range has ``inf`` distances (indices then meaningless)."""
    kernels = _kernels_for(len(P), k)
    if kernels is None:
        return None
    n = len(P)
    d = np.empty((n, k))
    idx = np.empty((n, k), dtype=np.int64)
    none = np.empty(0), np.empty((0, 3)), np.empty((0, 3))
    _search(kernels, P, k,
            lambda grid, unsettled: kernels.search(*grid.args(k), d, idx, *none, unsettled),
            lambda tree, points: kernels.hierarchy.knn(*tree.args(points), k, d, idx))
    return d, idx


def compiled_normals(P: np.ndarray, k: int, want_indices: bool):
    """PCA over the ``k`` nearest neighbours of every point, or None for the numpy path.

    Returns ``(eigenvalues (n, 3) ascending, unit normals (n, 3), k-th neighbour distance (n,),
    neighbour indices (n, k) or None)``; the distance is ``inf`` where distances overflow the
    float range (the other values of that row are then meaningless)."""
    kernels = _kernels_for(len(P), k)
    if kernels is None:
        return None
    n = len(P)
    values, normals, kth = np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
    idx = np.empty((n if want_indices else 0, k), dtype=np.int64)
    no_d = np.empty((0, k))
    _search(kernels, P, k,
            lambda grid, unsettled: kernels.search(*grid.args(k), no_d, idx, kth, values, normals, unsettled),
            lambda tree, points: kernels.hierarchy.knn_normals(*tree.args(points), k, values, normals, kth, idx,
                                                               want_indices))
    return values, normals, np.sqrt(kth), idx if want_indices else None
