"""The figures measured on one representation: accuracy against the exact surface and the time
per point of its queries (:func:`accuracy`, :func:`query_times`)."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["QUERY_POINTS", "accuracy", "near_points", "query_times"]

QUERY_POINTS = 200
"""Points per timed query (fewer for a representation that states ``query_points``)."""

NEAR = 2e-3
"""Offset of the query points from the surface along the exact normal, as a fraction of the
diagonal: smaller than the radii of curvature, so the exact closest point of ``p + d n`` is ``p``."""


def _angle_degrees(a, b) -> np.ndarray:
    cos = np.einsum("nd,nd->n", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def accuracy(holder, reference, rng, samples: int) -> dict:
    """``hausdorff``, ``mean_distance`` (model units), ``normal_angle`` (degrees, area-weighted
    mean), ``volume_error`` (relative) and ``genus`` of a representation.

    Distances are two-sided: from the exact samples to the representation
    (``holder.distance``) and from ``samples`` points on the representation to the exact
    surface (the reference tessellation, :attr:`Reference.tolerance` from it). The Hausdorff
    distance is the larger maximum (a sampled lower bound of the true one); the mean distance
    averages the two directions (the first weighted by area).
    """
    to_rep = holder.distance(reference.points)
    to_exact = reference.distance_to_exact(holder.surface_points(samples, rng))
    # normals where the exact samples are (a parametric holder answers at their parameters)
    normals = holder.reference_normals() if hasattr(holder, "reference_normals") else holder.normal(reference.points)
    angle = _angle_degrees(normals, reference.normals)
    out = {
        "hausdorff": float(max(to_rep.max(), to_exact.max())),
        "mean_distance": float(0.5 * (np.average(to_rep, weights=reference.weights) + to_exact.mean())),
        "normal_angle": float(np.average(angle, weights=reference.weights)),
        "volume_error": None,
        "genus": None,
    }
    if holder.applies("volume"):
        out["volume_error"] = abs(holder.volume() - reference.volume) / reference.volume
    if holder.applies("genus"):
        out["genus"] = holder.genus()
    return out


def near_points(reference, n, rng):
    """``(exact points p (n, 3), query points p + d n (n, 3))`` with ``d`` = :data:`NEAR` x diagonal
    alternately outside and inside."""
    pick = rng.choice(len(reference.points), min(n, len(reference.points)), replace=False)
    p = reference.points[pick]
    side = np.where(np.arange(len(pick)) % 2 == 0, 1.0, -1.0)
    return p, p + (side * NEAR * reference.diagonal)[:, None] * reference.normals[pick]


def _per_point(fn, n) -> float:
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) / n


def query_times(holder, reference, rng) -> dict:
    """Seconds per point of the four queries (None where one does not apply): ``point_s``
    (point from parameters), ``inside_s``, ``closest_s``, ``normal_s``; and what the answers
    are worth: ``inside_correct`` (fraction of near points classified right) and
    ``closest_error`` (largest distance from the known closest point, model units)."""
    n = getattr(holder, "query_points", QUERY_POINTS)
    exact, query = near_points(reference, n, rng)
    truth = np.arange(len(query)) % 2 == 1  # odd points were moved inward
    out = {"point_s": None}
    if holder.applies("point"):
        params = holder.random_parameters(len(query), rng)
        out["point_s"] = _per_point(lambda: holder.point(*params), len(query))
    got = {}
    out["inside_s"] = _per_point(lambda: got.setdefault("inside", holder.inside(query)), len(query))
    out["closest_s"] = _per_point(lambda: got.setdefault("closest", holder.closest(query)), len(query))
    out["normal_s"] = _per_point(lambda: holder.normal(query), len(query))
    out["inside_correct"] = float(np.mean(np.asarray(got["inside"]) == truth))
    out["closest_error"] = float(np.linalg.norm(got["closest"] - exact, axis=1).max())
    return out
