"""OpenCascade (OCP) interop: geometry, topology, build123d and cadquery.

Geometry: ``to_occ`` builds ``Geom_BSplineCurve`` / ``Geom_BSplineSurface``
(or the Bézier classes) and ``from_occ`` reads them back, losslessly: knots go
to OCC as distinct values plus multiplicities and OCC arrays are 1-based.

Topology: ``to_shape`` turns a curve into an edge, a surface into a face, a
list of surface patches into a sewn shell (or a solid oriented outward when the
patches close up), and a B-rep ``TrimmedFace`` / ``Shell`` / ``Solid`` into the
exact OCC face / shell / solid (:mod:`.occ_brep`); ``to_build123d`` /
``to_cadquery`` wrap that shape for those libraries. ``from_occ`` also accepts
OCC shapes (and build123d / cadquery objects): faces, shells and solids come
back as B-rep objects with their trims, orientations and shared edges (or, with
``surfaces=True``, as the plain B-spline forms of their faces), edges as
curves, converting analytic geometry exactly.

This module is the entry point; the work is done in modules named for what they hold:
:mod:`.occ_backend` (loading OCP), :mod:`.occ_shapes` (TopoDS helpers), :mod:`.occ_geometry`
(curves and surfaces), :mod:`.occ_brep_read` / :mod:`.occ_brep_write` (B-rep), :mod:`.occ_nurbs`.
OCP is imported inside the functions, so ``import splinekit`` does not load it.
"""

from __future__ import annotations

import numpy as np

from .._signals import reraise_interrupt
from .._validate import as_positive
from ..errors import BackendError, ParameterError
from ..tolerances import OCC_CONFUSION
# _ocp, _check_valid, _sub_shapes, _compound, _edge_to_curve are also reached through this module
# (exporters, the command line, tests): keep them importable here
from .occ_backend import _MODULES, _missing, _occ_call, _ocp, require_ocp  # noqa: F401  (_MODULES: tests reach it here)
from .occ_brep import brep_to_shape, is_brep
from .occ_brep_read import brep_from_shape
from .occ_geometry import (
    _curve_to_bspline,
    _edge_to_curve,
    _face_to_surface,
    _from_geom,
    _is_curve,
    _is_surface,
    geom_to_occ,
)
from .occ_shapes import _check_valid, _compound, _free_edges, _sub_shapes, _typed, _unwrap, _volume

__all__ = ["to_occ", "from_occ", "to_shape", "to_build123d", "to_cadquery", "require_ocp"]


def to_occ(obj, *, tolerance: float = OCC_CONFUSION):
    """An OCP ``Geom_*`` handle for a splinekit curve or surface (3-D only); for a B-rep
    ``TrimmedFace`` / ``Shell`` / ``Solid`` the ``TopoDS_Face`` / ``TopoDS_Shell`` /
    ``TopoDS_Solid`` (see :func:`to_shape`)."""
    if is_brep(obj):
        return to_shape(obj, tolerance=tolerance)
    return geom_to_occ(obj)


