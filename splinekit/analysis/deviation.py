"""Deviation of a point cloud or mesh (a scan) from a reference part: signed distances and
their statistics.

:func:`deviation` measures every point at once:

1. the reference is sampled (:func:`~splinekit.analysis.sampling.sample_sources`): exact
   geometry is tessellated, a mesh is taken as it is;
2. every point's nearest triangle and closest point on that mesh come from
   :class:`~splinekit.pointcloud.MeshDistance` (exact for the mesh; a bounding-volume
   hierarchy in compiled code for large clouds);
3. on exact geometry the closest point is then refined on the patch of that triangle:
   Newton's method of :func:`splinekit.project`, seeded with the point's parameters on the
   triangle (one seed per point, one batch per patch). The refined point is never farther
   than the seed. Near a seam the nearest triangle may belong to the wrong patch (the mesh
   is off the surfaces by up to its chordal deviation), so every other patch among the
   point's :data:`SEAM_NEIGHBOURS` nearest samples is tried as well, from its nearest sample,
   and the nearest answer kept. On a trimmed face an answer that leaves the face (its trims)
   is dropped and the point projected onto the face's trim edges (their 3-D curves,
   :func:`splinekit.project`) instead; a point with no answer left keeps the mesh's (within
   the tessellation's deviation);
4. the sign: positive on the side the reference's normals point to (outside a closed part;
   a part that faces inward is turned outward first, as for the maps), from the exact normal
   at the foot point (the mesh's face normal for a mesh). Where the
   foot point lies on an edge or corner, the offset is not along that normal; there a
   closed reference gives the sign of the angle-weighted pseudo-normal of the welded mesh
   (:meth:`~splinekit.pointcloud.MeshDistance.signed`, exact for the mesh).

Memory grows linearly with the number of points (about :data:`BYTES_PER_POINT` each, checked
against :mod:`splinekit.limits` first); a million points take seconds.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from .. import limits
from ..closest import project
from ..errors import ConvergenceError, ParameterError
from ..mesh import PolyMesh
from ..mesh.geometry import triangulate
from ..pointcloud import MeshDistance
from ..pointcloud._cloud import as_cloud
from . import deviation_pictures
from .sampling import SampledPart, freeze, sample_sources

__all__ = ["BYTES_PER_POINT", "Deviation", "deviation"]

BYTES_PER_POINT = 600
"""Peak memory per query point (the cloud, the foot points, parameters, the batch arrays)."""

SEAM_NEIGHBOURS = 8
"""Nearest samples of the reference whose patches are tried besides the nearest triangle's."""

ALONG_NORMAL = 0.5
"""Offsets whose cosine with the foot point's normal is below this lie off an edge or corner:
their sign is taken from the closed mesh's pseudo-normals."""


PERCENTILES = (50.0, 90.0, 95.0, 99.0)
"""Percentiles of ``|distance|`` in :meth:`Deviation.summary`."""


