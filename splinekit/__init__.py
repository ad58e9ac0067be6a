"""splinekit: vectorized Bézier, B-spline and NURBS curves and surfaces.

The math core imports only numpy and scipy; the OpenCascade bridge
(:mod:`splinekit.occ`) imports OCP lazily, inside its functions, and the
booleans import manifold3d the same way.
"""

from . import _signals

_signals.install_for_command()  # the `splinekit` command handles SIGINT/SIGTERM from its first moment

from . import errors, limits
from .basis import bernstein, design_matrix
from .curves import BezierCurve, BSplineCurve, NurbsCurve, SplineCurve
from .errors import SplineKitError
from .closest import Projection, distance, project
from .construct import (
    arc,
    arc_through_points,
    bicubic_coons,
    circle,
    coons,
    ellipse,
    extrude,
    gordon,
    line,
    loft,
    make_compatible,
    polyline,
    revolve,
    ruled,
    sweep,
)
from .diffgeom import (
    ExplicitSurface,
    ImplicitSurface,
    ParametricSurface,
    SubdivisionPatch,
    curvature,
    geodesic,
    trace_geodesic,
)
from .diffgeom.curves import ParametricCurve, frenet_frame, rotation_minimizing_frames
from .diffgeom.curves import curvature as curve_curvature
from .diffgeom.curves import torsion as curve_torsion
from .fit import approximate_curve, approximate_surface, fit_surface, interpolate_curve, interpolate_surface
from .interop.booleans import difference, intersection, union, union_all
from .mesh import PolyMesh
from .subdiv import Refinement, SubdivisionSurface, subdivide, subdivision_matrix
from .surfaces import BezierSurface, BSplineSurface, NurbsSurface, SplineSurface
from .tessellation import Tessellation, tessellate
from .tolerances import Tolerances

# ``splinekit.occ`` (the OpenCascade bridge, splinekit.interop.occ under its short name) loads the
# B-rep layer with it: it is imported on first use too
_LAZY_SUBMODULES = ("implicit", "pointcloud", "levelset", "convert", "occ")


def __getattr__(name):
    """``splinekit.implicit``, ``.pointcloud``, ``.levelset``, ``.convert`` and ``.occ`` are
    imported on first use, keeping ``import splinekit`` fast."""
    if name in _LAZY_SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    # construction
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
    # fitting
    "interpolate_curve",
    "interpolate_surface",
    "approximate_curve",
    "approximate_surface",
    "fit_surface",
    # closest points
    "project",
    "distance",
    "Projection",
    # differential geometry
    "curvature",
    "geodesic",
    "trace_geodesic",
    "ParametricSurface",
    "ExplicitSurface",
    "ImplicitSurface",
    "SubdivisionPatch",
    "ParametricCurve",
    "curve_curvature",
    "curve_torsion",
    "frenet_frame",
    "rotation_minimizing_frames",
    # tessellation
    "tessellate",
    "Tessellation",
    # booleans (manifold3d)
    "union",
    "difference",
    "intersection",
    "union_all",
]
