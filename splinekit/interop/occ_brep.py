"""OpenCascade topology <-> splinekit B-rep: TopoDS faces, shells and solids as
:class:`~splinekit.brep.TrimmedFace`, :class:`~splinekit.brep.Shell` and
:class:`~splinekit.brep.Solid`, and back.

OCC -> splinekit: :func:`brep_from_shape` (:mod:`.occ_brep_read`, through the exact NURBS
conversion of :mod:`.occ_nurbs`); splinekit -> OCC: :func:`brep_to_shape` and
:func:`brep_list_to_shape` (:mod:`.occ_brep_write`). This module gathers them with
:func:`is_brep`; OCP is imported inside the functions (through :mod:`.occ_backend`).
"""

from __future__ import annotations

from ..brep import Shell, Solid, TrimmedFace
from .occ_brep_read import brep_from_shape
from .occ_brep_write import brep_list_to_shape, brep_to_shape
from .occ_nurbs import _nurbs_converted  # noqa: F401  (tests reach it here)

__all__ = ["brep_from_shape", "brep_list_to_shape", "brep_to_shape", "is_brep"]


def is_brep(obj) -> bool:
    """Whether ``obj`` is a splinekit TrimmedFace, Shell or Solid."""
    return isinstance(obj, (TrimmedFace, Shell, Solid))