def from_occ(handle, *, oriented: bool = False, surfaces: bool = False):
    """splinekit geometry from OpenCascade geometry or topology.

    ``handle`` may be

    * a ``Geom_BSpline*`` / ``Geom_Bezier*`` handle: converted losslessly;
    * any other bounded ``Geom_Curve`` / ``Geom_Surface`` (lines trimmed,
      circles, planes trimmed, cylinders, spheres, offsets...): converted with
      ``GeomConvert`` to its exact (rational) B-spline form;
    * a ``TopoDS_Edge``: the B-spline form of its 3-D curve over the edge's
      parameter range (a curve);
    * a ``TopoDS_Face`` / ``TopoDS_Shell`` / ``TopoDS_Solid``: a
      :class:`~splinekit.brep.TrimmedFace` / ``Shell`` / ``Solid`` keeping every
      trimming loop, every face orientation (``reversed``) and the edges the faces
      share (``Edge.key``: the edge's index in one map of the whole shape). The
      shape is converted to NURBS first (``BRepBuilderAPI_NurbsConvert``), so
      analytic surfaces and their pcurves become B-splines consistently;
    * a compound, a build123d or cadquery object (anything holding the shape in
      ``.wrapped``), a cadquery ``Workplane`` or a list of these: one B-rep object
      per solid, shell and face of a compound (a list), and one curve per edge of
      a wire or loose edge; a single face, shell or solid gives the object itself.

    With ``surfaces=True`` topology gives plain untrimmed surfaces as before the
    B-rep layer: a face gives the B-spline form of its surface over the face's UV
    bounding box (trims dropped) and any other shape a list with one surface per
    distinct face, followed by one curve per non-degenerate edge that bounds no face.

    Periodic OCC B-splines are returned on a clamped, non-periodic equivalent:
    ``SetNotPeriodic`` on a copy (the caller's handle is untouched), whose
    unclamped end knots are then clamped by knot insertion; the geometry and
    the parameter domain are unchanged.
    With ``surfaces=True``, surfaces keep the parametrization OCC stores, whatever
    the face orientation; ``oriented=True`` (which implies ``surfaces=True``) reverses
    the surface of a reversed face in u, so that ``Su x Sv`` follows the face normal.
    """
    for flag, value in (("oriented", oriented), ("surfaces", surfaces)):
        if not isinstance(value, (bool, np.bool_)):
            raise ParameterError(f"{flag} must be True or False, got {value!r}")
    Geom, _, _, _ = require_ocp()
    direct = _from_geom(handle)
    if direct is not None:
        return direct
    if isinstance(handle, Geom.Geom_Curve):
        return _curve_to_bspline(handle)
    if isinstance(handle, Geom.Geom_Surface):
        try:
            u0, u1, v0, v1 = handle.Bounds()
        except Exception:
            u0 = u1 = v0 = v1 = np.inf
        if not all(abs(x) < 1e100 for x in (u0, u1, v0, v1)):
            raise ParameterError(
                f"cannot convert the unbounded surface {type(handle).__name__}: "
                "trim it first (Geom_RectangularTrimmedSurface) or pass a face"
            )
        (GeomConvert,) = _ocp("GeomConvert")
        bs = _occ_call("convert a surface to a B-spline", GeomConvert.GeomConvert.SurfaceToBSplineSurface_s, handle)
        return _from_geom(bs)
    if isinstance(handle, (list, tuple)):
        shapes = []
        for i, item in enumerate(handle):
            s = _unwrap(item)
            if s is None:
                raise ParameterError(f"from_occ: item {i} is a {type(item).__name__}, not an OCC shape")
            shapes.append(s)
        shape = _compound(shapes)
    else:
        shape = _unwrap(handle)
    if shape is None:
        raise ParameterError(f"from_occ does not know how to convert {type(handle).__name__}")
    if shape.IsNull():
        raise ParameterError("from_occ: the OCC shape is null (empty)")
    (TopAbs,) = _ocp("TopAbs")
    kind = shape.ShapeType()
    if kind == TopAbs.TopAbs_ShapeEnum.TopAbs_EDGE:
        curve = _edge_to_curve(_sub_shapes(shape, "EDGE")[0])
        if curve is None:
            raise ParameterError("from_occ: the edge is degenerate (it has no 3-D curve)")
        return curve
    if not (surfaces or oriented):  # oriented=True only means something for plain surfaces
        return brep_from_shape(shape)
    if kind == TopAbs.TopAbs_ShapeEnum.TopAbs_FACE:
        return _face_to_surface(_sub_shapes(shape, "FACE")[0], oriented)
    surfaces = [_face_to_surface(f, oriented) for f in _sub_shapes(shape, "FACE")]
    curves = (_edge_to_curve(e) for e in _free_edges(shape))
    return surfaces + [c for c in curves if c is not None]


# ----------------------------------------------------------------------------------------
# splinekit -> OCC topology


def _tolerance(tolerance) -> float:
    return as_positive(tolerance, "tolerance")


def _edge(curve):
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    maker = _occ_call("build an edge", BRepBuilderAPI.BRepBuilderAPI_MakeEdge, geom_to_occ(curve))
    if not maker.IsDone():
        raise BackendError(f"OpenCascade could not build an edge from the curve: {maker.Error().name}")
    return maker.Edge()


def _face(surface, tol: float):
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    maker = _occ_call("build a face", BRepBuilderAPI.BRepBuilderAPI_MakeFace, geom_to_occ(surface), tol)
    if not maker.IsDone():
        raise BackendError(f"OpenCascade could not build a face from the surface: {maker.Error().name}")
    return maker.Face()


def _closed_piece(shell):
    """A solid bounded by the closed ``shell``, oriented so that its volume is positive."""
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    maker = _occ_call("build a solid", BRepBuilderAPI.BRepBuilderAPI_MakeSolid, shell)
    if not maker.IsDone():
        raise BackendError("OpenCascade could not build a solid from the closed shell")
    solid = maker.Solid()
    if _volume(solid) < 0:  # the sewn faces point inward: flip the whole solid
        solid = solid.Reversed()
    return solid


