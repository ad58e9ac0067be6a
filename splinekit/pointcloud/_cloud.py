"""Checks and neighbourhood helpers shared by the point-cloud functions.

The neighbourhood statistics (covariance, eigen-decomposition) run on chunks
of points so that the ``(chunk, k, 3)`` temporaries stay a few tens of MB even
for clouds of millions of points.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_int
from ..errors import ControlPointError, ParameterError

CHUNK = 65536
"""Points whose neighbourhoods are processed together (bounds temporary memory)."""

DEGENERATE = 1e-13
"""In :func:`smallest_eigenpairs`: cross products of rows of ``C - lambda_min I`` shorter than
this times the squared longest row are rounding noise (the two smallest eigenvalues coincide
to about this fraction). The compiled kernels use the same value."""


def as_cloud(points, name: str = "points", dim: int | None = 3, min_count: int = 1) -> np.ndarray:
    """``points`` as a C-contiguous float64 ``(n, dim)`` array of finite values, ``n >= min_count``."""
    P = as_float_array(points, name, ControlPointError)
    if P.ndim != 2 or (dim is not None and P.shape[1] != dim) or P.shape[1] < 1:
        want = f"(n, {dim})" if dim is not None else "(n, dim)"
        raise ControlPointError(f"{name} must have shape {want}, got an array of shape {P.shape}")
    if P.shape[0] < min_count:
        raise ControlPointError(
            f"{name} is {'empty' if P.shape[0] == 0 else f'only {P.shape[0]} points'}: need at least {min_count}"
        )
    if not np.isfinite(P).all():  # one flat pass; the row is looked for only on failure
        i = int(np.flatnonzero(~np.isfinite(P).all(axis=1))[0])
        raise ControlPointError(f"{name}[{i}] = {P[i].tolist()} is not finite")
    return np.ascontiguousarray(P)


def as_neighbour_count(k, n: int, name: str = "k", minimum: int = 3) -> int:
    """A neighbourhood size ``minimum <= k <= n`` (the point itself counts as one of its ``k``)."""
    k = as_int(k, name, minimum=minimum)
    if k > n:
        raise ParameterError(f"{name} = {k} is larger than the cloud ({n} points)")
    return k


def as_rng(rng) -> np.random.Generator:
    """A numpy Generator from ``None``, a seed or a Generator."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        try:
            return np.random.default_rng(rng)
        except ValueError as exc:
            raise ParameterError(f"rng seed {rng!r} is not usable: {exc}") from None
    raise ParameterError(f"rng must be None, an integer seed or a numpy Generator, got {type(rng).__name__}")


def kd_tree(points: np.ndarray):
    from scipy.spatial import (
        cKDTree,  # imported on use: keeps ``import splinekit`` fast
    )

    return cKDTree(points, balanced_tree=False, compact_nodes=False)


def neighbours(tree, points: np.ndarray, k: int):
    """``(distances (n, k), indices (n, k))`` of the ``k`` nearest cloud points (the point itself first).

    Squared distances beyond the float range (coordinates or offsets above
    about ``1e154``) leave the tree without neighbours: a ControlPointError
    naming the point, not an out-of-range index further on."""
    d, i = tree.query(points, k=k, workers=-1)
    d, i = d.reshape(len(points), k), i.reshape(len(points), k)
    refuse_lost_neighbours(points, np.where((i < tree.n).all(axis=1), d[:, -1], np.inf), k)
    return d, i


def refuse_lost_neighbours(points: np.ndarray, kth: np.ndarray, k: int) -> None:
    """ControlPointError naming the first point whose distance to its k-th neighbour ``kth (n,)``
    is not finite (squared distances overflowed: the search found no such neighbour)."""
    lost = ~np.isfinite(kth)
    if lost.any():
        j = int(np.flatnonzero(lost)[0])
        raise ControlPointError(
            f"the distances from point {j} {np.asarray(points[j]).tolist()} to its {k} nearest cloud points "
            "overflow the float range; rescale the cloud"
        )


