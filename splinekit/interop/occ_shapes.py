"""OCC topology helpers: sub-shapes, compounds, wrapped shapes, validity and volume checks.

``TopoDS_Shape`` in, ``TopoDS_Shape`` (or lists of them) out; OCP comes through
:func:`.occ_backend._ocp`.
"""

from __future__ import annotations

from .._signals import reraise_interrupt
from ..errors import BackendError
from .occ_backend import _ocp


def _sub_shapes(shape, kind: str) -> list:
    """The distinct sub-shapes of ``kind`` ("FACE", "EDGE", ...) of ``shape``, in exploration order."""
    TopAbs, TopExp, TopTools, TopoDS = _ocp("TopAbs", "TopExp", "TopTools", "TopoDS")
    enum = getattr(TopAbs.TopAbs_ShapeEnum, f"TopAbs_{kind}")
    seen = TopTools.TopTools_IndexedMapOfShape()
    TopExp.TopExp.MapShapes_s(shape, enum, seen)
    cast = getattr(TopoDS.TopoDS, f"{kind.capitalize()}_s")
    return [cast(seen.FindKey(i)) for i in range(1, seen.Extent() + 1)]


def _free_edges(shape) -> list:
    """The distinct edges of ``shape`` that bound none of its faces (wires, loose edges)."""
    TopAbs, TopExp, TopoDS, TopTools = _ocp("TopAbs", "TopExp", "TopoDS", "TopTools")
    # one OCC pass maps every edge to the faces it bounds (an empty list for a free edge)
    faces_of = TopTools.TopTools_IndexedDataMapOfShapeListOfShape()
    kinds = TopAbs.TopAbs_ShapeEnum
    TopExp.TopExp.MapShapesAndAncestors_s(shape, kinds.TopAbs_EDGE, kinds.TopAbs_FACE, faces_of)
    free = (i for i in range(1, faces_of.Extent() + 1) if faces_of.FindFromIndex(i).Size() == 0)
    return [TopoDS.TopoDS.Edge_s(faces_of.FindKey(i)) for i in free]


def _children(shape) -> list:
    """The sub-shapes ``shape`` stores directly, in stored order (orientations composed)."""
    (TopoDS,) = _ocp("TopoDS")
    out, it = [], TopoDS.TopoDS_Iterator(shape)
    while it.More():
        out.append(it.Value())
        it.Next()
    return out


def _unwrap(obj):
    """The ``TopoDS_Shape`` inside an OCC shape / build123d / cadquery object, or None."""
    if hasattr(obj, "vals") and callable(obj.vals) and not hasattr(obj, "wrapped"):  # cadquery Workplane
        shapes = [_unwrap(v) for v in obj.vals()]
        return _compound([s for s in shapes if s is not None])
    wrapped = getattr(obj, "wrapped", obj)
    try:
        from OCP.TopoDS import TopoDS_Shape
    except ImportError as exc:
        reraise_interrupt(exc)
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


def _typed(shape):
    """``shape`` downcast to its concrete ``TopoDS_*`` class, with that class's name."""
    (TopoDS,) = _ocp("TopoDS")
    name = shape.ShapeType().name.replace("TopAbs_", "").capitalize()  # "Face", "Compsolid", ...
    return getattr(TopoDS.TopoDS, f"{name}_s")(shape), name


_CHECK_ORDER = ("VERTEX", "EDGE", "WIRE", "FACE", "SHELL", "SOLID")


def _check_valid(shape, what: str) -> None:
    """Raise BackendError naming the failing sub-shapes (up to five) if BRepCheck rejects ``shape``."""
    (BRepCheck,) = _ocp("BRepCheck")
    analyzer = BRepCheck.BRepCheck_Analyzer(shape)
    if analyzer.IsValid():
        return
    problems = []
    subs = {kind: _sub_shapes(shape, kind) for kind in _CHECK_ORDER}
    for kind in _CHECK_ORDER:
        for index, sub in enumerate(subs[kind]):
            result = analyzer.Result(sub)
            if result is None:
                continue
            bad = sorted({st.name for st in result.Status() if st.name != "BRepCheck_NoError"})
            if not bad:
                continue
            problems.append(f"{kind.lower()} {index}: {', '.join(bad)}")
            if kind != "FACE":
                continue
            # OCC marks a face "unorientable" when one of its edges fails on it (a pcurve too far
            # from the 3-D curve): name those edges too
            for edge in _sub_shapes(sub, "EDGE"):
                on = analyzer.Result(edge)
                if on is None or not on.IsStatusOnShape(sub):
                    continue
                bad = sorted({st.name for st in on.StatusOnShape(sub) if st.name != "BRepCheck_NoError"})
                if bad:
                    where = next((i for i, e in enumerate(subs["EDGE"]) if e.IsSame(edge)), "?")
                    problems.append(f"edge {where} on face {index}: {', '.join(bad)}")
    detail = "; ".join(problems[:5]) or "no sub-shape status was reported"
    raise BackendError(f"OpenCascade rejects the {what} (BRepCheck_Analyzer): {detail}")


def _volume(shape) -> float:
    BRepGProp, GProp = _ocp("BRepGProp", "GProp")
    props = GProp.GProp_GProps()
    BRepGProp.BRepGProp.VolumeProperties_s(shape, props)
    return props.Mass()
