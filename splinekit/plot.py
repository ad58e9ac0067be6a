"""Pictures of curves and surfaces (matplotlib, Agg backend, imported lazily).

A person would rather look at a surface than read its numbers; these helpers
write a shaded PNG so that anyone, including the test suite, can:

* :func:`render_surface` -- one surface and its control net (``splinekit demo``);
* :func:`render_patches` -- a set of exact patches colored by exact curvature
  (:func:`splinekit.curvature` on each patch's grid), normal or patch;
* :func:`render_mesh` -- a :class:`~splinekit.PolyMesh` colored by its discrete
  curvature, normal or patch / component.

Every PNG is written atomically (a temporary file renamed into place). The
drawing is matplotlib's mplot3d: polygons sorted by depth, not a z-buffer, so
surfaces that pierce each other (the Utah teapot's spout and body) can show
the wrong one in front near the intersection.
"""

from __future__ import annotations

import numpy as np

from ._atomic import atomic_write
from .errors import MissingDependencyError, ParameterError

__all__ = ["render_surface", "render_patches", "render_mesh", "COLOR_MODES", "COLOR_SCALES"]


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - matplotlib is a dependency
        raise MissingDependencyError(f"rendering needs matplotlib: pip install matplotlib ({exc})") from None
    return plt


def render_surface(surface, path, resolution: int = 80, color: str = "normal", show_net: bool = True, title=None):
    """Write a shaded PNG of a 3-D spline surface to ``path`` (atomically).

    ``color`` is ``"normal"`` (Lambert shading of the unit normal) or
    ``"height"`` (z coordinate), sampled on a ``resolution x resolution``
    parameter grid (an integer in ``[2, MAX_RESOLUTION]``). The control net is
    drawn as a wireframe when ``show_net``. Returns the path.
    """
    if getattr(surface, "dim", None) != 3:
        raise ParameterError("render_surface needs a surface in 3-D space")
    if color not in ("normal", "height"):
        raise ParameterError(f"color must be 'normal' or 'height', got {color!r}")
    resolution = _resolution(resolution)
    plt = _pyplot()
    from matplotlib import cm

    (a, b), (c, d) = surface.domain
    us = np.linspace(a, b, resolution)
    vs = np.linspace(c, d, resolution)
    X = surface.evaluate_grid(us, vs)
    if color == "normal":
        n = surface.normal_grid(us, vs)
        light = np.array([0.4, -0.5, 0.77])
        light /= np.linalg.norm(light)
        shade = 0.25 + 0.75 * np.abs(n @ light)
        colors = cm.viridis(shade)
    else:
        z = X[..., 2]
        span = np.ptp(z) or 1.0
        colors = cm.viridis((z - z.min()) / span)
    fig = plt.figure(figsize=(7, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(X[..., 0], X[..., 1], X[..., 2], facecolors=colors, rstride=1, cstride=1, linewidth=0, antialiased=False, shade=False)
    if show_net:
        P = surface.control_points
        ax.plot_wireframe(P[..., 0], P[..., 1], P[..., 2], color="0.3", linewidth=0.6, alpha=0.7)
        ax.scatter(P[..., 0].ravel(), P[..., 1].ravel(), P[..., 2].ravel(), color="crimson", s=6)
    extent = np.ptp(X.reshape(-1, 3), axis=0) + 1e-9
    ax.set_box_aspect(np.maximum(extent, 0.4 * extent.max()))  # keep flat surfaces readable
    ax.set_title(title or repr(surface), fontsize=8)
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", bbox_inches="tight"))
    finally:
        plt.close(fig)


# ---------------------------------------------------------------------------
# Shaded pictures of patch sets and meshes, colored by curvature, normal or patch

COLOR_MODES = ("curvature", "gaussian", "mean", "normal", "patch")
"""What :func:`render_patches` / :func:`render_mesh` can color by:
``curvature`` the RMS of the principal curvatures ``sqrt((k1^2 + k2^2) / 2)``
(unsigned, 1/length), ``gaussian`` K (1/length^2, signed), ``mean`` H
(1/length, signed against the normals as everywhere in splinekit and in OCC:
a sphere with outward normals has H = -1/r), ``normal`` the unit normal as RGB, ``patch`` the patch
(or, for a plain mesh, connected component) index."""

COLOR_SCALES = ("percentile", "symlog")
"""Color scales of the curvature modes: ``percentile`` is linear and clipped
at the 98th percentile of ``|value|`` (so a few extreme values at a crease or
pole do not wash out the rest); ``symlog`` is a symmetric logarithmic scale
over the full range, linear below the 25th percentile of ``|value|``."""

DEFAULT_SIZE = (1000, 800)
_QUAD_BUDGET = 40000  # quads drawn for a whole patch set: matplotlib draws ~20-40k polygons per second
_DPI = 100
_SIGNED = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H"}
_NAN_GREY = 0.6


MAX_RESOLUTION = 1000
"""Largest parameter grid per direction and patch (a million quads per patch
is already far beyond what matplotlib draws in reasonable time)."""


def _resolution(value) -> int:
    """A grid resolution: an integer in ``[2, MAX_RESOLUTION]``, else ParameterError."""
    from ._validate import as_int

    n = as_int(value, "resolution", minimum=2)
    if n > MAX_RESOLUTION:
        raise ParameterError(f"resolution must be at most {MAX_RESOLUTION}, got {n}")
    return n


def _check_render_options(color, scale, size, view):
    if color not in COLOR_MODES:
        raise ParameterError(f"color must be one of {', '.join(COLOR_MODES)}; got {color!r}")
    if scale not in COLOR_SCALES:
        raise ParameterError(f"scale must be one of {', '.join(COLOR_SCALES)}; got {scale!r}")
    try:
        w, h = (int(x) for x in size)
        ok = len(size) == 2 and all(float(x) == int(x) for x in size)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok or not (64 <= w <= 8000 and 64 <= h <= 8000):
        raise ParameterError(f"size must be two whole numbers of pixels between 64 and 8000 (width, height); got {size!r}")
    try:
        elev, azim = (float(x) for x in view)
    except (TypeError, ValueError):
        raise ParameterError(f"view must be two angles in degrees (elevation, azimuth); got {view!r}") from None
    if not (np.isfinite(elev) and np.isfinite(azim)):
        raise ParameterError(f"view angles must be finite degrees; got {view!r}")
    return (w, h), (elev, azim)


def _grid_quads(n_u: int, n_v: int) -> np.ndarray:
    """``((n_u - 1) * (n_v - 1), 4)`` corner indices of the quads of a raveled ``(n_u, n_v)`` grid, counter-clockwise in (u, v)."""
    i, j = np.meshgrid(np.arange(n_u - 1), np.arange(n_v - 1), indexing="ij")
    base = (i * n_v + j).ravel()
    return np.stack([base, base + n_v, base + n_v + 1, base + 1], axis=1)


def _rms_curvature(K, H):
    """``sqrt((k1^2 + k2^2) / 2) = sqrt(2 H^2 - K)``, clamped at 0 against rounding."""
    return np.sqrt(np.maximum(2.0 * H * H - K, 0.0))


def _field(color, K, H):
    return {"curvature": lambda: _rms_curvature(K, H), "gaussian": lambda: K, "mean": lambda: H}[color]()


def _unit_rows(n):
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _polygon_normals(polys):
    """``(F, 3)`` unit normals of ``(F, k, 3)`` polygons from their diagonals (k >= 3)."""
    if polys.shape[1] == 3:
        n = np.cross(polys[:, 1] - polys[:, 0], polys[:, 2] - polys[:, 0])
    else:
        half = polys.shape[1] // 2
        n = np.cross(polys[:, half] - polys[:, 0], polys[:, half + 1] - polys[:, 1])
    return _unit_rows(n)


def _polygon_areas(polys) -> np.ndarray:
    """``(F,)`` areas of ``(F, k, 3)`` planar-ish polygons (half the cross product of the diagonals)."""
    if polys.shape[1] == 3:
        return 0.5 * np.linalg.norm(np.cross(polys[:, 1] - polys[:, 0], polys[:, 2] - polys[:, 0]), axis=1)
    half = polys.shape[1] // 2
    return 0.5 * np.linalg.norm(np.cross(polys[:, half] - polys[:, 0], polys[:, half + 1] - polys[:, 1]), axis=1)


def _area_quantile(values, weights, q: float) -> float:
    """The value below which a fraction ``q`` of the total weight (surface area) lies."""
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    if not cumulative.size or not cumulative[-1] > 0:
        return float(np.quantile(values, q)) if values.size else 0.0
    return float(values[order][min(np.searchsorted(cumulative, q * cumulative[-1]), values.size - 1)])


def _norm_and_cmap(color, values, scale, areas):
    """The matplotlib norm and colormap of a per-face scalar field. The limits are
    area quantiles of ``|value|`` over the finite values, so that a fine grid on a
    small, sharply curved feature does not set the scale for the whole surface."""
    from matplotlib import colormaps
    from matplotlib import colors as mcolors

    plt_cmap = colormaps.get_cmap
    ok = np.isfinite(values)
    magnitude, weight = np.abs(values[ok]), areas[ok]
    top = float(magnitude.max()) if magnitude.size else 0.0
    clip = _area_quantile(magnitude, weight, 0.98)
    if not clip > 0:
        clip = top if top > 0 else 1.0
    if not top > 0:
        top = 1.0
    signed = color in _SIGNED
    if signed:
        cmap = plt_cmap("coolwarm")
    else:  # plasma without its darkest eighth, which shading would turn black
        cmap = mcolors.ListedColormap(plt_cmap("plasma")(np.linspace(0.12, 1.0, 256)), name="plasma_light")
    if scale == "percentile":
        norm = mcolors.Normalize(-clip if signed else 0.0, clip, clip=True)
    else:
        linthresh = max(_area_quantile(magnitude, weight, 0.25), 1e-4 * top)
        norm = mcolors.SymLogNorm(linthresh, linscale=0.5, vmin=-top if signed else 0.0, vmax=top, base=10, clip=True)
    return norm, cmap


def _shaded(base, normals, eye, light):
    """Two-sided Lambert + a little Blinn-Phong highlight on ``(F, 3)`` base colors."""
    half = _unit_rows((eye + light)[None, :])[0]
    diffuse = np.abs(normals @ light)
    spec = np.abs(normals @ half) ** 40
    rgb = base * (0.4 + 0.6 * diffuse)[:, None] + 0.2 * spec[:, None]
    return np.clip(rgb, 0.0, 1.0)


def _fill_zoom(fig, ax, points, fill: float = 0.92) -> float:
    """The ``set_box_aspect`` zoom at which the projected ``points`` fill ``fill`` of the
    axes (about the axes centre, where mplot3d keeps the box centre), at most 3."""
    from mpl_toolkits.mplot3d import proj3d

    fig.canvas.draw()  # the projection matrix depends on the axes' final size
    sample = points[:: max(1, len(points) // 20000)]  # the hull matters, not every corner
    x, y, _ = proj3d.proj_transform(sample[:, 0], sample[:, 1], sample[:, 2], ax.get_proj())
    px = ax.transData.transform(np.column_stack([x, y]))
    box = ax.bbox
    cx, cy = 0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1)
    reach_x = np.abs(px[:, 0] - cx).max()
    reach_y = np.abs(px[:, 1] - cy).max()
    zoom = fill * min(0.5 * box.width / max(reach_x, 1e-9), 0.5 * box.height / max(reach_y, 1e-9))
    return float(np.clip(zoom, 0.2, 3.0))


def _draw(polys, normals, color, values, patch_id, scale, size, view, title, path, outward=0):
    """Draw ``(F, k, 3)`` polygons shaded by their ``(F, 3)`` normals and colored by
    ``values`` (scalar field), their normals or ``patch_id``; write the PNG atomically.

    ``outward`` is +1 (-1) when the polygons bound a closed, consistently oriented
    surface with the normals pointing out (in): the back faces are then left out,
    which spares matplotlib's per-polygon depth sort most of its chances to go wrong.
    """
    plt = _pyplot()
    from matplotlib import cm
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    elev, azim = np.radians(view[0]), np.radians(view[1])
    eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
    right = np.array([-np.sin(azim), np.cos(azim), 0.0])
    light = _unit_rows((eye + 0.55 * np.array([0.0, 0.0, 1.0]) - 0.45 * right)[None, :])[0]

    norm = cmap = None
    if color == "normal":
        base = 0.5 + 0.5 * normals
    elif color == "patch":
        base = cm.tab20(np.asarray(patch_id) % 20)[:, :3]
    else:
        norm, cmap = _norm_and_cmap(color, values, scale, _polygon_areas(polys))
        base = cmap(norm(np.nan_to_num(values)))[:, :3]
        base[~np.isfinite(values)] = _NAN_GREY  # undefined curvature (a degenerate point) in grey
    rgb = _shaded(base, normals, eye, light)
    if outward:
        front = outward * (normals @ eye) > -1e-3  # orthographic view: the eye direction is the same everywhere
        polys, rgb = polys[front], rgb[front]

    w, h = size
    fig = plt.figure(figsize=(w / _DPI, h / _DPI), dpi=_DPI)
    try:
        bar_left = 1.0 - 135.0 / w  # the colour bar and its labels take the rightmost 135 pixels
        ax = fig.add_axes([0.0, 0.0, bar_left - 0.01 if norm is not None else 1.0, 0.93], projection="3d")
        ax.view_init(elev=view[0], azim=view[1])
        ax.set_proj_type("ortho")
        # edges drawn in the face color hide the hairline seams antialiasing leaves between polygons
        coll = Poly3DCollection(polys, facecolors=rgb, edgecolors=rgb, linewidths=0.3)
        ax.add_collection3d(coll)
        pts = polys.reshape(-1, 3) if len(polys) else np.zeros((1, 3))
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        extent = hi - lo
        pad = np.maximum(extent, 0.02 * extent.max() + 1e-12)
        mid = 0.5 * (lo + hi)
        ax.set_xlim(mid[0] - pad[0] / 2, mid[0] + pad[0] / 2)
        ax.set_ylim(mid[1] - pad[1] / 2, mid[1] + pad[1] / 2)
        ax.set_zlim(mid[2] - pad[2] / 2, mid[2] + pad[2] / 2)
        ax.set_box_aspect(pad)
        ax.set_axis_off()
        ax.set_box_aspect(pad, zoom=_fill_zoom(fig, ax, pts))
        if norm is not None:
            cax = fig.add_axes([bar_left, 0.14, 18.0 / w, 0.68])
            bar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax)
            label = _SIGNED.get(color, "RMS curvature √((k1² + k2²)/2)")
            bar.set_label(f"{label}\n({'clipped at the 98th area percentile' if scale == 'percentile' else 'symmetric log scale'})", fontsize=9)
            bar.ax.tick_params(labelsize=8)
        if title:
            fig.text(0.015, 0.975, title, fontsize=10, va="top")
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=_DPI, facecolor="white"))
    finally:
        plt.close(fig)


