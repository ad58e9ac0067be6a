"""Point samples of curves, surfaces and meshes: equal arc length, uniform by area, Poisson disk."""

from __future__ import annotations

import numpy as np

from .. import limits
from .._validate import as_int, as_real
from ..diffgeom.curves import equal_arc_length_parameters
from ..errors import ParameterError
from ..mesh.geometry import triangulate
from ..mesh.polymesh import PolyMesh
from ._cloud import as_cloud, as_rng, kd_tree

__all__ = ["poisson_disk", "sample_curve", "sample_mesh", "sample_surface"]

AREA_GRID = 96
"""Cells per direction of the parameter grid on which a surface's area density is tabulated."""

MAX_SAMPLES = 50_000_000
"""Largest sample count accepted (bounds memory: about 1.2 GB of float64 points)."""


BYTES_PER_SAMPLE = 256
"""Peak memory per sample point charged to the memory budget (:mod:`splinekit.limits`):
measured 170 bytes for :func:`sample_mesh` and 240 for :func:`sample_surface`."""

BYTES_PER_NEIGHBOUR = 96
"""Peak memory per neighbour pair of :func:`poisson_disk`'s neighbour graph (the kd-tree's
pair list, its symmetric copy, sort and round masks): measured 82-87 bytes with tracemalloc
on uniform clouds of 5,000-200,000 points."""


def _count(n, name: str = "n", minimum: int = 1) -> int:
    n = as_int(n, name, minimum=minimum)
    if n > MAX_SAMPLES:
        raise ParameterError(f"{name} = {n} exceeds the largest sample count {MAX_SAMPLES}")
    limits.check(n * BYTES_PER_SAMPLE, f"{n:,} sample points")
    return n


def sample_curve(curve, n: int) -> np.ndarray:
    """``n >= 2`` points ``(n, dim)`` equally spaced in arc length along ``curve``, both ends included.

    ``curve`` is any splinekit curve (or object with ``evaluate``,
    ``derivatives`` and ``domain``); spacing is exact to the arc-length table's
    tolerance (``1e-12`` relative).
    """
    if not all(hasattr(curve, a) for a in ("evaluate", "derivatives", "domain")):
        raise ParameterError(f"curve must be a parametric curve (evaluate, derivatives, domain), got {type(curve).__name__}")
    n = _count(n, minimum=2)
    return np.asarray(curve.evaluate(equal_arc_length_parameters(curve, n)), dtype=np.float64)


def _patches(surface):
    items = list(surface) if isinstance(surface, (list, tuple)) else [surface]
    if not items:
        raise ParameterError("surface is an empty list of patches")
    for i, s in enumerate(items):
        if not (hasattr(s, "derivatives") and hasattr(s, "evaluate")):
            raise ParameterError(f"patch {i} is a {type(s).__name__}, not a parametric surface")
        cp = getattr(s, "control_points", None)
        if cp is not None and np.shape(cp)[-1] != 3:
            raise ParameterError(f"patch {i} is {np.shape(cp)[-1]}-D; area sampling needs 3-D surfaces")
    return items


def _domain(s):
    dom = getattr(s, "domain", None)
    if dom is None:
        dom = (s.domain_u, s.domain_v)
    (u0, u1), (v0, v1) = dom
    return float(u0), float(u1), float(v0), float(v1)


def _area_density(s, u, v) -> np.ndarray:
    d = np.asarray(s.derivatives(u, v, 1), dtype=np.float64)
    return np.linalg.norm(np.cross(d[1, 0], d[0, 1]), axis=-1)


def sample_surface(surface, n: int, rng=None, *, return_parameters: bool = False):
    """``n`` random points ``(n, 3)`` distributed uniformly by area on a surface or patch set.

    The area density ``|Su x Sv|`` is tabulated at the centres of a
    ``96 x 96`` grid of parameter cells per patch; a cell is drawn with
    probability proportional to its (midpoint-rule) area, then a point uniform
    in the cell's parameter rectangle. The density therefore follows the true
    one up to its variation within a cell (second order in the cell size).

    Parameters
    ----------
    surface : parametric surface or list of them
        Anything with ``evaluate(u, v)``, ``derivatives(u, v, 1)`` and
        ``domain`` (splinekit Bézier, B-spline and NURBS surfaces); a list is a
        patch set sampled by total area.
    n : int
    rng : None, int or numpy Generator
    return_parameters : bool
        Also return ``(patch (n,), uv (n, 2))``.
    """
    patches = _patches(surface)
    n = _count(n)
    rng = as_rng(rng)
    g = AREA_GRID
    weights, boxes = [], []
    t = (np.arange(g) + 0.5) / g
    for s in patches:
        u0, u1, v0, v1 = _domain(s)
        U, V = np.meshgrid(u0 + (u1 - u0) * t, v0 + (v1 - v0) * t, indexing="ij")
        dens = _area_density(s, U.ravel(), V.ravel())
        weights.append(dens * (u1 - u0) * (v1 - v0) / g**2)
        boxes.append((u0, u1, v0, v1))
    w = np.concatenate(weights)
    if not (np.isfinite(w).all() and w.sum() > 0):
        raise ParameterError("the surface has zero (or non-finite) area: nothing to sample")
    cdf = np.cumsum(w)
    cell = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right"), len(w) - 1)
    patch, local = np.divmod(cell, g * g)
    iu, iv = np.divmod(local, g)
    box = np.asarray(boxes)[patch]
    u = box[:, 0] + (box[:, 1] - box[:, 0]) * (iu + rng.random(n)) / g
    v = box[:, 2] + (box[:, 3] - box[:, 2]) * (iv + rng.random(n)) / g
    u = np.minimum(u, box[:, 1])
    v = np.minimum(v, box[:, 3])
    points = np.empty((n, 3))
    for p, s in enumerate(patches):  # one batched evaluation per patch
        sel = np.flatnonzero(patch == p)
        if sel.size:
            points[sel] = s.evaluate(u[sel], v[sel])
    if return_parameters:
        return points, patch, np.column_stack([u, v])
    return points


