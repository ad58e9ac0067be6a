"""Implicit surfaces and signed distance functions.

Every implicit is an :class:`Implicit`: callable on ``(n, 3)`` points (negative
inside), with ``gradient``, ``normal``, ``hessian``, ``closest_points`` and
``to_mesh(edge_length)``; combined with ``|`` (union), ``&`` (intersection),
``-`` (difference), unary ``-`` (complement) and the smooth blends; moved with
``translate``, ``rotate`` and ``scale``.
"""

from .base import Implicit
from .csg import (
    Complement,
    Difference,
    Intersection,
    Offset,
    Shell,
    SmoothIntersection,
    SmoothUnion,
    Transformed,
    Union,
    complement,
    difference,
    intersection,
    smooth_difference,
    smooth_intersection,
    smooth_union,
    union,
)
from .frommesh import from_mesh
from .meshing import ImplicitMesh, mesh_implicit
from .primitives import box, capsule, cone, cylinder, plane, rounded_box, sphere, torus
from .sampled import SampledSDF, sample

__all__ = [
    "Complement",
    "Difference",
    "Implicit",
    "ImplicitMesh",
    "Intersection",
    "Offset",
    "SampledSDF",
    "Shell",
    "SmoothIntersection",
    "SmoothUnion",
    "Transformed",
    "Union",
    "box",
    "capsule",
    "complement",
    "cone",
    "cylinder",
    "difference",
    "from_mesh",
    "intersection",
    "mesh_implicit",
    "plane",
    "rounded_box",
    "sample",
    "smooth_difference",
    "smooth_intersection",
    "smooth_union",
    "sphere",
    "torus",
    "union",
]
