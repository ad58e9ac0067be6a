"""Sample counts of the Bézier cells: a-priori estimates and their propagation.

Each cell has a "u node" (the samples along its two u-running edges) and a "v node".
Cell edges that coincide, and neighbouring cells of one patch, link their nodes
(:func:`node_groups`); every connected set of nodes takes the largest count of its
members (:func:`propagate`), so shared edges carry the same samples on both sides.
The a-priori counts (:func:`initial_counts`) come from bounds on the second
derivatives and the angle tolerance.
"""

from __future__ import annotations

import numpy as np

from .cells import edge_samples, second_derivative_bounds
from .welding import close_pairs, components

__all__ = ["MAX_COUNT", "count_rates", "counts_from_rates", "initial_counts", "node_groups", "propagate"]

MAX_COUNT = 4096
"""Largest number of segments per cell and direction."""


def node_groups(cellsets, patch_of, span_of, nsv, weld_tol):
    """Connected sets of cell nodes that must share samples, and per-cell collapsed-edge flags.

    Node ``2 g`` is global cell ``g``'s u samples, ``2 g + 1`` its v samples.
    Returns ``(labels (2 C,), collapsed (C, 4) bool)``.
    """
    pts, ext = [], []
    for cs in cellsets:
        p, e = edge_samples(cs)
        pts.append(p)
        ext.append(e)
    pts = np.concatenate(pts)  # (C, 4, 5, 3)
    ext = np.concatenate(ext)  # (C, 4)
    C = len(pts)
    collapsed = ext <= weld_tol
    flat = pts.reshape(C * 4, 5, 3)
    live = np.flatnonzero(~collapsed.ravel())
    node = 2 * (np.arange(C * 4) // 4) + (np.arange(C * 4) % 4 >= 2)
    links = [np.zeros((0, 2), dtype=np.int64)]
    if live.size > 1:
        pairs = close_pairs(flat[live, 2], weld_tol)
        if len(pairs):
            a, b = live[pairs[:, 0]], live[pairs[:, 1]]
            A, B = flat[a], flat[b]
            same = (np.linalg.norm(A - B, axis=-1) <= weld_tol).all(axis=1)
            flip = (np.linalg.norm(A - B[:, ::-1], axis=-1) <= weld_tol).all(axis=1)
            ok = same | flip
            links.append(np.column_stack([node[a[ok]], node[b[ok]]]))
    # neighbours along a knot line of one patch share nodes (also when the line collapses)
    g = np.arange(C)
    step = nsv[patch_of]
    right = np.flatnonzero(span_of[:, 1] + 1 < step)  # cell (iu, iv + 1) is g + 1
    below = g + step
    down = np.flatnonzero(below < C)
    down = down[patch_of[below[down]] == patch_of[down]]  # cell (iu + 1, iv) is g + nsv
    links.append(np.column_stack([2 * right, 2 * (right + 1)]))
    links.append(np.column_stack([2 * down + 1, 2 * below[down] + 1]))
    links = np.concatenate(links)
    return components(2 * C, links[:, 0], links[:, 1]), collapsed


def initial_counts(cellsets, tol, angle_tol, bounds=None):
    """A-priori sample counts ``(nu, nv)`` per global cell (``bounds``: the cell sets'
    :func:`.cells.second_derivative_bounds` when already computed; they do not depend on ``tol``)."""
    return counts_from_rates(count_rates(cellsets, bounds), tol, angle_tol)


def count_rates(cellsets, bounds=None):
    """``(4, C)`` tolerance-independent factors of the a-priori counts of every global cell:
    the chordal ones ``sqrt((Muu + Muv) / 4)``, ``sqrt((Mvv + Muv) / 4)`` (steps times
    ``sqrt(tol)``) and the angular ones ``Muu / Lu``, ``Mvv / Lv`` (steps times the angle
    tolerance; 0 where the first derivative bound is 0). NaN marks an unbounded cell."""
    rows = []
    for i, cs in enumerate(cellsets):
        Muu, Muv, Mvv, Lu, Lv = second_derivative_bounds(cs) if bounds is None else bounds[i]
        # h_u^2 (Muu + Muv) / 8 + h_v^2 (Mvv + Muv) / 8 >= the bound (h_u^2 Muu + 2 h_u h_v Muv + h_v^2 Mvv) / 8
        with np.errstate(divide="ignore", invalid="ignore"):
            rows.append(np.stack([np.sqrt((Muu + Muv) / 4.0), np.sqrt((Mvv + Muv) / 4.0),
                                  np.where(Lu > 0, Muu / Lu, 0.0), np.where(Lv > 0, Mvv / Lv, 0.0)]))  # fmt: skip
    return np.concatenate(rows, axis=1) if rows else np.zeros((4, 0))


def counts_from_rates(rates, tol, angle_tol):
    """``(nu, nv)`` int64 counts from :func:`count_rates` at the chordal tolerance ``tol`` and
    the angle tolerance ``angle_tol`` (radians or None)."""
    ab = rates[:2] / np.sqrt(tol)
    if angle_tol is not None:
        ab = np.maximum(ab, rates[2:] / angle_tol)  # NaN (unbounded) propagates
    # NaN (an unbounded cell) counts as the most steps; clip takes +inf to MAX_COUNT
    ab[np.isnan(ab)] = MAX_COUNT
    counts = np.clip(np.ceil(ab), 1, MAX_COUNT).astype(np.int64)
    return counts[0], counts[1]


def propagate(nu, nv, labels):
    """Counts raised to the largest of each linked set of nodes."""
    counts = np.empty(2 * nu.size, dtype=np.int64)
    counts[0::2], counts[1::2] = nu, nv
    top = np.zeros(labels.max() + 1, dtype=np.int64)
    np.maximum.at(top, labels, counts)
    counts = top[labels]
    return counts[0::2].copy(), counts[1::2].copy()

