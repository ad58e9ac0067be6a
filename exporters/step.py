"""Exact STEP (AP214) export and import through OpenCascade's XCAF translator.

Curves are written as B-spline edges, surfaces as B-spline faces and patch
sets as sewn shells (solids when they close up): the control points, weights
and knots go into the file as they are, with no tessellation or refitting.
Each object is a STEP product carrying its name.

Reals are written with 16 significant digits (OCC's default is 12), so a
round trip changes a number by at most one rounding to 16 digits.

The file is written atomically: a temporary file in the target folder is
written, then renamed onto the target; a failed export leaves no temporary
file behind and any existing target untouched.

OCP is imported inside the functions.
"""

from __future__ import annotations

import os
import unicodedata
from contextlib import contextmanager

from splinekit._atomic import atomic_write, write_target
from splinekit._signals import reraise_interrupt
from splinekit.errors import ExportError, FileFormatError, ParameterError
from splinekit.interop.occ import _compound, from_occ, require_ocp, to_shape
from splinekit.interop.occ_brep import is_brep
from splinekit.interop.occ_step_poles import pole_edges_as_points
from splinekit.tolerances import OCC_CONFUSION

from ._brep_io import BrepItem, ReadResult, default_names, items_from_shapes
from ._meshio import _fspath
from ._step_corners import settle_corners
from ._step_isolated import transfer
from ._stepscan import scan_step, syntax_errors

__all__ = ["export_step", "import_step", "StepItem", "ReadResult", "STEP_UNITS"]

#: Length units a STEP file can declare: name -> (OCC's ``write.step.unit`` value, metres per unit).
STEP_UNITS = {
    "mm": ("MM", 1e-3),
    "cm": ("CM", 1e-2),
    "m": ("M", 1.0),
    "km": ("KM", 1e3),
    "um": ("UM", 1e-6),
    "inch": ("INCH", 0.0254),
    "ft": ("FT", 0.3048),
}


StepItem = BrepItem
"""One object read from a STEP file: ``(name, geometry)``, ``name`` the STEP product name (None if
the file gives none), ``geometry`` a Solid, Shell or TrimmedFace (a curve for a free edge; with
``import_step(..., surfaces=True)`` a plain surface per face)."""


def _unit(unit) -> tuple[str, float]:
    key = str(unit).strip().lower() if isinstance(unit, str) else None
    if key not in STEP_UNITS:
        raise ParameterError(f"unit must be one of {sorted(STEP_UNITS)}, got {unit!r}")
    return STEP_UNITS[key]


def _ocp_step():
    """The OCP modules this file uses (MissingDependencyError if OCP is absent)."""
    require_ocp()
    from OCP import (
        TDF,
        IFSelect,
        Interface,
        Message,
        STEPCAFControl,
        STEPControl,
        TCollection,
        TDataStd,
        TDocStd,
        XCAFDoc,
    )

    return IFSelect, Interface, Message, STEPCAFControl, STEPControl, TCollection, TDataStd, TDF, TDocStd, XCAFDoc


# OCC's "write.precision.mode": 1 ("Greatest") writes the greatest tolerance in the shape as the
# file's UNCERTAINTY_MEASURE_WITH_UNIT (OCC's default, "Average", writes the mean). OCC's reader
# takes that uncertainty as its precision and, while it translates each face, re-fits a pcurve by
# projecting the 3-D curve onto the surface wherever the pcurve lies further than twice the
# precision from the curve (XSAlgo_ShapeProcessor::CheckPCurve): with the mean, the loose edges of
# parts read from other CAD systems (a pcurve up to their tolerance off its curve) were re-fitted
# and their faces' areas moved (the SolidWorks 2012 file's round trip: 1.9e-9 relative with the
# mean, 2.4e-15 with the greatest); with the greatest, no pcurve we write is re-fitted.
_WRITE_PRECISION_GREATEST = 1


@contextmanager
def _occ_settings(step_unit: str | None = None):
    """Silence OCC's translator chatter and set ``write.step.unit`` and ``write.precision.mode``,
    restoring all after.

    OCC prints transfer statistics and parse errors on stdout through its default
    messenger; its printers are detached for the duration (errors reach the
    caller as exceptions instead).
    """
    _, Interface, Message, _, STEPControl, *_ = _ocp_step()
    # the STEP statics exist only once OCC's STEP controller is initialised (its first reader or
    # writer does that): before, setting them fails silently, and the first export of a process
    # ignored its unit
    STEPControl.STEPControl_Controller.Init_s()
    messenger = Message.Message.DefaultMessenger_s()
    printers = list(messenger.Printers())
    static = Interface.Interface_Static
    saved = {key: static.CVal_s(key) for key in ("write.step.unit", "write.step.schema", "write.precision.mode")}
    try:
        for p in printers:
            messenger.RemovePrinter(p)
        if step_unit is not None:
            static.SetCVal_s("write.step.unit", step_unit)
            static.SetCVal_s("write.step.schema", "AP214IS")
            static.SetIVal_s("write.precision.mode", _WRITE_PRECISION_GREATEST)
        yield
    finally:
        for p in printers:
            messenger.AddPrinter(p)
        for key, value in saved.items():
            static.SetCVal_s(key, value)


