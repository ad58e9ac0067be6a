"""What a subdivision scheme is to the generic machinery, and the one dispatch of a refinement step.

Each scheme module (:mod:`~splinekit.subdiv.catmull_clark`, :mod:`~splinekit.subdiv.loop`,
:mod:`~splinekit.subdiv.doo_sabin`) owns its rules and describes itself with one :class:`Scheme`;
:class:`~splinekit.subdiv.Refinement`, the compiled kernels' driver
(:mod:`splinekit.subdiv._compiled`) and the limit masks read only these fields, so none of them
names a scheme.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .. import _kernels
from ..mesh.topology import Topology
from . import _compiled
from .level import Level, RefinementStep

__all__ = ["KERNELS", "Scheme", "refine_once"]

KERNELS = "splinekit.subdiv._kernels"
"""The compiled kernels of the Catmull-Clark and Loop rules (loaded through :mod:`splinekit._kernels`)."""


@dataclass(frozen=True)
class Scheme:
    """A subdivision scheme as the generic machinery sees it.

    Attributes
    ----------
    name : ``"catmull-clark"``, ``"loop"`` or ``"doo-sabin"``
    refine : the numpy rules: :class:`Level` -> :class:`RefinementStep`
    child_faces : faces after one step of a topology (exact)
    input_face_size : the face size the rules require (3 for Loop), or None for any polygon
    output_face_size : sides of every face after a step (Doo-Sabin: 4 as an estimate)
    splits_edges : child edges ``2e, 2e + 1`` are the halves of parent edge ``e`` (so Chaikin's
        crease rule applies)
    kernel : the rule set's id in the compiled kernels (:mod:`splinekit.subdiv._kernels`), or None
    valence_weights : the per-valence weights table ``(n_max + 1,)`` the kernels read for the smooth
        vertex rule (Loop's beta), or None
    limit_mask : ``Topology -> (V, V)`` limit positions of smooth vertices, or None (no limit masks)
    tangent_terms : ``(topology, half-edges h, vertices v, valence n, ring position j) -> (rows, cols,
        w1, w2)``: the terms of the two smooth tangent masks at ring position ``j``
    sector_matrix : ``k -> (s, s)`` subdivision map of a one-sided crease ring of ``k`` faces
        (see :mod:`splinekit.subdiv.limit`)
    """

    name: str
    refine: Callable[[Level], RefinementStep]
    child_faces: Callable[[Topology], int]
    input_face_size: int | None
    output_face_size: int
    splits_edges: bool
    kernel: int | None = None
    valence_weights: Callable[[np.ndarray], np.ndarray] | None = None
    limit_mask: Callable | None = None
    tangent_terms: Callable | None = None
    sector_matrix: Callable[[int], np.ndarray] | None = None

    def estimated_faces(self, topology: Topology, levels: int) -> int:
        """Faces after ``levels`` steps (exact for Catmull-Clark and Loop): every step after the
        first splits each face in four."""
        if levels == 0:
            return topology.n_faces
        return self.child_faces(topology) * 4 ** (levels - 1)

    def kernels(self, topology: Topology, work: int | None = None):
        """The compiled kernels when they should refine ``topology``, else None (the numpy rules).

        ``work`` is the size of the whole job in child faces (default: one step of ``topology``);
        a multi-level refinement passes its finest level's faces once and refines every level,
        the smallest included, with what this returns."""
        if self.kernel is None:
            return None
        return _kernels.load(KERNELS, work=self.child_faces(topology) if work is None else work)


def refine_once(scheme: Scheme, level: Level) -> RefinementStep:
    """One step of ``scheme`` on ``level``: the compiled kernels for large levels, the numpy rules
    otherwise (the same topologies and sharpness, stencils equal to rounding)."""
    K = scheme.kernels(level.topology)
    if K is not None:
        return _compiled.refine(K, scheme, level)
    return scheme.refine(level)
