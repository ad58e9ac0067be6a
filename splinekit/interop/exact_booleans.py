"""Exact booleans of B-rep solids through OpenCascade: fuse, cut, common.

The operands are :class:`splinekit.brep.Solid` objects (or OCC shapes and
build123d / cadquery solids, which pass through unchanged). Each one is
converted with :func:`splinekit.interop.occ.to_occ`, combined by OCC's
general fuse algorithm (``BOPAlgo_PaveFiller`` then ``BOPAlgo_BOP``, the
engine behind ``BRepAlgoAPI_Fuse`` / ``Cut`` / ``Common``), and read back with
:func:`splinekit.interop.occ.from_occ`: the result's faces are trimmed faces
whose loops follow the new intersection edges.

The algorithm is driven directly rather than through ``BRepAlgoAPI_*``
because OCP 7.9 does not bind the error queries (``HasErrors``) on the API
classes and their ``DSFiller()`` accessor crashes the interpreter when its
result is released; ``BOPAlgo_*`` objects report errors themselves.

Nothing invalid is passed on: an OCC error, a result that
``BRepCheck_Analyzer`` rejects, a result that is not one solid, or a
converted Solid that fails splinekit's own ``check()`` raises a
:class:`~splinekit.errors.BackendError` naming the operation (``"exact
cut"``...) and OCC's alert, the failing sub-shapes or the problem.

Accuracy: operands converted from splinekit are B-spline faces, so the
intersection edges are OCC approximations (within the shapes' tolerance,
1e-7 by default); on a box minus a through cylinder the volume of the result
differs from the closed form by about 2e-9 relative.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_positive
from ..brep import Solid
from ..errors import BackendError, ParameterError
from .occ import _check_valid, _ocp, _sub_shapes, _unwrap, from_occ, to_occ

__all__ = ["fuse", "cut", "common", "occ_solid", "solid_from_occ"]

_OPERATIONS = {"fuse": "BOPAlgo_FUSE", "cut": "BOPAlgo_CUT", "common": "BOPAlgo_COMMON"}


# -- conversion -------------------------------------------------------------------------------
def occ_solid(obj, name: str = "the operand"):
    """The ``TopoDS_Shape`` for a splinekit Solid, or the shape inside an OCC / build123d object.

    Raises ParameterError for anything else, naming ``name``.
    """
    if isinstance(obj, Solid):
        return to_occ(obj)
    shape = _unwrap(obj) if not isinstance(obj, (list, tuple, np.ndarray)) else None
    if shape is None:
        raise ParameterError(
            f"{name} must be a splinekit.brep.Solid (or an OCC / build123d solid), got {type(obj).__name__}"
        )
    if shape.IsNull():
        raise ParameterError(f"{name} is a null (empty) OCC shape")
    return shape


def solid_from_occ(shape, what: str):
    """The splinekit Solid of an OCC solid (one ``TopoDS_Solid``), via ``from_occ``."""
    out = from_occ(shape)
    if isinstance(out, (list, tuple)) and len(out) == 1:
        out = out[0]
    if not isinstance(out, Solid):
        raise BackendError(f"the {what} did not convert to a Solid (from_occ gave {type(out).__name__})")
    # OCC called the shape valid; the converted shells are checked again by splinekit's own rules
    # (closed loops, trims inside the domain, pcurves on their 3-D edges, closed and consistently
    # oriented shells) before anyone gets them. The solid-level test that the shells point outward
    # is left out: it meshes every face (most of the time of a full check) and OCC's validity
    # check and the conversion keep orientations.
    problems = [p for shell in out.shells for p in shell.check()]
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise BackendError(
            f"the {what} gave a shape OCC calls valid, but its conversion to a splinekit Solid is not: "
            f"[{problems[0].kind}] {problems[0].message}{more}"
        )
    return out


# -- the OCC side -----------------------------------------------------------------------------
def _alerts(algo) -> str:
    """OCC's alert names for failures (and warnings) on a BOPAlgo object, e.g. ``BOPAlgo_AlertNullInputShapes``."""
    (Message,) = _ocp("Message")
    names = []
    try:
        report = algo.GetReport()
        for gravity in (Message.Message_Gravity.Message_Fail, Message.Message_Gravity.Message_Warning):
            names += [alert.GetMessageKey() for alert in report.GetAlerts(gravity)]
    except Exception:  # the report is a diagnostic only
        pass
    return ", ".join(dict.fromkeys(names)) or "no alert recorded"


def _solids(shape) -> list:
    """The distinct ``TopoDS_Solid`` sub-shapes of ``shape``."""
    return _sub_shapes(shape, "SOLID")


