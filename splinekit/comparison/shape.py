"""The shape a comparison holds in every representation, and the exact reference it is measured
against: :class:`Shape`, :func:`as_shape`, :func:`sphere`, :func:`torus` and :class:`Reference`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import limits
from ..brep import Shell, TrimmedFace
from ..brep import primitives as brep_primitives
from ..diffgeom import curvature
from ..errors import NotManifoldError, ParameterError
from ..implicit import primitives as implicit_primitives
from ..mesh.components import genus
from ..pointcloud.meshdistance import MeshDistance
from ..subdiv import SubdivisionSurface
from ..surfaces import BezierSurface, SplineSurface
from ..tessellation import tessellate

__all__ = ["REFERENCE_TOLERANCE", "Reference", "Shape", "as_shape", "sphere", "torus"]

REFERENCE_TOLERANCE = 1e-4
"""Chordal tolerance of the reference tessellation, as a fraction of the bounding-box diagonal.
Distances from a representation's surface to the exact surface are measured to this mesh (exact
point-triangle distances), so figures below about this much of the diagonal are not resolved."""


@dataclass(frozen=True, eq=False)
class Shape:
    """One closed shape with its exact surface and, where they exist, its other exact forms.

    Attributes
    ----------
    name : str
    patches : tuple of surfaces
        Exact Bézier / B-spline / NURBS patches that close up into one body (model units).
    subdivision : SubdivisionSurface or None
        A Catmull-Clark surface whose limit is the shape (the mug's cage), when one exists.
    implicit : Implicit or None
        An exact analytic signed distance of the shape (sphere, torus), when one exists.
    volume : float or None
        The exact enclosed volume when a closed form is known (else measured by quadrature).
    """

    name: str
    patches: tuple
    subdivision: SubdivisionSurface | None = None
    implicit: object = None
    volume: float | None = None


def sphere(radius: float = 1.0) -> Shape:
    """A sphere: one exact rational patch (a revolved semicircle) and its analytic SDF (genus 0)."""
    solid = brep_primitives.sphere(radius)
    return Shape("sphere", (solid.faces[0].surface,), implicit=implicit_primitives.sphere(radius=radius),
                 volume=4.0 / 3.0 * math.pi * radius**3)


def torus(major: float = 1.0, minor: float = 0.3) -> Shape:
    """A ring torus: one exact rational patch and its analytic SDF (genus 1, like the mug)."""
    solid = brep_primitives.torus(major, minor)
    return Shape("torus", (solid.faces[0].surface,), implicit=implicit_primitives.torus(major=major, minor=minor),
                 volume=2.0 * math.pi**2 * major * minor**2)


def _is_patch(obj) -> bool:
    return isinstance(obj, (BezierSurface, SplineSurface))


def as_shape(obj, name: str | None = None) -> Shape:
    """A :class:`Shape` from a Shape, a list of exact patches, a Catmull-Clark
    :class:`~splinekit.SubdivisionSurface` (its patches through ``to_bsplines(0)``), or a built
    model (an object with ``bodies``: exactly one body of patches). ParameterError otherwise."""
    if isinstance(obj, Shape):
        return obj
    if isinstance(obj, SubdivisionSurface):
        patches, _ = obj.to_bsplines(0)
        return Shape(name or "subdivision surface", tuple(patches), subdivision=obj)
    bodies = getattr(obj, "bodies", None)
    if bodies is not None:
        if len(bodies) != 1:
            raise ParameterError(f"a model compared must have exactly one body of exact patches, "
                                 f"'{getattr(obj, 'name', '?')}' has {len(bodies)} (mesh-only and B-rep models have none)")
        return Shape(name or getattr(obj, "name", "model"), tuple(bodies[0]))
    items = list(obj) if isinstance(obj, (list, tuple)) else [obj]
    bad = [i for i, p in enumerate(items) if not _is_patch(p)]
    if not items or bad:
        what = type(items[bad[0]]).__name__ if items else "an empty list"
        raise ParameterError(f"cannot compare {what}: give a comparison.Shape, exact patches, a "
                             "Catmull-Clark SubdivisionSurface or a model with one body of patches")
    return Shape(name or "patches", tuple(items))


def _grid_samples(patches, per_patch: int, rng):
    """Exact points, unit normals, |mean curvature| and area weights at one random point in each
    cell of a ``k x k`` parameter grid of every patch (jittered: samples at cell centres would
    line up with the vertices or face centres of a mesh made on the same grid and flatter it):
    ``(n, 3)``, ``(n, 3)``, ``(n,)``, ``(n,)``, and ``(patch (n,), uv (n, 2))``."""
    i, j = np.meshgrid(np.arange(per_patch), np.arange(per_patch), indexing="ij")
    out = {"points": [], "normals": [], "mean": [], "weights": [], "patch": [], "uv": []}
    for index, p in enumerate(patches):  # one batched evaluation per patch
        (u0, u1), (v0, v1) = np.asarray(p.domain, dtype=float).reshape(2, 2)
        U = u0 + (u1 - u0) * (i.ravel() + rng.random(i.size)) / per_patch
        V = v0 + (v1 - v0) * (j.ravel() + rng.random(j.size)) / per_patch
        c = curvature(p, U, V)
        area = np.sqrt(np.maximum(c.E * c.G - c.F**2, 0.0)) * (u1 - u0) * (v1 - v0) / per_patch**2
        out["points"].append(c.points.reshape(-1, 3))
        out["normals"].append(c.normal.reshape(-1, 3))
        out["mean"].append(np.abs(c.mean).ravel())
        out["weights"].append(area.ravel())
        out["patch"].append(np.full(U.size, index))
        out["uv"].append(np.column_stack([U.ravel(), V.ravel()]))
    return {k: np.concatenate(v) for k, v in out.items()}


class Reference:
    """What every representation is measured against: exact samples and a fine tessellation.

    Attributes
    ----------
    shape : Shape
    diagonal : float
        Bounding-box diagonal of the reference mesh (model units).
    points, normals : (n, 3)
        Exact surface points on a grid of cell centres of every patch, with outward unit normals.
    mean_curvature : (n,)
        ``|H|`` (1/model unit) at ``points`` from :func:`splinekit.curvature`.
    weights : (n,)
        Surface area each point stands for (midpoint rule), summing to about the area.
    patch, uv : (n,), (n, 2)
        Patch index and parameters of every point.
    mesh : Tessellation
        The patches tessellated at :data:`REFERENCE_TOLERANCE` of the diagonal (closed).
    volume : float
        Exact volume (closed form when the shape states one, else adaptive quadrature).
    genus : float
        Genus of the reference mesh.
    flip : float
        ``-1`` when the patches' ``Su x Sv`` normals point inward, else ``1``.

    Raises NotManifoldError when the patches do not close up (the comparison measures volumes,
    inside/outside and signed distances, which need a closed shape).
    """

    def __init__(self, shape: Shape, samples: int = 2000, seed: int = 0):
        self.shape = shape
        coarse = tessellate(list(shape.patches), None, relative=False)
        if not coarse.is_closed:
            edges = int(np.count_nonzero(coarse.topology.boundary_edges))
            raise NotManifoldError(f"shape '{shape.name}' is open ({edges} boundary edges in its tessellation): "
                                   "the comparison needs a closed shape (volume, inside/outside, signed distance)")
        lo, hi = coarse.vertices.min(axis=0), coarse.vertices.max(axis=0)
        self.diagonal = float(np.linalg.norm(hi - lo))
        self.bounds = (lo, hi)
        self.tolerance = REFERENCE_TOLERANCE * self.diagonal
        self.mesh = tessellate(list(shape.patches), self.tolerance)
        self.distance = MeshDistance.of_mesh(self.mesh)
        per_patch = max(2, math.ceil(math.sqrt(samples / len(shape.patches))))
        limits.check(per_patch**2 * len(shape.patches) * 120, f"{per_patch}^2 reference samples on each of {len(shape.patches)} patches")
        s = _grid_samples(shape.patches, per_patch, np.random.default_rng(seed))
        signed = Shell([TrimmedFace(p) for p in shape.patches]).volume(1e-8)
        self.flip = -1.0 if signed < 0 else 1.0  # patches facing inward: normals flipped to point out
        self.points, self.normals, self.mean_curvature = s["points"], self.flip * s["normals"], s["mean"]
        self.weights, self.patch, self.uv = s["weights"], s["patch"], s["uv"]
        self.volume = float(shape.volume) if shape.volume is not None else abs(float(signed))
        self.genus = genus(self.mesh)

    def distance_to_exact(self, points) -> np.ndarray:
        """Unsigned distances ``(n,)`` from points to the exact surface, through the reference mesh
        (within :attr:`tolerance` of the exact distance)."""
        return self.distance.query(np.asarray(points, dtype=float))[0]
