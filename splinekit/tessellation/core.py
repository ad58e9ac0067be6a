"""The public entry point :func:`tessellate`: input checks and dispatch."""

from __future__ import annotations

import math
import sys

import numpy as np

from .._validate import as_int, as_real
from ..curves import BezierCurve, SplineCurve
from ..errors import ParameterError
from ..mesh import PolyMesh
from ..subdiv.surface import SubdivisionSurface
from ..surfaces import BezierSurface, SplineSurface
from ..tolerances import DEVIATION_RTOL
from .curves import tessellate_curve
from .surfaces import tessellate_patches
from .trimmed import tessellate_faces

__all__ = ["DEFAULT_ANGLE_TOLERANCE", "DEFAULT_RELATIVE_TOLERANCE", "tessellate"]

DEFAULT_RELATIVE_TOLERANCE = DEVIATION_RTOL
"""Default chordal tolerance as a fraction of the model's bounding-box diagonal."""
DEFAULT_ANGLE_TOLERANCE = 0.5
"""Default largest angle (radians) between the exact normals at the two ends of a
triangle edge (tangents of a polyline segment); OpenCascade's BRepMesh default."""


def _brep_faces(obj):
    """The trimmed faces of a TrimmedFace, Shell, Solid or a list of them, or None when ``obj``
    is none of these."""
    # B-rep objects exist only once splinekit.brep is imported; not importing it here keeps
    # ``import splinekit`` fast (brep loads scipy.spatial)
    brep = sys.modules.get("splinekit.brep")
    if brep is None:
        return None
    TrimmedFace, Shell, Solid = brep.TrimmedFace, brep.Shell, brep.Solid
    kinds = (TrimmedFace, Shell, Solid)
    if isinstance(obj, kinds):
        obj = [obj]
    elif isinstance(obj, (str, bytes)) or not isinstance(obj, (list, tuple)) or not obj:
        return None
    if not any(isinstance(o, kinds) for o in obj):
        return None
    faces = []
    for i, o in enumerate(obj):
        if isinstance(o, TrimmedFace):
            faces.append(o)
        elif isinstance(o, (Shell, Solid)):
            faces.extend(o.faces)
        else:
            raise ParameterError(f"item {i} is a {type(o).__name__}; a list to tessellate holds TrimmedFace, Shell and Solid objects, or surfaces, not both")
    return faces


def _patches(obj, levels):
    """``(kind, items)``: ``("curve", curve)``, ``("faces", [TrimmedFace, ...])`` or
    ``("surfaces", [SplineSurface, ...])``."""
    faces = _brep_faces(obj)
    if faces is not None:
        return "faces", faces
    if isinstance(obj, BezierCurve):
        return "curve", obj.to_bspline()
    if isinstance(obj, SplineCurve):
        return "curve", obj
    if isinstance(obj, (BezierSurface, SplineSurface)):
        obj = [obj]
    elif isinstance(obj, SubdivisionSurface):
        obj = _subdivision_patches(obj, levels)
    elif isinstance(obj, (str, bytes)) or not hasattr(obj, "__iter__"):
        raise ParameterError(
            "tessellate takes a curve, a surface, a list of surfaces or a SubdivisionSurface, "
            f"got {type(obj).__name__}"
        )
    items = []
    for i, s in enumerate(obj):
        if isinstance(s, BezierSurface):
            s = s.to_bspline()
        if not isinstance(s, SplineSurface):
            raise ParameterError(f"patch {i} is a {type(s).__name__}; expected a BezierSurface, BSplineSurface or NurbsSurface")
        if s.dim != 3:
            raise ParameterError(f"patch {i} lies in {s.dim}-D space; tessellation needs 3-D surfaces")
        items.append(s)
    if not items:
        raise ParameterError("tessellate got an empty list of surfaces")
    return "surfaces", items