def _step_string(text: str) -> str:
    """``text`` with every character outside printable ASCII (and the backslash and apostrophe) as an
    ISO 10303-21 ``\\X2\\`` / ``\\X4\\`` escape, which OCC's reader decodes back to Unicode.

    OCC's writer would store the UTF-8 bytes unescaped, which its own reader then misreads;
    the apostrophe is escaped too, as OCC's reader cuts a name at a doubled ``''`` followed by
    a comma, and so are leading and trailing spaces, which the reader strips.
    """
    out, run = [], []  # run: consecutive escaped code points, written as one \\X2\\ group

    def flush():
        if run:
            wide = any(c > 0xFFFF for c in run)
            out.append("\\X4\\" + "".join("%08X" % c for c in run) if wide else "\\X2\\" + "".join("%04X" % c for c in run))
            out.append("\\X0\\")
            run.clear()

    last = len(text) - 1
    for i, ch in enumerate(text):
        code = ord(ch)
        if 32 <= code < 127 and ch not in "\\'" and not (ch == " " and i in (0, last)):
            flush()
            out.append(ch)
        else:
            run.append(code)
    flush()
    return "".join(out)


def _new_document(metres_per_unit: float):
    """An empty XCAF document whose length unit is ``metres_per_unit`` (so OCC never rescales)."""
    *_, TCollection, _, _, TDocStd, XCAFDoc = _ocp_step()
    doc = TDocStd.TDocStd_Document(TCollection.TCollection_ExtendedString("XmlOcaf"))
    XCAFDoc.XCAFDoc_DocumentTool.SetLengthUnit_s(doc, metres_per_unit)
    return doc


# OCC's default STEP real format keeps 12 significant digits. "%.15E" keeps 16 (a relative
# error of at most 5e-16) and is the longest that fits the writer's 24-byte buffer even with a
# three-digit exponent; it must go without OCC's zero suppression, which looks for the exponent
# in the first 16 characters only.
_REAL_FORMAT = "%.15E"


def _write_step_file(writer, path: str):
    """Write the transferred document to ``path`` with full-precision reals.

    Returns OCC's ``IFSelect_ReturnStatus`` (``IFSelect_RetDone`` on success).
    This is ``STEPControl_Writer.Write`` with the real format replaced:
    the same model is sent through a ``StepData_StepWriter`` of our own.
    """
    import io

    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.StepData import StepData_StepWriter

    model = writer.Writer().Model()
    step_writer = StepData_StepWriter(model)
    step_writer.FloatWriter().SetFormat(_REAL_FORMAT)  # a reference to the writer's own
    step_writer.SendModel(model.Protocol())
    buffer = io.BytesIO()
    if not step_writer.Print(buffer):
        return IFSelect_ReturnStatus.IFSelect_RetFail
    with open(path, "wb") as f:
        f.write(buffer.getbuffer())
    return IFSelect_ReturnStatus.IFSelect_RetDone


# OCC's writer breaks strings at column 72 and its reader cannot decode an escape sequence
# broken over two lines; an escaped name this short always fits on one line.
_MAX_ESCAPED_NAME = 64


def _objects(objects) -> list:
    if isinstance(objects, (list, tuple)):
        if len(objects) == 0:
            raise ParameterError("export_step: nothing to export (objects is empty)")
        return list(objects)
    return [objects]