@dataclass(frozen=True, eq=False)
class Deviation:
    """Signed distances of ``n`` points from a reference part.

    Attributes
    ----------
    points : (n, 3) float64
        The measured points (a scan mesh's vertices).
    distances : (n,) float64
        Signed distances in model units: positive on the side the reference's normals point
        to (outside a closed part), negative on the other.
    closest : (n, 3) float64
        The closest points on the reference (the foot points).
    reference : SampledPart
        The sampled reference (for the pictures).
    exact : bool
        Whether the distances are to exact surfaces (else to the reference mesh).
    scan : PolyMesh or None
        The scan when it was given as a mesh.
    """

    points: np.ndarray
    distances: np.ndarray
    closest: np.ndarray
    reference: SampledPart
    exact: bool
    scan: PolyMesh | None = None

    def __post_init__(self):
        freeze(self)

    # -- statistics --------------------------------------------------------------------------
    @cached_property
    def _magnitude(self) -> np.ndarray:
        return np.abs(self.distances)

    @property
    def max(self) -> float:
        """Largest ``|distance|``."""
        return float(self._magnitude.max())

    @property
    def max_outside(self) -> float:
        """Largest signed distance (the farthest point on the normals' side; may be negative)."""
        return float(self.distances.max())

    @property
    def max_inside(self) -> float:
        """Smallest signed distance (the deepest point on the other side; may be positive)."""
        return float(self.distances.min())

    @property
    def mean(self) -> float:
        """Mean signed distance (a systematic offset of the scan)."""
        return float(self.distances.mean())

    @property
    def mean_abs(self) -> float:
        """Mean ``|distance|``."""
        return float(self._magnitude.mean())

    @property
    def rms(self) -> float:
        """Root mean square distance."""
        return float(np.sqrt(np.mean(self.distances * self.distances)))

    @property
    def std(self) -> float:
        """Standard deviation of the signed distances."""
        return float(self.distances.std())

    def percentile(self, q) -> float:
        """The ``q``-th percentile (0 to 100) of ``|distance|``."""
        q = float(q)
        if not 0 <= q <= 100:
            raise ParameterError(f"q must be a percentage in [0, 100], got {q!r}")
        return float(np.percentile(self._magnitude, q))

    def summary(self) -> dict:
        """The statistics as a dict: ``count``, ``max``, ``max_outside``, ``max_inside``,
        ``mean``, ``mean_abs``, ``rms``, ``std`` and ``p50``, ``p90``, ``p95``, ``p99`` of ``|distance|``."""
        out = {"count": len(self.distances), "max": self.max, "max_outside": self.max_outside,
               "max_inside": self.max_inside, "mean": self.mean, "mean_abs": self.mean_abs, "rms": self.rms,
               "std": self.std}
        values = np.percentile(self._magnitude, PERCENTILES)
        out.update({f"p{q:g}": float(v) for q, v in zip(PERCENTILES, values)})
        return out

    # -- pictures ----------------------------------------------------------------------------
    def render(self, path, *, size=(1000, 800), view=(28.0, -58.0), title=None) -> str:
        """Write a colour map of the deviation as a PNG to ``path`` (atomically); returns the path.

        A scan mesh is drawn coloured by its vertices' distances; a point cloud is painted onto
        the reference at its foot points (each pixel of the reference takes the colour of the
        nearest foot point, up to a few point spacings away; farther pixels stay grey)."""
        return deviation_pictures.render_deviation(self, path, size=size, view=view, title=title)

    def histogram(self, path, *, bins: int = 60, size=(900, 500), title=None) -> str:
        """Write a histogram of the signed distances as a PNG to ``path`` (atomically), with the
        mean, the RMS and the statistics; returns the path."""
        return deviation_pictures.render_histogram(self, path, bins=bins, size=size, title=title)


def _query_points(points_or_mesh):
    """``(points (n, 3), scan mesh or None)``; ControlPointError naming an empty cloud or a
    non-finite point."""
    if isinstance(points_or_mesh, PolyMesh):
        if points_or_mesh.vertices.shape[1] != 3:
            raise ParameterError(f"the scan mesh must be 3-D, got {points_or_mesh.vertices.shape[1]}-D vertices")
        return as_cloud(points_or_mesh.vertices, "the scan mesh's vertices"), points_or_mesh
    if isinstance(points_or_mesh, (str, bytes)):
        raise ParameterError("points must be an (n, 3) array or a PolyMesh (read a file with exporters.import_mesh)")
    return as_cloud(points_or_mesh, "points"), None


def deviation(reference, points_or_mesh, *, tolerance=None) -> Deviation:
    """Signed distances of a point cloud or mesh from a reference part (module notes).

    Parameters
    ----------
    reference
        A surface, a list of surfaces (a body), a B-rep face, shell or solid, a
        Catmull-Clark :class:`~splinekit.SubdivisionSurface`, or a :class:`~splinekit.PolyMesh`.
    points_or_mesh
        ``(n, 3)`` finite points, or a :class:`~splinekit.PolyMesh` whose vertices are measured.
    tolerance
        Chordal tolerance of the reference's tessellation (model units; default 1e-3 of its
        size). It only seeds the exact refinement; the distances are to the exact surfaces.

    Returns
    -------
    Deviation
        Signed distances, foot points, statistics and pictures.

    Raises
    ------
    ControlPointError
        An empty cloud, a point that is not finite, a cloud that is not ``(n, 3)``.
    ResourceLimitError
        The cloud would need more memory than the budget of :mod:`splinekit.limits`.
    """
    P, scan = _query_points(points_or_mesh)
    limits.check(len(P) * BYTES_PER_POINT, f"the deviation of {len(P):,} points")
    sources = sample_sources(reference, tolerance)
    part, mesh = sources.part, sources.mesh
    if mesh is None:  # a SampledPart given as the reference: its own triangles
        mesh = part.mesh
    corners, face_of = triangulate(mesh)
    distance = MeshDistance(mesh.vertices, corners)
    dist, foot, tri = distance.query(P)
    exact = sources.surfaces is not None
    if exact:
        dist, foot, normal = _refine(sources, P, foot, face_of[tri], corners[tri], mesh)
    else:
        normal = _face_normals(mesh, corners)[tri]
    offset = P - foot
    along = np.einsum("ij,ij->i", offset, normal)
    signs = np.where(along < 0, -1.0, 1.0)
    off_edge = np.abs(along) < ALONG_NORMAL * dist
    if off_edge.any() and mesh.is_closed:
        side, _ = distance.signed(P[off_edge])
        signs[off_edge] = np.where(side < 0, -1.0, 1.0)
    if not exact and part.flipped:  # a mesh facing inward: outside is where its normals do not point
        signs = -signs
    return Deviation(points=np.array(P), distances=signs * dist, closest=foot, reference=part, exact=exact, scan=scan)


