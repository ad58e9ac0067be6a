"""The compiled k-nearest-neighbour search of a point cloud, and PCA normals in the same pass.

:func:`compiled_knn` and :func:`compiled_normals` answer what the numpy path answers (scipy's
cKDTree query, then the closed-form eigen-analysis of :mod:`splinekit.pointcloud._cloud`) with
compiled kernels. Two searches, one answer:

- a uniform cell grid (:mod:`splinekit.pointcloud._cellgrid_kernels`): each query reads the
  27 cells around it straight through; only occupied cells are stored (hashed), so empty space
  between clusters or up to a far outlier costs nothing. The fast path, for any cloud whose
  density varies slowly at the scale of a neighbourhood, which is what normals are estimated on;
- a Morton-ordered bounding-volume hierarchy (:mod:`splinekit.pointcloud._knn_kernels`): adapts
  to any distribution. It serves the queries the grid could not settle within two rings of
  cells (outliers, a sparse haze around a dense surface), and whole clouds no grid fits (most
  points in far fewer cells than they need: a blob a million times smaller than the cloud).

The cell side is measured, not assumed: the mean number of points in a point's own cell at
two to four trial sides gives the local dimension of the cloud (about 2 for a surface, 3 for
a volume), from which the side that makes it :data:`OCCUPANCY` ``* k`` follows.

Both return ``None`` when the numpy path should serve (compiled code off or not worth loading,
see :func:`splinekit._kernels.load`). Results come back in the caller's point order.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _kernels

KERNELS = "splinekit.pointcloud._cellgrid_kernels"
"""The grid kernels; the hierarchy's are its attribute ``hierarchy``."""

OCCUPANCY = 0.7
"""Target number of points in a point's own cell, on average, as a fraction of ``k``: for an
evenly sampled surface this makes the cell side about 1.45 times the typical k-th neighbour
distance, so the 27 cells around a point hold its neighbourhood with room to spare. Measured
on torus clouds of 100k and 300k points (k = 16, CPU time of search and normals, sides as
multiples of the k-th distance): 1.25 to 1.45 within 1 % of each other; 1.1 (more queries
going on to the 5 x 5 x 5 block) 1.13 times slower, 1.6 (more candidates) 1.02-1.05 times.
Averaged over points, not cells, so that a sparse haze of points alone in their cells does
not drag the estimate for a dense surface."""

CROWDING = 2.0
"""The grid does not fit when a point's own cell holds more than this times ``k`` points on
average (a query would read far more candidates than the hierarchy visits)."""

SLOTS = 2
"""Table slots per point, rounded up to a power of two (the table is 8 bytes a slot)."""

MAX_CELLS_PER_AXIS = 1 << 20
"""Cells along an axis at most (keeps the row hash of the grid kernels within int64)."""


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


def cell_side(kernels, P: np.ndarray, lo: np.ndarray, ext: np.ndarray, k: int, mask: int) -> float | None:
    """Cell side for the grid search of ``P`` (length), or None when no grid fits (all points
    one point, or extents beyond the float range)."""
    if not (np.isfinite(ext).all() and (ext > 0).any()):
        return None
    # measured: the mean number of *other* points in a point's cell, which grows as h^dim
    target = max(OCCUPANCY * k - 1.0, 0.5)
    floor = float(ext.max()) / (MAX_CELLS_PER_AXIS - 2)

    def others(h):
        return max(kernels.crowding(P, lo, h, _dims(ext, h), mask) - 1.0, 1.0 / len(P))

    # first guess: the side at which the points would fill the bounding box at the target
    h = max(_side_for(ext, len(P) / target), floor)
    m = others(h)
    dim = 2.0  # a surface, until two measurements tell
    for _ in range(8):  # 2-3 on an even cloud; more where clusters far apart need cells far smaller than the box
        step = min(max((target / m) ** (1 / dim), 1 / 16), 16.0)
        if abs(math.log(step)) < 0.05:
            break
        h_new = max(h * step, floor)
        if h_new == h:
            break
        m_new = others(h_new)
        if m_new != m:
            dim = min(max(math.log(m_new / m) / math.log(h_new / h), 1.0), 3.0)
        h, m = h_new, m_new
    return h


class _Grid:
    """The points sorted by cell of a uniform grid (module notes of the grid kernels), for
    points ``P (n, 3)`` in the box ``lo, hi``; ``fits`` False when no grid suits them."""

    def __init__(self, kernels, P: np.ndarray, k: int, lo: np.ndarray, hi: np.ndarray):
        self.lo = lo
        self.mask = (1 << max(4, int(np.ceil(np.log2(SLOTS * len(P)))))) - 1
        with np.errstate(over="ignore", invalid="ignore"):
            ext = hi - self.lo
        h = cell_side(kernels, P, self.lo, ext, k, self.mask)
        self.fits = h is not None
        if not self.fits:
            return
        self.h = h
        self.dims = _dims(ext, h)
        # cell numbers and cell faces are rounded apart by a few ulps of the coordinates
        self.guard = 16 * np.finfo(float).eps * float(np.abs(self.lo).max() + ext.max() + h)
        self.S, self.order, self.start, crowding = kernels.build(P, self.lo, h, self.dims, self.mask)
        self.fits = crowding <= CROWDING * k

    def args(self, k: int):
        return self.S, self.order, self.start, self.lo, self.h, self.guard, self.dims, self.mask, k


class _SortedCloud:
    """Points ``(n, 3)`` sorted along a Morton curve (``order``: sorted -> original index) and
    the box heap over leaves of ``LEAF`` sorted points (module notes of the hierarchy kernels)."""

    def __init__(self, tree, P: np.ndarray, lo: np.ndarray, hi: np.ndarray):
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
        """Sorted positions of the original point indices ``points``, ascending: queries in
        Morton order touch the same nodes one after another (in the callers' order they would
        jump across the tree, several times slower)."""
        if len(points) == len(self.order):
            return np.arange(len(points))
        rank = np.empty_like(self.order)
        rank[self.order] = np.arange(len(self.order))
        return np.sort(rank[points])

    def args(self, points: np.ndarray):
        return self.S, self.order, self.rows_of(points), self.L, self.lo, self.hi


def _search(kernels, P: np.ndarray, k: int, on_grid, on_tree) -> None:
    """Run ``on_grid(grid, unsettled)`` and then ``on_tree(tree, points)`` for the original
    indices the grid left unsettled (all of them when no grid fits)."""
    lo, hi = kernels.bounds(P)
    grid = _Grid(kernels, P, k, lo, hi)
    if grid.fits:
        unsettled = np.empty(len(P), dtype=np.uint8)
        on_grid(grid, unsettled)
        if not unsettled.any():
            return
        points = grid.order[unsettled.view(bool)]
    else:
        points = np.arange(len(P))
    on_tree(_SortedCloud(kernels.hierarchy, P, lo, hi), points)


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
