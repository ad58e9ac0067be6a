"""From shaded triangles to a PNG: rasterize with a depth test, colour, outline, and lay out
the picture (title, colour bar) with matplotlib, which writes the file."""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._atomic import atomic_write
from .._signals import reraise_interrupt
from ..errors import MissingDependencyError, ParameterError
from . import colors, raster

DEFAULT_SIZE = (1000, 800)
DPI = 100
SUPERSAMPLE = 2  # samples per pixel along each axis: edges and outlines are antialiased by averaging
BAR_PIXELS = 135  # the colour bar and its labels take the rightmost 135 pixels
BAR_MIN_HEIGHT = 120  # below this the bar's tick labels would overlap: no bar
TITLE_FONT = 10  # points; at DPI 100 a line takes about 17 pixels and a character at most 7.5
CREASE_COS = np.cos(np.radians(40.0))  # neighbouring samples whose normals differ more get an outline


def pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no window)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - matplotlib is a dependency
        reraise_interrupt(exc)  # Ctrl-C during the import is an interrupt, not a missing package
        raise MissingDependencyError(f"rendering needs matplotlib: pip install matplotlib ({exc})") from None
    return plt


def check_render_options(color, scale, size, view):
    """``(size, view)`` as ``(width, height)`` integers and ``(elevation, azimuth)`` floats; ParameterError otherwise."""
    if color not in colors.COLOR_MODES:
        raise ParameterError(f"color must be one of {', '.join(colors.COLOR_MODES)}; got {color!r}")
    if scale not in colors.COLOR_SCALES:
        raise ParameterError(f"scale must be one of {', '.join(colors.COLOR_SCALES)}; got {scale!r}")
    try:
        w, h = (int(x) for x in size)
        ok = len(size) == 2 and all(float(x) == int(x) for x in size)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok or not (64 <= w <= 8000 and 64 <= h <= 8000):
        raise ParameterError(f"size must be two whole numbers of pixels between 64 and 8000 (width, height); got {size!r}")
    return (w, h), view_angles(view)


def view_angles(view) -> tuple[float, float]:
    """``(elevation, azimuth)`` in degrees from a pair of finite numbers; ParameterError otherwise."""
    try:
        elev, azim = (float(x) for x in view)
    except (TypeError, ValueError):
        raise ParameterError(f"view must be two angles in degrees (elevation, azimuth); got {view!r}") from None
    if not (np.isfinite(elev) and np.isfinite(azim)):
        raise ParameterError(f"view angles must be finite degrees; got {view!r}")
    return elev, azim


def triangle_normals(tris):
    """``(T, 3)`` unit normals of ``(T, 3, 3)`` triangles (0 for degenerate ones)."""
    return colors.unit_rows(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]))


def triangle_areas(tris):
    """``(T,)`` areas of ``(T, 3, 3)`` triangles."""
    return 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)


def _wrapped_title(title, width, height):
    """``(text, height)``: ``title`` broken into lines that fit ``width`` pixels at TITLE_FONT,
    and the pixels the lines take at the top of the picture. No title (``("", 0)``) when
    there is none, or when it would not fit: lines under 20 characters, or more than a
    third of ``height``."""
    chars = int((width - 20) / 7.5)
    if not title or chars < 20:
        return "", 0
    lines = textwrap.wrap(str(title), chars) or [""]
    pixels = 12 + 17 * len(lines)
    if pixels > height / 3:
        return "", 0
    return "\n".join(lines), pixels


def _has_bar(norm, width, height):
    """Whether the picture gets a colour bar: a curvature mode (``norm`` set) and room for it,
    that is at least as many pixels left for the object as the bar takes, and BAR_MIN_HEIGHT."""
    return norm is not None and width >= 2 * BAR_PIXELS and height >= BAR_MIN_HEIGHT


