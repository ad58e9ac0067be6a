"""Polygon meshes: connectivity (Topology) and PolyMesh."""

from . import components, geometry, primitives
from .polymesh import PolyMesh
from .topology import Topology

__all__ = ["PolyMesh", "Topology", "components", "geometry", "primitives"]
