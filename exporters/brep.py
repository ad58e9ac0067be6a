"""OpenCascade's native ``.brep`` format: exact B-rep objects in and out (``BRepTools``).

The file holds one OCC shape (a compound for several objects) with full-precision reals and no
names. :func:`import_brep` returns the same items as :func:`exporters.import_step`
(``(None, Solid | Shell | TrimmedFace)``, each rebuilt and checked valid, ``strict`` as there);
:func:`export_brep` writes atomically (a temporary file renamed into place).

OCP is imported inside the functions.
"""

from __future__ import annotations

import os

from splinekit._atomic import atomic_write
from splinekit.errors import ExportError, FileFormatError, ParameterError
from splinekit.interop.occ import _compound, _ocp, require_ocp
from splinekit.tolerances import OCC_CONFUSION

from ._brep_io import ReadResult, items_from_shapes, shapes_for_export
from ._meshio import _fspath, check_target

__all__ = ["export_brep", "import_brep"]


def export_brep(path, objects, *, tolerance: float = OCC_CONFUSION) -> str:
    """Write ``objects`` (one object or a list: TrimmedFace, Shell, Solid, curves, surfaces or OCC
    shapes, as :func:`exporters.export_step` takes them) to the OCC ``.brep`` file ``path``;
    returns ``path``. B-rep objects are checked with ``BRepCheck_Analyzer`` first (an invalid one
    raises BackendError and nothing is written)."""
    path = check_target(_fspath(path), "BREP file")
    items = list(objects) if isinstance(objects, (list, tuple)) else [objects]
    if not items:
        raise ParameterError("export_brep: nothing to export (objects is empty)")
    require_ocp()
    shapes = shapes_for_export(items, tolerance)
    shape = shapes[0] if len(shapes) == 1 else _compound(shapes)
    (BRepTools,) = _ocp("BRepTools")

    def write(tmp: str) -> None:
        if not BRepTools.BRepTools.Write_s(shape, tmp):
            raise ExportError(f"OpenCascade failed to write {path!r}")

    try:
        return atomic_write(path, write)
    except ExportError:
        raise
    except OSError as exc:
        raise ExportError(f"cannot write {path!r}: {exc}") from None


def read_brep_shape(path):
    """The OCC shape stored in the ``.brep`` file ``path`` (FileFormatError if it holds none)."""
    BRep, BRepTools, TopoDS = _ocp("BRep", "BRepTools", "TopoDS")
    if not os.path.isfile(path):
        raise FileFormatError(f"BREP file {path!r} does not exist or is not a file")
    shape = TopoDS.TopoDS_Shape()
    try:
        ok = BRepTools.BRepTools.Read_s(shape, path, BRep.BRep_Builder())
    except Exception as exc:  # OCC's Standard_Failure family
        raise FileFormatError(f"{path!r} is not a readable BREP file (OpenCascade: {type(exc).__name__}: {exc})") from None
    if not ok or shape.IsNull():
        raise FileFormatError(f"{path!r} is not a readable BREP file or holds no shape")
    return shape


def import_brep(path, *, strict: bool = True) -> ReadResult:
    """The solids, shells and faces of the OCC ``.brep`` file ``path`` as splinekit B-rep items
    ``(None, geometry)``; see :func:`exporters.import_step` for ``strict`` and ``.problems``."""
    path = _fspath(path)
    if not isinstance(strict, bool):
        raise ParameterError(f"strict must be True or False, got {strict!r}")
    shape = read_brep_shape(path)
    items = items_from_shapes([(None, shape)], strict=strict, path=path, kind="BREP")
    if not items:
        raise FileFormatError(f"the BREP file {path!r} holds no faces or edges")
    return items
