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

OCP is imported inside the functions, so ``import splinekit`` does not load it.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_positive
from ..errors import BackendError, MissingDependencyError, ParameterError, SplineKitError

__all__ = ["to_occ", "from_occ", "to_shape", "to_build123d", "to_cadquery", "require_ocp"]

_INSTALL_HINT = "pip install 'cadquery==2.8.*' 'build123d>=0.12,<0.13'"


def _missing(what: str, exc: Exception) -> MissingDependencyError:
    return MissingDependencyError(
        f"{what} is missing: install it with {_INSTALL_HINT} "
        f"(they provide OCP 7.9); the import failed with: {exc}"
    )


_MODULES: dict = {}  # OCP submodules already imported, valid while sys.modules["OCP"] is unchanged


def require_ocp():
    """Import and return the OCP modules used here, or raise MissingDependencyError."""
    Geom, TColgp, TColStd, gp = _ocp("Geom", "TColgp", "TColStd", "gp")
    return Geom, TColgp, TColStd, gp


def _ocp(*names: str):
    """The OCP submodules ``names`` (e.g. ``"BRep"``), or MissingDependencyError.

    Imports are cached: converting many small patches calls this once per patch.
    """
    import sys

    root = sys.modules.get("OCP")
    if root is None or _MODULES.get("") is not root:  # first use, or OCP blocked / reloaded
        _MODULES.clear()
        try:
            import OCP
        except ImportError as exc:  # also covers sys.modules["OCP"] = None
            raise _missing("OpenCascade bindings (OCP)", exc) from None
        _MODULES[""] = OCP
    try:
        return tuple(_MODULES[n] if n in _MODULES else _import_ocp(n) for n in names)
    except ImportError as exc:
        raise _missing("OpenCascade bindings (OCP)", exc) from None


def _import_ocp(name: str):
    import importlib

    module = _MODULES[name] = importlib.import_module(f"OCP.{name}")
    return module


def _array1(values, kind: str):
    """A 1-based OCC ``TColStd_Array1Of{Real,Integer}`` holding ``values``."""
    _, _, TColStd, _ = require_ocp()
    cls, cast = (TColStd.TColStd_Array1OfReal, float) if kind == "real" else (TColStd.TColStd_Array1OfInteger, int)
    arr = cls(1, len(values))
    for i, x in enumerate(values):
        arr.SetValue(i + 1, cast(x))
    return arr


def _array1_real(values):
    return _array1(values, "real")


def _array1_int(values):
    return _array1(values, "int")


def _poles1(P):
    """A 1-based ``TColgp_Array1OfPnt`` of the ``(n, 3)`` points ``P``."""
    _, TColgp, _, gp = require_ocp()
    pnt, arr = gp.gp_Pnt, TColgp.TColgp_Array1OfPnt(1, len(P))
    for i, (x, y, z) in enumerate(P.tolist(), 1):  # one OCC call per pole: OCP has no bulk setter
        arr.SetValue(i, pnt(x, y, z))
    return arr


def _poles2(P):
    """A 1-based ``TColgp_Array2OfPnt`` of the ``(nu, nv, 3)`` points ``P``."""
    _, TColgp, _, gp = require_ocp()
    pnt, arr = gp.gp_Pnt, TColgp.TColgp_Array2OfPnt(1, P.shape[0], 1, P.shape[1])
    for i, row in enumerate(P.tolist(), 1):
        for j, (x, y, z) in enumerate(row, 1):
            arr.SetValue(i, j, pnt(x, y, z))
    return arr


def _points3(P):
    P = np.asarray(P, dtype=np.float64)
    if P.shape[-1] != 3:
        raise ParameterError(f"OpenCascade geometry is 3-D; these control points have dim={P.shape[-1]}")
    return P


def _knots_mults(knots):
    values, counts = np.unique(knots, return_counts=True)
    return _array1_real(values), _array1_int(counts)


