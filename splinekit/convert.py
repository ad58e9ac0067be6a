"""Conversions between surface representations, each with its loss measured.

Every function returns a :class:`Conversion`: the converted object, the
``error`` it introduced (a distance in model units, measured after the fact by
sampling and closest points, never a bound taken on trust from the converter),
the ``method`` used, and a sentence ``measured`` saying what ``error`` is.

Distances are measured with exact closest points where they are available:
:func:`splinekit.project` (Newton point inversion) for parametric surfaces,
Newton steps along the gradient (``splinekit.project``) for implicits, and exact
point-triangle distances (:class:`splinekit.pointcloud.MeshDistance`) for
meshes. A two-sided ("Hausdorff") error is the larger of the two one-sided
maxima, each over a finite random sample, so it can miss a narrow worst spot:
it is a sampled lower bound of the true Hausdorff distance that comes close
to it for the sample sizes used (thousands of points, plus every triangle
centre where the chordal error peaks).

========================  =========================================  =======================================
function                  result                                     error
========================  =========================================  =======================================
nurbs_to_mesh             Tessellation (splinekit.tessellate)        two-sided surface <-> mesh
mesh_to_sdf               sampled SDF grid (implicit.from_mesh)      two-sided mesh <-> zero set of the grid
sdf_to_mesh               mesh of the zero set (Implicit.to_mesh)    two-sided zero set <-> mesh
mesh_to_points            (n, 3) samples uniform by area             covering radius: mesh -> nearest sample
points_to_surface         BSplineSurface (fit_height_field)          max point -> surface distance
points_to_mesh            mesh of an MLS implicit reconstruction     two-sided cloud <-> mesh
explicit_to_bspline       BSplineSurface interpolating z = f(x, y)   max vertical gap on a 4x finer grid
explicit_to_implicit      ImplicitSurface F = f(x, y) - z            max |F| on graph points (0: exact)
========================  =========================================  =======================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import as_degree, as_float_array, as_int, as_real
from .closest import project
from .diffgeom import ExplicitSurface
from .errors import ParameterError
from .fit import interpolate_surface
from .implicit.frommesh import from_mesh
from .mesh.geometry import triangulate
from .pointcloud._cloud import as_cloud, as_rng, kd_tree
from .pointcloud.meshdistance import MeshDistance
from .pointcloud.reconstruct import fit_height_field, reconstruct_implicit
from .pointcloud.sampling import sample_mesh, sample_surface
from .tessellation import tessellate

__all__ = [
    "Conversion",
    "explicit_to_bspline",
    "explicit_to_implicit",
    "mesh_to_points",
    "mesh_to_sdf",
    "nurbs_to_mesh",
    "points_to_mesh",
    "points_to_surface",
    "sdf_to_mesh",
]

DEFAULT_SAMPLES = 4000
"""Random sample points per direction of a two-sided error measurement."""


@dataclass(frozen=True, eq=False)
class Conversion:
    """The result of a conversion and its measured loss.

    Attributes
    ----------
    result
        The converted object.
    error : float
        Measured distance between the input and the result (model units); what
        exactly is said in ``measured`` and in each function's notes.
    method : str
        Short name of the algorithm used.
    measured : str
        One sentence: what ``error`` measures and on how many samples.
    """

    result: object
    error: float
    method: str
    measured: str

    def __iter__(self):  # ``result, error = conversion``
        return iter((self.result, self.error))


def _samples(value) -> int:
    return as_int(value, "samples", minimum=1)


def _rng(rng):
    return as_rng(rng)


def _mesh_distance(mesh):
    return MeshDistance.of_mesh(mesh)


def _mesh_points(mesh, n, rng, *, centres: bool = True):
    """Random points on ``mesh`` (by area), with every triangle centre when ``centres``
    (where a flat triangle is farthest from a curved surface), at most ``n`` of them."""
    pts, faces = sample_mesh(mesh, n, rng, return_faces=True)
    if not centres:
        return pts, faces
    tris, tri_face = triangulate(mesh)
    pick = np.arange(len(tris)) if len(tris) <= n else rng.choice(len(tris), n, replace=False)
    c = np.asarray(mesh.vertices)[tris[pick]].mean(axis=1)
    return np.vstack([pts, c]), np.concatenate([faces, tri_face[pick]])


def _patch_list(surface):
    items = list(surface) if isinstance(surface, (list, tuple)) else [surface]
    if not items:
        raise ParameterError("surface is an empty list of patches")
    return items


def nurbs_to_mesh(surface, tolerance=None, *, samples: int = DEFAULT_SAMPLES, rng=0) -> Conversion:
    """Tessellate a B-spline/NURBS/Bézier surface or patch set and measure the chordal loss.

    Parameters
    ----------
    surface : parametric surface or list of them (a body)
    tolerance : float, optional
        Chordal tolerance passed to :func:`splinekit.tessellate` (model units).
    samples : int
        Random points drawn on each side (plus up to as many triangle centres).
    rng : None, int or numpy Generator

    Returns
    -------
    Conversion
        ``result`` a :class:`~splinekit.tessellation.Tessellation`; ``error`` the
        two-sided distance: the max over points of the mesh (random and triangle
        centres) of the distance to the patch the triangle came from
        (:func:`splinekit.project`), and the max over random points of the
        surface (uniform by area) of the exact distance to the mesh.
    """
    patches = _patch_list(surface)
    n = _samples(samples)
    rng = _rng(rng)
    mesh = tessellate(patches if len(patches) > 1 else patches[0], tolerance)
    pts, faces = _mesh_points(mesh, n, rng)
    owner = np.asarray(mesh.face_patch)[faces]
    to_surface = 0.0
    for i, s in enumerate(patches):  # one batched projection per patch
        sel = owner == i
        if sel.any():
            to_surface = max(to_surface, float(project(s, pts[sel]).distances.max()))
    on_surface = sample_surface(patches, n, rng)
    to_mesh = float(_mesh_distance(mesh).query(on_surface)[0].max())
    return Conversion(
        mesh,
        max(to_surface, to_mesh),
        "tessellate",
        f"two-sided max distance: {len(pts)} mesh points to their patch, {n} surface points to the mesh",
    )


def _implicit_vs_mesh(implicit, mesh, n, rng, spread):
    """Two-sided max distance between the zero set of ``implicit`` and ``mesh``.

    Mesh points are projected onto ``F = 0`` (:func:`splinekit.project`: the
    distance to the zero-set point reached); zero-set points are mesh points
    moved randomly by up to ``spread`` and projected onto ``F = 0``, then
    measured exactly against the mesh.
    """
    pts, _ = _mesh_points(mesh, n, rng)
    to_zero = float(project(implicit, pts).distances.max())
    jitter = pts[:n] + rng.uniform(-spread, spread, (min(n, len(pts)), 3))
    zero = project(implicit, jitter).points
    to_mesh = float(_mesh_distance(mesh).query(zero)[0].max())
    return max(to_zero, to_mesh), len(pts), len(zero)


def mesh_to_sdf(mesh, resolution, *, samples: int = DEFAULT_SAMPLES, rng=0) -> Conversion:
    """Sample the signed distance of a closed mesh on a grid (:func:`splinekit.implicit.from_mesh`).

    Returns
    -------
    Conversion
        ``result`` the sampled SDF (an implicit); ``error`` the two-sided max
        distance between the mesh and the zero set of the interpolated grid
        (see :func:`sdf_to_mesh` for how it is measured).
    """
    n = _samples(samples)
    rng = _rng(rng)
    sdf = from_mesh(mesh, resolution)
    spread = 2.0 * float(np.max(sdf.spacing))
    error, a, b = _implicit_vs_mesh(sdf, mesh, n, rng, spread)
    return Conversion(
        sdf,
        error,
        "sampled signed distance grid",
        f"two-sided max distance: {a} mesh points projected onto the grid's zero set, "
        f"{b} zero-set points to the mesh",
    )


def sdf_to_mesh(implicit, edge_length, *, bounds=None, samples: int = DEFAULT_SAMPLES, rng=0) -> Conversion:
    """Mesh the zero set of an implicit (``implicit.to_mesh(edge_length)``) and measure the loss.

    Returns
    -------
    Conversion
        ``result`` a closed triangle mesh; ``error`` the two-sided max distance:
        mesh points (random and triangle centres) to the zero set they reach by
        Newton steps along the gradient (:func:`splinekit.project`; the true
        distance for an exact SDF, an upper bound otherwise), and zero-set
        points (mesh points jittered by up to one edge length and projected onto
        ``F = 0``) to the mesh, exactly.
    """
    h = as_real(edge_length, "edge_length")
    if not h > 0:
        raise ParameterError(f"edge_length must be > 0, got {h!r}")
    n = _samples(samples)
    rng = _rng(rng)
    if not (callable(implicit) and hasattr(implicit, "to_mesh")):
        raise ParameterError(f"implicit must be an Implicit with to_mesh, got {type(implicit).__name__}")
    mesh = implicit.to_mesh(h) if bounds is None else implicit.to_mesh(h, bounds)
    if mesh.n_faces == 0:
        raise ParameterError("the implicit's zero set is empty inside its bounds: nothing to mesh")
    error, a, b = _implicit_vs_mesh(implicit, mesh, n, rng, h)
    return Conversion(
        mesh,
        error,
        "grid sampling + marching tetrahedra",
        f"two-sided max distance: {a} mesh points projected onto F = 0, {b} zero-set points to the mesh",
    )


def mesh_to_points(mesh, n: int, *, rng=0, check_samples=None) -> Conversion:
    """``n`` points uniform by area on a mesh, with the covering radius as the loss.

    Returns
    -------
    Conversion
        ``result`` ``(n, 3)`` points (each exactly on the mesh); ``error`` the
        covering radius: the max over a dense random sample of the mesh
        (``check_samples``, default ``10 n`` capped at 2 million, plus every
        vertex) of the distance to the nearest returned point -- how far the
        cloud leaves parts of the surface unrepresented.
    """
    n = as_int(n, "n", minimum=1)
    rng = _rng(rng)
    pts = sample_mesh(mesh, n, rng)
    m = min(10 * n, 2_000_000) if check_samples is None else _samples(check_samples)
    dense = np.vstack([sample_mesh(mesh, m, rng), np.asarray(mesh.vertices)])
    cover = float(kd_tree(pts).query(dense, workers=-1)[0].max())
    return Conversion(
        pts,
        cover,
        "uniform by area",
        f"covering radius: max distance from {len(dense)} mesh points to the nearest of the {n} samples",
    )


def points_to_surface(points, tolerance=None, **options) -> Conversion:
    """Fit a B-spline surface to a height-field-like cloud (:func:`splinekit.pointcloud.fit_height_field`).

    ``options`` go to ``fit_height_field`` (``n_control``, ``degree``,
    ``smoothing``, ``max_control``).

    Returns
    -------
    Conversion
        ``result`` a BSplineSurface; ``error`` the max over the input points of
        the exact distance to the surface (:func:`splinekit.project`).
    """
    P = as_cloud(points, min_count=3)
    surface = fit_height_field(P, tolerance, **options)
    error = float(project(surface, P).distances.max())
    return Conversion(
        surface,
        error,
        "height-field least squares",
        f"max distance from the {len(P)} input points to the surface",
    )


def points_to_mesh(points, normals=None, edge_length=None, *, k: int = 16, samples: int = DEFAULT_SAMPLES, rng=0) -> Conversion:
    """Reconstruct a closed mesh from a cloud: an MLS implicit (:func:`~splinekit.pointcloud.reconstruct_implicit`) meshed by level set.

    Parameters
    ----------
    points : (n, 3) samples of a closed surface
    normals : (n, 3), optional
        Outward normals; default estimated and oriented.
    edge_length : float, optional
        Meshing grid spacing; default twice the median nearest-neighbour
        spacing of the cloud.
    k : int
        Neighbours of the MLS blend.

    Returns
    -------
    Conversion
        ``result`` the mesh; ``error`` the two-sided max distance between the
        cloud and the mesh: every input point to the mesh (exact), and random
        mesh points to the nearest input point (which includes the cloud's own
        sampling gaps).
    """
    P = as_cloud(points, min_count=3)
    rng = _rng(rng)
    n = _samples(samples)
    implicit = reconstruct_implicit(P, normals, k=k)
    tree = kd_tree(P)
    if edge_length is None:
        h = 2.0 * float(np.median(tree.query(P, k=2, workers=-1)[0][:, 1]))
        if not h > 0:
            raise ParameterError("the cloud's points coincide: pass edge_length")
    else:
        h = as_real(edge_length, "edge_length")
        if not h > 0:
            raise ParameterError(f"edge_length must be > 0, got {h!r}")
    mesh = implicit.to_mesh(h)
    if mesh.n_faces == 0:
        raise ParameterError("the reconstruction's zero set is empty: check the normals' orientation")
    to_mesh = float(_mesh_distance(mesh).query(P)[0].max())
    pts, _ = _mesh_points(mesh, n, rng)
    to_cloud = float(tree.query(pts, workers=-1)[0].max())
    return Conversion(
        mesh,
        max(to_mesh, to_cloud),
        "implicit moving least squares + level set",
        f"two-sided max distance: {len(P)} input points to the mesh, {len(pts)} mesh points to the nearest input point",
    )


def _explicit_domain(domain):
    d = as_float_array(domain, "domain")
    with np.errstate(over="ignore"):  # a width beyond the float range is refused
        ok = d.shape == (2, 2) and np.isfinite(d).all() and (d[:, 1] > d[:, 0]).all() and np.isfinite(d[:, 1] - d[:, 0]).all()
    if not ok:
        raise ParameterError(f"domain must be ((x0, x1), (y0, y1)) with finite x0 < x1 and y0 < y1 (and finite widths), got {domain!r}")
    return d


def _heights(f, X, Y):
    if not callable(f):
        raise ParameterError(f"f must be callable as f(x, y) on arrays, got {type(f).__name__}")
    Z = as_float_array(f(X, Y), "f(x, y)")
    if Z.shape != X.shape:
        try:
            Z = np.broadcast_to(Z, X.shape).copy()
        except ValueError:
            raise ParameterError(f"f(x, y) returned shape {Z.shape} for inputs of shape {X.shape}") from None
    bad = ~np.isfinite(Z)
    if bad.any():
        i = np.argwhere(bad)[0]
        raise ParameterError(f"f({X[tuple(i)]!r}, {Y[tuple(i)]!r}) = {Z[tuple(i)]!r} is not finite")
    return Z


def explicit_to_bspline(f, domain, n=32, *, degree: int = 3, check: int = 4) -> Conversion:
    """Interpolate the graph ``z = f(x, y)`` on an ``n x n`` grid by a B-spline surface.

    Parameters
    ----------
    f : callable
        ``f(x, y)`` on arrays of one shape -> heights of that shape.
    domain : ((x0, x1), (y0, y1))
    n : int or (int, int)
        Grid points per direction, at least ``degree + 1``.
    degree : int
    check : int
        Refinement of the grid on which the error is measured.

    Returns
    -------
    Conversion
        ``result`` a BSplineSurface with parameters ``(u, v) = (x, y)`` (its x
        and y coordinates reproduce the parameters exactly, since spline
        interpolation reproduces linear data); ``error`` the max vertical gap
        ``|S_z(x, y) - f(x, y)|`` on a grid ``check`` times finer -- at those
        points an upper bound of the distance between the two graphs.
    """
    d = _explicit_domain(domain)
    p = as_degree(degree)
    if isinstance(n, (tuple, list, np.ndarray)):
        if len(n) != 2:
            raise ParameterError(f"n must be an int or a pair, got {n!r}")
        nx, ny = (as_int(v, "n", minimum=p + 1) for v in n)
    else:
        nx = ny = as_int(n, "n", minimum=p + 1)
    c = as_int(check, "check", minimum=1)
    xs, ys = np.linspace(*d[0], nx), np.linspace(*d[1], ny)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    grid = np.stack([X, Y, _heights(f, X, Y)], axis=-1)
    surface = interpolate_surface(grid, p, p, parameters_u=xs, parameters_v=ys)
    fx, fy = np.linspace(*d[0], c * (nx - 1) + 1), np.linspace(*d[1], c * (ny - 1) + 1)
    S = surface.evaluate_grid(fx, fy)
    FX, FY = np.meshgrid(fx, fy, indexing="ij")
    error = float(np.abs(S[..., 2] - _heights(f, FX, FY)).max())
    return Conversion(
        surface,
        error,
        "grid interpolation",
        f"max |S_z(x, y) - f(x, y)| on a {len(fx)} x {len(fy)} grid ({c}x finer than the data)",
    )


def explicit_to_implicit(f, domain=((-1.0, 1.0), (-1.0, 1.0)), *, gradient=None, n: int = 64) -> Conversion:
    """The graph ``z = f(x, y)`` as the implicit ``F(x, y, z) = f(x, y) - z``
    (``splinekit.ExplicitSurface(f, gradient).to_implicit()``).

    Returns
    -------
    Conversion
        ``result`` an :class:`~splinekit.ImplicitSurface`; ``error`` the max
        ``|F|`` at ``n x n`` points of the graph over ``domain`` (a vertical
        distance; 0 up to rounding, the conversion being exact).
    """
    d = _explicit_domain(domain)
    n = as_int(n, "n", minimum=2)
    X, Y = np.meshgrid(np.linspace(*d[0], n), np.linspace(*d[1], n), indexing="ij")
    Z = _heights(f, X, Y)
    implicit = ExplicitSurface(f, gradient).to_implicit()
    F = np.asarray(implicit(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])), dtype=np.float64)
    return Conversion(implicit, float(np.abs(F).max()), "F = f(x, y) - z", f"max |F| at {n} x {n} points of the graph")