def _sewn(patches, tol: float):
    """Sew ``patches`` into shells; closed shells become outward-oriented solids."""
    BRep, BRepBuilderAPI, TopoDS, TopTools = _ocp("BRep", "BRepBuilderAPI", "TopoDS", "TopTools")
    if len(patches) == 0:
        raise ParameterError("to_shape: the patch list is empty; expected at least one surface")
    for i, p in enumerate(patches):
        if not _is_surface(p):
            raise ParameterError(f"to_shape: patch {i} is a {type(p).__name__}; a patch list must hold surfaces only")
    sewing = BRepBuilderAPI.BRepBuilderAPI_Sewing(tol)
    for p in patches:
        sewing.Add(_face(p, tol))
    _occ_call("sew the patches", sewing.Perform)
    sewed = sewing.SewedShape()
    shells = _sub_shapes(sewed, "SHELL")
    in_shells = sum(len(_sub_shapes(s, "FACE")) for s in shells)
    if in_shells < len(_sub_shapes(sewed, "FACE")):
        # faces that sewing left alone (a single patch, or ones touching nothing): one shell each
        builder = BRep.BRep_Builder()
        known = TopTools.TopTools_IndexedMapOfShape()
        for s in shells:
            for f in _sub_shapes(s, "FACE"):
                known.Add(f)
        for f in _sub_shapes(sewed, "FACE"):
            if not known.Contains(f):
                shell = TopoDS.TopoDS_Shell()
                builder.MakeShell(shell)
                builder.Add(shell, f)
                shells.append(shell)
    pieces = []
    for shell in shells:
        closed = BRep.BRep_Tool.IsClosed_s(shell)
        piece = _closed_piece(shell) if closed else shell
        _check_valid(piece, "sewn solid" if closed else "sewn shell")
        pieces.append(piece)
    return pieces[0] if len(pieces) == 1 else _compound(pieces)


def to_shape(obj, *, tolerance: float = OCC_CONFUSION):
    """An OCP ``TopoDS_Shape`` for splinekit geometry.

    * a curve -> ``TopoDS_Edge`` (the exact B-spline / Bézier curve);
    * a surface -> ``TopoDS_Face`` bounded by its natural (domain) boundary;
    * a list or tuple of surfaces -> the patches sewn (``BRepBuilderAPI_Sewing``
      with ``tolerance``) into a ``TopoDS_Shell``; a closed shell becomes a
      ``TopoDS_Solid`` oriented outward (positive volume). Patches that sew into
      several disconnected pieces give a ``TopoDS_Compound`` of them. Shells and
      solids are checked with ``BRepCheck_Analyzer``; an invalid result raises
      BackendError naming the failing sub-shapes;
    * a :class:`~splinekit.brep.TrimmedFace` / ``Shell`` / ``Solid`` -> ``TopoDS_Face``
      / ``TopoDS_Shell`` / ``TopoDS_Solid`` built from the surfaces and pcurves, each
      shared edge built once (see :mod:`splinekit.interop.occ_brep`), checked with
      ``BRepCheck_Analyzer`` (an invalid result raises BackendError); a list of
      them -> a ``TopoDS_Compound``;
    * an OCC shape, or a build123d / cadquery object: its ``TopoDS_Shape``.

    ``tolerance`` (model units, mm by default in STEP) is the face tolerance and
    the sewing tolerance: patch edges farther apart than that are not joined.
    """
    tol = _tolerance(tolerance)
    if is_brep(obj):
        shape = brep_to_shape(obj, tolerance=tol)
        _check_valid(shape, type(obj).__name__)
        return shape
    if isinstance(obj, (list, tuple)):
        if obj and all(is_brep(o) for o in obj):
            return _compound([to_shape(o, tolerance=tol) for o in obj])
        return _sewn(list(obj), tol)
    if _is_curve(obj):
        return _edge(obj)
    if _is_surface(obj):
        return _face(obj, tol)
    require_ocp()
    shape = _unwrap(obj)
    if shape is not None:
        return shape
    raise ParameterError(
        f"to_shape does not know how to convert {type(obj).__name__}: "
        "expected a curve, a surface, a list of surfaces or an OCC shape"
    )


def to_build123d(obj, *, tolerance: float = OCC_CONFUSION):
    """A build123d ``Edge`` / ``Face`` / ``Shell`` / ``Solid`` / ``Compound`` for ``obj``.

    ``obj`` is anything :func:`to_shape` accepts (a curve, a surface, a list of
    surface patches...); ``tolerance`` is passed on.
    """
    shape = to_shape(obj, tolerance=tolerance)
    try:
        import build123d
    except ImportError as exc:
        reraise_interrupt(exc)
        raise _missing("build123d", exc) from None
    typed, name = _typed(shape)
    cls = {"Compsolid": "Compound"}.get(name, name)
    return getattr(build123d, cls)(typed)


def to_cadquery(obj, *, workplane: bool = False, tolerance: float = OCC_CONFUSION):
    """A cadquery ``Shape`` (``Edge``, ``Face``, ``Shell``, ``Solid``...) for ``obj``.

    ``obj`` is anything :func:`to_shape` accepts. With ``workplane=True`` the
    shape comes on a ``cadquery.Workplane`` (``Workplane().add(shape)``), ready
    for cadquery's fluent API.
    """
    if not isinstance(workplane, (bool, np.bool_)):
        raise ParameterError(f"workplane must be True or False, got {workplane!r}")
    shape = to_shape(obj, tolerance=tolerance)
    try:
        import cadquery
    except ImportError as exc:
        reraise_interrupt(exc)
        raise _missing("cadquery", exc) from None
    typed, _ = _typed(shape)
    cq_shape = cadquery.Shape.cast(typed)
    return cadquery.Workplane().add(cq_shape) if workplane else cq_shape