def to_occ(obj, *, tolerance: float = 1e-7):
    """An OCP ``Geom_*`` handle for a splinekit curve or surface (3-D only); for a B-rep
    ``TrimmedFace`` / ``Shell`` / ``Solid`` the ``TopoDS_Face`` / ``TopoDS_Shell`` /
    ``TopoDS_Solid`` (see :func:`to_shape`)."""
    from ..curves import BezierCurve, SplineCurve
    from ..surfaces import BezierSurface, SplineSurface
    from .occ_brep import is_brep

    if is_brep(obj):
        return to_shape(obj, tolerance=tolerance)
    Geom, TColgp, TColStd, _ = require_ocp()
    if isinstance(obj, BezierCurve):
        P = _points3(obj.control_points)
        poles = _poles1(P)
        if obj.weights is None:
            return Geom.Geom_BezierCurve(poles)
        return Geom.Geom_BezierCurve(poles, _array1_real(obj.weights))
    if isinstance(obj, SplineCurve):
        P = _points3(obj.control_points)
        poles = _poles1(P)
        knots, mults = _knots_mults(obj.knots)
        if obj.weights is None:
            return Geom.Geom_BSplineCurve(poles, knots, mults, obj.degree, False)
        return Geom.Geom_BSplineCurve(poles, _array1_real(obj.weights), knots, mults, obj.degree, False)
    if isinstance(obj, (SplineSurface, BezierSurface)):
        P = _points3(obj.control_points)
        nu, nv = P.shape[:2]
        poles = _poles2(P)
        weights = None
        if obj.weights is not None:
            weights = TColStd.TColStd_Array2OfReal(1, nu, 1, nv)
            for i, row in enumerate(obj.weights.tolist(), 1):
                for j, w in enumerate(row, 1):
                    weights.SetValue(i, j, w)
        if isinstance(obj, BezierSurface):
            return Geom.Geom_BezierSurface(poles) if weights is None else Geom.Geom_BezierSurface(poles, weights)
        ku, mu = _knots_mults(obj.knots_u)
        kv, mv = _knots_mults(obj.knots_v)
        if weights is None:
            return Geom.Geom_BSplineSurface(poles, ku, kv, mu, mv, obj.degree_u, obj.degree_v, False, False)
        return Geom.Geom_BSplineSurface(poles, weights, ku, kv, mu, mv, obj.degree_u, obj.degree_v, False, False)
    raise ParameterError(f"to_occ does not know how to convert {type(obj).__name__}")


def _flat_knots(get_knot, get_mult, count):
    return np.repeat([get_knot(i) for i in range(1, count + 1)], [get_mult(i) for i in range(1, count + 1)])



def _xyz(p):
    return (p.X(), p.Y(), p.Z())


def _from_geom(handle):
    """A splinekit curve or surface from an OCP ``Geom_BSpline*`` / ``Geom_Bezier*`` handle, or None."""
    from ..curves import BezierCurve, BSplineCurve, NurbsCurve
    from ..surfaces import BezierSurface, BSplineSurface, NurbsSurface

    Geom, _, _, _ = require_ocp()
    if isinstance(handle, Geom.Geom_BezierCurve):
        n = handle.NbPoles()
        P = [_xyz(handle.Pole(i)) for i in range(1, n + 1)]
        w = [handle.Weight(i) for i in range(1, n + 1)] if handle.IsRational() else None
        return BezierCurve(P, w)
    if isinstance(handle, Geom.Geom_BSplineCurve):
        if handle.IsPeriodic():  # unperiodize a copy: same geometry on a clamped knot vector
            handle = handle.Copy()  # OCP returns the derived class
            handle.SetNotPeriodic()
        n = handle.NbPoles()
        P = [_xyz(handle.Pole(i)) for i in range(1, n + 1)]
        U = _flat_knots(handle.Knot, handle.Multiplicity, handle.NbKnots())
        if handle.IsRational():
            curve = NurbsCurve(handle.Degree(), U, P, [handle.Weight(i) for i in range(1, n + 1)])
        else:
            curve = BSplineCurve(handle.Degree(), U, P)
        return curve.clamp()  # an unperiodized OCC curve keeps unclamped end knots
    if isinstance(handle, (Geom.Geom_BezierSurface, Geom.Geom_BSplineSurface)):
        bezier = isinstance(handle, Geom.Geom_BezierSurface)
        if not bezier and (handle.IsUPeriodic() or handle.IsVPeriodic()):
            handle = handle.Copy()
            if handle.IsUPeriodic():
                handle.SetUNotPeriodic()
            if handle.IsVPeriodic():
                handle.SetVNotPeriodic()
        nu, nv = handle.NbUPoles(), handle.NbVPoles()
        P = np.array([[_xyz(handle.Pole(i, j)) for j in range(1, nv + 1)] for i in range(1, nu + 1)])
        rational = handle.IsURational() or handle.IsVRational()
        W = np.array([[handle.Weight(i, j) for j in range(1, nv + 1)] for i in range(1, nu + 1)]) if rational else None
        if bezier:
            return BezierSurface(P, W)
        ku = _flat_knots(handle.UKnot, handle.UMultiplicity, handle.NbUKnots())
        kv = _flat_knots(handle.VKnot, handle.VMultiplicity, handle.NbVKnots())
        if rational:
            surface = NurbsSurface(handle.UDegree(), handle.VDegree(), ku, kv, P, W)
        else:
            surface = BSplineSurface(handle.UDegree(), handle.VDegree(), ku, kv, P)
        return surface.clamp()  # an unperiodized OCC surface keeps unclamped end knots
    return None


