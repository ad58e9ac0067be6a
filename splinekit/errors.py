"""The exception tree of splinekit.

Every error raised on bad input derives from :class:`SplineKitError`, which is a
``ValueError`` so that code written against plain numpy/scipy habits still
catches it. Messages name the offending value or index and what was expected.
"""

from __future__ import annotations

__all__ = [
    "SplineKitError",
    "DegreeError",
    "KnotVectorError",
    "ControlPointError",
    "WeightError",
    "ParameterError",
    "DomainError",
    "KnotRemovalError",
    "MeshTopologyError",
    "BackendError",
    "MissingDependencyError",
    "ShadowedPackageError",
    "FittingError",
    "ConvergenceError",
    "NotManifoldError",
    "FileFormatError",
    "ExportError",
    "ResourceLimitError",
    "BRepError",
    "TrimError",
]


class SplineKitError(ValueError):
    """Base class of every error splinekit raises on bad input."""


class DegreeError(SplineKitError):
    """A degree is not an integer >= 1, or is inconsistent with the data."""


class KnotVectorError(SplineKitError):
    """A knot vector is malformed: wrong length, decreasing, non-finite, or a
    multiplicity above what the degree allows."""


class ControlPointError(SplineKitError):
    """Control points have the wrong shape or non-finite coordinates."""


class WeightError(SplineKitError):
    """Rational weights are non-positive, non-finite or of the wrong shape."""


class ParameterError(SplineKitError):
    """An argument other than geometry is malformed (a direction name, an
    order, a count, a matrix)."""


class DomainError(SplineKitError):
    """A parameter value lies outside the parameter domain."""


class KnotRemovalError(SplineKitError):
    """A knot cannot be removed without moving the geometry more than the
    requested tolerance (or it is not a knot at all)."""


class MeshTopologyError(SplineKitError):
    """A polygon mesh is malformed: an index out of range, a degenerate face, a
    non-manifold edge, inconsistently oriented neighbours or bad coordinates.
    The message names the face, edge or vertex."""


class BackendError(SplineKitError, RuntimeError):
    """An external kernel (OpenCascade, manifold3d) reported a failure."""


class MissingDependencyError(SplineKitError, ImportError):
    """An optional backend is not installed; the message names the package."""


class ShadowedPackageError(SplineKitError, ImportError):
    """``import models`` / ``import exporters`` found another project's package of
    that name before the one installed beside splinekit; the message names both."""


class FittingError(SplineKitError):
    """Data to interpolate or approximate cannot define the requested fit:
    coincident consecutive points, too few points for the degree, a singular
    system. The message names the offending point index."""


class ConvergenceError(SplineKitError, RuntimeError):
    """An iterative method (Newton, an ODE shooting, a knot-adding loop) did
    not reach its tolerance within its iteration budget; the message gives
    the residual reached."""


class NotManifoldError(MeshTopologyError):
    """A mesh that must bound a solid (booleans, watertight export) is not a
    closed, consistently oriented 2-manifold; the message names the first bad
    edge (its two vertex indices) or vertex."""


class FileFormatError(SplineKitError):
    """A file format is unsupported, or a file being read is malformed; the
    message names the format or the offending line/byte offset."""


class ExportError(SplineKitError, OSError):
    """A file cannot be written (unwritable folder, a writer failure); the
    target is left untouched."""


class ResourceLimitError(SplineKitError, MemoryError):
    """An operation would allocate more than the memory budget
    (:mod:`splinekit.limits`). Raised before the allocation; the message names
    the estimate, the budget and how to raise it."""


class BRepError(SplineKitError):
    """A boundary representation is invalid: an open shell passed as a solid, neighbouring faces
    oriented inconsistently, an edge used by more than two faces, a solid pointing inward. The
    message names the shell, face or edge and the problem (:meth:`splinekit.brep.Solid.check`)."""


class TrimError(BRepError):
    """A trimmed face's loops are invalid: not closed, leaving the surface's domain, crossing
    themselves or each other, turned the wrong way, or off their 3-D edge curves. The message
    names the face, the loop and the problem."""
