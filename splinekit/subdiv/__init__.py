"""Subdivision: topology refinement with sparse stencils, and limit surfaces.

A :class:`Refinement` is a hierarchy of frozen :class:`Level` objects (topology, edge and vertex
sharpness, scheme, and the stencil that made each level from its parent); each scheme module
(``catmull_clark``, ``loop``, ``doo_sabin``) owns its rules and describes itself to the generic
machinery with a :class:`~splinekit.subdiv.scheme.Scheme` (see :data:`SCHEMES`).
"""

from .level import Level, RefinementStep
from .refiner import SCHEMES, Refinement, subdivide, subdivision_matrix
from .surface import SubdivisionSurface

__all__ = ["SCHEMES", "Level", "Refinement", "RefinementStep", "SubdivisionSurface", "subdivide", "subdivision_matrix"]