def _occ_call(what: str, fn, *args):
    """``fn(*args)``, with an OpenCascade exception turned into a BackendError naming ``what``."""
    try:
        return fn(*args)
    except SplineKitError:
        raise
    except Exception as exc:  # OCP's Standard_Failure family shares no base class but Exception
        raise BackendError(f"OpenCascade failed to {what}: {type(exc).__name__}: {exc}") from None


def _curve_to_bspline(curve, first=None, last=None):
    """The B-spline (or Bézier) form of an OCC ``Geom_Curve`` on ``[first, last]``."""
    Geom, _, _, _ = require_ocp()
    (GeomConvert,) = _ocp("GeomConvert")
    if first is not None:
        a, b = curve.FirstParameter(), curve.LastParameter()
        native = isinstance(curve, (Geom.Geom_BSplineCurve, Geom.Geom_BezierCurve))
        if not (native and _same_range((first, last), (a, b))):
            curve = _occ_call("trim a curve", Geom.Geom_TrimmedCurve, curve, first, last)
    out = _from_geom(curve)
    if out is None:
        if curve.FirstParameter() < -1e100 or curve.LastParameter() > 1e100:
            raise ParameterError(f"cannot convert the unbounded curve {type(curve).__name__}: trim it first")
        out = _from_geom(_occ_call("convert a curve to a B-spline", GeomConvert.GeomConvert.CurveToBSplineCurve_s, curve))
    return out


def _same_range(ab, cd) -> bool:
    """Whether two parameter ranges agree to 1e-12 of their length (UV bounds carry rounding)."""
    scale = max(1.0, abs(cd[1] - cd[0]))
    return abs(ab[0] - cd[0]) <= 1e-12 * scale and abs(ab[1] - cd[1]) <= 1e-12 * scale


def _face_to_surface(face, oriented: bool):
    """The B-spline form of a face's surface over the face's UV bounding box."""
    Geom, _, _, _ = require_ocp()
    BRep, BRepTools, GeomConvert, TopAbs = _ocp("BRep", "BRepTools", "GeomConvert", "TopAbs")
    surf = BRep.BRep_Tool.Surface_s(face)  # a located copy when the face is moved
    u0, u1, v0, v1 = BRepTools.BRepTools.UVBounds_s(face)
    if not all(abs(x) < 1e100 for x in (u0, u1, v0, v1)):  # OCC's "infinite" is 2e100
        raise ParameterError(
            f"cannot convert an unbounded face (UV bounds {[u0, u1, v0, v1]} on a {type(surf).__name__}): "
            "bound it with edges first"
        )
    nu0, nu1, nv0, nv1 = surf.Bounds()
    # clamp to the natural range along non-periodic directions: STEP-rounded bounds a hair past a
    # sphere's poles made OCC's conversion raise
    if not surf.IsUPeriodic():
        u0, u1 = max(u0, nu0), min(u1, nu1)
    else:  # and to one period along periodic ones (a torus's 2 pi + 1e-15 made it raise too)
        u1 = min(u1, u0 + surf.UPeriod())
    if not surf.IsVPeriodic():
        v0, v1 = max(v0, nv0), min(v1, nv1)
    else:
        v1 = min(v1, v0 + surf.VPeriod())
    native = isinstance(surf, (Geom.Geom_BSplineSurface, Geom.Geom_BezierSurface))
    if not (native and _same_range((u0, u1), (nu0, nu1)) and _same_range((v0, v1), (nv0, nv1))):
        surf = _occ_call("trim a surface", Geom.Geom_RectangularTrimmedSurface, surf, u0, u1, v0, v1)
    out = _from_geom(surf)
    if out is None:
        bs = _occ_call("convert a surface to a B-spline", GeomConvert.GeomConvert.SurfaceToBSplineSurface_s, surf)
        out = _from_geom(bs)
    if oriented and face.Orientation() == TopAbs.TopAbs_Orientation.TopAbs_REVERSED:
        out = (out.to_bspline() if not hasattr(out, "reverse") else out).reverse("u")
    return out


