"""What a neural implicit is trained on: a closed shape turned into a signed-distance oracle, its
normalization into the unit cube, and the training samples.

Any closed splinekit shape is accepted (:func:`as_target`): a closed
:class:`~splinekit.mesh.PolyMesh`; anything :func:`splinekit.tessellate` makes watertight (a B-rep
``Solid`` or closed ``Shell``, a closed ``SubdivisionSurface``, a closed list of patches); a
built model (``models.build_model(...)``: its bodies, solids or mesh); or a bounded
:class:`~splinekit.implicit.Implicit`. Exact surfaces are tessellated at ``tolerance`` and the
exact signed distance *of that tessellation* is the target (nearest triangle by a BVH, sign by
angle-weighted pseudo-normals: :class:`~splinekit.pointcloud.MeshDistance`); an implicit that is an
exact SDF is its own target. An open shape raises NotManifoldError naming a boundary edge.

Training samples, in the normalized cube (shape box mapped into ``[-FILL, FILL]^3``), drawn once
per fit from a numpy generator seeded by the fit's seed:

* surface points uniform by area, with the surface normal there (zero level, normal alignment);
* near points: surface points moved by Gaussian noise of two widths, ``NEAR_SIGMAS`` (the band
  where the level set is decided), with their signed distances;
* space points uniform in the cube ``[-1, 1]^3`` with their signed distances (no stray surfaces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _kernels, limits
from .._validate import as_int
from ..errors import DomainError, ParameterError
from ..implicit.base import Implicit
from ..implicit.frommesh import closed_triangles
from ..mesh.components import concatenate
from ..mesh.polymesh import PolyMesh
from ..pointcloud.meshdistance import KERNELS as MESH_KERNELS
from ..pointcloud.meshdistance import MeshDistance
from ..pointcloud.sampling import sample_mesh
from ..tessellation import tessellate

_NEEDS = "a signed distance or occupancy"
"""What a training mesh must be closed for (error messages)."""

__all__ = ["FILL", "NEAR_SIGMAS", "Normalization", "SamplePool", "Target", "as_target", "draw_samples"]

FILL = 0.8
"""Half-size of the shape's largest box side in the normalized cube ``[-1, 1]^3``."""

NEAR_SIGMAS = (0.01, 0.06)
"""Standard deviations (normalized units) of the noise that makes near points from surface points."""

IMPLICIT_MESH_CELLS = 96
"""Grid cells along the longest side when an implicit is meshed to sample its surface."""


@dataclass(frozen=True)
class Normalization:
    """``x_hat = (x - center) / scale``: model units to the normalized cube (and back)."""

    center: np.ndarray
    scale: float

    @classmethod
    def of_box(cls, lo, hi) -> "Normalization":
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        size = float(np.max(hi - lo))
        if not (np.isfinite(size) and size > 0):
            raise ParameterError(f"the shape has no extent (box {lo.tolist()} .. {hi.tolist()})")
        return cls(0.5 * (lo + hi), 0.5 * size / FILL)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        return (points - self.center) / self.scale

    def to_model(self, points: np.ndarray) -> np.ndarray:
        return points * self.scale + self.center

    @property
    def bounds(self):
        """The normalized cube ``[-1, 1]^3`` in model units: ``(lo, hi)``."""
        return self.center - self.scale, self.center + self.scale


@dataclass(frozen=True)
class Target:
    """A closed shape prepared for training: a closed triangle mesh ``vertices (V, 3)``,
    ``triangles (T, 3)`` in model units, and its signed distance ``distance(points) -> (n,)``
    (model units, negative inside)."""

    vertices: np.ndarray
    triangles: np.ndarray
    distance: object
    implicit: object = None  # the implicit itself when it was one (exact surface points)

    @property
    def box(self):
        return self.vertices.min(axis=0), self.vertices.max(axis=0)


def _mesh_of(shape, tolerance):
    """A closed PolyMesh of ``shape`` (module notes) and a name for messages."""
    if isinstance(shape, PolyMesh):
        return shape, "the mesh"
    if all(hasattr(shape, a) for a in ("bodies", "solids", "mesh", "closed")):  # a built model
        name = f"model {getattr(shape, 'name', '')!r}"
        items = [list(body) for body in shape.bodies] + list(shape.solids)
        if not items:
            if shape.mesh is None:
                raise ParameterError(f"{name} has neither exact bodies nor a mesh")
            return shape.mesh, name
        return concatenate([tessellate(item, tolerance) for item in items]), name
    try:
        mesh = tessellate(shape, tolerance)
    except ParameterError as exc:
        raise ParameterError(
            f"cannot train on a {type(shape).__name__}: expected a closed PolyMesh, B-rep solid, "
            f"subdivision surface, patch list, built model or bounded implicit ({exc})"
        ) from None
    if not isinstance(mesh, PolyMesh):  # a curve gives a polyline
        raise ParameterError(f"cannot train on a {type(shape).__name__}: it bounds no solid")
    return mesh, f"the {type(shape).__name__}"


