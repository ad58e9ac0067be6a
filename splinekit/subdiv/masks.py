"""Sparse building blocks shared by the schemes: crease and corner masks and the
rule blending of semi-sharp creases. Every matrix maps parent vertex data
``(V, ...)`` to child data and is assembled from index arrays at once."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.topology import Topology
from .creases import CORNER, CREASE, DART, child_sharpness, sharp_edge_counts, transition_weights, vertex_rules
from .level import Level


def csr(rows, cols, vals, shape) -> sp.csr_matrix:
    """CSR matrix from triplets (duplicates summed)."""
    return sp.csr_matrix((np.asarray(vals, dtype=np.float64), (rows, cols)), shape=shape)


def diag(values) -> sp.dia_matrix:
    return sp.diags(np.asarray(values, dtype=np.float64))


def midpoint_matrix(topology: Topology) -> sp.csr_matrix:
    """``(E, V)``: each edge's midpoint."""
    E = topology.n_edges
    e = np.arange(E)
    return csr(np.repeat(e, 2), topology.edges.ravel(), np.full(2 * E, 0.5), (E, topology.n_vertices))


def neighbor_matrix(topology: Topology, weight: np.ndarray) -> sp.csr_matrix:
    """``(V, V)``: ``weight[v]`` times each edge-neighbour of v."""
    a, b = topology.edges[:, 0], topology.edges[:, 1]
    rows = np.concatenate([a, b])
    cols = np.concatenate([b, a])
    V = topology.n_vertices
    return csr(rows, cols, weight[rows], (V, V))


def crease_matrix(topology: Topology, sharp: np.ndarray, rows_mask: np.ndarray, centre: float = 0.75) -> sp.csr_matrix:
    """``(V, V)`` crease rule ``centre v + (1 - centre) / 2 (a + b)`` along the two
    sharp edges, for the vertices in ``rows_mask`` (which must have exactly two
    sharp edges). ``centre = 3/4`` subdivides, ``2/3`` gives the limit position."""
    V = topology.n_vertices
    ends = topology.edges[sharp]
    a, b = ends[:, 0], ends[:, 1]
    rows = np.concatenate([a, b])
    cols = np.concatenate([b, a])
    keep = rows_mask[rows]
    diag_rows = np.flatnonzero(rows_mask)
    return csr(
        np.concatenate([rows[keep], diag_rows]),
        np.concatenate([cols[keep], diag_rows]),
        np.concatenate([np.full(keep.sum(), 0.5 * (1.0 - centre)), np.full(diag_rows.size, centre)]),
        (V, V),
    )


def vertex_point_matrix(level: Level, smooth: sp.spmatrix) -> sp.csr_matrix:
    """``(V, V)`` vertex-point stencils of ``level``: the scheme's ``smooth`` mask where the
    vertex is smooth or a dart, the crease mask at creases, the vertex itself at
    corners; blended between the parent and the child rule where a semi-sharp
    feature fades (see :mod:`splinekit.subdiv.creases`)."""
    topology, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
    child_e, child_v = child_sharpness(edge_s), child_sharpness(vertex_s)
    parent = vertex_rules(topology, edge_s, vertex_s)
    child = vertex_rules(topology, child_e, child_v)
    w = transition_weights(topology, edge_s, vertex_s)
    same = parent == child
    coef_parent = np.where(same, 1.0, w)
    coef_child = np.where(same, 0.0, 1.0 - w)

    def rule_matrix(rule, sharp):
        m = diag(rule <= DART) @ smooth
        m = m + crease_matrix(topology, sharp, rule == CREASE)
        return m + diag(rule == CORNER)

    out = diag(coef_parent) @ rule_matrix(parent, edge_s > 0)
    if (coef_child > 0).any():
        out = out + diag(coef_child) @ rule_matrix(child, child_e > 0)
    return sp.csr_matrix(out)


def edge_blend(edge_s: np.ndarray) -> np.ndarray:
    """Weight of the sharp (midpoint) rule per edge: 1 for ``s >= 1``, ``s`` below."""
    return np.clip(edge_s, 0.0, 1.0)


def isolated_rows(topology: Topology) -> np.ndarray:
    """Mask of vertices with no face (they are carried over unchanged)."""
    return topology.vertex_face_count == 0


__all__ = [
    "csr",
    "diag",
    "midpoint_matrix",
    "neighbor_matrix",
    "crease_matrix",
    "vertex_point_matrix",
    "edge_blend",
    "isolated_rows",
    "sharp_edge_counts",
]
