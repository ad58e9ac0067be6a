"""Polygon meshes: connectivity (Topology) and PolyMesh."""

from . import geometry, primitives
from .polymesh import PolyMesh
from .topology import Topology

__all__ = ["PolyMesh", "Topology", "geometry", "primitives"]