def as_target(shape, tolerance=None) -> Target:
    """The training target of a closed shape (module notes).

    ``tolerance``: chordal tolerance (model units) of the tessellation of exact surfaces (default
    that of :func:`splinekit.tessellate`, 1e-3 of the model size); for an implicit that is not an
    exact SDF, the edge length of its mesh (default its box / ``IMPLICIT_MESH_CELLS``).
    """
    if isinstance(shape, Implicit):
        if shape.bounds is None:
            raise ParameterError(f"{type(shape).__name__} is unbounded (bounds is None): nothing closed to learn")
        lo, hi = shape.bounds
        edge = float(np.max(hi - lo)) / IMPLICIT_MESH_CELLS if tolerance is None else float(tolerance)
        mesh = shape.to_mesh(edge)
        if mesh.n_faces == 0:
            raise ParameterError(f"{type(shape).__name__} has no surface (F has no zero crossing in its bounds)")
        V, T = closed_triangles(mesh, f"the mesh of {type(shape).__name__}", _NEEDS)
        oracle = shape if shape.is_exact_sdf else _signed(MeshDistance(V, T))
        return Target(V, T, oracle, shape)
    mesh, what = _mesh_of(shape, tolerance)
    V, T = closed_triangles(mesh, what, _NEEDS)
    return Target(V, T, _signed(MeshDistance(V, T)))


def _signed(md: MeshDistance):
    def distance(points):
        if len(points) >= _kernels.MIN_WORK:
            # a training pool is one large job, and numpy's search is the wrong tool for it: random
            # points inside a thin-walled body (a vase) are far from every triangle, and its
            # exhaustive fallback then gathers thousands of candidates per point (gigabytes)
            _kernels.load(MESH_KERNELS)
        return md.signed(points)[0]

    return distance


@dataclass(frozen=True)
class SamplePool:
    """Training samples of one shape in normalized units (float32).

    ``surface (ns, 3)``, ``normals (ns, 3)``, ``space (nd, 3)`` (near and uniform points) with
    their signed distances ``distance (nd,)``."""

    surface: np.ndarray
    normals: np.ndarray
    space: np.ndarray
    distance: np.ndarray

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.surface, self.normals, self.space, self.distance))


BYTES_PER_SAMPLE = 400
"""Peak memory per training sample while the pool is made (mesh sampling, distance queries)."""


def draw_samples(target: Target, norm: Normalization, n: int, seed: int) -> SamplePool:
    """``n`` surface points, ``n`` near points and ``n`` uniform points of ``target``."""
    n = as_int(n, "samples", minimum=64)
    limits.check(BYTES_PER_SAMPLE * 3 * n, f"{n:,} neural training samples per kind")
    rng = np.random.default_rng(seed)
    mesh = PolyMesh(target.vertices, target.triangles)
    surface, tri = sample_mesh(mesh, n, rng, return_faces=True)
    normals = np.asarray(mesh.face_normals)[tri]
    if target.implicit is not None:  # onto the exact zero set, with its normals
        surface = target.implicit.closest_points(surface)
        normals = target.implicit.normal(surface)
    unit = norm.to_unit(surface)
    sigmas = np.asarray(NEAR_SIGMAS)[rng.integers(0, len(NEAR_SIGMAS), n)]
    near = unit + rng.normal(size=(n, 3)) * sigmas[:, None]
    uniform = rng.uniform(-1.0, 1.0, size=(n, 3))
    space = np.concatenate([near, uniform])
    distance = np.asarray(target.distance(norm.to_model(space)), dtype=np.float64) / norm.scale
    for name, arr in (("surface point", unit), ("surface normal", normals), ("signed distance", distance)):
        bad = ~np.isfinite(arr.reshape(len(arr), -1)).all(axis=1)
        if bad.any():
            raise DomainError(f"{int(bad.sum())} training samples have a non-finite {name} (first: sample {int(np.argmax(bad))})")
    f32 = lambda a: np.ascontiguousarray(a, dtype=np.float32)  # noqa: E731
    return SamplePool(f32(unit), f32(normals), f32(space), f32(distance))
