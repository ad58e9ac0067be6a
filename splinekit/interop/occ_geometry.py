"""Curves and surfaces to and from OpenCascade geometry (``Geom_*`` and ``Geom2d_*`` handles).

splinekit -> OCC (:func:`geom_to_occ`) builds ``Geom_BSplineCurve`` / ``Geom_BSplineSurface`` (or
the Bézier classes), losslessly: knots go to OCC as distinct values plus multiplicities, and OCC
arrays are 1-based. OCC -> splinekit (:func:`_from_geom`) reads them back; other bounded curves
and surfaces (lines, circles, planes, cylinders...) go through ``GeomConvert`` to their exact
(rational) B-spline forms. The 2-D pcurves of B-rep edges (``Geom2d_*``) go both ways too, keeping
OCC's parameter.
"""

from __future__ import annotations

import numpy as np

from ..brep.edge import as_pcurve
from ..curves import BezierCurve, BSplineCurve, NurbsCurve, SplineCurve
from ..errors import ParameterError
from ..surfaces import BezierSurface, BSplineSurface, NurbsSurface, SplineSurface
from .occ_backend import _ocp, _occ_call, require_ocp

__all__ = ["geom_to_occ"]


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


def geom_to_occ(obj):
    """An OCP ``Geom_BSpline*`` / ``Geom_Bezier*`` handle for a splinekit curve or surface (3-D
    only); ParameterError for anything else (:func:`splinekit.interop.occ.to_occ` also takes B-rep
    objects)."""
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


def _is_curve(obj) -> bool:
    return isinstance(obj, (BezierCurve, SplineCurve))


def _is_surface(obj) -> bool:
    return isinstance(obj, (BezierSurface, SplineSurface))


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


def _same_domain(a, b) -> bool:
    scale = max(1.0, abs(a[1] - a[0]))
    return abs(a[0] - b[0]) <= 1e-9 * scale and abs(a[1] - b[1]) <= 1e-9 * scale


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


# ----------------------------------------------------------------------------------------
# 2-D curves (pcurves) and the 3-D curves of edges, on OCC's parameter


def _curve2d_to_occ(curve):
    """An OCP ``Geom2d_BSplineCurve`` for a 2-D splinekit curve."""
    _, _, TColStd, _ = require_ocp()
    Geom2d, TColgp, gp = _ocp("Geom2d", "TColgp", "gp")
    curve = as_pcurve(curve)
    P = np.asarray(curve.control_points, dtype=np.float64)
    poles = TColgp.TColgp_Array1OfPnt2d(1, len(P))
    for i, (x, y) in enumerate(P.tolist(), 1):
        poles.SetValue(i, gp.gp_Pnt2d(x, y))
    values, counts = np.unique(curve.knots, return_counts=True)
    knots = TColStd.TColStd_Array1OfReal(1, len(values))
    mults = TColStd.TColStd_Array1OfInteger(1, len(values))
    for i, (k, m) in enumerate(zip(values.tolist(), counts.tolist()), 1):
        knots.SetValue(i, k)
        mults.SetValue(i, int(m))
    if curve.weights is None:
        return Geom2d.Geom2d_BSplineCurve(poles, knots, mults, curve.degree, False)
    weights = TColStd.TColStd_Array1OfReal(1, len(P))
    for i, w in enumerate(np.asarray(curve.weights).tolist(), 1):
        weights.SetValue(i, w)
    return Geom2d.Geom2d_BSplineCurve(poles, weights, knots, mults, curve.degree, False)


def _curve2d_from_occ(handle, first: float, last: float):
    """A 2-D splinekit B-spline / NURBS curve for the OCP ``Geom2d_Curve`` on ``[first, last]``,
    keeping OCC's parameter (a B-spline is cut with ``Segment``, which does not reparametrize)."""
    Geom2d, Geom2dConvert = _ocp("Geom2d", "Geom2dConvert")
    if isinstance(handle, Geom2d.Geom2d_TrimmedCurve):
        handle = handle.BasisCurve()
    if isinstance(handle, Geom2d.Geom2d_BezierCurve):
        handle = Geom2dConvert.Geom2dConvert.CurveToBSplineCurve_s(handle)  # same parameter [0, 1]
    if isinstance(handle, Geom2d.Geom2d_Line):  # exactly, on the same parameter
        p, q = handle.Value(first), handle.Value(last)
        return BSplineCurve(1, [first, first, last, last], [[p.X(), p.Y()], [q.X(), q.Y()]])
    if not isinstance(handle, Geom2d.Geom2d_BSplineCurve):
        trimmed = _occ_call("trim a pcurve", Geom2d.Geom2d_TrimmedCurve, handle, first, last)
        handle = _occ_call("convert a pcurve", Geom2dConvert.Geom2dConvert.CurveToBSplineCurve_s, trimmed)
    else:
        handle = handle.Copy()  # OCP returns the derived class
    _segment(handle, first, last)
    n = handle.NbPoles()
    P = [(handle.Pole(i).X(), handle.Pole(i).Y()) for i in range(1, n + 1)]
    U = np.repeat([handle.Knot(i) for i in range(1, handle.NbKnots() + 1)],
                  [handle.Multiplicity(i) for i in range(1, handle.NbKnots() + 1)])
    if handle.IsRational():
        curve = NurbsCurve(handle.Degree(), U, P, [handle.Weight(i) for i in range(1, n + 1)])
    else:
        curve = BSplineCurve(handle.Degree(), U, P)
    return curve.clamp()


def _segment(handle, first: float, last: float) -> None:
    """Cut the B-spline ``handle`` (a copy; 2-D or 3-D) to ``[first, last]`` in place."""
    a, b = handle.FirstParameter(), handle.LastParameter()
    scale = max(1.0, abs(b - a))
    if handle.IsPeriodic():
        handle.Segment(first, last)  # a periodic segment may cross the knot origin
        handle.SetNotPeriodic()
        return
    if abs(first - a) <= 1e-13 * scale and abs(last - b) <= 1e-13 * scale:
        return
    # STEP rounding can put a range a hair past the curve's ends: clamp it to the natural range
    first, last = max(first, a), min(last, b)
    if last - first > 1e-12 * scale:
        handle.Segment(first, last)


def _curve3d_from_occ(edge):
    """The 3-D curve of ``edge`` on its own range (OCC's parameter kept), or None."""
    Geom, _, _, _ = require_ocp()
    (BRep, GeomConvert) = _ocp("BRep", "GeomConvert")
    curve = BRep.BRep_Tool.Curve_s(edge, 0.0, 0.0)  # a located copy when the edge is moved
    if curve is None:
        return None
    first, last = BRep.BRep_Tool.Range_s(edge)
    if isinstance(curve, Geom.Geom_TrimmedCurve):
        curve = curve.BasisCurve()
    if isinstance(curve, Geom.Geom_BezierCurve):
        curve = GeomConvert.GeomConvert.CurveToBSplineCurve_s(curve)
    if isinstance(curve, Geom.Geom_Line):  # exactly, on the same parameter
        return BSplineCurve(1, [first, first, last, last], [_xyz(curve.Value(first)), _xyz(curve.Value(last))])
    if not isinstance(curve, Geom.Geom_BSplineCurve):
        return None  # anything else is left to BRepLib.BuildCurve3d on export
    curve = curve.Copy()
    _segment(curve, first, last)
    return _from_geom(curve)
