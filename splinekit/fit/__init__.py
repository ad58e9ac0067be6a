"""Fitting: interpolation and least-squares approximation of points by B-spline
curves and surfaces (The NURBS Book, chapter 9), and smoothed fits of scattered points."""

from .approximate import approximate_curve, approximate_surface
from .interpolate import interpolate_curve, interpolate_surface
from .parametrize import (
    approximation_knots,
    averaged_knots,
    grid_parameters,
    parametrize,
)
from .scattered import fit_surface, plane_parameters, thin_plate_energy

__all__ = [
    "approximate_curve",
    "approximate_surface",
    "approximation_knots",
    "averaged_knots",
    "fit_surface",
    "grid_parameters",
    "interpolate_curve",
    "interpolate_surface",
    "parametrize",
    "plane_parameters",
    "thin_plate_energy",
]
