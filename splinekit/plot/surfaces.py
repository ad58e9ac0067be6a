"""Pictures of spline surfaces: one surface with its control net, or a set of exact patches
coloured by exact curvature."""

from __future__ import annotations

import numpy as np

from .._atomic import atomic_write
from .._validate import as_int
from ..diffgeom import curvature
from ..errors import ParameterError
from ..surfaces import BezierSurface, SplineSurface
from . import colors, picture, raster

MAX_RESOLUTION = 1000
"""Largest parameter grid per direction and patch."""

QUAD_BUDGET = 40000  # grid quads sampled for a whole patch set by default


def _resolution(value) -> int:
    """A grid resolution: an integer in ``[2, MAX_RESOLUTION]``, else ParameterError."""
    n = as_int(value, "resolution", minimum=2)
    if n > MAX_RESOLUTION:
        raise ParameterError(f"resolution must be at most {MAX_RESOLUTION}, got {n}")
    return n


def grid_quads(n_u: int, n_v: int) -> np.ndarray:
    """``((n_u - 1) * (n_v - 1), 4)`` corner indices of the quads of a raveled ``(n_u, n_v)`` grid, counter-clockwise in (u, v)."""
    i, j = np.meshgrid(np.arange(n_u - 1), np.arange(n_v - 1), indexing="ij")
    base = (i * n_v + j).ravel()
    return np.stack([base, base + n_v, base + n_v + 1, base + 1], axis=1)


def render_surface(surface, path, resolution: int = 80, color: str = "normal", show_net: bool = True, title=None):
    """Write a shaded PNG of a 3-D spline surface to ``path`` (atomically).

    ``color`` is ``"normal"`` (Lambert shading of the unit normal) or
    ``"height"`` (z coordinate), sampled on a ``resolution x resolution``
    parameter grid (an integer in ``[2, MAX_RESOLUTION]``). The control net is
    drawn as a wireframe when ``show_net`` (matplotlib's mplot3d, which orders
    polygons by depth rather than per pixel: fine for one surface and its net).
    Returns the path.
    """
    if getattr(surface, "dim", None) != 3:
        raise ParameterError("render_surface needs a surface in 3-D space")
    if color not in ("normal", "height"):
        raise ParameterError(f"color must be 'normal' or 'height', got {color!r}")
    resolution = _resolution(resolution)
    plt = picture.pyplot()
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
        rgb = cm.viridis(shade)
    else:
        z = X[..., 2]
        span = np.ptp(z) or 1.0
        rgb = cm.viridis((z - z.min()) / span)
    fig = plt.figure(figsize=(7, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(X[..., 0], X[..., 1], X[..., 2], facecolors=rgb, rstride=1, cstride=1, linewidth=0, antialiased=False, shade=False)
    if show_net:
        P = surface.control_points
        ax.plot_wireframe(P[..., 0], P[..., 1], P[..., 2], color="0.3", linewidth=0.6, alpha=0.7)
        ax.scatter(P[..., 0].ravel(), P[..., 1].ravel(), P[..., 2].ravel(), color="crimson", s=6)
    extent = np.ptp(X.reshape(-1, 3), axis=0) + 1e-9
    ax.set_box_aspect(np.maximum(extent, 0.4 * extent.max()))  # keep flat surfaces readable
    ax.set_title(title or repr(surface), fontsize=8, wrap=True)
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", bbox_inches="tight"))
    finally:
        plt.close(fig)


def render_patches(patches, path, *, color: str = "curvature", scale: str = "percentile", size=picture.DEFAULT_SIZE,
                   view=(28.0, -58.0), resolution=None, title=None) -> str:
    """Write a shaded PNG of a set of 3-D spline patches to ``path`` (atomically); returns the path.

    ``patches`` is a surface or a list of surfaces (Bézier, B-spline or NURBS).
    Each patch is sampled on a uniform ``resolution x resolution`` parameter
    grid (by default chosen so the whole set has about 40 000 quads, 5 to 65
    points per direction), with the exact normals and curvatures of
    :func:`splinekit.curvature` evaluated on the whole grid at once and
    interpolated across each grid triangle; a z-buffer decides what is in front
    per pixel. ``color`` is one of :data:`COLOR_MODES`, ``scale`` one of
    :data:`COLOR_SCALES`; ``size`` is ``(width, height)`` in pixels and
    ``view`` ``(elevation, azimuth)`` in degrees. The curvature modes get a
    color bar in 1/model-unit (squared for Gaussian). A long title is wrapped.
    """
    size, view = picture.check_render_options(color, scale, size, view)
    if isinstance(patches, (BezierSurface, SplineSurface)):
        patches = [patches]
    patches = list(patches)
    if not patches:
        raise ParameterError("render_patches got no patches to draw")
    for i, s in enumerate(patches):
        if not isinstance(s, (BezierSurface, SplineSurface)) or s.dim != 3:
            raise ParameterError(f"patch {i} is not a 3-D Bézier, B-spline or NURBS surface ({type(s).__name__})")
    if resolution is None:
        n = int(np.clip(np.sqrt(QUAD_BUDGET / len(patches)), 4, 64)) + 1
    else:
        n = _resolution(resolution)
    corners, _ = raster.fan_triangles(grid_quads(n, n))  # (T, 3) grid indices, shared by every patch
    points, normals, K, H = [], [], [], []
    for s in patches:  # one vectorized grid evaluation per patch
        (a, b), (c, d) = s.domain
        us, vs = np.linspace(a, b, n), np.linspace(c, d, n)
        k = curvature(s, us, vs, grid=True)
        points.append(s.evaluate_grid(us, vs).reshape(-1, 3)[corners])
        normals.append(k.normal.reshape(-1, 3)[corners])
        K.append(k.gaussian.reshape(-1)[corners])
        H.append(k.mean.reshape(-1)[corners])
    values = None
    if color not in ("normal", "patch"):
        values = colors.curvature_field(color, np.concatenate(K), np.concatenate(H))
    patch_id = np.repeat(np.arange(len(patches)), len(corners))
    return picture.draw(np.concatenate(points), np.concatenate(normals), color, scale, size, view, title, path,
                        corner_values=values, patch_id=patch_id)
