"""splinekit: vectorized Bézier, B-spline and NURBS curves and surfaces, subdivision
surfaces and meshes, cross-checked against the OpenCascade kernel.

Every evaluator takes arrays of parameters and returns arrays: points are
``(n, dim)`` float64, grids ``(nu, nv, dim)``. Curves, surfaces and meshes are
immutable; knot insertion, refinement, degree elevation and splitting return
new objects. Bad input raises :class:`SplineKitError` (a ``ValueError``).

Example: a quarter of the unit circle as an exact NURBS curve::

    >>> import numpy as np
    >>> import splinekit as sk
    >>> c = sk.NurbsCurve(2, [0, 0, 0, 1, 1, 1], [[1, 0], [1, 1], [0, 1]], [1, np.sqrt(0.5), 1])
    >>> p = c.evaluate(np.linspace(0, 1, 5))           # (5, 2) points
    >>> bool(np.allclose(np.hypot(p[:, 0], p[:, 1]), 1.0))
    True

Where things are (``help(sk.<name>)`` for each):

* curves and surfaces: ``BezierCurve``, ``BSplineCurve``, ``NurbsCurve``,
  ``BezierSurface``, ``BSplineSurface``, ``NurbsSurface``, ``bernstein``;
* construction and fitting: ``line``, ``circle``, ``arc``, ``revolve``,
  ``loft``, ``sweep``, ``coons``, ``interpolate_curve``, ``approximate_surface``...;
* parameter sweeps of a model on Dask: ``sweep("vase", {"height": [...]})`` (the same
  ``sweep``, told apart by its first argument; ``sk.batch`` is the engine);
* measuring: ``curvature``, ``geodesic``, ``project``, ``distance``;
* meshes and subdivision: ``PolyMesh``, ``subdivide``, ``SubdivisionSurface``,
  ``tessellate``; booleans of closed bodies: ``union``, ``difference``, ``intersection``;
* B-rep: ``sk.brep`` (trimmed faces, shells, solids, their mass properties);
* subpackages loaded on first use: ``sk.implicit`` (SDFs), ``sk.pointcloud``,
  ``sk.levelset``, ``sk.convert``, ``sk.plot`` (PNG pictures); ``sk.occ`` is the
  OpenCascade bridge;
* files: ``from exporters import export_step, export_stl, export_mesh``;
  parametric models: ``from models import build_model``.

OCP, build123d, cadquery and manifold3d are imported inside the functions that
need them, so ``import splinekit`` stays fast and works without them.
"""

import importlib as _importlib

from . import _signals

_signals.install_for_command()  # the `splinekit` command handles SIGINT/SIGTERM from its first moment

from . import _siblings, errors, limits
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
)
from ._dispatch import sweep
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

_siblings.install()  # splinekit's own imports of models/exporters refuse another package of that name

# Subpackages imported on first attribute access, keeping ``import splinekit`` fast; ``splinekit.occ``
# (the OpenCascade bridge, splinekit.interop.occ under its short name) loads the B-rep layer with it
# (brep comes with the tessellation, which pairs the edges of trimmed faces with its helpers)
_LAZY_SUBMODULES = ("analysis", "batch", "brep", "comparison", "convert", "implicit", "levelset", "neural", "occ",
                    "plot", "pointcloud")
# Functions of lazily loaded subpackages, by name -> (subpackage, function). ``compare`` lives in
# the package ``comparison`` (not ``compare``: importing a subpackage sets it as an attribute of
# its parent, which would replace the function ``splinekit.compare``).
_LAZY_FUNCTIONS = {"compare": ("comparison", "compare")}


def __getattr__(name):
    """``splinekit.brep``, ``.implicit``, ``.pointcloud``, ``.levelset``, ``.convert``, ``.occ``,
    ``.plot``, ``.analysis``, ``.batch``, ``.comparison`` and ``.neural`` (optional extra: JAX) are
    imported on first use, and so is ``splinekit.compare``."""
    if name in _LAZY_SUBMODULES:
        return _importlib.import_module(f"{__name__}.{name}")
    if name in _LAZY_FUNCTIONS:
        package, function = _LAZY_FUNCTIONS[name]
        value = getattr(_importlib.import_module(f"{__name__}.{package}"), function)
        globals()[name] = value  # later look-ups skip __getattr__
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    """The module's names plus the lazily loaded subpackages and functions (for ``dir()`` and tab completion)."""
    return sorted(set(globals()) | set(_LAZY_SUBMODULES) | set(_LAZY_FUNCTIONS))


__version__ = "0.1.0"

# The public names. Not ``__all__``: pydoc writes out every name of ``__all__`` in full, which made
# help(splinekit) 2,800 lines; without it help shows the overview above and the subpackages, and
# ``from splinekit import *`` still gives every public name (those without a leading underscore).
_PUBLIC = [
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
    "limits",
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
# ``compare`` is public too, but resolved on first access (``_LAZY_FUNCTIONS``): a star import
# would have to import the comparison package to give it, so it is left out of the list above.
