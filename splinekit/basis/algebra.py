"""Knot algebra on coefficient arrays: refinement, clamping, Bézier
decomposition, degree elevation, knot removal and splitting.

Every function takes control coefficients as an array ``(n, ...)`` whose first
axis runs over the control points; trailing axes are arbitrary, so the same
code serves curves ``(n, dim)``, rational curves in homogeneous form
``(n, dim + 1)`` and surfaces along one direction ``(nu, nv, dim + 1)``.
All operations are linear in the coefficients; the old -> new maps are
available as sparse matrices (``refinement_matrix``) or by applying the
operation to an identity matrix.

Algorithms:
- refinement by the Oslo algorithm (Cohen-Lyche-Riesenfeld 1980; Lyche & Mørken,
  *Spline Methods*, ch. 4), vectorised over all new control points, with the
  loops running over the degree only;
- degree elevation by Bézier decomposition, elevation of every segment at once
  and re-assembly through blossoms (the control point ``Q_j`` of a spline is
  the blossom of any of its polynomial pieces over ``supp N_j`` evaluated at
  ``tau[j+1..j+p]``); this yields the same spline as The NURBS Book's A5.9;
- knot removal as the least-squares inverse of refinement, with the removal
  accepted only when the refined result reproduces the original coefficients
  within tolerance: since the B-splines are non-negative and sum to one, the
  largest coefficient difference bounds the largest geometric deviation.
"""

from __future__ import annotations

from math import comb

import numpy as np
import scipy.sparse as sp

from ..errors import KnotVectorError
from .bspline import find_span

__all__ = [
    "refinement_matrix",
    "refine",
    "insert_knots_to_multiplicity",
    "clamp",
    "clamped_knots",
    "bezier_segments",
    "bezier_elevation_matrix",
    "blossom_bezier",
    "elevate",
    "remove_knots",
    "split",
    "reverse",
]


def _check_subsequence(old: np.ndarray, new: np.ndarray) -> None:
    vo, co = np.unique(old, return_counts=True)
    vn, cn = np.unique(new, return_counts=True)
    idx = np.searchsorted(vn, vo)
    idx = np.clip(idx, 0, vn.size - 1)
    missing = (vn[idx] != vo) | (cn[idx] < co)
    if missing.any():
        k = np.flatnonzero(missing)[0]
        raise KnotVectorError(
            f"the refined knot vector must contain every old knot with at least its multiplicity; "
            f"knot {vo[k]!r} (multiplicity {co[k]}) is missing or less frequent"
        )


def refinement_matrix(degree: int, knots: np.ndarray, new_knots: np.ndarray) -> sp.csr_matrix:
    """Sparse ``(n_new, n_old)`` matrix ``T`` with ``Q = T @ P`` (Oslo algorithm).

    ``new_knots`` must contain ``knots`` as a sub-multiset; the spline with
    knots ``new_knots`` and control points ``T @ P`` equals the original one
    on its domain.
    """
    p = degree
    t = np.asarray(knots, dtype=np.float64)
    tau = np.asarray(new_knots, dtype=np.float64)
    _check_subsequence(t, tau)
    n_new = tau.size - p - 1
    j = np.arange(n_new)
    # mu: the old span holding tau_j, so that t_mu <= tau_j < t_mu+1
    mu = find_span(p, t, tau[j])
    N = np.zeros((p + 1, n_new))
    N[0] = 1.0
    for k in range(1, p + 1):
        x = tau[j + k]
        saved = np.zeros(n_new)
        for r in range(k):
            hi = t[mu + 1 + r]
            lo = t[mu + 1 + r - k]
            temp = N[r] / (hi - lo)
            N[r] = saved + (hi - x) * temp
            saved = (x - lo) * temp
        N[k] = saved
    cols = mu[None, :] - p + np.arange(p + 1)[:, None]
    # On an unclamped knot vector some B-splines have no support inside the
    # domain [a, b]; their coefficients never reach the geometry, and the Oslo
    # formula (an extrapolating blossom there) may give them negative weights.
    # Such a new coefficient copies the old one at the same end instead.
    n_old = t.size - p - 1
    a, b = t[p], t[n_old]
    dead_lo = tau[j + p + 1] <= a
    dead_hi = tau[j] >= b
    if dead_lo.any() or dead_hi.any():
        N[:, dead_lo | dead_hi] = 0.0
        N[0, dead_lo | dead_hi] = 1.0
        cols[0, dead_lo] = np.minimum(j[dead_lo], n_old - 1)
        cols[0, dead_hi] = np.maximum(n_old - (n_new - j[dead_hi]), 0)
        cols[1:, dead_lo | dead_hi] = cols[0, dead_lo | dead_hi]
    rows = np.broadcast_to(j, cols.shape)
    T = sp.csr_matrix((N.ravel(), (rows.ravel(), cols.ravel())), shape=(n_new, t.size - p - 1))
    T.eliminate_zeros()
    return T


