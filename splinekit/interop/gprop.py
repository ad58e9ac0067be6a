"""Measurements of OpenCascade shapes, and reference area and volume of exact patch sets for
cross-checking splinekit's integrals: OpenCascade's GProp at raised precision where it is
reliable, scipy's adaptive cubature where it is not.

Measurements of an OCC shape (a ``TopoDS_Shape``, e.g. from :func:`splinekit.occ.to_shape` or
``exporters.step.read_step_shape``): :func:`occ_area`, :func:`occ_volume`, :func:`occ_bbox`,
:func:`topology_counts`, :func:`occ_euler_characteristic`, :func:`face_kinds`,
:func:`trimmed_face_count`, :func:`is_valid`; :func:`point_deviation` compares splinekit's
evaluation of patches with OCC's evaluation of the same surfaces.

GProp (``BRepGProp.SurfaceProperties_s`` / ``VolumeProperties_s`` with a precision argument)
matches closed forms to about 1e-13 on faces whose area element never vanishes, but drifts on
collapsed edges and poles: on the Utah teapot it gives 21158.38 (precision 1e-4), 21154.50
(1e-8), 21152.98 (1e-10 and 1e-11) for a true 21153.3212370, and the vase's volume is 9e-9
off at 1e-9. :func:`reference_integrals` therefore uses GProp only on patch sets without such
patches (:func:`splinekit.brep.crosscheck.singular_patches`) and says which reference it used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._progress import progress
from ..errors import SplineKitError
from ..brep.crosscheck import scipy_integrals, singular_patches
from ..tolerances import INTEGRAL_RTOL
from .occ import _ocp, _sub_shapes, to_shape

__all__ = ["Reference", "occ_area", "occ_volume", "occ_bbox", "topology_counts", "occ_euler_characteristic",
           "face_kinds", "trimmed_face_count", "is_valid", "point_deviation", "reference_integrals",
           "OCC_PRECISION", "SCIPY_TOLERANCE", "SHAPE_KINDS"]

OCC_PRECISION = INTEGRAL_RTOL
"""Precision passed to GProp: matches closed forms to ~1e-13 on parts without collapsed edges."""

SCIPY_TOLERANCE = INTEGRAL_RTOL
"""Relative tolerance asked of scipy's cubature per Bézier span."""


def occ_area(shape, precision: float = OCC_PRECISION) -> float:
    """Total face area of an OCC shape by GProp's adaptive integration at ``precision``."""
    BRepGProp, GProp = _ocp("BRepGProp", "GProp")
    props = GProp.GProp_GProps()
    BRepGProp.BRepGProp.SurfaceProperties_s(shape, props, precision)
    return float(props.Mass())


def occ_volume(shape, precision: float = OCC_PRECISION) -> float:
    """Total volume of the solids of an OCC shape (0.0 without solids) at ``precision``."""
    BRepGProp, GProp = _ocp("BRepGProp", "GProp")
    total = 0.0
    for solid in _sub_shapes(shape, "SOLID"):
        props = GProp.GProp_GProps()
        BRepGProp.BRepGProp.VolumeProperties_s(solid, props, precision)
        total += float(props.Mass())
    return total


SHAPE_KINDS = ("SOLID", "SHELL", "FACE", "EDGE", "VERTEX")
"""The sub-shape kinds :func:`topology_counts` counts."""


def occ_bbox(shape) -> tuple[np.ndarray, np.ndarray]:
    """``(lo (3,), hi (3,))``: the bounding box of ``shape`` from its exact geometry (no
    triangulation), tight up to the tolerance of its vertices and edges (OCC widens it by that:
    1e-7 for shapes :func:`splinekit.occ.to_shape` sews); zeros for an empty shape."""
    Bnd, BRepBndLib = _ocp("Bnd", "BRepBndLib")
    box = Bnd.Bnd_Box()
    BRepBndLib.BRepBndLib.AddOptimal_s(shape, box, False, False)
    if box.IsVoid():
        return np.zeros(3), np.zeros(3)
    x0, y0, z0, x1, y1, z1 = box.Get()
    return np.array([x0, y0, z0]), np.array([x1, y1, z1])


def topology_counts(shape) -> dict:
    """``{"SOLID": n, "SHELL": n, "FACE": n, "EDGE": n, "VERTEX": n}``: distinct sub-shapes of
    ``shape`` of each kind (a solid's shell counts as a shell; degenerate edges count)."""
    return {kind: len(_sub_shapes(shape, kind)) for kind in SHAPE_KINDS}


def occ_euler_characteristic(shape) -> int:
    """The Euler characteristic of ``shape``'s faces as OCC's topology holds them, counted the
    way B-rep topology counts (Euler-Poincaré with inner loops)::

        V - (E - degenerate E) + F - (W - F)

    A degenerate edge (a pole, a collapsed patch side) is a point, not an edge: left out. A seam
    is one edge that its face uses twice, so a face closed on itself is still one disk: a one-face
    sphere (2 poles, 1 seam, 2 degenerate edges) gives 2 - 1 + 1 = 2, a one-face torus (1 vertex,
    2 seams) 1 - 2 + 1 = 0. Each wire beyond a face's first is a hole (``- (W - F)``). For a
    closed shell this is ``2 - 2 genus``; plain ``V - E + F`` gives 0 for the sphere."""
    (BRep,) = _ocp("BRep")
    counts = topology_counts(shape)
    degenerate = sum(bool(BRep.BRep_Tool.Degenerated_s(e)) for e in _sub_shapes(shape, "EDGE"))
    holes = sum(len(_sub_shapes(f, "WIRE")) - 1 for f in _sub_shapes(shape, "FACE"))
    return counts["VERTEX"] - (counts["EDGE"] - degenerate) + counts["FACE"] - holes