def _names(names, count: int) -> list:
    if names is None:
        return [None] * count
    if isinstance(names, str):
        names = [names]
    try:
        names = list(names)
    except TypeError:
        raise ParameterError(f"names must be a list of strings (or None), got {type(names).__name__}") from None
    if len(names) != count:
        raise ParameterError(f"names has {len(names)} entries but there are {count} objects to export")
    for i, n in enumerate(names):
        if n is not None and not (isinstance(n, str) and n):
            raise ParameterError(f"names[{i}] must be a non-empty string or None, got {n!r}")
        if n is None:
            continue
        bad = next((k for k, ch in enumerate(n) if unicodedata.category(ch) in ("Cc", "Cs")), None)
        if bad is not None:  # STEP strings cannot carry control characters (OCC garbles them)
            raise ParameterError(
                f"names[{i}] = {n!r} has the control character U+{ord(n[bad]):04X} at position {bad}; "
                "names must be printable text"
            )
        encoded = _step_string(n)
        if encoded != n and len(encoded) > _MAX_ESCAPED_NAME:
            raise ParameterError(
                f"names[{i}] = {n!r} is {len(encoded)} characters long once its non-ASCII characters, "
                f"apostrophes and end spaces are escaped for STEP; at most {_MAX_ESCAPED_NAME} are kept "
                "intact (OpenCascade's reader garbles an escape broken across the file's 72-column lines)"
            )
    return names


def _name_ok(name) -> bool:
    try:
        _names([name], 1)
    except ParameterError:
        return False
    return True


def _products(shapes, names):
    """``(shape, name)`` per STEP product: each named object alone, and each run of
    consecutive unnamed objects as one compound (a STEP product costs OCC about half a
    millisecond to translate, and unnamed objects need no product of their own)."""
    out, run = [], []
    for shape, name in zip(shapes, names):
        if name is None:
            run.append(shape)
            continue
        if run:
            out.append((run[0] if len(run) == 1 else _compound(run), None))
            run = []
        out.append((shape, name))
    if run:
        out.append((run[0] if len(run) == 1 else _compound(run), None))
    return out


def _built_here(obj) -> bool:
    """Whether :func:`to_shape` builds a new OCC shape for ``obj`` (a B-rep object or a list of
    them), rather than handing back the caller's own."""
    if isinstance(obj, (list, tuple)):
        return bool(obj) and all(is_brep(o) for o in obj)
    return is_brep(obj)


def _check_target(path) -> str:
    """``path`` as a str, checked before the (slow) OCC translation: the mesh writers' checks,
    and a writable folder."""
    path = _fspath(path)
    real, _ = write_target(path, "STEP file")
    folder = os.path.dirname(real)  # of the file a symbolic link names: the temporary file goes there
    if not os.access(folder, os.W_OK):
        raise ExportError(f"cannot write STEP file {path!r}: the folder {folder!r} is not writable")
    return path


def export_step(path, objects, *, names=None, unit: str = "mm", tolerance: float = OCC_CONFUSION) -> str:
    """Write ``objects`` to the STEP (AP214) file ``path``, exactly; returns ``path``.

    ``objects`` is one object or a list (or tuple) of objects; each object is

    * a curve: a B-spline edge (Bézier and NURBS curves likewise);
    * a surface: a B-spline face bounded by its domain;
    * a list or tuple of surfaces: the patches sewn into a shell, written as a
      solid when the shell is closed (see :func:`splinekit.occ.to_shape`);
    * a :class:`~splinekit.brep.TrimmedFace`, ``Shell`` or ``Solid``: an exact OCC face, shell
      or solid with its trims and shared edges, checked with ``BRepCheck_Analyzer`` before
      anything is written (an invalid one raises BackendError naming the failing faces); the pole
      edges of a loop that is only a seam and poles, beside other loops, are written as edges of
      zero length, which OCC's reader turns back into pole edges
      (:mod:`splinekit.interop.occ_step_poles`);
    * an OCC shape or a build123d / cadquery object: written as it is.

    So ``export_step(p, [s0, s1])`` writes two faces and ``export_step(p, [[s0, s1]])``
    one shell. ``names`` (one non-empty printable string or ``None`` per object)
    become the STEP product names (by default the B-rep objects' own ``.name``). Each named object is a product of its own;
    consecutive unnamed objects share one product (a compound), which gets OCC's
    default name (its shape type, such as ``"COMPOUND"``, ``"FACE"`` or ``"SOLID"``).
    The geometry and its order are the same either way. Coordinates are written unchanged and the file declares them
    in ``unit`` (``"mm"`` by default; see ``STEP_UNITS``). ``tolerance`` is the
    face and sewing tolerance in that unit.

    Raises ExportError if the folder is missing or unwritable or OCC fails to
    write (any existing file at ``path`` is left unchanged), ParameterError on
    bad arguments (including a ``path`` that is not a str / os.PathLike, or is
    empty) and BackendError if OCC rejects the geometry.
    """
    path = _fspath(path)
    step_unit, metres = _unit(unit)
    items = _objects(objects)
    if names is None:  # the objects' own names, each kept only if STEP can carry it intact
        labels = [n if n is None or _name_ok(n) else None for n in (default_names(items, None) or [None] * len(items))]
    else:
        labels = _names(names, len(items))
    path = _check_target(path)
    IFSelect, _, _, STEPCAFControl, STEPControl, TCollection, TDataStd, _, _, XCAFDoc = _ocp_step()
    shapes = [to_shape(obj, tolerance=tolerance) for obj in items]
    for obj, shape in zip(items, shapes):
        if _built_here(obj):  # a shape of our own making, never the caller's: changed in place
            pole_edges_as_points(shape)
    doc = _new_document(metres)
    tool = XCAFDoc.XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    for shape, name in _products(shapes, labels):
        label = tool.AddShape(shape, False)  # a product of its own, not an assembly
        if name is not None:
            TDataStd.TDataStd_Name.Set_s(label, TCollection.TCollection_ExtendedString(_step_string(name)))

    def write(tmp: str) -> None:
        with _occ_settings(step_unit):
            writer = STEPCAFControl.STEPCAFControl_Writer()
            writer.SetNameMode(True)
            if not writer.Transfer(doc, STEPControl.STEPControl_StepModelType.STEPControl_AsIs):
                raise ExportError(f"OpenCascade could not translate the objects to STEP for {path!r}")
            try:
                status = _write_step_file(writer, tmp)
            except OSError:
                raise
            except Exception as exc:  # an OCC failure while writing: the target stays untouched
                reraise_interrupt(exc)  # an interrupt OCC wrapped is still an interrupt
                raise ExportError(f"OpenCascade failed to write {path!r}: {type(exc).__name__}: {exc}") from None
        if status != IFSelect.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise ExportError(f"OpenCascade failed to write {path!r}: {getattr(status, 'name', status)}")

    return atomic_write(path, write, "STEP file")


