"""Normals of a point cloud: PCA over k nearest neighbours, oriented by a minimum spanning tree.

Each point's unoriented normal is the eigenvector of the smallest eigenvalue of
the covariance of its ``k`` nearest neighbours (itself included). Orientation
follows Hoppe et al. 1992: on the k-nearest-neighbour graph weighted by
``1 - |n_i . n_j|`` (small where neighbouring planes agree) a minimum spanning
tree is grown, and every normal is flipped to agree with its parent in the tree,
so that signs propagate across nearly parallel planes first. The flip of a node
is the product of the relative signs along its path to the root; the products
are computed for all nodes at once by pointer jumping (``log2(depth)`` whole-
array steps), not by a walk per point. Each connected piece of the graph is
rooted at its point farthest from the centroid of the cloud, whose normal is
made to point away from the centroid: outward for a closed surface around the
centroid (and for each of several separate closed surfaces whose farthest
point sees the centroid inside).
"""

from __future__ import annotations

import numpy as np

from ..errors import FittingError
from ._cloud import (
    CHUNK,
    as_cloud,
    as_neighbour_count,
    covariances,
    kd_tree,
    neighbours,
    refuse_lost_neighbours,
    smallest_eigenpairs,
)
from ._pointtree import compiled_knn, compiled_normals

__all__ = ["estimate_normals", "orient_normals"]

PLANARITY_RTOL = 1e-12
"""A neighbourhood whose second covariance eigenvalue is below this fraction of
the largest is (numerically) a line or a point: it defines no normal."""

EDGE_FLOOR = 1e-9
"""Added to every graph weight so that exactly parallel neighbours keep an edge
(sparse graphs read a stored zero as "no edge")."""


def estimate_normals(points, k: int = 16, *, orient: bool = True) -> np.ndarray:
    """Unit normals ``(n, 3)`` of a cloud by PCA over each point's ``k`` nearest neighbours.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Finite points (model units), ``n >= k``.
    k : int
        Neighbourhood size, itself included, ``3 <= k <= n``. 10-30 suits
        evenly sampled surfaces; more smooths noise and rounds off edges.
    orient : bool
        Orient consistently by minimum-spanning-tree propagation, outward
        (see :func:`orient_normals`); ``False`` leaves each sign arbitrary.

    Returns
    -------
    ndarray, shape (n, 3)
        Unit normals.

    Raises
    ------
    ControlPointError
        Empty cloud, wrong shape, non-finite coordinates.
    ParameterError
        ``k`` not an integer in ``[3, n]``.
    FittingError
        A neighbourhood is collinear (or all one point): it has no normal.
    """
    P = as_cloud(points, min_count=1)
    k = as_neighbour_count(k, len(P))
    fast = compiled_normals(P, k, want_indices=orient)
    if fast is None:
        _, idx = neighbours(kd_tree(P), P, k)
        N = _pca_normals(P, idx)
    else:  # search and PCA in one compiled pass (same neighbourhoods, same closed-form eigenvectors)
        values, N, kth, idx = fast
        refuse_lost_neighbours(P, kth, k)
        _refuse_flat(P, values, k, 0)
    if orient:
        N = _orient(P, N, idx)
    return N


def orient_normals(points, normals, k: int = 16) -> np.ndarray:
    """Consistently oriented copies ``(n, 3)`` of unoriented unit ``normals``.

    Minimum spanning tree over the ``k``-nearest-neighbour graph weighted by
    ``1 - |n_i . n_j|``; each normal takes the sign that agrees with its tree
    parent; each connected piece is rooted at its point farthest from the
    cloud's centroid, whose normal is turned away from the centroid. The
    result is outward for closed surfaces around the centroid; a thin sheet
    or sharp edges (where neighbouring planes disagree) may still flip.
    """
    P = as_cloud(points, min_count=1)
    N = as_cloud(normals, "normals")
    if N.shape != P.shape:
        raise FittingError(f"normals must have the shape of points {P.shape}, got {N.shape}")
    length = np.linalg.norm(N, axis=1)
    bad = ~(length > 0)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise FittingError(f"normals[{i}] is the zero vector: it has no direction to orient")
    k = as_neighbour_count(k, len(P), minimum=2)
    fast = compiled_knn(P, k)
    if fast is None:
        _, idx = neighbours(kd_tree(P), P, k)
    else:
        d, idx = fast
        refuse_lost_neighbours(P, d[:, -1], k)
    return _orient(P, N / length[:, None], idx)