def _subdivision_patches(surface, levels: int):
    """B-spline patches of a Catmull-Clark limit surface, from its cage refined
    uniformly ``levels`` times (creases, corners and their remaining sharpness
    carried along: the same limit surface) and converted without further local
    refinement. Every face then meets its neighbours edge to edge, so the patch
    set has no T-junctions and tessellates watertight; ``to_bsplines(levels)``
    refines only around irregular faces, which leaves T-junctions that patch
    stitching cannot close."""
    if levels == 0:
        return surface.to_bsplines(0)[0]
    r = surface.refinement(levels)
    fine = PolyMesh.from_topology(r.apply(surface.mesh.vertices), r.topology)
    options = surface._options
    finer = SubdivisionSurface(fine, surface.scheme, creases=r.edge_sharpness[-1], corners=r.vertex_sharpness[-1],
                               boundary=options["boundary"], crease_method=options["crease_method"])  # fmt: skip
    return finer.to_bsplines(0)[0]


def _diagonal(points) -> float:
    rows = np.ascontiguousarray(np.reshape(points, (-1, points.shape[-1])).T)  # (dim, n): fast row reductions
    lo, hi = rows.min(axis=1), rows.max(axis=1)
    return float(np.linalg.norm(hi - lo))


def _set_diagonal(items, points) -> float:
    """The bounding-box diagonal of ``points(item)`` over ``items`` (faces or surfaces), kept in
    the first item's cache (they are immutable) with the item set it belongs to."""
    cache = getattr(items[0], "_cache", None)
    hit = cache.get("diagonal") if cache is not None else None
    if hit is not None and len(hit[0]) == len(items) and all(a is b for a, b in zip(hit[0], items)):
        return hit[1]
    size = _diagonal(np.concatenate([np.asarray(points(it)).reshape(-1, 3) for it in items]))
    if cache is not None:
        cache["diagonal"] = tuple(items), size
    return size