def face_kinds(shape) -> dict:
    """``kind -> number of faces`` of ``shape``: OCC's surface type (``"Plane"``,
    ``"Cylinder"``, ...); Bézier and B-spline surfaces with their degrees and whether they are
    rational (``"BSplineSurface, degree 3 x 3, rational"``)."""
    (BRepAdaptor,) = _ocp("BRepAdaptor")
    kinds: dict = {}
    for face in _sub_shapes(shape, "FACE"):
        surface = BRepAdaptor.BRepAdaptor_Surface(face)
        kind = surface.GetType().name.replace("GeomAbs_", "")
        if kind in ("BSplineSurface", "BezierSurface"):
            kind += f", degree {surface.UDegree()} x {surface.VDegree()}"
            if surface.IsURational() or surface.IsVRational():
                kind += ", rational"
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def trimmed_face_count(shape) -> int:
    """How many faces of ``shape`` are trimmed: with more than one wire (holes), or with an
    outer wire whose (u, v) box lies inside the surface's own parameter domain (relative
    1e-9 of the parameters' size)."""
    BRep, BRepTools = _ocp("BRep", "BRepTools")
    trimmed = 0
    for face in _sub_shapes(shape, "FACE"):
        if len(_sub_shapes(face, "WIRE")) > 1:
            trimmed += 1
            continue
        box = BRepTools.BRepTools.UVBounds_s(face)
        natural = BRep.BRep_Tool.Surface_s(face).Bounds()
        scale = max(1.0, *(abs(x) for x in box))
        trimmed += any(abs(a - b) > 1e-9 * scale for a, b in zip(box, natural))
    return trimmed


def is_valid(shape) -> bool:
    """Whether OCC's ``BRepCheck_Analyzer`` accepts ``shape``."""
    (BRepCheck,) = _ocp("BRepCheck")
    return bool(BRepCheck.BRepCheck_Analyzer(shape).IsValid())


def point_deviation(patches, samples: int = 9) -> tuple[float, int]:
    """``(largest distance, number of points)`` between splinekit's and OCC's evaluation of
    ``patches`` (Bézier, B-spline or NURBS surfaces) at a ``samples x samples`` parameter grid
    of each: splinekit evaluates the grid in one call, OCC evaluates the surface of the face
    that :func:`splinekit.occ.to_shape` builds from the patch, one point at a time (OCC has no
    batch evaluator). Both evaluate the same control net in float64, so the two agree to a few
    hundred units in the last place of the coordinates."""
    (BRep,) = _ocp("BRep")
    worst, count = 0.0, 0
    with progress(len(patches), "comparing points") as bar:
        for patch in patches:
            (a, b), (c, d) = patch.domain
            us, vs = np.linspace(a, b, samples), np.linspace(c, d, samples)
            ours = patch.evaluate_grid(us, vs).reshape(-1, 3)
            surface = BRep.BRep_Tool.Surface_s(to_shape(patch))
            U, V = np.meshgrid(us, vs, indexing="ij")
            theirs = np.array([[p.X(), p.Y(), p.Z()] for p in map(surface.Value, U.ravel(), V.ravel())])
            worst = max(worst, float(np.linalg.norm(ours - theirs, axis=1).max()))
            count += ours.shape[0]
            bar.advance()
    return worst, count


@dataclass(frozen=True)
class Reference:
    """Area and volume from an independent reference.

    Attributes
    ----------
    area : float
        Total area of every body (mm^2).
    volume : float or None
        Total enclosed volume of the closed bodies (None when ``closed`` was False).
    source : str
        ``"OCC GProp 1e-10"`` or ``"scipy cubature 1e-10"``.
    reason : str
        Why that reference: the first singular patch found, or that there is none.
    """

    area: float
    volume: float | None
    source: str
    reason: str


def reference_integrals(bodies, *, closed: bool, shapes=None) -> Reference:
    """Area and volume of ``bodies`` (lists of exact patches, outward ``Su x Sv`` on closed
    bodies) by a reference independent of :mod:`splinekit.brep.integrate`.

    Without collapsed edges, poles or singular corners in any patch: OCC's GProp at
    :data:`OCC_PRECISION` on ``shapes`` (the bodies sewn by :func:`splinekit.occ.to_shape`;
    sewn here when not given). Otherwise scipy's adaptive cubature on every Bézier span
    (:func:`splinekit.brep.crosscheck.scipy_integrals`), volume by the divergence theorem.
    """
    bodies = [list(b) for b in bodies]
    singular = [(i, j, why) for i, body in enumerate(bodies) for j, why in singular_patches(body)]
    sew_error = None
    if not singular:
        try:
            if shapes is None:
                shapes = [to_shape(body) for body in bodies]
        except SplineKitError as exc:  # no sewn shape to measure: fall back to scipy
            sew_error = str(exc).splitlines()[0]
        else:
            area = sum(occ_area(s) for s in shapes)
            volume = sum(occ_volume(s) for s in shapes) if closed else None
            return Reference(area, volume, f"OCC GProp {OCC_PRECISION:g}", "no collapsed edges or poles")
    area = volume = 0.0
    for body in bodies:
        a, v, _err = scipy_integrals(body, SCIPY_TOLERANCE)
        area += a
        volume += v
    if singular:
        i, j, why = singular[0]
        more = f" (and {len(singular) - 1} more patches)" if len(singular) > 1 else ""
        reason = f"OCC unreliable: body {i} patch {j}: {why}{more}"
    else:
        reason = f"OCC could not sew the patches: {sew_error}"
    return Reference(area, volume if closed else None, f"scipy cubature {SCIPY_TOLERANCE:g}", reason)