def _face_normals(mesh, corners):
    """Unit normals ``(T, 3)`` of the fan triangles (zero for a degenerate one)."""
    V = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.cross(V[corners[:, 1]] - V[corners[:, 0]], V[corners[:, 2]] - V[corners[:, 0]])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _barycentric(p, a, b, c):
    """Barycentric coordinates ``(m, 3)`` of points ``p`` in triangles ``(a, b, c)`` (all ``(m, 3)``),
    clipped to the triangle (the closest points lie on it up to rounding)."""
    v0, v1, v2 = b - a, c - a, p - a
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((v0, v0), (v0, v1), (v1, v1)))
    d20, d21 = np.einsum("ij,ij->i", v2, v0), np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    safe = np.where(den > 0, den, 1.0)
    w1 = np.where(den > 0, (d11 * d20 - d01 * d21) / safe, 1.0 / 3.0)
    w2 = np.where(den > 0, (d00 * d21 - d01 * d20) / safe, 1.0 / 3.0)
    w = np.clip(np.column_stack([1.0 - w1 - w2, w1, w2]), 0.0, 1.0)
    return w / w.sum(axis=1, keepdims=True)


def _refine(sources, P, foot, tri_face, tri_corners, mesh):
    """Distances, foot points and oriented unit normals on the exact patches (module notes, 3.)."""
    part, surfaces = sources.part, sources.surfaces
    V = np.asarray(mesh.vertices, dtype=np.float64)
    patch = np.asarray(mesh.face_patch, dtype=np.int64)[tri_face]
    w = _barycentric(foot, V[tri_corners[:, 0]], V[tri_corners[:, 1]], V[tri_corners[:, 2]])
    corner_uv = np.asarray(mesh.corner_uv)[tri_face]  # (n, 3, 2); fan triangles of a triangle mesh are its faces
    uv = np.einsum("nk,nkj->nj", w, corner_uv)
    best = _Best(np.full(len(P), np.inf), np.array(foot), uv.copy(), patch.copy())
    # 1. Newton on the patch of the nearest triangle
    pairs = [(np.arange(len(P)), patch, uv)]
    # 2. near a seam the nearest triangle may lie on the wrong patch (the mesh is off the surfaces
    # by up to its chordal deviation): every other patch among the point's nearest samples
    _, near = cKDTree(part.points).query(P, k=min(SEAM_NEIGHBOURS, part.n_vertices), workers=-1)
    near = near.reshape(len(P), -1)
    owner = np.repeat(np.arange(len(P)), near.shape[1])
    other = part.patch[near.ravel()]
    _, first = np.unique(owner * (len(surfaces) + 1) + other, return_index=True)  # each (point, patch) once
    first = first[other[first] != patch[owner[first]]]  # seeded at its nearest sample
    pairs.append((owner[first], other[first], part.uv[near.ravel()[first]]))
    for who, which, seeds in pairs:
        ok, d, f, new_uv = _newton_pairs(sources, P, who, which, seeds)
        best.update(who[ok], d[ok], f[ok], new_uv[ok], which[ok])
        if sources.faces is not None:  # 3. a face that Newton left: the closest point on its trims
            _on_trims(sources, P, who[~ok], which[~ok], best)
    # 3. on a patch closed on itself (a sphere's or cylinder's seam) an answer stuck on the seam
    # may be the other side's: Newton again from just across the seam
    for who, which, seeds in _across_seams(surfaces, best):
        ok, d, f, new_uv = _newton_pairs(sources, P, who, which, seeds)
        best.update(who[ok], d[ok], f[ok], new_uv[ok], which[ok])
    # a point left with no answer keeps the mesh's (within the tessellation's deviation)
    lost = ~np.isfinite(best.dist)
    best.dist[lost] = np.linalg.norm(P[lost] - foot[lost], axis=1)
    best.foot[lost], best.uv[lost], best.patch[lost] = foot[lost], uv[lost], patch[lost]
    # 4. the oriented normal at every foot point
    normal = np.zeros_like(best.foot)
    for p, rows in _groups(best.patch, len(surfaces)):
        normal[rows] = part.patch_sign[p] * surfaces[p].normal(best.uv[rows, 0], best.uv[rows, 1])
    return best.dist, best.foot, normal


