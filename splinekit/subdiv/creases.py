"""Sharpness of edges and vertices, and the vertex rules they imply.

Semi-sharp creases follow DeRose, Kass & Truong 1998 as OpenSubdiv's Sdc
layer does:

- an edge of sharpness ``s >= 1`` is subdivided with the sharp (midpoint)
  rule, ``0 < s < 1`` blends sharp and smooth rules with weight ``s``; each
  level its child edges get ``max(s - 1, 0)`` (uniform decrement) or, with
  ``crease_method="chaikin"``, the decrement of the sharpness averaged with
  the neighbouring crease edges (:func:`chaikin_half_sharpness`);
- a vertex's rule comes from its own sharpness and the number of incident
  sharp edges: smooth (0), dart (1, smooth mask), crease (2), corner (3 or more,
  or a sharp vertex);
- where the rule changes between parent and child level (sharpness crossing
  zero), the parent-rule and child-rule positions are blended by the average
  parent sharpness of the edges (and vertex) that become smooth.

Boundary edges are infinitely sharp. With ``boundary="edge-and-corner"``
(OpenSubdiv's default) a boundary vertex with a single incident face is also
an infinitely sharp corner, so the limit surface interpolates it; with
``"edge-only"`` it follows the boundary curve.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_indices
from ..errors import MeshTopologyError, ParameterError
from ..mesh.topology import Topology

__all__ = [
    "SMOOTH",
    "DART",
    "CREASE",
    "CORNER",
    "BOUNDARY_MODES",
    "CREASE_METHODS",
    "edge_sharpness",
    "vertex_sharpness",
    "vertex_rules",
    "chaikin_half_sharpness",
]

SMOOTH, DART, CREASE, CORNER = 0, 1, 2, 3
BOUNDARY_MODES = ("edge-and-corner", "edge-only")


def edge_sharpness(topology: Topology, creases) -> np.ndarray:
    """Per-edge sharpness ``(E,)`` from ``creases``.

    ``creases`` is ``None``, a mapping ``{(v0, v1): sharpness}``, a pair
    ``(pairs (k, 2), sharpness (k,))``, or an ``(E,)`` array aligned with
    ``topology.edges``. Sharpness is >= 0; ``inf`` is infinitely sharp.
    Boundary edges are always infinitely sharp.
    """
    E = topology.n_edges
    s = np.zeros(E)
    if creases is not None:
        if isinstance(creases, dict):
            items = list(creases.items())
            keys = [k for k, _ in items]
            if any(not isinstance(k, tuple) or len(k) != 2 for k in keys):
                bad = next(k for k in keys if not isinstance(k, tuple) or len(k) != 2)
                raise ParameterError(f"crease keys must be vertex pairs (v0, v1), got {bad!r}")
            # flattened, so that numpy cannot promote a bool or round a float in a pair to an index
            flat = np.empty(2 * len(keys), dtype=object)
            flat[:] = [x for k in keys for x in k]
            pairs = as_indices(flat, "crease vertex", range_error=MeshTopologyError).reshape(-1, 2)
            values = as_float_array([v for _, v in items], "crease sharpness")
        elif isinstance(creases, tuple) and len(creases) == 2:
            pairs = as_indices(creases[0], "crease vertex", range_error=MeshTopologyError)
            if pairs.size % 2:
                raise ParameterError(f"crease edges must be a (k, 2) array of vertex indices, got shape {pairs.shape}")
            pairs = pairs.reshape(-1, 2)
            values = as_float_array(creases[1], "crease sharpness").ravel()
            if values.size == 1 and len(pairs) != 1:
                values = np.full(len(pairs), float(values[0]))
        else:
            values = as_float_array(creases, "crease sharpness")
            if values.shape != (E,):
                raise ParameterError(
                    f"creases must be a dict {{(v0, v1): sharpness}}, a pair (edges, sharpness) or an array of "
                    f"{E} per-edge values, got shape {values.shape}"
                )
            pairs = topology.edges
        if len(values) != len(pairs):
            raise ParameterError(f"{len(pairs)} crease edges but {len(values)} sharpness values")
        bad = np.flatnonzero(~(values >= 0))
        if bad.size:
            raise ParameterError(f"crease sharpness must be >= 0 (inf allowed), got {float(values[bad[0]])!r} for edge {pairs[bad[0]].tolist()}")
        idx = topology.find_edges(pairs)
        missing = np.flatnonzero(idx < 0)
        if missing.size:
            raise MeshTopologyError(f"crease edge {pairs[missing[0]].tolist()} is not an edge of the mesh")
        s[idx] = values
    s[topology.boundary_edges] = np.inf
    return s


def vertex_sharpness(topology: Topology, corners, boundary: str) -> np.ndarray:
    """Per-vertex sharpness ``(V,)`` from ``corners`` (``{vertex: sharpness}`` or ``(V,)``) and
    the boundary mode."""
    if boundary not in BOUNDARY_MODES:
        raise ParameterError(f"boundary must be one of {BOUNDARY_MODES}, got {boundary!r}")
    V = topology.n_vertices
    s = np.zeros(V)
    if corners is not None:
        if isinstance(corners, dict):
            idx = as_indices(list(corners.keys()), "corner vertex", V, range_error=MeshTopologyError)
            values = as_float_array(list(corners.values()), "corner sharpness")
        else:
            values = as_float_array(corners, "corner sharpness")
            if values.shape != (V,):
                raise ParameterError(f"corners must be a dict {{vertex: sharpness}} or {V} per-vertex values")
            idx = np.arange(V)
        if not (values >= 0).all():  # False for NaN
            raise ParameterError("corner sharpness must be >= 0 (inf allowed)")
        s[idx] = values
    if boundary == "edge-and-corner":
        corner = topology.boundary_vertices & (topology.vertex_face_count == 1)
        s[corner] = np.inf
    return s


def sharp_edge_counts(topology: Topology, sharp: np.ndarray) -> np.ndarray:
    """Number of edges with ``sharp`` True at each vertex ``(V,)``."""
    ends = topology.edges[sharp].ravel()
    return np.bincount(ends, minlength=topology.n_vertices)


def vertex_rules(topology: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> np.ndarray:
    """Rule code per vertex: SMOOTH, DART, CREASE or CORNER ``(V,)``."""
    count = sharp_edge_counts(topology, edge_s > 0)
    rule = np.minimum(count, 3)
    rule[vertex_s > 0] = CORNER
    return rule


def transition_weights(topology: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> np.ndarray:
    """Blend weight of the parent rule where the rule changes at the next level ``(V,)``.

    The average parent sharpness over the incident edges (and the vertex) whose
    sharpness drops to zero at the child level, clipped to 1.
    """
    fading = (edge_s > 0) & (edge_s <= 1)
    total = np.zeros(topology.n_vertices)
    count = np.zeros(topology.n_vertices)
    ends = topology.edges[fading]
    np.add.at(total, ends.ravel(), np.repeat(edge_s[fading], 2))
    np.add.at(count, ends.ravel(), 1.0)
    vfading = (vertex_s > 0) & (vertex_s <= 1)
    total[vfading] += vertex_s[vfading]
    count[vfading] += 1.0
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(count > 0, total / np.maximum(count, 1), 0.0)
    return np.minimum(w, 1.0)


CREASE_METHODS = ("uniform", "chaikin")


def chaikin_half_sharpness(topology: Topology, edge_s: np.ndarray) -> np.ndarray:
    """Sharpness of the two child halves of every edge under the Chaikin rule
    (OpenSubdiv's ``CREASE_CHAIKIN``): ``(2E,)``, entry ``2e + k`` for the half
    at ``edges[e, k]``.

    A semi-sharp edge ``s`` meeting other semi-sharp edges at a vertex is first
    averaged there, ``3/4 s + 1/4 (mean of the others)``, then decremented, so
    sharpness varies smoothly along a crease instead of stepping; smooth and
    infinitely sharp edges, and semi-sharp edges alone at a vertex, decrement
    as in the uniform rule.
    """
    semi = (edge_s > 0) & np.isfinite(edge_s)
    V = topology.n_vertices
    ends = topology.edges
    value = np.where(semi, edge_s, 0.0)
    total = np.bincount(ends.ravel(), weights=np.repeat(value, 2), minlength=V)
    count = np.bincount(ends.ravel(), weights=np.repeat(semi.astype(np.float64), 2), minlength=V)
    out = np.empty(2 * len(edge_s))
    for k in range(2):
        x = ends[:, k]
        others = count[x] - 1
        averaged = np.where(
            semi & (others > 0), 0.75 * edge_s + 0.25 * (total[x] - value) / np.maximum(others, 1), edge_s
        )
        out[k::2] = child_sharpness(averaged)
    return out


def child_sharpness(s: np.ndarray) -> np.ndarray:
    """Uniform decrement: ``max(s - 1, 0)`` (``inf`` stays ``inf``)."""
    return np.maximum(s - 1.0, 0.0)
