"""Surface quality analysis: zebra stripes, isophotes, curvature and draft-angle maps over a
whole part, deviation between a part and a point cloud or mesh (a scan), and pictures of
curvature combs."""

from .comb_pictures import render_curvature_comb
from .deviation import Deviation, deviation
from .maps import CURVATURE_KINDS, DraftMap, SurfaceMap, curvature_map, draft_angle, isophotes, zebra
from .sampling import SampledPart, Sources, sample_part, sample_sources
