"""Pictures of a :class:`~splinekit.analysis.deviation.Deviation`: the colour map on the part
and the histogram of the signed distances. Both PNGs are written atomically."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .._atomic import atomic_write
from ..errors import ParameterError
from ..mesh.geometry import triangulate
from ..plot import picture
from ..plot.picture import ColourBar

__all__ = ["render_deviation", "render_histogram"]

NO_DATA = 0.78
"""Grey of the reference where no measured point lies near."""
CLIP_PERCENTILE = 99.0
"""The colour scale ends at this percentile of |distance|: a few outliers do not wash out the map."""
PAINT_POINTS = 400_000
"""Foot points painted at most (an even subsample of larger clouds)."""
REACH = 5.0
"""A pixel takes the colour of the nearest foot point within this many typical point spacings."""
CMAP = "RdYlBu_r"  # blue inside, pale yellow on the surface, red outside; never the no-data grey


def _scale(dev):
    """``(norm, cmap, limit)`` of the signed-distance colour scale."""
    picture.pyplot()
    from matplotlib import colormaps
    from matplotlib import colors as mcolors

    magnitude = np.abs(dev.distances)
    limit = float(np.percentile(magnitude, CLIP_PERCENTILE))
    if not limit > 0:
        limit = float(magnitude.max()) if magnitude.max() > 0 else 1.0
    return mcolors.Normalize(-limit, limit, clip=True), colormaps.get_cmap(CMAP), limit


def _units(x: float) -> str:
    return f"{x:.3g}"


def _default_title(dev) -> str:
    what = "scan mesh vertices" if dev.scan is not None else "points"
    return (f"deviation of {len(dev.distances):,} {what}: max |d| {_units(dev.max)}, RMS {_units(dev.rms)}, "
            f"mean {dev.mean:+.3g} (model units; + outside)")


def render_deviation(dev, path, *, size, view, title) -> str:
    """The colour map (:meth:`Deviation.render`)."""
    size, view = picture.check_render_options("normal", "percentile", size, view)
    norm, cmap, limit = _scale(dev)
    label = (f"signed deviation (model units, + outside)\nclipped at the {CLIP_PERCENTILE:g}th percentile "
             f"of |d|; max |d| {_units(dev.max)}")
    bar = ColourBar(norm, cmap, label)
    title = _default_title(dev) if title is None else title
    if dev.scan is not None:
        corners, _ = triangulate(dev.scan)
        tris = dev.points[corners]
        n = picture.triangle_normals(tris)

        def paint_scan(px):
            return cmap(norm(px.values))[:, :3], None, True

        return picture.draw(tris, np.repeat(n[:, None], 3, axis=1), "normal", "percentile", size, view, title, path,
                            corner_values=dev.distances[corners], paint=paint_scan, colour_bar=bar)
    part = dev.reference
    step = max(1, -(-len(dev.closest) // PAINT_POINTS))
    feet, values = dev.closest[::step], dev.distances[::step]
    tree = cKDTree(feet)
    probe = feet[:: max(1, len(feet) // 2000)]
    spacing = float(np.median(tree.query(probe, k=2)[0][:, 1])) if len(feet) > 1 else 0.0
    reach = REACH * spacing if spacing > 0 else 0.02 * part.size()

    def paint_cloud(px):
        d, i = tree.query(px.points, k=1, distance_upper_bound=reach, workers=-1)
        found = np.isfinite(d)
        rgb = np.full((len(d), 3), NO_DATA)
        rgb[found] = cmap(norm(values[i[found]]))[:, :3]
        return rgb, None, True

    return picture.draw(part.points[part.triangles], part.normals[part.triangles], "normal", "percentile", size, view,
                        title, path, paint=paint_cloud, colour_bar=bar)


def render_histogram(dev, path, *, bins, size, title) -> str:
    """The histogram (:meth:`Deviation.histogram`)."""
    try:
        bins = int(bins)
    except (TypeError, ValueError):
        raise ParameterError(f"bins must be a whole number from 2 to 1000, got {bins!r}") from None
    if not 2 <= bins <= 1000:
        raise ParameterError(f"bins must be a whole number from 2 to 1000, got {bins!r}")
    size, _ = picture.check_render_options("normal", "percentile", size, (0.0, 0.0))
    plt = picture.pyplot()
    norm, cmap, limit = _scale(dev)
    d = dev.distances
    lo, hi = float(d.min()), float(d.max())
    if not hi > lo:
        pad = max(abs(lo), 1.0) * 1e-6
        lo, hi = lo - pad, hi + pad
    counts, edges = np.histogram(d, bins=bins, range=(lo, hi))
    centres = 0.5 * (edges[:-1] + edges[1:])
    w, h = size
    fig, ax = plt.subplots(figsize=(w / picture.DPI, h / picture.DPI), dpi=picture.DPI)
    try:
        ax.bar(centres, counts, width=np.diff(edges), color=cmap(norm(centres)), edgecolor="0.3", linewidth=0.3)
        ax.axvline(0.0, color="black", linewidth=0.8)
        ax.axvline(dev.mean, color="black", linestyle="--", linewidth=1.0, label=f"mean {dev.mean:+.3g}")
        for x in (-dev.rms, dev.rms):
            ax.axvline(x, color="0.35", linestyle=":", linewidth=1.0)
        ax.plot([], [], color="0.35", linestyle=":", label=f"± RMS {dev.rms:.3g}")
        s = dev.summary()
        text = "\n".join([f"points  {s['count']:,}", f"max |d|  {s['max']:.3g}", f"max +  {s['max_outside']:+.3g}",
                          f"max −  {s['max_inside']:+.3g}", f"mean |d|  {s['mean_abs']:.3g}", f"std  {s['std']:.3g}",
                          f"p50 / p95 / p99 |d|  {s['p50']:.3g} / {s['p95']:.3g} / {s['p99']:.3g}"])
        ax.text(0.01, 0.97, text, transform=ax.transAxes, va="top", ha="left", fontsize=8, family="monospace",
                bbox=dict(facecolor="white", edgecolor="0.7", alpha=0.85))
        ax.set_xlabel("signed deviation (model units, + outside)")
        ax.set_ylabel("points")
        ax.legend(loc="upper right", fontsize=8)
        ax.set_title(_default_title(dev) if title is None else title, fontsize=9)
        fig.tight_layout()
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=picture.DPI, facecolor="white"))
    finally:
        plt.close(fig)