def _across_seams(surfaces, best, step: float = 1e-3):
    """``(who, which, seeds)`` batches: the points whose answer lies on a side of its patch's
    domain where the patch closes on itself (the surface at ``u0`` equals the surface at ``u1``,
    or the same in ``v``), seeded ``step`` of the width inside the opposite side."""
    for p, rows in _groups(best.patch, len(surfaces)):
        surface = surfaces[p]
        (u0, u1), (v0, v1) = surface.domain
        t = np.linspace(0.0, 1.0, 7)
        size = float(np.ptp(surface.control_points.reshape(-1, surface.control_points.shape[-1])[:, :3], axis=0).max())
        for k, (a, b), (c, d) in ((0, (u0, u1), (v0, v1)), (1, (v0, v1), (u0, u1))):
            x = c + (d - c) * t
            lo = surface.evaluate(np.full(7, a), x) if k == 0 else surface.evaluate(x, np.full(7, a))
            hi = surface.evaluate(np.full(7, b), x) if k == 0 else surface.evaluate(x, np.full(7, b))
            if np.abs(lo - hi).max() > 1e-9 * max(size, 1e-300):
                continue  # not closed in this direction
            uv = best.uv[rows]
            at_lo, at_hi = uv[:, k] <= a + 1e-9 * (b - a), uv[:, k] >= b - 1e-9 * (b - a)
            sel = at_lo | at_hi
            if sel.any():
                seeds = uv[sel].copy()
                seeds[:, k] = np.where(at_lo[sel], b - step * (b - a), a + step * (b - a))
                yield rows[sel], np.full(int(sel.sum()), p), seeds


@dataclass
class _Best:
    """The nearest answer so far of every point: distance, foot point, its patch and parameters."""

    dist: np.ndarray
    foot: np.ndarray
    uv: np.ndarray
    patch: np.ndarray

    def update(self, who, dist, foot, uv, patch):
        """Keep the answers ``who`` (point indices, repeats allowed) that are nearer than what they have."""
        order = np.argsort(dist)[::-1]  # a point answered twice: the nearest is written last
        who, dist, foot, uv, patch = who[order], dist[order], foot[order], uv[order], patch[order]
        nearer = dist < self.dist[who]
        who = who[nearer]
        self.dist[who], self.foot[who], self.uv[who], self.patch[who] = dist[nearer], foot[nearer], uv[nearer], patch[nearer]


def _on_trims(sources, P, who, which, best):
    """Closest points of ``P[who]`` on the trim edges (their 3-D curves) of faces ``which``."""
    for p, rows in _groups(which, len(sources.faces)):
        points = who[rows]
        for edge in sources.faces[p].edges:
            if edge.degenerate or edge.curve is None:
                continue
            try:
                result = project(edge.curve, P[points])
            except ConvergenceError:
                continue
            t = np.asarray(result.parameters)
            (t0, t1) = edge.pcurve.domain
            uv = edge.pcurve.evaluate(np.clip(t, t0, t1))
            best.update(points, np.asarray(result.distances), np.asarray(result.points), uv, np.full(len(points), p))


def _groups(patch, n_patches):
    """``(patch, rows)`` for every patch that has rows."""
    order = np.argsort(patch, kind="stable")
    bounds = np.searchsorted(patch[order], np.arange(n_patches + 1))
    for p in np.flatnonzero(np.diff(bounds)):
        yield p, order[bounds[p]:bounds[p + 1]]


def _newton_pairs(sources, P, who, which, seeds):
    """Closest points of ``P[who]`` on patches ``which`` (both ``(m,)``) from ``seeds`` ``(m, 2)``:
    ``(ok, distance, foot, uv)``, ``ok`` False where Newton failed or left the face's trims
    (``contains_uv`` outside; on a trim counts as inside)."""
    surfaces, faces = sources.surfaces, sources.faces
    m = len(who)
    ok = np.zeros(m, dtype=bool)
    dist, foot, uv = np.full(m, np.inf), np.zeros((m, 3)), np.array(seeds, dtype=np.float64)
    for p, rows in _groups(which, len(surfaces)):  # one Newton batch per patch
        surface = surfaces[p]
        (u0, u1), (v0, v1) = surface.domain
        start = np.column_stack([np.clip(uv[rows, 0], u0, u1), np.clip(uv[rows, 1], v0, v1)])
        uv[rows] = start
        try:
            result = project(surface, P[who[rows]], seeds=start)
        except ConvergenceError:  # these points keep what they have (the mesh's answer)
            continue
        new_uv = np.asarray(result.parameters)
        inside = np.ones(len(rows), dtype=bool) if faces is None else faces[p].contains_uv(new_uv) >= 0
        ok[rows] = inside
        dist[rows], foot[rows], uv[rows] = result.distances, result.points, new_uv
    return ok, dist, foot, uv
