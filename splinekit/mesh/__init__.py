"""Polygon meshes: connectivity (Topology) and PolyMesh."""

from .polymesh import PolyMesh
from .topology import Topology

__all__ = ["PolyMesh", "Topology"]
