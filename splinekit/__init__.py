"""splinekit: vectorized Bézier, B-spline and NURBS curves and surfaces.

The math core imports only numpy and scipy; the OpenCascade bridge
(:mod:`splinekit.occ`) imports OCP lazily, inside its functions.
"""

from . import errors
from .basis import bernstein, design_matrix
from .curves import BezierCurve, BSplineCurve, NurbsCurve, SplineCurve
from .errors import SplineKitError
from .interop import occ
from .mesh import PolyMesh
from .subdiv import Refinement, SubdivisionSurface, subdivide, subdivision_matrix
from .surfaces import BezierSurface, BSplineSurface, NurbsSurface, SplineSurface
from .tolerances import Tolerances

__version__ = "0.1.0"

__all__ = [
    "bernstein",
    "design_matrix",
    "BezierCurve",
    "BSplineCurve",
    "NurbsCurve",
    "SplineCurve",
    "BezierSurface",
    "BSplineSurface",
    "NurbsSurface",
    "SplineSurface",
    "PolyMesh",
    "Refinement",
    "SubdivisionSurface",
    "subdivide",
    "subdivision_matrix",
    "SplineKitError",
    "Tolerances",
    "errors",
    "occ",
]
