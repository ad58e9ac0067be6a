"""Mesh to signed distance: :func:`from_mesh`, a closed mesh's exact signed distance on a grid.

For every sample point the exact Euclidean distance to the nearest triangle and the sign from
the angle-weighted pseudo-normal of the nearest feature (face, edge or vertex; Baerentzen &
Aanaes 2005), which is exact for a closed, consistently oriented mesh: both from
:class:`~splinekit.pointcloud.meshdistance.MeshDistance`, the one mesh distance of splinekit
(on large grids its compiled :meth:`~splinekit.pointcloud.meshdistance.MeshDistance.grid_signed`,
which scans the characteristic regions of the mesh's faces, edges and vertices).
Voxels farther than half a voxel from the surface take the majority sign of their 6-connected
component (no such component can straddle the surface), which protects them against a rounding
slip of the pseudo-normal test. On a dense grid with compiled code a pass that checks whether any
two such neighbours differ in sign comes first (:mod:`._frommesh_kernels`); where none do,
every component has one sign and the majority changes nothing, so the labelling is skipped.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels
from ..errors import NotManifoldError, ParameterError
from ..mesh.geometry import triangulate
from ..mesh.polymesh import PolyMesh
from ..pointcloud.meshdistance import MeshDistance
from ._checks import positive
from .narrowband import NarrowBandSDF
from .sampled import SampledSDF, _check_count, _grid_layout, _interp_name

__all__ = ["from_mesh"]

SIGN_KERNELS = "splinekit.implicit._frommesh_kernels"


def closed_triangles(mesh, what: str = "the mesh", needs: str = "a signed distance"):
    """``(V (n, 3), T (m, 3))`` of a closed, consistently oriented mesh (quads fan-split).

    ``what`` names the mesh and ``needs`` what it is for in the error messages: a mesh that is not
    a non-empty 3-D PolyMesh (whose vertices PolyMesh keeps finite) with no boundary edge is refused."""
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"{what} must be a PolyMesh, got {type(mesh).__name__}")
    V = np.asarray(mesh.vertices, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ParameterError(f"{what} must have 3-D vertices, got vertices of shape {V.shape}")
    if mesh.n_faces == 0:
        raise NotManifoldError(f"{what} has no faces; {needs} needs a closed mesh")
    topo = mesh.topology
    be = np.flatnonzero(topo.boundary_edges)
    if be.size:
        a, b = (int(v) for v in topo.edges[be[0]])
        raise NotManifoldError(
            f"{what} is open: edge ({a}, {b}) bounds one face only ({be.size} boundary edges in all); "
            f"{needs} needs a closed mesh"
        )
    T, _ = triangulate(topo)
    return V, np.ascontiguousarray(T, dtype=np.int64)


def from_mesh(mesh, resolution, *, band=None, padding: float = 0.1, interpolation: str = "linear"):
    """The signed distance of a closed triangle (or polygon, fan-split) mesh on a grid.

    Parameters
    ----------
    mesh : PolyMesh
        Closed, consistently oriented (faces counter-clockwise seen from
        outside), 3-D. An open mesh raises NotManifoldError naming a boundary
        edge. A mesh oriented inside out as a whole gets negated distances
        (the sign follows the faces' orientation).
    resolution : int or (3,) ints
        As in :func:`sample`, over the mesh's bounding box grown by ``padding``.
    band : float, optional
        If given (model units, at least two voxel diagonals), only samples
        with ``|d| < band`` are computed and stored: a :class:`NarrowBandSDF`.
    padding : float
        Margin added on every side, as a fraction of the longest side of the
        mesh's bounding box (>= 0); the grid also gets at least one extra voxel.
    interpolation : "linear" or "cubic"

    Returns
    -------
    SampledSDF or NarrowBandSDF
        Exact signed distances at the samples (module notes: nearest triangle
        by a BVH, per sample or by blocks of samples; sign by pseudo-normals).
    """
    pad = positive(padding, "padding", allow_zero=True)
    _interp_name(interpolation)
    V, T = closed_triangles(mesh)
    lo, hi = V.min(axis=0), V.max(axis=0)
    with np.errstate(over="ignore"):
        size = float((hi - lo).max())
    if not np.isfinite(size):
        raise ParameterError("the mesh is wider than the float range")
    if not size > 0:
        raise ParameterError("the mesh has no extent")
    with np.errstate(over="ignore"):
        lo, hi = lo - pad * size, hi + pad * size
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ParameterError(f"padding = {pad!r} takes the grid box beyond the float range")
    shape, spacing = _grid_layout(lo, hi, resolution)
    # one more voxel all round, so the outermost samples are off the surface
    lo = lo - spacing
    shape = shape + 2
    _check_count(shape)
    if band is not None:
        band = positive(band, "band")
        need = 2.0 * float(np.linalg.norm(spacing))
        if band < need:
            raise ParameterError(f"band = {band!r} must be at least two voxel diagonals ({need:.6g}) for this grid")
    dist = MeshDistance(V, T)
    limit = np.inf if band is None else band
    d = dist.grid_signed(lo, spacing, shape, limit)  # compiled, by regions or blocks of samples
    gap = 0.5 * float(spacing.max())
    if d is None:
        d, found = _signed_by_chunks(dist, lo, spacing, shape, limit)
    else:
        kern = _kernels.load(SIGN_KERNELS) if band is None else None
        if kern is not None:
            signed = np.empty_like(d)
            if kern.settle_signs(d, gap, signed) == 0:  # every far component has one sign
                return SampledSDF(signed, lo, spacing, interpolation)
        found = np.isfinite(d)
    inside = _component_signs(d, found, gap)
    d = np.where(found, np.abs(d), np.inf)
    signed = np.where(inside, -d, d)
    if band is None:
        return SampledSDF(signed, lo, spacing, interpolation)
    keep = np.flatnonzero(np.abs(signed).ravel() < band)
    return NarrowBandSDF(keep, signed.ravel()[keep], inside, tuple(shape), lo, spacing, band, interpolation)


def _signed_by_chunks(dist, lo, spacing, shape, limit):
    """``(signed distances, found)`` of shape ``shape`` by :meth:`MeshDistance.signed` on chunks
    of the grid's points (the path without compiled code)."""
    total = int(np.prod(shape))
    nx, ny, nz = (int(s) for s in shape)
    d = np.empty(total)
    found = np.empty(total, dtype=bool)
    for s in range(0, total, 1 << 20):
        flat = np.arange(s, min(s + (1 << 20), total))
        ijk = np.stack([flat // (ny * nz), (flat // nz) % ny, flat % nz], axis=1)
        d[flat], found[flat] = dist.signed(lo + ijk * spacing, limit)
    return d.reshape(nx, ny, nz), found.reshape(nx, ny, nz)


def _component_signs(d, found, gap):
    """Inside mask: samples within ``gap`` (half the largest step) of the
    surface keep their own pseudo-normal sign; the others take the majority
    sign (over samples with a known sign) of their 6-connected component of
    samples farther than ``gap``, which cannot cross the surface (a crossing
    between two neighbours puts one of them within half a step of it)."""
    from scipy import ndimage  # imported on use: it takes longer to import than the rest of implicit/

    near = found & (np.abs(d) <= gap)
    far = ~near
    labels, count = ndimage.label(far)
    flat_l = labels.ravel()
    known = (found.ravel() & far.ravel())
    neg = np.bincount(flat_l[known], weights=(d.ravel()[known] < 0).astype(float), minlength=count + 1)
    tot = np.bincount(flat_l[known], minlength=count + 1)
    comp_inside = neg * 2 > tot
    inside = np.where(near, d < 0, comp_inside[labels])
    return inside
