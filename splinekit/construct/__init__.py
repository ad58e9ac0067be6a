"""Geometric construction (The NURBS Book, chapters 7 and 8).

Exact curves (lines, polylines, circles, arcs, ellipses as rational quadratic
NURBS), curve compatibility, and surfaces built from curves: extrusion, ruled,
revolved, skinned (loft), swept, Coons and Gordon surfaces.
"""

from .compat import make_compatible
from .curves import arc, arc_through_points, circle, ellipse, line, polyline
from .patches import bicubic_coons, coons, gordon
from .surfaces import extrude, loft, revolve, ruled
from .sweep import sweep

__all__ = [
    "line",
    "polyline",
    "circle",
    "arc",
    "ellipse",
    "arc_through_points",
    "make_compatible",
    "extrude",
    "ruled",
    "revolve",
    "loft",
    "sweep",
    "coons",
    "bicubic_coons",
    "gordon",
]
