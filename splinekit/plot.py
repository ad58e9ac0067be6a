"""Pictures of curves and surfaces (matplotlib, Agg backend, imported lazily).

A person would rather look at a surface than read its numbers; these helpers
write a shaded PNG so that anyone, including the test suite, can.
"""

from __future__ import annotations

import numpy as np

from ._atomic import atomic_write
from .errors import MissingDependencyError, ParameterError

__all__ = ["render_surface"]


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
    ``"height"`` (z coordinate). The control net is drawn as a wireframe when
    ``show_net``. Returns the path.
    """
    if getattr(surface, "dim", None) != 3:
        raise ParameterError("render_surface needs a surface in 3-D space")
    if color not in ("normal", "height"):
        raise ParameterError(f"color must be 'normal' or 'height', got {color!r}")
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
