"""Random test geometry as plain functions (no pytest fixtures).

Every generator takes a ``numpy.random.Generator`` so that a failing case is
reproduced by its seed alone. Import from a test module with
``from _geometry import ...`` (pytest puts ``tests/`` on ``sys.path``).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "random_knots",
    "random_points",
    "random_weights",
    "random_curve_data",
    "random_surface_data",
    "interior_params",
    "middle_of_widest_span",
]

WEIGHT_RANGE = (0.2, 5.0)


def random_knots(rng: np.random.Generator, degree: int, n_spans: int | None = None, max_spans: int = 5):
    """A clamped knot vector of ``degree`` with random interior knots.

    The domain ``[a, b]`` is random (``a`` in [-3, 3], length in [0.5, 4]);
    interior knots are distinct random values with multiplicities 1..degree,
    kept at least 2 % of the domain length apart (so spans are not degenerate).
    Returns the full knot vector (multiplicities repeated).
    """
    p = int(degree)
    if n_spans is None:
        n_spans = int(rng.integers(1, max_spans + 1))
    a = float(rng.uniform(-3.0, 3.0))
    length = float(rng.uniform(0.5, 4.0))
    b = a + length
    n_inner = n_spans - 1
    # distinct interior values with a minimum gap: spread the slack randomly
    gap = 0.02 * length
    slack = length - gap * (n_inner + 1)
    cuts = np.sort(rng.uniform(0.0, slack, n_inner))
    inner = a + cuts + gap * np.arange(1, n_inner + 1)
    mults = rng.integers(1, p + 1, n_inner) if n_inner else np.zeros(0, dtype=int)
    return np.concatenate([np.full(p + 1, a), np.repeat(inner, mults), np.full(p + 1, b)])


def random_points(rng: np.random.Generator, shape, dim: int = 3):
    """Control points ``shape + (dim,)`` in a random box: scale 10**U(-1, 2), random offset."""
    scale = 10.0 ** rng.uniform(-1.0, 2.0)
    offset = rng.uniform(-1.0, 1.0, dim) * scale
    return offset + scale * rng.uniform(-1.0, 1.0, tuple(shape) + (dim,))


def random_weights(rng: np.random.Generator, shape):
    """Weights uniform in [0.2, 5]."""
    return rng.uniform(*WEIGHT_RANGE, shape)


def random_curve_data(
    rng: np.random.Generator, rational: bool, degree: int | None = None, max_degree: int = 7, max_spans: int = 5
):
    """``(degree, knots, points, weights_or_None)`` of a random clamped spline curve."""
    p = int(rng.integers(1, max_degree + 1)) if degree is None else int(degree)
    U = random_knots(rng, p, max_spans=max_spans)
    n = U.size - p - 1
    P = random_points(rng, (n,))
    W = random_weights(rng, n) if rational else None
    return p, U, P, W


def random_surface_data(
    rng: np.random.Generator,
    rational: bool,
    degrees: tuple[int, int] | None = None,
    max_degree: int = 7,
    max_spans: int = 4,
):
    """``(pu, pv, knots_u, knots_v, points (nu, nv, 3), weights_or_None)``."""
    if degrees is None:
        pu, pv = (int(x) for x in rng.integers(1, max_degree + 1, 2))
    else:
        pu, pv = (int(x) for x in degrees)
    ku = random_knots(rng, pu, max_spans=max_spans)
    kv = random_knots(rng, pv, max_spans=max_spans)
    nu, nv = ku.size - pu - 1, kv.size - pv - 1
    P = random_points(rng, (nu, nv))
    W = random_weights(rng, (nu, nv)) if rational else None
    return pu, pv, ku, kv, P, W


def interior_params(rng: np.random.Generator, knots: np.ndarray, degree: int, count: int):
    """``count`` random parameters of the domain plus its two ends."""
    a, b = knots[degree], knots[knots.size - degree - 1]
    return np.concatenate([[a, b], rng.uniform(a, b, count)])


def middle_of_widest_span(rng: np.random.Generator, knots: np.ndarray) -> float:
    """A random parameter in the middle third of the widest knot span.

    Knot removal is ill-conditioned for knots very close to their neighbours
    (the removal formulas divide by knot differences), so removal tests insert
    their knot here, where a removal is expected to be exact to rounding.
    """
    br = np.unique(knots)
    i = int(np.argmax(np.diff(br)))
    lo, hi = br[i], br[i + 1]
    return float(rng.uniform(lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0))