def _apply(T: sp.spmatrix, coefs: np.ndarray) -> np.ndarray:
    flat = coefs.reshape(coefs.shape[0], -1)
    out = T @ flat
    return np.asarray(out).reshape((T.shape[0],) + coefs.shape[1:])


def refine(degree: int, knots: np.ndarray, coefs: np.ndarray, new_knots: np.ndarray) -> np.ndarray:
    """Control coefficients of the same spline on the finer ``new_knots``."""
    return _apply(refinement_matrix(degree, knots, new_knots), coefs)


def insert_knots_to_multiplicity(knots: np.ndarray, values, target) -> np.ndarray:
    """The knot vector with each of ``values`` raised to multiplicity ``target``
    (an int or one per value); values already that frequent are left alone."""
    values = np.atleast_1d(np.asarray(values, dtype=np.float64))
    target = np.broadcast_to(np.asarray(target), values.shape)
    have = np.array([np.count_nonzero(knots == v) for v in values], dtype=int)
    extra = np.repeat(values, np.maximum(target - have, 0))
    return np.sort(np.concatenate([knots, extra]), kind="stable")


def clamp(degree: int, knots: np.ndarray, coefs: np.ndarray):
    """The same spline with end knots of multiplicity ``degree + 1``.

    Returns ``(knots, coefs)``; a clamped input is returned unchanged.
    """
    p = degree
    n = knots.size - p - 1
    a, b = knots[p], knots[n]
    if knots[0] == a and knots[-1] == b:
        return knots, coefs
    tau = insert_knots_to_multiplicity(knots, [a, b], p)
    Q = refine(p, knots, coefs, tau)
    # With a of multiplicity m >= p and k knots before it, the first
    # k + m - (p + 1) control points act only left of the domain (for m = p the
    # B-spline that starts at the knot before a is, on [a, b], the clamped end
    # B-spline, so it stays). Same at b.
    n_tau = tau.size - p - 1
    first = np.count_nonzero(tau < a) + np.count_nonzero(tau == a) - (p + 1)
    last = n_tau - (np.count_nonzero(tau > b) + np.count_nonzero(tau == b) - (p + 1))
    return clamped_knots(p, knots), Q[first:last]


def clamped_knots(degree: int, knots: np.ndarray) -> np.ndarray:
    """The clamped knot vector of the same domain and interior knots."""
    p = degree
    a, b = knots[p], knots[knots.size - p - 1]
    inner = knots[(knots > a) & (knots < b)]
    return np.concatenate([np.full(p + 1, a), inner, np.full(p + 1, b)])


def bezier_segments(degree: int, knots: np.ndarray, coefs: np.ndarray):
    """Bézier decomposition (the result of A5.6, computed by refinement).

    Returns ``(breaks, segments)``: ``breaks`` ``(s + 1,)`` are the distinct
    knots of the domain; ``segments`` ``(s, p + 1, ...)`` hold each span's
    Bézier control coefficients on the local parameter [0, 1].
    """
    p = degree
    U, P = clamp(p, knots, coefs)
    interior = np.unique(U[p + 1 : U.size - p - 1])
    tau = insert_knots_to_multiplicity(U, interior, p)
    Q = refine(p, U, P, tau)
    n_seg = interior.size + 1
    breaks = np.concatenate([[U[0]], interior, [U[-1]]])
    # consecutive segments share their end points: rows 0..p, p..2p, ...
    idx = np.arange(n_seg)[:, None] * p + np.arange(p + 1)[None, :]
    return breaks, Q[idx]


def bezier_elevation_matrix(degree: int, by: int) -> np.ndarray:
    """``(p + t + 1, p + 1)`` matrix raising a degree-``p`` Bézier to ``p + t``.

    ``E[i, j] = C(p, j) C(t, i - j) / C(p + t, i)``.
    """
    p, t = degree, by
    E = np.zeros((p + t + 1, p + 1))
    for i in range(p + t + 1):
        for j in range(max(0, i - t), min(p, i) + 1):
            E[i, j] = comb(p, j) * comb(t, i - j) / comb(p + t, i)
    return E


