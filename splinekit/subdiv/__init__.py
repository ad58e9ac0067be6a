"""Subdivision: topology refinement with sparse stencils, and limit surfaces."""

from .refiner import SCHEMES, Refinement, subdivide, subdivision_matrix
from .surface import SubdivisionSurface

__all__ = ["SCHEMES", "Refinement", "SubdivisionSurface", "subdivide", "subdivision_matrix"]