def _edge_to_curve(edge):
    """The B-spline form of an edge's 3-D curve over the edge's range, or None for a degenerate edge."""
    (BRep,) = _ocp("BRep")
    if BRep.BRep_Tool.Degenerated_s(edge):
        return None
    curve = BRep.BRep_Tool.Curve_s(edge, 0.0, 0.0)  # a located copy when the edge is moved
    if curve is None:
        return None
    first, last = BRep.BRep_Tool.Range_s(edge)
    if not (abs(first) < 1e100 and abs(last) < 1e100):  # OCC's "infinite" is 2e100
        raise ParameterError(
            f"cannot convert an unbounded edge (parameter range [{first!r}, {last!r}] on a "
            f"{type(curve).__name__}): give it finite end parameters"
        )
    return _curve_to_bspline(curve, first, last)


def _sub_shapes(shape, kind: str) -> list:
    """The distinct sub-shapes of ``kind`` ("FACE", "EDGE", ...) of ``shape``, in exploration order."""
    TopAbs, TopExp, TopTools, TopoDS = _ocp("TopAbs", "TopExp", "TopTools", "TopoDS")
    enum = getattr(TopAbs.TopAbs_ShapeEnum, f"TopAbs_{kind}")
    seen = TopTools.TopTools_IndexedMapOfShape()
    TopExp.TopExp.MapShapes_s(shape, enum, seen)
    cast = getattr(TopoDS.TopoDS, f"{kind.capitalize()}_s")
    return [cast(seen.FindKey(i)) for i in range(1, seen.Extent() + 1)]


def _unwrap(obj):
    """The ``TopoDS_Shape`` inside an OCC shape / build123d / cadquery object, or None."""
    if hasattr(obj, "vals") and callable(obj.vals) and not hasattr(obj, "wrapped"):  # cadquery Workplane
        shapes = [_unwrap(v) for v in obj.vals()]
        return _compound([s for s in shapes if s is not None])
    wrapped = getattr(obj, "wrapped", obj)
    try:
        from OCP.TopoDS import TopoDS_Shape
    except ImportError:
        return None
    return wrapped if isinstance(wrapped, TopoDS_Shape) else None


def _compound(shapes):
    """A ``TopoDS_Compound`` holding ``shapes``."""
    BRep, TopoDS = _ocp("BRep", "TopoDS")
    comp = TopoDS.TopoDS_Compound()
    builder = BRep.BRep_Builder()
    builder.MakeCompound(comp)
    for s in shapes:
        builder.Add(comp, s)
    return comp


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
        from .occ_brep import brep_from_shape

        return brep_from_shape(shape)
    if kind == TopAbs.TopAbs_ShapeEnum.TopAbs_FACE:
        return _face_to_surface(_sub_shapes(shape, "FACE")[0], oriented)
    surfaces = [_face_to_surface(f, oriented) for f in _sub_shapes(shape, "FACE")]
    curves = (_edge_to_curve(e) for e in _free_edges(shape))
    return surfaces + [c for c in curves if c is not None]


def _free_edges(shape) -> list:
    """The distinct edges of ``shape`` that bound none of its faces (wires, loose edges)."""
    TopAbs, TopExp, TopoDS, TopTools = _ocp("TopAbs", "TopExp", "TopoDS", "TopTools")
    # one OCC pass maps every edge to the faces it bounds (an empty list for a free edge)
    faces_of = TopTools.TopTools_IndexedDataMapOfShapeListOfShape()
    kinds = TopAbs.TopAbs_ShapeEnum
    TopExp.TopExp.MapShapesAndAncestors_s(shape, kinds.TopAbs_EDGE, kinds.TopAbs_FACE, faces_of)
    free = (i for i in range(1, faces_of.Extent() + 1) if faces_of.FindFromIndex(i).Size() == 0)
    return [TopoDS.TopoDS.Edge_s(faces_of.FindKey(i)) for i in free]