def _outlines(fragments, covered, normals, pixel_size):
    """``(h, w)`` booleans: samples on a silhouette, at a depth jump (one surface in front
    of another) or on a crease, compared with the right and lower neighbours; ``covered``
    and ``normals`` ``(h, w, 3)`` per sample, ``pixel_size`` in model units."""
    depth = fragments.depth
    edge = np.zeros_like(covered)
    jump = 6.0 * pixel_size  # steeper than ~80 degrees between neighbouring samples: another surface
    for axis in (0, 1):
        here = [slice(None)] * 2
        there = [slice(None)] * 2
        here[axis], there[axis] = slice(None, -1), slice(1, None)
        a, b = tuple(here), tuple(there)
        both = covered[a] & covered[b]
        gap = np.zeros(both.shape)
        gap[both] = np.abs(depth[a][both] - depth[b][both])
        step = (covered[a] != covered[b]) | (gap > jump)
        other = fragments.triangle[a] != fragments.triangle[b]
        crease = both & other  # then only where two triangles meet: compare their normals
        na, nb = normals[a][crease], normals[b][crease]
        crease[crease] = (na * nb).sum(axis=1) < CREASE_COS
        mark = step | crease
        # mark the nearer side only, so the line lies on the front surface
        nearer_a = np.where(both, depth[a] >= depth[b], covered[a])
        edge[a] |= mark & nearer_a
        edge[b] |= mark & ~nearer_a
    return edge


class Pixels:
    """What a custom painter (``draw(..., paint=...)``) gets for the ``n`` covered samples of a
    picture: ``normals`` ``(n, 3)`` unit (interpolated across each triangle), ``values``
    ``(n,)`` the interpolated ``corner_values`` (or None), ``triangle`` ``(n,)`` the triangle
    each sample shows, ``eye`` ``(3,)`` the unit direction towards the viewer (orthographic:
    one for all), and ``points`` ``(n, 3)``, the surface points in model units (interpolated
    on first use)."""

    def __init__(self, normals, values, triangle, eye, interpolate_points):
        self.normals, self.values, self.triangle, self.eye = normals, values, triangle, eye
        self._interpolate_points = interpolate_points

    @cached_property
    def points(self) -> np.ndarray:
        return self._interpolate_points()


@dataclass(frozen=True)
class ColourBar:
    """A colour bar of a custom painter: matplotlib ``norm`` and ``cmap``, the ``label`` and
    optional ``ticks`` (None: matplotlib's)."""

    norm: object
    cmap: object
    label: str
    ticks: object = None