def _label_name(label, TDataStd) -> str | None:
    """The label's name, or None; OCC's made-up component names ``=>[0:1:1:6]`` count as none."""
    attr = TDataStd.TDataStd_Name()
    if label.FindAttribute(TDataStd.TDataStd_Name.GetID_s(), attr):
        name = attr.Get().ToExtString()
        return None if name.startswith("=>[") else name
    return None


def _named_shapes(tool, label, inherited, parent_loc, mods):
    """``(name, shape)`` for every part under ``label``, walking assemblies into their components.

    ``parent_loc`` is the placement accumulated from the enclosing assemblies;
    a part's name is its component's name, else its own, else the assembly's.
    """
    TDataStd, TDF = mods
    name = _label_name(label, TDataStd) or inherited
    if tool.IsReference_s(label):  # a component: a placed instance of another label
        referred = TDF.TDF_Label()
        tool.GetReferredShape_s(label, referred)
        if tool.IsAssembly_s(referred):
            loc = parent_loc.Multiplied(tool.GetLocation_s(label))
            return _named_shapes(tool, referred, name, loc, mods)
        name = name or _label_name(referred, TDataStd)
        return [(name, tool.GetShape_s(label).Moved(parent_loc))]
    if tool.IsAssembly_s(label):
        comps = TDF.TDF_LabelSequence()
        tool.GetComponents_s(label, comps)
        out = []
        for i in range(1, comps.Length() + 1):
            out.extend(_named_shapes(tool, comps.Value(i), name, parent_loc, mods))
        return out
    return [(name, tool.GetShape_s(label).Moved(parent_loc))]


