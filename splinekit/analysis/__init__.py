"""Surface and curve quality analysis.

Continuity across shared edges (G0/G1/G2): ``edge_continuity(a, b)`` measures two faces or
surfaces along the edge they share; ``shell_continuity(shell)`` reports every shared edge of a
shell, solid or patch list. Curves: ``curvature_comb``, ``curve_continuity`` and ``inflections``.
Maps over a whole part: zebra stripes, isophotes, curvature and draft angle; ``deviation``
between a part and a point cloud or mesh (a scan); pictures of all of them, and of curvature combs.
"""

from .comb_pictures import render_curvature_comb
from .continuity import EdgeContinuity, NoSharedEdgeError, edge_continuity
from .curves import CurvatureComb, CurveContinuity, curvature_comb, curvature_combs, curve_continuity, inflections
from .deviation import Deviation, deviation
from .maps import CURVATURE_KINDS, DraftMap, SurfaceMap, curvature_map, draft_angle, isophotes, zebra
from .sampling import SampledPart, Sources, sample_part, sample_sources
from .shell import ShellContinuity, shell_continuity
