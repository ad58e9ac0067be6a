"""What the exact B-rep readers (STEP, IGES, OCC's .brep) share: OCC shapes -> splinekit
``Solid`` / ``Shell`` / ``TrimmedFace`` items with the problems found, strict or not, and
splinekit objects -> one checked OCC shape per object for the writers.

A converted object is passed on only if OpenCascade's ``BRepCheck_Analyzer`` calls its rebuilt
shape valid: an invalid solid never leaves a reader.
"""

from __future__ import annotations

import warnings
from typing import Any, NamedTuple

from splinekit.brep import Shell, Solid, TrimmedFace
from splinekit.errors import BackendError, FileFormatError
from splinekit.interop.occ import _check_valid, _ocp, _sub_shapes, to_shape
from splinekit.interop.occ_brep import brep_from_shape, brep_to_shape, is_brep

__all__ = ["BrepItem", "ReadResult", "items_from_shapes"]


class BrepItem(NamedTuple):
    """One object read from an exact CAD file, with the name of the product it belongs to.

    ``geometry`` is a :class:`~splinekit.brep.Solid`, :class:`~splinekit.brep.Shell` or
    :class:`~splinekit.brep.TrimmedFace` (a curve for an edge that bounds no face).
    """

    name: str | None
    geometry: Any


class ReadResult(list):
    """The items read from a file (a list), with ``.problems``: one message per face or object that
    was left out (empty when everything was read; only ``strict=False`` reads leave things out)."""

    def __init__(self, items=(), problems=()):
        super().__init__(items)
        self.problems = list(problems)


def _face_problems(obj) -> tuple[list[int], str | None]:
    """``(bad face numbers, message)`` from OCC's check of ``obj`` rebuilt, or ``([], None)`` if valid."""
    try:
        shape = brep_to_shape(obj)
        _check_valid(shape, type(obj).__name__)
    except BackendError as exc:
        bad = []
        try:
            (BRepCheck,) = _ocp("BRepCheck")
            analyzer = BRepCheck.BRepCheck_Analyzer(shape)
            for i, f in enumerate(_sub_shapes(shape, "FACE")):
                if not BRepCheck.BRepCheck_Analyzer(f).IsValid() or any(
                        st.name != "BRepCheck_NoError" for st in (analyzer.Result(f).Status() if analyzer.Result(f) else [])):
                    bad.append(i)
        except Exception:  # the rebuild itself failed: no face to single out
            pass
        return bad, str(exc)
    return [], None


def items_from_shapes(named_shapes, *, strict: bool, path: str, kind: str, prepare=None) -> ReadResult:
    """Convert ``(name, TopoDS_Shape)`` pairs read from ``path`` (a ``kind`` file: "STEP"...).
    ``prepare``: applied to each converted B-rep object before it is checked (the STEP reader
    settles loop corners the format cannot carry, :mod:`exporters._step_corners`).

    ``strict=True``: any face that cannot be converted, or any object OCC does not call valid once
    rebuilt, raises FileFormatError naming the product, the face and the problem.
    ``strict=False``: those faces are left out (a solid that lost faces comes back as its remaining
    faces in a Shell), each problem is listed in ``.problems`` of the result and warned about.
    """
    items, problems = [], []
    for name, shape in named_shapes:
        where = f"{kind} file {path!r}, " + (f"object {name!r}" if name else "an unnamed object")
        reported = []
        objects = brep_from_shape(shape, name=name, on_error=lambda i, msg: reported.append(msg))
        if reported and strict:
            raise FileFormatError(f"{where}: {len(reported)} face(s) cannot be converted: " + "; ".join(reported[:5]))
        problems.extend(f"{where}: {msg}" for msg in reported)
        for obj in objects:
            if not isinstance(obj, (Solid, Shell, TrimmedFace)):
                items.append(BrepItem(name, obj))  # a free curve
                continue
            if prepare is not None:
                obj = prepare(obj)
            bad, message = _face_problems(obj)
            if message is None:
                items.append(BrepItem(name, obj))
                continue
            if strict:
                raise FileFormatError(f"{where}: the converted {type(obj).__name__.lower()} is not valid: {message}")
            problems.append(f"{where}: {type(obj).__name__.lower()} left out or reduced: {message}")
            faces = list(obj.faces) if not isinstance(obj, TrimmedFace) else [obj]
            good = [f for i, f in enumerate(faces) if i not in set(bad)] if bad else []
            if good and len(good) < len(faces):
                items.append(BrepItem(name, Shell(good, name=name)))
    for message in problems:
        warnings.warn(message, stacklevel=3)
    return ReadResult(items, problems)


def shapes_for_export(objects, tolerance: float) -> list:
    """One OCC shape per object (B-rep objects rebuilt and checked valid: an invalid one raises
    BackendError naming the failing faces); other objects as :func:`splinekit.occ.to_shape` makes them."""
    return [to_shape(obj, tolerance=tolerance) for obj in objects]


def default_names(objects, names):
    """``names``, or each B-rep object's own ``.name`` when ``names`` is None and some object has one."""
    if names is not None:
        return names
    own = [o.name if is_brep(o) else None for o in objects]
    return own if any(n is not None for n in own) else None