# ----------------------------------------------------------------------------------------
# splinekit -> OCC topology


def _tolerance(tolerance) -> float:
    return as_positive(tolerance, "tolerance")


def _is_curve(obj) -> bool:
    from ..curves import BezierCurve, SplineCurve

    return isinstance(obj, (BezierCurve, SplineCurve))


def _is_surface(obj) -> bool:
    from ..surfaces import BezierSurface, SplineSurface

    return isinstance(obj, (BezierSurface, SplineSurface))


def _edge(curve):
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    maker = _occ_call("build an edge", BRepBuilderAPI.BRepBuilderAPI_MakeEdge, to_occ(curve))
    if not maker.IsDone():
        raise BackendError(f"OpenCascade could not build an edge from the curve: {maker.Error().name}")
    return maker.Edge()


def _face(surface, tol: float):
    (BRepBuilderAPI,) = _ocp("BRepBuilderAPI")
    maker = _occ_call("build a face", BRepBuilderAPI.BRepBuilderAPI_MakeFace, to_occ(surface), tol)
    if not maker.IsDone():
        raise BackendError(f"OpenCascade could not build a face from the surface: {maker.Error().name}")
    return maker.Face()


_CHECK_ORDER = ("VERTEX", "EDGE", "WIRE", "FACE", "SHELL", "SOLID")


def _check_valid(shape, what: str) -> None:
    """Raise BackendError naming the failing sub-shapes (up to five) if BRepCheck rejects ``shape``."""
    (BRepCheck,) = _ocp("BRepCheck")
    analyzer = BRepCheck.BRepCheck_Analyzer(shape)
    if analyzer.IsValid():
        return
    problems = []
    for kind in _CHECK_ORDER:
        for index, sub in enumerate(_sub_shapes(shape, kind)):
            result = analyzer.Result(sub)
            if result is None:
                continue
            bad = sorted({st.name for st in result.Status() if st.name != "BRepCheck_NoError"})
            if bad:
                problems.append(f"{kind.lower()} {index}: {', '.join(bad)}")
    detail = "; ".join(problems[:5]) or "no sub-shape status was reported"
    raise BackendError(f"OpenCascade rejects the {what} (BRepCheck_Analyzer): {detail}")


def _volume(shape) -> float:
    BRepGProp, GProp = _ocp("BRepGProp", "GProp")
    props = GProp.GProp_GProps()
    BRepGProp.BRepGProp.VolumeProperties_s(shape, props)
    return props.Mass()


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


def to_shape(obj, *, tolerance: float = 1e-7):
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
    from .occ_brep import brep_to_shape, is_brep

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


def _typed(shape):
    """``shape`` downcast to its concrete ``TopoDS_*`` class, with that class's name."""
    (TopoDS,) = _ocp("TopoDS")
    name = shape.ShapeType().name.replace("TopAbs_", "").capitalize()  # "Face", "Compsolid", ...
    return getattr(TopoDS.TopoDS, f"{name}_s")(shape), name


def to_build123d(obj, *, tolerance: float = 1e-7):
    """A build123d ``Edge`` / ``Face`` / ``Shell`` / ``Solid`` / ``Compound`` for ``obj``.

    ``obj`` is anything :func:`to_shape` accepts (a curve, a surface, a list of
    surface patches...); ``tolerance`` is passed on.
    """
    shape = to_shape(obj, tolerance=tolerance)
    try:
        import build123d
    except ImportError as exc:
        raise _missing("build123d", exc) from None
    typed, name = _typed(shape)
    cls = {"Compsolid": "Compound"}.get(name, name)
    return getattr(build123d, cls)(typed)


def to_cadquery(obj, *, workplane: bool = False, tolerance: float = 1e-7):
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
        raise _missing("cadquery", exc) from None
    typed, _ = _typed(shape)
    cq_shape = cadquery.Shape.cast(typed)
    return cadquery.Workplane().add(cq_shape) if workplane else cq_shape
