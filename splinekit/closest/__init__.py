"""Closest points: projection of many points onto curves, surfaces and implicits.

``project(geometry, points)`` finds, for every point ``P``, the point of the
geometry nearest to it, all points at once:

* **Parametric curves and surfaces** (any splinekit curve of any dimension,
  :class:`~splinekit.BSplineSurface`, :class:`~splinekit.NurbsSurface`,
  :class:`~splinekit.BezierSurface`, or any object with ``evaluate``,
  ``derivatives`` and ``domain``). The geometry is sampled on a parameter grid
  that contains every knot line, a few samples per Bézier span, refined so that
  the samples are about evenly spaced in space (short spans and high weights
  get more). A k-d tree gives each point its nearest samples; the nearest, the
  next ones that are discrete local minima of the distance (no grid neighbour
  nearer), and the next nearest other sample become Newton seeds. Newton's
  method on the point-inversion equations (The NURBS Book, section 6.1:
  ``C'.(C - P) = 0`` for a curve, the 2 x 2 system with second derivatives for
  a surface) runs on all seeds of all points as one batch, with per-seed
  convergence masks:

  - it stays inside the parameter box: a parameter that reaches the boundary
    with the gradient pointing out is frozen, so the search goes on along the
    boundary curve, or stops at the corner;
  - where the Hessian is not positive definite (far points, strong curvature)
    it is shifted to be, and only steps that do not increase the distance are
    accepted (the step is cut back otherwise), so the result is never farther
    than the seed;
  - where the geometry is only C0 (knots of full multiplicity, every knot of
    degree 1) the distance has a kink, so each seed searches one smooth piece
    at a time and crosses a crease only when the distance keeps decreasing
    across it.

  Each point keeps its nearest result. Closed curves and surfaces need nothing
  special: samples on both sides of a seam are near a point there.
* **Implicit surfaces**: any object callable on ``(n, dim)`` points returning
  ``(n,)`` values ``F`` that has ``.gradient(points)`` -> ``(n, dim)``. Points
  move by ``q <- q - F(q) grad F(q) / |grad F(q)|^2`` until ``|F(q)| <=
  tolerance``; for a true signed-distance function one step lands on the
  closest point, for other implicits the result is a nearby point of the zero
  set (not necessarily the closest one).

The work is split by what it holds: :mod:`.projection` (``project``,
``distance``), :mod:`.parametric` (sampling and seeds of curves and surfaces),
:mod:`.newton` (the batch search), :mod:`.batch` (``curve_distances``: many point
sets, each to its own curve, in one search), :mod:`.implicit` and :mod:`.queries`
(the result type and input checks). The tuning constants live beside the code that
reads them.
"""

from .batch import curve_distances
from .projection import distance, project
from .queries import Projection

__all__ = ["Projection", "curve_distances", "distance", "project"]