def blossom_bezier(ctrl: np.ndarray, args: np.ndarray) -> np.ndarray:
    """Blossom of Bézier segments at per-level arguments (de Casteljau).

    ``ctrl`` is ``(m, q + 1, ...)`` (one Bézier segment per row, on [0, 1]) and
    ``args`` ``(m, q)``; returns ``(m, ...)``. With all arguments equal to t
    this is de Casteljau's evaluation at t.
    """
    b = ctrl.copy()
    q = ctrl.shape[1] - 1
    extra = (slice(None),) + (None,) * (ctrl.ndim - 2)
    for k in range(q):
        x = args[:, k][extra]
        b = (1.0 - x)[:, None] * b[:, :-1] + x[:, None] * b[:, 1:]
    return b[:, 0]


def _spline_from_pieces(degree: int, knots: np.ndarray, breaks: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Control coefficients of the spline whose pieces are given Bézier segments.

    ``knots`` must be a knot vector of the same spline (right continuity); each
    ``Q_j`` is the blossom of a piece over ``supp N_j`` at ``knots[j+1..j+p]``.
    """
    p = degree
    n = knots.size - p - 1
    j = np.arange(n)
    mid = 0.5 * (knots[j] + knots[j + p + 1])
    seg = np.clip(np.searchsorted(breaks, mid, side="right") - 1, 0, breaks.size - 2)
    a, b = breaks[seg], breaks[seg + 1]
    args = knots[j[:, None] + np.arange(1, p + 1)[None, :]]
    local = (args - a[:, None]) / (b - a)[:, None]
    return blossom_bezier(segments[seg], local)


def elevate(degree: int, knots: np.ndarray, coefs: np.ndarray, by: int = 1):
    """Raise the degree by ``by`` without changing the spline.

    Returns ``(knots, coefs)`` of degree ``degree + by``: every distinct knot
    gains multiplicity ``by`` (the spline keeps its continuity), ends clamped.
    """
    p = degree
    breaks, segs = bezier_segments(p, knots, coefs)
    E = bezier_elevation_matrix(p, by)
    segs_up = np.einsum("ij,sj...->si...", E, segs)
    values, counts = np.unique(clamped_knots(p, knots), return_counts=True)
    new_knots = np.repeat(values, counts + by)
    return new_knots, _spline_from_pieces(p + by, new_knots, breaks, segs_up)


def remove_knots(degree: int, knots: np.ndarray, coefs: np.ndarray, u: float, times: int):
    """Remove ``times`` copies of the knot ``u`` (least squares).

    Returns ``(knots, coefs, deviation)`` where ``deviation`` ``(...,)`` over
    the trailing non-coordinate axes is, per point, the largest distance (norm
    over the last axis) between the original coefficients and those of the
    result refined back; it bounds how far the spline moved (in the space of
    ``coefs``). The caller decides whether it is within tolerance.
    """
    p = degree
    pos = np.flatnonzero(knots == u)
    tau = np.delete(knots, pos[:times])
    T = refinement_matrix(p, tau, knots).toarray()
    flat = coefs.reshape(coefs.shape[0], -1)
    Q, *_ = np.linalg.lstsq(T, flat, rcond=None)
    resid = (T @ Q - flat).reshape(coefs.shape)
    deviation = np.sqrt((resid**2).sum(axis=-1)).max(axis=0)
    return tau, Q.reshape((tau.size - p - 1,) + coefs.shape[1:]), deviation


def split(degree: int, knots: np.ndarray, coefs: np.ndarray, u: float):
    """Split at an interior parameter ``u``: ``((knots_left, coefs_left), (knots_right, coefs_right))``."""
    p = degree
    U, P = clamp(p, knots, coefs)
    tau = insert_knots_to_multiplicity(U, [u], p)
    Q = refine(p, U, P, tau)
    k = int(np.searchsorted(tau, u, side="left"))
    left = (np.concatenate([tau[: k + p], [u]]), Q[:k])
    right = (np.concatenate([[u], tau[k:]]), Q[k - 1 :])
    return left, right


def reverse(degree: int, knots: np.ndarray, coefs: np.ndarray):
    """The same curve traversed backwards on the same domain."""
    p = degree
    n = knots.size - p - 1
    a, b = knots[p], knots[n]
    return (a + b) - knots[::-1], coefs[::-1]