def render_patches(patches, path, *, color: str = "curvature", scale: str = "percentile", size=DEFAULT_SIZE,
                   view=(28.0, -58.0), resolution=None, title=None) -> str:
    """Write a shaded PNG of a set of 3-D spline patches to ``path`` (atomically); returns the path.

    ``patches`` is a surface or a list of surfaces (Bézier, B-spline or NURBS).
    Each patch is sampled on a uniform ``resolution x resolution`` parameter
    grid (by default chosen so the whole set draws about 40 000 quads, 5 to 65
    points per direction), with the exact normals and curvatures of
    :func:`splinekit.curvature` evaluated on the whole grid at once.
    ``color`` is one of :data:`COLOR_MODES`, ``scale`` one of
    :data:`COLOR_SCALES`; ``size`` is ``(width, height)`` in pixels and
    ``view`` ``(elevation, azimuth)`` in degrees. The curvature modes get a
    color bar in 1/model-unit (squared for Gaussian).
    """
    from .diffgeom import curvature
    from .surfaces import BezierSurface, SplineSurface

    size, view = _check_render_options(color, scale, size, view)
    if isinstance(patches, (BezierSurface, SplineSurface)):
        patches = [patches]
    patches = list(patches)
    if not patches:
        raise ParameterError("render_patches got no patches to draw")
    for i, s in enumerate(patches):
        if not isinstance(s, (BezierSurface, SplineSurface)) or s.dim != 3:
            raise ParameterError(f"patch {i} is not a 3-D Bézier, B-spline or NURBS surface ({type(s).__name__})")
    if resolution is None:
        n = int(np.clip(np.sqrt(_QUAD_BUDGET / len(patches)), 4, 64)) + 1
    else:
        n = _resolution(resolution)
    quads = _grid_quads(n, n)
    polys, normals, K, H = [], [], [], []
    for s in patches:  # one vectorized grid evaluation per patch
        (a, b), (c, d) = s.domain
        us, vs = np.linspace(a, b, n), np.linspace(c, d, n)
        X = s.evaluate_grid(us, vs).reshape(-1, 3)
        k = curvature(s, us, vs, grid=True)
        polys.append(X[quads])
        normals.append(k.normal.reshape(-1, 3)[quads].sum(axis=1))
        K.append(k.gaussian.reshape(-1)[quads].mean(axis=1))
        H.append(k.mean.reshape(-1)[quads].mean(axis=1))
    polys = np.concatenate(polys)
    normals = _unit_rows(np.concatenate(normals))
    flat = ~normals.any(axis=1)  # corner normals cancelled or were undefined: use the polygon's own
    normals[flat] = _polygon_normals(polys[flat])
    H = np.concatenate(H)
    values = None if color in ("normal", "patch") else _field(color, np.concatenate(K), H)
    patch_id = np.repeat(np.arange(len(patches)), len(quads))
    return _draw(polys, normals, color, values, patch_id, scale, size, view, title, path)