def local_frames(points: np.ndarray, idx: np.ndarray):
    """Eigen-decomposition of each neighbourhood's covariance.

    Parameters
    ----------
    points : (n, 3) float64
    idx : (m, k) int
        Neighbour indices of ``m`` query points.

    Returns
    -------
    eigenvalues : (m, 3), ascending (units: length squared)
    eigenvectors : (m, 3, 3), column ``j`` belongs to eigenvalue ``j``
    centroids : (m, 3)
    """
    m, k = idx.shape
    values = np.empty((m, 3))
    vectors = np.empty((m, 3, 3))
    centroids = np.empty((m, 3))
    for s in range(0, m, CHUNK):
        X = points[idx[s:s + CHUNK]]
        c = X.mean(axis=1)
        X -= c[:, None, :]
        C = np.matmul(X.transpose(0, 2, 1), X) / k
        values[s:s + CHUNK], vectors[s:s + CHUNK] = np.linalg.eigh(C)
        centroids[s:s + CHUNK] = c
    return np.maximum(values, 0.0), vectors, centroids


def covariances(points: np.ndarray, idx: np.ndarray, start: int, stop: int) -> np.ndarray:
    """``(stop - start, 3, 3)`` covariances of the neighbourhoods ``idx[start:stop]``."""
    X = points[idx[start:stop]]
    X -= X.mean(axis=1)[:, None, :]
    return np.matmul(X.transpose(0, 2, 1), X) / idx.shape[1]


def smallest_eigenpairs(C: np.ndarray):
    """Closed-form eigen-analysis of symmetric 3 x 3 matrices ``(m, 3, 3)``.

    Returns ``(eigenvalues (m, 3) ascending, unit eigenvector of the smallest (m, 3))``.
    Eigenvalues by the trigonometric solution of the characteristic cubic
    (Smith 1961); the eigenvector as the longest cross product of two rows of
    ``C - lambda_min I``. The vector's error is about ``eps * lambda_max /
    (lambda_mid - lambda_min)``: accurate for surface-like neighbourhoods
    (where ``lambda_mid`` is of the order of ``lambda_max``), meaningless where
    the two smallest eigenvalues coincide (where they coincide to rounding, the
    vector is any unit vector of their common eigenspace). About ten
    times faster than ``numpy.linalg.eigh`` on stacks of 3 x 3 matrices.
    """
    a, b, c = C[:, 0, 0], C[:, 1, 1], C[:, 2, 2]
    d, e, f = C[:, 0, 1], C[:, 1, 2], C[:, 0, 2]
    q = (a + b + c) / 3.0
    aq, bq, cq = a - q, b - q, c - q
    p1 = d * d + e * e + f * f
    p = np.sqrt((aq * aq + bq * bq + cq * cq + 2.0 * p1) / 6.0)
    safe = np.where(p > 0, p, 1.0)
    # det((C - q I) / p) / 2
    r = (aq * (bq * cq - e * e) - d * (d * cq - e * f) + f * (d * e - bq * f)) / (2.0 * safe**3)
    phi = np.arccos(np.clip(r, -1.0, 1.0)) / 3.0
    hi = q + 2.0 * p * np.cos(phi)
    lo = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    mid = 3.0 * q - hi - lo
    values = np.column_stack([lo, mid, hi])
    M = C - lo[:, None, None] * np.eye(3)
    r0, r1, r2 = M[:, 0], M[:, 1], M[:, 2]
    cands = np.stack([np.cross(r0, r1), np.cross(r0, r2), np.cross(r1, r2)], axis=1)
    norms = np.einsum("mjd,mjd->mj", cands, cands)
    best = norms.argmax(axis=1)
    rows = np.arange(len(C))
    v = cands[rows, best]
    # where the two smallest eigenvalues coincide, C - lambda_min I has rank one (its rows all
    # along the top eigenvector) and every cross product is rounding noise: take a vector
    # orthogonal to the longest row instead, which lies in the double eigenvalue's eigenspace
    row2 = np.einsum("mjd,mjd->mj", M, M)
    g = M[rows, row2.argmax(axis=1)]
    noise = norms[rows, best] <= (DEGENERATE * row2.max(axis=1)) ** 2
    if noise.any():
        gn = g[noise]
        axis = np.eye(3)[np.abs(gn).argmin(axis=1)]
        ortho = np.cross(gn, axis)
        zero = ~(np.einsum("md,md->m", ortho, ortho) > 0)  # the zero matrix: any direction
        ortho[zero] = (0.0, 0.0, 1.0)
        v[noise] = ortho
    length = np.sqrt(np.einsum("md,md->m", v, v))
    v /= np.where(length > 0, length, 1.0)[:, None]
    return values, v
