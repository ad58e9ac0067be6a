"""OpenCascade (OCP) interop for curves and surfaces.

``to_occ`` builds ``Geom_BSplineCurve`` / ``Geom_BSplineSurface`` (or the
Bézier classes) and ``from_occ`` reads them back, losslessly: knots go to OCC
as distinct values plus multiplicities and OCC arrays are 1-based. OCP is
imported inside the functions, so ``import splinekit`` does not load it.
"""

from __future__ import annotations

import numpy as np

from ..errors import MissingDependencyError, ParameterError

__all__ = ["to_occ", "from_occ", "require_ocp"]


def require_ocp():
    """Import and return the OCP modules used here, or raise MissingDependencyError."""
    try:
        from OCP import Geom, TColgp, TColStd, gp  # noqa: F401
    except ImportError as exc:  # also covers sys.modules["OCP"] = None
        raise MissingDependencyError(
            "OpenCascade bindings are missing: install them with "
            "pip install 'cadquery==2.8.*' 'build123d>=0.12,<0.13' "
            f"(they provide OCP 7.9); the import failed with: {exc}"
        ) from None
    return Geom, TColgp, TColStd, gp


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


def _pnt(xyz):
    _, _, _, gp = require_ocp()
    return gp.gp_Pnt(*(float(c) for c in xyz))


def _points3(P):
    P = np.asarray(P, dtype=np.float64)
    if P.shape[-1] != 3:
        raise ParameterError(f"OpenCascade geometry is 3-D; these control points have dim={P.shape[-1]}")
    return P


def _knots_mults(knots):
    values, counts = np.unique(knots, return_counts=True)
    return _array1_real(values), _array1_int(counts)


def to_occ(obj):
    """An OCP ``Geom_*`` handle for a splinekit curve or surface (3-D only)."""
    from ..curves import BezierCurve, SplineCurve
    from ..surfaces import BezierSurface, SplineSurface

    Geom, TColgp, TColStd, _ = require_ocp()
    if isinstance(obj, BezierCurve):
        P = _points3(obj.control_points)
        poles = TColgp.TColgp_Array1OfPnt(1, len(P))
        for i, x in enumerate(P):
            poles.SetValue(i + 1, _pnt(x))
        if obj.weights is None:
            return Geom.Geom_BezierCurve(poles)
        return Geom.Geom_BezierCurve(poles, _array1_real(obj.weights))
    if isinstance(obj, SplineCurve):
        P = _points3(obj.control_points)
        poles = TColgp.TColgp_Array1OfPnt(1, len(P))
        for i, x in enumerate(P):
            poles.SetValue(i + 1, _pnt(x))
        knots, mults = _knots_mults(obj.knots)
        if obj.weights is None:
            return Geom.Geom_BSplineCurve(poles, knots, mults, obj.degree, False)
        return Geom.Geom_BSplineCurve(poles, _array1_real(obj.weights), knots, mults, obj.degree, False)
    if isinstance(obj, (SplineSurface, BezierSurface)):
        P = _points3(obj.control_points)
        nu, nv = P.shape[:2]
        poles = TColgp.TColgp_Array2OfPnt(1, nu, 1, nv)
        for i in range(nu):
            for j in range(nv):
                poles.SetValue(i + 1, j + 1, _pnt(P[i, j]))
        weights = None
        if obj.weights is not None:
            weights = TColStd.TColStd_Array2OfReal(1, nu, 1, nv)
            for i in range(nu):
                for j in range(nv):
                    weights.SetValue(i + 1, j + 1, float(obj.weights[i, j]))
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


def from_occ(handle):
    """A splinekit curve or surface from an OCP ``Geom_BSpline*`` / ``Geom_Bezier*`` handle.

    Periodic OCC splines are returned on their clamped (non-periodic) form.
    """
    from ..curves import BezierCurve, BSplineCurve, NurbsCurve
    from ..surfaces import BezierSurface, BSplineSurface, NurbsSurface

    Geom, _, _, _ = require_ocp()
    if isinstance(handle, Geom.Geom_BezierCurve):
        P = [[handle.Pole(i).X(), handle.Pole(i).Y(), handle.Pole(i).Z()] for i in range(1, handle.NbPoles() + 1)]
        w = [handle.Weight(i) for i in range(1, handle.NbPoles() + 1)] if handle.IsRational() else None
        return BezierCurve(P, w)
    if isinstance(handle, Geom.Geom_BSplineCurve):
        if handle.IsPeriodic():
            handle = Geom.Geom_BSplineCurve.DownCast(handle.Copy())
            handle.SetNotPeriodic()
        n = handle.NbPoles()
        P = [[handle.Pole(i).X(), handle.Pole(i).Y(), handle.Pole(i).Z()] for i in range(1, n + 1)]
        U = _flat_knots(handle.Knot, handle.Multiplicity, handle.NbKnots())
        if handle.IsRational():
            return NurbsCurve(handle.Degree(), U, P, [handle.Weight(i) for i in range(1, n + 1)])
        return BSplineCurve(handle.Degree(), U, P)
    if isinstance(handle, (Geom.Geom_BezierSurface, Geom.Geom_BSplineSurface)):
        bezier = isinstance(handle, Geom.Geom_BezierSurface)
        if not bezier and (handle.IsUPeriodic() or handle.IsVPeriodic()):
            handle = Geom.Geom_BSplineSurface.DownCast(handle.Copy())
            if handle.IsUPeriodic():
                handle.SetUNotPeriodic()
            if handle.IsVPeriodic():
                handle.SetVNotPeriodic()
        nu, nv = handle.NbUPoles(), handle.NbVPoles()
        P = np.array(
            [[[handle.Pole(i, j).X(), handle.Pole(i, j).Y(), handle.Pole(i, j).Z()] for j in range(1, nv + 1)] for i in range(1, nu + 1)]
        )
        rational = handle.IsURational() or handle.IsVRational()
        W = np.array([[handle.Weight(i, j) for j in range(1, nv + 1)] for i in range(1, nu + 1)]) if rational else None
        if bezier:
            return BezierSurface(P, W)
        ku = _flat_knots(handle.UKnot, handle.UMultiplicity, handle.NbUKnots())
        kv = _flat_knots(handle.VKnot, handle.VMultiplicity, handle.NbVKnots())
        if rational:
            return NurbsSurface(handle.UDegree(), handle.VDegree(), ku, kv, P, W)
        return BSplineSurface(handle.UDegree(), handle.VDegree(), ku, kv, P)
    raise ParameterError(f"from_occ does not know how to convert {type(handle).__name__}")