def _mesh_corners(mesh):
    """``(corners (F', k), source face (F',))``: the faces' vertex indices as they are
    when every face has ``k`` sides, otherwise fan triangles (a face with k corners gives k - 2)."""
    from .mesh.geometry import triangulate

    idx, off = np.asarray(mesh.face_indices), np.asarray(mesh.face_offsets)
    counts = np.diff(off)
    if counts.size and (counts == counts[0]).all():
        return idx.reshape(-1, counts[0]), np.arange(counts.size)
    return triangulate(mesh)


def _halves(corners, order):
    """The two halves ``(a, m, c)`` and ``(m, b, c)`` of triangles whose per-corner data
    ``corners`` ``(n, 3, d)`` is rolled by ``order`` ``(n, 3)`` so that a-b is the
    edge to split; ``m`` is its midpoint."""
    rolled = np.take_along_axis(corners, order[:, :, None], axis=1)
    a, b, c = rolled[:, 0], rolled[:, 1], rolled[:, 2]
    m = 0.5 * (a + b)
    return np.stack([a, m, c], axis=1), np.stack([m, b, c], axis=1)


def _split_long_triangles(tris, corner_values, source, relative: float = 0.05, budget: int = 50000):
    """Halve every triangle across its longest edge while that edge is longer than
    ``relative`` x the model diagonal (at most ``budget`` triangles in all).

    matplotlib orders polygons by their mean depth, which goes wrong for long
    slivers (CAD meshes are full of them); small pieces sort right, and per-corner
    values interpolated to the new corners keep a vertex's colour near the vertex.
    Returns the new ``(tris, corner_values, source)``.
    """
    pts = tris.reshape(-1, 3)
    limit = relative * float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
    for _ in range(16):
        lengths = np.linalg.norm(tris[:, [1, 2, 0]] - tris, axis=2)  # edge k runs from corner k to k + 1
        longest = lengths.argmax(axis=1)
        split = lengths[np.arange(len(tris)), longest] > limit
        n_split = int(split.sum())
        if n_split == 0 or len(tris) + n_split > budget:
            break
        order = (longest[split, None] + np.arange(3)) % 3  # corners a, b, c with a-b the longest edge
        first, second = _halves(tris[split], order)
        tris = np.concatenate([tris[~split], first, second])
        if corner_values is not None:
            v1, v2 = _halves(corner_values[split][..., None], order)
            corner_values = np.concatenate([corner_values[~split], v1[..., 0], v2[..., 0]])
        source = np.concatenate([source[~split], source[split], source[split]])
    return tris, corner_values, source


