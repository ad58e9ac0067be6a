"""Point clouds: sampling, normals, curvature, outlier removal and reconstruction.

Sampling (:func:`sample_curve`, :func:`sample_surface`, :func:`sample_mesh`,
:func:`poisson_disk`), PCA normals with minimum-spanning-tree orientation
(:func:`estimate_normals`, :func:`orient_normals`), curvature estimates
(:func:`curvature`), statistical outlier removal (:func:`remove_outliers`), and
reconstruction as a B-spline height field (:func:`fit_height_field`) or an
implicit surface (:func:`reconstruct_implicit`). Exact point-to-mesh distances:
:func:`closest_points_on_mesh`. Every function takes and returns whole
``(n, 3)`` float64 arrays; neighbour searches use scipy's cKDTree, or for large
clouds the compiled cell grid of :mod:`._cellgrid_kernels` with the Morton-ordered
hierarchy of :mod:`._knn_kernels` behind it (the same answer; see :mod:`._pointtree`).
"""

from .analysis import PointCurvature, curvature, remove_outliers
from .meshdistance import MeshDistance, closest_points_on_mesh
from .normals import estimate_normals, orient_normals
from .reconstruct import fit_height_field, mls_distance, reconstruct_implicit
from .sampling import poisson_disk, sample_curve, sample_mesh, sample_surface

__all__ = [
    "MeshDistance",
    "PointCurvature",
    "closest_points_on_mesh",
    "curvature",
    "estimate_normals",
    "fit_height_field",
    "mls_distance",
    "orient_normals",
    "poisson_disk",
    "reconstruct_implicit",
    "remove_outliers",
    "sample_curve",
    "sample_mesh",
    "sample_surface",
]
