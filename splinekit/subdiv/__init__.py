"""Subdivision: topology refinement with sparse stencils, and limit surfaces."""

from .refiner import SCHEMES, Refinement, subdivide, subdivision_matrix

__all__ = ["SCHEMES", "Refinement", "subdivide", "subdivision_matrix"]