def _face_components(mesh) -> np.ndarray:
    """``(F,)`` connected-component index of each face (faces sharing a vertex are connected)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    idx = np.asarray(mesh.face_indices)
    face_of_corner = mesh.topology.corner_face
    n = mesh.n_vertices + mesh.n_faces
    graph = coo_matrix((np.ones(idx.size), (idx, mesh.n_vertices + face_of_corner)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    return labels[mesh.n_vertices:]


def render_mesh(mesh, path, *, color: str = "curvature", scale: str = "percentile", size=DEFAULT_SIZE,
                view=(28.0, -58.0), title=None) -> str:
    """Write a shaded PNG of a 3-D :class:`~splinekit.PolyMesh` to ``path`` (atomically); returns the path.

    Faces are drawn flat-shaded by their own normals. The curvature modes use
    the mesh's discrete curvatures (``gaussian_curvature``, ``mean_curvature``,
    per vertex, averaged over each face's corners; 0 on the boundary). Long
    triangles are halved for drawing (see :func:`_split_long_triangles`). On CAD
    meshes with sharp edges the discrete curvature concentrates at the edge and
    corner vertices (that is what it measures), so ``normal`` or ``patch``
    reads better there;
    ``patch`` uses the mesh's ``face_patch`` when it has one (a tessellation),
    else its connected components. Options as in :func:`render_patches`.
    Drawing takes matplotlib about a second per 30 000 faces.
    """
    from .mesh import PolyMesh

    size, view = _check_render_options(color, scale, size, view)
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"render_mesh needs a PolyMesh, got {type(mesh).__name__}")
    if mesh.vertices.shape[1] != 3 or mesh.n_faces == 0:
        raise ParameterError(f"render_mesh needs a 3-D mesh with faces; got {mesh.vertices.shape[1]}-D with {mesh.n_faces} faces")
    corners, source = _mesh_corners(mesh)
    polys = np.asarray(mesh.vertices, dtype=np.float64)[corners]
    corner_values = None
    if color not in ("normal", "patch"):
        corner_values = _field(color, np.asarray(mesh.gaussian_curvature), np.asarray(mesh.mean_curvature))[corners]
    if polys.shape[1] == 3:
        polys, corner_values, source = _split_long_triangles(polys, corner_values, source)
    normals = _polygon_normals(polys)
    values = None if corner_values is None else corner_values.mean(axis=1)
    patch_id = None
    if color == "patch":
        face_patch = getattr(mesh, "face_patch", None)
        patch_id = (np.asarray(face_patch) if face_patch is not None else _face_components(mesh))[source]
    outward = 0
    if mesh.is_closed:  # closed PolyMeshes are consistently oriented; the volume's sign says which way
        outward = int(np.sign(float(mesh.volume)))
    return _draw(polys, normals, color, values, patch_id, scale, size, view, title, path, outward)