def _pca_normals(P: np.ndarray, idx: np.ndarray) -> np.ndarray:
    N = np.empty((len(P), 3))
    for s in range(0, len(P), CHUNK):
        stop = min(s + CHUNK, len(P))
        values, N[s:stop] = smallest_eigenpairs(covariances(P, idx, s, stop))
        _refuse_flat(P, values, idx.shape[1], s)
    return N


def _refuse_flat(P: np.ndarray, values: np.ndarray, k: int, start: int) -> None:
    """FittingError naming the first point (from ``start``) whose covariance eigenvalues
    ``values`` (ascending) say its neighbourhood is a line or a point."""
    flat = ~(values[:, 1] > PLANARITY_RTOL * values[:, 2])
    if flat.any():
        i = start + int(np.flatnonzero(flat)[0])
        raise FittingError(
            f"the {k} nearest neighbours of point {i} {P[i].tolist()} are collinear or coincide: "
            "no normal is defined there; remove duplicates or use a larger k"
        )


def _orient(P: np.ndarray, N: np.ndarray, idx: np.ndarray) -> np.ndarray:
    from scipy.sparse import coo_matrix, csr_matrix
    from scipy.sparse.csgraph import (
        breadth_first_order,
        connected_components,
        minimum_spanning_tree,
    )

    n = len(P)
    # the kNN graph straight in CSR form (rows are the points, in order): no sort needed
    keep = idx != np.arange(n)[:, None]
    w = 1.0 - np.abs(np.einsum("nd,nkd->nk", N, N[idx])) + EDGE_FLOOR
    indptr = np.concatenate([[0], np.cumsum(keep.sum(axis=1))])
    graph = csr_matrix((np.maximum(w[keep], EDGE_FLOOR), idx[keep], indptr), shape=(n, n))
    tree = minimum_spanning_tree(graph)
    tree = (tree + tree.T).tocsr()
    n_parts, labels = connected_components(tree, directed=False)
    roots = _farthest_per_label(P, labels, n_parts)
    # one virtual node joined to every root makes the forest a single tree rooted there
    t = tree.tocoo()
    r = np.concatenate([t.row, roots, np.full(n_parts, n)])
    c = np.concatenate([t.col, np.full(n_parts, n), roots])
    d = np.concatenate([t.data, np.ones(2 * n_parts)])
    rooted = coo_matrix((d, (r, c)), shape=(n + 1, n + 1)).tocsr()
    _, parent = breadth_first_order(rooted, n, directed=False, return_predecessors=True)
    parent = parent.astype(np.int64)
    parent[n] = n
    # relative sign of each node against its parent; the roots against "outward"
    sign = np.ones(n + 1)
    inner = np.arange(n)
    pa = parent[:n]
    dots = np.einsum("nd,nd->n", N, N[np.minimum(pa, n - 1)])
    sign[:n] = np.where(dots < 0, -1.0, 1.0)
    sign[roots] = _outward_signs(P, N, roots)
    # pointer jumping: sign[i] becomes the product of the relative signs from i up to the root
    while (parent[:n] != n).any():
        sign[inner] = sign[inner] * sign[parent[inner]]
        parent[inner] = parent[parent[inner]]
    return N * sign[:n, None]


def _farthest_per_label(P: np.ndarray, labels: np.ndarray, n_parts: int) -> np.ndarray:
    X = P - P.mean(axis=0)
    r2 = np.einsum("nd,nd->n", X, X)
    order = np.lexsort((r2, labels))
    last = np.flatnonzero(np.r_[labels[order][1:] != labels[order][:-1], True])
    return order[last][:n_parts]


def _outward_signs(P: np.ndarray, N: np.ndarray, roots: np.ndarray) -> np.ndarray:
    away = P[roots] - P.mean(axis=0)
    return np.where(np.einsum("nd,nd->n", N[roots], away) < 0, -1.0, 1.0)
