"""``curve_distances``: the distances of many point sets, each to its own curve, with one batched
Newton search for all of them (what :func:`~splinekit.closest.project` does for one curve)."""

from __future__ import annotations

import numpy as np

from ..curves.batch import CurveBatch
from ..errors import ParameterError
from .newton import nearest_per_point, newton_search
from .parametric import _Curve
from .projection import project
from .queries import _as_query_points

__all__ = ["curve_distances"]


class _Curves:
    """Many curves as :func:`newton_search` sees them with ``rows`` (row ``i``: curve ``i`` of
    the :class:`~splinekit.curves.batch.CurveBatch`); ``size`` per seed."""

    def __init__(self, batch: CurveBatch, size):
        self.batch, self.size = batch, size
        self.hi = batch.domains[:, 1:]

    def derivs(self, x, rows):
        d = self.batch.derivatives(rows, x[:, 0], 2)
        return d[0], d[1][..., None], d[2][..., None, None]

    def evaluate(self, x, rows):
        return self.batch.evaluate(rows, x[:, 0])


def _piece_seeds(breaks, x0, owner):
    """``(seeds, owner, lo, hi, first, last)``: the seeds ``x0`` (of the points ``owner``) in the
    boxes of the smooth pieces between ``breaks`` (a curve's ends and creases) that hold them; a
    seed on a crease starts in both pieces beside it, as :func:`project` does.
    ``first``, ``last``: whether the box is the curve's first / last piece."""
    piece = np.clip(np.searchsorted(breaks, x0, side="right") - 1, 0, breaks.size - 2)
    on = np.isin(x0, breaks[1:-1])
    x0, owner = np.concatenate([x0, x0[on]]), np.concatenate([owner, owner[on]])
    piece = np.concatenate([piece, piece[on] - 1])
    return x0, owner, breaks[piece], breaks[piece + 1], piece == 0, piece == breaks.size - 2


def curve_distances(curves, point_sets) -> list:
    """Per curve ``i``, the distances ``(n_i,)`` of the points ``point_sets[i]`` ``(n_i, dim)``
    to ``curves[i]``: ``project(curves[i], point_sets[i]).distances``, with the Newton searches
    of all curves run as one batch.

    Everything else is :func:`project`'s own: each curve's samples and seeds, the smooth pieces
    the seeds search in, the stopping distance (its default). A curve goes through
    :func:`project` itself (and raises what it raises) when a point's best search does not
    converge, or stops on a crease with the distance still falling across it (``project`` would
    search on in the next piece), or when ``project`` would rescale the curve (larger than 1e60
    or smaller than 1e-60).

    Raises ParameterError when the numbers of curves and point sets differ, or a point set is not
    finite ``(n, dim)`` points of its curve's dimension (worded as ``project`` words it)."""
    curves, point_sets = list(curves), list(point_sets)
    if len(curves) != len(point_sets):
        raise ParameterError(f"curve_distances needs one point set per curve, got {len(curves)} curves "
                             f"and {len(point_sets)} point sets")
    out = [None] * len(curves)
    targets = [_Curve(curve, curve.domain) for curve in curves]
    # each set checked as project checks it (finite, the curve's dimension, not too large)
    point_sets = [_as_query_points(pts, tg.dim, tg.unit)[0] * tg.unit for pts, tg in zip(point_sets, targets)]
    batched = [i for i, tg in enumerate(targets) if tg.unit == 1.0 and len(point_sets[i])]
    if batched:
        x0, owner, lo, hi, first, last, counts, start = [], [], [], [], [], [], [], 0
        for i in batched:
            point, seeds = targets[i].seeds(point_sets[i])
            got = _piece_seeds(targets[i].breaks[0], seeds[:, 0], start + point)
            for acc, x in zip((x0, owner, lo, hi, first, last), got):
                acc.append(x)
            counts.append(got[0].size)
            start += len(point_sets[i])
        x0, owner, lo, hi, first, last = (np.concatenate(a) for a in (x0, owner, lo, hi, first, last))
        rows = np.repeat(np.arange(len(batched)), counts)
        size = np.array([targets[i].size for i in batched])[rows]
        tol = np.array([targets[i].tolerance(None) for i in batched])[rows]
        x, _, dist, g, converged, stationary = newton_search(
            _Curves(CurveBatch([curves[i] for i in batched]), size),
            np.concatenate([point_sets[i] for i in batched])[owner], x0[:, None], lo[:, None], hi[:, None], tol, rows)
        across = ((x[:, 0] <= lo) & (g[:, 0] > 0) & ~first) | ((x[:, 0] >= hi) & (g[:, 0] < 0) & ~last)
        ok = ((converged | stationary) | (dist <= tol)) & ~across
        best = nearest_per_point(owner, dist, start)
        sizes = [len(point_sets[i]) for i in batched]
        point_curve = np.repeat(np.arange(len(batched)), sizes)
        bad = np.zeros(len(batched), dtype=bool)
        np.logical_or.at(bad, point_curve, ~ok[best])
        for j, d in zip(range(len(batched)), np.split(dist[best], np.cumsum(sizes)[:-1])):
            if not bad[j]:
                out[batched[j]] = d
    return [np.asarray(project(curve, points).distances) if got is None else got
            for curve, points, got in zip(curves, point_sets, out)]