def boolean_shape(a, b, operation: str, *, fuzzy: float | None = None, simplify: bool = True):
    """The OCC result (a ``TopoDS_Shape``, checked valid) of ``a <operation> b``.

    ``a`` is a ``TopoDS_Shape`` solid, ``b`` one or a list of them (the tools,
    all applied in one run: ``cut(a, [b1, b2])`` is ``a - b1 - b2``); ``operation`` is ``"fuse"``,
    ``"cut"`` or ``"common"``. ``fuzzy`` (model units) is OCC's fuzzy value:
    sub-shapes closer than that are treated as touching. ``simplify`` merges
    faces that the operation split but that lie on one surface
    (``ShapeUpgrade_UnifySameDomain``), as OCC's ``SimplifyResult`` does.
    Raises BackendError naming ``exact <operation>`` on any OCC error or an
    invalid result.
    """
    BOPAlgo, TopTools = _ocp("BOPAlgo", "TopTools")
    what = f"exact {operation}"
    tools = list(b) if isinstance(b, (list, tuple)) else [b]
    args = TopTools.TopTools_ListOfShape()
    for shape in [a] + tools:
        args.Append(shape)
    filler = BOPAlgo.BOPAlgo_PaveFiller()
    filler.SetArguments(args)
    filler.SetRunParallel(False)  # the machines are shared; OCC's threads do not pay on small parts
    if fuzzy is not None:
        filler.SetFuzzyValue(float(fuzzy))
    try:
        filler.Perform()
    except Exception as exc:  # Standard_Failure and friends
        raise BackendError(f"the {what} failed while intersecting the operands: {type(exc).__name__}: {exc}") from None
    if filler.HasErrors():
        raise BackendError(f"the {what} failed while intersecting the operands: OCC reports {_alerts(filler)}")
    bop = BOPAlgo.BOPAlgo_BOP()
    bop.AddArgument(a)
    for tool in tools:
        bop.AddTool(tool)
    bop.SetOperation(getattr(BOPAlgo.BOPAlgo_Operation, _OPERATIONS[operation]))
    bop.SetRunParallel(False)
    try:
        bop.PerformWithFiller(filler)
    except Exception as exc:
        raise BackendError(f"the {what} failed: {type(exc).__name__}: {exc}") from None
    if bop.HasErrors():
        raise BackendError(f"the {what} failed: OCC reports {_alerts(bop)}")
    result = bop.Shape()
    if result is None or result.IsNull():
        raise BackendError(f"the {what} returned a null shape")
    if simplify and _solids(result):
        result = _unified(result, what)
    _check_valid(result, f"result of the {what}")
    return result


def _unified(shape, what: str):
    """``shape`` with coplanar / co-surface neighbour faces and collinear edges merged."""
    (ShapeUpgrade,) = _ocp("ShapeUpgrade")
    unify = ShapeUpgrade.ShapeUpgrade_UnifySameDomain(shape, True, True, False)
    try:
        unify.Build()
    except Exception as exc:
        raise BackendError(f"merging the faces of the {what} failed: {type(exc).__name__}: {exc}") from None
    return unify.Shape()


def _result_solids(shape, what: str, pieces: bool):
    solids = _solids(shape)
    if pieces:
        return [solid_from_occ(s, what) for s in solids]
    if not solids:
        raise BackendError(f"the {what} is empty: the result holds no solid (pieces=True returns an empty list)")
    if len(solids) > 1:
        raise BackendError(
            f"the {what} gives {len(solids)} disjoint solids; a Solid is one body: pass pieces=True for a list"
        )
    return solid_from_occ(solids[0], what)


def _exact(a, b, operation: str, fuzzy, simplify, pieces):
    if not isinstance(pieces, (bool, np.bool_)):
        raise ParameterError(f"pieces must be True or False, got {pieces!r}")
    if not isinstance(simplify, (bool, np.bool_)):
        raise ParameterError(f"simplify must be True or False, got {simplify!r}")
    if fuzzy is not None:
        fuzzy = as_positive(fuzzy, "fuzzy")
    sa = occ_solid(a, f"the first operand of the exact {operation}")
    if not _solids(sa):
        raise ParameterError(f"the first operand of the exact {operation} holds no solid")
    if isinstance(b, (list, tuple)):
        if not b:
            raise ParameterError(f"the second operand of the exact {operation} is an empty list of solids")
        sb = [occ_solid(t, f"solid {i} of the second operand of the exact {operation}") for i, t in enumerate(b)]
    else:
        sb = [occ_solid(b, f"the second operand of the exact {operation}")]
    for i, shape in enumerate(sb):
        if not _solids(shape):
            raise ParameterError(f"the second operand of the exact {operation} (solid {i}) holds no solid")
    result = boolean_shape(sa, sb, operation, fuzzy=fuzzy, simplify=bool(simplify))
    return _result_solids(result, f"exact {operation}", bool(pieces))


def fuse(a, b, *, fuzzy=None, simplify=True, pieces=False):
    """The exact union ``a ∪ b`` of two solids, as a :class:`splinekit.brep.Solid`.

    Parameters
    ----------
    a : Solid (or an OCC / build123d / cadquery solid)
        A closed, valid solid.
    b : Solid, or a list of Solids
        The other operand(s), in the same length unit; a list is applied in one
        OCC run (``fuse(a, [b1, b2])`` is ``a ∪ b1 ∪ b2``, ``cut(a, [b1, b2])``
        is ``a \\ b1 \\ b2``, ``common(a, [b1, b2])`` is ``a ∩ (b1 ∪ b2)``).
    fuzzy : float, optional
        OCC's fuzzy value (length units): faces closer than this count as touching.
    simplify : bool
        Merge faces the operation split that lie on one surface (default True).
    pieces : bool
        False (default): the result must be one solid. True: a list of Solids
        (empty when the result is empty).

    Raises
    ------
    BackendError
        OCC failed (its alert is named), the result is invalid (the failing
        sub-shapes are named), empty, or several solids without ``pieces``.
    ParameterError
        An operand is not a solid.
    """
    return _exact(a, b, "fuse", fuzzy, simplify, pieces)


def cut(a, b, *, fuzzy=None, simplify=True, pieces=False):
    """The exact difference ``a \\ b`` (``a`` minus ``b``) as a Solid; see :func:`fuse`."""
    return _exact(a, b, "cut", fuzzy, simplify, pieces)


def common(a, b, *, fuzzy=None, simplify=True, pieces=False):
    """The exact intersection ``a ∩ b`` as a Solid; see :func:`fuse`. Disjoint operands raise
    BackendError (empty result) unless ``pieces=True``, which returns ``[]``."""
    return _exact(a, b, "common", fuzzy, simplify, pieces)
