"""Close pairs of points and the connected sets their links form, in whole-array numpy.

Edge pairing (:func:`.topology.pair_by_samples`), vertex clustering and the tessellator's
welding (:mod:`splinekit.tessellation.welding`, which adds compiled kernels on top) all ask the
same two questions of small, sparse point sets: which points lie within a distance of each
other (:func:`close_pairs`), and which nodes a list of links joins (:func:`link_components`).
Both are answered here without building a k-d tree or a sparse matrix where a sort does.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SWEEP", "close_pairs", "link_components"]

SWEEP = np.array([0.5773502691896258, 0.6289340932953637, -0.5206089939262417])
"""Unit direction of the sweep in :func:`close_pairs`: generic, so that the planes
of axis-aligned geometry do not project many points onto one value."""


def close_pairs(X, r) -> np.ndarray:
    """``(k, 2)`` index pairs ``i != j`` of the points ``X`` ``(n, 3)`` at most ``r`` apart
    (model units; each pair once, in no particular order).

    A sweep along :data:`SWEEP`: points are sorted by their projection, each is paired with
    those whose projection lies within ``r`` above its own, and the candidates are kept when they
    are truly within ``r``. Points to pair are few and isolated, so the candidates are few; should
    they not be (many points on a plane across the sweep: over ``16 n + 1000`` candidates), a k-d
    tree answers instead.
    """
    X = np.asarray(X, dtype=np.float64)
    n = len(X)
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64)
    proj = X @ SWEEP
    order = np.argsort(proj, kind="stable")
    ps = proj[order]
    # the margin covers rounding of the projections; the exact test follows
    end = np.searchsorted(ps, ps + r * (1.0 + 1e-6) + 4.0 * np.finfo(float).eps * np.abs(ps), side="right")
    count = end - np.arange(1, n + 1)
    total = int(count.sum())
    if total > 16 * n + 1000:
        return kd_pairs(X, r)
    i = np.repeat(np.arange(n), count)
    j = i + 1 + (np.arange(total) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[i], order[j]
    d = X[a] - X[b]
    ok = np.einsum("ij,ij->i", d, d) <= r * r
    return np.column_stack([a[ok], b[ok]])


def kd_pairs(X, r) -> np.ndarray:
    """:func:`close_pairs` by a k-d tree (for point sets the sweep would compare too often)."""
    from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep

    return cKDTree(X).query_pairs(r=float(r), output_type="ndarray").astype(np.int64, copy=False)


def link_components(n: int, a, b) -> np.ndarray:
    """``(n,)`` label of each of ``n`` nodes linked by the edges ``a[k] - b[k]`` (index arrays
    ``(k,)``): the smallest node of its connected component.

    Roots hook onto the smallest root they are linked to, then every node jumps to its root; a
    few rounds of whole-array operations, far cheaper than building a sparse graph for the few
    thousand links of a shell (scipy's ``connected_components`` costs ~0.2 ms in checks alone).
    """
    a = np.asarray(a, dtype=np.intp)
    b = np.asarray(b, dtype=np.intp)
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


def first_use_labels(smallest: np.ndarray) -> np.ndarray:
    """Dense labels ``0, 1, ...`` numbered in order of each component's smallest node, from the
    labels of :func:`link_components` (``(n,)``)."""
    first = smallest == np.arange(len(smallest))
    return (np.cumsum(first) - 1)[smallest]