def _triangles(mesh):
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"mesh must be a splinekit PolyMesh, got {type(mesh).__name__}")
    V = np.asarray(mesh.vertices, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ParameterError(f"the mesh must be 3-D, got vertices of shape {V.shape}")
    tris, tri_face = triangulate(mesh)
    return V, tris, tri_face


def sample_mesh(mesh, n: int, rng=None, *, return_faces: bool = False):
    """``n`` random points ``(n, 3)`` uniform by area on a polygon mesh.

    Faces are fan-triangulated; a triangle is drawn with probability
    proportional to its area and a point uniform in it (barycentric
    ``(1 - sqrt(r1), sqrt(r1) (1 - r2), sqrt(r1) r2)``). With
    ``return_faces`` also the index ``(n,)`` of the original face of each point.
    """
    V, tris, tri_face = _triangles(mesh)
    n = _count(n)
    rng = as_rng(rng)
    A = V[tris]
    area = 0.5 * np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1)
    if not area.sum() > 0:
        raise ParameterError("the mesh has zero area: nothing to sample")
    cdf = np.cumsum(area)
    t = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right"), len(area) - 1)
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    a, b, c = 1.0 - r1, r1 * (1.0 - r2), r1 * r2
    P = A[t]
    points = a[:, None] * P[:, 0] + b[:, None] * P[:, 1] + c[:, None] * P[:, 2]
    return (points, tri_face[t]) if return_faces else points


def poisson_disk(source, radius: float, rng=None, *, oversampling: float = 8.0) -> np.ndarray:
    """A subset ``(m, dim)`` of points no two of which are closer than ``radius``, and maximal.

    Parameters
    ----------
    source : (n, dim) points or a PolyMesh
        A mesh is first sampled uniformly by area with about
        ``oversampling * area / (pi (radius / 2)^2)`` points.
    radius : float
        Minimum distance between kept points (model units), > 0.
    rng : None, int or numpy Generator

    The kept set is the greedy one in a random order (a point is kept when no
    point kept before it lies within ``radius``), computed without a loop per
    point: in rounds, every undecided point whose random rank is smallest among
    its undecided neighbours within ``radius`` is kept and its neighbours
    dropped (Luby's rounds; they reproduce the sequential greedy result). Every
    dropped point lies within ``radius`` of a kept one, so the result covers
    the source to within ``radius``.
    """
    r = as_real(radius, "radius")
    if not r > 0:
        raise ParameterError(f"radius must be > 0, got {r!r}")
    rng = as_rng(rng)
    if hasattr(source, "vertices") and hasattr(source, "face_indices"):
        over = as_real(oversampling, "oversampling")
        if not over >= 1:
            raise ParameterError(f"oversampling must be >= 1, got {over!r}")
        V, tris, _ = _triangles(source)
        A = V[tris]
        area = 0.5 * np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1).sum()
        with np.errstate(over="ignore", divide="ignore"):  # a tiny radius: refused below, not cast
            count = float(np.ceil(over * area / (np.pi * np.float64(0.5 * r) ** 2)))
        if not count <= MAX_SAMPLES:
            raise ParameterError(
                f"radius = {r!r} needs about {count:.3g} samples of the mesh, more than {MAX_SAMPLES}; use a larger radius"
            )
        # about 4 x oversampling neighbours within the radius per sample (density x pi r^2)
        limits.check(count * (BYTES_PER_SAMPLE + 4.0 * over * BYTES_PER_NEIGHBOUR),
                     f"Poisson-disk sampling at radius {r!r} ({count:,.0f} samples)")
        P = sample_mesh(source, max(int(count), 1), rng)
    else:
        P = as_cloud(source, "source", dim=None)
        limits.check(len(P) * BYTES_PER_SAMPLE, f"Poisson-disk sampling of {len(P):,} points")
    keep = _greedy_independent(P, r, rng)
    return P[keep]


def _greedy_independent(P: np.ndarray, r: float, rng) -> np.ndarray:
    """Indices of the greedy maximal set of points pairwise ``>= r`` apart, in a random order."""
    n = len(P)
    tree = kd_tree(P)
    # the neighbour count first: a dual-tree count that allocates nothing per pair, so a cloud
    # whose points crowd within the radius is refused before its pair list exists
    n_pairs = (float(tree.count_neighbors(tree, r)) - n) / 2.0  # without self pairs, each pair once
    limits.check(n_pairs * BYTES_PER_NEIGHBOUR, f"Poisson-disk sampling at radius {r!r} ({n_pairs:,.0f} neighbour pairs)")
    pairs = tree.query_pairs(r, output_type="ndarray")
    if len(pairs) == 0:
        return np.arange(n)
    a = np.concatenate([pairs[:, 0], pairs[:, 1]])
    b = np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.argsort(a, kind="stable")
    a, b = a[order], b[order]
    rank = rng.permutation(n)
    state = np.zeros(n, dtype=np.int8)  # 0 undecided, 1 kept, -1 dropped
    while True:
        live = (state[a] == 0) & (state[b] == 0)
        if not live.any():
            break
        a, b = a[live], b[live]
        best = np.full(n, n, dtype=np.int64)
        np.minimum.at(best, a, rank[b])
        kept = (state == 0) & (rank < best)
        state[kept] = 1
        hit = b[kept[a]]
        state[hit[state[hit] == 0]] = -1
    state[state == 0] = 1
    return np.flatnonzero(state == 1)