def import_step(path, *, unit: str = "mm", strict: bool = True, surfaces: bool = False,
                isolated: bool = True) -> ReadResult:
    """The solids, shells and faces of the STEP file ``path`` as splinekit B-rep objects, in file order.

    Returns a :class:`ReadResult` (a list) of :class:`StepItem` ``(name, geometry)``: one item
    per solid, per shell outside a solid and per face outside a shell, ``geometry`` a
    :class:`~splinekit.brep.Solid` / ``Shell`` / ``TrimmedFace`` keeping every trimming loop,
    face orientation and shared edge (see :func:`splinekit.occ.from_occ`), ``name`` the STEP
    product (object) it belongs to; edges that bound no face give one curve each. Every surface
    type OCC reads (plane, cylinder, cone, sphere, torus, revolution, extrusion, offset, Bézier,
    B-spline) comes as its exact B-spline / NURBS form. Coordinates come in ``unit``
    (millimetres by default), converted from the unit the file declares.

    Each object is rebuilt and checked with OCC's ``BRepCheck_Analyzer`` before it is returned.
    ``strict=True`` (default): a face that cannot be converted or an object that is not valid
    raises FileFormatError naming the object, the face and the problem. ``strict=False``: those
    are left out (a solid that lost faces comes back as a Shell of the good ones), and each is
    described in the result's ``.problems`` list and in a warning.

    ``surfaces=True`` gives the former reading instead: one item per face holding the plain
    B-spline form of its surface over the face's UV box (trims dropped).

    ``isolated=True`` (default): OCC's translation runs in a worker process (see
    :mod:`exporters._step_isolated`), so a file that crashes or hangs OCC raises FileFormatError
    instead of ending this process. The worker starts once per process (a few seconds: it
    imports OCP); after that a file costs what it costs in-process. ``isolated=False``
    translates in this process: for files from a trusted writer only.

    Raises FileFormatError if ``path`` is missing, unreadable or not STEP, or
    holds no geometry, or nests parentheses deeper than OCC's parser survives
    (see :mod:`exporters._stepscan`); ResourceLimitError if OCC's model of the
    file would exceed the memory budget; ParameterError if ``path`` is not a path (``None``, an
    empty string) or ``unit`` is unknown.
    """
    path = _fspath(path)
    _, metres = _unit(unit)
    if not os.path.isfile(path):
        raise FileFormatError(f"STEP file {path!r} does not exist or is not a file")
    for flag, value in (("strict", strict), ("surfaces", surfaces), ("isolated", isolated)):
        if not isinstance(value, bool):
            raise ParameterError(f"{flag} must be True or False, got {value!r}")
    scan_step(path)  # OCC's parser crashes the process on some inputs: refuse them first
    # and its transfer on others (entities of the wrong type, cycles): run it in a child
    named = transfer(path, "named", metres) if isolated else _read_named_shapes(path, metres)
    if surfaces:
        items = ReadResult()
        for name, shape in named:
            geometry = from_occ(shape, surfaces=True)
            for g in geometry if isinstance(geometry, list) else [geometry]:
                items.append(StepItem(name, g))
    else:
        items = items_from_shapes(named, strict=strict, path=path, kind="STEP", prepare=settle_corners)
    if not items:
        raise FileFormatError(f"the STEP file {path!r} holds no faces or edges")
    return items


def read_step_shape(path, *, isolated: bool = True):
    """The OCC shape of all roots of the STEP file ``path``, as OCC reads it (coordinates in
    millimetres), for measuring the file with OCC (:mod:`splinekit.interop.gprop`).
    ``isolated``: translate in a child process, as :func:`import_step` does.

    Raises FileFormatError if ``path`` is missing, unreadable, not STEP, holds no shapes or
    nests parentheses deeper than OCC's parser survives (see :mod:`exporters._stepscan`).
    """
    path = _fspath(path)
    IFSelect, _, _, _, STEPControl, _, _, _, _, _ = _ocp_step()
    if not os.path.isfile(path):
        raise FileFormatError(f"STEP file {path!r} does not exist or is not a file")
    scan_step(path)  # OCC's parser crashes the process on some inputs: refuse them first
    if isolated:
        return transfer(path, "shape")[0][1]
    with _occ_settings():
        reader = STEPControl.STEPControl_Reader()
        status = reader.ReadFile(path)
        if status != IFSelect.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise FileFormatError(f"{path!r} is not a readable STEP file (OpenCascade: {status.name})")
        syntax_errors(reader, f"STEP file {path!r}")
        if reader.TransferRoots() == 0:
            raise FileFormatError(f"the STEP file {path!r} holds no shapes")
    return reader.OneShape()


def _read_named_shapes(path: str, metres: float) -> list:
    """``(product name, TopoDS_Shape)`` for every part of the STEP file, assemblies walked."""
    IFSelect, _, _, STEPCAFControl, _, _, TDataStd, TDF, _, XCAFDoc = _ocp_step()
    doc = _new_document(metres)
    with _occ_settings():
        reader = STEPCAFControl.STEPCAFControl_Reader()
        reader.SetNameMode(True)
        status = reader.ReadFile(path)
        if status != IFSelect.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise FileFormatError(f"{path!r} is not a readable STEP file (OpenCascade: {status.name})")
        syntax_errors(reader.Reader(), f"STEP file {path!r}")
        if not reader.Transfer(doc):
            raise FileFormatError(f"OpenCascade could not translate the STEP file {path!r}")
    from OCP import TopLoc

    tool = XCAFDoc.XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    free = TDF.TDF_LabelSequence()
    tool.GetFreeShapes(free)
    named = []
    for i in range(1, free.Length() + 1):
        for name, shape in _named_shapes(tool, free.Value(i), None, TopLoc.TopLoc_Location(), (TDataStd, TDF)):
            if not shape.IsNull():
                named.append((name, shape))
    return named
