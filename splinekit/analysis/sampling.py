"""A whole part sampled for the analysis maps: points, unit normals and curvatures at the
vertices of a triangle mesh, one set of vertices per patch.

:func:`sample_part` takes what the maps work on -- a surface, a list of surfaces (a body),
a B-rep face, shell or solid, a Catmull-Clark :class:`~splinekit.SubdivisionSurface`, or a
:class:`~splinekit.PolyMesh` -- and returns a :class:`SampledPart`:

* exact geometry is tessellated (:func:`splinekit.tessellate`) and the tessellation's
  vertices are split along patch (face) boundaries, so that a vertex on the edge of a box
  has one copy per face, each with that face's normal: a draft or zebra map then changes
  sharply at the edge instead of blurring across it. Normals and curvatures are exact, from
  :func:`splinekit.curvature` at each vertex's patch parameters (one vectorized call per
  patch); at singular parameters (a pole, a collapsed edge) they are the limits
  :func:`splinekit.curvature` extrapolates, and the vertex is flagged in ``degenerate``;
* a plain mesh keeps its vertices, split at its sharp edges (:mod:`.mesh_normals`: a box
  gets one vertex per face at each corner, each with its face's normal), with the mesh's
  discrete curvatures (:attr:`~splinekit.PolyMesh.gaussian_curvature`,
  :attr:`~splinekit.PolyMesh.mean_curvature`); vertices whose normal vanishes are flagged.

Normals point the way the tessellation's triangles face (outward for a closed body; a part
that encloses a volume with its normals pointing in, such as the Utah teapot's patches, is
turned to face outward), and the curvatures are measured against them (:mod:`splinekit.diffgeom.curvature`'s sign
convention: ``H = -1/r`` on a sphere with outward normals).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..brep import Shell, Solid, TrimmedFace
from ..diffgeom import curvature
from ..errors import ParameterError
from ..mesh import PolyMesh
from ..mesh.geometry import triangulate
from ..subdiv.surface import SubdivisionSurface
from ..surfaces import BezierSurface, SplineSurface
from ..tessellation import tessellate
from ..tessellation.core import _subdivision_patches
from .mesh_normals import split_at_creases

__all__ = ["SampledPart", "Sources", "freeze", "sample_part", "sample_sources", "unit_direction"]

OUTWARD_FRACTION = 0.01
"""Enclosed volume, as a fraction of the bounding box, above which a part is turned to face outward."""

SUBDIVISION_LEVELS = 2
"""Uniform refinements of a Catmull-Clark cage before its faces become B-spline patches."""


def freeze(obj) -> None:
    """Make every array field of the dataclass ``obj`` read-only (results are values)."""
    for value in vars(obj).values():
        if isinstance(value, np.ndarray):
            value.setflags(write=False)


def unit_direction(direction, name: str = "direction") -> np.ndarray:
    """``direction`` as a unit ``(3,)`` float array; ParameterError naming ``name`` for
    anything that is not three finite numbers of non-zero length."""
    try:
        d = np.asarray(direction, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be three numbers (x, y, z), got {direction!r}") from None
    if d.shape != (3,):
        raise ParameterError(f"{name} must be three numbers (x, y, z), got shape {d.shape}")
    if not np.isfinite(d).all():
        raise ParameterError(f"{name} {d.tolist()} is not finite")
    big = float(np.abs(d).max())
    if not big > 0:
        raise ParameterError(f"{name} {d.tolist()} has zero length: it names no direction")
    d = d / big  # scaled first: the norm of a huge or tiny vector would overflow or underflow
    return d / np.linalg.norm(d)


@dataclass(frozen=True, eq=False)
class SampledPart:
    """Per-vertex geometry of a part (module notes).

    Attributes
    ----------
    points : (n, 3) float64
        Vertex positions (model units).
    normals : (n, 3) float64
        Unit normals.
    triangles : (T, 3) int64
        Triangles over ``points``, counter-clockwise seen from the side the normals point to.
    patch : (n,) int64
        Patch (face) index of each vertex; -1 for a plain mesh.
    uv : (n, 2) float64
        Parameters of each vertex in its patch (NaN for a plain mesh).
    gaussian, mean, k1, k2 : (n,) float64
        Gaussian (1/length^2), mean (1/length) and principal curvatures ``k1 >= k2``.
    degenerate : (n,) bool
        Vertices whose normal is a limit (a pole of a surface) or, on a plain mesh, undefined
        (then the normal is zero and the curvatures 0).
    patch_sign : (P,) float64
        Per patch, +1 where the part's normals are the patch's ``Su x Sv`` direction, -1 where
        they are its opposite (a reversed face, a body turned outward); empty for a plain mesh.
    exact : bool
        Whether normals and curvatures are those of exact surfaces (else a mesh's discrete ones).
    tolerance : float
        Chordal deviation of the triangles from the exact surfaces (0 for a plain mesh).
    flipped : bool
        Whether the part was turned to face outward (its source faced inward).
    """

    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    patch: np.ndarray
    uv: np.ndarray
    gaussian: np.ndarray
    mean: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    degenerate: np.ndarray
    patch_sign: np.ndarray
    exact: bool
    tolerance: float
    flipped: bool = False

    def __post_init__(self):
        freeze(self)

    @property
    def n_vertices(self) -> int:
        return len(self.points)

    @property
    def mesh(self) -> PolyMesh:
        """The triangles as a :class:`~splinekit.PolyMesh` (vertices split along patch boundaries)."""
        return PolyMesh(self.points, self.triangles)

    def size(self) -> float:
        """Diagonal of the bounding box of the points (model units)."""
        return float(np.linalg.norm(np.ptp(self.points, axis=0))) if len(self.points) else 0.0


def _surfaces_of(obj):
    """``(kind, items)``: ``("mesh", PolyMesh)``, ``("exact", obj to tessellate, [surface per patch])``."""
    if isinstance(obj, SampledPart):
        return "sampled", obj, None
    if isinstance(obj, PolyMesh):  # a Tessellation too: without its surfaces, a mesh
        return "mesh", obj, None
    if isinstance(obj, SubdivisionSurface):
        if obj.scheme != "catmull-clark":  # no exact patches: its limit through a fine refinement
            return "mesh", obj.refine(3), None
        return "exact", obj, None
    if isinstance(obj, (BezierSurface, SplineSurface)):
        return "exact", [obj], [obj]
    kinds = (TrimmedFace, Shell, Solid)
    if isinstance(obj, kinds):
        faces = [obj] if isinstance(obj, TrimmedFace) else list(obj.faces)
        return "exact", obj, [f.surface for f in faces]
    if isinstance(obj, (list, tuple)) and obj:
        if all(isinstance(s, (BezierSurface, SplineSurface)) for s in obj):
            return "exact", list(obj), list(obj)
        if all(isinstance(s, kinds) for s in obj):
            faces = [f for o in obj for f in ([o] if isinstance(o, TrimmedFace) else o.faces)]
            return "exact", list(obj), [f.surface for f in faces]
    raise ParameterError(
        f"cannot analyse a {type(obj).__name__}: expected a surface, a list of surfaces, a B-rep face, "
        "shell or solid, a SubdivisionSurface or a PolyMesh"
    )


def sample_part(obj, tolerance=None) -> SampledPart:
    """The :class:`SampledPart` of ``obj`` (module notes).

    ``tolerance`` is the chordal tolerance of the tessellation of exact geometry (model
    units; default :func:`splinekit.tessellate`'s, 1e-3 of the model size); it is ignored
    for a mesh. A :class:`SampledPart` is returned as it is.
    """
    return obj if isinstance(obj, SampledPart) else sample_sources(obj, tolerance).part


@dataclass(frozen=True, eq=False)
class Sources:
    """A sampled part and what it was made of: ``part`` (:class:`SampledPart`), ``mesh`` the
    welded mesh it was cut from (the :class:`~splinekit.tessellation.Tessellation` of exact
    geometry, or the mesh itself), ``surfaces`` the exact surface of each patch and ``faces``
    the trimmed face of each patch (None where there are none)."""

    part: SampledPart
    mesh: PolyMesh | None
    surfaces: list | None
    faces: list | None


def sample_sources(obj, tolerance=None) -> Sources:
    """:func:`sample_part` with the mesh, surfaces and faces behind it (:class:`Sources`); a
    :class:`Sources` is returned as it is (to sample once for several analyses)."""
    if isinstance(obj, Sources):
        return obj
    kind, item, surfaces = _surfaces_of(obj)
    if kind == "sampled":
        return Sources(item, None, None, None)
    if kind == "mesh":
        return Sources(_outward(_sample_mesh(item)), item, None, None)
    tess = tessellate(item, tolerance, levels=SUBDIVISION_LEVELS)
    if surfaces is None:  # a subdivision surface: its patches are those tessellate made
        surfaces = _subdivision_patches(item, SUBDIVISION_LEVELS)
    faces = _faces_of(item)
    return Sources(_outward(_sample_tessellation(tess, surfaces)), tess, surfaces, faces)


def _faces_of(item):
    """The trimmed faces of a face, shell, solid or list of them, in tessellation order; else None."""
    items = item if isinstance(item, list) else [item]
    if not items or not all(isinstance(o, (TrimmedFace, Shell, Solid)) for o in items):
        return None
    return [f for o in items for f in ([o] if isinstance(o, TrimmedFace) else o.faces)]


def _outward(part: SampledPart) -> SampledPart:
    """``part`` turned inside out when it encloses a volume with its normals pointing in.

    The signed volume of the triangles about the bounding-box centre is the enclosed volume
    for a closed surface and close to it for a nearly closed one (a teapot without a bottom,
    a mesh with a few holes); when it is negative and at least ``OUTWARD_FRACTION`` of the
    bounding box, the normals, the triangles' winding and the signed curvatures are reversed.
    An open sheet (a single patch) encloses nothing and keeps its orientation.
    """
    lo, hi = part.points.min(axis=0), part.points.max(axis=0)
    box = float(np.prod(hi - lo))
    corners = part.points[part.triangles] - 0.5 * (lo + hi)
    volume = float(np.einsum("tk,tk->", corners[:, 0], np.cross(corners[:, 1], corners[:, 2]))) / 6.0
    if not (box > 0 and volume < -OUTWARD_FRACTION * box):
        return part
    return replace(part, normals=-part.normals, triangles=part.triangles[:, ::-1].copy(), mean=-part.mean,
                   k1=-part.k2, k2=-part.k1, patch_sign=-part.patch_sign, flipped=not part.flipped)


def _sample_mesh(mesh: PolyMesh) -> SampledPart:
    """A plain mesh: vertices split at sharp edges (:mod:`.mesh_normals`) with the mesh's own
    discrete curvatures of the vertex each copy comes from."""
    if mesh.vertices.shape[1] != 3 or mesh.n_faces == 0:
        raise ParameterError(f"the analysis needs a 3-D mesh with faces; got {mesh.vertices.shape[1]}-D with {mesh.n_faces} faces")
    tris, _ = triangulate(mesh)
    source, normals, triangles = split_at_creases(mesh.vertices, tris)
    K = np.array(mesh.gaussian_curvature, dtype=np.float64)[source]
    H = np.array(mesh.mean_curvature, dtype=np.float64)[source]
    root = np.sqrt(np.maximum(H * H - K, 0.0))
    n = len(source)
    return SampledPart(
        points=np.array(mesh.vertices, dtype=np.float64)[source], normals=normals, triangles=triangles,
        patch=np.full(n, -1, dtype=np.int64), uv=np.full((n, 2), np.nan), gaussian=K, mean=H, k1=H + root, k2=H - root,
        degenerate=~normals.any(axis=1), patch_sign=np.zeros(0), exact=False, tolerance=0.0,
    )


def _sample_tessellation(tess, surfaces) -> SampledPart:
    """Split the tessellation's vertices along patch boundaries and evaluate each patch's
    normals and curvatures at its own vertices' parameters."""
    faces = np.asarray(tess.faces, dtype=np.int64)
    face_patch = np.asarray(tess.face_patch, dtype=np.int64)
    corner_patch = np.repeat(face_patch, 3)
    # one new vertex per (old vertex, patch) pair
    key = faces.ravel() * (len(surfaces) + 1) + corner_patch
    unique, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    triangles = inverse.reshape(-1, 3)
    patch = corner_patch[first]
    uv = np.asarray(tess.corner_uv).reshape(-1, 2)[first]
    n = len(unique)
    points = np.empty((n, 3))
    normals = np.empty((n, 3))
    K, H, k1, k2 = (np.empty(n) for _ in range(4))
    singular = np.zeros(n, dtype=bool)
    order = np.argsort(patch, kind="stable")
    bounds = np.searchsorted(patch[order], np.arange(len(surfaces) + 1))
    for p in np.flatnonzero(np.diff(bounds)):  # one vectorized evaluation per patch
        rows = order[bounds[p]:bounds[p + 1]]
        c = curvature(surfaces[p], uv[rows, 0], uv[rows, 1])
        points[rows], normals[rows], singular[rows] = c.points, c.normal, c.singular
        K[rows], H[rows], k1[rows], k2[rows] = c.gaussian, c.mean, c.k1, c.k2
    # orient each patch like its triangles (a reversed face, a body flipped to face outward)
    corners = points[triangles]
    area_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    agree = np.einsum("tk,tk->t", area_normals, normals[triangles].sum(axis=1))
    votes = np.bincount(face_patch, weights=agree, minlength=len(surfaces))
    flip = (votes < 0)[patch]
    normals[flip] *= -1.0
    H[flip] *= -1.0
    k1[flip], k2[flip] = -k2[flip], -k1[flip]
    return SampledPart(points=points, normals=normals, triangles=triangles, patch=patch, uv=uv, gaussian=K, mean=H,
                       k1=k1, k2=k2, degenerate=singular, patch_sign=np.where(votes < 0, -1.0, 1.0), exact=True,
                       tolerance=float(tess.max_deviation))
