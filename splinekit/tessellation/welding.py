"""Coincident points and the connected sets they form.

The tessellator welds grid-border vertices that lie within the weld distance (the
patches' shared edges, collapsed edges) and links cell edges that coincide; both need
the close pairs of a point set (:func:`close_pairs`) and the connected components of
the resulting links (:func:`components`). Compiled kernels serve both once loaded
(:mod:`splinekit._kernels`); the numpy path gives the same results.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels

__all__ = ["SWEEP", "close_pairs", "components"]


SWEEP = np.array([0.5773502691896258, 0.6289340932953637, -0.5206089939262417])
"""Unit direction of the sweep in :func:`close_pairs`: generic, so that the planes
of axis-aligned geometry do not project many points onto one value."""


def close_pairs(X, r):
    """``(k, 2)`` index pairs ``i != j`` of the points ``X`` ``(n, 3)`` at most ``r`` apart
    (each pair once). A sweep along one direction: points are sorted by their
    projection, each is paired with those whose projection lies within ``r`` above
    its own, and the candidates are kept when they are truly within ``r``. Points to
    weld are few and isolated, so the candidates are few; should they not be (many
    points on a plane across the sweep), a k-d tree answers instead."""
    n = len(X)
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64)
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        pairs, ok = jit.close_pairs(np.ascontiguousarray(X, dtype=np.float64), float(r), SWEEP, 16 * n + 1000)
        if ok:
            return pairs
        from scipy.spatial import cKDTree

        return cKDTree(X).query_pairs(r=r, output_type="ndarray")
    proj = X @ SWEEP
    order = np.argsort(proj, kind="stable")
    ps = proj[order]
    # the margin covers rounding of the projections; the exact test follows
    end = np.searchsorted(ps, ps + r * (1.0 + 1e-6) + 4.0 * np.finfo(float).eps * np.abs(ps), side="right")
    count = end - np.arange(1, n + 1)
    total = int(count.sum())
    if total > 16 * n + 1000:
        from scipy.spatial import cKDTree

        return cKDTree(X).query_pairs(r=r, output_type="ndarray")
    i = np.repeat(np.arange(n), count)
    j = i + 1 + (np.arange(total) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[i], order[j]
    d = X[a] - X[b]
    ok = np.einsum("ij,ij->i", d, d) <= r * r
    return np.column_stack([a[ok], b[ok]])


def components(n, a, b):
    """``(n,)`` label of each of ``n`` nodes linked by the edges ``a[k] - b[k]``: the smallest
    node of its connected component. Roots hook onto the smallest root they are linked
    to, then every node jumps to its root; a few rounds of whole-array operations, far
    cheaper than building a sparse graph for the small graphs of a tessellation (or
    a compiled union-find with the same labels)."""
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        return jit.components(int(n), np.ascontiguousarray(a, dtype=np.int64), np.ascontiguousarray(b, dtype=np.int64))
    lab = np.arange(n)
    while a.size:
        la, lb = lab[a], lab[b]
        lo = np.minimum(la, lb)
        new = lab.copy()
        np.minimum.at(new, la, lo)
        np.minimum.at(new, lb, lo)
        while True:  # pointer jumping: labels only decrease, so this ends at the roots
            jumped = new[new]
            if np.array_equal(jumped, new):
                break
            new = jumped
        if np.array_equal(new, lab):
            break
        lab = new
    return lab