def _label_borders(covered, labels):
    """``(h, w)`` booleans: covered samples whose ``labels`` (one per covered sample, in
    ``np.nonzero(covered)`` order) differ from the right or lower covered neighbour's."""
    grid = np.full(covered.shape, np.iinfo(np.int64).min, dtype=np.int64)
    grid[covered] = labels
    border = np.zeros_like(covered)
    for a, b in (((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
                 ((slice(None, -1), slice(None)), (slice(1, None), slice(None)))):
        differ = covered[a] & covered[b] & (grid[a] != grid[b])
        border[a] |= differ
    return border


def draw(tris, corner_normals, color, scale, size, view, title, path, *, corner_values=None, patch_id=None, outward=0,
         paint=None, colour_bar=None):
    """Write a PNG of ``(T, 3, 3)`` triangles to ``path`` (atomically); returns the path.

    ``corner_normals`` ``(T, 3, 3)`` are interpolated across each triangle (pass each
    triangle's own normal three times for flat shading); ``corner_values`` ``(T, 3)``
    (the curvature modes) are interpolated too; ``patch_id`` ``(T,)`` colours the
    ``patch`` mode. ``outward`` is +1 (-1) when the triangles bound a closed,
    consistently oriented surface with the normals pointing out (in): back faces are
    then left out before rasterizing, which halves the work. A picture too small for the
    colour bar or the title (see :func:`_has_bar`, :func:`_wrapped_title`) is drawn
    without them.

    A custom colouring (the analysis maps: zebra, isophotes, draft): ``paint(pixels)`` gets
    the :class:`Pixels` of the covered samples and returns ``(rgb (n, 3), labels, shaded)``:
    the base colours, optional ``(n,)`` integer labels whose boundaries are drawn as dark
    lines (isophotes, a region's border) and whether to shade the colours (zebra stripes are
    not); ``colour_bar`` (a :class:`ColourBar`) then replaces the curvature colour bar.
    """
    plt = pyplot()
    from matplotlib import cm

    w, h = size
    eye, right, up = raster.view_basis(*view)
    light = colors.unit_rows((eye + 0.55 * np.array([0.0, 0.0, 1.0]) - 0.45 * right)[None, :])[0]
    face_normals = triangle_normals(tris)

    norm = cmap = None
    if colour_bar is not None:
        norm, cmap = colour_bar.norm, colour_bar.cmap
    elif corner_values is not None and paint is None:
        norm, cmap = colors.norm_and_cmap(color, corner_values.mean(axis=1), scale, triangle_areas(tris))
    if outward:
        front = outward * (face_normals @ eye) > -1e-3  # orthographic: one eye direction everywhere
        tris, corner_normals, face_normals = tris[front], corner_normals[front], face_normals[front]
        corner_values = None if corner_values is None else corner_values[front]
        patch_id = None if patch_id is None else np.asarray(patch_id)[front]

    # a small picture leaves out the colour bar and the title rather than the object
    text, title_px = _wrapped_title(title, w, h)
    bar = _has_bar(norm, w, h)
    frame_w = w - (BAR_PIXELS if bar else 0)
    frame_h = h - title_px
    s = SUPERSAMPLE
    points = tris.reshape(-1, 3)
    xy, depth, pixels_per_unit = raster.project(points, view, frame_w * s, frame_h * s)
    fragments = raster.rasterize(xy.reshape(-1, 3, 2), depth.reshape(-1, 3), frame_w * s, frame_h * s)
    hit = fragments.covered
    triangle = fragments.triangle[hit]
    n = colors.unit_rows(fragments.interpolate(np.nan_to_num(corner_normals), hit))
    lost = ~n.any(axis=1)  # corner normals cancelled or undefined: the triangle's own
    n[lost] = face_normals[triangle[lost]]
    values = None if corner_values is None else fragments.interpolate(corner_values, hit)
    labels, shaded = None, True
    if paint is not None:
        base, labels, shaded = paint(Pixels(n, values, triangle, eye, lambda: fragments.interpolate(tris, hit)))
    else:
        base = colors.base_colors(color, values=values, normals=n,
                                  patch_id=None if patch_id is None else np.asarray(patch_id)[triangle], norm=norm, cmap=cmap)
    image = np.ones(hit.shape + (3,), dtype=np.float32)
    image[hit] = colors.shade(base, n, eye, light) if shaded else base
    normals = np.zeros(hit.shape + (3,), dtype=np.float32)
    normals[hit] = n
    image[_outlines(fragments, hit, normals, 1.0 / pixels_per_unit)] *= 0.45
    if labels is not None:
        image[_label_borders(hit, labels)] *= 0.3
    image = image.reshape(frame_h, s, frame_w, s, 3).mean(axis=(1, 3))

    fig = plt.figure(figsize=(w / DPI, h / DPI), dpi=DPI)
    try:
        fig.figimage(image, xo=0, yo=0, origin="upper")
        if bar:
            top = min(0.82, 1.0 - (title_px + 24.0) / h)  # below the title
            cax = fig.add_axes([1.0 - BAR_PIXELS / w, 0.14, 18.0 / w, max(top - 0.14, 0.2)])
            colorbar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax)
            if colour_bar is not None:
                colorbar.set_label(colour_bar.label, fontsize=9)
                if colour_bar.ticks is not None:
                    colorbar.set_ticks(colour_bar.ticks)
            else:
                colorbar.set_label(colors.colorbar_label(color, scale), fontsize=9)
                if scale == "symlog":
                    colorbar.set_ticks(colors.symlog_ticks(norm))
            colorbar.ax.tick_params(labelsize=8)
        if text:
            fig.text(10.0 / w, 1.0 - 6.0 / h, text, fontsize=TITLE_FONT, va="top")
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=DPI, facecolor="white"))
    finally:
        plt.close(fig)
