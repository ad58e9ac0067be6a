"""IGES in and out for exact B-rep objects (OpenCascade's ``IGESControl``).

Solids are written as IGES 5.3 B-rep solids (manifold solid B-rep objects, entity 186:
``write.iges.brep.mode`` = 1), so faces keep their shared edges and a re-read gives solids
again. :func:`import_iges` returns the same items as :func:`exporters.import_step` (names are
not kept: ``(None, Solid | Shell | TrimmedFace)``, each rebuilt and checked valid, ``strict`` as
there); :func:`export_iges` writes atomically (a temporary file renamed into place).

OCP is imported inside the functions.
"""

from __future__ import annotations

import os
from contextlib import contextmanager

from splinekit._atomic import atomic_write
from splinekit.errors import ExportError, FileFormatError, ParameterError
from splinekit.interop.occ import _ocp, require_ocp
from splinekit.tolerances import OCC_CONFUSION

from ._brep_io import ReadResult, items_from_shapes, shapes_for_export
from ._meshio import _fspath, check_target
from .step import _occ_settings

__all__ = ["export_iges", "import_iges"]


@contextmanager
def _brep_mode():
    """``write.iges.brep.mode`` = 1 (solids as B-rep entities) for the duration, then restored."""
    (Interface,) = _ocp("Interface")
    static = Interface.Interface_Static
    saved = static.IVal_s("write.iges.brep.mode")
    static.SetIVal_s("write.iges.brep.mode", 1)
    try:
        yield
    finally:
        static.SetIVal_s("write.iges.brep.mode", saved)


def export_iges(path, objects, *, unit: str = "MM", tolerance: float = OCC_CONFUSION) -> str:
    """Write ``objects`` (one object or a list, as :func:`exporters.export_step` takes them) to
    the IGES file ``path``; returns ``path``. B-rep objects are checked with
    ``BRepCheck_Analyzer`` first (an invalid one raises BackendError and nothing is written)."""
    path = check_target(_fspath(path), "IGES file")
    items = list(objects) if isinstance(objects, (list, tuple)) else [objects]
    if not items:
        raise ParameterError("export_iges: nothing to export (objects is empty)")
    if not isinstance(unit, str) or unit.upper() not in ("MM", "CM", "M", "IN", "FT", "UM", "KM"):
        raise ParameterError(f"unit must be one of MM, CM, M, IN, FT, UM, KM, got {unit!r}")
    require_ocp()
    shapes = shapes_for_export(items, tolerance)
    (IGESControl,) = _ocp("IGESControl")

    def write(tmp: str) -> None:
        with _brep_mode(), _occ_settings():
            writer = IGESControl.IGESControl_Writer(unit.upper(), 1)
            for shape in shapes:
                if not writer.AddShape(shape):
                    raise ExportError(f"OpenCascade could not translate an object to IGES for {path!r}")
            writer.ComputeModel()
            if not writer.Write(tmp):
                raise ExportError(f"OpenCascade failed to write {path!r}")

    try:
        return atomic_write(path, write)
    except ExportError:
        raise
    except OSError as exc:
        raise ExportError(f"cannot write {path!r}: {exc}") from None


def read_iges_shape(path):
    """The OCC shape of all roots of the IGES file ``path``."""
    IFSelect, IGESControl = _ocp("IFSelect", "IGESControl")
    if not os.path.isfile(path):
        raise FileFormatError(f"IGES file {path!r} does not exist or is not a file")
    reader = IGESControl.IGESControl_Reader()
    with _occ_settings():  # OCC prints its loading statistics otherwise
        status = reader.ReadFile(path)
        if status != IFSelect.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise FileFormatError(f"{path!r} is not a readable IGES file (OpenCascade: {status.name})")
        roots = reader.TransferRoots()
    if roots == 0:
        raise FileFormatError(f"the IGES file {path!r} holds no shapes")
    return reader.OneShape()


def import_iges(path, *, strict: bool = True) -> ReadResult:
    """The solids, shells and faces of the IGES file ``path`` as splinekit B-rep items
    ``(None, geometry)``; see :func:`exporters.import_step` for ``strict`` and ``.problems``."""
    path = _fspath(path)
    if not isinstance(strict, bool):
        raise ParameterError(f"strict must be True or False, got {strict!r}")
    shape = read_iges_shape(path)
    items = items_from_shapes([(None, shape)], strict=strict, path=path, kind="IGES")
    if not items:
        raise FileFormatError(f"the IGES file {path!r} holds no faces or edges")
    return items
