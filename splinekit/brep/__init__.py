"""Boundary representation: trimmed faces, shells and solids (numpy/scipy only).

A :class:`TrimmedFace` is a splinekit surface bounded by trimming loops in its ``(u, v)`` plane;
a :class:`Shell` is faces sharing edges; a :class:`Solid` is closed shells, outer first.
"""

from .edge import Edge
from .face import TrimmedFace
from .shell import Shell, Solid
from .mass import MassProperties
from .primitives import box, box_with_hole, cone, cylinder, plate_with_holes, sphere, torus

__all__ = [
    "Edge", "MassProperties", "Shell", "Solid", "TrimmedFace",
    "box", "box_with_hole", "cone", "cylinder", "plate_with_holes", "sphere", "torus",
]
