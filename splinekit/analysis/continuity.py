"""Continuity across the edge two faces or surfaces share: G0 gap, G1 normal angle, G2 jump of
the normal curvature across the edge, sampled along the edge all at once.

:func:`edge_continuity` finds the shared edge (:mod:`.matching`), samples it (:mod:`.sampling`)
and compares the two sides (:mod:`.compare`, where the quantities, the orientation of the normals
and the levels are defined).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_int
from ..errors import ParameterError
from ..tolerances import CONTINUITY_MATCH
from .compare import LEVELS, EdgeContinuity, tolerance_value
from .matching import NoSharedEdgeError, lies_on, polyline, shared_edge
from .edge_samples import measure
from .sides import SIDE_NAMES, Side, as_patch, sides_of

__all__ = ["LEVELS", "EdgeContinuity", "NoSharedEdgeError", "edge_continuity"]


def _given_side(sides: list, spec, which: str) -> Side:
    """The use named by ``spec``: a side name (``"u0"``, ``"u1"``, ``"v0"``, ``"v1"``), an index into
    the face's edges, or one of its Edge objects."""
    if isinstance(spec, str):
        found = [s for s in sides if s.name == spec]
        if not found:
            names = ", ".join(s.name for s in sides)
            raise ParameterError(f"edge side {spec!r} of {which} is not one of its sides ({names}; natural sides "
                                 f"are named {', '.join(SIDE_NAMES)})")
        return found[0]
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        if not 0 <= int(spec) < len(sides):
            raise ParameterError(f"edge index {int(spec)} of {which} is outside 0..{len(sides) - 1}")
        return sides[int(spec)]
    pc = getattr(spec, "pcurve", None)
    found = [s for s in sides if pc is not None and s.pcurve is not None and s.pcurve is pc]
    if not found:
        raise ParameterError(f"edge {spec!r} is not an edge of {which}: give a side name, an index or one of its Edges")
    return found[0]


def edge_continuity(a, b, samples: int = 64, *, edge=None, gap_tol=None, angle_tol=None, curvature_tol=None,
                    match_rtol=None) -> EdgeContinuity:
    """G0/G1/G2 continuity along the edge shared by ``a`` and ``b``.

    Parameters
    ----------
    a, b
        B-rep faces (:class:`~splinekit.brep.TrimmedFace`, e.g. faces of a Shell or Solid) or
        parametric surfaces in 3-D (B-spline, NURBS or Bézier patches,
        :class:`~splinekit.SubdivisionPatch`, anything with ``domain``, ``evaluate`` and
        ``derivatives``). ``a`` may be ``b`` (a face meeting itself across a seam).
    samples : int
        Samples along the edge (>= 2), end points included, at equal steps of the sampled use's
        pcurve parameter.
    edge : (side_a, side_b), optional
        The uses that form the edge, each a natural side name (``"u0"``, ``"u1"``, ``"v0"``,
        ``"v1"``: the side ``u = u0``...), an index into the face's edges, or one of its
        :class:`~splinekit.brep.Edge` objects. By default the shared edge is found: uses with one
        B-rep key, else the pair of sides of which one lies on the other (either direction and
        parametrization; one may be part of the other).
    gap_tol : float, optional
        G0 tolerance (model units); default ``CONTINUITY_GAP`` times the model size (largest
        absolute coordinate along the edge, at least 1), at least the faces' own tolerances.
    angle_tol : float, optional
        G1 tolerance on the normals' angle (radians); default ``CONTINUITY_ANGLE``.
    curvature_tol : float, optional
        G2 tolerance on the curvature jump relative to ``max(|k_a|, |k_b|, 1 / edge length)``;
        default ``CONTINUITY_CURVATURE``.
    match_rtol : float, optional
        How close (relative to its length) a use must lie on the other to be the shared edge;
        default ``CONTINUITY_MATCH``.

    Returns
    -------
    EdgeContinuity
        ``.gap``, ``.angle``, ``.curvature_jump``, ``.normal_curvature``, ``.params``,
        ``.points``, ``.level`` ("G2", "G1", "G0" or "none"), per-edge maxima... (:mod:`splinekit.analysis.compare`
        for the definitions and the orientation of the normals).

    Raises
    ------
    NoSharedEdgeError
        (a ParameterError) ``a`` and ``b`` share no edge.
    ParameterError
        Not a face or 3-D surface, bad ``samples``, ``edge`` or tolerance, a surface that evaluates
        to non-finite values.
    """
    samples = as_int(samples, "samples", minimum=2)
    match_rtol = tolerance_value(match_rtol, "match_rtol", CONTINUITY_MATCH)
    as_patch(a, "a")
    as_patch(b, "b")
    same = a is b
    sides_a = sides_of(0, a)
    sides_b = sides_a if same else sides_of(1, b)
    if edge is not None:
        if isinstance(edge, (str, bytes)) or not isinstance(edge, (tuple, list)) or len(edge) != 2:
            raise ParameterError(f"edge must be a pair (side of a, side of b), got {edge!r}")
        spec_a, spec_b = edge
        x, y = _given_side(sides_a, spec_a, "a"), _given_side(sides_b, spec_b, "b")
        if x.degenerate or y.degenerate:
            raise ParameterError("the given edge collapses to a point on one face: it has no length to sample")
        px, py = polyline(x), polyline(y)
        from_a = lies_on(px, py) <= lies_on(py, px)
        inner, outer = (x, y) if from_a else (y, x)
    else:
        inner, outer = shared_edge(sides_a, sides_b, match_rtol, same=same)
        from_a = same or any(inner is s for s in sides_a)
    return measure(inner, outer, samples, gap_tol=gap_tol, angle_tol=angle_tol, curvature_tol=curvature_tol,
                   swap=not from_a)
