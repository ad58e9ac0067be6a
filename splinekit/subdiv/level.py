"""The value types of a refinement hierarchy: one :class:`Level`, and the :class:`RefinementStep`
that one application of a scheme's rules makes from it.

A level is what every rule needs and what used to travel as four loose arguments
``(topology, edge sharpness, vertex sharpness, scheme)``: its connectivity, the sharpness of its
edges and vertices (see :mod:`splinekit.subdiv.creases`), the name of the scheme that refines it
and, for a refined level, the stencil ``S`` that made its per-vertex data from its parent's
(``data = S @ parent_data``, as in OpenSubdiv's Far layer). Levels are frozen and their
sharpness arrays read-only: a level is shared between a :class:`~splinekit.subdiv.Refinement`, its
surfaces and their caches.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology
from .creases import child_sharpness

__all__ = ["Level", "RefinementStep", "inherited_edge_sharpness"]


def _frozen(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.flags.writeable:
        a = a.view()  # a read-only view: the caller's array stays writable
        a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Level:
    """One level of a refinement hierarchy.

    Attributes
    ----------
    topology : Topology
    edge_sharpness : ``(E,)`` float, aligned with ``topology.edges`` (boundary edges ``inf``)
    vertex_sharpness : ``(V,)`` float
    scheme : the scheme's name (a key of :data:`splinekit.subdiv.SCHEMES`)
    stencil : ``(V, V_parent)`` CSR mapping the parent level's per-vertex data to this level's;
        None for an input level, or when the refinement did not keep it
    """

    topology: Topology
    edge_sharpness: np.ndarray
    vertex_sharpness: np.ndarray
    scheme: str
    stencil: sp.csr_matrix | None = None

    def __post_init__(self):
        object.__setattr__(self, "edge_sharpness", _frozen(self.edge_sharpness))
        object.__setattr__(self, "vertex_sharpness", _frozen(self.vertex_sharpness))

    @property
    def n_vertices(self) -> int:
        return self.topology.n_vertices

    def __repr__(self):
        t = self.topology
        return f"Level({self.scheme}, {t.n_vertices} vertices, {t.n_faces} faces)"


def inherited_edge_sharpness(child: Topology, pairs: np.ndarray, parent_s: np.ndarray) -> np.ndarray:
    """Child edge sharpness ``(E',)``: the decremented parent sharpness ``parent_s`` ``(k,)`` on the
    child edges with vertex pairs ``pairs`` ``(k, 2)``, ``inf`` on the child's boundary, 0 elsewhere."""
    out = np.zeros(child.n_edges)
    if len(pairs):
        out[child.find_edges(pairs)] = child_sharpness(parent_s)
    out[child.boundary_edges] = np.inf
    return out


@dataclass(frozen=True, eq=False)
class RefinementStep:
    """One refinement of a :class:`Level` by its scheme's rules.

    Attributes
    ----------
    level : the child :class:`Level` (its ``stencil`` maps the parent's data to it)
    crease_pairs : ``(k, 2)`` child vertex pairs of the child edges that inherit a parent crease
    crease_sharpness : ``(k,)`` the parent sharpness they inherit (before the decrement)

    It unpacks (and indexes) as the 5-tuple the per-scheme ``refine`` functions used to return,
    ``(topology, stencil, crease_pairs, crease_sharpness, vertex_sharpness)``, so callers of the
    former API keep working; new code reads the named fields.
    """

    level: Level
    crease_pairs: np.ndarray
    crease_sharpness: np.ndarray

    @property
    def topology(self) -> Topology:
        return self.level.topology

    @property
    def stencil(self) -> sp.csr_matrix:
        return self.level.stencil

    def _legacy(self) -> tuple:
        lv = self.level
        return lv.topology, lv.stencil, self.crease_pairs, self.crease_sharpness, lv.vertex_sharpness

    def __iter__(self):
        return iter(self._legacy())

    def __getitem__(self, index):
        return self._legacy()[index]

    def __len__(self) -> int:
        return 5

    @classmethod
    def from_creases(cls, scheme: str, child: Topology, stencil: sp.csr_matrix, pairs: np.ndarray,
                     parent_s: np.ndarray, vertex_s: np.ndarray) -> "RefinementStep":
        """The step whose child edges ``pairs`` inherit ``parent_s`` (see :func:`inherited_edge_sharpness`)."""
        level = Level(child, inherited_edge_sharpness(child, pairs, parent_s), vertex_s, scheme, stencil)
        return cls(level, pairs, parent_s)