def tessellate(obj, tolerance=None, *, angle_tolerance=DEFAULT_ANGLE_TOLERANCE, relative: bool = False, levels: int = 2):
    """Adaptive tessellation of a curve, a surface, a patch set or a subdivision surface.

    Parameters
    ----------
    obj
        A curve (:class:`~splinekit.BezierCurve`, :class:`~splinekit.BSplineCurve`,
        :class:`~splinekit.NurbsCurve`) -> :class:`Polyline`; a surface
        (:class:`~splinekit.BezierSurface`, :class:`~splinekit.BSplineSurface`,
        :class:`~splinekit.NurbsSurface`), a list of them (a body: patches
        that share edges are stitched), or a Catmull-Clark
        :class:`~splinekit.SubdivisionSurface` (through ``to_bsplines(levels)``)
        -> :class:`Tessellation`. Surfaces must be 3-D. A B-rep
        :class:`~splinekit.brep.TrimmedFace`, :class:`~splinekit.brep.Shell` or
        :class:`~splinekit.brep.Solid`, or a list of them -> one watertight
        :class:`Tessellation` (``face_patch`` / ``vertex_patch`` index the faces in
        order; see :mod:`splinekit.tessellation.trimmed`).
    tolerance : float, optional
        Chordal tolerance, an absolute distance in model units (or, with
        ``relative=True``, a fraction of the model size). The model size is
        the diagonal of the bounding box of all control points. Default:
        ``1e-3`` of the model size.
    angle_tolerance : float or None
        Largest angle in radians between the exact normals at the two ends of
        a triangle edge (or the tangents at the ends of a polyline segment);
        ``None`` disables the criterion. Default 0.5.
    relative : bool
        Read ``tolerance`` as a fraction of the model size.
    levels : int
        For a ``SubdivisionSurface``: how many times the cage is refined
        uniformly before its faces become B-spline patches (regular faces
        exactly, faces at extraordinary vertices as Coons patches whose
        distance from the limit surface shrinks with each level). Default 2.

    Returns
    -------
    Tessellation or Polyline
        Whose ``max_deviation`` is at most ``tolerance`` unless refinement hit
        its limits (4096 segments per Bézier cell and direction, 8 rounds).
        ``max_deviation`` is measured at every triangle's parametric centre
        and every edge's parametric midpoint: the distance between the exact
        surface point there and the corresponding point of the flat triangle
        (so it includes the tangential part of the error, and bounds the
        distance of those points from the surface).

    Notes
    -----
    Patches are stitched where whole Bézier cell edges coincide (same points
    at 0, 1/4, 1/2, 3/4 and 1 of the edge, either direction), as in Bézier
    patch sets, Catmull-Clark patch sets and NURBS bodies cut at common knots.
    An edge shared with a different parametrization, or a T-junction (one
    patch edge against two), is not stitched and leaves a crack. Edges that
    collapse to a point (poles) become one vertex. The angle criterion
    ignores edges shorter than the tolerance and normals more than 90 degrees
    apart (folds), and stops refining a cell direction at 64 steps.
    Raises :class:`~splinekit.errors.ParameterError` for a bad tolerance or an
    unsupported object, and :class:`~splinekit.errors.ResourceLimitError` when a
    refinement round would need more memory than the budget of
    :mod:`splinekit.limits` (the estimate is made from the per-cell sample counts
    before the round's grids are built).

    Trimmed faces, shells and solids: every edge is sampled once in 3-D and
    shared by the faces that use it (uses paired by their ``key``, keyless
    uses geometrically), so a closed shell gives a closed mesh; the trims
    are the constraints of a constrained Delaunay triangulation of each face's
    parameter plane (scaled so that the interior grid's step is one in both
    directions), refined where the measured deviation exceeds the tolerance.
    Triangles follow the faces' orientation (``reversed``). Planes and right
    circular cylinders bounded by straight edges and circle arcs get no
    interior points (ear clipping of the planes' boundary polygons, strips on
    the cylinders, circles cut at uniform angle; see :mod:`.trimmed`). ``max_deviation``
    is measured as above, at every triangle's centre and edge midpoint. A face
    whose trims are invalid (not closed, leaving the domain, crossing, facing
    the wrong way, a hole outside the outer loop) raises ParameterError naming
    the face.
    """
    if tolerance is not None:
        tolerance = as_real(tolerance, "tolerance")
        if not tolerance > 0:
            raise ParameterError(f"tolerance must be > 0, got {tolerance!r}")
    if angle_tolerance is not None:
        angle_tolerance = as_real(angle_tolerance, "angle_tolerance")
        if not 0 < angle_tolerance <= math.pi:
            raise ParameterError(f"angle_tolerance must lie in (0, pi] radians or be None, got {angle_tolerance!r}")
    if not isinstance(relative, (bool, np.bool_)):
        raise ParameterError(f"relative must be True or False, got {relative!r}")
    levels = as_int(levels, "levels", minimum=0)
    kind, item = _patches(obj, levels)
    if kind == "curve":
        size = _diagonal(np.asarray(item.control_points))
    elif kind == "faces":
        size = _set_diagonal(item, lambda f: f.surface.control_points)
    else:
        size = _set_diagonal(item, lambda s: s.control_points)
    if not np.isfinite(size):
        raise ParameterError("the model's bounding box overflows the float range")
    if size == 0.0:
        size = 1.0  # a single point: any positive tolerance is met
    if tolerance is None:
        tol = DEFAULT_RELATIVE_TOLERANCE * size
    else:
        tol = tolerance * size if relative else tolerance
    if not (np.isfinite(tol) and tol > 0):
        raise ParameterError(f"the tolerance {tol!r} (model units) is not a positive finite distance")
    if kind == "curve":
        return tessellate_curve(item, tol, angle_tolerance)
    if kind == "faces":
        return tessellate_faces(item, tol, angle_tolerance, size)
    return tessellate_patches(item, tol, angle_tolerance, size)
