"""Surface and curve quality analysis: continuity across shared edges (G0/G1/G2), curvature
combs, continuity between consecutive curves and inflection points.

``edge_continuity(a, b)`` measures two faces or surfaces along the edge they share;
``shell_continuity(shell)`` reports every shared edge of a shell, solid or patch list;
``curvature_comb``, ``curve_continuity`` and ``inflections`` analyse curves.
"""

from .continuity import EdgeContinuity, NoSharedEdgeError, edge_continuity
from .shell import ShellContinuity, shell_continuity
from .curves import CurvatureComb, CurveContinuity, curvature_comb, curve_continuity, inflections
