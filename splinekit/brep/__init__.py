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

# Exact booleans and blends run in OpenCascade, which only splinekit.interop may import, and
# interop sits above brep in the layer order: resolve these names on first use instead of
# importing interop here (``splinekit.brep.fuse`` then loads splinekit.interop and OCP).
_FROM_INTEROP = {
    "fuse": "exact_booleans",
    "cut": "exact_booleans",
    "common": "exact_booleans",
    "fillet": "blends",
    "chamfer": "blends",
}


def __getattr__(name):
    module = _FROM_INTEROP.get(name)
    if module is None:
        raise AttributeError(f"module 'splinekit.brep' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f"splinekit.interop.{module}"), name)
    globals()[name] = value  # later look-ups skip __getattr__
    return value


def __dir__():
    return sorted(list(globals()) + list(_FROM_INTEROP))
