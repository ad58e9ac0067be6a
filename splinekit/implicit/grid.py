"""Deprecated module path: the sampled grids now live in modules named for what they hold.

=====================  ==========================================================
:mod:`.sampled`        :class:`SampledSDF`, :func:`sample`, ``MAX_GRID_POINTS``
:mod:`.narrowband`     :class:`NarrowBandSDF`
:mod:`.frommesh`       :func:`from_mesh` (distances from
                       :class:`splinekit.pointcloud.meshdistance.MeshDistance`)
:mod:`.marching`       :func:`grid_mesh`
=====================  ==========================================================

``from splinekit.implicit.grid import ...`` keeps working for these public names; import them
from ``splinekit.implicit`` or the modules above instead.
"""

from .frommesh import from_mesh
from .marching import grid_mesh
from .narrowband import NarrowBandSDF
from .sampled import BYTES_PER_GRID_POINT, MAX_GRID_POINTS, SampledSDF, sample

__all__ = ["BYTES_PER_GRID_POINT", "MAX_GRID_POINTS", "NarrowBandSDF", "SampledSDF", "from_mesh", "grid_mesh", "sample"]
