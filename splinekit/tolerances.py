"""The shared named tolerances of splinekit, with their units.

There is no mutable global state: a function that needs a tolerance takes it as an argument whose
default is one of the constants below (or a figure derived from one, such as
:func:`geometric_tolerance`). Relative tolerances are multiplied by a length the caller knows (a
parameter domain, the size of a control net), so the same default means the same for a part in
metres and one in microns.

========================  =========  ==========================================================
name                      value      meaning and unit
========================  =========  ==========================================================
``PARAMETRIC_SLACK``      1e-10      relative to a domain's length: a parameter this far outside
                                     the domain is clamped onto it (``np.linspace(a, b)`` computed
                                     in floating point never fails)
``KNOT_CONFUSION``        1e-12      relative to a domain's length: two knot values closer than
                                     this are the same knot when a knot is looked up by value
``GEOMETRIC_CONFUSION``   1e-9       relative to the model's size (its largest absolute
                                     coordinate, at least 1): two points closer than this are one
                                     (knot removal, closedness checks; the default stopping
                                     distance of closest-point searches)
``ANGULAR_CONFUSION``     1e-12      radians: two directions closer than this are parallel; an
                                     arc this close to a full turn is a full circle
``INTEGRAL_RTOL``         1e-10      relative error of adaptive integrals (areas, volumes,
                                     moments) and of OCC's GProp references when the caller
                                     gives none
``ARC_LENGTH_RTOL``       1e-12      relative to a curve's length: accuracy of arc lengths and
                                     of arc-length parametrizations
``SAMPLE_COINCIDENCE``    1e-13      relative to a point set's size (its largest absolute
                                     coordinate): consecutive fit samples closer than this are
                                     one point when data are parametrized
``OCC_CONFUSION``         1e-7       model units (absolute): the tolerance of B-rep edges and
                                     faces and of the shapes handed to OpenCascade and the
                                     STEP/IGES/BREP writers (OCC's ``Precision::Confusion``)
``WELD``                  1e-8       relative to the model's bounding-box diagonal: tessellation
                                     welds vertices and matches edge end points this close
``DEVIATION_RTOL``        1e-3       relative to the bounding-box diagonal (of the model, or of
                                     a point cloud): default largest deviation of an
                                     approximation (tessellation chords, a fitted height field)
``FD_STEP``               1e-3       relative to a length (a parameter domain's, or the largest
                                     extent of an implicit's bounds): the step of numeric
                                     finite-difference derivatives
``CONTINUITY_GAP``        1e-6       relative to the model's size (largest absolute coordinate,
                                     at least 1): two faces closer than this along their shared
                                     edge meet G0 (splinekit.analysis)
``CONTINUITY_ANGLE``      1e-3       radians: normals closer than this across an edge meet G1
                                     (OpenCascade's LocalAnalysis default)
``CONTINUITY_CURVATURE``  1e-2       relative to the larger normal curvature across an edge (at
                                     least 1 / the edge's length): a smaller jump is G2
                                     (OpenCascade's LocalAnalysis default percentage)
``CONTINUITY_MATCH``      1e-3       relative to an edge's length: a side lying this close to
                                     another one is the edge they share
========================  =========  ==========================================================

``DEFAULT`` carries the first three under their older short names (``DEFAULT.param``,
``DEFAULT.knot``, ``DEFAULT.point``) for the modules that read them. The class ``Tolerances`` is
deprecated: no function ever accepted an instance; pass the number to the function instead.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

__all__ = [
    "PARAMETRIC_SLACK",
    "KNOT_CONFUSION",
    "GEOMETRIC_CONFUSION",
    "ANGULAR_CONFUSION",
    "INTEGRAL_RTOL",
    "ARC_LENGTH_RTOL",
    "SAMPLE_COINCIDENCE",
    "OCC_CONFUSION",
    "WELD",
    "DEVIATION_RTOL",
    "FD_STEP",
    "CONTINUITY_GAP",
    "CONTINUITY_ANGLE",
    "CONTINUITY_CURVATURE",
    "CONTINUITY_MATCH",
    "DEFAULT",
    "geometric_tolerance",
    "Tolerances",
]

PARAMETRIC_SLACK = 1e-10
KNOT_CONFUSION = 1e-12
GEOMETRIC_CONFUSION = 1e-9
ANGULAR_CONFUSION = 1e-12
INTEGRAL_RTOL = 1e-10
ARC_LENGTH_RTOL = 1e-12
SAMPLE_COINCIDENCE = 1e-13
OCC_CONFUSION = 1e-7
WELD = 1e-8
DEVIATION_RTOL = 1e-3
FD_STEP = 1e-3
CONTINUITY_GAP = 1e-6
CONTINUITY_ANGLE = 1e-3
CONTINUITY_CURVATURE = 1e-2
CONTINUITY_MATCH = 1e-3


@dataclass(frozen=True)
class _Defaults:
    """The defaults under their short names (see the module's table)."""

    param: float = PARAMETRIC_SLACK
    knot: float = KNOT_CONFUSION
    point: float = GEOMETRIC_CONFUSION


DEFAULT = _Defaults()


@dataclass(frozen=True)
class Tolerances(_Defaults):
    """Deprecated: no function accepts it. Its fields are the defaults ``DEFAULT.param``,
    ``DEFAULT.knot`` and ``DEFAULT.point``; give a function its tolerance as a number."""

    def __post_init__(self):
        warnings.warn(
            "splinekit.Tolerances is deprecated and no function accepts it: pass a tolerance to the "
            "function as a number; the defaults are the named constants of splinekit.tolerances",
            DeprecationWarning,
            stacklevel=3,
        )


def geometric_tolerance(tol, points) -> float:
    """``tol`` checked (finite, >= 0), or by default ``GEOMETRIC_CONFUSION`` times the size of
    the control net ``points`` (its largest absolute coordinate, at least 1), in the points' unit."""
    if tol is None:
        return GEOMETRIC_CONFUSION * max(1.0, float(np.abs(points).max()))
    try:
        tol = float(tol)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"tol must be a number, got {tol!r}") from None
    if not (math.isfinite(tol) and tol >= 0):
        raise ParameterError(f"tol must be finite and >= 0, got {tol!r}")
    return tol
