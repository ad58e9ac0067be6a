"""Continuity of every shared edge of a shell, a solid, a subdivision surface or a list of patches.

The edges come from the B-rep topology of a :class:`~splinekit.brep.Shell` or
:class:`~splinekit.brep.Solid` (two uses of one edge, paired by key or geometry), and from the
sampled boundaries of bare patches (:func:`~splinekit.analysis.matching.candidate_pairs`: sides
whose end points coincide and of which one lies on the other). Each edge is measured by
:func:`~splinekit.analysis.continuity.measure`, vectorized over its samples (a loop over edges).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_int
from ..brep import Shell, Solid, TrimmedFace
from ..diffgeom.protocol import SubdivisionPatch
from ..errors import ParameterError
from ..subdiv import SubdivisionSurface
from ..tolerances import CONTINUITY_MATCH
from .compare import LEVELS, tolerance_value
from .edge_samples import measure_many
from .matching import candidate_pairs
from .sides import sides_of, sides_of_all
from .subdivision import subdivision_continuity

__all__ = ["ShellContinuity", "shell_continuity", "subdivision_patches"]


@dataclass(frozen=True)
class ShellContinuity:
    """Per-edge continuity of a whole part.

    ``edges``: one :class:`~splinekit.analysis.EdgeContinuity` per shared edge; ``faces``
    ``(E, 2)``: the two faces (indices into the part's faces or patches); ``max_gap``,
    ``max_angle`` (radians), ``max_curvature_jump`` ``(E,)``; ``levels`` ``(E,)`` str;
    ``free_edges``: sides used by one face only (boundary edges, not measured).
    """

    edges: tuple
    faces: np.ndarray
    max_gap: np.ndarray
    max_angle: np.ndarray
    max_curvature_jump: np.ndarray
    levels: np.ndarray
    free_edges: int

    @property
    def summary(self) -> dict:
        """``{"edges", "free_edges", "G2", "G1", "G0", "none", "worst", "max_gap", "max_angle",
        "max_curvature_jump"}``: counts per level, the worst level and the largest values."""
        out = {"edges": len(self.edges), "free_edges": self.free_edges}
        out.update({level: int((self.levels == level).sum()) for level in reversed(LEVELS)})
        worst = min((LEVELS.index(str(x)) for x in self.levels), default=len(LEVELS) - 1)
        out["worst"] = LEVELS[worst]
        for name in ("max_gap", "max_angle", "max_curvature_jump"):
            values = getattr(self, name)
            out[name] = float(values.max()) if values.size else 0.0
        return out

    def table(self) -> str:
        """The per-edge rows and the summary as text."""
        lines = [f"{'faces':>11}  {'level':>5}  {'max gap':>10}  {'max angle':>10}  {'max jump':>10}"]
        for (i, j), level, g, a, k in zip(self.faces, self.levels, self.max_gap, self.max_angle, self.max_curvature_jump):
            lines.append(f"{i:>5} {j:>5}  {level:>5}  {g:10.3g}  {a:10.3g}  {k:10.3g}")
        s = self.summary
        lines.append(f"{s['edges']} shared edges (G2 {s['G2']}, G1 {s['G1']}, G0 {s['G0']}, none {s['none']}), "
                     f"{s['free_edges']} free; worst {s['worst']}")
        return "\n".join(lines)

    def __repr__(self):
        s = self.summary
        return f"ShellContinuity({s['edges']} edges: G2 {s['G2']}, G1 {s['G1']}, G0 {s['G0']}, none {s['none']})"


def subdivision_patches(surface: SubdivisionSurface) -> list:
    """One :class:`~splinekit.SubdivisionPatch` per quad that ``surface.evaluate`` addresses (the
    control mesh's quads, or its first refinement's when it has other polygons)."""
    mesh = surface.mesh
    count = mesh.n_faces if mesh.is_quad_mesh else surface.refine(1).n_faces
    return [SubdivisionPatch(surface, f) for f in range(count)]


def _brep_pairs(shells) -> tuple[list, int]:
    """Pairs of uses ``(inner, outer)`` of the shells' shared edges, and the free-edge count."""
    pairs, free, offset = [], 0, 0
    for shell in shells:
        topology = shell.topology
        sides = [sides_of(offset + i, face) for i, face in enumerate(shell.faces)]
        starts = [np.cumsum([0] + [len(loop) for loop in face.boundary_loops()]) for face in shell.faces]
        for group in topology.edges:
            if group.degenerate:
                continue
            if len(group.uses) == 1:
                free += 1
            uses = [sides[f][starts[f][loop] + e] for f, loop, e in group.uses]
            pairs += [(uses[0], other) for other in uses[1:]]
        offset += len(shell.faces)
    return pairs, free


def shell_continuity(part, samples: int = 32, *, gap_tol=None, angle_tol=None, curvature_tol=None,
                     match_rtol=None) -> ShellContinuity:
    """Continuity along every shared edge of ``part``.

    ``part``: a :class:`~splinekit.brep.Shell` or :class:`~splinekit.brep.Solid` (edges from its
    topology), a :class:`~splinekit.SubdivisionSurface` (Catmull-Clark; one
    :class:`~splinekit.SubdivisionPatch` per quad, every edge evaluated in one batch), or a list of B-rep faces or parametric
    surfaces (sides paired by their sampled end points and shapes). ``samples`` per edge;
    tolerances as in :func:`~splinekit.analysis.edge_continuity`.
    Returns :class:`ShellContinuity` (per-edge rows and ``.summary``).
    """
    samples = as_int(samples, "samples", minimum=2)
    match_rtol = tolerance_value(match_rtol, "match_rtol", CONTINUITY_MATCH)
    if isinstance(part, SubdivisionSurface):
        edges, free = subdivision_continuity(part, samples, gap_tol, angle_tol, curvature_tol)
        return _collect(edges, free)
    if isinstance(part, (Shell, Solid)):
        pairs, free = _brep_pairs(part.shells if isinstance(part, Solid) else [part])
    else:
        try:
            items = list(part)
        except TypeError:
            raise ParameterError(f"shell_continuity takes a Shell, Solid, SubdivisionSurface or a list of faces or "
                                 f"surfaces, got {type(part).__name__}") from None
        if not items:
            raise ParameterError("shell_continuity got an empty list of faces")
        if all(isinstance(x, TrimmedFace) for x in items):
            pairs, free = _brep_pairs([Shell(items)])
        else:
            sides = sides_of_all(items)
            pairs = candidate_pairs(sides, match_rtol)
            paired = {id(s) for pair in pairs for s in pair}
            free = sum(1 for s in sides if not s.degenerate and id(s) not in paired)
    edges = tuple(measure_many(pairs, samples, gap_tol=gap_tol, angle_tol=angle_tol, curvature_tol=curvature_tol,
                               swaps=[inner.patch > outer.patch for inner, outer in pairs]))
    return _collect(edges, free)


def _collect(edges: tuple, free: int) -> ShellContinuity:
    def column(name):
        return np.array([getattr(e, name) for e in edges], dtype=np.float64)

    faces = np.array([e.patches for e in edges], dtype=np.int64).reshape(-1, 2)
    levels = np.array([e.level for e in edges], dtype="<U4")
    return ShellContinuity(edges, faces, column("max_gap"), column("max_angle"), column("max_curvature_jump"), levels, free)

