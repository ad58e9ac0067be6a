"""Knot vectors, B-spline and Bernstein bases, and the knot algebra on coefficient arrays."""

from .bernstein import all_bernstein, bernstein, bezier_knots
from .bspline import basis_ders, basis_funs, design_matrix, find_span
from .knots import clamped_uniform, distinct, domain, is_clamped, multiplicity, validate_knots

__all__ = [
    "all_bernstein",
    "bernstein",
    "bezier_knots",
    "basis_ders",
    "basis_funs",
    "design_matrix",
    "find_span",
    "clamped_uniform",
    "distinct",
    "domain",
    "is_clamped",
    "multiplicity",
    "validate_knots",
]
