"""Pictures of the analysis maps: each map's colouring as a painter for
:func:`splinekit.plot.picture.draw`, which rasterizes the part's triangles with a depth test
and writes the PNG (atomically).

The painters evaluate the maps' formulas per pixel on the interpolated unit normal, so
zebra stripes, isophote lines and the border of an under-cut are as sharp as the pixels.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..plot import colors, picture
from ..plot.picture import ColourBar
from .fields import VERTICAL_DEGREES, draft_degrees, isophote_angle, zebra_angle, zebra_stripe

__all__ = ["render_map", "vector_text"]

DARK, LIGHT = 0.08, 0.97  # zebra stripe greys
DRAFT_EDGES = (-90.0, -45.0, -15.0, -5.0, 0.0, 5.0, 15.0, 45.0, 90.0)
"""Class edges of the draft colour bar (degrees); ``min_draft`` is added to them."""


def vector_text(v) -> str:
    return "(" + ", ".join(f"{x:.3g}" for x in np.asarray(v, dtype=float)) + ")"


def _matplotlib_colors():
    picture.pyplot()  # the Agg backend before anything else of matplotlib
    from matplotlib import colormaps
    from matplotlib import colors as mcolors

    return colormaps, mcolors


def render_map(m, path, *, size=picture.DEFAULT_SIZE, view=None, title=None) -> str:
    """Write a PNG of the :class:`~splinekit.analysis.maps.SurfaceMap` ``m`` to ``path``."""
    own_view = m.options.get("view")
    if view is None:
        view = own_view if own_view is not None else (28.0, -58.0)
    elif own_view is not None and tuple(float(x) for x in view) != tuple(own_view):
        raise ParameterError(f"a zebra map is drawn from the view it was computed for, {own_view}; "
                             f"compute it again with view={tuple(view)}")
    size, view = picture.check_render_options("normal", "percentile", size, view)
    part = m.part
    tris = part.points[part.triangles]
    corner_normals = part.normals[part.triangles]
    painter, bar, default_title, corner_values = _PAINTERS[m.kind](m)
    return picture.draw(tris, corner_normals, "normal", "percentile", size, view,
                        default_title if title is None else title, path,
                        corner_values=corner_values, paint=painter, colour_bar=bar)


def _zebra_painter(m):
    eye, axis, stripes = m.options["eye"], m.options["axis"], m.options["stripes"]

    def paint(px):
        stripe = zebra_stripe(zebra_angle(px.normals, eye, axis), stripes)
        rgb = np.where(stripe[:, None] == 1, LIGHT, DARK) * np.ones(3)
        return rgb, None, False

    along = "upright in the view" if m.options.get("upright") else f"along {vector_text(axis)}"
    return paint, None, f"zebra stripes: {stripes} pairs all around, light bands {along}", None


def _isophote_painter(m):
    colormaps, mcolors = _matplotlib_colors()
    direction, step = m.options["direction"], m.options["step"]
    cmap = colormaps.get_cmap("viridis")
    norm = mcolors.Normalize(0.0, 180.0)

    def paint(px):
        angle = isophote_angle(px.normals, direction)
        band = np.floor(angle / step).astype(np.int64)
        rgb = cmap(norm(angle))[:, :3] * np.where(band % 2 == 0, 1.0, 0.82)[:, None]
        return rgb, band, False

    n_ticks = int(180 // step) + 1
    ticks = np.arange(n_ticks) * step if n_ticks <= 13 else np.arange(0.0, 181.0, 30.0)
    bar = ColourBar(norm, cmap, f"angle between normal and light (degrees)\nlines every {step:g}°", ticks)
    return paint, bar, f"isophotes: light along {vector_text(direction)}, every {step:g}°", None


_CURVATURE_LABELS = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H",
                     "max": "max principal curvature k1", "min": "min principal curvature k2"}


def _curvature_painter(m):
    part = m.part
    scale = m.options.get("scale", "percentile")
    corner_values = m.values[part.triangles]
    areas = picture.triangle_areas(part.points[part.triangles])
    # k1 and k2 are signed like H: the signed colour map of colors.norm_and_cmap
    norm, cmap = colors.norm_and_cmap("gaussian" if m.kind == "gaussian" else "mean", corner_values.mean(axis=1),
                                      scale, areas)

    def paint(px):
        values = px.values
        rgb = cmap(norm(np.nan_to_num(values)))[:, :3]
        rgb[~np.isfinite(values)] = colors.NAN_GREY
        return rgb, None, True

    how = "clipped at the 98th area percentile" if scale == "percentile" else "log scale"
    ticks = colors.symlog_ticks(norm) if scale == "symlog" else None
    bar = ColourBar(norm, cmap, f"{_CURVATURE_LABELS[m.kind]} ({m.unit})\n({how})", ticks)
    return paint, bar, f"{_CURVATURE_LABELS[m.kind]}" + (" (discrete, mesh)" if not part.exact else ""), corner_values


def _draft_painter(m):
    colormaps, mcolors = _matplotlib_colors()
    pull, min_draft = m.options["pull"], m.options["min_draft"]
    edges = np.unique(np.r_[DRAFT_EDGES, min_draft])
    lower = edges[:-1]
    # under-cut bins red, [0, min_draft) amber, enough draft green to blue
    reds = colormaps.get_cmap("Reds")(np.linspace(0.85, 0.45, max(int((lower < 0).sum()), 1)))
    goods = colormaps.get_cmap("GnBu")(np.linspace(0.45, 0.9, max(int((lower >= min_draft).sum()), 1)))
    palette = []
    r = g = 0
    for lo in lower:
        if lo < 0:
            palette.append(reds[r])
            r += 1
        elif lo < min_draft:
            palette.append((0.98, 0.75, 0.2, 1.0))
        else:
            palette.append(goods[g])
            g += 1
    cmap = mcolors.ListedColormap(palette, name="draft")
    norm = mcolors.BoundaryNorm(edges, cmap.N)

    def paint(px):
        draft = draft_degrees(px.normals, pull)
        draft[np.abs(draft) < VERTICAL_DEGREES] = 0.0  # a vertical wall, not a rounding-deep under-cut
        rgb = cmap(norm(draft))[:, :3]
        region = np.where(draft < -VERTICAL_DEGREES, 0, np.where(draft < min_draft - VERTICAL_DEGREES, 1, 2))
        return rgb, region, True

    label = f"draft angle (degrees) for pull {vector_text(pull)}\nred: under-cut"
    if min_draft > 0:
        label += f", amber: below {min_draft:g}°"
    undercut = 100.0 * float(m.undercut.mean()) if len(m.values) else 0.0
    title = f"draft angle, pull {vector_text(pull)}, minimum {min_draft:g}°: {undercut:.1f} % of the vertices under-cut"
    return paint, ColourBar(norm, cmap, label, edges), title, None


_PAINTERS = {"zebra": _zebra_painter, "isophotes": _isophote_painter, "gaussian": _curvature_painter,
             "mean": _curvature_painter, "max": _curvature_painter, "min": _curvature_painter, "draft": _draft_painter}
