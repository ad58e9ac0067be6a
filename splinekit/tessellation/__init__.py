"""Adaptive, watertight tessellation: curves -> polylines, surfaces, patch sets and
Catmull-Clark limit surfaces -> triangle meshes (see :func:`tessellate`)."""

from .core import DEFAULT_ANGLE_TOLERANCE, DEFAULT_RELATIVE_TOLERANCE, tessellate
from .result import Polyline, Tessellation

__all__ = ["DEFAULT_ANGLE_TOLERANCE", "DEFAULT_RELATIVE_TOLERANCE", "Polyline", "Tessellation", "tessellate"]
